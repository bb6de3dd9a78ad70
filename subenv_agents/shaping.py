"""Training-only reward shaping: an L1 penalty on the plane commands, and a bonus for holding depth.

The environment's effort term is quadratic (``-effort_weight * mean(a^2)``,
:class:`subenv.envs.DivePlaneEnv`), which is nearly free for small commands: a policy that keeps its
planes swinging by +-0.05 rad around zero, or holds them against each other, pays almost nothing for
it, yet that is what the plane RMS of the evaluation counts. ``-weight * mean(|a|)`` costs small
commands in proportion, and full ones no more than the quadratic term does.

With a reference speed u_ref the weight scales with the forward speed u of the step,
``weight * u / u_ref``: the planes' force grows with u^2, so at speed a small angle does what
only a large one does slowly, and a hurried policy spends plane angle where it is cheapest not to.
Measured, it did not pay: PPO on Mixed with weight 1.0 and u_ref = u_cr (0.58 m/s) selected a policy
with 100% validation success at 0.096 rad plane RMS, the same run with the constant weight 1.0 one
at 0.075 rad (30 validation episodes per scenario each). The shipped configs leave it off.

The depth-band bonus (:class:`DepthBandBonusVecEnv`) adds ``bonus`` to every step that ends within
``half_width_m`` of the ordered depth. The environment's depth reward, 1 - tanh(|e| / scale), is
smooth, so with the effort terms a policy can find it cheaper to settle 0.5 m off depth than to
hold the plane angle that would bring it back. That is the shipped PPO's one way of failing
(SpeedTransient ending at 0.4 u_cr under the random heave force, settled 0.51 m off with the
planes free). The evaluation's success criterion is a band (|e| <= 0.5 m over the final 60 s).
The bonus makes leaving a narrower band a step in the reward, which no plane saving outweighs.

Both terms are added to the training reward only; the environment's own reward and everything
the evaluation measures are unchanged.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnvWrapper

from subenv.envs import OBSERVATION_NAMES
from subenv_agents.config import DepthBandBonusConfig

__all__ = ["DEPTH_ERROR_KEY", "DepthBandBonusVecEnv", "PlaneEffortL1VecEnv"]

_SPEED = OBSERVATION_NAMES.index("speed_mps")
DEPTH_ERROR_KEY = "depth_error_m"
"""The ``info`` key :class:`DepthBandBonusVecEnv` reads: the true depth error after the step, without sensor
noise."""


class PlaneEffortL1VecEnv(VecEnvWrapper):  # type: ignore[misc]
    """Subtract ``weight * mean(|a|)`` (a: the commands in [-1, 1] that were stepped) from every reward of
    ``venv``, times ``u / reference_speed_mps`` (u: the speed observed before the step) if that is given."""

    def __init__(self, venv: Any, weight: float, reference_speed_mps: float | None = None) -> None:
        if not (isinstance(weight, (int, float)) and np.isfinite(weight) and weight >= 0):
            raise ValueError(f"plane_effort_l1={weight!r} is invalid: must be a finite number >= 0")
        if reference_speed_mps is not None and not (
            isinstance(reference_speed_mps, (int, float))
            and np.isfinite(reference_speed_mps)
            and reference_speed_mps > 0
        ):
            raise ValueError(
                f"plane_effort_reference_speed_mps={reference_speed_mps!r} is invalid: must be None or "
                "a finite number > 0"
            )
        super().__init__(venv)
        self.weight = float(weight)
        self.reference_speed_mps = reference_speed_mps
        self._speed = np.zeros(venv.num_envs)
        self._penalty = np.zeros(venv.num_envs)

    def step_async(self, actions: np.ndarray) -> None:
        """Step ``venv`` with ``actions``, keeping each sub-environment's penalty for :meth:`step_wait`."""
        a = np.clip(np.asarray(actions, dtype=float).reshape(self.num_envs, -1), -1.0, 1.0)
        self._penalty = self.weight * np.abs(a).mean(axis=1)
        if self.reference_speed_mps is not None:
            self._penalty *= self._speed / self.reference_speed_mps
        self.venv.step_async(actions)

    def step_wait(self) -> Any:
        """``venv``'s step with the penalty of the stepped commands subtracted from the rewards."""
        obs, rewards, dones, infos = self.venv.step_wait()
        self._speed = np.asarray(obs[:, _SPEED], dtype=float)  # (a new episode's first, where one ended)
        return obs, (rewards - self._penalty).astype(rewards.dtype), dones, infos

    def reset(self) -> np.ndarray:
        """Reset ``venv``, noting each sub-environment's speed for the first step's penalty."""
        obs = self.venv.reset()
        self._speed = np.asarray(obs[:, _SPEED], dtype=float)
        return obs


class DepthBandBonusVecEnv(VecEnvWrapper):  # type: ignore[misc]
    """Add ``bonus`` to every reward of ``venv`` whose step ends with |depth error| <= ``half_width_m``.

    The depth error is the true one, ``info["depth_error_m"]`` (the observation's has sensor noise);
    for a step that ended its episode it is the final state's. ``venv``'s infos must carry that key
    (``make_sb3_vec_env(..., info_keys=(DEPTH_ERROR_KEY,))``).
    """

    def __init__(self, venv: Any, half_width_m: float, bonus: float) -> None:
        band = DepthBandBonusConfig(half_width_m, bonus)  # checks both (ValueError naming the bad one)
        super().__init__(venv)
        self.half_width_m = float(band.half_width_m)
        self.bonus = float(band.bonus)

    def step_wait(self) -> Any:
        """``venv``'s step with the bonus added to the rewards of the steps that end inside the band."""
        obs, rewards, dones, infos = self.venv.step_wait()
        try:
            error = np.array([info[DEPTH_ERROR_KEY] for info in infos], dtype=float)
        except KeyError:
            raise ValueError(
                f"DepthBandBonusVecEnv needs info[{DEPTH_ERROR_KEY!r}] from every step: make the environment "
                f"with info_keys including {DEPTH_ERROR_KEY!r}"
            ) from None
        inside = np.abs(error) <= self.half_width_m
        return obs, (rewards + self.bonus * inside).astype(rewards.dtype), dones, infos

    def reset(self) -> np.ndarray:
        """Reset ``venv`` (the bonus keeps no state between steps)."""
        return self.venv.reset()
