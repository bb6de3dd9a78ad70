"""The report stage's tables: the tidy per-episode table, aggregates with confidence intervals and
scores, the leaderboard.

All tables are lists of flat dicts (one row per observation, one column per variable), written as
CSV and Markdown, and every one is a function of the per-episode table: :func:`read_results` reads a
``results.csv`` back, and :func:`summarize` and :func:`leaderboard_markdown` of what it reads are the
run's ``summary.csv`` and ``leaderboard.md``. Every file is written atomically, and a results folder is
assembled beside its place and swapped in (:mod:`subenv.atomic`, whose functions are re-exported
here), so a reader never sees a half-written file or folder.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import itertools
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
from subenv.evaluation.failures import ControllerFailure
from subenv.evaluation.measure import EpisodeResult
from subenv.evaluation.metrics import (
    APPROACH_S,
    DEPTH_TOLERANCE_M,
    HOLD_WINDOW_S,
    OUTCOMES,
    QUALITY_ACCURACY_WEIGHT,
    QUALITY_EFFORT_WEIGHT,
    REGULATION_BAND_M,
    EpisodeMetrics,
)
from subenv.evaluation.score import (
    POOLED,
    SCORE_FORMULA,
    PairedComparison,
    Score,
    paired_comparisons,
    rank_by_score,
    rank_by_success,
    scores,
)
from subenv.evaluation.stats import CONFIDENCE_LEVEL, mean_interval, median_interval, wilson_interval

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
    "read_results",
    "representative_episodes",
    "summarize",
    "summary_markdown",
    "table_csv",
    "wilson_interval",
    "write_csv",
]

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
    "regulation_accuracy": (0.0, 1.0),
    "plane_effort": (0.0, 1.0),
}
"""Continuous metrics aggregated as a mean with a Student-t interval, and the range each can take.

``settling_time_s`` is averaged over the episodes that settled (finite values; their number is
the ``settled`` column), since a never-settling episode has no settling time.
"""


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


def summarize(
    results: Sequence[EpisodeResult],
    confidence: float = CONFIDENCE_LEVEL,
    *,
    score_table: Sequence[Score] | None = None,
) -> list[dict[str, Any]]:
    """Aggregate per controller x scenario (in the order first seen).

    Columns: ``controller``, ``scenario``, ``episodes``; for each outcome (:data:`RATE_METRICS`,
    and any other that occurred) ``outcome_<o>`` (the count of :func:`outcome_counts`) and
    ``<o>_rate``, ``<o>_ci_low``, ``<o>_ci_high`` (Wilson); for each of
    :data:`CONTINUOUS_METRICS` ``<m>_mean``, ``<m>_ci_low``, ``<m>_ci_high`` (Student t);
    ``settled`` (episodes with a finite settling time); where the results say which episodes are
    winnable (:attr:`EpisodeResult.winnable`), ``winnable`` (their number), ``winnable_successes`` and
    ``winnable_success_rate``, ``winnable_ci_low``, ``winnable_ci_high``; ``safety_events`` (episodes
    ended by one); and the score's (:class:`~subenv.evaluation.score.Score`, from ``score_table`` if
    given, as :func:`~subenv.evaluation.score.scores` gives it): ``scored``, ``wins``,
    ``scored_success_rate``, ``scored_success_ci_low``, ``scored_success_ci_high``, ``quality``,
    ``quality_ci_low``, ``quality_ci_high``, ``score``, ``score_ci_low``, ``score_ci_high``.
    """
    extra = [o for o in _outcomes(results) if o not in OUTCOMES]
    by_key = {
        (x.controller, x.scenario): x
        for x in (scores(results, confidence) if score_table is None else score_table)
    }
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
        row["safety_events"] = sum(m.safety_event for m in metrics)
        row |= _score_columns(by_key[(controller, scenario)])
        rows.append(row)
    return rows


def _score_columns(score: Score) -> dict[str, Any]:
    """The score's columns of a summary row."""
    return {
        "scored": score.scored,
        "wins": score.wins,
        "scored_success_rate": score.success_rate,
        "scored_success_ci_low": score.success_ci[0],
        "scored_success_ci_high": score.success_ci[1],
        "quality": score.quality,
        "quality_ci_low": score.quality_ci[0],
        "quality_ci_high": score.quality_ci[1],
        "score": score.score,
        "score_ci_low": score.score_ci[0],
        "score_ci_high": score.score_ci[1],
    }


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


