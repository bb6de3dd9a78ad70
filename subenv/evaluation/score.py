"""The score of a controller, 0-1000, with intervals; and paired comparisons of controllers.

**The score.** On a set of N scored episodes (those its suite's classifier counts: the winnable ones on
the default suite; :mod:`subenv.evaluation.classify`) a controller wins W, with a mean quality Q over
the won ones (:func:`subenv.evaluation.metrics.episode_quality`: q = 0.8 a + 0.2 (1 - e^2), a the
regulation accuracy, e the plane effort). Its score is::

    S = 1000 (W - 1 + Q) / N    for W >= 1,     S = 0 for W = 0,

so that 1000 (W - 1) / N <= S <= 1000 W / N: the score is the success count, with the quality as a
tie-break that can move it by less than one episode's worth. A controller that wins more episodes of
the same N never scores less than one that wins fewer, however well the other holds depth (equal only
at the band's edges); between controllers that win alike (the best ones win every winnable episode of
the default suite) the quality decides. This is the only shape such a score can have: if the quality
could move a score by more than 1000 / N, a controller with one more win and a worse quality could fall
below one with fewer. The quality, reported beside it on the same 0-1000 scale (1000 Q), shows how much
better one controller holds depth than another when both win everything.

The score is given per controller and scenario, and pooled over a suite (all its scored episodes, so
that the guarantee holds for the suite's total wins too).

**Intervals.** The success rate's is Wilson's (:func:`~subenv.evaluation.stats.wilson_interval`). The
score's and the quality's come from a stratified bootstrap (``scipy.stats.bootstrap``, percentile
intervals, :data:`BOOTSTRAP_RESAMPLES` resamples, seed :data:`BOOTSTRAP_SEED`): the episodes of each
scenario are resampled on their own (one sample per scenario), so each resample keeps the suite's mix of
scenarios, as rliable's stratified bootstrap does (Agarwal et al. 2021). Per episode the score reads
x = q for a won episode and -1 for a lost one; the quality resamples the won episodes' q.

**Paired comparisons.** Controllers that ran the same seeds met the same episodes, so their results
pair up: an exact McNemar test on success (``scipy.stats.binomtest`` on the discordant pairs: episodes
one won and the other lost) and a Wilcoxon signed-rank test (``scipy.stats.wilcoxon``) on the quality
over the episodes both won (:func:`paired_comparisons`).

References
----------
Tassa, Y. et al. (2018). DeepMind Control Suite. arXiv:1801.00690 (scores 0-1000 per task).
Agarwal, R. et al. (2021). Deep reinforcement learning at the edge of the statistical precipice.
NeurIPS (stratified bootstrap intervals).
McNemar, Q. (1947). Psychometrika 12, 153-157. Wilcoxon, F. (1945). Biometrics Bulletin 1, 80-83.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass
from typing import Any, Final

import numpy as np

from subenv.evaluation.measure import EpisodeResult
from subenv.evaluation.stats import CONFIDENCE_LEVEL, wilson_interval

__all__ = [
    "BOOTSTRAP_RESAMPLES",
    "BOOTSTRAP_SEED",
    "POOLED",
    "SCORE_FORMULA",
    "SCORE_MAX",
    "PairedComparison",
    "Score",
    "paired_comparisons",
    "rank_by_score",
    "rank_by_success",
    "score_value",
    "scores",
]

SCORE_MAX: Final = 1000.0
"""The score's scale, DeepMind Control Suite's (0-1000 per task)."""

BOOTSTRAP_RESAMPLES: Final = 2000
"""Resamples of the score's and the quality's intervals: 50 beyond each bound of a 95% percentile
interval, and a bound moves by at most 4% of the interval's width from one bootstrap seed to another
(measured over seeds 0-4 on the default suite's mpc, reversal_aware and lqr). One bootstrap per
controller gives every scenario's interval and the pooled one (each scenario's episodes are resampled
from that scenario alone, so its own interval is that of its own bootstrap): the default suite's eight
controllers (5600 episodes) take 0.6-0.7 s on a loaded 2-core machine."""

BOOTSTRAP_SEED: Final = 0
"""Fixed, so the same results give the same intervals every time."""

POOLED: Final = "all"
"""The scenario of a score pooled over a suite's scenarios."""

SCORE_FORMULA: Final = "S = 1000 (W - 1 + Q) / N (0 if W = 0)"
"""The score in one line, as the leaderboard's caption and ``run.json`` give it."""


