"""The hyperparameter search on Ray Tune (a local instance with the machine's CPUs, started here), with a
tiny budget: two trials of a few hundred steps."""

from __future__ import annotations

import json
import math
import signal

import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")
pytest.importorskip("ray.tune", reason="the 'ray' extra is not installed")
pytest.importorskip("optuna", reason="the 'ray' extra is not installed")

from subenv_agents.tune import search

_SMALL = {
    "n_envs": 2,
    "n_steps": 256,
    "batch_size": 128,
    "n_epochs": 1,
    "depth_integral": False,
    "policy_kwargs": {"net_arch": [16, 16]},
}
SPACE = {"learning_rate": ("log", 1e-4, 1e-3), "gamma": ("choice", [0.99, 0.999])}


def test_a_tiny_search_trains_scores_and_keeps_every_trial(local_ray, tmp_path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "search"
    handler = signal.getsignal(signal.SIGINT)
    best = search(
        "ppo", "subenv/LowSpeed-v0", out, space=SPACE, samples=2, timesteps=512, episodes=2, overrides=_SMALL
    )
    record = json.loads((out / "best.json").read_text())
    trials = record["trials"]
    assert len(trials) == 2 and record["best"] == best
    for trial in trials:
        assert 1e-4 <= trial["values"]["learning_rate"] <= 1e-3 and trial["values"]["gamma"] in (0.99, 0.999)
        assert 0.0 <= trial["success_rate"] <= 1.0 and math.isfinite(trial["plane_rms_rad"])
        assert (tmp_path / trial["run_dir"]).joinpath("model.zip").is_file() and trial["timesteps"] == 512
    assert best["success_rate"] == max(t["success_rate"] for t in trials)
    assert signal.getsignal(signal.SIGINT) is handler  # (Ray Tune's own handler does not outlive the search)
    with pytest.raises(FileExistsError, match="holds a finished search"):
        search("ppo", "subenv/LowSpeed-v0", out, space=SPACE, samples=1, timesteps=512, overrides=_SMALL)


@pytest.mark.parametrize(
    ("space", "match"),
    [
        (
            {"learning_rate": ("log", 0.0, 1e-3)},
            r"space\['learning_rate'\]=.* must be \('log', low, high\) with 0 < low",
        ),
        ({"gamma": ("pick", [0.9])}, r"must start with one of \['log', 'uniform', 'choice'\]"),
        ({"gamma": ("choice", [])}, r"must be \('choice', \[values\]\)"),
    ],
)
def test_a_bad_space_is_refused_before_anything_runs(space, match, tmp_path) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=match):
        search("ppo", "subenv/LowSpeed-v0", tmp_path / "bad", space=space, samples=1, timesteps=512)
    assert not (tmp_path / "bad").exists()
