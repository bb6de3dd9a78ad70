"""The reproduction's numbers: Riedel (1993)'s published values recomputed, and what lies beyond the thesis.

Every function here returns data: :func:`reproduction` gathers it for one vehicle (a
:class:`Reproduction`), and ``subenv analyze`` writes it as ``report.json`` (:func:`write_findings`)
and prints its tables. The written report, with the thesis's figures redrawn, is the documentation's
(its generator, ``docs/_ext/reproduction.py``, draws from these functions). Every computed number
comes from the package's functions; the thesis's values appear only as :attr:`ReportRow.thesis`.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
from scipy.optimize import brentq

from subenv.analysis import bifurcation as bif
from subenv.analysis.critical import critical_froude, critical_speed, critical_speed_for_planes, froude_number
from subenv.analysis.design import (
    closed_loop_eigenvalues,
    controllability_losses,
    depth_gain_denominator,
    thesis_gain,
)
from subenv.analysis.equilibria import equilibria
from subenv.analysis.free_surface import (
    LevelFlightDepth,
    SurfaceCriticalSpeed,
    min_level_flight_depth,
    surface_critical_speed,
    surface_trim,
)
from subenv.analysis.hopf import HopfPoint, continue_periodic_orbits, hopf_points, oscillatory_growth_rate
from subenv.analysis.linear import BOW_PLANES_ONLY, Allocation, plane_derivatives
from subenv.atomic import atomic_output_dir
from subenv.dynamics.free_surface import FreeSurface, suction
from subenv.dynamics.model import model_params
from subenv.thesis import reference_length_ratio
from subenv.units import FOOT_M, mps_to_fps
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.scaling import froude_factor
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "FIG_4_X_GB_OVER_L",
    "PATH_B_FROUDE",
    "PATH_C_FROUDE",
    "REPORT_FILE",
    "REPORT_KIND",
    "SURFACE_DEPTHS_M",
    "SURFACE_SPEED_RATIOS",
    "HopfFindings",
    "ReportRow",
    "Reproduction",
    "SurfaceFindings",
    "VehicleRow",
    "critical_speed_three_ways",
    "env_growth_rate",
    "has_suboff_shape",
    "hopf_findings",
    "reproduce_numbers",
    "reproduction",
    "saturation_pitch_and_froude",
    "surface_depths",
    "surface_findings",
    "vehicle_numbers",
    "write_findings",
]


# Inputs the thesis used for its figures (not results).
FIG_4_X_GB_OVER_L: Final = -1e-4
"""The ballast offset x_GB / L of Riedel (1993) Figs 4-1, 4-6 and 4-11 (path A)."""
PATH_C_FROUDE: Final = 1.0
"""The Froude number of path C of Fig. 4-13 (the hysteresis jump)."""
PATH_B_FROUDE: Final = 1.1
"""The Froude number of path B of Fig. 4-13."""


@dataclass(frozen=True)
class ReportRow:
    """One line of the reproduction table."""

    quantity: str
    thesis: float
    computed: float
    unit: str
    note: str = ""

    @property
    def difference(self) -> float:
        """Computed minus thesis value, in :attr:`unit`."""
        return self.computed - self.thesis


@dataclass(frozen=True)
class VehicleRow:
    """One line of the report's table for a vehicle the thesis did not study."""

    quantity: str
    computed: float
    unit: str
    note: str = ""


