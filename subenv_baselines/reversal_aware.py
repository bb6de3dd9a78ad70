"""A reversal-aware depth controller for the whole speed range, through the critical speed."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import partial
from typing import Any, Final

import numpy as np
from scipy.optimize import brentq

from subenv.analysis import critical_speed
from subenv.dynamics import CONTROL_PERIOD_S
from subenv.evaluation import SingleRowMixin, check_batch
from subenv.vehicles import Vehicle
from subenv_baselines._common import GainSchedule, scaled_points, speeds
from subenv_baselines.lqr import DEFAULT_POINTS, INTEGRAL_LIMIT_M_S, DepthIntegrator, lqi_command, lqi_gain

ALLOCATIONS: Final = (-1.0, 1.0)
"""The bow/stern allocations it chooses between: the extremes move u_cr furthest (Fig. 3-9)."""
HYSTERESIS: Final = 0.03
"""Relative speed band around the switching speed inside which the allocation is kept."""


class ReversalAware(SingleRowMixin):
    """Depth control that knows where the planes reverse, and keeps away from it.

    The physics (Riedel 1993 Ch. III, V): with one plane command and allocation alpha, the depth
    mode is uncontrollable at u_cr(alpha) (eq. 3.9, Fig. 3-14); a linear design's depth gain goes
    through infinity there and reverses sign below it (Fig. 5-3). No single gain works on both
    sides, and no gain works near u_cr(alpha). But u_cr depends on the allocation: for SUBOFF
    it runs from 0.44 m/s (alpha = -1, bow planes opposing the stern planes) to 0.67 m/s
    (alpha = +1) (Fig. 3-9). So:

    1. **Allocation.** At the current speed u, choose the alpha in {-1, +1} whose critical speed
       is furthest from u, measured by the controllability margin |1 - (u / u_cr(alpha))^2|.
       The two margins are equal at one switching speed (0.519 m/s for SUBOFF): below it
       alpha = +1 (the boat is well below its u_cr = 0.67 m/s, in the reversed regime), above
       it alpha = -1 (well above u_cr = 0.44 m/s, the normal regime). The margin never falls
       below 22% for SUBOFF, whereas with alpha = 0 it is 0 at 0.578 m/s. A 3% hysteresis band
       stops the allocation chattering at the switching speed during a speed transient. The
       planes are driven independently (``control="independent"``) as stern = delta,
       bow = alpha delta.
    2. **Gains.** LQR with integral action on (theta, w, q, e, int e) for the chosen allocation,
       designed at every 0.02 m/s and interpolated (:func:`subenv_baselines.lqr.lqi_gain`): the depth
       gains carry the sign each regime needs (reversed below u_cr(alpha)), the integral removes
       the steady error of excess buoyancy (surface suction) and ballast offsets. When the
       allocation switches, the integrator is rescaled so that its contribution to the command
       is continuous (bumpless transfer).
    3. **Saturation.** The depth error fed back is clipped to +-1.5 m, so that a large depth
       change is made at a bounded pitch rather than with pinned planes; the integrator stops
       integrating while the planes are saturated in its direction (anti-windup).

    Limits: where no depth-holding steady state exists inside the plane limits for either
    allocation (for example a ballast offset of a few millimetres right at u_cr; see
    :func:`subenv.analysis.equilibria`), it cannot hold depth either.
    """

    name = "reversal_aware"
    control = "independent"
    alpha = 0.0

    def __init__(self, points: np.ndarray = DEFAULT_POINTS, dt_s: float = CONTROL_PERIOD_S) -> None:
        self.points = np.asarray(points, dtype=float)
        self.schedules: dict[float, GainSchedule] = {}
        self.switch_speed_mps = float("nan")
        self.allocation = np.zeros(0)
        """The allocation alpha in use in every episode (one per row of the last ``reset_batch``)."""
        self._vehicle: Vehicle | None = None
        self._limit = 0.4
        self.integrator = DepthIntegrator(dt_s, INTEGRAL_LIMIT_M_S)

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Find the switching speed and design both allocations' gain schedules for ``vehicle`` (once per
        vehicle); start one integral per episode of ``infos`` and choose its allocation at its initial
        speed (``info["speed_mps"]``)."""
        if vehicle is not self._vehicle:
            self._limit = vehicle.planes.limit_rad
            ucr = {a: critical_speed(vehicle, a) for a in ALLOCATIONS}
            low, high = sorted(ucr.values())
            self.switch_speed_mps = brentq(
                lambda u: self._margin(u, ucr[ALLOCATIONS[0]]) - self._margin(u, ucr[ALLOCATIONS[1]]),
                low,
                high,
            )
            self._slow, self._fast = (a for a, _ in sorted(ucr.items(), key=lambda kv: -kv[1]))
            self.schedules = {
                a: GainSchedule.design(
                    scaled_points(self.points, vehicle),
                    partial(lqi_gain, vehicle, alpha=a, plane_limit_rad=self._limit),
                )
                for a in ALLOCATIONS
            }
            self._vehicle = vehicle
        self.integrator.reset(len(infos))
        self.allocation = self._choose(np.array([float(info["speed_mps"]) for info in infos]), None)

    @staticmethod
    def _margin(u: float, ucr: float) -> float:
        return abs(1.0 - (u / ucr) ** 2)

    def _choose(self, speed_mps: np.ndarray, current: np.ndarray | None) -> np.ndarray:
        """The slow-speed allocation (largest u_cr) below the switching speed, the other above; within
        the hysteresis band around it, ``current``."""
        chosen = np.where(speed_mps < self.switch_speed_mps, self._slow, self._fast)
        if current is None:
            return chosen
        band = HYSTERESIS * self.switch_speed_mps
        return np.where(np.abs(speed_mps - self.switch_speed_mps) < band, current, chosen)

    def _gains(self, allocation: np.ndarray, speed_mps: np.ndarray) -> np.ndarray:
        """The gain row of every episode's allocation at its speed, shape (N, 5)."""
        slow, fast = (self.schedules[a].at(speed_mps) for a in (self._slow, self._fast))
        return np.where((allocation == self._slow)[:, None], slow, fast)

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The normalised (stern, bow) commands of every episode, shape (N, 2): stern = delta, bow =
        alpha delta, the allocation rechosen at its observed speed (with hysteresis) and the integral
        rescaled where it switched (bumpless transfer)."""
        if not self.schedules:
            raise RuntimeError("call reset() or reset_batch() first")
        obs = check_batch(observations, self.allocation.size)
        speed = speeds(obs)
        allocation = self._choose(speed, self.allocation)
        gains = self._gains(allocation, speed)
        switched = allocation != self.allocation
        if switched.any():  # bumpless: keep the integral's command where the integral gain is not 0
            old = self._gains(self.allocation, speed)[:, 4]
            rescale = switched & (gains[:, 4] != 0)
            self.integrator.value = np.where(
                rescale,
                self.integrator.value * (old / np.where(rescale, gains[:, 4], 1.0)),
                self.integrator.value,
            )
        self.allocation = allocation
        delta = lqi_command(gains, obs, self.integrator, self._limit)
        return np.stack([delta, allocation * delta], axis=1).astype(np.float32) / np.float32(self._limit)
