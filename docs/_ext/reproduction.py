"""The reproduction report of Riedel (1993): its Markdown pages and figures, written at build time.

The numbers are the library's (:func:`subenv.analysis.report.reproduction`, what ``subenv analyze``
writes as ``report.json``); this module lays them out as the documentation's pages and redraws the
thesis's figures (3-4 to 5-7) and the two beyond it (the Hopf bifurcation, the free surface) from the
library's functions, for SUBOFF and for the REMUS 100.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any, Final

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from subenv.analysis import bifurcation as bif
from subenv.analysis.continuation import continue_equilibria
from subenv.analysis.critical import (
    critical_froude,
    critical_speed,
    critical_speed_for_planes,
    froude_number,
)
from subenv.analysis.design import (
    closed_loop_eigenvalues,
    controllability_determinant,
    scheduled_depth_gain,
    thesis_gain,
)
from subenv.analysis.equilibria import (
    DragMoment,
    Equilibrium,
    HullIntegral,
    equilibria,
    symmetric_pitchfork,
)
from subenv.analysis.free_surface import surface_critical_speed
from subenv.analysis.hopf import oscillatory_growth_rate
from subenv.analysis.linear import BOW_PLANES_ONLY
from subenv.analysis.report import (
    FIG_4_X_GB_OVER_L,
    PATH_B_FROUDE,
    PATH_C_FROUDE,
    SURFACE_SPEED_RATIOS,
    HopfFindings,
    ReportRow,
    Reproduction,
    SurfaceFindings,
    VehicleRow,
    reproduction,
    saturation_pitch_and_froude,
    surface_depths,
)
from subenv.analysis.reversal import level_flight_trim
from subenv.dynamics.free_surface import validity_depth_m
from subenv.scenarios import get_scenario
from subenv.thesis import reference_length_ratio
from subenv.units import mps_to_fps
from subenv.vehicles import load_vehicle
from subenv.vehicles.scaling import froude_factor
from subenv.vehicles.vehicle import Vehicle

VEHICLES: Final = ("suboff", "remus100")
"""The vehicles whose report the documentation shows, one page each."""


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
    for k, r in enumerate(SURFACE_SPEED_RATIOS):
        cells = [f"{found.held[a][k].min_depth_m:.3f} m ({found.held[a][k].limited_by})" for a in alphas]
        held.append(f"| {r:g} | " + " | ".join(cells) + " |")
    return [
        "## Beyond the thesis: level flight near the free surface",
        "",
        "Riedel (1993) Ch. VI's first recommendation: a more complete expression for the free surface's",
        "effect, taken into the bifurcation analysis. The model (`subenv.dynamics.free_surface`, the",
        "[free surface's page](../free_surface.md)) is the consistent first-order slender-body theory",
        "under a rigid lid (the zero-Froude limit of Havelock's free-surface source): the Lagally force of",
        "the hull's sources in their images' flow, the couple u int (rho S + a_33) w dx of the dipoles the",
        "images raise, and the images of the hull's own cross-flow (its share of Z_w, M_w, Z_q, M_q). The",
        "force is up, proportional to u^2 and falls as h^-4 far away; in level flight the moment grows as",
        "the bow rises. It enters the one right-hand side, so the critical speed (eq. 3.9 with the suction's",
        "pitch and heave derivatives, checked by the root of the linearised steady depth-rate gain), the",
        "trims and their stability follow from it. The model holds deeper than two hull radii "
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
    top, bottom = surface_depths(vehicle, (3.0, 2.0))
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
            SURFACE_SPEED_RATIOS,
            [r.min_depth_m for r in rows],
            "-",
            color=f"C{k}",
            lw=1,
            label=f"alpha = {a:g}",
        )
        for why, marker in markers.items():
            pts = [
                (x, r.min_depth_m)
                for x, r in zip(SURFACE_SPEED_RATIOS, rows, strict=True)
                if r.limited_by == why
            ]
            if pts:
                right.plot(*zip(*pts, strict=True), marker, color=f"C{k}", ms=5)
    for why, marker in markers.items():
        right.plot([], [], marker, color="0.3", label=why)
    right.axhspan(
        *surface_depths(vehicle, get_scenario("PeriscopeDepth-v1").depth_command_m),
        color="0.85",
        label="PeriscopeDepth's\nordered depths",
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
    one_metre = surface_depths(vehicle, (1.0,))[0]
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
        _plot_branches(axes[0], list(fns), states, lambda e: math.degrees(e.pitch_rad), "pitch")
        _plot_branches(axes[1], list(fns), states, lambda e: math.degrees(e.plane_rad), "plane")
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
            [saturation_pitch_and_froude(vehicle, float(a))[1] for a in alphas],
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
        biased = drag_free.variant(x_GB_m=FIG_4_X_GB_OVER_L * L)
        ax = fig.subplots()
        for v, color, name in ((drag_free, "C0", "x_GB = 0"), (biased, "C1", "x_GB/L = -1e-4")):
            xs, ths, stab = [], [], []
            for fn in fns:
                for e in equilibria(v, fn * fn_scale, saturation=False):
                    xs.append(fn)
                    ths.append(math.degrees(e.pitch_rad))
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
        biased = drag_free.variant(x_GB_m=FIG_4_X_GB_OVER_L * L)
        states = [equilibria(biased, float(fn * fn_scale)) for fn in fns]
        ax = fig.subplots()
        _plot_branches(ax, list(fns), states, lambda e: math.degrees(e.pitch_rad), "x_GB/L = -1e-4")
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
        ax.axvline(FIG_4_X_GB_OVER_L, color="C2", label="path A, x_GB/L = -1e-4")
        ax.set(xlabel="x_GB / L", ylabel="sqrt(lambda)", xlim=(-6e-4, 6e-4))
        _legend_outside(ax)
        return "Fig. 4-11: path A at constant ballast through the bifurcation and saturation cusps."

    def fig_4_13(fig: Any) -> str:
        ax = fig.subplots()
        xs = np.linspace(-5e-4, 5e-4, 201)
        for fn, color, name in (
            (PATH_C_FROUDE, "C0", "path C, Fn 1.0"),
            (PATH_B_FROUDE, "C1", "path B, Fn 1.1"),
        ):
            u = fn * fn_scale
            states = [equilibria(drag_free.variant(x_GB_m=float(x * L)), u) for x in xs]
            _plot_branches(ax, list(xs), states, lambda e: math.degrees(e.pitch_rad), name, color)
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


def _figure_size(name: str) -> tuple[float, float]:
    return {"fig3-5_3-7": (8.5, 8.0), "hopf": (8.5, 7.0)}.get(name, (8.5, 5.0))


def report_page(
    vehicle: Vehicle, found: Reproduction, figures: str
) -> tuple[str, dict[str, Callable[[Any], str]]]:
    """The page of ``vehicle`` (MyST) and its figures (name -> drawing function returning the caption),
    whose files are ``<figures>/<name>.png`` relative to the page."""
    # Figures of the bow/stern allocation need bow planes; Fig. 5-7 redraws the thesis's own inputs (its
    # truncated SUBOFF hull), so it is SUBOFF's alone.
    skipped = (() if vehicle.planes.has_bow_planes else ("fig3-9", "fig3-13", "fig5-4")) + (
        () if found.suboff_shape else ("fig5-7",)
    )
    drawings = {
        **{name: draw for name, draw in _figures(vehicle).items() if name not in skipped},
        "hopf": lambda fig: _hopf_figure(fig, vehicle, found.hopf),
        "free_surface": lambda fig: _surface_figure(fig, vehicle, found.surface),
    }
    if found.suboff_shape:
        intro = [
            f"# Reproduction of Riedel (1993): {vehicle.name}",
            "",
            f"Vehicle: `{vehicle.name}` ({vehicle.description}). Figures 3-4 to 5-4 use C_D = 0 as the",
            "thesis's did (so neither the hull integral nor the drag-moment sign enters them). The",
            "supplementary Fig. 5-7 has drag: it is drawn with the thesis's inputs (truncated hull",
            "integral, printed moment sign) next to the full hull with the physically consistent sign.",
            "",
            "## Published numbers",
            "",
            _table(list(found.published)),
            "",
            "Equation 4.37 as printed is not dimensionless; Fig. 4-2 shows it evaluated as printed (u in",
            "fps) next to the dimensionally consistent form, which agrees with the exact folds of",
            "eq. 4.3.",
            "",
        ]
    else:
        intro = [
            f"# Riedel (1993)'s analysis of {vehicle.name}",
            "",
            f"Vehicle: `{vehicle.name}` ({vehicle.description}); source: {vehicle.source}. The thesis",
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
            _vehicle_table(list(found.numbers)),
            "",
        ]
    text = [
        *intro,
        f"The numbers are `subenv analyze --vehicle {vehicle.name}`'s (its `report.json`).",
        "",
        *_hopf_markdown(vehicle, found.hopf),
        *_surface_markdown(vehicle, found.surface),
        "## Figures",
        "",
    ]
    return "\n".join(text), drawings


def write_pages(folder: Path) -> None:
    """Write ``index.md`` and one page per vehicle of :data:`VEHICLES`, with its figures, into ``folder``."""
    for name in VEHICLES:
        vehicle = load_vehicle(name)
        text, drawings = report_page(vehicle, reproduction(vehicle), name)
        (folder / name).mkdir()
        lines = [text]
        for figure, draw in drawings.items():
            fig = plt.figure(figsize=_figure_size(figure), layout="constrained")
            caption = draw(fig)
            fig.suptitle(_TITLES[figure], fontsize="medium")
            fig.savefig(folder / name / f"{figure}.png", dpi=100)
            plt.close(fig)
            lines += [f":::{{figure}} {name}/{figure}.png", f":name: {name}-{figure}", "", caption, ":::", ""]
        (folder / f"{name}.md").write_text("\n".join(lines) + "\n", "utf-8")
    (folder / "index.md").write_text(
        "\n".join(
            [
                "# Reproduction report",
                "",
                "Riedel (1993)'s published numbers recomputed by the package, his figures redrawn, and",
                "the two analyses his Ch. VI asks for (the Hopf bifurcation at speed, the free surface),",
                "for SUBOFF and, with the same code, for the REMUS 100. Written when the documentation",
                "is built, from {func}`subenv.analysis.report.reproduction` (what `subenv analyze` writes",
                "as `report.json`).",
                "",
                "```{toctree}",
                ":maxdepth: 1",
                "",
                *VEHICLES,
                "```",
                "",
            ]
        ),
        "utf-8",
    )