def critical_speed_three_ways(vehicle: Vehicle, alpha: float = 0.0) -> dict[str, float]:
    """u_cr [m/s] from eq. 3.9, from a closed-loop eigenvalue crossing zero, and from det(ctrb) = 0.

    The eigenvalue crossing is found for the thesis's gain (any stabilising gain gives the same
    speed: the constant coefficient of the closed-loop polynomial is k4 D(u), eq. 3.7).
    """
    closed = critical_speed(vehicle, alpha)
    gain = thesis_gain(vehicle, alpha)

    def smallest_real_eigenvalue(u: float) -> float:
        eig = closed_loop_eigenvalues(vehicle, [u], gain, alpha)[0]
        real = eig[np.abs(eig.imag) < 1e-9].real
        return float(real.max()) if real.size else -1.0

    lo, hi = 0.5 * closed, 1.5 * closed
    eigen = brentq(lambda u: depth_gain_denominator(vehicle, u, alpha), lo, hi, xtol=1e-14)
    # Confirm with the eigenvalues themselves: the largest real eigenvalue changes sign there.
    assert smallest_real_eigenvalue(eigen * 0.99) > 0 > smallest_real_eigenvalue(eigen * 1.01)
    losses = controllability_losses(vehicle, np.linspace(lo, hi, 201), alpha)
    # The loss that matters is that of the depth mode (eigenvalue 0 of A); see controllability_losses.
    ctrb = min(losses, key=lambda loss: abs(loss[1]))[0]
    return {"closed_form": closed, "eigenvalue": eigen, "controllability": ctrb}


def saturation_pitch_and_froude(vehicle: Vehicle, alpha: Allocation) -> tuple[float, float]:
    """Where the symmetric pitchfork reaches the plane limit, with the planes allocated as ``alpha``:
    (pitch [rad], Froude number) (Riedel 1993 eqs 3.17, 3.21; Figs 3-5, 3-13)."""
    c = vehicle.coefficients
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    theta = math.atan(vehicle.planes.limit_rad * abs(Z_d / c.Z_w))  # |delta_ss| = limit in eq. 3.21
    u_cr = critical_speed_for_planes(vehicle, Z_d, M_d)
    return theta, froude_number(vehicle, u_cr * math.sqrt(math.cos(theta)))  # eq. 3.17


def _jump_at_path_c(vehicle: Vehicle) -> tuple[float, float, float]:
    """Fig. 4-13: x_GB/L where the +limit branch ends at Fn 1.0, and the pitch before and after."""
    u = PATH_C_FROUDE * math.sqrt(vehicle.gravity_m_s2 * vehicle.z_GB_m)
    x_plus, _ = bif.saturation_cusp(vehicle, np.array([u]))
    x_end = float(x_plus[0])

    def saturated_pitch(x: float, sign: float) -> float:
        states = [
            e
            for e in equilibria(vehicle.variant(x_GB_m=x), u)
            if e.saturated and np.sign(e.plane_rad) == sign
        ]
        return states[0].pitch_rad

    before = saturated_pitch(x_end * (1 - 1e-6), 1.0)
    after = saturated_pitch(x_end * (1 + 1e-6), -1.0)
    return x_end / vehicle.length_m, before, after


def _path_a_crossings(vehicle: Vehicle) -> tuple[float, float]:
    """Fig. 4-11: sqrt(lambda) where the path x_GB/L = -1e-4 meets the two saturation curves."""
    target = FIG_4_X_GB_OVER_L * vehicle.length_m
    scale = math.sqrt(vehicle.gravity_m_s2 * vehicle.z_GB_m)
    crossings = []
    for index in (0, 1):

        def f(fn: float, index: int = index) -> float:
            return float(bif.saturation_cusp(vehicle, np.array([fn * scale]))[index][0]) - target

        grid = np.linspace(0.8, 1.3, 101)
        values = np.array([f(g) for g in grid])
        i = int(np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0])
        crossings.append(brentq(f, grid[i], grid[i + 1], xtol=1e-12))
    return max(crossings), min(crossings)


