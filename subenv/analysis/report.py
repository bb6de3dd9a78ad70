"""The reproduction report: published numbers of Riedel (1993) recomputed, and its figures redrawn.

``subenv analyze`` calls :func:`write_report`. Every computed number comes from the package's
functions; the thesis's values appear only in the "thesis value" column.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
from scipy.optimize import brentq

from subenv.analysis import bifurcation as bif
from subenv.analysis.continuation import continue_equilibria
from subenv.analysis.critical import critical_froude, critical_speed, critical_speed_for_planes, froude_number
from subenv.analysis.design import (
    closed_loop_eigenvalues,
    controllability_determinant,
    controllability_losses,
    depth_gain_denominator,
    scheduled_depth_gain,
    thesis_gain,
)
from subenv.analysis.equilibria import DragMoment, Equilibrium, HullIntegral, equilibria, symmetric_pitchfork
from subenv.analysis.free_surface import (
    LevelFlightDepth,
    SurfaceCriticalSpeed,
    min_level_flight_depth,
    surface_critical_speed,
    surface_trim,
)
from subenv.analysis.hopf import HopfPoint, continue_periodic_orbits, hopf_points, oscillatory_growth_rate
from subenv.analysis.linear import BOW_PLANES_ONLY, Allocation, plane_derivatives
from subenv.analysis.reversal import level_flight_trim
from subenv.atomic import atomic_output_dir
from subenv.dynamics.free_surface import FreeSurface, suction, validity_depth_m
from subenv.dynamics.model import model_params
from subenv.thesis import reference_length_ratio
from subenv.units import FOOT_M, mps_to_fps
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.scaling import froude_factor
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "REPORT_KIND",
    "HopfFindings",
    "ReportRow",
    "SurfaceFindings",
    "critical_speed_three_ways",
    "env_growth_rate",
    "hopf_findings",
    "reproduce_numbers",
    "surface_findings",
    "write_report",
]

# Inputs the thesis used for its figures (not results): x_GB/L of Figs 4-1, 4-6, 4-11 and the
# Froude numbers of the paths of Fig. 4-13.
_XGB_OVER_L_CH4 = -1e-4
_PATH_C_FN, _PATH_B_FN = 1.0, 1.1


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


def _deg(x: float) -> float:
    return math.degrees(x)


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


def _saturation_pitch_and_froude(vehicle: Vehicle, alpha: Allocation) -> tuple[float, float]:
    """Where the symmetric pitchfork reaches the plane limit: (pitch [rad], Froude number)."""
    c = vehicle.coefficients
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    theta = math.atan(vehicle.planes.limit_rad * abs(Z_d / c.Z_w))  # |delta_ss| = limit in eq. 3.21
    u_cr = critical_speed_for_planes(vehicle, Z_d, M_d)
    return theta, froude_number(vehicle, u_cr * math.sqrt(math.cos(theta)))  # eq. 3.17


def _jump_at_path_c(vehicle: Vehicle) -> tuple[float, float, float]:
    """Fig. 4-13: x_GB/L where the +limit branch ends at Fn 1.0, and the pitch before and after."""
    u = _PATH_C_FN * math.sqrt(vehicle.gravity_m_s2 * vehicle.z_GB_m)
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
    target = _XGB_OVER_L_CH4 * vehicle.length_m
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
    theta_sat, fn_sat = _saturation_pitch_and_froude(vehicle, 0.0)
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
        VehicleRow("pitch at saturation (as Figs 3-5, 4-6)", _deg(theta_sat), "deg"),
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
    theta_sat, fn_sat = _saturation_pitch_and_froude(vehicle, 0.0)
    rows.append(ReportRow("saturation Fn, symmetric pitchfork (Figs 3-5, 3-6)", 1.05, fn_sat, "-"))
    rows.append(
        ReportRow("pitch at saturation (Figs 3-5, 4-6)", 9.0, _deg(theta_sat), "deg", "thesis: 'about nine'")
    )
    theta_bow, _ = _saturation_pitch_and_froude(vehicle, BOW_PLANES_ONLY)
    rows.append(ReportRow("pitch at saturation, bow planes only (Fig. 5-5)", 4.5, _deg(theta_bow), "deg"))
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
    rows.append(ReportRow("Fig. 4-13 pitch before the jump", -9.0, _deg(before), "deg"))
    rows.append(ReportRow("Fig. 4-13 pitch after the jump", 7.5, _deg(after), "deg"))
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


def _hopf_markdown(vehicle: Vehicle, found: HopfFindings) -> list[str]:
    p = found.point
    predicted_rad = p.predicted_amplitude_rad(vehicle, found.orbit_speeds_mps[0])
    rows = [
        (
            "Hopf speed u_H, eigenvalues of level flight (planes held)",
            f"{p.speed_mps:.4f}",
            "m/s",
            f"{p.speed_mps / critical_speed(vehicle):.3f} u_cr",
        ),
        (
            "u_H, where the environment's zero-action growth rates cross zero",
            f"{found.env_hopf_speed_mps:.4f}",
            "m/s",
            "rates "
            + ", ".join(
                f"{g:+.4f}/s at {u:.2f}"
                for u, g in zip(found.env_speeds_mps, found.env_growth_rates, strict=True)
            ),
        ),
        ("frequency at u_H (period)", f"{p.frequency_radps:.4f}", "rad/s", f"period {p.period_s:.1f} s"),
        (
            "d Re(lambda) / du at u_H",
            f"{p.growth_slope:.4f}",
            "1/s per m/s",
            "level flight unstable above u_H",
        ),
        (
            "amplitude coefficient c2 (drag, averaged)",
            f"{p.amplitude_coefficient:.5f}",
            "1/(s rad)",
            f"{p.criticality}: stable cycles above u_H, amplitude ~ -Re(lambda)/c2",
        ),
        (
            f"cycle pitch amplitude at {found.orbit_speeds_mps[0]:.3g} m/s: continuation / normal form",
            f"{math.degrees(found.orbit_amplitudes_rad[0]):.2f}",
            "deg",
            f"normal form {math.degrees(predicted_rad):.2f} deg",
        ),
        (
            "speed at which the cycle reaches the 0.6 rad pitch limit",
            *(
                (f"{found.pitch_limit_speed_mps:.3f}", "m/s", "zero action ends on pitch_limit above it")
                if math.isfinite(found.pitch_limit_speed_mps)
                else (
                    "not reached",
                    "",
                    f"up to {max(found.orbit_speeds_mps):.3g} m/s, the fastest cycle continued",
                )
            ),
        ),
        ("speed above which the pair is real (divergence)", f"{found.splitting_speed_mps:.3f}", "m/s", ""),
    ]
    lines = ["| quantity | value | unit | note |", "|---|---:|---|---|"]
    lines += [f"| {q} | {v} | {u} | {n} |" for q, v, u, n in rows]
    return [
        "## Beyond the thesis: the Hopf bifurcation at speed",
        "",
        "Riedel (1993) Ch. VI recommends a Hopf bifurcation analysis of the instability at high speed. With",
        "the planes held at zero, level flight has an oscillatory pitch/heave mode that loses stability as",
        "the speed rises (the destabilising Munk moment grows with u, the restoring moment W z_GB does not).",
        "The hull's cross-flow drag is quadratic (v|v|), so the cubic first Lyapunov coefficient does not",
        "decide the criticality: the averaged amplitude equation dr/dt = Re(lambda) r + c2 r^2 does",
        "(`subenv.analysis.hopf`). The cycles are continued by shooting on the nonlinear equations, and the",
        "Hopf speed is checked against growth rates measured in the environment.",
        "",
        *lines,
        "",
    ]


_SURFACE_DEPTHS_M: Final = (0.3, 0.35, 0.4, 0.5, 0.6, 0.8, 1.0, 1.2, 1.5, 2.0, 3.0)
"""Depths of midship [m] at which the report gives the critical speed near the surface (SUBOFF's;
Froude-scaled on another vehicle: :func:`_surface_depths`)."""
_SURFACE_SPEED_RATIOS: Final = (
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
_PERISCOPE_DEPTHS_M: Final = (1.0, 1.2)  # PeriscopeDepth's ordered depths (subenv.scenarios.presets)


def _surface_depths(vehicle: Vehicle, depths: tuple[float, ...] = _SURFACE_DEPTHS_M) -> tuple[float, ...]:
    """SUBOFF's depths Froude-scaled to ``vehicle``'s length, as the scenarios' are; those where its hull (of
    another shape) would broach are left out."""
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
    """alpha -> the shallowest depth held at each of :data:`_SURFACE_SPEED_RATIOS`."""
    suction_N: tuple[float, ...]
    """The suction at :data:`_SURFACE_DEPTHS_M`, level, at u_cr [N, down positive]."""
    growth_per_s: tuple[float, ...]
    """The fastest eigenvalue's real part of level flight at :data:`_SURFACE_DEPTHS_M`, planes held,
    0.5 u_cr [1/s]."""


def surface_findings(vehicle: Vehicle) -> SurfaceFindings:
    """The free-surface section's numbers: the critical speed two ways, the shallowest depth held, the
    suction and the stability of level flight against depth."""
    ucr = critical_speed(vehicle)
    depths = _surface_depths(vehicle)
    critical = tuple(surface_critical_speed(vehicle, h) for h in depths)
    held = {
        a: tuple(min_level_flight_depth(vehicle, r * ucr, a) for r in _SURFACE_SPEED_RATIOS)
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


def _surface_markdown(vehicle: Vehicle, found: SurfaceFindings) -> list[str]:
    ucr = critical_speed(vehicle)
    header = (
        "| depth [m] | suction at u_cr [N] | u_cr, eq. 3.9 + suction [m/s] | u_cr, linearised rhs [m/s] "
        "| shift | growth, planes held, 0.5 u_cr [1/s] |"
    )
    lines = [header, "|---:|---:|---:|---:|---:|---:|"]
    for c, z, g in zip(found.critical, found.suction_N, found.growth_per_s, strict=True):
        mark = "" if c.within_validity else " *"
        lines.append(
            f"| {c.depth_m:.2f}{mark} | {z:.3f} | {c.speed_mps:.4f} | {c.speed_numerical_mps:.4f} | "
            f"{100 * c.shift:+.2f} % | {g:+.4f} |"
        )
    alphas = tuple(found.held)
    held = [
        ("| u / u_cr | " + " | ".join(f"alpha = {a:g}" for a in alphas) + " |"),
        "|---:|" + "---|" * len(alphas),
    ]
    for k, r in enumerate(_SURFACE_SPEED_RATIOS):
        cells = [f"{found.held[a][k].min_depth_m:.3f} m ({found.held[a][k].limited_by})" for a in alphas]
        held.append(f"| {r:g} | " + " | ".join(cells) + " |")
    return [
        "## Beyond the thesis: level flight near the free surface",
        "",
        "Riedel (1993) Ch. VI's first recommendation: a more complete expression for the free surface's",
        "effect, taken into the bifurcation analysis. The model (`subenv.dynamics.free_surface`,",
        "docs/free_surface.md) is the consistent first-order slender-body theory under a rigid lid (the",
        "zero-Froude limit of Havelock's free-surface source): the Lagally force of the hull's sources in",
        "their images' flow, the couple u int (rho S + a_33) w dx of the dipoles the images raise, and the",
        "images of the hull's own cross-flow (its share of Z_w, M_w, Z_q, M_q). The force is up,",
        "proportional to u^2 and falls as h^-4 far away; in level flight the moment grows as the bow rises.",
        "It enters the one right-hand side, so the critical speed (eq. 3.9 with the suction's pitch and",
        "heave derivatives, checked by the root of the linearised steady depth-rate gain), the trims and",
        "their stability follow from it. The model holds deeper than two hull radii "
        f"({validity_depth_m(vehicle):.3g} m) and for u^2 / (g h) up to 0.25; depths marked * lie",
        "shallower, where it is extrapolated (its line images' error grows as (r / 2h)^2).",
        f"Deep-water u_cr = {ucr:.4f} m/s.",
        "",
        *lines,
        "",
        "With the planes held, level flight near the surface is unstable in depth: the suction weakens with",
        "depth, so a boat pushed down keeps sinking and one pushed up keeps rising (the growth rate above).",
        "The shallowest depth at which level flight is held with the planes within "
        f"{vehicle.planes.limit_rad:.2g} rad",
        "(the trim followed up from deep water; `planes`: the plane limit; `no trim`: the trim meets another",
        "in a fold and vanishes; `broaching`: held up to the hull radius):",
        "",
        *held,
        "",
    ]


def _surface_figure(fig: Any, vehicle: Vehicle, found: SurfaceFindings) -> str:
    ucr = critical_speed(vehicle)
    left, right = fig.subplots(1, 2)
    top, bottom = _surface_depths(vehicle, (3.0, 2.0))
    shallowest = max(
        0.27 * froude_factor("length", reference_length_ratio(vehicle)), 0.51 * max(vehicle.hull.breadth_m)
    )
    depths = np.geomspace(shallowest, top, 120)
    closed = [surface_critical_speed(vehicle, h).speed_mps / ucr for h in depths]
    left.plot(closed, depths, lw=1.2, label="eq. 3.9 with the suction's\npitch and heave derivatives")
    left.plot(
        [c.speed_numerical_mps / ucr for c in found.critical],
        [c.depth_m for c in found.critical],
        "o",
        ms=4,
        label="root of the linearised\nsteady depth-rate gain",
    )
    left.set(xlabel="u_cr(depth) / u_cr(deep)", ylabel="depth of midship [m]", ylim=(top, 0.0))
    left.legend(fontsize="small", loc="lower left")
    markers = {"planes": "o", "no trim": "x", "broaching": "^"}
    for k, a in enumerate(found.held):
        rows = found.held[a]
        right.plot(
            _SURFACE_SPEED_RATIOS,
            [r.min_depth_m for r in rows],
            "-",
            color=f"C{k}",
            lw=1,
            label=f"alpha = {a:g}",
        )
        for why, marker in markers.items():
            pts = [
                (x, r.min_depth_m)
                for x, r in zip(_SURFACE_SPEED_RATIOS, rows, strict=True)
                if r.limited_by == why
            ]
            if pts:
                right.plot(*zip(*pts, strict=True), marker, color=f"C{k}", ms=5)
    for why, marker in markers.items():
        right.plot([], [], marker, color="0.3", label=why)
    right.axhspan(
        *_surface_depths(vehicle, _PERISCOPE_DEPTHS_M), color="0.85", label="PeriscopeDepth's\nordered depths"
    )
    both = critical_speed(vehicle, 1.0) / ucr if vehicle.planes.has_bow_planes else None
    for k, x in enumerate((1.0, both) if both is not None else (1.0,)):
        right.axvline(x, color=f"C{k}", ls=":", lw=1)
    right.set(
        xlabel="u / u_cr (deep water, alpha = 0)",
        ylabel="shallowest depth held [m]",
        ylim=(bottom, 0.0),
        xlim=(0.25, 2.05),
    )
    right.legend(fontsize="small", loc="lower right")
    worst = max((r for r in found.held[0.0] if r.speed_mps < ucr), key=lambda r: r.min_depth_m)
    one_metre = _surface_depths(vehicle, (1.0,))[0]
    shift = next(c for c in found.critical if c.depth_m == one_metre).shift
    both_text = (
        ""
        if both is None
        else f" With both pairs (alpha = 1, u_cr = {both:.2f} u_cr(alpha = 0)) the band "
        "moves up in speed and shallower."
    )
    return (
        f"Left: the critical speed falls towards the surface ({100 * shift:+.1f} % at {one_metre:.3g} m, "
        f"{100 * found.critical[0].shift:+.0f} % at {found.critical[0].depth_m:g} m), the two ways agreeing. "
        "Right (dotted: each allocation's deep-water u_cr): "
        f"just below each allocation's critical speed level flight cannot be held near the surface: its "
        f"trim vanishes in a fold (stern planes alone, at {worst.speed_mps / ucr:.2f} u_cr not above "
        f"{worst.min_depth_m:.2f} m, deeper than PeriscopeDepth's ordered depths).{both_text}"
    )


# --- figures ----------------------------------------------------------------------------------


def _fn_axis(vehicle: Vehicle, fn: np.ndarray) -> np.ndarray:
    return fn * math.sqrt(vehicle.gravity_m_s2 * vehicle.z_GB_m)


def _plot_branches(
    ax: Any,
    xs: list[float],
    states: list[list[Equilibrium]],
    value: Callable[[Equilibrium], float],
    label: str | None = None,
    color: str = "C0",
) -> None:
    """Scatter steady states: filled = stable, hollow = unstable."""
    stable = [(x, value(e)) for x, es in zip(xs, states, strict=True) for e in es if e.stable]
    unstable = [(x, value(e)) for x, es in zip(xs, states, strict=True) for e in es if not e.stable]
    if stable:
        ax.plot(*zip(*stable, strict=True), ".", ms=3, color=color, label=label and f"{label} (stable)")
    if unstable:
        ax.plot(
            *zip(*unstable, strict=True),
            "o",
            ms=2.5,
            mfc="none",
            color=color,
            alpha=0.6,
            label=label and f"{label} (unstable)",
        )


def _legend_outside(ax: Any) -> None:
    """The legend to the right of the axes, where it covers no data (the figure's constrained
    layout makes room for it)."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize="small")