def _score_cell(value: float, interval: tuple[float, float]) -> str:
    if math.isnan(value):
        return "-"
    if math.isnan(interval[0]):
        return f"{value:.1f}"
    return f"{value:.1f} [{interval[0]:.1f}, {interval[1]:.1f}]"


def _p(value: float) -> str:
    return "-" if math.isnan(value) else f"p = {value:.2g}"


SCORE_NOTE: Final = (
    f"Score: {SCORE_FORMULA}, of the N episodes the score counts (those that can be won), W of them won, "
    "Q the mean quality of the won ones, q = "
    f"{QUALITY_ACCURACY_WEIGHT:g} a + {QUALITY_EFFORT_WEIGHT:g} (1 - e^2): a the time fraction within "
    f"{REGULATION_BAND_M:g} m of the ordered depth from {APPROACH_S:g} s after the order to the end, e the "
    "RMS plane angle per plane over the limit (DeepMind Control's 4/5 task, 1/5 small control). So "
    "1000 (W - 1) / N <= S <= 1000 W / N: the score is the success count, with the quality as a "
    "tie-break worth less than one episode, and a controller that wins more never ranks below one that "
    "wins fewer; between controllers that win alike, the quality (1000 Q) shows which holds depth more "
    "tightly with less plane motion."
)
"""The leaderboard's caption of the score: the formula and why."""


COUNTED: Final = {
    "winnable": "winnable: a depth-holding trim exists within the limits, subenv.analysis.winnable",
    "achievable": (
        "achievable: a full-information plan stored for the episode won it on replay, "
        "subenv.evaluation.achievable; where none is stored, winnable"
    ),
}
"""What the leaderboard's caption says the score counts, per classifier (:attr:`Suite.scored_by
<subenv.evaluation.suites.Suite.scored_by>`)."""


def leaderboard_markdown(
    results: Sequence[EpisodeResult],
    *,
    title: str = "Leaderboard",
    confidence: float = CONFIDENCE_LEVEL,
    failures: Sequence[ControllerFailure] = (),
    score_table: Sequence[Score] | None = None,
    scored_by: str = "winnable",
) -> str:
    """Markdown leaderboard: controllers ranked by their score over the suite, with intervals.

    Four tables. (1) The ranking: per controller whether it was told the environment's settings
    (:attr:`EpisodeResult.informed`), its score over every scored episode of the suite
    (:class:`~subenv.evaluation.score.Score`, pooled), its success W/N over those with a Wilson interval,
    its quality 1000 Q, its rank by success beside its rank by score, and its safety events (episodes
    ended by broaching or the pitch limit). (2) Success over all episodes, over the winnable ones and
    per scenario, and the failures by outcome (:func:`outcome_counts`, the counts :func:`summarize`
    gives per scenario). (3) The score per scenario. (4) Paired comparisons of the controllers next to
    each other in the ranking (:func:`~subenv.evaluation.score.paired_comparisons`: McNemar on success,
    Wilcoxon on quality). Every interval is at level ``confidence``; ``score_table`` is
    :func:`~subenv.evaluation.score.scores` of ``results`` if it is already computed; ``scored_by``
    the suite's classifier, which the caption names (:data:`COUNTED`).

    A controller with ``failures`` (:class:`~subenv.evaluation.failures.ControllerFailure`) is not
    ranked, whatever it completed: its failures are listed below the tables (:func:`failures_markdown`).
    """
    failed = {f.controller for f in failures}
    results = [r for r in results if r.controller not in failed]
    if not results:
        if failures:
            none = "No controller completed the suite: none is ranked."
            return f"## {title}\n\n{none}\n{failures_markdown(failures)}"
        raise ValueError("results is empty: nothing to rank")
    table = (
        scores(results, confidence)
        if score_table is None
        else [s for s in score_table if s.controller not in failed]
    )
    pooled = {s.controller: s for s in table if s.scenario == POOLED}
    order = rank_by_score(pooled.values())
    by_success = rank_by_success(pooled.values())
    informed = {c: any(r.informed for r in results if r.controller == c) for c in order}
    safety = {c: sum(r.metrics.safety_event for r in results if r.controller == c) for c in order}
    header = [
        "rank",
        "controller",
        "informed",
        "score",
        "success",
        "quality",
        "rank by success",
        "safety events",
    ]
    rows = []
    for i, c in enumerate(order, start=1):
        p = pooled[c]
        success = f"{p.wins}/{p.scored} {_pct(p.success_rate, *p.success_ci)}" if p.scored else "-"
        rows.append(
            [
                str(i),
                c,
                "yes" if informed[c] else "no",
                _score_cell(p.score, p.score_ci),
                success,
                _score_cell(p.quality, p.quality_ci),
                str(by_success[c]),
                str(safety[c]),
            ]
        )
    scenarios = list(dict.fromkeys(r.scenario for r in results))
    per = {(s.controller, s.scenario): s for s in table}
    scenario_rows = [
        [
            c,
            *(
                _score_cell(per[(c, s)].score, per[(c, s)].score_ci) if (c, s) in per else "-"
                for s in scenarios
            ),
        ]
        for c in order
    ]
    first = results[0].controller
    n_scored = sum(r.counts for r in results if r.controller == first)
    n_all = sum(r.controller == first for r in results)
    note = (
        f"Ranked by the score over the {n_scored} of {n_all} episodes that count "
        f"({COUNTED.get(scored_by, scored_by)}; the same seeds for every controller), "
        f"{100 * confidence:.0f}% intervals: success Wilson, score and quality a bootstrap stratified by "
        "scenario. 'rank by success': by W / N alone (ties share a "
        f"rank). 'informed': told the environment's settings (limits, control period). {SCORE_NOTE}"
    )
    parts = [
        f"## {title}\n\n{_markdown_table(header, rows)}\n\n{note}\n",
        _success_markdown(results, order, confidence),
        f"### Score per scenario\n\n{_markdown_table(['controller', *scenarios], scenario_rows)}\n",
    ]
    if len(order) > 1:
        adjacent = paired_comparisons(results, list(itertools.pairwise(order)), per_scenario=False)
        parts.append(_paired_markdown(adjacent))
    return "\n".join(parts) + failures_markdown(failures)