def has_suboff_shape(vehicle: Vehicle) -> bool:
    """Whether ``vehicle`` is SUBOFF at some size: the thesis's non-dimensional derivatives and hull shape,
    so that its published numbers (Froude numbers, angles, ratios) apply to it (``suboff``,
    ``suboff_fullscale``)."""
    suboff = load_vehicle("suboff")
    ratio = vehicle.length_m / suboff.length_m
    return (
        vehicle.hydro == suboff.hydro
        and vehicle.planes == suboff.planes
        and np.allclose(vehicle.hull.x_m, np.array(suboff.hull.x_m) * ratio, rtol=1e-9, atol=0.0)
        and np.allclose(vehicle.hull.breadth_m, np.array(suboff.hull.breadth_m) * ratio, rtol=1e-9, atol=0.0)
    )


def vehicle_numbers(vehicle: Vehicle) -> list[VehicleRow]:
    """The critical speed (three ways), critical and saturation Froude numbers of any vehicle: the report's
    table for a vehicle of another shape than SUBOFF's, where the thesis's numbers do not apply."""
    three = critical_speed_three_ways(vehicle)
    theta_sat, fn_sat = saturation_pitch_and_froude(vehicle, 0.0)
    rows = [
        VehicleRow("u_cr, eq. 3.9 closed form", three["closed_form"], "m/s", "stern planes"),
        VehicleRow(
            "u_cr, closed-loop eigenvalue crossing zero (as Fig. 3-4)",
            three["eigenvalue"],
            "m/s",
            "the pole-placement gain of eq. 2.98 at the Froude-scaled design speed",
        ),
        VehicleRow("u_cr, controllability matrix singular (as Fig. 3-14)", three["controllability"], "m/s"),
        VehicleRow(
            "critical Froude number u_cr / sqrt(g z_GB)", critical_froude(vehicle, 0.0), "-", "eq. 4.25"
        ),
        VehicleRow(
            "critical Froude number u_cr / sqrt(g L)",
            three["closed_form"] / math.sqrt(vehicle.gravity_m_s2 * vehicle.length_m),
            "-",
        ),
        VehicleRow("saturation Froude number, symmetric pitchfork (as Figs 3-5, 3-6)", fn_sat, "-"),
        VehicleRow("pitch at saturation (as Figs 3-5, 4-6)", math.degrees(theta_sat), "deg"),
    ]
    if vehicle.planes.has_bow_planes:
        rows.append(
            VehicleRow(
                "critical Froude number, bow planes only (as Fig. 5-4)",
                critical_froude(vehicle, BOW_PLANES_ONLY),
                "-",
            )
        )
    return rows


