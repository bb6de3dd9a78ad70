"""The reference results table of the protocol page (docs/guides/reporting.md), printed from results folders.

    PYTHONPATH=$PWD .venv/bin/python -m subenv evaluate --no-progress --out /tmp/bench
    PYTHONPATH=$PWD .venv/bin/python benchmarks/reference_table.py /tmp/bench/default /tmp/bench/hard

One Markdown table: per suite (``run.json``'s ``suite``) and controller, ranked by the pooled score, the
score and the quality with their intervals and the success W / N over the episodes the suite counts
(winnable on the default track, achievable on the Hard one), all read from each folder's ``run.json``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from subenv.evaluation.score import POOLED


def rows(folder: Path) -> list[str]:
    """The table's rows of one results folder, best score first."""
    run = json.loads((folder / "run.json").read_text("utf-8"))
    informed = {c["name"]: c["informed"] for c in run["controllers"]}
    pooled = sorted((s for s in run["scores"] if s["scenario"] == POOLED), key=lambda s: -s["score"])
    lines = []
    for s in pooled:
        quality = (
            "-"
            if s["wins"] == 0
            else f"{s['quality']:.0f} [{s['quality_ci_low']:.0f}, {s['quality_ci_high']:.0f}]"
        )
        told = "yes" if informed[s["controller"]] else "no"
        lines.append(
            f"| {run['suite']} ({run['scored_by']}) | {s['controller']} | {told} "
            f"| {s['score']:.0f} [{s['score_ci_low']:.0f}, {s['score_ci_high']:.0f}] "
            f"| {s['wins']}/{s['scored']} {100 * s['success_rate']:.0f}% "
            f"[{100 * s['success_ci_low']:.0f}, {100 * s['success_ci_high']:.0f}] | {quality} |"
        )
    return lines


def main() -> None:
    folders = [Path(arg) for arg in sys.argv[1:]]
    if not folders:
        raise SystemExit("usage: reference_table.py RESULTS_FOLDER [RESULTS_FOLDER ...]")
    print(
        "| suite (counted) | controller | informed | score [95% CI] | success [95% CI] | quality [95% CI] |"
    )
    print("|---|---|---|---|---|---|")
    for folder in folders:
        print("\n".join(rows(folder)))


if __name__ == "__main__":
    main()