_TITLES: Final = {
    "fig3-4": "Closed-loop eigenvalues against speed, thesis gain (Riedel 1993, Fig. 3-4)",
    "fig3-5_3-7": "Symmetric pitchfork: steady pitch, plane angle and depth offset against Froude number\n"
    "(Riedel 1993, Figs 3-5 to 3-7)",
    "fig3-9": "Critical Froude number against the bow/stern allocation alpha (Riedel 1993, Fig. 3-9)",
    "fig3-13": "Critical and plane-saturation Froude numbers against alpha (Riedel 1993, Fig. 3-13)",
    "fig3-14": "Controllability determinant against Froude number (Riedel 1993, Fig. 3-14)",
    "fig4-1": "Steady pitch against Froude number, with and without a ballast offset\n"
    "(Riedel 1993, Fig. 4-1)",
    "fig4-2": "Bifurcation sets in the ballast offset-Froude number plane (Riedel 1993, Fig. 4-2)",
    "fig4-6": "Steady pitch against Froude number with plane saturation, x_GB/L = -1e-4\n"
    "(Riedel 1993, Fig. 4-6)",
    "fig4-11": "Path A at constant ballast through the bifurcation and saturation cusps\n"
    "(Riedel 1993, Fig. 4-11)",
    "fig4-13": "Steady pitch against ballast offset at constant speed: hysteresis (Riedel 1993, Fig. 4-13)",
    "fig5-2": "Level-flight trim against speed with 0.01% excess buoyancy (Riedel 1993, Fig. 5-2)",
    "fig5-3": "Depth gain of the pole placement repeated at each speed (Riedel 1993, Fig. 5-3)",
    "fig5-4": "Critical Froude number as the bow planes' share alpha grows (Riedel 1993, Fig. 5-4)",
    "fig5-7": "Saturation cusps with drag and excess buoyancy (supplementary; Riedel 1993, Fig. 5-7)",
    "hopf": "Planes held at zero: growth of the pitch oscillation and amplitude of the cycles against speed\n"
    "(the Hopf bifurcation Riedel 1993 Ch. VI asks for)",
    "free_surface": "Near the free surface: the critical speed against depth, and the shallowest depth at "
    "which\nlevel flight is held within the plane limit against speed (Riedel 1993 Ch. VI's first "
    "recommendation)",
}
"""Each figure's title: what it shows, then the thesis figure it reproduces."""


