"""The multi-seed reference results (subenv_agents.reference) on a local Ray instance, with a tiny budget:
PPO with two seeds of one iteration each, two evaluation episodes per scenario."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")
pytest.importorskip("ray.tune", reason="the 'ray' extra is not installed")
pytest.importorskip("rliable", reason="the 'stats' extra is not installed")

from rliable import metrics

from subenv.evaluation import DEFAULT_SUITE, evaluate, get_suite
from subenv_agents.controller import AgentController
from subenv_agents.policy import load_agent
from subenv_agents.reference import Plan, run_reference

_SMALL = {
    "n_envs": 2,
    "n_steps": 128,
    "batch_size": 128,
    "n_epochs": 1,
    "depth_integral": False,
    "policy_kwargs": {"net_arch": [16, 16]},
}
PLAN = Plan(
    timesteps={"ppo": 256}, seeds=2, episodes=2, curve_points=2, curve_episodes=1, reps=200, overrides=_SMALL
)


def test_a_tiny_reference_run_gives_rliable_estimates_of_what_it_evaluated_and_resumes(
    local_ray, tmp_path
) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "reference"
    summary = run_reference(out, PLAN, progress=False, baselines=["thesis"])
    scenarios = list(get_suite(DEFAULT_SUITE).scenarios)
    assert summary["scenarios"] == scenarios and summary["runs"] == {"PPO": 2, "thesis": 1}

    # A trial's scores are its final policy's on the default suite's episodes: evaluated again here.
    trial = json.loads((out / "trials" / "ppo-seed1" / "evaluation.json").read_text())
    again = evaluate(
        [AgentController(load_agent(out / "trials" / "ppo-seed1"), name="again")],
        DEFAULT_SUITE,
        2,
        progress=False,
        keep_trajectories=0,
    )
    for s in scenarios:
        rows = [r for r in again if r.scenario == s and r.winnable is not False]
        assert trial["scenarios"][s]["winnable"] == len(rows)
        assert trial["scenarios"][s]["winnable_successes"] == sum(r.metrics.success for r in rows)

    # The table's statistics are rliable's of the scores in scores.csv (runs x scenarios).
    with open(out / "scores.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 3 * len(scenarios)
    ppo = np.array(
        [
            [
                float(
                    next(
                        r["score"]
                        for r in rows
                        if r["name"] == "PPO" and r["seed"] == str(k) and r["scenario"] == s
                    )
                )
                for s in scenarios
            ]
            for k in range(2)
        ]
    )
    assert ppo[1].tolist() == [trial["scenarios"][s]["score"] for s in scenarios]
    aggregate = summary["aggregate"]["PPO"]
    assert math.isclose(aggregate["iqm"], metrics.aggregate_iqm(ppo))
    assert math.isclose(aggregate["mean"], float(ppo.mean()))
    assert aggregate["iqm_ci"][0] <= aggregate["iqm"] <= aggregate["iqm_ci"][1]
    for j, s in enumerate(scenarios):
        point, low, high = summary["per_scenario"][s]["PPO"]
        assert math.isclose(point, ppo[:, j].mean()) and low <= point <= high
    curve = summary["learning_curves"]["PPO"]
    history = [
        json.loads((out / "trials" / f"ppo-seed{k}" / "selection.json").read_text())["history"]
        for k in range(2)
    ]
    assert curve["timesteps"] == [h["timestep"] for h in history[0]]
    assert np.allclose(curve["mean"], np.mean([[h["success_rate"] for h in hs] for hs in history], axis=0))
    assert "| **PPO** | 2 |" in (out / "reference.md").read_text()
    for figure in ("learning_curves.png", "performance_profiles.png"):
        assert (out / figure).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    # Run again after losing one trial's result: that trial alone is trained again. The other's evaluation,
    # made as if on another suite, is made again on this one from its saved policy (not trained again).
    kept = (out / "trials" / "ppo-seed0" / "model.zip").stat().st_mtime_ns
    (out / "trials" / "ppo-seed1" / "evaluation.json").unlink()
    first = json.loads((out / "trials" / "ppo-seed0" / "evaluation.json").read_text())
    stale = {**first, "scenarios": {"Retired-v0": first["scenarios"][scenarios[0]]}}
    (out / "trials" / "ppo-seed0" / "evaluation.json").write_text(json.dumps(stale))
    run_reference(out, PLAN, progress=False, baselines=["thesis"])
    assert (out / "trials" / "ppo-seed0" / "model.zip").stat().st_mtime_ns == kept
    assert (
        json.loads((out / "trials" / "ppo-seed0" / "evaluation.json").read_text())["scenarios"]
        == first["scenarios"]
    )
    assert (
        json.loads((out / "trials" / "ppo-seed1" / "evaluation.json").read_text())["scenarios"]
        == trial["scenarios"]
    )


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"timesteps": {"a2c": 100}}, r"timesteps\['a2c'\] is invalid: the algorithm must be one of"),
        ({"timesteps": {"ppo": 0}}, r"timesteps\['ppo'\]=0 is invalid: must be an integer >= 1"),
        ({"seeds": 0}, r"seeds=0 is invalid: must be an integer >= 1"),
        ({"reps": 10}, r"reps=10 is invalid: must be an integer >= 100"),
    ],
)
def test_a_bad_plan_is_refused(kwargs, match) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=match):
        Plan(**kwargs)


def test_a_bad_hyperparameter_is_refused_before_anything_runs(tmp_path) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match="learning_rat"):
        run_reference(
            tmp_path / "bad", Plan(timesteps={"ppo": 256}, overrides={"learning_rat": 1e-3}), progress=False
        )
    assert not (tmp_path / "bad").exists()


def test_without_an_extra_the_command_says_which_in_one_line_and_makes_nothing(monkeypatch, tmp_path) -> None:  # type: ignore[no-untyped-def]
    import subenv.extras
    from subenv_agents.reference import main

    real = subenv.extras.find_spec
    monkeypatch.setattr(subenv.extras, "find_spec", lambda name: None if name == "rliable" else real(name))
    with pytest.raises(
        SystemExit, match=r"^subenv_agents.reference: the 'stats' extra is needed .*subenv\[stats\]"
    ):
        main(["--out", str(tmp_path / "out")])
    assert not (tmp_path / "out").exists()
