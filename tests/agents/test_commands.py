"""The command lines: subenv train forwards to subenv_agents.train; subenv_agents.evaluate compares."""

from __future__ import annotations

import json
import pickle
import re
import shutil
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")

from subenv.cli import main as subenv_main
from subenv_agents import shipped_models
from subenv_agents.evaluate import main as evaluate_main
from subenv_agents.policy import RUN_ID_ATTRIBUTE, load_agent
from subenv_agents.train import main as train_main

_SMALL = [
    "-n",
    "512",
    "--eval-freq",
    "0",
    "--save-freq",
    "0",
    "-q",
    "--no-progress",
    "-params",
    "n_envs:2",
    "n_steps:256",
    "batch_size:128",
    "n_epochs:1",
    "depth_integral:false",
]


def test_subenv_train_then_agents_evaluate(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    run = tmp_path / "run"
    assert (
        subenv_main(["train", "--algo", "ppo", "--env", "subenv/LowSpeed-v0", "--run-dir", str(run), *_SMALL])
        == 0
    )
    assert (run / "model.zip").is_file() and (run / "vecnormalize.pkl").is_file()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the model and its statistics carry the run's id
        assert (
            vars(load_agent(run).model)[RUN_ID_ATTRIBUTE]
            == vars(pickle.loads((run / "vecnormalize.pkl").read_bytes()))[RUN_ID_ATTRIBUTE]
        )
    out = tmp_path / "eval"
    assert (
        evaluate_main([f"mine={run}", "--suite", "tiny", "--episodes", "1", "--out", str(out), "--no-plots"])
        == 0
    )
    printed = capsys.readouterr().out
    assert "| mine |" in printed and "| reversal_aware |" in printed  # the agent next to the baseline
    assert (out / "leaderboard.md").is_file() and (out / "results.csv").read_text().count("\n") == 1 + 2 * 2
    with pytest.raises(SystemExit, match="no trained model"):
        evaluate_main([str(tmp_path / "missing"), "--suite", "tiny", "--out", str(tmp_path / "e2")])
    with pytest.raises(SystemExit, match="exists"):
        evaluate_main([str(run), "--suite", "tiny", "--episodes", "1", "--out", str(out), "--no-plots"])


def test_n_is_rounded_up_to_whole_rollouts_and_progress_shows_in_a_log(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """-n 700 with rollouts of 2 envs x 256 steps trains 1024 steps, says so, and counts them on stderr
    in lines a log file keeps (no terminal here); SB3's tables go to stdout whole."""
    run = tmp_path / "run"
    small = [arg for arg in _SMALL if arg not in ("-q", "--no-progress")]
    small[small.index("512")] = "700"
    assert train_main(["--algo", "ppo", "--env", "subenv/LowSpeed-v0", "--run-dir", str(run), *small]) == 0
    captured = capsys.readouterr()
    assert "training 1024 steps: 700 rounded up to whole iterations of 512 steps" in captured.err
    assert json.loads((run / "train.json").read_text())["timesteps"] == 1024
    lines = [line for line in captured.err.splitlines() if line.startswith("train: ")]
    assert lines[-1].startswith("train: 1024/1024 steps, 100%;") and len(lines) == 20, lines  # every 5%
    tables = [line for line in captured.out.splitlines() if line.startswith("|    total_timesteps")]
    assert [int(line.split("|")[2]) for line in tables] == [512, 1024]


# --- broken folders and bad input: one-line errors naming the file (issue 18, finding 7) -----------


def _copy_of_shipped(tmp_path: Path, name: str = "ppo") -> Path:
    folder = tmp_path / f"copy_of_{name}"
    shutil.copytree(shipped_models()[name], folder)
    return folder


def _truncate(path: Path, fraction: float) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: int(fraction * len(data))])


def _change_statistics(folder: Path, change: Callable[[Any], object]) -> None:
    """Load the folder's pickled statistics, change them, and pickle them back."""
    path = folder / "vecnormalize.pkl"
    stats = pickle.loads(path.read_bytes())
    change(stats)
    for key, value in (("venv", None), ("class_attributes", {}), ("returns", None)):
        vars(stats).setdefault(key, value)  # what VecNormalize.__getstate__ removes again
    path.write_bytes(pickle.dumps(stats))


