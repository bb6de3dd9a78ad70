"""Plots of an evaluation: a typical episode of every outcome, and metrics against u / u_cr.

Figures are built on :class:`matplotlib.figure.Figure` directly (the Agg canvas, no pyplot state,
no display needed) and written atomically. matplotlib is the optional ``plot`` extra. Legends sit
outside the axes, so they never cover data.
"""

from __future__ import annotations

import io
import math
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np

from subenv.atomic import atomic_write_bytes
from subenv.evaluation.controller import Controller
from subenv.evaluation.measure import EpisodeResult
from subenv.evaluation.metrics import DEPTH_TOLERANCE_M, HOLD_WINDOW_S
from subenv.evaluation.results import by_speed_ratio, representative_episodes
from subenv.evaluation.rollout import run_episode
from subenv.evaluation.stats import CONFIDENCE_LEVEL
from subenv.evaluation.trajectory import Trajectory
from subenv.extras import require
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "metrics_vs_speed_figure",
    "outcomes_figure",
    "plot_metrics_vs_speed",
    "plot_outcomes",
    "replay_trajectory",
    "require_matplotlib",
    "save_figure",
    "speed_crossing_s",
]

_DPI: Final = 110

_HOLD_COLOR: Final = "gold"
_HOLD_ALPHA: Final = 0.3
"""The final hold window on the depth-error axes: see-through, so the tolerance band shows within it."""

_OUTCOME_COLORS: Final = {
    "success": "tab:green",
    "wrong_branch": "tab:red",
    "steady_offset": "tab:orange",
    "broached": "tab:blue",
    "left_depth_band": "tab:purple",
    "pitch_limit": "tab:brown",
    "diverged": "black",
    "unsettled": "tab:gray",
}
"""One colour per outcome, the same in every figure (an outcome not listed is drawn in magenta)."""


def require_matplotlib() -> None:
    """Raise :class:`~subenv.extras.MissingExtra` (an ImportError naming the ``plot`` extra) without
    matplotlib."""
    require("plot", "the plots", "matplotlib")


def save_figure(fig: Any, path: str | os.PathLike[str], image_format: str = "png") -> Path:
    """Write a matplotlib figure to ``path`` completely or not at all.

    The figure is rendered in memory (``image_format``, e.g. ``"png"``, ``"pdf"``, ``"svg"``; 110 dpi)
    and written with :func:`~subenv.atomic.atomic_write_bytes`. Returns the path.
    """
    buffer = io.BytesIO()
    fig.savefig(buffer, format=image_format, dpi=_DPI)
    return atomic_write_bytes(path, buffer.getvalue())


