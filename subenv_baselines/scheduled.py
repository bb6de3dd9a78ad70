"""Gain scheduling: the thesis's pole placement repeated over a speed grid (Riedel 1993 Fig. 5-3)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from subenv.analysis import place_gain, thesis_poles
from subenv.evaluation import SingleRowMixin
from subenv.vehicles import Vehicle
from subenv_baselines._common import GainSchedule, feedback_state, row_dot, scaled_points, speeds

DEFAULT_POINTS = np.linspace(0.15, 2.0, 38)
"""Scheduling speeds [m/s], every 0.05 m/s; for SUBOFF u_cr = 0.5785 m/s lies between two points."""


class GainScheduledPolePlacement(SingleRowMixin):
    """Pole placement at every scheduling speed (same poles as the thesis), interpolated at the current speed.

    What it does near the critical speed: the depth gain that places the poles is
    k4 = p1 p2 p3 p4 / D(u) (eq. 2.97), and D(u_cr) = 0 (eq. 3.7), so k4 grows without bound as
    u -> u_cr and changes sign below it (:func:`subenv.analysis.scheduled_depth_gain`). The
    scheduled gains are therefore huge at the grid points around u_cr, and their interpolation
    between the two points that straddle u_cr passes through zero at some speed: there the
    controller has no depth feedback at all. Within roughly 10% of u_cr the planes saturate on
    small errors and the loop degrades; away from u_cr it works on both sides, since the
    schedule carries the reversed gain sign below critical.
    """

    name = "scheduled"
    control = "dual"
    alpha = 0.0

    def __init__(self, points: np.ndarray = DEFAULT_POINTS) -> None:
        self.points = np.asarray(points, dtype=float)
        self.schedule: GainSchedule | None = None
        self._vehicle: Vehicle | None = None
        self._limit = 0.4

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Place the gains at every (Froude-scaled) scheduling speed for ``vehicle``, once per vehicle (the
        controller keeps no per-episode state, so ``infos`` is not read)."""
        if vehicle is not self._vehicle:
            self.schedule = GainSchedule.design(
                scaled_points(self.points, vehicle),
                lambda u: place_gain(vehicle, u, thesis_poles(vehicle), self.alpha),
            )
            self._vehicle = vehicle
            self._limit = vehicle.planes.limit_rad

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The normalised stern-plane command of every episode, shape (N, 1): -K(u) x with the gains
        interpolated at its observed speed, clipped to the limit."""
        if self.schedule is None:
            raise RuntimeError("call reset() or reset_batch() first")
        delta = -row_dot(self.schedule.at(speeds(observations)), feedback_state(observations))
        return np.clip(delta / self._limit, -1.0, 1.0).astype(np.float32)[:, None]