_BREAKAGES = {
    "sac model in a ppo folder": (
        lambda f: shutil.copy(shipped_models()["sac"] / "model.zip", f / "model.zip"),
        r"model\.zip' cannot be loaded \(TypeError: .*\): must be a complete PPO model",
    ),
    "model cut at 30%": (
        lambda f: _truncate(f / "model.zip", 0.3),
        r"model\.zip' cannot be loaded \(AssertionError",
    ),
    "model cut at 90%": (lambda f: _truncate(f / "model.zip", 0.9), r"model\.zip' cannot be loaded"),
    "config not YAML": (
        lambda f: (f / "config.yml").write_text("algo: ppo\nenv_id: [\n"),
        r"config\.yml' is not valid YAML: .* at line 3, column 1",
    ),
    "config in latin-1": (
        lambda f: (f / "config.yml").write_bytes(b"algo: ppo  # \xe9\n"),
        r"config\.yml' is not UTF-8 text \(byte 0xe9",
    ),
    "statistics cut": (
        lambda f: _truncate(f / "vecnormalize.pkl", 0.5),
        r"vecnormalize\.pkl' cannot be read \(UnpicklingError",
    ),
    "statistics with a variance below 0": (
        lambda f: _change_statistics(f, lambda stats: stats.obs_rms.var.__setitem__(0, -1.0)),
        r"vecnormalize\.pkl': obs_rms\.var=\[-1\.0, .*\] is invalid: must be finite and >= 0",
    ),
    "statistics with a NaN mean": (
        lambda f: _change_statistics(f, lambda stats: stats.obs_rms.mean.__setitem__(1, np.nan)),
        r"vecnormalize\.pkl': obs_rms\.mean=\[.*, nan, .*\] is invalid: must be finite",
    ),
    "statistics clipping at 0": (
        lambda f: _change_statistics(f, lambda stats: setattr(stats, "clip_obs", 0.0)),
        r"vecnormalize\.pkl': clip_obs=0\.0 is invalid: must be finite and > 0",
    ),
    "statistics of another model": (
        lambda f: shutil.copy(shipped_models()["sac"] / "vecnormalize.pkl", f / "vecnormalize.pkl"),
        r"vecnormalize\.pkl' holds the statistics of run [0-9a-f]+: must be those of the run",
    ),
}


@pytest.mark.parametrize("breakage", sorted(_BREAKAGES))
def test_a_broken_model_folder_is_named_in_one_line(tmp_path, breakage) -> None:  # type: ignore[no-untyped-def]
    folder = _copy_of_shipped(tmp_path)
    sac = shipped_models()["sac"]
    assert np.shape(load_agent(sac).obs_mean) == np.shape(
        load_agent(folder).obs_mean
    )  # the same shape: not enough
    damage, message = _BREAKAGES[breakage]
    damage(folder)
    with pytest.raises(SystemExit) as exc:
        evaluate_main(
            [str(folder), "--suite", "tiny", "--episodes", "1", "--out", str(tmp_path / "e"), "--no-plots"]
        )
    text = str(exc.value)
    assert re.search(r"subenv_agents\.evaluate: '" + re.escape(str(folder)) + "/" + message, text), text
    assert "\n" not in text
    assert not (tmp_path / "e").exists()


def test_statistics_saved_without_a_run_id_load_with_a_warning(tmp_path) -> None:  # type: ignore[no-untyped-def]
    folder = _copy_of_shipped(tmp_path)
    _change_statistics(
        folder, lambda stats: vars(stats).pop(RUN_ID_ATTRIBUTE)
    )  # as older versions saved them
    with pytest.warns(UserWarning, match=r"saved without a run id .*cannot be checked"):
        agent = load_agent(folder)
    assert agent.obs_mean is not None


@pytest.mark.parametrize("name", sorted(shipped_models()))
def test_shipped_models_and_statistics_carry_one_run_id(name) -> None:  # type: ignore[no-untyped-def]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        agent = load_agent(shipped_models()[name])
    assert len(vars(agent.model)[RUN_ID_ATTRIBUTE]) == 32


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-conf", "BAD_YAML"], r"'.*bad\.yml' is not valid YAML: .* at line 2, column 1"),
        (["-params", "n_steps:["], r"--hyperparams 'n_steps:\[' is invalid: the value must be YAML \(.*\)"),
        (
            ["-params", "n_envs:2", "n_steps:-5"],
            r"PPO refused the hyperparameters \{.*'n_steps': -5.*\}: .*n_steps=-5",
        ),
        (
            ["--env", "CartPole-v1"],
            r"env_id='CartPole-v1' is not registered by subenv: must be one of \['subenv/",
        ),
    ],
)
def test_train_refuses_bad_input_in_one_line_and_leaves_no_folder(tmp_path, args, message) -> None:  # type: ignore[no-untyped-def]
    bad = tmp_path / "bad.yml"
    bad.write_text("a: [\n")
    logs = tmp_path / "logs"
    args = [str(bad) if a == "BAD_YAML" else a for a in args]
    with pytest.raises(SystemExit) as exc:
        train_main(
            [
                "--algo",
                "ppo",
                "-f",
                str(logs),
                "-n",
                "512",
                "--eval-freq",
                "0",
                "--save-freq",
                "0",
                "-q",
                "--no-progress",
                *args,
            ]
        )
    text = str(exc.value)
    assert re.search(r"^subenv_agents\.train: " + message, text), text
    assert "\n" not in text
    assert not logs.exists()  # not even an empty logs/ppo/
