"""Confidence intervals, tables and the atomic writing of results."""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import os
from pathlib import Path

import numpy as np
import pytest

from subenv.evaluation import results as res
from subenv.evaluation.metrics import OUTCOMES, episode_metrics


@pytest.mark.parametrize(
    ("successes", "n", "low", "high"),
    [
        # Newcombe (1998), Statistics in Medicine 17:857-872, Table I, method 3 (Wilson score).
        (81, 263, 0.2553, 0.3662),
        (15, 148, 0.0624, 0.1605),
        (0, 20, 0.0, 0.1611),
        (1, 29, 0.0061, 0.1718),
    ],
)
def test_wilson_interval_matches_published_values(successes, n, low, high):
    lo, hi = res.wilson_interval(successes, n)
    assert (round(lo, 4), round(hi, 4)) == (low, high)


def test_wilson_interval_closed_form_and_edges():
    z = 1.959963984540054
    k, n = 7, 50
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    assert res.wilson_interval(k, n) == pytest.approx((centre - half, centre + half), rel=1e-12)
    assert res.wilson_interval(10, 10)[1] == pytest.approx(1.0)
    assert all(math.isnan(v) for v in res.wilson_interval(0, 0))
    with pytest.raises(ValueError, match="successes"):
        res.wilson_interval(3, 2)


def test_mean_interval_is_the_student_t_interval():
    mean, low, high = res.mean_interval([1.0, 2.0, 3.0])
    half = 4.302652729749464 * 1.0 / math.sqrt(3)  # t_{0.975, 2} * s / sqrt(n)
    assert (mean, low, high) == pytest.approx((2.0, 2.0 - half, 2.0 + half), rel=1e-9)
    assert res.mean_interval([5.0, 5.0, 5.0]) == (5.0, 5.0, 5.0)  # no spread, no width
    m1 = res.mean_interval([4.0])
    assert m1[0] == 4.0 and math.isnan(m1[1]) and math.isnan(m1[2])
    assert res.mean_interval([0.0, 0.0, 9.0], support=(0.0, math.inf))[1] == 0.0  # clipped at 0


def _results(make_result):
    _result = make_result
    out = []
    for i in range(4):
        out.append(_result("weak", "A", i, success=i == 0))
        out.append(_result("weak", "B", i, success=False))
        out.append(_result("strong", "A", i, success=True))
        out.append(_result("strong", "B", i, success=i < 3))
    return out


def test_summary_aggregates_per_controller_and_scenario(make_result):
    summary = res.summarize(_results(make_result))
    by_key = {(r["controller"], r["scenario"]): r for r in summary}
    assert set(by_key) == {("weak", "A"), ("weak", "B"), ("strong", "A"), ("strong", "B")}
    strong_b = by_key[("strong", "B")]
    assert strong_b["episodes"] == 4 and strong_b["success_rate"] == 0.75
    ci = (strong_b["success_ci_low"], strong_b["success_ci_high"])
    assert ci == pytest.approx(res.wilson_interval(3, 4))
    assert strong_b["outcome_success"] == 3 and strong_b["outcome_steady_offset"] == 1
    assert strong_b["settled"] == 3  # settling time averages the settled episodes only
    weak_b = by_key[("weak", "B")]
    assert weak_b["settled"] == 0 and math.isnan(weak_b["settling_time_s_mean"])


def test_leaderboard_ranks_by_pooled_success_and_lists_every_scenario(make_result):
    text = res.leaderboard_markdown(_results(make_result), title="T")
    ranking = _markdown_rows(text)
    assert [(row["rank"], row["controller"]) for row in ranking] == [("1", "strong"), ("2", "weak")]
    assert ranking[0]["success"] == "7/8 88% [53, 98]"  # 7 of 8, Wilson
    assert [row["rank by success"] for row in ranking] == ["1", "2"]
    lines = [line for line in _section(text, "Success and failures").splitlines() if line.startswith("| ")]
    header, rows = lines[0], lines[1:]
    assert header.startswith("| controller | all scenarios | A | B |")
    assert [row.split("|")[1].strip() for row in rows] == ["strong", "weak"]
    assert "88% [53, 98]" in rows[0]
    assert "| controller | A | B |" in _section(text, "Score per scenario")
    assert "Wilson" in text and "0.5 m" in text and "60 s" in text
    assert "S = 1000 (W - 1 + Q) / N" in text and "tie-break" in text  # the formula and why, in the caption
    with pytest.raises(ValueError, match="empty"):
        res.leaderboard_markdown([])


