"""The ``subenv`` command: the demonstration the README's main command runs."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from subenv.cli import main


def test_demo_prints_the_summary_and_writes_the_plot(tmp_path: Path, capsys):
    out = tmp_path / "figs" / "demo.png"
    assert main(["demo", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "u_cr = 0.5785 m/s = 1.8979 fps" in text
    rows = [line.split() for line in text.splitlines() if line.strip().startswith(("1.524", "0.450"))]
    assert len(rows) == 2
    design, low = rows
    assert abs(float(design[2])) < 0.01  # holds the ordered depth at 5 fps
    assert abs(float(low[2])) > 1.0  # loses it below the critical speed
    assert out.read_bytes().startswith(b"\x89PNG")
    assert [p.name for p in out.parent.iterdir()] == ["demo.png"]  # no temporary file left


def test_bad_option_is_a_clear_error(capsys):
    with pytest.raises(SystemExit, match=r"--low-speed=-1\.0 is invalid"):
        main(["demo", "--low-speed", "-1", "--no-plot"])


def test_list_names_every_id(capsys):
    assert main(["list"]) == 0
    text = capsys.readouterr().out
    assert "subenv/LowSpeed-v0" in text and "subenv/DivePlane-v0" in text


def test_analyze_writes_the_report_and_refuses_to_overwrite(tmp_path: Path, analysis_report):
    # `subenv analyze --out <folder>` into a folder that did not exist, once per session (tests/conftest.py).
    out = analysis_report.folder
    assert analysis_report.exit_code == 0
    text = analysis_report.printed
    assert "| quantity | thesis value | computed value | difference |" in text
    assert (out / "report.md").is_file() and len(list(out.glob("*.png"))) == 14
    with pytest.raises(SystemExit, match="exists; pass overwrite=True"):
        main(["analyze", "--out", str(out)])
    existing = tmp_path / "analysis"  # the shared report stays as it is: --force replaces a copy of it
    shutil.copytree(out, existing)
    assert main(["analyze", "--out", str(existing), "--force"]) == 0


def test_evaluate_end_to_end_on_the_tiny_suite(tmp_path: Path, capsys):
    out = tmp_path / "eval"
    assert main(["evaluate", "--suite", "tiny", "--episodes", "1", "--controllers", "thesis,reversal_aware",
                 "--out", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "| controller |" in text and "reversal_aware" in text and "thesis" in text
    assert (out / "results.csv").is_file() and (out / "leaderboard.md").is_file()
    with pytest.raises(SystemExit, match="exists"):
        main(["evaluate", "--suite", "tiny", "--episodes", "1", "--out", str(out), "--no-progress"])


def test_evaluate_rejects_unknown_names(tmp_path: Path):
    with pytest.raises(SystemExit, match=r"controller='pid' is unknown: must be one of \[") as error:
        main(["evaluate", "--controllers", "pid", "--out", str(tmp_path / "x"), "--no-progress"])
    assert all(f"'{name}'" in str(error.value) for name in ("thesis", "scheduled", "lqr", "reversal_aware"))
    with pytest.raises(SystemExit, match=r"suite|scenario"):
        main(["evaluate", "--suite", "Fastest", "--out", str(tmp_path / "y"), "--no-progress"])
    with pytest.raises(SystemExit, match="cannot import controller package 'nopkg'"):
        main(["evaluate", "--plugins", "nopkg", "--out", str(tmp_path / "z")])