def reproduce_numbers(vehicle: Vehicle) -> list[ReportRow]:
    """The thesis's published numbers next to the values the package computes for ``vehicle`` (of SUBOFF's
    shape: :func:`has_suboff_shape`)."""
    rows = []
    # On SUBOFF at another size (Froude-similar, lambda = L / L_SUBOFF) the published dimensional numbers are
    # compared Froude-scaled: a speed x sqrt(lambda), the gains on (theta, w, q, Z) x (1, 1/sqrt(lambda),
    # sqrt(lambda), 1/lambda) (the poles, rates, scale as 1/sqrt(lambda)); exactly the published ones on
    # SUBOFF.
    ratio = reference_length_ratio(vehicle)
    speed = froude_factor("speed", ratio)
    scaled = "" if ratio == 1.0 else f"; published value Froude-scaled to lambda = {ratio:.4g}"
    gain = thesis_gain(vehicle)
    gain_ft = gain * np.array([1.0, FOOT_M, 1.0, FOOT_M])
    gain_scale = (1.0, 1.0 / speed, speed, 1.0 / froude_factor("length", ratio))
    for i, (name, published) in enumerate(
        zip(("k_theta", "k_w", "k_q", "k_Z"), (-0.9917, -0.8333, -0.6026, 0.0351), strict=True)
    ):
        rows.append(
            ReportRow(
                f"eq. 2.98 gain {name}",
                published * gain_scale[i],
                float(gain_ft[i]),
                "ft units",
                "poles (-0.3,-0.31,-0.32,-0.33) at 5 fps" + scaled,
            )
        )
    three = critical_speed_three_ways(vehicle)
    rows.append(
        ReportRow(
            "u_cr, eq. 3.9 closed form",
            1.8979 * speed,
            mps_to_fps(three["closed_form"]),
            "fps",
            "alpha = 0" + scaled,
        )
    )
    rows.append(
        ReportRow(
            "u_cr, closed-loop eigenvalue crossing zero (Fig. 3-4)",
            1.8979 * speed,
            mps_to_fps(three["eigenvalue"]),
            "fps",
            "thesis gain" + scaled,
        )
    )
    rows.append(
        ReportRow(
            "u_cr, controllability matrix singular (Fig. 3-14)",
            1.8979 * speed,
            mps_to_fps(three["controllability"]),
            "fps",
            scaled.removeprefix("; "),
        )
    )
    rows.append(ReportRow("critical Fn, alpha = -1 (Fig. 3-9)", 0.81, critical_froude(vehicle, -1.0), "-"))
    rows.append(ReportRow("critical Fn, alpha = +1 (Fig. 3-9)", 1.22, critical_froude(vehicle, 1.0), "-"))
    rows.append(
        ReportRow(
            "critical Fn, bow planes only (Fig. 5-4)", 2.05, critical_froude(vehicle, BOW_PLANES_ONLY), "-"
        )
    )
    theta_sat, fn_sat = saturation_pitch_and_froude(vehicle, 0.0)
    rows.append(ReportRow("saturation Fn, symmetric pitchfork (Figs 3-5, 3-6)", 1.05, fn_sat, "-"))
    rows.append(
        ReportRow(
            "pitch at saturation (Figs 3-5, 4-6)", 9.0, math.degrees(theta_sat), "deg", "thesis: 'about nine'"
        )
    )
    theta_bow, _ = saturation_pitch_and_froude(vehicle, BOW_PLANES_ONLY)
    rows.append(
        ReportRow("pitch at saturation, bow planes only (Fig. 5-5)", 4.5, math.degrees(theta_bow), "deg")
    )
    drag_free = vehicle.variant(crossflow_drag=0.0)  # the thesis's Ch. III-IV conditions
    high, low = _path_a_crossings(drag_free)
    rows.append(
        ReportRow(
            "path A meets saturation cusp, upper (Fig. 4-11)", 1.08, high, "sqrt(lambda)", "x_GB/L = -1e-4"
        )
    )
    rows.append(ReportRow("path A enters saturation cusp (Fig. 4-11)", 0.99, low, "sqrt(lambda)"))
    x_jump, before, after = _jump_at_path_c(drag_free)
    rows.append(ReportRow("Fig. 4-13 jump location, path C (Fn 1.0)", 1e-4, x_jump, "x_GB/L"))
    rows.append(ReportRow("Fig. 4-13 pitch before the jump", -9.0, math.degrees(before), "deg"))
    rows.append(ReportRow("Fig. 4-13 pitch after the jump", 7.5, math.degrees(after), "deg"))
    return rows


# --- beyond the thesis: the Hopf bifurcation at speed (its Ch. VI recommendation) ------------------

_HOPF_ENV_SPEEDS: Final = (0.955, 0.98, 1.015, 1.04)
"""Speeds of the environment runs whose growth rates cross-check the Hopf speed, as multiples of it
(two each side: for SUBOFF 0.80, 0.82, 0.85 and 0.87 m/s)."""
_ORBIT_SPEEDS: Final = np.arange(1.004, 1.2, 0.024)
"""Speeds of the continued cycles, as multiples of the Hopf speed (for SUBOFF 0.84 to 1.0 m/s)."""
_HOPF_ENV_ID: Final = "subenv/Nominal-v0"  # (its scenario has no disturbance and no sensor noise)


