"""PPO in one JAX program (subenv_agents.jax_ppo): it trains under one jit, saves and loads its model,
and its policy is a controller of subenv.evaluation, the shipped one included."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("optax", reason="the 'jax-rl' extra is not installed")

import gymnasium as gym
import jax
import jax.numpy as jnp

from subenv.evaluation import controller_names, evaluate, make_controller
from subenv_agents import jax_ppo
from subenv_agents.jax_ppo import (
    JaxPPOController,
    PPOConfig,
    RunningStats,
    load,
    make_train,
    policy_mean,
    save,
)
from subenv_agents.records import REVERSAL_SCENARIOS, evaluation_record

TINY = PPOConfig(
    env_id="subenv/Nominal-v0",
    total_timesteps=2 * 32 * 16,
    num_envs=32,
    num_steps=16,
    num_minibatches=4,
    update_epochs=2,
    hidden=(16, 16),
    episodes=8,
    env_kwargs={"control": "independent"},
)


@pytest.fixture(scope="module")
def trained():
    """Two updates of a tiny training, as one jit, with the progress callback."""
    seen = []
    train, env = make_train(TINY, lambda index, metrics: seen.append((int(index), float(metrics.reward))))
    state, metrics = jax.block_until_ready(jax.jit(train)(jax.random.key(0)))
    return state, metrics, seen, env


def test_training_runs_as_one_program_and_reports_every_update(trained):
    state, metrics, seen, env = trained
    assert [index for index, _ in seen] == [0, 1] and TINY.num_updates == 2
    assert metrics.reward.shape == (2,) and np.all(np.isfinite(np.asarray(metrics.reward)))
    leaves = jax.tree_util.tree_leaves(state.network)
    assert all(np.all(np.isfinite(np.asarray(leaf))) for leaf in leaves)
    first = jax_ppo.init_network(jax.random.split(jax.random.key(0), 3)[1], 8, 2, TINY.hidden)
    assert any(
        not np.array_equal(np.asarray(a), np.asarray(b))  # (the updates changed the network)
        for a, b in zip(jax.tree_util.tree_leaves(first), leaves)
    )
    # The observation statistics are those of everything observed: the resets, then every step.
    assert float(state.obs_stats.count) == pytest.approx(32 * (1 + 2 * 16), rel=1e-6)
    assert env.num_actions == 2


def test_a_saved_model_loads_and_acts_as_the_policy_mean(trained, tmp_path):
    state, *_ = trained
    folder = save(tmp_path / "model", TINY, state.network, state.obs_stats, {"env_steps": 1024})
    config, network, _ = load(folder)
    assert config == TINY
    for a, b in zip(jax.tree_util.tree_leaves(network), jax.tree_util.tree_leaves(state.network)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    controller = JaxPPOController(folder)
    assert (controller.name, controller.control, controller.alpha) == ("model", "independent", 0.0)
    env = gym.make("subenv/Nominal-v0", control="independent")
    obs, info = env.reset(seed=1)
    controller.reset_batch([info, info, info], env.unwrapped.vehicle)
    batch = np.stack([obs, obs * 0.5, obs * 100.0])
    actions = controller.act_batch(batch)
    expected = np.clip(np.asarray(policy_mean(state.network, jnp.asarray(batch), state.obs_stats)), -1, 1)
    np.testing.assert_allclose(actions, expected, rtol=1e-6, atol=1e-7)
    assert actions.shape == (3, 2) and actions.dtype == np.float32 and np.all(np.abs(actions) <= 1.0)
    with pytest.raises(ValueError, match="observations"):
        controller.act_batch(batch[:2])


def test_save_never_replaces_what_it_did_not_write(trained, tmp_path):
    state, *_ = trained
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "notes.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="refusing to replace it"):
        save(tmp_path / "taken", TINY, state.network, state.obs_stats, {}, overwrite=True)
    assert (tmp_path / "taken" / "notes.txt").read_text() == "mine"
    with pytest.raises(FileNotFoundError, match="not a jax-ppo model folder"):
        load(tmp_path / "taken")


@pytest.mark.parametrize(
    "change, match",
    [
        ({"num_envs": 0}, "num_envs"),
        ({"gamma": 1.5}, "gamma"),
        ({"num_minibatches": 7}, "num_minibatches"),
        ({"total_timesteps": 10}, "total_timesteps"),
        ({"hidden": ()}, "hidden"),
        ({"lr": -1.0}, "lr"),
        ({"env_id": "CartPole-v1"}, "env_id"),
        ({"env_kwargs": {"control": "sideways"}}, "control"),
        ({"env_kwargs": {"colour": "red"}}, "env_kwargs"),
    ],
)
def test_bad_settings_are_refused_by_name(change, match):
    with pytest.raises(ValueError, match=match):
        PPOConfig(**{**TINY.__dict__, **change})


def test_running_statistics_are_the_datas():
    data = np.random.default_rng(0).normal(3.0, 2.0, (1000, 2))
    stats = RunningStats.empty((2,))
    for chunk in np.split(data, 10):
        stats = stats.update(jnp.asarray(chunk))
    np.testing.assert_allclose(np.asarray(stats.mean), data.mean(axis=0), rtol=1e-6)
    np.testing.assert_allclose(np.asarray(stats.var), data.var(axis=0), rtol=1e-4)


def test_the_shipped_model_is_a_registered_controller_that_evaluate_runs():
    assert "ppo_jax" in controller_names()
    controller = make_controller("ppo_jax")
    assert controller.name == "ppo_jax"
    results = evaluate([controller], ["Nominal"], episodes=2, progress=False)
    assert len(results) == 2 and all(r.controller == "ppo_jax" for r in results)


def test_the_shipped_models_card_is_its_record_and_its_numbers_reproduce():
    folder = jax_ppo.shipped_folder()
    record = json.loads((folder / "train.json").read_text())
    stored = json.loads((folder / "evaluation.json").read_text())
    card = (folder / "MODEL_CARD.md").read_text()
    assert record["env_steps"] > 0 and record["wall_time_s"] > 0 and f"`{record['command']}`" in card
    assert f"**{'met' if stored['target_met'] else 'not met'}**" in card and stored["target"] in card
    again = evaluation_record(
        evaluate(
            [make_controller("ppo_jax")],
            list(REVERSAL_SCENARIOS),
            episodes=stored["episodes"],
            progress=False,
        )
    )
    for scenario in REVERSAL_SCENARIOS:
        ours, theirs = again["ppo_jax"][scenario], stored["suite"]["ppo_jax"][scenario]
        assert ours["success_rate"] == theirs["success_rate"], scenario
        assert ours["plane_rms_rad"] == pytest.approx(theirs["plane_rms_rad"], rel=1e-6), scenario


def test_a_model_trained_on_other_dynamics_is_refused_as_a_controller(trained):
    state, *_ = trained
    config = PPOConfig(**{**TINY.__dict__, "env_kwargs": {"control": "independent", "max_pitch_rad": 0.3}})
    with pytest.raises(ValueError, match=r"env_kwargs \['max_pitch_rad'\]"):
        JaxPPOController.of(config, state.network, state.obs_stats, "other")
