"""The multi-seed reference results (subenv_agents.reference) on a local Ray instance, with a tiny budget:
PPO with two seeds of one iteration each, two evaluation episodes per scenario; beside them two ppo_jax
trials whose model folders are made here untrained (training one is the slow test's), evaluated by the
reference as its trials are."""

from __future__ import annotations

import csv
import json
import math
import shutil

import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")
pytest.importorskip("ray.tune", reason="the 'ray' extra is not installed")
pytest.importorskip("rliable", reason="the 'stats' extra is not installed")
pytest.importorskip("optax", reason="the 'jax-rl' extra is not installed")

import jax
from rliable import metrics

from subenv.evaluation import DEFAULT_SUITE, evaluate, get_suite
from subenv_agents import jax_ppo
from subenv_agents.controller import AgentController
from subenv_agents.policy import load_agent
from subenv_agents.records import score_record
from subenv_agents.reference import Plan, _evaluated, _jax_config, run_reference

_SMALL = {
    "n_envs": 2,
    "n_steps": 128,
    "batch_size": 128,
    "n_epochs": 1,
    "depth_integral": False,
    "policy_kwargs": {"net_arch": [16, 16]},
}
_JAX_SMALL = {
    "env_id": "subenv/Nominal-v0",
    "num_envs": 32,
    "num_steps": 16,
    "num_minibatches": 4,
    "update_epochs": 2,
    "hidden": (16, 16),
    "episodes": 8,
    "memory": 0,
}
PLAN = Plan(
    timesteps={"ppo": 256, "ppo_jax": 2 * 32 * 16},
    seeds=2,
    episodes=2,
    curve_points=2,
    curve_episodes=1,
    reps=200,
    overrides=_SMALL,
    jax_overrides=_JAX_SMALL,
)


def _finished_jax_trials(out, plan: Plan) -> None:  # type: ignore[no-untyped-def]
    """The plan's ppo_jax trials as finished ones: an untrained network in the first's model folder,
    evaluated as the reference evaluates its trials; the others its copies (the same network, the same
    evaluation: made once, for the suite's time)."""
    first, *others = [t for t in plan.trials() if t["algo"] == "ppo_jax"]
    config = _jax_config(first["timesteps"], 0, plan.jax_overrides)
    network = jax_ppo.init_network(jax.random.key(0), 8, 2, config.hidden)
    run_dir = jax_ppo.save(
        out / "trials" / first["name"], config, network, jax_ppo.RunningStats.empty((8,)), {}
    )
    record = _evaluated({**first, "timesteps_trained": 0, "train_time_s": 0.0}, run_dir, plan.episodes)
    for trial in others:
        shutil.copytree(run_dir, out / "trials" / trial["name"])
        (out / "trials" / trial["name"] / "evaluation.json").write_text(json.dumps({**record, **trial}))