def _figures(vehicle: Vehicle) -> dict[str, Callable[[Any], str]]:
    """Name -> function drawing into a fresh figure and returning its caption (keys: :data:`_TITLES`)."""
    drag_free = vehicle.variant(crossflow_drag=0.0)
    L = vehicle.length_m
    ucr = critical_speed(vehicle)
    fn_scale = math.sqrt(vehicle.gravity_m_s2 * vehicle.z_GB_m)

    def fig_3_4(fig: Any) -> str:
        speeds = np.linspace(0.3, 2.0, 400)
        eig = closed_loop_eigenvalues(vehicle, speeds, thesis_gain(vehicle))
        ax = fig.subplots()
        for k in range(4):
            ax.plot(mps_to_fps(speeds), eig[:, k].real, lw=1)
        ax.axhline(0, color="k", lw=0.5)
        ax.axvline(mps_to_fps(ucr), color="r", ls="--", lw=1, label=f"u_cr = {mps_to_fps(ucr):.4f} fps")
        ax.set(xlabel="speed [fps]", ylabel="Re(eigenvalue) [1/s]", ylim=(-1.5, 0.3))
        _legend_outside(ax)
        return (
            "Fig. 3-4: real parts of the closed-loop eigenvalues with the thesis gain; one crosses zero at "
            "u_cr."
        )

    def fig_3_5_to_3_7(fig: Any) -> str:
        fns = np.linspace(0.6, 1.3, 141)
        states = [symmetric_pitchfork(drag_free, float(u)) for u in _fn_axis(vehicle, fns)]
        axes = fig.subplots(3, 1, sharex=True)
        _plot_branches(axes[0], list(fns), states, lambda e: _deg(e.pitch_rad), "pitch")
        _plot_branches(axes[1], list(fns), states, lambda e: _deg(e.plane_rad), "plane")
        depth = [[e for e in es if e.depth_offset_m is not None] for es in states]
        _plot_branches(axes[2], list(fns), depth, lambda e: float(e.depth_offset_m or 0.0) / L, "Z_ss/L")
        axes[0].set_ylabel("theta [deg]")
        axes[1].set_ylabel("delta [deg]")
        axes[2].set_ylabel("Z_ss / L")
        axes[2].set_xlabel("Froude number")
        _legend_outside(axes[0])
        return (
            "Figs 3-5 to 3-7: symmetric pitchfork (eqs 3.17-3.23) with saturation (eq. 4.42); filled stable, "
            "hollow unstable. Saturated states sink or rise steadily, so have no Z_ss."
        )

    def fig_3_9(fig: Any) -> str:
        alphas = np.linspace(-1, 1, 201)
        ax = fig.subplots()
        ax.plot([critical_froude(vehicle, float(a)) for a in alphas], alphas)
        ax.set(xlabel="critical Froude number", ylabel="alpha")
        ax.grid(alpha=0.3)
        return "Fig. 3-9: critical Froude number versus the bow/stern allocation alpha (0.80 to 1.22)."

    def fig_3_13(fig: Any) -> str:
        alphas = np.linspace(-1, 1, 201)
        ax = fig.subplots()
        ax.plot([critical_froude(vehicle, float(a)) for a in alphas], alphas, label="critical")
        ax.plot(
            [_saturation_pitch_and_froude(vehicle, float(a))[1] for a in alphas],
            alphas,
            "--",
            label="saturation",
        )
        ax.set(xlabel="Froude number", ylabel="alpha")
        _legend_outside(ax)
        return "Fig. 3-13: critical and plane-saturation Froude numbers versus alpha."

    def fig_3_14(fig: Any) -> str:
        fns = np.linspace(0.5, 1.6, 400)
        ax = fig.subplots()
        for a in (-1.0, 0.0, 1.0):
            det = np.array(
                [controllability_determinant(vehicle, float(u), a) for u in _fn_axis(vehicle, fns)]
            )
            ax.plot(fns, det / np.abs(det).max(), label=f"alpha = {a:g}")
        ax.axhline(0, color="k", lw=0.5)
        ax.set(xlabel="Froude number", ylabel="det(controllability matrix), normalised")
        _legend_outside(ax)
        return "Fig. 3-14: the controllability matrix becomes singular at the critical Froude number."

    def fig_4_1(fig: Any) -> str:
        fns = np.linspace(0.6, 1.4, 161)
        biased = drag_free.variant(x_GB_m=_XGB_OVER_L_CH4 * L)
        ax = fig.subplots()
        for v, color, name in ((drag_free, "C0", "x_GB = 0"), (biased, "C1", "x_GB/L = -1e-4")):
            xs, ths, stab = [], [], []
            for fn in fns:
                for e in equilibria(v, fn * fn_scale, saturation=False):
                    xs.append(fn)
                    ths.append(_deg(e.pitch_rad))
                    stab.append(e.stable)
            xs_a, ths_a, stab_a = np.array(xs), np.array(ths), np.array(stab)
            ax.plot(xs_a[stab_a], ths_a[stab_a], ".", ms=3, color=color, label=f"{name} stable")
            ax.plot(
                xs_a[~stab_a],
                ths_a[~stab_a],
                "o",
                ms=2.5,
                mfc="none",
                color=color,
                alpha=0.6,
                label=f"{name} unstable",
            )
        ax.set(xlabel="Froude number", ylabel="theta [deg]", ylim=(-40, 40))
        _legend_outside(ax)
        return (
            "Fig. 4-1: exact steady states (eq. 4.3, no saturation) for x_GB/L = -1e-4 next to the symmetric "
            "pitchfork; the bias perturbs the pitchfork and moves the bifurcation to lower Fn."
        )

    def fig_4_2(fig: Any) -> str:
        lam = np.linspace(0.6, 1.2, 121)
        speeds = bif.speed_from_lambda(drag_free, lam)
        lo, hi = bif.exact_bifurcation_set(drag_free, speeds)
        ax = fig.subplots()
        ax.plot(lo / L, np.sqrt(lam), "k-", label="exact bifurcation set (eq. 4.3 folds)")
        ax.plot(hi / L, np.sqrt(lam), "k-")
        forms: tuple[tuple[bif.CuspForm, str], ...] = (("consistent", "C0--"), ("thesis", "C1:"))
        for form, style in forms:
            beta = bif.exact_cusp(drag_free, lam, form=form)
            x = bif.offset_from_beta(drag_free, beta, speeds) / L
            ax.plot(x, np.sqrt(lam), style, label=f"exact cusp eq. 4.37 ({form})")
            ax.plot(-x, np.sqrt(lam), style)
        beta = np.linspace(-0.02, 0.02, 201)
        lam_approx = bif.approximate_cusp(drag_free, beta)
        x = bif.offset_from_beta(drag_free, beta, bif.speed_from_lambda(drag_free, lam_approx)) / L
        ax.plot(x, np.sqrt(lam_approx), "C2-.", label="approximate cusp eq. 4.39")
        ax.set(xlabel="x_GB / L", ylabel="sqrt(lambda) = Fn", xlim=(-6e-4, 6e-4))
        _legend_outside(ax)
        return (
            "Fig. 4-2: bifurcation sets in the (x_GB, Fn) plane. The printed eq. 4.37 carries a dimensional "
            "u^2 (evaluated in fps, as the thesis did); the dimensionally consistent cusp matches the exact "
            "folds."
        )

    def fig_4_6(fig: Any) -> str:
        fns = np.linspace(0.6, 1.4, 161)
        biased = drag_free.variant(x_GB_m=_XGB_OVER_L_CH4 * L)
        states = [equilibria(biased, float(fn * fn_scale)) for fn in fns]
        ax = fig.subplots()
        _plot_branches(ax, list(fns), states, lambda e: _deg(e.pitch_rad), "x_GB/L = -1e-4")
        ax.set(xlabel="Froude number", ylabel="theta [deg]")
        _legend_outside(ax)
        return "Fig. 4-6: exact solution set for x_GB/L = -1e-4 with plane saturation (eqs 4.3, 4.42)."

    def fig_4_11(fig: Any) -> str:
        fn = np.linspace(0.7, 1.3, 241)
        speeds = fn * fn_scale
        lo, hi = bif.exact_bifurcation_set(drag_free, speeds)
        xp, xm = bif.saturation_cusp(drag_free, speeds)
        ax = fig.subplots()
        ax.plot(lo / L, fn, "k-", label="exact bifurcation set")
        ax.plot(hi / L, fn, "k-")
        ax.plot(xp / L, fn, "C1:", label="saturation cusp (eqs 4.43-4.45)")
        ax.plot(xm / L, fn, "C1:")
        ax.axvline(_XGB_OVER_L_CH4, color="C2", label="path A, x_GB/L = -1e-4")
        ax.set(xlabel="x_GB / L", ylabel="sqrt(lambda)", xlim=(-6e-4, 6e-4))
        _legend_outside(ax)
        return "Fig. 4-11: path A at constant ballast through the bifurcation and saturation cusps."

    def fig_4_13(fig: Any) -> str:
        ax = fig.subplots()
        xs = np.linspace(-5e-4, 5e-4, 201)
        for fn, color, name in ((_PATH_C_FN, "C0", "path C, Fn 1.0"), (_PATH_B_FN, "C1", "path B, Fn 1.1")):
            u = fn * fn_scale
            states = [equilibria(drag_free.variant(x_GB_m=float(x * L)), u) for x in xs]
            _plot_branches(ax, list(xs), states, lambda e: _deg(e.pitch_rad), name, color)
            branch = continue_equilibria(
                drag_free, "x_GB", -5e-4 * L, 5e-4 * L, speed_mps=u, initial_pitch_rad=0.5
            )
            ax.plot(
                branch.values / L,
                np.degrees(branch.states[:, 0]),
                "-",
                color=color,
                lw=0.6,
                alpha=0.5,
                label=f"{name}: continuation, planes unlimited",
            )
        ax.set(xlabel="x_GB / L", ylabel="theta [deg]", ylim=(-20, 20))
        _legend_outside(ax)
        return (
            "Fig. 4-13: steady pitch versus ballast at constant speed. With saturation, path C (Fn 1.0) "
            "jumps between the saturated branches (hysteresis); the thin lines are the pseudo-arclength "
            "continuation of the unlimited-plane steady states, whose folds give the S-shape."
        )

    def fig_5_2(fig: Any) -> str:
        speeds = np.linspace(0.25, 1.6, 541)
        light = drag_free.variant(excess_buoyancy_N=1e-4 * drag_free.weight_N)
        trim = level_flight_trim(light, speeds)
        axes = fig.subplots(2, 1, sharex=True)
        axes[0].plot(speeds, np.degrees(trim.pitch_rad))
        axes[1].plot(speeds, np.degrees(trim.plane_rad))
        for ax in axes:
            ax.axvline(ucr, color="r", ls="--", lw=1, label=f"u_cr = {ucr:.3f} m/s")
            ax.axhline(0, color="k", lw=0.5)
        axes[0].set(ylabel="pitch [deg]", ylim=(-20, 20))
        axes[1].set(ylabel="stern planes [deg]", ylim=(-40, 40), xlabel="speed [m/s]")
        limit_deg = math.degrees(vehicle.planes.limit_rad)
        axes[1].axhspan(
            -limit_deg,
            limit_deg,
            color="g",
            alpha=0.08,
            label=f"within the plane limit +-{limit_deg:.1f} deg",
        )
        _legend_outside(axes[0])
        _legend_outside(axes[1])
        return (
            "Fig. 5-2: pitch and stern-plane angle for straight and level flight with 0.01% excess buoyancy "
            "(BIFSU.M's B = 1.0001 W); both pass through infinity at u_cr and reverse sign below it."
        )

    def fig_5_3(fig: Any) -> str:
        speeds = np.linspace(0.25, 1.6, 541)
        k4 = scheduled_depth_gain(vehicle, speeds)
        ax = fig.subplots()
        ax.plot(speeds, k4)
        ax.axvline(ucr, color="r", ls="--", lw=1, label=f"u_cr = {ucr:.3f} m/s")
        ax.set(xlabel="speed [m/s]", ylabel="scheduled depth gain k4 [rad/m]", ylim=(-5, 5))
        _legend_outside(ax)
        return (
            "Fig. 5-3: depth gain of the pole-placement design repeated at each speed; it diverges at u_cr."
        )

    def fig_5_4(fig: Any) -> str:
        alphas = np.logspace(-2, 3, 300)
        ax = fig.subplots()
        fns = []
        c = vehicle.coefficients
        for a in alphas:
            # Z_ds + alpha Z_db scaled by 1/alpha (the same critical speed), so alpha -> infinity
            # tends to bow planes only.
            u_cr = critical_speed_for_planes(
                vehicle, c.Z_delta_s / a + c.Z_delta_b, c.M_delta_s / a + c.M_delta_b
            )
            fns.append(froude_number(vehicle, u_cr))
        ax.semilogx(alphas, fns)
        ax.axhline(
            critical_froude(vehicle, BOW_PLANES_ONLY), color="r", ls="--", lw=1, label="bow planes only"
        )
        ax.set(xlabel="alpha", ylabel="critical Froude number")
        _legend_outside(ax)
        return "Fig. 5-4: critical Froude number as alpha grows; bow planes alone give 2.05."

    def fig_5_7(fig: Any) -> str:
        fn = np.linspace(0.6, 1.3, 141)
        speeds = fn * fn_scale
        ax = fig.subplots()
        for k, excess in enumerate((0.0, 1e-4, 5e-4)):
            boat = vehicle.variant(crossflow_drag=0.3, excess_buoyancy_N=excess * vehicle.weight_N)
            inputs: tuple[tuple[DragMoment, HullIntegral, str], ...] = (
                ("consistent", "full", "-"),
                ("thesis", "thesis", ":"),
            )
            for moment, hull, style in inputs:
                xp, xm = bif.saturation_cusp(boat, speeds, drag_moment=moment, hull=hull)
                label = f"B-W = {excess:.2%} W, " + (
                    "full hull, M = -x Z" if hull == "full" else "thesis A, x_A, sign"
                )
                ax.plot(xp / L, fn, style, color=f"C{k}", label=label)
                ax.plot(xm / L, fn, style, color=f"C{k}")
        ax.set(xlabel="x_GB / L", ylabel="sqrt(lambda)", xlim=(-1.5e-3, 1.5e-3))
        _legend_outside(ax)
        return (
            "Fig. 5-7 (supplementary): saturation cusps with C_D = 0.3 and excess buoyancy (eqs 5.1-5.2). "
            "Dotted: the thesis's inputs (truncated hull A = 19.85 ft^2, x_A = 0.201 ft, its drag-moment "
            "sign); solid: the full hull and the physically consistent sign the simulation uses."
        )

    return {
        "fig3-4": fig_3_4,
        "fig3-5_3-7": fig_3_5_to_3_7,
        "fig3-9": fig_3_9,
        "fig3-13": fig_3_13,
        "fig3-14": fig_3_14,
        "fig4-1": fig_4_1,
        "fig4-2": fig_4_2,
        "fig4-6": fig_4_6,
        "fig4-11": fig_4_11,
        "fig4-13": fig_4_13,
        "fig5-2": fig_5_2,
        "fig5-3": fig_5_3,
        "fig5-4": fig_5_4,
        "fig5-7": fig_5_7,
    }