def test_episode_table_round_trips_through_csv(tmp_path: Path, make_result):
    rows = res.episode_table(_results(make_result))
    path = res.write_csv(tmp_path / "results.csv", rows)
    read = list(csv.DictReader(io.StringIO(path.read_text())))
    assert len(read) == 16
    assert read[0]["controller"] == "weak" and read[0]["success"] == "True"
    assert float(read[0]["critical_speed_mps"]) == 0.5785
    assert float(read[1]["settling_time_s"]) == math.inf
    for key in ("initial_speed_mps", "critical_speed_mps", "iae_m_s", "outcome", "wrong_branch", "seed"):
        assert key in read[0]


def test_atomic_write_leaves_the_old_file_when_it_fails(tmp_path: Path, monkeypatch):
    path = tmp_path / "summary.csv"
    res.atomic_write_text(path, "old\n")

    def broken_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        res.atomic_write_text(path, "new\n")
    assert path.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["summary.csv"]  # no temporary file left


def test_output_folder_is_refused_if_it_exists_and_replaced_with_overwrite(tmp_path: Path):
    out = tmp_path / "eval"
    with res.atomic_output_dir(out) as tmp:
        res.atomic_write_text(tmp / "a.txt", "first")
        assert not out.exists()  # nothing visible until the block succeeds
    assert (out / "a.txt").read_text() == "first"
    with pytest.raises(FileExistsError, match="exists"), res.atomic_output_dir(out):
        pytest.fail("the block must not run when the folder exists")
    with res.atomic_output_dir(out, overwrite=True) as tmp:
        res.atomic_write_text(tmp / "b.txt", "second")
    assert sorted(p.name for p in out.iterdir()) == ["b.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eval"]  # no temporary folders left


def test_a_failed_run_writes_no_folder(tmp_path: Path):
    out = tmp_path / "eval"
    with pytest.raises(RuntimeError, match="crash"), res.atomic_output_dir(out) as tmp:
        res.atomic_write_text(tmp / "half.csv", "x")
        raise RuntimeError("crash")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "file").write_text("not a folder")
    with pytest.raises(FileExistsError, match="not a folder"):
        res.check_output_dir(tmp_path / "file", overwrite=True)


def _wrong_branch_then_broached(make_result, controller: str, scenario: str, episode: int):
    """The thesis's failure mode over the final 60 s (stern plane pinned, steady 3 deg pitch, rising off
    depth), ended by broaching: outcome wrong_branch, broached flag set."""
    t = np.arange(0.0, 121.0, 1.0)
    e = np.linspace(2.0, -8.0, t.size)
    limit = 0.4
    m = episode_metrics(
        t,
        e,
        np.full_like(t, math.radians(3.0)),
        np.zeros_like(t),
        np.full_like(t, limit),
        np.zeros_like(t),
        termination_reason="broached",
        plane_limit_rad=limit,
    )
    assert m.wrong_branch and m.broached and m.outcome == "wrong_branch"
    return dataclasses.replace(make_result(controller, scenario, episode, False), metrics=m)


def _broached(make_result, controller: str, scenario: str, episode: int):
    t = np.arange(0.0, 31.0, 1.0)
    zeros = np.zeros_like(t)
    m = episode_metrics(
        t,
        np.linspace(0.0, -10.0, t.size),
        zeros,
        zeros,
        zeros,
        zeros,
        termination_reason="broached",
        plane_limit_rad=0.4,
    )
    assert m.outcome == "broached"
    return dataclasses.replace(make_result(controller, scenario, episode, False), metrics=m)


