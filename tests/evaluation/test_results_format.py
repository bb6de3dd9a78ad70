"""What ``subenv evaluate`` writes: a run validated against the documented format (a JSON Schema of
run.json, the columns of results.csv), and the tables (leaderboard and summary) recomputed from the
per-episode CSV alone."""

from __future__ import annotations

import csv
import json
import math
from collections import defaultdict
from pathlib import Path

import jsonschema
import pytest

from subenv.evaluation import run_comparison
from subenv.evaluation.results import leaderboard_markdown, read_results, summarize, table_csv
from subenv.evaluation.results_format import RESULTS_COLUMNS, RUN_SCHEMA, check_results_csv, markdown

DOC = Path(__file__).parents[2] / "docs" / "results-format.md"
CONTROLLERS = ("thesis", "reversal_aware", "lqr")


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run of three controllers on Nominal and BallastOffset, seeds 10009-10011: BallastOffset's 10010
    has no depth-holding trim (not scored), and the thesis design loses episodes there."""
    out = tmp_path_factory.mktemp("format") / "run"
    run_comparison(
        list(CONTROLLERS),
        ["Nominal", "BallastOffset"],
        episodes=3,
        seed=10009,
        out_dir=out,
        progress=False,
        plots=False,
    )
    return out


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as file:
        return list(csv.DictReader(file))


def test_run_json_is_valid_against_its_schema(written: Path) -> None:
    record = json.loads((written / "run.json").read_text())
    jsonschema.Draft202012Validator.check_schema(RUN_SCHEMA)
    jsonschema.Draft202012Validator(RUN_SCHEMA).validate(record)
    assert record["scored_by"] == "winnable" and record["env_kwargs"] == {}
    assert {(s["controller"], s["scenario"]) for s in record["scores"]} == {
        (c, s) for c in CONTROLLERS for s in ("Nominal", "BallastOffset", "all")
    }
    assert len([p for p in record["paired"] if p["scenario"] == "all"]) == 3  # every pair
    # The schema can fail: a field left out, or one it does not document.
    for broken in ({k: v for k, v in record.items() if k != "scores"}, record | {"extra": 1}):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(broken, RUN_SCHEMA)


def test_results_csv_has_the_documented_columns_and_cell_types(written: Path, tmp_path: Path) -> None:
    assert check_results_csv(written / "results.csv") == len(CONTROLLERS) * 2 * 3
    text = (written / "results.csv").read_text()
    assert text.splitlines()[0] == ",".join(RESULTS_COLUMNS)
    bad = tmp_path / "results.csv"
    bad.write_text(text.replace(",True,", ",yes,", 1))
    with pytest.raises(ValueError, match=r"line 2: .* is not a bool"):
        check_results_csv(bad)


def test_the_format_page_is_generated_from_the_definitions() -> None:
    assert DOC.read_text() == markdown(), (
        "run: python -m subenv.evaluation.results_format > docs/results-format.md"
    )


def test_both_tables_are_the_per_episode_csvs(written: Path) -> None:
    """summary.csv and leaderboard.md are what the per-episode CSV gives, read back."""
    results = read_results(written / "results.csv")
    assert (written / "summary.csv").read_text() == table_csv(summarize(results))
    board = leaderboard_markdown(results, title="Leaderboard: suite 'custom'")
    assert (written / "leaderboard.md").read_text() == board


def test_the_scores_recomputed_from_the_csv_agree_with_both_tables(written: Path) -> None:
    """The score's parts from results.csv by hand (N scored, W won, Q their mean quality, S), per
    controller and scenario against summary.csv, and pooled against the leaderboard and run.json."""
    groups: dict[tuple[str, str], list[dict[str, str]]] = defaultdict(list)
    for row in _rows(written / "results.csv"):
        groups[(row["controller"], row["scenario"])].append(row)
        groups[(row["controller"], "all")].append(row)

    def parts(rows: list[dict[str, str]]) -> tuple[int, int, float, float]:
        scored = [r for r in rows if r["scored"] == "True"]
        won = [float(r["quality"]) for r in scored if r["success"] == "True"]
        n, w = len(scored), len(won)
        q = sum(won) / w if w else math.nan
        return n, w, 1000 * q, (1000 * (w - 1 + q) / n if w else 0.0)

    expected = {key: parts(rows) for key, rows in groups.items()}
    assert any(r["scored"] == "False" for rows in groups.values() for r in rows)  # 10010 is left out
    for row in _rows(written / "summary.csv"):
        n, w, quality, score = expected[(row["controller"], row["scenario"])]
        assert (int(row["scored"]), int(row["wins"])) == (n, w)
        assert float(row["score"]) == pytest.approx(score, rel=1e-12)
        assert float(row["quality"]) == pytest.approx(quality, rel=1e-12, nan_ok=True)
    record = json.loads((written / "run.json").read_text())
    for s in record["scores"]:
        n, w, quality, score = expected[(s["controller"], s["scenario"])]
        assert (s["scored"], s["wins"], s["score"]) == (n, w, pytest.approx(score, rel=1e-12))
    board = (written / "leaderboard.md").read_text().split("\n\n")[1].splitlines()[2:]
    ranking = [[cell.strip() for cell in line.strip("|").split("|")] for line in board]
    pooled = {c: expected[(c, "all")] for c in CONTROLLERS}
    assert [row[1] for row in ranking] == sorted(CONTROLLERS, key=lambda c: (-pooled[c][3], c))
    for _, name, _, score, success, *_ in ranking:
        n, w, _, s = pooled[name]
        assert score.split(" ")[0] == f"{s:.1f}" and success.startswith(f"{w}/{n} ")
