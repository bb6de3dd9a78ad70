"""Pieces the classical controllers share: reading the observations, and gain schedules as data.

Everything here works on batches (one row per episode) with elementwise operations only, so a
row's result has the same bits whatever the batch size (a BLAS dot product may sum in another
order for another shape).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from subenv.envs.dive_plane import OBSERVATION_NAMES
from subenv.thesis import froude_speed_factor
from subenv.vehicles import Vehicle

_I = {name: i for i, name in enumerate(OBSERVATION_NAMES)}
DEPTH_ERROR, PITCH, HEAVE, PITCH_RATE, SPEED = (
    _I["depth_error_m"],
    _I["pitch_rad"],
    _I["heave_mps"],
    _I["pitch_rate_radps"],
    _I["speed_mps"],
)


def feedback_state(observations: np.ndarray, depth_error_limit_m: float = np.inf) -> np.ndarray:
    """X = (theta, w, q, depth error) of every row of ``observations`` (N, obs_dim): shape (N, 4), the
    error clipped to +-limit.

    Clipping the depth error bounds the command far from the ordered depth, so the boat approaches
    it at a limited pitch instead of pinning its planes (a classic depth-error saturation).
    """
    obs = np.asarray(observations, dtype=float)
    error = np.clip(obs[:, DEPTH_ERROR], -depth_error_limit_m, depth_error_limit_m)
    return np.stack([obs[:, PITCH], obs[:, HEAVE], obs[:, PITCH_RATE], error], axis=1)


def scaled_points(points: np.ndarray, vehicle: Vehicle) -> np.ndarray:
    """A gain schedule's speeds [m/s], chosen for SUBOFF, Froude-scaled to ``vehicle``: x sqrt(L / L_SUBOFF)
    (the same points, 1.0 times, on SUBOFF), so the schedule covers the same speeds relative to the
    boat's own physics (its critical and Hopf speeds scale so)."""
    return points * froude_speed_factor(vehicle)


def speeds(observations: np.ndarray) -> np.ndarray:
    """The observed speed [m/s] of every row of ``observations`` (N, obs_dim)."""
    return np.asarray(observations[:, SPEED], dtype=float)


def row_dot(gains: np.ndarray, x: np.ndarray) -> np.ndarray:
    """sum_k gains[..., k] x[:, k] for every row of ``x`` (N, k); ``gains`` one row or one per row of ``x``.

    Summed in the order k = 0, 1, ...: the same bits for every batch size.
    """
    total = gains[..., 0] * x[:, 0]
    for k in range(1, x.shape[1]):
        total = total + gains[..., k] * x[:, k]
    return total


@dataclass(frozen=True)
class GainSchedule:
    """Gains designed at scheduling points, linearly interpolated between them.

    The python-control convention (``gainsched``): ``gains[i]`` is the gain row designed at
    ``points[i]`` (speeds in m/s, ascending); outside the grid the end gains are held.
    """

    gains: np.ndarray  # (n_points, n_states)
    points: np.ndarray  # (n_points,)

    @classmethod
    def design(
        cls, points: Sequence[float] | np.ndarray, design: Callable[[float], np.ndarray]
    ) -> GainSchedule:
        """Run ``design(speed)`` at every point."""
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 1 or pts.size < 2 or np.any(np.diff(pts) <= 0):
            raise ValueError(f"points={points!r} is invalid: must be at least 2 ascending speeds")
        return cls(gains=np.array([design(float(u)) for u in pts]), points=pts)

    def at(self, speed_mps: float | np.ndarray) -> np.ndarray:
        """The interpolated gain row at ``speed_mps``: shape (n_states,), or (N, n_states) for N speeds.

        Outside the grid the weight t is clipped to 0 or 1, which gives the end gains exactly.
        """
        p = self.points
        u = np.asarray(speed_mps, dtype=float)
        i = np.clip(np.searchsorted(p, u) - 1, 0, p.size - 2)
        t = np.clip((u - p[i]) / (p[i + 1] - p[i]), 0.0, 1.0)[..., None]
        return (1.0 - t) * self.gains[i] + t * self.gains[i + 1]
