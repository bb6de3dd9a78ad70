"""Trained agents as controllers of the evaluation harness (:mod:`subenv.evaluation`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from agents.policy import TrainedAgent, load_agent
from subenv.vehicles import Vehicle

__all__ = ["AgentController"]

# Environment arguments that change what the agent sees or commands (the harness makes its
# environments with control and alpha only, the rest at their defaults); reward weights do not.
_DYNAMICS_KWARGS = ("vehicle", "dt", "substeps", "plane_rate_limit_radps", "max_pitch_rad", "max_depth_error_m")


class AgentController:
    """A trained agent (:func:`agents.load_agent`) behind the :class:`~subenv.evaluation.Controller` protocol.

    Acts deterministically on the raw observation (the agent's normalisation is applied inside).
    ``control`` and ``alpha`` are those the agent was trained with.

    Parameters
    ----------
    agent : TrainedAgent or path
        The agent, or a folder / model file to load it from.
    name : str, optional
        The name in tables (default: the folder's name).
    """

    def __init__(self, agent: TrainedAgent | str | Path, name: str | None = None) -> None:
        self.agent = agent if isinstance(agent, TrainedAgent) else load_agent(agent)
        env_kwargs = self.agent.config.env_kwargs
        changed = [k for k in _DYNAMICS_KWARGS if k in env_kwargs]
        if changed:
            raise ValueError(
                f"the agent {str(self.agent.path)!r} was trained with env_kwargs {changed} changed from the "
                "defaults the evaluation harness uses; evaluate it on its own environment instead"
            )
        self.name = name or self.agent.path.parent.name
        self.control = env_kwargs.get("control", "dual")
        self.alpha = float(env_kwargs.get("alpha", 0.0))

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        """Nothing to reset: the policy is a function of the observation."""

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self.agent.predict(observation)
