"""Plots of an evaluation: every controller on the same episode, and metrics versus speed.

Figures are built on :class:`matplotlib.figure.Figure` directly (the Agg canvas, no pyplot state,
no display needed) and written atomically. matplotlib is the optional ``plot`` extra.
"""

from __future__ import annotations

import io
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np

from subenv.atomic import atomic_write_bytes
from subenv.evaluation.metrics import DEPTH_TOLERANCE_M
from subenv.evaluation.rollout import EpisodeResult

__all__ = ["plot_metrics_vs_speed", "plot_trajectories", "require_matplotlib", "save_figure"]

_DPI: Final = 110


def require_matplotlib() -> None:
    """Raise ImportError with the install hint if matplotlib is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as exc:
        raise ImportError("the evaluation plots need matplotlib: pip install 'subenv[plot]'") from exc


def save_figure(fig: Any, path: str | os.PathLike[str], image_format: str = "png") -> Path:
    """Write a matplotlib figure to ``path`` completely or not at all.

    The figure is rendered in memory (``image_format``, e.g. ``"png"``, ``"pdf"``, ``"svg"``; 110 dpi)
    and written with :func:`~subenv.atomic.atomic_write_bytes`. Returns the path.
    """
    buffer = io.BytesIO()
    fig.savefig(buffer, format=image_format, dpi=_DPI)
    return atomic_write_bytes(path, buffer.getvalue())


def _colors(names: Sequence[str]) -> dict[str, Any]:
    from matplotlib import colormaps

    cmap = colormaps["tab10"]
    return {name: cmap(i % 10) for i, name in enumerate(names)}


def plot_trajectories(
    results: Sequence[EpisodeResult], path: str | os.PathLike[str], *, title: str | None = None
) -> Path:
    """Depth error, pitch and plane angles against time, one line per controller, same episode.

    ``results`` are the results (with trajectories) of one scenario and seed; the figure has
    three panels sharing the time axis, the tolerance band shaded on the depth-error panel.
    """
    from matplotlib.figure import Figure

    runs = [r for r in results if r.trajectory is not None]
    if not runs:
        raise ValueError("no result carries a trajectory (evaluate(..., keep_trajectories >= 1))")
    keys = {(r.scenario, r.seed) for r in runs}
    if len(keys) != 1:
        raise ValueError(f"results come from several episodes {sorted(keys)}: pass one scenario and seed")
    colors = _colors([r.controller for r in runs])
    fig = Figure(figsize=(9, 8.5))
    axes = fig.subplots(3, 1, sharex=True)
    axes[0].axhspan(-DEPTH_TOLERANCE_M, DEPTH_TOLERANCE_M, color="0.9", label=f"+-{DEPTH_TOLERANCE_M:g} m")
    for r in runs:
        tr = r.trajectory
        assert tr is not None
        color = colors[r.controller]
        label = f"{r.controller} ({r.metrics.outcome.replace('_', ' ')})"
        axes[0].plot(tr.time_s, tr.depth_error_m, color=color, label=label)
        axes[1].plot(tr.time_s, np.degrees(tr.pitch_rad), color=color)
        axes[2].plot(tr.time_s[1:], np.degrees(tr.stern_plane_rad[1:]), color=color, drawstyle="steps-pre")
        if np.any(tr.bow_plane_rad[1:] != 0.0):
            axes[2].plot(tr.time_s[1:], np.degrees(tr.bow_plane_rad[1:]), color=color, linestyle="--",
                         drawstyle="steps-pre")
        if tr.termination_reason:
            axes[0].plot(tr.time_s[-1], tr.depth_error_m[-1], marker="x", color=color, markersize=9)
    limit = math.degrees(runs[0].trajectory.plane_limit_rad)  # type: ignore[union-attr]
    for sign in (1, -1):
        axes[2].axhline(sign * limit, color="0.5", linewidth=0.8, linestyle=":")
    axes[0].invert_yaxis()  # depth is positive down: too deep plots below
    axes[0].set_ylabel("depth error [m]\n(+ too deep)")
    axes[1].set_ylabel("pitch [deg]\n(+ nose up)")
    axes[2].set_ylabel("planes [deg]\n(solid stern, dashed bow)")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize="small")
    first = runs[0]
    u0, u1 = first.initial_speed_mps, first.final_speed_mps
    speeds = f"{u0:.3f} m/s" if math.isclose(u0, u1) else f"{u0:.3f} -> {u1:.3f} m/s"
    ucrs = sorted({round(r.critical_speed_mps, 4) for r in runs})
    fig.suptitle(title or (
        f"{first.scenario}, seed {first.seed}: speed {speeds}, u_cr {', '.join(f'{u:.3f}' for u in ucrs)} m/s"
    ))
    fig.tight_layout()
    return save_figure(fig, path)


_MAX_CRITICAL_LINES: Final = 3
"""With more distinct critical speeds than this (randomised loadings), speeds are plotted as u / u_cr."""


def plot_metrics_vs_speed(
    results: Sequence[EpisodeResult], path: str | os.PathLike[str], *, bins: int | None = None
) -> Path:
    """Success rate (binned) and IAE (per episode) against speed, the critical speed marked.

    The speed is the one at the end of the episode, over the hold window that decides success
    (the only speed, except in ``SpeedTransient``, whose decisive speed is its final one). Each
    distinct critical speed of the results (one per loading and plane allocation) is a vertical
    line, labelled with the controllers it applies to. When the loadings vary (more than three
    distinct critical speeds, as in ``Randomized``), the axis is the speed in units of each
    episode's own critical speed instead, with u / u_cr = 1 marked.
    """
    from matplotlib.figure import Figure

    if not results:
        raise ValueError("results is empty: nothing to plot")
    by_ucr: dict[float, list[str]] = {}
    for r in results:
        if math.isfinite(r.critical_speed_mps):
            names = by_ucr.setdefault(round(r.critical_speed_mps, 4), [])
            if r.controller not in names:
                names.append(r.controller)
    relative = len(by_ucr) > _MAX_CRITICAL_LINES

    def x_of(r: EpisodeResult) -> float:
        return r.final_speed_mps / r.critical_speed_mps if relative else r.final_speed_mps

    controllers = list(dict.fromkeys(r.controller for r in results))
    colors = _colors(controllers)
    speeds = np.array([x_of(r) for r in results])
    speeds = speeds[np.isfinite(speeds)]
    if speeds.size == 0:
        raise ValueError("no episode has a finite speed to plot against (no critical speed?)")
    n_bins = bins or int(np.clip(math.ceil(math.sqrt(len(set(np.round(speeds, 6))))), 4, 15))
    low, high = float(speeds.min()), float(speeds.max())
    if high <= low:
        n_bins = 1
    edges = np.linspace(low, high, n_bins + 1)

    fig = Figure(figsize=(9, 7.5))
    ax_success, ax_iae = fig.subplots(2, 1, sharex=True)
    for c in controllers:
        mine = [r for r in results if r.controller == c and math.isfinite(x_of(r))]
        u = np.array([x_of(r) for r in mine])
        ok = np.array([r.metrics.success for r in mine], dtype=float)
        which = np.clip(np.digitize(u, edges[1:-1]), 0, n_bins - 1)
        counts = np.bincount(which, minlength=n_bins)
        with np.errstate(invalid="ignore", divide="ignore"):  # empty bins: nan breaks the line
            rate = np.bincount(which, weights=ok, minlength=n_bins) / counts
            at = np.bincount(which, weights=u, minlength=n_bins) / counts  # mean speed in the bin
        ax_success.plot(at, rate, marker="o", color=colors[c], label=c)
        iae = np.array([r.metrics.iae_m_s for r in mine])
        ax_iae.scatter(u, iae, s=12, alpha=0.6, color=colors[c], label=c)
    lines = [(1.0, "u = u_cr of each episode")] if relative else [
        (ucr, f"u_cr = {ucr:.3f} m/s" + ("" if len(by_ucr) == 1 else f" ({', '.join(names)})"))
        for ucr, names in sorted(by_ucr.items())
    ]
    for i, (x, label) in enumerate(lines):
        style = ("--", ":", "-.")[i % 3]
        for ax in (ax_success, ax_iae):
            ax.axvline(x, color="k", linestyle=style, linewidth=1, label=label if ax is ax_success else None)
    ax_success.set_ylim(-0.05, 1.05)
    ax_success.set_ylabel(f"success rate\n({n_bins} equal speed bins,\nat their mean speed)")
    ax_success.legend(loc="best", fontsize="small")
    if np.all([r.metrics.iae_m_s > 0 for r in results]):
        ax_iae.set_yscale("log")
    ax_iae.set_ylabel("IAE [m s] per episode")
    ax_iae.set_xlabel("speed over the final hold window " + ("/ u_cr" if relative else "[m/s]"))
    for ax in (ax_success, ax_iae):
        ax.grid(alpha=0.3)
    scenarios = ", ".join(dict.fromkeys(r.scenario for r in results))
    fig.suptitle(f"Metrics versus speed ({scenarios})", fontsize="medium")
    fig.tight_layout()
    return save_figure(fig, path)
