"""The command lines: subenv train forwards to agents.train; agents.evaluate compares with the baselines."""

from __future__ import annotations

import re

import pytest

pytest.importorskip("stable_baselines3")

from agents.evaluate import main as evaluate_main
from agents.train import main as train_main
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


# --- bad input: one-line errors naming the file or parameter (issue 18, finding 7) ----------------

@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-conf", "BAD_YAML"], r"'.*bad\.yml' is not valid YAML: .* at line 2, column 1"),
        (["-params", "n_steps:["], r"--hyperparams 'n_steps:\[' is invalid: the value must be YAML \(.*\)"),
        (["-params", "n_envs:2", "n_steps:-5"], r"PPO refused the hyperparameters \{.*'n_steps': -5.*\}: .*n_steps=-5"),
        (["--env", "CartPole-v1"], r"env_id='CartPole-v1' is not registered by subenv: must be one of \['subenv/"),
    ],
)
def test_train_refuses_bad_input_in_one_line_and_leaves_no_folder(tmp_path, args, message) -> None:  # type: ignore[no-untyped-def]
    bad = tmp_path / "bad.yml"
    bad.write_text("a: [\n")
    logs = tmp_path / "logs"
    args = [str(bad) if a == "BAD_YAML" else a for a in args]
    with pytest.raises(SystemExit) as exc:
        train_main(["--algo", "ppo", "-f", str(logs), "-n", "512", "--eval-freq", "0", "--save-freq", "0", "-q",
                    "--no-progress", *args])
    text = str(exc.value)
    assert re.search(r"^agents\.train: " + message, text), text
    assert "\n" not in text
    assert not logs.exists()  # not even an empty logs/ppo/
