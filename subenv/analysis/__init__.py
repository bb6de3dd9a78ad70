"""Analysis of the dive-plane model (Riedel 1993 Ch. II-V): where the physics turns hard.

- :mod:`~subenv.analysis.linear`: closed-form linear model (eqs 2.59-2.68), numerical Jacobian.
- :mod:`~subenv.analysis.critical`: critical speed and Froude number (eq. 3.9).
- :mod:`~subenv.analysis.design`: pole placement (eq. 2.98), closed-loop eigenvalues,
  controllability (Fig. 3-14), scheduled depth gain (Fig. 5-3).
- :mod:`~subenv.analysis.equilibria`: steady states with stability (eqs 3.17-3.23, 4.3-4.4, 4.40-4.42).
- :mod:`~subenv.analysis.continuation`: pseudo-arclength continuation over speed or x_GB.
- :mod:`~subenv.analysis.bifurcation`: cusps and bifurcation sets (eqs 4.7, 4.37, 4.39, 4.43-4.45, 5.1-5.2).
- :mod:`~subenv.analysis.reversal`: level-flight trim through the critical speed (Fig. 5-2).
- :mod:`~subenv.analysis.curriculum`: speed stages relative to the critical speed, and how hard an
  episode is (its distance to u_cr, its loading's trim margin).
- :mod:`~subenv.analysis.hopf`: beyond the thesis (its Ch. VI): the Hopf bifurcation of level flight at
  speed, its criticality, and the periodic orbits born there.
- :mod:`~subenv.analysis.free_surface`: beyond the thesis (its Ch. VI's first recommendation): level
  flight near the free surface, its stability, the shallowest depth a speed holds, the critical
  speed's shift.
- :mod:`~subenv.analysis.winnable`: depth-holding trims with every plane pair free (can an episode be won).
- :mod:`~subenv.analysis.report`: the reproduction report (``subenv analyze``).

Importing the package loads none of them: each public name below is imported from its module on first
use (PEP 562), so that ``import subenv``, whose environments need only :mod:`~subenv.analysis.linear`
and :mod:`~subenv.analysis.critical`, does not load SciPy's optimisers and signal tools with the
rest (``benchmarks/import_time.py``).
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING, Any, Final

if TYPE_CHECKING:  # (the names as the type checkers see them; imported on use at run time)
    from subenv.analysis.bifurcation import (
        approximate_cusp,
        buoyancy_bifurcation_set,
        exact_bifurcation_set,
        exact_cusp,
        saturation_cusp,
        saturation_cusp_closed_form,
    )
    from subenv.analysis.continuation import Branch, ContinuationError, continue_equilibria
    from subenv.analysis.critical import critical_froude, critical_speed, froude_number
    from subenv.analysis.curriculum import EpisodeDifficulty, SpeedStage, episode_difficulty, speed_curriculum
    from subenv.analysis.design import (
        THESIS_POLES,
        closed_loop_eigenvalues,
        controllability_determinant,
        controllability_losses,
        place_gain,
        scheduled_depth_gain,
        thesis_gain,
        thesis_poles,
    )
    from subenv.analysis.equilibria import Equilibrium, equilibria, steady_state_residual, symmetric_pitchfork
    from subenv.analysis.free_surface import (
        LevelFlightDepth,
        SurfaceCriticalSpeed,
        SurfaceTrim,
        min_level_flight_depth,
        surface_critical_speed,
        surface_trim,
    )
    from subenv.analysis.hopf import (
        HopfPoint,
        PeriodicOrbit,
        continue_periodic_orbits,
        hopf_points,
        oscillatory_growth_rate,
        periodic_orbit,
    )
    from subenv.analysis.linear import BOW_PLANES_ONLY, LinearModel, linear_model, numerical_jacobian
    from subenv.analysis.reversal import LevelFlightTrim, level_flight_trim
    from subenv.analysis.winnable import DepthHoldingTrim, depth_holding_trim, winnable

_MODULES: Final = {
    "bifurcation": (
        "approximate_cusp",
        "buoyancy_bifurcation_set",
        "exact_bifurcation_set",
        "exact_cusp",
        "saturation_cusp",
        "saturation_cusp_closed_form",
    ),
    "continuation": ("Branch", "ContinuationError", "continue_equilibria"),
    "critical": ("critical_froude", "critical_speed", "froude_number"),
    "curriculum": ("EpisodeDifficulty", "SpeedStage", "episode_difficulty", "speed_curriculum"),
    "design": (
        "THESIS_POLES",
        "closed_loop_eigenvalues",
        "controllability_determinant",
        "controllability_losses",
        "place_gain",
        "scheduled_depth_gain",
        "thesis_gain",
        "thesis_poles",
    ),
    "equilibria": ("Equilibrium", "equilibria", "steady_state_residual", "symmetric_pitchfork"),
    "free_surface": (
        "LevelFlightDepth",
        "SurfaceCriticalSpeed",
        "SurfaceTrim",
        "min_level_flight_depth",
        "surface_critical_speed",
        "surface_trim",
    ),
    "hopf": (
        "HopfPoint",
        "PeriodicOrbit",
        "continue_periodic_orbits",
        "hopf_points",
        "oscillatory_growth_rate",
        "periodic_orbit",
    ),
    "linear": ("BOW_PLANES_ONLY", "LinearModel", "linear_model", "numerical_jacobian"),
    "reversal": ("LevelFlightTrim", "level_flight_trim"),
    "winnable": ("DepthHoldingTrim", "depth_holding_trim", "winnable"),
}
"""The public names by the module that defines them: the imports above as data, for :func:`__getattr__`
(``tests/analysis/test_lazy_import.py`` checks that the three lists agree)."""
_HOME: Final = {name: module for module, names in _MODULES.items() for name in names}

__all__ = [
    "BOW_PLANES_ONLY",
    "THESIS_POLES",
    "Branch",
    "ContinuationError",
    "DepthHoldingTrim",
    "EpisodeDifficulty",
    "Equilibrium",
    "HopfPoint",
    "LevelFlightDepth",
    "LevelFlightTrim",
    "LinearModel",
    "PeriodicOrbit",
    "SpeedStage",
    "SurfaceCriticalSpeed",
    "SurfaceTrim",
    "approximate_cusp",
    "buoyancy_bifurcation_set",
    "closed_loop_eigenvalues",
    "continue_equilibria",
    "continue_periodic_orbits",
    "controllability_determinant",
    "controllability_losses",
    "critical_froude",
    "critical_speed",
    "depth_holding_trim",
    "episode_difficulty",
    "equilibria",
    "exact_bifurcation_set",
    "exact_cusp",
    "froude_number",
    "hopf_points",
    "level_flight_trim",
    "linear_model",
    "min_level_flight_depth",
    "numerical_jacobian",
    "oscillatory_growth_rate",
    "periodic_orbit",
    "place_gain",
    "saturation_cusp",
    "saturation_cusp_closed_form",
    "scheduled_depth_gain",
    "speed_curriculum",
    "steady_state_residual",
    "surface_critical_speed",
    "surface_trim",
    "symmetric_pitchfork",
    "thesis_gain",
    "thesis_poles",
    "winnable",
]


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use and kept (PEP 562)."""
    module = _HOME.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


class _Package(types.ModuleType):
    """The package's module type: it keeps the functions ``equilibria`` and ``winnable`` bound to their
    names when their modules of the same name are imported.

    The import system binds a submodule to the attribute of its name on the package the first time it
    is imported (``import subenv.analysis.winnable``, or any module importing it); the eager package
    imported the functions after their modules, so the names were the functions, which ``from
    subenv.analysis import winnable`` must keep giving whatever was imported before.
    """

    def __setattr__(self, name: str, value: Any) -> None:
        if isinstance(value, types.ModuleType) and name in _HOME and _HOME[name] == name:
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