def score_value(wins: int, scored: int, quality: float) -> float:
    """S = 1000 (W - 1 + Q) / N for W >= 1, 0 for W = 0 (nan for N = 0): ``wins`` W of ``scored`` N
    episodes, with a mean quality ``quality`` Q in [0, 1] over the won ones."""
    if scored == 0:
        return math.nan
    if wins == 0:
        return 0.0
    return SCORE_MAX * (wins - 1 + quality) / scored


def _score_values(wins: np.ndarray, total: np.ndarray, scored: int) -> np.ndarray:
    """:func:`score_value`, vectorised: ``wins`` W and the won episodes' summed quality ``total``."""
    quality = total / np.maximum(wins, 1)
    return np.where(wins >= 1, SCORE_MAX * (wins - 1 + quality) / max(scored, 1), 0.0)


def _scores_of(strata: Sequence[np.ndarray], axis: int) -> np.ndarray:
    """The score of each stratum of x (q won, -1 lost), then of all pooled: shape (k + 1, ...)."""
    wins = [np.count_nonzero(x >= 0, axis=axis) for x in strata]
    totals = [np.maximum(x, 0.0).sum(axis=axis) for x in strata]  # (q >= 0: the won episodes' q)
    each = [_score_values(w, t, x.shape[axis]) for w, t, x in zip(wins, totals, strata, strict=True)]
    pooled = _score_values(sum(wins), sum(totals), sum(x.shape[axis] for x in strata))
    return np.stack([*each, pooled])


def _qualities_of(strata: Sequence[np.ndarray], axis: int) -> np.ndarray:
    """1000 times the mean of each stratum of q, then of all pooled: shape (k + 1, ...)."""
    totals = [x.sum(axis=axis) for x in strata]
    sizes = [x.shape[axis] for x in strata]
    each = [SCORE_MAX * t / n for t, n in zip(totals, sizes, strict=True)]
    return np.stack([*each, SCORE_MAX * sum(totals) / sum(sizes)])


def _stratified_intervals(
    strata: Sequence[np.ndarray],
    statistic: Callable[[Sequence[np.ndarray], int], np.ndarray],
    confidence: float,
) -> np.ndarray:
    """Percentile intervals of a statistic of every stratum and of all pooled (``statistic`` returns
    k + 1 values for k non-empty strata), from one stratified bootstrap: each resample draws every
    stratum's episodes from that stratum alone, keeping its size; returns shape (k + 1, 2).

    A stratum of one episode resamples to itself, so it enters every resample as it is, and its own
    interval is (nan, nan), as is the pooled one without a stratum of two or more (nothing to resample).
    """
    varying = [i for i, x in enumerate(strata) if x.size >= 2]
    out = np.full((len(strata) + 1, 2), np.nan)
    if not varying:
        return out
    from scipy import stats  # imported on use: importing subenv.evaluation stays light

    def resampled(*drawn: np.ndarray, axis: int = -1) -> np.ndarray:
        batch = drawn[0].shape[:-1]
        full = [np.broadcast_to(x, (*batch, x.size)) for x in strata]
        for i, x in zip(varying, drawn, strict=True):
            full[i] = x
        return statistic(full, axis)

    ci = stats.bootstrap(
        tuple(strata[i] for i in varying),
        resampled,
        n_resamples=BOOTSTRAP_RESAMPLES,
        confidence_level=confidence,
        method="percentile",
        vectorized=True,
        rng=np.random.default_rng(BOOTSTRAP_SEED),
    ).confidence_interval
    out[:] = np.stack([ci.low, ci.high], axis=-1)
    out[[i for i, x in enumerate(strata) if x.size < 2]] = np.nan
    return out


