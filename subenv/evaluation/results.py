"""Result tables: the tidy per-episode table, aggregates with confidence intervals, the leaderboard.

All tables are lists of flat dicts (one row per observation, one column per variable), written as
CSV and Markdown. Every file is written atomically, and a results folder is assembled beside its
place and swapped in (:mod:`subenv.atomic`, whose functions are re-exported here), so a reader
never sees a half-written file or folder.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np

from subenv.atomic import (
    OutputDirError,
    atomic_output_dir,
    atomic_write_bytes,
    atomic_write_text,
    check_output_dir,
)
from subenv.evaluation.metrics import DEPTH_TOLERANCE_M, HOLD_WINDOW_S, OUTCOMES, EpisodeMetrics
from subenv.evaluation.rollout import ControllerFailure, EpisodeResult

__all__ = [
    "CONFIDENCE_LEVEL",
    "CONTINUOUS_METRICS",
    "OUTCOME_NOTE",
    "RATE_METRICS",
    "OutputDirError",
    "atomic_output_dir",
    "atomic_write_bytes",
    "atomic_write_text",
    "by_speed_ratio",
    "check_output_dir",
    "episode_table",
    "failures_markdown",
    "leaderboard_markdown",
    "mean_interval",
    "median_interval",
    "outcome_counts",
    "representative_episodes",
    "summarize",
    "summary_markdown",
    "table_csv",
    "wilson_interval",
    "write_csv",
]

CONFIDENCE_LEVEL: Final = 0.95
"""Two-sided level of every confidence interval in the tables."""

RATE_METRICS: Final = OUTCOMES
"""The outcomes, each aggregated as a rate with a Wilson interval.

Every episode has exactly one outcome (:data:`~subenv.evaluation.metrics.OUTCOMES`, with its
order of precedence), so the rates of a row add up to 1 and every table counts a failure once.
"""

CONTINUOUS_METRICS: Final = {
    "iae_m_s": (0.0, math.inf),
    "settling_time_s": (0.0, math.inf),
    "overshoot_m": (0.0, math.inf),
    "peak_pitch_deg": (0.0, 180.0),
    "plane_rms_rad": (0.0, math.inf),
    "saturated_fraction": (0.0, 1.0),
    "hold_max_abs_error_m": (0.0, math.inf),
}
"""Continuous metrics aggregated as a mean with a Student-t interval, and the range each can take.

