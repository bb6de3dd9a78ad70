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
"""Resamples of the score's and the quality's intervals: the percentile bounds then move by about a
tenth of the interval's width from one bootstrap seed to another, and the intervals of a comparison of
eight controllers on seven scenarios take about a second."""

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


def _sums(strata: Sequence[np.ndarray], axis: int) -> tuple[np.ndarray, np.ndarray]:
    """(wins, sum of the won episodes' q) over strata of x (q won, -1 lost), along ``axis``."""
    wins = sum(np.count_nonzero(x >= 0, axis=axis) for x in strata)
    total = sum(np.where(x >= 0, x, 0.0).sum(axis=axis) for x in strata)
    return np.asarray(wins), np.asarray(total)


def _score_statistic(scored: int) -> Callable[..., np.ndarray]:
    """The score of strata of x, vectorised along ``axis`` (N = ``scored``, fixed by the strata)."""

    def statistic(*strata: np.ndarray, axis: int = -1) -> np.ndarray:
        wins, total = _sums(strata, axis)
        quality = total / np.maximum(wins, 1)
        return np.where(wins >= 1, SCORE_MAX * (wins - 1 + quality) / scored, 0.0)

    return statistic


def _quality_statistic(*strata: np.ndarray, axis: int = -1) -> np.ndarray:
    """1000 times the mean of strata of q, vectorised along ``axis``."""
    wins, total = _sums(strata, axis)
    return SCORE_MAX * total / wins


def _stratified_interval(
    strata: Sequence[np.ndarray],
    statistic: Callable[..., np.ndarray],
    confidence: float,
) -> tuple[float, float]:
    """The percentile interval of ``statistic`` over a stratified bootstrap of ``strata``.

    A stratum of one episode resamples to itself, so it enters every resample as it is; without a
    stratum of two or more the interval is (nan, nan) (nothing to resample).
    """
    varying = [x for x in strata if x.size >= 2]
    fixed = [x for x in strata if x.size == 1]
    if not varying:
        return (math.nan, math.nan)
    if all(np.all(x == x[0]) for x in varying):  # every resample is the sample
        value = float(statistic(*strata))
        return (value, value)
    from scipy import stats  # imported on use: importing subenv.evaluation stays light

    def with_fixed(*resampled: np.ndarray, axis: int = -1) -> np.ndarray:
        shape = resampled[0].shape[:-1]
        return statistic(*resampled, *(np.broadcast_to(x, (*shape, 1)) for x in fixed), axis=axis)

    ci = stats.bootstrap(
        tuple(varying),
        with_fixed,
        n_resamples=BOOTSTRAP_RESAMPLES,
        confidence_level=confidence,
        method="percentile",
        vectorized=True,
        rng=np.random.default_rng(BOOTSTRAP_SEED),
    ).confidence_interval
    return (float(ci.low), float(ci.high))


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


def _score(controller: str, scenario: str, results: Sequence[EpisodeResult], confidence: float) -> Score:
    """The :class:`Score` of one controller's ``results`` (one scenario's, or a suite's: stratified by
    scenario)."""
    counted = [r for r in results if r.counts]
    by_scenario: dict[str, list[EpisodeResult]] = {}
    for r in counted:
        by_scenario.setdefault(r.scenario, []).append(r)
    x = [
        np.array([r.metrics.quality if r.metrics.success else -1.0 for r in rs])
        for rs in by_scenario.values()
    ]
    won = [xs[xs >= 0] for xs in x]
    n = len(counted)
    wins = sum(w.size for w in won)
    q = float(np.sum([w.sum() for w in won])) / wins if wins else math.nan
    return Score(
        controller=controller,
        scenario=scenario,
        episodes=len(results),
        scored=n,
        wins=wins,
        quality=SCORE_MAX * q,
        score=score_value(wins, n, q),
        success_ci=wilson_interval(wins, n, confidence),
        quality_ci=_stratified_interval(won, _quality_statistic, confidence),
        score_ci=_stratified_interval(x, _score_statistic(n), confidence) if n else (math.nan, math.nan),
    )


def scores(results: Sequence[EpisodeResult], confidence: float = CONFIDENCE_LEVEL) -> list[Score]:
    """Every controller's :class:`Score` on each scenario, then pooled (:data:`POOLED`): controllers and
    scenarios in the order first seen."""
    by_controller: dict[str, list[EpisodeResult]] = {}
    for r in results:
        by_controller.setdefault(r.controller, []).append(r)
    out = []
    for controller, mine in by_controller.items():
        scenarios = list(dict.fromkeys(r.scenario for r in mine))
        for scenario in scenarios:
            out.append(_score(controller, scenario, [r for r in mine if r.scenario == scenario], confidence))
        out.append(_score(controller, POOLED, mine, confidence))
    return out


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
    index = {(r.controller, r.scenario, r.seed): r for r in results}
    controllers = list(dict.fromkeys(r.controller for r in results))
    scenarios = list(dict.fromkeys(r.scenario for r in results))
    out = []
    for first, second in itertools.combinations(controllers, 2) if pairs is None else pairs:
        matched = [
            (r, index[(second, r.scenario, r.seed)])
            for r in results
            if r.controller == first and (second, r.scenario, r.seed) in index
        ]
        matched = [(x, y) for x, y in matched if x.counts and y.counts]
        out.append(_paired(first, second, POOLED, matched))
        if per_scenario:
            for scenario in scenarios:
                mine = [(x, y) for x, y in matched if x.scenario == scenario]
                if mine:
                    out.append(_paired(first, second, scenario, mine))
    return out
