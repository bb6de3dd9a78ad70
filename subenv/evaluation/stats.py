"""Confidence intervals of the tables: Wilson for rates, Student t for means, the bootstrap for medians.

The score's own intervals (a stratified bootstrap) and paired tests are in :mod:`subenv.evaluation.score`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final

import numpy as np

__all__ = ["CONFIDENCE_LEVEL", "mean_interval", "median_interval", "wilson_interval"]

CONFIDENCE_LEVEL: Final = 0.95
"""Two-sided level of every confidence interval in the tables."""


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