def env_growth_rate(
    speed_mps: float,
    env_id: str = _HOPF_ENV_ID,
    initial_pitch_rad: float = 1e-3,
    vehicle: Vehicle | None = None,
) -> float:
    """The growth rate [1/s] of the pitch oscillation in the environment with zero action (planes held
    at zero), from a small initial pitch: the slope of log |theta| at its peaks over the episode.

    An independent check of :func:`subenv.analysis.hopf.hopf_points`: the environment integrates the
    nonlinear equations (drag included) with its own integrator; near level flight the slope is the
    real part of the oscillatory pair of eigenvalues.
    """
    import gymnasium as gym

    import subenv.envs  # noqa: F401  (registers the ids)
    from subenv.envs.dive_plane import DivePlaneEnv

    kwargs: dict[str, Any] = {} if vehicle is None else {"vehicle": vehicle}
    env = gym.make(env_id, **kwargs)
    base = env.unwrapped
    if not isinstance(base, DivePlaneEnv):
        env.close()
        raise ValueError(f"env_id={env_id!r} is invalid: must be a subenv environment id")
    depth = 5.0 * base.base_vehicle.length_m  # (deep: no surface for any hull)
    _, info = env.reset(
        seed=0,
        options={
            "speed": speed_mps,
            "depth_command": depth,
            "initial_state": (initial_pitch_rad, 0.0, 0.0, depth),
        },
    )
    times, pitch = [info["time_s"]], [info["pitch_rad"]]
    action = np.zeros(base.config.n_actions, dtype=np.float32)
    while True:
        _, _, terminated, truncated, info = env.step(action)
        times.append(info["time_s"])
        pitch.append(info["pitch_rad"])
        if terminated or truncated:
            break
    env.close()
    t, size = np.array(times), np.abs(np.array(pitch))
    peaks = np.flatnonzero((size[1:-1] > size[:-2]) & (size[1:-1] >= size[2:])) + 1
    return float(np.polyfit(t[peaks], np.log(size[peaks]), 1)[0])


@dataclass(frozen=True)
class HopfFindings:
    """What the report says of the Hopf bifurcation of ``vehicle`` with the planes held."""

    point: HopfPoint
    env_speeds_mps: tuple[float, ...]
    env_growth_rates: tuple[float, ...]
    env_hopf_speed_mps: float
    """Where the environment's growth rates cross zero (linear interpolation between the two speeds
    around the crossing)."""
    orbit_speeds_mps: tuple[float, ...]
    orbit_amplitudes_rad: tuple[float, ...]
    orbits_stable: bool
    pitch_limit_speed_mps: float
    """The speed at which the cycle's pitch amplitude reaches the environments' default pitch limit."""
    splitting_speed_mps: float
    """Above this speed the oscillatory pair has become two real eigenvalues (a monotonic divergence)."""


def hopf_findings(vehicle: Vehicle) -> HopfFindings:
    """The open-loop Hopf point, its environment cross-check and the cycles born there (the report's
    Hopf section, and the environment docstring's account of zero action)."""
    from subenv.envs.config import DivePlaneConfig

    (point,) = hopf_points(vehicle)
    env_speeds = tuple(point.speed_mps * f for f in _HOPF_ENV_SPEEDS)
    rates = tuple(env_growth_rate(u, vehicle=vehicle) for u in env_speeds)
    k = next(i for i in range(len(rates) - 1) if rates[i] < 0.0 <= rates[i + 1])
    u0, u1, g0, g1 = env_speeds[k], env_speeds[k + 1], rates[k], rates[k + 1]
    orbits = continue_periodic_orbits(vehicle, point.speed_mps * _ORBIT_SPEEDS)
    speeds = np.array([o.speed_mps for o in orbits])
    amplitudes = np.array([o.pitch_amplitude_rad for o in orbits])
    limit = DivePlaneConfig().max_pitch_rad
    pitch_limit_speed = float(np.interp(limit, amplitudes, speeds)) if amplitudes.max() >= limit else math.nan

    def pair_exists(u: float) -> float:
        return 1.0 if math.isfinite(oscillatory_growth_rate(vehicle, u)) else -1.0

    splitting = brentq(pair_exists, point.speed_mps, 3.0 * point.speed_mps, xtol=1e-6)
    return HopfFindings(
        point=point,
        env_speeds_mps=env_speeds,
        env_growth_rates=rates,
        env_hopf_speed_mps=u0 - g0 * (u1 - u0) / (g1 - g0),
        orbit_speeds_mps=tuple(speeds),
        orbit_amplitudes_rad=tuple(amplitudes),
        orbits_stable=all(o.stable for o in orbits),
        pitch_limit_speed_mps=pitch_limit_speed,
        splitting_speed_mps=float(splitting),
    )