@dataclass(frozen=True)
class Score:
    """A controller's score on a scenario, or pooled over a suite (:data:`POOLED`), with its parts.

    Attributes
    ----------
    controller, scenario : str
    episodes : int
        Every episode run.
    scored : int
        N: the episodes the score counts.
    wins : int
        W: the scored episodes won.
    quality : float
        1000 Q, Q the mean quality of the won scored episodes (nan when none was won).
    score : float
        S (:func:`score_value`), 0-1000.
    success_ci, quality_ci, score_ci : tuple of float
        Intervals of W / N (Wilson), of the quality and of the score (stratified bootstrap).
    """

    controller: str
    scenario: str
    episodes: int
    scored: int
    wins: int
    quality: float
    score: float
    success_ci: tuple[float, float]
    quality_ci: tuple[float, float]
    score_ci: tuple[float, float]

    @property
    def success_rate(self) -> float:
        """W / N (nan for N = 0)."""
        return self.wins / self.scored if self.scored else math.nan

    def as_dict(self) -> dict[str, Any]:
        """Flat: the counts, ``success_rate``, ``quality``, ``score``, each interval as ``<name>_ci_low``
        and ``<name>_ci_high``."""
        row = {k: v for k, v in asdict(self).items() if not k.endswith("_ci")}
        row["success_rate"] = self.success_rate
        for name in ("success", "quality", "score"):
            low, high = getattr(self, f"{name}_ci")
            row |= {f"{name}_ci_low": low, f"{name}_ci_high": high}
        return row


def _controller_scores(controller: str, results: Sequence[EpisodeResult], confidence: float) -> list[Score]:
    """One controller's :class:`Score` on each scenario (in the order first seen), then pooled; the
    intervals of all of them from one stratified bootstrap of the score and one of the quality."""
    scenarios = list(dict.fromkeys(r.scenario for r in results))
    every = {s: [r for r in results if r.scenario == s] for s in scenarios}
    x = {
        s: np.array([r.metrics.quality if r.metrics.success else -1.0 for r in rs if r.counts])
        for s, rs in every.items()
    }
    won = {s: xs[xs >= 0] for s, xs in x.items()}
    scored = [s for s in scenarios if x[s].size]  # (a scenario without scored episodes has no score)
    winning = [s for s in scenarios if won[s].size]
    score_rows = _stratified_intervals([x[s] for s in scored], _scores_of, confidence)
    quality_rows = _stratified_intervals([won[s] for s in winning], _qualities_of, confidence)
    score_ci = dict(zip([*scored, POOLED], score_rows, strict=True))
    quality_ci = dict(zip([*winning, POOLED], quality_rows, strict=True))
    out = []
    for scenario in [*scenarios, POOLED]:
        xs = np.concatenate([x[s] for s in scenarios]) if scenario == POOLED else x[scenario]
        n, wins = xs.size, int(np.count_nonzero(xs >= 0))
        q = float(np.maximum(xs, 0.0).sum()) / wins if wins else math.nan
        out.append(
            Score(
                controller=controller,
                scenario=scenario,
                episodes=len(results) if scenario == POOLED else len(every[scenario]),
                scored=n,
                wins=wins,
                quality=SCORE_MAX * q,
                score=score_value(wins, n, q),
                success_ci=wilson_interval(wins, n, confidence),
                quality_ci=_pair(quality_ci.get(scenario)),
                score_ci=_pair(score_ci.get(scenario)),
            )
        )
    return out


def _pair(interval: np.ndarray | None) -> tuple[float, float]:
    return (math.nan, math.nan) if interval is None else (float(interval[0]), float(interval[1]))


def scores(results: Sequence[EpisodeResult], confidence: float = CONFIDENCE_LEVEL) -> list[Score]:
    """Every controller's :class:`Score` on each scenario, then pooled (:data:`POOLED`): controllers and
    scenarios in the order first seen."""
    by_controller: dict[str, list[EpisodeResult]] = {}
    for r in results:
        by_controller.setdefault(r.controller, []).append(r)
    return [s for c, mine in by_controller.items() for s in _controller_scores(c, mine, confidence)]


def rank_by_score(pooled: Iterable[Score]) -> list[str]:
    """Controllers best first: by score, then by success rate, then by name."""
    return [
        s.controller
        for s in sorted(
            pooled,
            key=lambda s: (-_or(s.score, -1.0), -_or(s.success_rate, -1.0), s.controller),
        )
    ]


def rank_by_success(pooled: Iterable[Score]) -> dict[str, int]:
    """Each controller's rank by success rate over the scored episodes, 1 the best; controllers that
    win alike share a rank (1, 1, 3, ...)."""
    rates = {s.controller: _or(s.success_rate, -1.0) for s in pooled}
    return {c: 1 + sum(other > rate for other in rates.values()) for c, rate in rates.items()}


def _or(value: float, instead: float) -> float:
    return instead if math.isnan(value) else value