# --- a typical episode of every outcome -------------------------------------------------------
def replay_trajectory(
    result: EpisodeResult,
    controller: Controller,
    *,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> Trajectory:
    """The trajectory of ``result``: its own if kept, else the episode run again from its seed.

    Seeded episodes are deterministic, so running ``controller`` (the one that produced ``result``)
    on the same scenario, seed, vehicle, time limit and environment settings gives the same episode.
    The replay is checked against the recorded metrics (outcome and IAE); a mismatch raises ValueError,
    since a figure of a different episode would mislabel it.
    """
    if result.trajectory is not None:
        return result.trajectory
    if controller.name != result.controller:
        raise ValueError(
            f"result of controller {result.controller!r} cannot be replayed with {controller.name!r}"
        )
    again = run_episode(
        controller,
        result.scenario,
        result.seed,
        episode=result.episode,
        vehicle=vehicle,
        max_duration_s=max_duration_s,
        env_kwargs=env_kwargs,
    )
    if again.metrics.outcome != result.metrics.outcome or not math.isclose(
        again.metrics.iae_m_s, result.metrics.iae_m_s, rel_tol=1e-6, abs_tol=1e-9
    ):
        raise ValueError(
            f"replaying {result.controller} on {result.scenario} seed {result.seed} gave outcome "
            f"{again.metrics.outcome!r}, IAE {again.metrics.iae_m_s:.6g} m s; the results say "
            f"{result.metrics.outcome!r}, {result.metrics.iae_m_s:.6g} m s (another vehicle or time limit, "
            "or a controller that is not deterministic?)"
        )
    assert again.trajectory is not None
    return again.trajectory


def speed_crossing_s(trajectory: Trajectory) -> float | None:
    """Time at which the speed first crosses the critical speed [s], linear between the samples on
    either side; None if it stays on one side (at or above u_cr counts as above)."""
    u, ucr = trajectory.speed_mps, trajectory.critical_speed_mps
    above = u >= ucr
    changes = np.flatnonzero(above[1:] != above[:-1])
    if changes.size == 0:
        return None
    k = int(changes[0])
    t0, t1 = trajectory.time_s[k], trajectory.time_s[k + 1]
    return float(t0 + (ucr - u[k]) / (u[k + 1] - u[k]) * (t1 - t0))


def _label(outcome: str) -> str:
    return outcome.replace("_", " ")


def outcomes_figure(
    results: Sequence[EpisodeResult],
    trajectory_of: Callable[[EpisodeResult], Trajectory] | None = None,
    *,
    title: str | None = None,
) -> Any:
    """The figure of :func:`plot_outcomes` (a :class:`matplotlib.figure.Figure`), not written.

    One column per outcome that occurred, holding the episode
    :func:`~subenv.evaluation.results.representative_episodes` chose for it; the top axes of a
    column is titled with the outcome, how many of the shown controller's episodes and how many of
    all the episodes had it, the controller, seed and speed ratio.
    """
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    scenarios = list(dict.fromkeys(r.scenario for r in results))
    if len(scenarios) != 1:
        raise ValueError(f"results come from scenarios {scenarios}: pass the episodes of one scenario")
    chosen = representative_episodes(results)[scenarios[0]]

    def own(r: EpisodeResult) -> Trajectory:
        if r.trajectory is None:
            raise ValueError(
                f"{r.controller} on {r.scenario} seed {r.seed} has no trajectory: pass trajectory_of"
            )
        return r.trajectory

    get = trajectory_of or own
    shown = [(outcome, r, get(r)) for outcome, r in chosen.items()]
    with_speed = any(np.ptp(tr.speed_mps) > 0 for _, _, tr in shown)
    rows = 4 if with_speed else 3
    fig = Figure(figsize=(max(6.0, 3.4 * len(shown)), 2.1 * rows + 2.1), layout="constrained")
    axes = fig.subplots(rows, len(shown), sharex="col", squeeze=False)
    crossing_drawn = False
    for col, (outcome, r, tr) in enumerate(shown):
        color = _OUTCOME_COLORS.get(outcome, "magenta")
        ax_e, ax_p, ax_d = axes[0, col], axes[1, col], axes[2, col]
        ax_e.axhspan(-DEPTH_TOLERANCE_M, DEPTH_TOLERANCE_M, color="0.88")
        if not tr.termination_reason:  # a terminated episode has no hold window: it failed at its end
            ax_e.axvspan(tr.time_s[-1] - HOLD_WINDOW_S, tr.time_s[-1], color=_HOLD_COLOR, alpha=_HOLD_ALPHA)
        ax_e.plot(tr.time_s, tr.depth_error_m, color=color)
        ax_e.invert_yaxis()  # depth is positive down: too deep plots below
        ax_p.plot(tr.time_s, np.degrees(tr.pitch_rad), color=color)
        ax_d.plot(tr.time_s[1:], np.degrees(tr.stern_plane_rad[1:]), color=color, drawstyle="steps-pre")
        if np.any(tr.bow_plane_rad[1:] != 0.0):
            ax_d.plot(
                tr.time_s[1:],
                np.degrees(tr.bow_plane_rad[1:]),
                color=color,
                linestyle="--",
                drawstyle="steps-pre",
            )
        for sign in (1, -1):
            ax_d.axhline(sign * math.degrees(tr.plane_limit_rad), color="0.4", linewidth=0.8, linestyle=":")
        if tr.termination_reason:
            ax_e.plot(tr.time_s[-1], tr.depth_error_m[-1], marker="X", color="k", markersize=9, linestyle="")
        crossing = speed_crossing_s(tr) if with_speed else None
        if with_speed:
            ax_u = axes[3, col]
            ax_u.plot(tr.time_s, tr.speed_mps, color=color)
            ax_u.axhline(tr.critical_speed_mps, color="k", linestyle="--", linewidth=1)
            ax_u.set_xlabel("time [s]")
        else:
            ax_d.set_xlabel("time [s]")
        if crossing is not None:
            crossing_drawn = True
            for ax in axes[:, col]:
                ax.axvline(crossing, color="crimson", linestyle="-.", linewidth=1)
            axes[3, col].annotate(
                f"u = u_cr\nat {crossing:.0f} s",
                (crossing, tr.critical_speed_mps),
                xytext=(6, 6),
                textcoords="offset points",
                fontsize="small",
                color="crimson",
            )
        count = sum(x.metrics.outcome == outcome for x in results)
        its = [x for x in results if x.controller == r.controller]
        its_count = sum(x.metrics.outcome == outcome for x in its)
        ratio0 = tr.speed_mps[0] / tr.critical_speed_mps
        ratio1 = r.final_speed_mps / r.critical_speed_mps
        speed = (
            f"u/u_cr {ratio1:.2f}" if math.isclose(ratio0, ratio1) else f"u/u_cr {ratio0:.2f} to {ratio1:.2f}"
        )
        ended = (
            f", ended: {_label(tr.termination_reason)}" if tr.termination_reason not in ("", outcome) else ""
        )
        ax_e.set_title(
            f"{_label(outcome)} (all controllers: {count} of {len(results)})\n"
            f"{r.controller}: {its_count} of {len(its)}; seed {r.seed}{ended}\n{speed}",
            fontsize="medium",
            color=color,
        )
        for ax in axes[:, col]:
            ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("depth error [m]\n(+ too deep)")
    axes[1, 0].set_ylabel("pitch [deg]\n(+ nose up)")
    axes[2, 0].set_ylabel("planes [deg]")
    if with_speed:
        axes[3, 0].set_ylabel("speed [m/s]")
    handles = [
        Patch(color="0.88", label=f"|depth error| <= {DEPTH_TOLERANCE_M:g} m"),
        Patch(color=_HOLD_COLOR, alpha=_HOLD_ALPHA, label=f"final {HOLD_WINDOW_S:g} s (success judged)"),
        Line2D([], [], color="0.3", label="stern plane"),
        Line2D([], [], color="0.3", linestyle="--", label="bow plane"),
        Line2D([], [], color="0.4", linestyle=":", label="plane limit"),
    ]
    if any(tr.termination_reason for _, _, tr in shown):
        handles.append(Line2D([], [], color="k", marker="X", linestyle="", label="terminated"))
    if with_speed:
        handles.append(Line2D([], [], color="k", linestyle="--", label="critical speed u_cr"))
    if crossing_drawn:
        handles.append(Line2D([], [], color="crimson", linestyle="-.", label="u crosses u_cr"))
    fig.legend(
        handles=handles,
        loc="outside lower center",
        ncols=min(len(handles), 4 if len(shown) > 1 else 2),
        fontsize="small",
    )
    controllers = len({x.controller for x in results})
    fig.suptitle(
        title
        or (
            f"{scenarios[0]}: a typical episode of each outcome\n({len(results)} episodes, {controllers} "
            f"controller{'s' if controllers > 1 else ''}; success is judged over the final "
            f"{HOLD_WINDOW_S:g} s)"
        ),
        fontsize="medium",
    )
    return fig


def plot_outcomes(
    results: Sequence[EpisodeResult],
    path: str | os.PathLike[str],
    trajectory_of: Callable[[EpisodeResult], Trajectory] | None = None,
    *,
    title: str | None = None,
) -> Path:
    """Depth error, pitch and planes against time for a typical episode of each outcome of one scenario.

    ``results`` are every episode of one scenario (all controllers). One column per outcome that
    occurred (success, wrong branch, broached, ...), holding the episode
    :func:`~subenv.evaluation.results.representative_episodes` chose: the controller with that
    outcome most often, its episode of median IAE. ``trajectory_of`` gives an episode's trajectory
    (e.g. :func:`replay_trajectory` with the controller bound); by default the results must carry
    theirs. When the speed varies (``SpeedTransient``) a fourth row shows the speed and u_cr, and
    the time the speed crosses u_cr is marked in every row.
    """
    return save_figure(outcomes_figure(results, trajectory_of, title=title), path)


# --- metrics against u / u_cr -----------------------------------------------------------------
def _colors(names: Sequence[str]) -> dict[str, Any]:
    from matplotlib import colormaps

    cmap = colormaps["tab10"]
    return {name: cmap(i % 10) for i, name in enumerate(names)}


_DODGE: Final = 0.7
"""Share of a bin's width over which the controllers' points are spread, side by side (the bin itself
is shaded, so the spread reads as one bin, not as different speeds)."""


def _bin_edges(rows: Sequence[Mapping[str, Any]]) -> tuple[np.ndarray, float]:
    """The bin edges of one scenario's rows of :func:`by_speed_ratio` and the width of a bin (one speed:
    a single band 10% wide around it)."""
    low = min(row["ratio_low"] for row in rows)
    high = max(row["ratio_high"] for row in rows)
    n_bins = 1 + max(row["bin"] for row in rows)
    if high > low:
        return np.linspace(low, high, n_bins + 1), (high - low) / n_bins
    width = 0.1 * low
    return np.array([low - width / 2, low + width / 2]), width


def _mark_critical_speed(axes: Sequence[Any], x_low: float, x_high: float) -> None:
    """Mark u = u_cr: a dashed line where the panel's range holds it, else an arrow at the edge it lies
    beyond: the range is the scenario's own, not stretched to reach u_cr."""
    if x_low < 1.0 < x_high:
        for ax in axes:
            ax.axvline(1.0, color="k", linestyle="--", linewidth=1)
        return
    right = x_high <= 1.0
    axes[0].annotate(
        "u_cr \u2192" if right else "\u2190 u_cr",
        (0.98 if right else 0.02, 0.5),
        xycoords="axes fraction",
        ha="right" if right else "left",
        va="center",
        fontsize="small",
        color="0.3",
    )


def plot_metrics_vs_speed(
    results: Sequence[EpisodeResult], path: str | os.PathLike[str], *, bins: int | None = None
) -> Path:
    """Write :func:`metrics_vs_speed_figure` to ``path`` (PNG)."""
    return save_figure(metrics_vs_speed_figure(results, bins=bins), path)


def metrics_vs_speed_figure(results: Sequence[EpisodeResult], *, bins: int | None = None) -> Any:
    """Success rate and median IAE against u / u_cr, one column per scenario, binned with intervals
    (a :class:`matplotlib.figure.Figure`, not written).

    The bins and intervals are :func:`~subenv.evaluation.results.by_speed_ratio`'s: per scenario,
    equal-width bins of the speed ratio (final speed over the episode's own critical speed); success
    rate with 95% Wilson intervals, median IAE with 95% bootstrap intervals. Within each bin (the bins
    shaded alternately) the controllers stand side by side in a fixed order, each a marker with its
    interval, joined from bin to bin by a faint line. Each panel spans its own scenario's speeds;
    u = u_cr is a dashed line where it falls within them, else an arrow at the side it lies beyond.
    """
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    table = by_speed_ratio(results, bins)
    if not table:
        raise ValueError(
            "no episode has a finite speed ratio to plot against (results empty, or no critical speed?)"
        )
    scenarios = list(dict.fromkeys(row["scenario"] for row in table))
    controllers = list(dict.fromkeys(row["controller"] for row in table))
    colors = _colors(controllers)
    panel_width = 2.9 + 0.1 * max(0, len(controllers) - 4)  # room for the controllers side by side
    fig = Figure(figsize=(max(6.0, panel_width * len(scenarios) + 1.5), 6.4), layout="constrained")
    axes = fig.subplots(2, len(scenarios), sharey="row", squeeze=False)
    positive = all(row["iae_median"] > 0 for row in table)
    for col, scenario in enumerate(scenarios):
        ax_s, ax_i = axes[0, col], axes[1, col]
        rows = [row for row in table if row["scenario"] == scenario]
        edges, width = _bin_edges(rows)
        for j, c in enumerate(controllers):
            mine = [row for row in rows if row["controller"] == c]
            if not mine:
                continue
            offset = ((j + 0.5) / len(controllers) - 0.5) * _DODGE * width
            x = np.array([0.5 * (row["ratio_low"] + row["ratio_high"]) + offset for row in mine])
            for ax, key in ((ax_s, "success"), (ax_i, "iae")):
                centre = np.array([row[f"{key}_rate" if key == "success" else "iae_median"] for row in mine])
                lo = np.array([row[f"{key}_ci_low"] for row in mine])
                hi = np.array([row[f"{key}_ci_high"] for row in mine])
                yerr = np.nan_to_num(np.vstack([centre - lo, hi - centre]))  # no interval: no bar
                ax.plot(x, centre, color=colors[c], linewidth=0.8, alpha=0.35)
                ax.errorbar(
                    x,
                    centre,
                    yerr=yerr,
                    color=colors[c],
                    marker="o",
                    markersize=3.5,
                    linestyle="",
                    elinewidth=1,
                    capsize=0,
                )
        episodes = max(sum(row["episodes"] for row in rows if row["controller"] == c) for c in controllers)
        ax_s.set_title(f"{scenario}\n({episodes} episodes per controller)", fontsize="medium")
        x_low, x_high = edges[0] - 0.05 * width, edges[-1] + 0.05 * width
        for ax in (ax_s, ax_i):
            for b in range(0, len(edges) - 1, 2):
                ax.axvspan(edges[b], edges[b + 1], color="0.93", zorder=0)
            ax.set_xlim(x_low, x_high)
            ax.grid(alpha=0.3, axis="y")
        _mark_critical_speed((ax_s, ax_i), x_low, x_high)
        ax_i.set_xlabel("u / u_cr")
    axes[0, 0].set_ylim(-0.05, 1.05)
    axes[0, 0].set_ylabel(f"success rate\n({100 * CONFIDENCE_LEVEL:.0f}% Wilson interval)")
    axes[1, 0].set_ylabel(f"median IAE [m s]\n({100 * CONFIDENCE_LEVEL:.0f}% bootstrap interval)")
    if positive:
        axes[1, 0].set_yscale("log")
    handles = [Line2D([], [], color=colors[c], marker="o", label=c) for c in controllers]
    handles.append(Line2D([], [], color="k", linestyle="--", label="u = u_cr"))
    fig.legend(
        handles=handles, loc="outside right center", fontsize="small", title="left to right\nin each bin"
    )
    fig.suptitle(
        "Success and median IAE against u / u_cr (final speed over the episode's own critical speed)\n"
        "bins of equal width per scenario, shaded alternately; the controllers side by side in each bin",
        fontsize="medium",
    )
    return fig
