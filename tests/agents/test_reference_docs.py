"""The multi-seed reference results shipped in docs/reference/ (made by ``python -m
subenv_agents.reference``): the benchmark page (docs/benchmark.md) shows
their table as the run wrote it, and the table's statistics
are those of their scores."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

metrics = pytest.importorskip("rliable.metrics", reason="the 'stats' extra is not installed")

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "reference"


def test_the_benchmark_page_shows_the_reference_table_as_the_run_wrote_it() -> None:
    table = [line for line in (DOCS / "reference.md").read_text().splitlines() if line.startswith("|")]
    page = (ROOT / "docs" / "benchmark.md").read_text()
    assert len(table) > 3 and all(line in page.splitlines() for line in table)


def test_the_reference_statistics_are_those_of_the_scores() -> None:
    summary = json.loads((DOCS / "reference.json").read_text())
    with open(DOCS / "scores.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    scenarios = summary["scenarios"]
    for name, runs in summary["runs"].items():
        mine = [r for r in rows if r["name"] == name]
        seeds = list(dict.fromkeys(r["seed"] for r in mine))
        assert len(seeds) == runs and len(mine) == runs * len(scenarios)
        score = np.array(
            [
                [
                    float(next(r["score"] for r in mine if r["seed"] == k and r["scenario"] == s))
                    for s in scenarios
                ]
                for k in seeds
            ]
        )
        aggregate = summary["aggregate"][name]
        assert math.isclose(aggregate["iqm"], metrics.aggregate_iqm(score), abs_tol=1e-12)
        assert math.isclose(aggregate["mean"], float(score.mean()), abs_tol=1e-12)
        for j, s in enumerate(scenarios):
            assert math.isclose(summary["per_scenario"][s][name][0], float(score[:, j].mean()), abs_tol=1e-12)
    multi = [n for n, kind in summary["kinds"].items() if kind == "multi-seed"]
    assert sorted(multi) == ["PPO", "PPO_JAX", "SAC", "TD3"] and all(summary["runs"][n] >= 5 for n in multi)
    # The score: several seeds' mean with an interval inside their range; one run's own, with its interval.
    for name, score in summary["benchmark_score"].items():
        assert len(score["runs"]) == summary["runs"][name]
        assert math.isclose(score["score"], float(np.mean(score["runs"])), abs_tol=1e-9)
        low, high = score["ci"]
        assert low <= score["score"] <= high
        if len(score["runs"]) > 1:
            assert min(score["runs"]) <= low and high <= max(score["runs"])