def _hopf_figure(fig: Any, vehicle: Vehicle, found: HopfFindings) -> str:
    p = found.point
    speeds = np.linspace(0.36, 1.44, 300) * p.speed_mps
    growth = [oscillatory_growth_rate(vehicle, u) for u in speeds]
    growth = [g if math.isfinite(g) else math.nan for g in growth]  # (no pair: nothing to draw)
    top, bottom = fig.subplots(2, 1, sharex=True)
    top.plot(speeds, growth, lw=1.2, label="Re(lambda), oscillatory pair")
    top.plot(found.env_speeds_mps, found.env_growth_rates, "o", color="C1", label="environment, zero action")
    top.axhline(0.0, color="k", lw=0.5)
    top.axvline(p.speed_mps, color="r", ls="--", lw=1, label=f"u_H = {p.speed_mps:.3f} m/s")
    top.axvline(critical_speed(vehicle), color="0.5", ls=":", lw=1, label="u_cr (planes reverse)")
    top.set(ylabel="growth rate [1/s]")
    orbit_u = np.array(found.orbit_speeds_mps)
    bottom.plot(orbit_u, np.degrees(found.orbit_amplitudes_rad), "o-", ms=3, label="stable cycles (shooting)")
    near = np.linspace(p.speed_mps, orbit_u.max(), 100)
    bottom.plot(
        near,
        [math.degrees(p.predicted_amplitude_rad(vehicle, float(u))) for u in near],
        "--",
        label="normal form -Re(lambda)/c2",
    )
    bottom.axhline(math.degrees(0.6), color="k", ls=":", lw=1, label="environments' pitch limit (0.6 rad)")
    bottom.axvline(p.speed_mps, color="r", ls="--", lw=1)
    bottom.set(xlabel="speed [m/s]", ylabel="cycle pitch amplitude [deg]", ylim=(0.0, 70.0))
    _legend_outside(top)
    _legend_outside(bottom)
    return (
        f"Beyond the thesis: with the planes held, level flight's pitch/heave oscillation grows above "
        f"u_H = {p.speed_mps:.3f} m/s ({p.period_s:.0f} s period; the environment's measured growth rates "
        f"agree). The bifurcation is {p.criticality}: stable cycles grow linearly with u - u_H (the "
        "quadratic drag's signature)"
        + (
            f" and reach the pitch limit at {found.pitch_limit_speed_mps:.2f} m/s."
            if math.isfinite(found.pitch_limit_speed_mps)
            else f", within the pitch limit up to {max(found.orbit_speeds_mps):.2f} m/s."
        )
    )


