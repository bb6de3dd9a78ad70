"""Trained agents as controllers of the evaluation harness (:mod:`subenv.evaluation`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from agents.features import DepthIntegral
from agents.policy import TrainedAgent, load_agent
from subenv.dynamics import CONTROL_PERIOD_S
from subenv.vehicles import Vehicle

__all__ = ["AgentController"]

# Environment arguments that change what the agent sees or commands (the harness makes its
# environments with control and alpha only, the rest at their defaults); reward weights do not.
_DYNAMICS_KWARGS = ("vehicle", "dt", "substeps", "plane_rate_limit_radps", "max_pitch_rad", "max_depth_error_m")


class AgentController:
    """A trained agent (:func:`agents.load_agent`) behind the :class:`~subenv.evaluation.Controller` protocol.

    Acts deterministically on the environment's observation: appends the depth-error integral
    (:mod:`agents.features`) if the agent observes it, then normalises as in training.
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
        integral = self.agent.config.depth_integral
        self._integral = None if integral is None else DepthIntegral(1, CONTROL_PERIOD_S, integral)
        self._first = True

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        """Start an episode: the depth-error integral (if the agent observes it) restarts at 0."""
        if self._integral is not None:
            self._integral.reset()
        self._first = True

    def act(self, observation: np.ndarray) -> np.ndarray:
        if self._integral is None:
            return self.agent.predict(observation)
        obs = np.asarray(observation, dtype=np.float32).reshape(1, -1)
        if self._first:  # the reset's observation: I_0 = 0
            self._first = False
        else:
            self._integral.update(obs)
        return self.agent.predict(self._integral.append(obs, self._integral.value)[0])