def test_outcome_counts_count_every_episode_once(make_result):
    metrics = [
        _wrong_branch_then_broached(make_result, "c", "A", 0).metrics,
        _broached(make_result, "c", "A", 1).metrics,
        make_result("c", "A", 2, True).metrics,
    ]
    counts = res.outcome_counts(metrics)
    assert list(counts)[: len(OUTCOMES)] == list(OUTCOMES)
    assert counts["wrong_branch"] == 1 and counts["broached"] == 1 and counts["success"] == 1
    assert sum(counts.values()) == 3  # the broaching wrong-branch episode is not counted twice
    assert sum(m.broached for m in metrics) == 2  # though two episodes ended by broaching


def _section(text: str, heading: str) -> str:
    """The text of a leaderboard's ``### heading`` section (to the next heading)."""
    after = text.split(f"### {heading}\n", 1)[1]
    return after.split("\n#", 1)[0]


def _markdown_rows(text: str) -> list[dict[str, str]]:
    """The rows of the first table of ``text``, by column."""
    lines = []
    for line in text.splitlines():
        if line.startswith("|"):
            lines += [line] if line.startswith("| ") else []  # (not the header's separator)
        elif lines:
            break
    header = [cell.strip() for cell in lines[0].strip("|").split("|")]
    return [
        dict(zip(header, (cell.strip() for cell in line.strip("|").split("|")), strict=True))
        for line in lines[1:]
    ]


def _assert_tables_agree(results) -> set[str]:
    """The leaderboard's failure counts equal summary.md's rates times n, summed over the scenarios;
    each summary row's rates add up to 100%. Returns the failure outcomes the tables show."""
    board = _markdown_rows(_section(res.leaderboard_markdown(results), "Success and failures"))
    summary = _markdown_rows(res.summary_markdown(res.summarize(results)))
    scenarios = {r.scenario for r in results}
    board_failures = [k for k in board[0] if k not in {"controller", "all scenarios", "winnable", *scenarios}]
    columns = [c for c in summary[0] if c not in ("winnable: success", "score", "quality")]
    rate_columns = columns[3 : columns.index("IAE [m s]")]
    assert rate_columns[0] == "success" and rate_columns[1:] == board_failures
    for row in summary:
        percents = [int(row[c].split("%")[0]) for c in rate_columns]
        assert abs(sum(percents) - 100) <= len(percents) / 2  # integer rounding of each rate
    for line in board:
        mine = [row for row in summary if row["controller"] == line["controller"]]
        for outcome in board_failures:
            from_summary = sum(round(int(row[outcome].split("%")[0]) * int(row["n"]) / 100) for row in mine)
            assert int(line[outcome]) == from_summary, (line["controller"], outcome)
    return set(board_failures)


def test_leaderboard_and_summary_count_failures_alike(make_result):
    results = []
    for i in range(4):
        results += [
            _wrong_branch_then_broached(make_result, "thesis", "A", i)
            if i < 2
            else _broached(make_result, "thesis", "A", i),
            make_result("thesis", "B", i, success=i < 3),
            make_result("other", "A", i, success=True),
            _broached(make_result, "other", "B", i) if i == 0 else make_result("other", "B", i, True),
        ]
    assert _assert_tables_agree(results) == {"wrong branch", "steady offset", "broached"}
    board_text = _section(res.leaderboard_markdown(results), "Success and failures")
    board = {row["controller"]: row for row in _markdown_rows(board_text)}
    assert board["thesis"]["broached"] == "2" and board["thesis"]["wrong branch"] == "2"
    assert "first that applies" in res.leaderboard_markdown(results)
    assert "first that applies" in res.summary_markdown(res.summarize(results))


def test_tables_agree_on_a_small_run(small_run):
    # The case that made the tables disagree: wrong-branch episodes that then broached.
    assert any(r.metrics.outcome == "wrong_branch" and r.metrics.broached for r in small_run.results)
    assert _assert_tables_agree(small_run.results) >= {"wrong branch", "broached"}


