"""An extra observation for the agents: the leaky integral of the depth error.

A policy that maps the observation to the planes is a proportional-derivative controller at
best: wherever a steady state off the ordered depth exists with the planes free (below the
critical speed they do; :func:`subenv.analysis.equilibria`), it can settle there, 0.5-1 m off
depth. The classical baselines remove that offset with integral action (``subenv_baselines.lqr``, LQR
with the depth-error integral as a state). The agents get the same information as one more
observation component::

    I_0 = 0,    I_k = exp(-dt / T) I_(k-1) + dt e_k,    clipped to +-limit

with e_k the observed depth error (component 0) after step k, dt the control period, T the leak
time constant (the leak keeps I stationary under noise and disturbances). The training stack
appends it with :class:`DepthIntegralVecEnv`; the evaluation controller
(:class:`subenv_agents.controller.AgentController`) computes the same sequence with :class:`DepthIntegral`,
so an agent sees the same numbers in training and in evaluation.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecEnvWrapper

from subenv_agents.config import DepthIntegralConfig

__all__ = ["DepthIntegral", "DepthIntegralEnv", "DepthIntegralVecEnv", "augmented_space"]

_DEPTH_ERROR = 0  # index of the depth error in subenv's observation (subenv.envs.OBSERVATION_NAMES)


def augmented_space(space: spaces.Box, config: DepthIntegralConfig) -> spaces.Box:
    """``space`` with the integral appended (bounds +-limit)."""
    low = np.append(space.low, -config.limit_ms).astype(space.dtype)
    high = np.append(space.high, config.limit_ms).astype(space.dtype)
    return spaces.Box(low, high, dtype=space.dtype)  # type: ignore[arg-type]


class DepthIntegral:
    """The integral of ``n`` environments: :meth:`reset` some, :meth:`update` all after a step."""

    def __init__(self, n: int, dt_s: float, config: DepthIntegralConfig) -> None:
        self.value = np.zeros(n)
        self.dt_s = float(dt_s)
        self.decay = math.exp(-self.dt_s / config.time_constant_s)
        self.limit = config.limit_ms

    def reset(self, mask: np.ndarray | None = None) -> None:
        """Set the integrals to 0: all of them, or those where the boolean ``mask`` (shape (n,)) is set."""
        if mask is None:
            self.value[:] = 0.0
        else:
            self.value[mask] = 0.0

    def _next(self, value: Any, error: Any) -> Any:
        return np.clip(self.decay * value + self.dt_s * error, -self.limit, self.limit)

    def update(self, obs: np.ndarray) -> np.ndarray:
        """Advance with the observations after a step; returns the new values."""
        self.value = self._next(self.value, obs[:, _DEPTH_ERROR])
        return self.value

    def peek(self, index: int, obs: np.ndarray) -> float:
        """What :meth:`update` would make environment ``index``'s value for its observation ``obs``
        (shape (obs_dim,)), without changing the state."""
        return float(self._next(self.value[index], obs[_DEPTH_ERROR]))

    def append(self, obs: np.ndarray, values: np.ndarray) -> np.ndarray:
        """The observations (n, obs_dim) with ``values`` (n,) as one more column, in ``obs``'s dtype."""
        return np.concatenate([obs, values[:, None].astype(obs.dtype)], axis=1)


class DepthIntegralVecEnv(VecEnvWrapper):  # type: ignore[misc]
    """An SB3 ``VecEnvWrapper`` that appends the depth-error integral to every observation of
    ``venv`` (subenv observations), the terminal observations in ``infos`` included."""

    def __init__(self, venv: Any, config: DepthIntegralConfig, dt_s: float) -> None:
        super().__init__(venv, observation_space=augmented_space(venv.observation_space, config))
        self.integral = DepthIntegral(venv.num_envs, dt_s, config)

    def reset(self) -> np.ndarray:
        """Reset ``venv``: its observations with every integral at 0 appended."""
        obs = self.venv.reset()
        self.integral.reset()
        return self.integral.append(obs, self.integral.value)

    def step_wait(self) -> Any:
        """``venv``'s step with the integrals advanced and appended; an ended episode's terminal
        observation gets its last integral, and the integral of the episode that replaces it starts at 0."""
        obs, rewards, dones, infos = self.venv.step_wait()
        for i in np.flatnonzero(dones):
            terminal = infos[i].get("terminal_observation")
            if terminal is not None:
                value = self.integral.peek(i, terminal)
                infos[i]["terminal_observation"] = np.append(
                    terminal, np.asarray(value, dtype=terminal.dtype)
                )
        self.integral.update(obs)
        self.integral.reset(dones)  # those observations start new episodes: I_0 = 0
        return self.integral.append(obs, self.integral.value), rewards, dones, infos


class DepthIntegralEnv(gym.Wrapper):  # type: ignore[type-arg]
    """A Gymnasium wrapper that appends the depth-error integral to one environment's observations, as
    :class:`DepthIntegralVecEnv` does in training (``TrainedAgent.make_env`` uses it)."""

    def __init__(self, env: gym.Env, config: DepthIntegralConfig, dt_s: float) -> None:  # type: ignore[type-arg]
        super().__init__(env)
        self.observation_space = augmented_space(env.observation_space, config)  # type: ignore[arg-type]
        self.integral = DepthIntegral(1, dt_s, config)

    def reset(self, **kwargs: Any) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset the environment (``kwargs``: its ``reset``'s): the observation with the integral at 0."""
        obs, info = self.env.reset(**kwargs)
        self.integral.reset()
        return self.integral.append(obs[None], self.integral.value)[0], info

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict[str, Any]]:
        """Step the environment: its step's return with the integral advanced and appended."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.integral.update(obs[None])
        return self.integral.append(obs[None], self.integral.value)[0], reward, terminated, truncated, info