def _vehicle_table(rows: list[VehicleRow]) -> str:
    lines = ["| quantity | value | unit | note |", "|---|---:|---|---|"]
    lines += [f"| {r.quantity} | {r.computed:.5g} | {r.unit} | {r.note} |" for r in rows]
    return "\n".join(lines)


def _table(rows: list[ReportRow]) -> str:
    lines = [
        "| quantity | thesis value | computed value | difference | unit | note |",
        "|---|---:|---:|---:|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r.quantity} | {r.thesis:.5g} | {r.computed:.5g} | {r.difference:+.3g} | {r.unit} "
            f"| {r.note} |"
        )
    return "\n".join(lines)


REPORT_KIND = "subenv analyze"
"""What a report folder's marker file says (:data:`subenv.atomic.MARKER_FILE`): ``overwrite``
replaces only a folder that says so."""


def write_report(out_dir: str | Path, vehicle: Vehicle | None = None, overwrite: bool = False) -> Path:
    """Write ``report.md`` and the PNG figures into ``out_dir``, completely or not at all.

    The folder is assembled beside ``out_dir`` and put in place atomically
    (:func:`subenv.atomic.atomic_output_dir`), after ``out_dir`` was checked and the temporary
    folder created, before any computation.

    Raises
    ------
    FileExistsError
        ``out_dir`` exists and ``overwrite`` is False, or it is not an earlier report.
    OutputDirError
        ``out_dir`` cannot be created (a file in the way, no permission); a ValueError.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    vehicle = vehicle or load_vehicle("suboff")
    started = time.perf_counter()
    with atomic_output_dir(out_dir, overwrite=overwrite, kind=REPORT_KIND) as folder:
        suboff_shape = has_suboff_shape(vehicle)
        table = (
            _table(reproduce_numbers(vehicle)) if suboff_shape else _vehicle_table(vehicle_numbers(vehicle))
        )
        captions = []
        found = hopf_findings(vehicle)
        surface = surface_findings(vehicle)
        # Figures of the bow/stern allocation need bow planes; Fig. 5-7 redraws the thesis's own inputs (its
        # truncated SUBOFF hull), so it is SUBOFF's alone.
        skipped = (() if vehicle.planes.has_bow_planes else ("fig3-9", "fig3-13", "fig5-4")) + (
            () if suboff_shape else ("fig5-7",)
        )
        figures = {
            **{name: draw for name, draw in _figures(vehicle).items() if name not in skipped},
            "hopf": lambda fig: _hopf_figure(fig, vehicle, found),
            "free_surface": lambda fig: _surface_figure(fig, vehicle, surface),
        }
        for name, draw in figures.items():
            tall = name in ("fig3-5_3-7", "hopf")
            fig = plt.figure(
                figsize=(8.5, 8 if name == "fig3-5_3-7" else 7) if tall else (8.5, 5), layout="constrained"
            )
            caption = draw(fig)
            fig.suptitle(_TITLES[name], fontsize="medium")
            fig.savefig(folder / f"{name}.png", dpi=100)
            plt.close(fig)
            captions.append((name, caption))
        elapsed = time.perf_counter() - started
        if suboff_shape:
            intro = [
                "# Reproduction of Riedel (1993) with subenv",
                "",
                f"Vehicle: {vehicle.name} ({vehicle.description}). Figures 3-4 to 5-4 use C_D = 0 as the",
                "thesis's did (so neither the hull integral nor the drag-moment sign enters them). The",
                "supplementary Fig. 5-7 has drag: it is drawn with the thesis's inputs (truncated hull",
                "integral, printed moment sign) next to the full hull with the physically consistent sign.",
                "",
                "## Published numbers",
                "",
                table,
                "",
                "Equation 4.37 as printed is not dimensionless; Fig. 4-2 shows it evaluated as printed (u in",
                "fps) next to the dimensionally consistent form, which agrees with the exact folds of",
                "eq. 4.3.",
                "",
            ]
        else:
            intro = [
                f"# Riedel (1993)'s analysis of {vehicle.name} with subenv",
                "",
                f"Vehicle: {vehicle.name} ({vehicle.description}); source: {vehicle.source}. The thesis",
                "studied SUBOFF, so its published numbers do not apply here: the same analysis code computes",
                "this vehicle's. The figures are the thesis's, drawn for this vehicle, with C_D = 0 as the",
                "thesis's Ch. III-IV did"
                + (
                    "."
                    if vehicle.planes.has_bow_planes
                    else "; it has no bow planes, so the figures of the bow/stern"
                    " allocation (3-9, 3-13, 5-4) are left out."
                ),
                "",
                "## Critical speed and saturation",
                "",
                table,
                "",
            ]
        text = [
            *intro,
            *_hopf_markdown(vehicle, found),
            *_surface_markdown(vehicle, surface),
            "## Figures",
            "",
        ]
        for name, caption in captions:
            text += [f"![{name}]({name}.png)", "", caption, ""]
        text += [f"Generated in {elapsed:.1f} s."]
        (folder / "report.md").write_text("\n".join(text) + "\n")
    return Path(out_dir)