def test_by_speed_ratio_bins_each_scenario_on_its_own(make_result):
    results = []
    for i, ratio in enumerate(np.linspace(0.3, 0.8, 8)):  # scenario "Low": ratios 0.3-0.8
        r = make_result("a", "Low", i, success=ratio > 0.55, iae=float(i + 1))
        results.append(dataclasses.replace(r, final_speed_mps=ratio * r.critical_speed_mps))
    for i in range(3):  # scenario "Fixed": one speed, 2.63 u_cr
        r = make_result("a", "Fixed", i, success=True)
        results.append(dataclasses.replace(r, final_speed_mps=2.63 * r.critical_speed_mps))
    rows = res.by_speed_ratio(results, bins=2)
    low = [row for row in rows if row["scenario"] == "Low"]
    assert [x for row in low for x in (row["ratio_low"], row["ratio_high"])] == pytest.approx(
        [0.3, 0.55, 0.55, 0.8]
    )
    assert [row["episodes"] for row in low] == [4, 4]
    assert [row["success"] for row in low] == [0, 4]
    assert (low[1]["success_ci_low"], low[1]["success_ci_high"]) == pytest.approx(res.wilson_interval(4, 4))
    fixed = [row for row in rows if row["scenario"] == "Fixed"]
    assert len(fixed) == 1 and fixed[0]["episodes"] == 3 and fixed[0]["ratio_mean"] == pytest.approx(2.63)
    by_default = res.by_speed_ratio(results)  # 8 episodes: round(sqrt(8) / 2) = 1 bin
    assert [row["episodes"] for row in by_default if row["scenario"] == "Low"] == [8]


def test_median_interval_brackets_the_median_and_repeats():
    values = [1.0, 2.0, 3.0, 4.0, 100.0]
    median, low, high = res.median_interval(values)
    assert median == 3.0 and 1.0 <= low <= 3.0 <= high <= 100.0
    assert res.median_interval(values) == (median, low, high)  # a fixed seed: the same figure every time
    assert res.median_interval([2.0, 2.0]) == (2.0, 2.0, 2.0)
    one = res.median_interval([7.0])
    assert one[0] == 7.0 and math.isnan(one[1]) and math.isnan(one[2])


def test_representative_episode_is_the_commonest_controllers_median(make_result):
    results = [make_result("rare", "S", 0, success=True, iae=0.5)]
    results += [
        make_result("common", "S", i, success=True, iae=float(iae)) for i, iae in enumerate([3, 1, 2])
    ]
    results += [make_result("rare", "S", 5, success=False)]
    chosen = res.representative_episodes(results)["S"]
    assert list(chosen) == ["success", "steady_offset"]
    assert (chosen["success"].controller, chosen["success"].episode) == ("common", 2)  # IAE 2 of 1, 2, 3
    assert (chosen["steady_offset"].controller, chosen["steady_offset"].episode) == ("rare", 5)


def test_the_leaderboard_ranks_by_the_winnable_episodes(make_result):
    """An episode that no controller can win (no depth-holding trim within the limits) does not rank:
    a controller that lost only unwinnable episodes ranks above one that lost a winnable one."""

    def run(controller, lost_winnable):  # type: ignore[no-untyped-def]
        rows = [dataclasses.replace(make_result(controller, "A", i, True), winnable=True) for i in range(8)]
        rows += [
            dataclasses.replace(make_result(controller, "A", 8 + i, False), winnable=False) for i in range(3)
        ]
        if lost_winnable:  # wins two of the unwinnable ones by luck, loses one winnable
            rows[0] = dataclasses.replace(make_result(controller, "A", 0, False), winnable=True)
            rows[8] = dataclasses.replace(make_result(controller, "A", 8, True), winnable=False)
            rows[9] = dataclasses.replace(make_result(controller, "A", 9, True), winnable=False)
        return rows

    results = run("lucky", True) + run("sound", False)
    assert [line["controller"] for line in _markdown_rows(res.leaderboard_markdown(results))] == [
        "sound",
        "lucky",
    ]
    board = _markdown_rows(_section(res.leaderboard_markdown(results), "Success and failures"))
    assert [line["controller"] for line in board] == ["sound", "lucky"]
    assert board[0]["winnable"].startswith("100% ") and board[1]["winnable"].startswith("88% ")
    assert board[1]["all scenarios"].startswith("82% ") and board[0]["all scenarios"].startswith("73% ")
    summary = {r["controller"]: r for r in res.summarize(results)}
    assert (summary["sound"]["winnable"], summary["sound"]["winnable_successes"]) == (8, 8)
    assert "| A | lucky | 11 | 7/8 |" in res.summary_markdown(res.summarize(results))
