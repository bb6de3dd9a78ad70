"""Trained agents as controllers of the evaluation harness (:mod:`subenv.evaluation`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from subenv.dynamics import CONTROL_PERIOD_S
from subenv.evaluation import SingleRowMixin, check_batch
from subenv.vehicles import Vehicle
from subenv_agents.features import DepthIntegral
from subenv_agents.policy import TrainedAgent, load_agent
from subenv_agents.records import check_harness_kwargs

__all__ = ["AgentController"]


class AgentController(SingleRowMixin):
    """A trained agent (:func:`subenv_agents.load_agent`) behind the
    :class:`~subenv.evaluation.Controller` protocol.

    Acts deterministically on the environment's observations (one episode, or a batch: one row
    per episode): appends each episode's depth-error integral (:mod:`subenv_agents.features`) if the
    agent observes it, then normalises as in training.
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
        check_harness_kwargs(env_kwargs, f"agent {str(self.agent.path)!r}")
        self.name = name or self.agent.path.parent.name
        self.control = env_kwargs.get("control", "dual")
        self.alpha = float(env_kwargs.get("alpha", 0.0))
        self._integral_config = self.agent.config.depth_integral
        self._integral: DepthIntegral | None = None
        self._episodes = 0
        self._first = True

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Start ``len(infos)`` episodes: their depth-error integrals (if the agent observes it) start at
        0."""
        self._episodes = len(infos)
        if self._integral_config is not None:
            self._integral = DepthIntegral(self._episodes, CONTROL_PERIOD_S, self._integral_config)
        self._first = True

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The agent's deterministic action for every episode's observation, shape (N, action_dim): with
        each episode's depth-error integral appended (advanced by this observation, except the reset's)
        if the agent observes it."""
        obs = check_batch(observations, self._episodes).astype(np.float32, copy=False)
        if self._integral is None:
            return self.agent.predict(obs)
        if self._first:  # the reset's observation: I_0 = 0
            self._first = False
        else:
            self._integral.update(obs)
        return self.agent.predict(self._integral.append(obs, self._integral.value))
