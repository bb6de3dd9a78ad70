"""Pieces the classical controllers share: reading the observation, and gain schedules as data."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from subenv.envs.dive_plane import OBSERVATION_NAMES

_I = {name: i for i, name in enumerate(OBSERVATION_NAMES)}
DEPTH_ERROR, PITCH, HEAVE, PITCH_RATE, SPEED = (
    _I["depth_error_m"], _I["pitch_rad"], _I["heave_mps"], _I["pitch_rate_radps"], _I["speed_mps"]
)


def feedback_state(observation: np.ndarray, depth_error_limit_m: float = np.inf) -> np.ndarray:
    """x = (theta, w, q, depth error) from an observation, the error clipped to +-limit.

    Clipping the depth error bounds the command far from the ordered depth, so the boat approaches
    it at a limited pitch instead of pinning its planes (a classic depth-error saturation).
    """
    error = float(np.clip(observation[DEPTH_ERROR], -depth_error_limit_m, depth_error_limit_m))
    return np.array([observation[PITCH], observation[HEAVE], observation[PITCH_RATE], error], dtype=float)


@dataclass(frozen=True)
class GainSchedule:
    """Gains designed at scheduling points, linearly interpolated between them.

    The python-control convention (``gainsched``): ``gains[i]`` is the gain row designed at
    ``points[i]`` (speeds in m/s, ascending); outside the grid the end gains are held.
    """

    gains: np.ndarray  # (n_points, n_states)
    points: np.ndarray  # (n_points,)

    @classmethod
    def design(cls, points: Sequence[float] | np.ndarray, design: Callable[[float], np.ndarray]) -> GainSchedule:
        """Run ``design(speed)`` at every point."""
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 1 or pts.size < 2 or np.any(np.diff(pts) <= 0):
            raise ValueError(f"points={points!r} is invalid: must be at least 2 ascending speeds")
        return cls(gains=np.array([design(float(u)) for u in pts]), points=pts)

    def at(self, speed_mps: float) -> np.ndarray:
        """The interpolated gain row at ``speed_mps``."""
        p = self.points
        if speed_mps <= p[0]:
            return self.gains[0]
        if speed_mps >= p[-1]:
            return self.gains[-1]
        i = int(np.searchsorted(p, speed_mps)) - 1
        t = (speed_mps - p[i]) / (p[i + 1] - p[i])
        return (1.0 - t) * self.gains[i] + t * self.gains[i + 1]
