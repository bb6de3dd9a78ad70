"""The command lines: subenv train forwards to agents.train; agents.evaluate compares with the baselines."""

from __future__ import annotations

import pytest

pytest.importorskip("stable_baselines3")

from agents.evaluate import main as evaluate_main
from subenv.cli import main as subenv_main

_SMALL = ["-n", "512", "--eval-freq", "0", "--save-freq", "0", "-q", "--no-progress",
          "-params", "n_envs:2", "n_steps:256", "batch_size:128", "n_epochs:1", "depth_integral:false"]


def test_subenv_train_then_agents_evaluate(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    run = tmp_path / "run"
    assert subenv_main(["train", "--algo", "ppo", "--env", "subenv/LowSpeed-v0", "--run-dir", str(run), *_SMALL]) == 0
    assert (run / "model.zip").is_file() and (run / "vecnormalize.pkl").is_file()
    out = tmp_path / "eval"
    assert evaluate_main([f"mine={run}", "--suite", "tiny", "--episodes", "1", "--out", str(out), "--no-plots"]) == 0
    printed = capsys.readouterr().out
    assert "| mine |" in printed and "| reversal_aware |" in printed  # the agent next to the baseline
    assert (out / "leaderboard.md").is_file() and (out / "results.csv").read_text().count("\n") == 1 + 2 * 2
    with pytest.raises(SystemExit, match="no trained model"):
        evaluate_main([str(tmp_path / "missing"), "--suite", "tiny", "--out", str(tmp_path / "e2")])
    with pytest.raises(SystemExit, match="exists"):
        evaluate_main([str(run), "--suite", "tiny", "--episodes", "1", "--out", str(out), "--no-plots"])