SURFACE_DEPTHS_M: Final = (0.3, 0.35, 0.4, 0.5, 0.6, 0.8, 1.0, 1.2, 1.5, 2.0, 3.0)
"""Depths of midship [m] at which the report gives the critical speed near the surface (SUBOFF's;
Froude-scaled on another vehicle: :func:`surface_depths`)."""
SURFACE_SPEED_RATIOS: Final = (
    0.3,
    0.5,
    0.7,
    0.8,
    0.85,
    0.9,
    0.93,
    0.95,
    0.97,
    1.03,
    1.05,
    1.1,
    1.15,
    1.2,
    1.5,
    2.0,
)
"""u / u_cr (deep water, alpha = 0) at which the report gives the shallowest depth held."""
_SURFACE_ALPHAS: Final = (0.0, 1.0)  # stern planes only; both pairs, equal


def surface_depths(vehicle: Vehicle, depths: tuple[float, ...] = SURFACE_DEPTHS_M) -> tuple[float, ...]:
    """SUBOFF's ``depths`` [m] Froude-scaled to ``vehicle``'s length, as the scenarios' are; those where
    its hull (of another shape) would broach are left out."""
    length = froude_factor("length", reference_length_ratio(vehicle))
    radius = 0.5 * max(vehicle.hull.breadth_m)
    return tuple(h * length for h in depths if h * length > radius)


def _surface_alphas(vehicle: Vehicle) -> tuple[float, ...]:
    return _SURFACE_ALPHAS if vehicle.planes.has_bow_planes else (0.0,)


@dataclass(frozen=True)
class SurfaceFindings:
    """What the report says of level flight near the free surface (:mod:`subenv.analysis.free_surface`)."""

    critical: tuple[SurfaceCriticalSpeed, ...]
    held: dict[float, tuple[LevelFlightDepth, ...]]
    """alpha -> the shallowest depth held at each of :data:`SURFACE_SPEED_RATIOS`."""
    suction_N: tuple[float, ...]
    """The suction at :data:`SURFACE_DEPTHS_M`, level, at u_cr [N, down positive]."""
    growth_per_s: tuple[float, ...]
    """The fastest eigenvalue's real part of level flight at :data:`SURFACE_DEPTHS_M`, planes held,
    0.5 u_cr [1/s]."""


def surface_findings(vehicle: Vehicle) -> SurfaceFindings:
    """The free-surface section's numbers: the critical speed two ways, the shallowest depth held, the
    suction and the stability of level flight against depth."""
    ucr = critical_speed(vehicle)
    depths = surface_depths(vehicle)
    critical = tuple(surface_critical_speed(vehicle, h) for h in depths)
    held = {
        a: tuple(min_level_flight_depth(vehicle, r * ucr, a) for r in SURFACE_SPEED_RATIOS)
        for a in _surface_alphas(vehicle)
    }
    trims = [surface_trim(vehicle, 0.5 * ucr, h) for h in depths]
    params = model_params(vehicle, FreeSurface())
    suction_at_ucr, _ = suction(params.hull, 0.0, np.array(depths), ucr, params.rho_suction)
    return SurfaceFindings(
        critical=critical,
        held=held,
        suction_N=tuple(float(z) for z in suction_at_ucr),
        growth_per_s=tuple(float(max(t.eigenvalues.real)) for t in trims),
    )