``settling_time_s`` is averaged over the episodes that settled (finite values; their number is
the ``settled`` column), since a never-settling episode has no settling time.
"""


# --- confidence intervals -------------------------------------------------------------------
def wilson_interval(successes: int, n: int, confidence: float = CONFIDENCE_LEVEL) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion (``scipy.stats.binomtest``).

    Chosen over the normal (Wald) interval because it stays inside [0, 1] and keeps its coverage
    at rates of 0 or 1 and small n, which is exactly where controllers that always or never
    succeed put a leaderboard. ``n == 0`` gives (nan, nan).

    References
    ----------
    Wilson, E. B. (1927). Probable inference, the law of succession, and statistical inference.
    JASA 22, 209-212.
    """
    if not (isinstance(n, (int, np.integer)) and n >= 0 and 0 <= successes <= n):
        raise ValueError(f"successes={successes!r}, n={n!r} are invalid: need 0 <= successes <= n")
    if n == 0:
        return (math.nan, math.nan)
    from scipy import stats  # imported on use: importing subenv.evaluation stays light

    ci = stats.binomtest(int(successes), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    return (float(ci.low), float(ci.high))


def mean_interval(
    values: Sequence[float] | np.ndarray,
    confidence: float = CONFIDENCE_LEVEL,
    support: tuple[float, float] = (-math.inf, math.inf),
) -> tuple[float, float, float]:
    """(mean, low, high): the mean and its Student-t confidence interval.

    The t interval assumes a roughly normal sample mean, which the central limit theorem gives
    with tens of episodes; with a handful it is wide, as it should be. Its bounds are clipped to
    ``support``, the range the metric can take (the true mean lies inside it, so clipping never
    excludes it). Fewer than 2 values give nan bounds; values that are all equal give a
    zero-width interval.
    """
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        return (math.nan, math.nan, math.nan)
    mean = float(x.mean())
    if x.size < 2:
        return (mean, math.nan, math.nan)
    from scipy import stats

    sem = float(stats.sem(x))
    if sem == 0.0 or not math.isfinite(sem):
        return (mean, mean, mean) if sem == 0.0 else (mean, math.nan, math.nan)
    low, high = stats.t.interval(confidence, x.size - 1, loc=mean, scale=sem)
    return (mean, max(float(low), support[0]), min(float(high), support[1]))


_BOOTSTRAP_RESAMPLES: Final = 4999
"""Resamples of :func:`median_interval`: enough that the percentile bounds move by well under the
interval's own width from one seed to another, few enough for hundreds of intervals per figure."""

_BOOTSTRAP_SEED: Final = 0
"""Fixed, so the same results give the same intervals (and the same figure) every time."""


def median_interval(
    values: Sequence[float] | np.ndarray, confidence: float = CONFIDENCE_LEVEL
) -> tuple[float, float, float]:
    """(median, low, high): the median and its percentile-bootstrap confidence interval
    (``scipy.stats.bootstrap``, fixed seed).

    For skewed metrics such as the IAE, where one terminated episode (charged its final error until
    the scheduled end) can outweigh twenty good ones in a mean. Fewer than 2 values give nan
    bounds; values that are all equal give a zero-width interval.
    """
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        return (math.nan, math.nan, math.nan)
    median = float(np.median(x))
    if x.size < 2:
        return (median, math.nan, math.nan)
    if np.all(x == x[0]):
        return (median, median, median)
    from scipy import stats

    ci = stats.bootstrap(
        (x,),
        np.median,
        confidence_level=confidence,
        n_resamples=_BOOTSTRAP_RESAMPLES,
        method="percentile",
        rng=np.random.default_rng(_BOOTSTRAP_SEED),
    ).confidence_interval
    return (median, float(ci.low), float(ci.high))


# --- tables ---------------------------------------------------------------------------------
def episode_table(results: Sequence[EpisodeResult]) -> list[dict[str, Any]]:
    """The tidy per-episode table: one row per controller x scenario x episode."""
    return [r.row() for r in results]


def _groups(results: Sequence[EpisodeResult]) -> dict[tuple[str, str], list[EpisodeResult]]:
    groups: dict[tuple[str, str], list[EpisodeResult]] = {}
    for r in results:
        groups.setdefault((r.controller, r.scenario), []).append(r)
    return groups


def outcome_counts(metrics: Iterable[EpisodeMetrics]) -> dict[str, int]:
    """Episodes per outcome: every outcome of :data:`~subenv.evaluation.metrics.OUTCOMES` (in its
    order, zeros included), then any other outcome that occurred (sorted).

    The one count behind every table: :func:`summarize` (and so ``summary.md``/``summary.csv``)
    and :func:`leaderboard_markdown` both count failures with it, so their numbers agree.
    """
    counts = dict.fromkeys(OUTCOMES, 0)
    others: dict[str, int] = {}
    for m in metrics:
        if m.outcome in counts:
            counts[m.outcome] += 1
        else:
            others[m.outcome] = others.get(m.outcome, 0) + 1
    return counts | dict(sorted(others.items()))


def summarize(results: Sequence[EpisodeResult], confidence: float = CONFIDENCE_LEVEL) -> list[dict[str, Any]]:
    """Aggregate per controller x scenario (in the order first seen).

    Columns: ``controller``, ``scenario``, ``episodes``; for each outcome (:data:`RATE_METRICS`,
    and any other that occurred) ``outcome_<o>`` (the count of :func:`outcome_counts`) and
    ``<o>_rate``, ``<o>_ci_low``, ``<o>_ci_high`` (Wilson); for each of
    :data:`CONTINUOUS_METRICS` ``<m>_mean``, ``<m>_ci_low``, ``<m>_ci_high`` (Student t);
    ``settled`` (episodes with a finite settling time); where the results say which episodes are
    winnable (:attr:`EpisodeResult.winnable`), ``winnable`` (their number), ``winnable_successes`` and
    ``winnable_success_rate``, ``winnable_ci_low``, ``winnable_ci_high``.
    """
    extra = [o for o in _outcomes(results) if o not in OUTCOMES]
    rows = []
    for (controller, scenario), group in _groups(results).items():
        row: dict[str, Any] = {"controller": controller, "scenario": scenario, "episodes": len(group)}
        metrics = [r.metrics for r in group]
        counts = outcome_counts(metrics)
        row |= {f"outcome_{o}": counts.get(o, 0) for o in (*OUTCOMES, *extra)}
        for name in (*OUTCOMES, *extra):
            k = counts.get(name, 0)
            low, high = wilson_interval(k, len(metrics), confidence)
            row |= {f"{name}_rate": k / len(metrics), f"{name}_ci_low": low, f"{name}_ci_high": high}
        for name, support in CONTINUOUS_METRICS.items():
            values = [float(getattr(m, name)) for m in metrics]
            if name == "settling_time_s":
                values = [v for v in values if math.isfinite(v)]
                row["settled"] = len(values)
            mean, low, high = mean_interval(values, confidence, support)
            row |= {f"{name}_mean": mean, f"{name}_ci_low": low, f"{name}_ci_high": high}
        if all(r.winnable is not None for r in group):
            k, n = _winnable_successes(group)
            low, high = wilson_interval(k, n, confidence) if n else (math.nan, math.nan)
            row |= {
                "winnable": n,
                "winnable_successes": k,
                "winnable_success_rate": k / n if n else math.nan,
                "winnable_ci_low": low,
                "winnable_ci_high": high,
            }
        rows.append(row)
    return rows


def _winnable_successes(results: Iterable[EpisodeResult]) -> tuple[int, int]:
    """(successes, episodes) among the winnable episodes of ``results``."""
    winnable = [r for r in results if r.winnable]
    return sum(r.metrics.success for r in winnable), len(winnable)


_MAX_SPEED_BINS: Final = 6
"""At most this many bins of u/u_cr per scenario: with the default 100 episodes, about 20 episodes per
bin and controller, so a success rate's Wilson interval is about +-20 points, not +-30."""


def by_speed_ratio(
    results: Sequence[EpisodeResult], bins: int | None = None, confidence: float = CONFIDENCE_LEVEL
) -> list[dict[str, Any]]:
    """Success rate and median IAE per scenario x controller x bin of the speed ratio u / u_cr.

    u is the speed at the end of the episode (over the hold window that decides success; the only
    speed except in ``SpeedTransient``), u_cr the episode's own critical speed (its loading and the
    controller's plane allocation), so episodes of different loadings and controllers share an axis.
    Each scenario is binned on its own: equal-width bins spanning the ratios of its episodes, the
    same edges for every controller; a scenario whose episodes all have one ratio has one bin.
    Episodes without a finite ratio are left out.

    Parameters
    ----------
    results : sequence of EpisodeResult
    bins : int, optional
        Bins per scenario; default ``round(sqrt(n) / 2)`` in 1..6, n the most episodes of one
        controller in the scenario.
    confidence : float
        Level of the intervals.

    Returns
    -------
    list of dict
        One row per non-empty bin, in the order of scenarios, then controllers, first seen:
        ``scenario``, ``controller``, ``bin``, ``ratio_low``, ``ratio_high`` (the bin's edges),
        ``ratio_mean``, ``episodes``, ``success``, ``success_rate``, ``success_ci_low``,
        ``success_ci_high`` (Wilson), ``iae_median``, ``iae_ci_low``, ``iae_ci_high``
        (:func:`median_interval`).
    """
    if bins is not None and not (isinstance(bins, int) and bins >= 1):
        raise ValueError(f"bins={bins!r} is invalid: must be an integer >= 1")
    ratio = {id(r): r.final_speed_mps / r.critical_speed_mps for r in results}
    usable = [r for r in results if math.isfinite(ratio[id(r)])]
    rows: list[dict[str, Any]] = []
    for scenario in dict.fromkeys(r.scenario for r in usable):
        mine = [r for r in usable if r.scenario == scenario]
        controllers = list(dict.fromkeys(r.controller for r in mine))
        x = np.array([ratio[id(r)] for r in mine])
        low, high = float(x.min()), float(x.max())
        most = max(sum(r.controller == c for r in mine) for c in controllers)
        n_bins = bins or int(np.clip(round(math.sqrt(most) / 2), 1, _MAX_SPEED_BINS))
        if math.isclose(low, high, rel_tol=1e-9, abs_tol=1e-12):
            n_bins = 1
        edges = np.linspace(low, high, n_bins + 1)
        which = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, n_bins - 1)
        for c in controllers:
            for b in range(n_bins):
                group = [
                    (r, float(u))
                    for r, u, k in zip(mine, x, which, strict=True)
                    if r.controller == c and k == b
                ]
                if not group:
                    continue
                k_ok = sum(r.metrics.success for r, _ in group)
                s_low, s_high = wilson_interval(k_ok, len(group), confidence)
                median, i_low, i_high = median_interval([r.metrics.iae_m_s for r, _ in group], confidence)
                rows.append(
                    {
                        "scenario": scenario,
                        "controller": c,
                        "bin": b,
                        "ratio_low": float(edges[b]),
                        "ratio_high": float(edges[b + 1]),
                        "ratio_mean": float(np.mean([u for _, u in group])),
                        "episodes": len(group),
                        "success": k_ok,
                        "success_rate": k_ok / len(group),
                        "success_ci_low": s_low,
                        "success_ci_high": s_high,
                        "iae_median": median,
                        "iae_ci_low": i_low,
                        "iae_ci_high": i_high,
                    }
                )
    return rows