def _paired_markdown(comparisons: Sequence[PairedComparison]) -> str:
    """The paired comparisons of adjacent controllers as a Markdown section."""
    header = [
        "pair",
        "episodes",
        "won by one only",
        "McNemar",
        "won by both",
        "higher quality",
        "median difference",
        "Wilcoxon",
    ]
    rows = [
        [
            f"{c.first} vs {c.second}",
            str(c.episodes),
            f"{c.first_only} / {c.second_only}",
            _p(c.mcnemar_p),
            str(c.both_won),
            f"{c.first_better} / {c.second_better}",
            "-" if math.isnan(c.quality_difference) else f"{c.quality_difference:+.1f}",
            _p(c.wilcoxon_p),
        ]
        for c in comparisons
    ]
    note = (
        "Each controller against the next in the ranking, on the episodes both ran that count (the same "
        "seeds): the episodes only the first / only the second won, with the exact McNemar test of equal "
        "success; of the episodes both won, where the first's / the second's quality is higher, the median "
        "of 1000 (q_first - q_second), and the Wilcoxon signed-rank test of equal quality. Every pair, per "
        "scenario too, is in run.json."
    )
    return f"### Paired comparisons\n\n{_markdown_table(header, rows)}\n\n{note}\n"


def _success_markdown(results: Sequence[EpisodeResult], order: Sequence[str], confidence: float) -> str:
    """Success per controller over all episodes, the winnable ones and per scenario, and the failures by
    outcome, as a Markdown section (rows in ``order``)."""
    scenarios = list(dict.fromkeys(r.scenario for r in results))
    groups = _groups(results)
    pooled = {c: [r.metrics for r in results if r.controller == c] for c in order}
    judged = all(r.winnable is not None for r in results)
    winnable = {c: _winnable_successes(r for r in results if r.controller == c) for c in order}
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
    winnable_note = (
        "'winnable': over the episodes whose loading has a depth-holding trim within the plane and pitch "
        "limits at their final speed, with every plane pair the vehicle has free (subenv.analysis.winnable). "
        if judged
        else ""
    )
    note = (
        f"Success rate with {100 * confidence:.0f}% Wilson intervals, {per} episodes per scenario "
        f"(the same seeds for every controller). {winnable_note}Last columns: episodes per failure outcome, "
        f"all scenarios. {OUTCOME_NOTE}"
    )
    return f"### Success and failures\n\n{_markdown_table(header, rows)}\n\n{note}\n"


