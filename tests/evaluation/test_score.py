"""The score: its formula and guarantee, its stratified-bootstrap intervals, the ranking, and the paired
comparisons, on hand-made results whose answers are known."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from subenv.evaluation import score as sc
from subenv.evaluation.measure import EpisodeResult


@pytest.fixture
def episode(make_result):
    """An episode of ``controller`` on ``scenario`` with seed 100 + ``i``: won or lost, of quality ``q``."""

    def _episode(
        controller: str, scenario: str, i: int, won: bool, q: float = 1.0, scored: bool = True
    ) -> EpisodeResult:
        r = make_result(controller, scenario, i, won)
        return dataclasses.replace(
            r, metrics=dataclasses.replace(r.metrics, quality=q), winnable=scored, scored=scored
        )

    return _episode


@given(
    n=st.integers(1, 300),
    data=st.data(),
)
@settings(max_examples=200)
def test_more_wins_never_score_less_and_the_quality_moves_the_score_less_than_a_win(n, data) -> None:
    wins = data.draw(st.integers(0, n))
    q, q_other = data.draw(st.floats(0, 1)), data.draw(st.floats(0, 1))
    s = sc.score_value(wins, n, q)
    assert 1000 * max(wins - 1, 0) / n <= s <= 1000 * wins / n + 1e-9
    if wins < n:  # one more win, with any quality, scores at least as much
        assert sc.score_value(wins + 1, n, q_other) >= s - 1e-9
    assert sc.score_value(0, n, q) == 0.0
    assert math.isnan(sc.score_value(0, 0, q))


def test_a_controller_that_wins_more_ranks_above_one_that_holds_depth_better(episode) -> None:
    """10 of 10 won with a poor quality against 9 of 10 won perfectly: the one that wins more is first,
    by score and by success; the quality column says the other holds depth better."""
    results = [episode("steady", "A", i, True, q=0.2) for i in range(10)]
    results += [episode("sharp", "A", i, i < 9, q=1.0) for i in range(10)]
    table = sc.scores(results)
    pooled = {s.controller: s for s in table if s.scenario == sc.POOLED}
    assert (pooled["steady"].wins, pooled["steady"].scored) == (10, 10)
    assert pooled["steady"].score == pytest.approx(1000 * (9 + 0.2) / 10)
    assert pooled["sharp"].score == pytest.approx(1000 * (8 + 1.0) / 10)
    assert pooled["sharp"].quality == pytest.approx(1000.0) and pooled["steady"].quality == pytest.approx(
        200.0
    )
    assert sc.rank_by_score(pooled.values()) == ["steady", "sharp"]
    assert sc.rank_by_success(pooled.values()) == {"steady": 1, "sharp": 2}


def test_between_controllers_that_win_alike_the_quality_decides(episode) -> None:
    results = [episode("a", "A", i, True, q=0.8) for i in range(5)]
    results += [episode("b", "A", i, True, q=0.9) for i in range(5)]
    pooled = [s for s in sc.scores(results) if s.scenario == sc.POOLED]
    assert sc.rank_by_score(pooled) == ["b", "a"]
    assert sc.rank_by_success(pooled) == {"a": 1, "b": 1}  # a tie shares the rank


def test_the_score_counts_only_the_scored_episodes_and_pools_every_scenario(episode) -> None:
    results = [
        episode("c", "A", 0, True, q=0.5),
        episode("c", "A", 1, False),
        episode("c", "A", 2, True, q=1.0, scored=False),  # a win that cannot count
        episode("c", "B", 0, True, q=0.7),
        episode("c", "B", 1, True, q=0.9),
    ]
    by = {s.scenario: s for s in sc.scores(results)}
    assert list(by) == ["A", "B", sc.POOLED]
    assert (by["A"].episodes, by["A"].scored, by["A"].wins) == (3, 2, 1)
    assert by["A"].score == pytest.approx(1000 * (0 + 0.5) / 2)
    assert (by[sc.POOLED].scored, by[sc.POOLED].wins) == (4, 3)
    assert by[sc.POOLED].quality == pytest.approx(1000 * (0.5 + 0.7 + 0.9) / 3)  # over the won episodes
    assert by[sc.POOLED].score == pytest.approx(1000 * (2 + 0.7) / 4)
    assert by[sc.POOLED].success_ci == pytest.approx(stats.binomtest(3, 4).proportion_ci(method="wilson"))


def test_the_intervals_come_from_a_bootstrap_stratified_by_scenario(episode) -> None:
    """Each resample keeps every scenario's number of episodes: the interval is scipy's bootstrap with
    one sample per scenario; it contains the score, repeats (a fixed seed), and a scenario whose
    episodes are all alike adds no width."""
    rng = np.random.default_rng(5)
    results = [episode("c", "A", i, bool(rng.random() < 0.8), q=float(rng.random())) for i in range(30)]
    results += [episode("c", "B", i, True, q=0.5) for i in range(20)]
    pooled = next(s for s in sc.scores(results) if s.scenario == sc.POOLED)
    x = [
        np.array([r.metrics.quality if r.metrics.success else -1.0 for r in results if r.scenario == s])
        for s in "AB"
    ]

    def score(a, b, axis=-1):  # type: ignore[no-untyped-def]
        wins = (a >= 0).sum(axis) + (b >= 0).sum(axis)
        total = np.where(a >= 0, a, 0).sum(axis) + np.where(b >= 0, b, 0).sum(axis)
        return 1000 * (wins - 1 + total / wins) / 50

    expected = stats.bootstrap(
        tuple(x),
        score,
        n_resamples=sc.BOOTSTRAP_RESAMPLES,
        method="percentile",
        vectorized=True,
        rng=np.random.default_rng(sc.BOOTSTRAP_SEED),
    ).confidence_interval
    assert pooled.score_ci == pytest.approx((expected.low, expected.high), rel=1e-12)
    assert pooled.score_ci[0] <= pooled.score <= pooled.score_ci[1]
    assert pooled.quality_ci[0] <= pooled.quality <= pooled.quality_ci[1]
    again = next(s for s in sc.scores(results) if s.scenario == sc.POOLED)
    assert again == pooled
    b = next(s for s in sc.scores(results) if s.scenario == "B")
    assert b.score_ci == (b.score, b.score) and b.quality_ci == (500.0, 500.0)


def test_one_episode_has_no_interval_and_one_per_scenario_enters_every_resample(episode) -> None:
    one = sc.scores([episode("c", "A", 0, True, q=0.5)])[0]
    assert one.score == pytest.approx(500.0) and all(math.isnan(v) for v in one.score_ci)
    results = [episode("c", "A", 0, True, q=0.5)] + [
        episode("c", "B", i, i % 2 == 0, q=0.6) for i in range(6)
    ]
    pooled = next(s for s in sc.scores(results) if s.scenario == sc.POOLED)
    assert pooled.score_ci[0] <= pooled.score <= pooled.score_ci[1]
    assert all(math.isfinite(v) for v in pooled.score_ci)


def test_nothing_won_scores_zero_with_no_quality(episode) -> None:
    lost = sc.scores([episode("c", "A", i, False) for i in range(4)])[0]
    assert lost.score == 0.0 and lost.wins == 0 and math.isnan(lost.quality)
    assert lost.score_ci == (0.0, 0.0) and all(math.isnan(v) for v in lost.quality_ci)


def test_paired_comparisons_are_mcnemar_on_success_and_wilcoxon_on_quality(episode) -> None:
    rng = np.random.default_rng(3)
    won_a = rng.random(40) < 0.9
    won_b = rng.random(40) < 0.6
    q_a, q_b = rng.random(40), rng.random(40) * 0.8
    results = [episode("a", "S", i, bool(won_a[i]), float(q_a[i])) for i in range(40)]
    results += [episode("b", "S", i, bool(won_b[i]), float(q_b[i])) for i in range(40)]
    results += [episode("b", "S", 99, True)]  # a seed the other did not run: no pair
    results += [episode("a", "S", 50 + i, True, scored=False) for i in range(3)]  # not counted
    results += [episode("b", "S", 50 + i, False, scored=False) for i in range(3)]
    pooled, scenario = sc.paired_comparisons(results)
    assert (pooled.first, pooled.second, pooled.scenario, scenario.scenario) == ("a", "b", sc.POOLED, "S")
    assert dataclasses.replace(scenario, scenario=sc.POOLED) == pooled
    b, c = int(np.sum(won_a & ~won_b)), int(np.sum(won_b & ~won_a))
    assert (pooled.episodes, pooled.first_only, pooled.second_only) == (40, b, c)
    assert pooled.mcnemar_p == pytest.approx(stats.binomtest(b, b + c, 0.5).pvalue)
    both = won_a & won_b
    d = q_a[both] - q_b[both]
    assert (pooled.both_won, pooled.first_better, pooled.second_better) == (
        both.sum(),
        (d > 0).sum(),
        (d < 0).sum(),
    )
    assert pooled.wilcoxon_p == pytest.approx(stats.wilcoxon(d).pvalue)
    assert pooled.quality_difference == pytest.approx(1000 * np.median(d))


def test_identical_controllers_show_no_difference(episode) -> None:
    results = [episode(c, "S", i, i != 2, 0.7) for c, i in itertools.product("ab", range(5))]
    (pooled,) = sc.paired_comparisons(results, per_scenario=False)
    assert (pooled.first_only, pooled.second_only, pooled.mcnemar_p) == (0, 0, 1.0)
    assert (pooled.both_won, pooled.wilcoxon_p, pooled.quality_difference) == (4, 1.0, 0.0)