@dataclass(frozen=True)
class PairedComparison:
    """Two controllers on the episodes both ran (the same scenario and seed) and the score counts.

    Attributes
    ----------
    first, second : str
        The controllers.
    scenario : str
        A scenario, or :data:`POOLED` for all of the suite's.
    episodes : int
        The pairs: episodes both ran, scored for both.
    first_only, second_only : int
        Discordant pairs: episodes the first won and the second lost, and the other way round.
    mcnemar_p : float
        Exact McNemar test of equal success (two-sided binomial test of ``first_only`` of the
        discordant pairs at 1/2); 1 with no discordant pair.
    both_won : int
        Episodes both won.
    first_better, second_better : int
        Of those, where the first's quality is higher, and where the second's is.
    quality_difference : float
        The median over those of 1000 (q_first - q_second) (nan when none was won by both).
    wilcoxon_p : float
        Wilcoxon signed-rank test of equal quality over the episodes both won (zero differences
        dropped, as Wilcoxon did); 1 when every difference is zero, nan when none was won by both.
    """

    first: str
    second: str
    scenario: str
    episodes: int
    first_only: int
    second_only: int
    mcnemar_p: float
    both_won: int
    first_better: int
    second_better: int
    quality_difference: float
    wilcoxon_p: float

    def as_dict(self) -> dict[str, Any]:
        """The fields as a flat dict."""
        return asdict(self)


def _paired(
    first: str, second: str, scenario: str, pairs: list[tuple[EpisodeResult, EpisodeResult]]
) -> PairedComparison:
    from scipy import stats

    a = np.array([p[0].metrics.success for p in pairs], dtype=bool)
    b = np.array([p[1].metrics.success for p in pairs], dtype=bool)
    first_only, second_only = int(np.count_nonzero(a & ~b)), int(np.count_nonzero(b & ~a))
    discordant = first_only + second_only
    mcnemar = float(stats.binomtest(first_only, discordant, 0.5).pvalue) if discordant else 1.0
    both = [
        (x.metrics.quality, y.metrics.quality) for x, y in pairs if x.metrics.success and y.metrics.success
    ]
    d = np.array([x - y for x, y in both])
    if d.size == 0:
        wilcoxon, median = math.nan, math.nan
    else:
        median = float(SCORE_MAX * np.median(d))
        wilcoxon = float(stats.wilcoxon(d, zero_method="wilcox").pvalue) if np.any(d != 0) else 1.0
    return PairedComparison(
        first=first,
        second=second,
        scenario=scenario,
        episodes=len(pairs),
        first_only=first_only,
        second_only=second_only,
        mcnemar_p=mcnemar,
        both_won=int(d.size),
        first_better=int(np.count_nonzero(d > 0)),
        second_better=int(np.count_nonzero(d < 0)),
        quality_difference=median,
        wilcoxon_p=wilcoxon,
    )


def paired_comparisons(
    results: Sequence[EpisodeResult],
    pairs: Iterable[tuple[str, str]] | None = None,
    *,
    per_scenario: bool = True,
) -> list[PairedComparison]:
    """Paired comparisons of controllers on the episodes both ran and the score counts for both.

    Parameters
    ----------
    results : sequence of EpisodeResult
    pairs : iterable of (str, str), optional
        The controllers to compare (default: every pair, in the order first seen).
    per_scenario : bool
        Compare on each scenario too, not only over all the suite's (:data:`POOLED`).

    Returns
    -------
    list of PairedComparison
        Per pair: the pooled comparison, then (``per_scenario``) one per scenario both ran.
    """
    runs: dict[str, dict[tuple[str, int], EpisodeResult]] = {}  # controller -> (scenario, seed) -> result
    for r in results:
        runs.setdefault(r.controller, {})[(r.scenario, r.seed)] = r
    out = []
    for first, second in itertools.combinations(runs, 2) if pairs is None else pairs:
        theirs = runs[second]
        matched = [
            (r, theirs[key])
            for key, r in runs[first].items()
            if key in theirs and r.counts and theirs[key].counts
        ]
        out.append(_paired(first, second, POOLED, matched))
        by_scenario: dict[str, list[tuple[EpisodeResult, EpisodeResult]]] = {}
        for pair in matched if per_scenario else ():
            by_scenario.setdefault(pair[0].scenario, []).append(pair)
        out += [_paired(first, second, scenario, mine) for scenario, mine in by_scenario.items()]
    return out