def test_a_tiny_reference_run_gives_rliable_estimates_of_what_it_evaluated_and_resumes(
    local_ray, tmp_path
) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "reference"
    _finished_jax_trials(out, PLAN)
    summary = run_reference(out, PLAN, progress=False, baselines=["thesis"])
    scenarios = list(get_suite(DEFAULT_SUITE).scenarios)
    assert summary["scenarios"] == scenarios
    assert summary["runs"] == {"PPO": 2, "PPO_JAX": 2, "thesis": 1}
    assert summary["kinds"] == {"PPO": "multi-seed", "PPO_JAX": "multi-seed", "thesis": "baseline"}

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
    assert trial["benchmark"]["all"]["score"] == score_record(again)["again"]["all"]["score"]

    # The score column: several seeds' mean with an interval over the seeds, one run's own interval.
    for name in ("PPO", "PPO_JAX"):
        runs = [
            json.loads((out / "trials" / f"{name.lower()}-seed{k}" / "evaluation.json").read_text())[
                "benchmark"
            ]["all"]["score"]
            for k in range(2)
        ]
        mine = summary["benchmark_score"][name]
        assert mine["runs"] == runs and math.isclose(mine["score"], float(np.mean(runs)))
        assert min(runs) <= mine["ci"][0] <= mine["score"] <= mine["ci"][1] <= max(runs)
    thesis = summary["benchmark_score"]["thesis"]  # (one run: its interval over the episodes)
    assert thesis["runs"] == [thesis["score"]] and thesis["ci"][0] <= thesis["score"] <= thesis["ci"][1]
    assert (
        thesis["interval_over"] == "episodes"
        and summary["benchmark_score"]["PPO"]["interval_over"] == "seeds"
    )
    lines = (out / "reference.md").read_text().splitlines()
    table = [line.split(" | ") for line in lines if line.startswith("| ")][1:]  # (not the header)
    shown = {cells[0].strip("| *").split(" (")[0]: float(cells[2].split(" [")[0]) for cells in table}
    assert shown == {n: round(s["score"], 1) for n, s in summary["benchmark_score"].items()}
    assert list(shown.values()) == sorted(shown.values(), reverse=True)

    # The table's statistics are rliable's of the scores in scores.csv (runs x scenarios).
    with open(out / "scores.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 5 * len(scenarios)
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
    assert "| **PPO_JAX** | 2 |" in (out / "reference.md").read_text()
    assert list(summary["learning_curves"]) == ["PPO"]  # (ppo_jax trials have no validation curve)
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
        ({"jax_overrides": {"seed": 3}}, r"jax_overrides\['seed'\] is invalid: the plan sets it"),
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


def test_every_shipped_agent_is_labelled_as_one() -> None:
    """The rows of the shipped agents, SB3's and the JAX PPO's, say they are one selected run."""
    from subenv_agents import shipped_models
    from subenv_agents.reference import _shipped_names

    assert _shipped_names() == {*shipped_models(), "ppo_jax"} and {"ppo", "sac"} <= _shipped_names()


def test_the_default_plan_trains_the_jax_ppo_as_the_shipped_agent_was_trained() -> None:
    shipped, _, _ = jax_ppo.load(jax_ppo.shipped_folder())
    assert Plan().timesteps["ppo_jax"] == jax_ppo.PPOConfig().total_timesteps == shipped.total_timesteps
    assert Plan().jax_overrides == {}


def test_a_bad_jax_setting_is_refused_before_anything_runs(tmp_path) -> None:  # type: ignore[no-untyped-def]
    for overrides, match in (({"learning_rate": 1e-3}, "learning_rate"), ({"num_envs": 0}, "num_envs")):
        with pytest.raises(ValueError, match=match):
            run_reference(
                tmp_path / "bad", Plan(timesteps={"ppo_jax": 1024}, jax_overrides=overrides), progress=False
            )
        assert not (tmp_path / "bad").exists()


@pytest.mark.slow
def test_a_ppo_jax_trial_trains_its_model_folder_and_evaluates_its_final_policy(local_ray, tmp_path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "reference"
    plan = Plan(timesteps={"ppo_jax": 2 * 32 * 16}, seeds=1, episodes=1, reps=200, jax_overrides=_JAX_SMALL)
    summary = run_reference(out, plan, progress=False, baselines=["thesis"])
    config, _, _ = jax_ppo.load(out / "trials" / "ppo_jax-seed0")
    assert config.total_timesteps == 2 * 32 * 16 and config.seed == 0 and config.env_id == "subenv/Nominal-v0"
    trial = json.loads((out / "trials" / "ppo_jax-seed0" / "evaluation.json").read_text())
    assert trial["timesteps_trained"] == 2 * 32 * 16
    again = evaluate(
        [jax_ppo.JaxPPOController(out / "trials" / "ppo_jax-seed0", name="again")],
        DEFAULT_SUITE,
        1,
        progress=False,
        keep_trajectories=0,
    )
    assert trial["benchmark"]["all"]["score"] == score_record(again)["again"]["all"]["score"]
    assert summary["benchmark_score"]["PPO_JAX"]["runs"] == [trial["benchmark"]["all"]["score"]]


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