# --- the whole reproduction, as data -----------------------------------------------------------


@dataclass(frozen=True)
class Reproduction:
    """Everything the reproduction computes for one vehicle (:func:`reproduction`).

    Attributes
    ----------
    vehicle : str
        The vehicle's name.
    suboff_shape : bool
        Whether the thesis's published numbers apply (:func:`has_suboff_shape`).
    published : tuple of ReportRow
        The thesis's numbers next to the computed ones (SUBOFF's shape; empty otherwise).
    numbers : tuple of VehicleRow
        The critical speed and saturation of a vehicle of another shape (empty for SUBOFF's).
    hopf : HopfFindings
        The Hopf bifurcation of level flight with the planes held.
    surface : SurfaceFindings
        Level flight near the free surface.
    """

    vehicle: str
    suboff_shape: bool
    published: tuple[ReportRow, ...]
    numbers: tuple[VehicleRow, ...]
    hopf: HopfFindings
    surface: SurfaceFindings

    def as_dict(self) -> dict[str, Any]:
        """The numbers as JSON types: dataclasses as objects, each row's ``difference`` included, the
        surface's allocations (``alpha``) as keys, and the Hopf point's period and criticality."""
        data = _jsonable(self)
        data["published"] = [{**_jsonable(r), "difference": r.difference} for r in self.published]
        data["hopf"]["point"].update(
            period_s=self.hopf.point.period_s, criticality=self.hopf.point.criticality
        )
        return data


def _jsonable(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {f"{k:g}" if isinstance(k, float) else str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, tuple | list | np.ndarray):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def reproduction(vehicle: Vehicle) -> Reproduction:
    """The published numbers (or, for a vehicle of another shape, its own), the Hopf findings and the
    free-surface findings of ``vehicle``: what ``subenv analyze`` writes and the documentation's report
    shows (tens of seconds)."""
    suboff_shape = has_suboff_shape(vehicle)
    return Reproduction(
        vehicle=vehicle.name,
        suboff_shape=suboff_shape,
        published=tuple(reproduce_numbers(vehicle)) if suboff_shape else (),
        numbers=() if suboff_shape else tuple(vehicle_numbers(vehicle)),
        hopf=hopf_findings(vehicle),
        surface=surface_findings(vehicle),
    )


REPORT_KIND = "subenv analyze"
"""What a report folder's marker file says (:data:`subenv.atomic.MARKER_FILE`): ``overwrite``
replaces only a folder that says so."""
REPORT_FILE = "report.json"
"""The file :func:`write_findings` writes: :meth:`Reproduction.as_dict` as JSON."""


def write_findings(
    out_dir: str | Path, vehicle: Vehicle | None = None, overwrite: bool = False
) -> Reproduction:
    """Compute :func:`reproduction` (of SUBOFF by default) and write it into ``out_dir`` as
    :data:`REPORT_FILE`, completely or not at all.

    The folder is assembled beside ``out_dir`` and put in place atomically
    (:func:`subenv.atomic.atomic_output_dir`), after ``out_dir`` was checked and the temporary folder
    created, before any computation.

    Raises
    ------
    FileExistsError
        ``out_dir`` exists and ``overwrite`` is False, or it is not an earlier report.
    OutputDirError
        ``out_dir`` cannot be created (a file in the way, no permission); a ValueError.
    """
    vehicle = vehicle or load_vehicle("suboff")
    with atomic_output_dir(out_dir, overwrite=overwrite, kind=REPORT_KIND) as folder:
        found = reproduction(vehicle)
        (folder / REPORT_FILE).write_text(json.dumps(found.as_dict(), indent=1) + "\n", "utf-8")
    return found
