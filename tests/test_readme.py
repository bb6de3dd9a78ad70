"""The README's Python blocks run as written, in order, as a reader would paste them into one session."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text("utf-8"), flags=re.S)


def test_the_readme_has_its_examples() -> None:
    assert len(BLOCKS) >= 5 and any("class DepthP" in block for block in BLOCKS)


def test_every_python_block_of_the_readme_runs(tmp_path, monkeypatch, capsys) -> None:
    pytest.importorskip("stable_baselines3")  # (the agents' and SB3's blocks need the "rl" extra)
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": "__readme__"}
    for k, block in enumerate(BLOCKS):
        exec(compile(block, f"README.md python block {k}", "exec"), namespace)  # noqa: S102
    printed = capsys.readouterr().out
    # The own-controller example's leaderboard, with its three rows.
    assert all(f"| {name} |" in printed for name in ("depth_p", "thesis", "reversal_aware")), printed
    # What the README says of it: it holds depth on LowSpeed and loses it on Nominal.
    header = next(line for line in printed.splitlines() if line.startswith("| controller |"))
    row = next(line for line in printed.splitlines() if line.startswith("| depth_p |"))
    columns = dict(zip((c.strip() for c in header.split("|")), (c.strip() for c in row.split("|"))))
    assert columns["Nominal"].startswith("0% ") and columns["LowSpeed"].startswith("100% "), row