def representative_episodes(results: Sequence[EpisodeResult]) -> dict[str, dict[str, EpisodeResult]]:
    """Per scenario, one episode for each outcome that occurred: ``{scenario: {outcome: result}}``.

    Of the episodes of a scenario with a given outcome, the representative belongs to the controller
    that had that outcome most often there (the first in the results on a tie), and is that
    controller's episode of median IAE among them (the lower median; the earlier episode on a tie):
    a typical case of the outcome, not its extreme. Scenarios and outcomes are in the order of the
    results and of :data:`~subenv.evaluation.metrics.OUTCOMES`.
    """
    chosen: dict[str, dict[str, EpisodeResult]] = {}
    for scenario in dict.fromkeys(r.scenario for r in results):
        mine = [r for r in results if r.scenario == scenario]
        chosen[scenario] = {}
        for outcome in _outcomes(mine):
            having = [r for r in mine if r.metrics.outcome == outcome]
            controllers = list(dict.fromkeys(r.controller for r in having))
            most = max(controllers, key=lambda c: sum(r.controller == c for r in having))  # first on a tie
            ranked = sorted(
                (r for r in having if r.controller == most), key=lambda r: (r.metrics.iae_m_s, r.episode)
            )
            chosen[scenario][outcome] = ranked[(len(ranked) - 1) // 2]
    return chosen


def _outcomes(results: Sequence[EpisodeResult]) -> list[str]:
    seen = {r.metrics.outcome for r in results}
    return [o for o in OUTCOMES if o in seen] + sorted(seen - set(OUTCOMES))


def _pct(rate: float, low: float, high: float) -> str:
    if math.isnan(rate):
        return "-"
    return f"{100 * rate:.0f}% [{100 * low:.0f}, {100 * high:.0f}]"


def _num(mean: float, low: float, high: float, fmt: str = ".3g") -> str:
    if math.isnan(mean):
        return "-"
    if math.isnan(low):
        return f"{mean:{fmt}}"
    return f"{mean:{fmt}} [{low:{fmt}}, {high:{fmt}}]"


OUTCOME_NOTE: Final = (
    "Each episode counts under one outcome, the first that applies: success (not terminated and "
    f"|depth error| <= {DEPTH_TOLERANCE_M:g} m over the final {HOLD_WINDOW_S:g} s); wrong branch (a steady "
    "pitched state with a plane pinned at its limit, off depth, over that window, even if the episode then "
    "broached or left the depth band); steady offset (settled off depth, planes free); the environment's "
    "termination reason (broached, left depth band, pitch limit, diverged); unsettled (still moving off "
    "depth at the time limit)."
)
"""How the tables count outcomes (the precedence of :data:`~subenv.evaluation.metrics.OUTCOMES`), in
the notes of the leaderboard and of ``summary.md``."""


def _markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def failures_markdown(failures: Sequence[ControllerFailure]) -> str:
    """The section of a results file that lists the controllers' failures, one line each ("" if none)."""
    if not failures:
        return ""
    names = ", ".join(dict.fromkeys(f.controller for f in failures))
    lines = "\n".join(f"- {f.message}" for f in failures)
    return (
        f"\n### Failed: {names}\n\nNot ranked: a controller that raised an exception or returned an action "
        "the environment refused has no episodes on that scenario. Its scenarios that completed are "
        f"in results.csv and the summary.\n\n{lines}\n"
    )


def leaderboard_markdown(
    results: Sequence[EpisodeResult],
    *,
    title: str = "Leaderboard",
    confidence: float = CONFIDENCE_LEVEL,
    failures: Sequence[ControllerFailure] = (),
) -> str:
    """Markdown leaderboard: controllers as rows, success rate per scenario with its interval.

    Where the results say which episodes are winnable (:attr:`EpisodeResult.winnable`: a depth-holding
    trim exists within the limits), the column ``winnable`` is the success over those, and the rows are
    sorted by it: an episode no controller can win says nothing about a controller. Then by the
    success rate over all the suite's episodes (pooled), best first, then by name. The last columns
    break the pooled failures down by outcome (:func:`outcome_counts`, the counts :func:`summarize`
    gives per scenario).

    A controller with ``failures`` (:class:`~subenv.evaluation.rollout.ControllerFailure`) is not
    ranked, whatever it completed: its failures are listed below the table (:func:`failures_markdown`).
    """
    failed = {f.controller for f in failures}
    results = [r for r in results if r.controller not in failed]
    if not results:
        if failures:
            none = "No controller completed the suite: none is ranked."
            return f"## {title}\n\n{none}\n{failures_markdown(failures)}"
        raise ValueError("results is empty: nothing to rank")
    scenarios = list(dict.fromkeys(r.scenario for r in results))
    controllers = list(dict.fromkeys(r.controller for r in results))
    groups = _groups(results)
    pooled = {c: [r.metrics for r in results if r.controller == c] for c in controllers}
    judged = all(r.winnable is not None for r in results)
    winnable = {c: _winnable_successes(r for r in results if r.controller == c) for c in controllers}

    def rank(c: str) -> tuple[float, float, str]:
        k, n = winnable[c]
        return (-(k / n) if judged and n else 0.0, -sum(m.success for m in pooled[c]) / len(pooled[c]), c)

    order = sorted(controllers, key=rank)
    failure_outcomes = [o for o in _outcomes(results) if o != "success"]
    rows = []
    for c in order:
        ms = pooled[c]
        k = sum(m.success for m in ms)
        cells = [c, _pct(k / len(ms), *wilson_interval(k, len(ms), confidence))]
        if judged:
            kw, nw = winnable[c]
            cells.append(_pct(kw / nw, *wilson_interval(kw, nw, confidence)) if nw else "-")
        for s in scenarios:
            group = groups.get((c, s), [])
            ks = sum(r.metrics.success for r in group)
            ci = wilson_interval(ks, len(group), confidence) if group else (math.nan, math.nan)
            cells.append(_pct(ks / len(group), *ci) if group else "-")
        counts = outcome_counts(ms)
        cells += [str(counts.get(o, 0)) for o in failure_outcomes]
        rows.append(cells)
    episodes = sorted({len(g) for g in groups.values()})
    per = str(episodes[0]) if len(episodes) == 1 else f"{episodes[0]}-{episodes[-1]}"
    header = [
        "controller",
        "all scenarios",
        *(["winnable"] if judged else []),
        *scenarios,
        *(o.replace("_", " ") for o in failure_outcomes),
    ]
    first = controllers[0]
    n_winnable = sum(1 for r in results if r.controller == first and r.winnable)
    n_first = sum(1 for r in results if r.controller == first)
    ranking = (
        f"Ranked by the success over the winnable episodes ({n_winnable} of {n_first} here: those whose "
        "loading has a depth-holding trim within the plane and pitch limits at their final speed, with every "
        "plane pair the vehicle has free; subenv.analysis.winnable), then over all. "
        if judged
        else ""
    )
    note = (
        f"Success rate with {100 * confidence:.0f}% Wilson intervals, {per} episodes per scenario "
        f"(the same seeds for every controller). {ranking}Last columns: episodes per failure outcome, all "
        f"scenarios. {OUTCOME_NOTE}"
    )
    return f"## {title}\n\n{_markdown_table(header, rows)}\n\n{note}\n{failures_markdown(failures)}"


_SUMMARY_MEANS: Final = (
    ("IAE [m s]", "iae_m_s"),
    ("settling [s]", "settling_time_s"),
    ("overshoot [m]", "overshoot_m"),
    ("peak pitch [deg]", "peak_pitch_deg"),
    ("plane RMS [rad]", "plane_rms_rad"),
    ("saturated", "saturated_fraction"),
)


def summary_markdown(summary: Sequence[Mapping[str, Any]], *, title: str = "Per scenario") -> str:
    """The aggregate table (from :func:`summarize`) as Markdown, one row per controller x scenario.

    The rate columns are the success rate and the rate of every failure outcome that occurred in
    any row, so each row's rates add up to 100% (up to rounding) and, times ``n``, summed over the
    scenarios, give the leaderboard's failure counts.
    """
    outcomes = [
        key.removeprefix("outcome_")
        for key in dict.fromkeys(k for r in summary for k in r)
        if key.startswith("outcome_")
    ]
    shown = [o for o in outcomes if o == "success" or any(r.get(f"outcome_{o}", 0) for r in summary)]
    judged = all("winnable" in r for r in summary)
    header = [
        "scenario",
        "controller",
        "n",
        *(["winnable: success"] if judged else []),
        *(o.replace("_", " ") for o in shown),
        *(label for label, _ in _SUMMARY_MEANS),
        "settled",
    ]
    scenarios = list(dict.fromkeys(r["scenario"] for r in summary))
    ordered = sorted(summary, key=lambda r: scenarios.index(r["scenario"]))  # stable: controllers keep order
    rows = []
    for r in ordered:
        cells = [r["scenario"], r["controller"], str(r["episodes"])]
        if judged:
            cells.append(f"{r['winnable_successes']}/{r['winnable']}")
        cells += [_pct(r[f"{o}_rate"], r[f"{o}_ci_low"], r[f"{o}_ci_high"]) for o in shown]
        cells += [
            _num(r[f"{name}_mean"], r[f"{name}_ci_low"], r[f"{name}_ci_high"]) for _, name in _SUMMARY_MEANS
        ]
        cells.append(str(r["settled"]))
        rows.append(cells)
    note = (
        "Rates of each outcome with 95% Wilson intervals; means with 95% Student-t intervals. Settling "
        "time averages the episodes that settled (column 'settled'). IAE charges a terminated episode "
        "its final error until the scheduled end. 'winnable: success': successes / episodes among those "
        f"that have a depth-holding trim within the limits (subenv.analysis.winnable). {OUTCOME_NOTE}"
    )
    return f"## {title}\n\n{_markdown_table(header, rows)}\n\n{note}\n"


def table_csv(rows: Sequence[Mapping[str, Any]]) -> str:
    """CSV text of a table of flat dicts (columns: the union of keys, in first-seen order)."""
    columns = list(dict.fromkeys(k for row in rows for k in row))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _cell(v) for k, v in row.items()})
    return buffer.getvalue()


def _cell(value: Any) -> Any:
    if isinstance(value, (float, np.floating)):
        return repr(float(value))  # round-trips exactly; nan and inf as 'nan' and 'inf'
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    return value


def write_csv(path: str | os.PathLike[str], rows: Sequence[Mapping[str, Any]]) -> Path:
    """Write a table of flat dicts as CSV, atomically."""
    return atomic_write_text(path, table_csv(rows))
