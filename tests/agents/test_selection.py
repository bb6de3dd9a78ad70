"""Model selection on validation episodes: the saved policy is the one that scored best, and it says so."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")

from subenv.evaluation import DEFAULT_SEED
from subenv_agents.config import load_config
from subenv_agents.policy import load_agent
from subenv_agents.selection import (
    SELECTED_DIR,
    SELECTION_SCENARIOS,
    VALIDATION_SEED,
    SelectionCallback,
    validation_score,
)
from subenv_agents.train import train

_SMALL = {
    "n_timesteps": 2048,
    "n_envs": 4,
    "n_steps": 128,
    "batch_size": 128,
    "n_epochs": 2,
    "policy_kwargs": {"net_arch": [8]},
    "depth_integral": {"time_constant_s": 50.0},
}


def test_validation_seeds_are_not_the_evaluation_seeds() -> None:
    # The default suites use DEFAULT_SEED + i for i < 100; shipped cards report on those.
    assert abs(VALIDATION_SEED - DEFAULT_SEED) >= 1000


def test_selected_policy_is_the_best_validated_one_and_reloads_to_its_score(tmp_path) -> None:  # type: ignore[no-untyped-def]
    config = load_config("ppo", "subenv/LowSpeed-v0", overrides=_SMALL)
    run = train(
        config,
        seed=5,
        run_dir=tmp_path / "run",
        eval_freq=0,
        save_freq=0,
        verbose=0,
        select_freq=512,
        select_episodes=2,
    )
    record = json.loads((run.run_dir / "selection.json").read_text())
    history = record["history"]
    # Every 512 steps (one check per 4-env step that crosses a multiple), and the final policy.
    assert [h["timestep"] for h in history] == [512, 1024, 1536, 2048]
    assert record["scenarios"] == list(SELECTION_SCENARIOS) and record["seed"] == VALIDATION_SEED
    best = max(history, key=lambda h: (h["success_rate"], -h["plane_rms_rad"]))
    assert record["best"] == best
    assert json.loads((run.run_dir / "train.json").read_text())["selection"]["best"] == best

    selected = load_agent(run.run_dir / SELECTED_DIR)  # a folder that loads on its own
    assert selected.config == config
    again = validation_score(selected, SELECTION_SCENARIOS, 2)
    assert again["success_rate"] == best["success_rate"]
    assert again["plane_rms_rad"] == pytest.approx(best["plane_rms_rad"], rel=1e-12)

    # A continued run validates the policy it starts from, then every 512 steps from there on.
    more = train(
        load_config("ppo", "subenv/LowSpeed-v0", overrides={**_SMALL, "n_timesteps": 1024}),
        seed=6,
        run_dir=tmp_path / "more",
        trained_agent=run.run_dir,
        eval_freq=0,
        save_freq=0,
        verbose=0,
        select_freq=512,
        select_episodes=2,
    )
    steps = [h["timestep"] for h in json.loads((more.run_dir / "selection.json").read_text())["history"]]
    assert steps == [2048, 2560, 3072]


def test_bad_selection_arguments_are_refused(tmp_path) -> None:  # type: ignore[no-untyped-def]
    config = load_config("ppo", "subenv/LowSpeed-v0")
    with pytest.raises(ValueError, match="freq=0"):
        SelectionCallback(config, tmp_path, freq=0)
    with pytest.raises(ValueError, match="episodes=-1"):
        SelectionCallback(config, tmp_path, freq=10, episodes=-1)
    with pytest.raises(ValueError, match="select_freq=-5"):
        train(config, run_dir=tmp_path / "x", select_freq=-5)
