"""LQR with integral action, scheduled over speed: the modern reference."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Final

import numpy as np
from scipy.linalg import solve_continuous_are

from subenv.analysis import linear_model
from subenv.analysis.linear import Allocation
from subenv.dynamics import CONTROL_PERIOD_S
from subenv.evaluation import SingleRowMixin, check_batch
from subenv.vehicles import Vehicle
from subenv_baselines._common import GainSchedule, feedback_state, row_dot, scaled_points, speeds

# Bryson's rule: each state weighted by the inverse square of its acceptable size.
ACCEPTABLE: Final = {
    "pitch_rad": 0.1,
    "heave_mps": 0.1,
    "pitch_rate_radps": 0.05,
    "depth_error_m": 1.0,
    "depth_error_integral_ms": 30.0,
}
INTEGRAL_LIMIT_M_S: Final = 3 * ACCEPTABLE["depth_error_integral_ms"]
"""The depth-error integral is held within +-this (anti-windup bound of the LQI baselines) [m s]."""
DEPTH_ERROR_LIMIT_M: Final = 1.5
"""Depth error fed back is clipped to this: far from the ordered depth the boat closes at a bounded pitch."""
DEFAULT_POINTS: Final = np.linspace(0.12, 2.0, 95)
"""Scheduling speeds [m/s], every 0.02 m/s."""


def lqi_gain(vehicle: Vehicle, speed_mps: float, alpha: Allocation, plane_limit_rad: float) -> np.ndarray:
    """LQR gain on (theta, w, q, e, integral of e) for the linear model at one speed.

    The model is Riedel (1993) eqs 2.59-2.68 augmented with z_dot = e; Q by Bryson's rule
    (:data:`ACCEPTABLE`), R = 1 / limit^2. Solved with ``scipy.linalg.solve_continuous_are``.
    The depth gains come out with the sign the speed needs: reversed below the critical speed.
    """
    lm = linear_model(vehicle, speed_mps, alpha)
    A = np.zeros((5, 5))
    A[:4, :4] = lm.A
    A[4, 3] = 1.0
    B = np.zeros((5, 1))
    B[:4, 0] = lm.B
    Q = np.diag([1.0 / v**2 for v in ACCEPTABLE.values()])
    R = np.array([[1.0 / plane_limit_rad**2]])
    P = solve_continuous_are(A, B, Q, R)
    return np.linalg.solve(R, B.T @ P)[0]


class DepthIntegrator:
    """Integral of the (clipped) depth error of N episodes, with conditional-integration anti-windup."""

    def __init__(self, dt_s: float, limit: float) -> None:
        self.dt_s, self.limit = dt_s, limit
        self.value = np.zeros(0)

    def reset(self, episodes: int) -> None:
        """Start ``episodes`` integrals at 0."""
        self.value = np.zeros(episodes)

    def update(self, error: np.ndarray, integral_gain: np.ndarray, saturated: np.ndarray) -> None:
        """Integrate one period of every episode's depth ``error`` [m], within +-limit.

        Parameters
        ----------
        error : ndarray, shape (N,)
            The (clipped) depth error fed back.
        integral_gain : ndarray, shape (N,) or ()
            The gain on the integral, whose sign says which way the integral moves the planes.
        saturated : ndarray of bool, shape (N,)
            Whether the planes are at their limit; such an integral is held where integrating would
            push them further (conditional integration).
        """
        # Integrate unless the planes are saturated and integrating would push them further.
        hold = saturated & (np.sign(error) == np.sign(integral_gain * self.value))
        self.value = np.where(
            hold, self.value, np.clip(self.value + error * self.dt_s, -self.limit, self.limit)
        )


def lqi_command(
    gains: np.ndarray, observations: np.ndarray, integrator: DepthIntegrator, limit_rad: float
) -> np.ndarray:
    """The saturated plane commands -K (theta, w, q, e, int e) of every row of ``observations``
    (``gains``: one row, or one per observation), advancing the integrator (anti-windup)."""
    x = feedback_state(observations, DEPTH_ERROR_LIMIT_M)
    raw = -(row_dot(gains[..., :4], x) + gains[..., 4] * integrator.value)
    delta = np.clip(raw, -limit_rad, limit_rad)
    integrator.update(x[:, 3], gains[..., 4], saturated=delta != raw)
    return delta


class ScheduledLQR(SingleRowMixin):
    """LQR with integral action on the stern planes (dual control, alpha = 0), scheduled over speed.

    A modern reference: the optimal gain for the thesis's plane allocation at every speed, so it
    carries the reversed depth gain below the critical speed. At u_cr itself the depth mode is
    uncontrollable with this allocation (Fig. 3-14), so close to it the gains grow and the loop
    weakens; compare :class:`subenv_baselines.reversal_aware.ReversalAware`, which moves u_cr away.
    """

    name = "lqr"
    control = "dual"
    alpha = 0.0

    def __init__(self, points: np.ndarray = DEFAULT_POINTS, dt_s: float = CONTROL_PERIOD_S) -> None:
        self.points = np.asarray(points, dtype=float)
        self.schedule: GainSchedule | None = None
        self._vehicle: Vehicle | None = None
        self._limit = 0.4
        self.integrator = DepthIntegrator(dt_s, INTEGRAL_LIMIT_M_S)

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Design the gain schedule for ``vehicle`` (once per vehicle, at its Froude-scaled points) and
        start one depth-error integral at 0 per episode of ``infos``."""
        if vehicle is not self._vehicle:
            self._limit = vehicle.planes.limit_rad
            self.schedule = GainSchedule.design(
                scaled_points(self.points, vehicle), lambda u: lqi_gain(vehicle, u, self.alpha, self._limit)
            )
            self._vehicle = vehicle
        self.integrator.reset(len(infos))

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The normalised stern-plane command of every episode, shape (N, 1): -K(u) (theta, w, q, e, int e)
        with the gains at its observed speed, saturated at the plane limit; advances the integrals."""
        if self.schedule is None:
            raise RuntimeError("call reset() or reset_batch() first")
        obs = check_batch(observations, self.integrator.value.size)
        delta = lqi_command(self.schedule.at(speeds(obs)), obs, self.integrator, self._limit)
        return (delta / self._limit).astype(np.float32)[:, None]