_SUMMARY_MEANS: Final = (
    ("IAE [m s]", "iae_m_s"),
    ("settling [s]", "settling_time_s"),
    ("overshoot [m]", "overshoot_m"),
    ("peak pitch [deg]", "peak_pitch_deg"),
    ("plane RMS [rad]", "plane_rms_rad"),
    ("saturated", "saturated_fraction"),
    ("accuracy", "regulation_accuracy"),
    ("effort", "plane_effort"),
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
        "score",
        "quality",
        *(o.replace("_", " ") for o in shown),
        *(label for label, _ in _SUMMARY_MEANS),
        "settled",
        "safety events",
    ]
    scenarios = list(dict.fromkeys(r["scenario"] for r in summary))
    ordered = sorted(summary, key=lambda r: scenarios.index(r["scenario"]))  # stable: controllers keep order
    rows = []
    for r in ordered:
        cells = [r["scenario"], r["controller"], str(r["episodes"])]
        if judged:
            cells.append(f"{r['winnable_successes']}/{r['winnable']}")
        cells += [_score_cell(r[k], (r[f"{k}_ci_low"], r[f"{k}_ci_high"])) for k in ("score", "quality")]
        cells += [_pct(r[f"{o}_rate"], r[f"{o}_ci_low"], r[f"{o}_ci_high"]) for o in shown]
        cells += [
            _num(r[f"{name}_mean"], r[f"{name}_ci_low"], r[f"{name}_ci_high"]) for _, name in _SUMMARY_MEANS
        ]
        cells += [str(r["settled"]), str(r["safety_events"])]
        rows.append(cells)
    note = (
        "Rates of each outcome with 95% Wilson intervals; means with 95% Student-t intervals. Settling "
        "time averages the episodes that settled (column 'settled'). IAE charges a terminated episode "
        "its final error until the scheduled end. 'winnable: success': successes / episodes among those "
        "that have a depth-holding trim within the limits (subenv.analysis.winnable). Score and quality "
        "(of the episodes that count) with 95% intervals of a bootstrap, as in the leaderboard; accuracy: "
        f"the time fraction within {REGULATION_BAND_M:g} m from {APPROACH_S:g} s after the order; effort: "
        "the RMS plane angle per plane over the limit; safety events: episodes ended by broaching or the "
        f"pitch limit. {OUTCOME_NOTE}"
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


def _parse(kind: str, text: str) -> Any:
    """A cell of the per-episode table as the field's type (``kind``: its annotation) holds it."""
    if kind == "str":
        return text
    if kind == "int":
        return int(text)
    if kind == "float":
        return float(text)  # (repr of a float, 'inf' and 'nan' included: exact)
    if text == "" and kind.endswith("| None"):
        return None
    if text not in ("True", "False"):
        raise ValueError(f"{text!r} is not a boolean (True or False)")
    return text == "True"


def read_results(path: str | os.PathLike[str]) -> list[EpisodeResult]:
    """The :class:`~subenv.evaluation.measure.EpisodeResult` objects of a per-episode table
    (``results.csv``, as :func:`episode_table` and :func:`write_csv` write it), without trajectories.

    Every float round-trips exactly, so the tables of what it returns are those of the run.

    Raises
    ------
    ValueError
        A column an episode's result needs is missing, or a cell is not of its column's type (named,
        with its line).
    """
    metric_fields = {f.name: str(f.type) for f in dataclasses.fields(EpisodeMetrics)}
    result_fields = {
        f.name: str(f.type)
        for f in dataclasses.fields(EpisodeResult)
        if f.name not in ("metrics", "trajectory")
    }
    optional = {f.name for f in dataclasses.fields(EpisodeResult) if f.default is not dataclasses.MISSING}
    with open(path, newline="") as file:
        reader = csv.DictReader(file)
        columns = set(reader.fieldnames or ())
        missing = [c for c in (*result_fields, *metric_fields) if c not in columns and c not in optional]
        if missing:
            raise ValueError(
                f"{os.fspath(path)!r} lacks the columns {missing}: it is not a results.csv of subenv"
            )
        out = []
        for line, row in enumerate(reader, start=2):
            try:
                metrics = EpisodeMetrics(**{k: _parse(kind, row[k]) for k, kind in metric_fields.items()})
                given = {k: _parse(kind, row[k]) for k, kind in result_fields.items() if k in columns}
            except ValueError as exc:
                raise ValueError(f"{os.fspath(path)!r}, line {line}: {exc}") from None
            out.append(EpisodeResult(**given, metrics=metrics))
    return out
