"""The environments' warning when an episode leaves the range where the free-surface model holds."""

from __future__ import annotations

import warnings

import numpy as np

from subenv.dynamics.free_surface import (
    VALIDITY_DEPTH_RADII,
    VALIDITY_FROUDE_SQUARED,
    validity_depth_m,
    within_validity,
)
from subenv.envs.config import DivePlaneConfig
from subenv.scenarios.registry import get_scenario

__all__ = ["FreeSurfaceRangeWarning", "SurfaceValidityWatch"]


class FreeSurfaceRangeWarning(UserWarning):
    """An episode left the range where the free-surface model holds (its suction is extrapolated there):
    a category of its own, so that a caller can filter or count it (``subenv evaluate`` prints one line
    for all its environments)."""


class SurfaceValidityWatch:
    """Warns, once per environment, the first time a step reports a state where the free-surface model
    does not hold (:func:`subenv.dynamics.free_surface.within_validity`): shallower than
    :data:`~subenv.dynamics.free_surface.VALIDITY_DEPTH_RADII` hull radii, or a depth Froude number
    u^2 / (g h) above :data:`~subenv.dynamics.free_surface.VALIDITY_FROUDE_SQUARED`.

    A warning, not an error: the boat gets there by its own dynamics (every broaching episode passes
    through), the episode goes on with the model extrapolated, and a refusal could only end it early,
    which would change what the scenario measures. Once per environment, so that no step or reset
    repeats it; scenarios without a free surface are never watched.
    """

    def __init__(self, config: DivePlaneConfig, warned: bool = False) -> None:
        scenario = config.base_scenario
        drawn = [get_scenario(name) for name in scenario.components] or [scenario]
        surface = any(s.free_surface is not None and s.free_surface.suction_factor > 0 for s in drawn)
        self.warned = warned
        """Whether this environment has warned (it does not again, even after ``set_scenario``)."""
        self.active = surface and not warned
        self.vehicle = config.base_vehicle
        self.depth_m = validity_depth_m(self.vehicle)
        self._g_froude = self.vehicle.gravity_m_s2 * VALIDITY_FROUDE_SQUARED

    def check(self, depth_m: float, speed_mps: float) -> None:
        """One environment's reported depth [m] and speed [m/s] (plain floats: a step's cost stays a
        compare)."""
        if self.active and (depth_m < self.depth_m or speed_mps * speed_mps > self._g_froude * depth_m):
            self._warn(depth_m, speed_mps)

    def check_all(self, depth_m: np.ndarray, speed_mps: np.ndarray) -> None:
        """The sub-environments' reported depths and speeds (arrays)."""
        if self.active:
            outside = ~within_validity(self.vehicle, depth_m, speed_mps)
            if outside.any():
                i = int(np.flatnonzero(outside)[0])
                self._warn(float(depth_m[i]), float(speed_mps[i]))

    def _warn(self, depth_m: float, speed_mps: float) -> None:
        self.active, self.warned = False, True
        warnings.warn(
            f"subenv: an episode reached {depth_m:.3g} m at {speed_mps:.3g} m/s, outside the range of the "
            f"free-surface model (depth at least {self.depth_m:.3g} m, {VALIDITY_DEPTH_RADII:g} hull radii, "
            f"and u^2 / (g h) at most {VALIDITY_FROUDE_SQUARED:g}): its suction is extrapolated there "
            "(subenv.dynamics.free_surface). Shown once per environment.",
            FreeSurfaceRangeWarning,
            stacklevel=3,
        )
