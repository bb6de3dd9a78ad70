"""PPO in one JAX program (subenv_agents.jax_ppo): it trains under one jit, saves and loads its model,
and its policy is a controller of subenv.evaluation, the shipped one included."""

from __future__ import annotations

import json
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

pytest.importorskip("optax", reason="the 'jax-rl' extra is not installed")

import gymnasium as gym
import jax
import jax.numpy as jnp

from subenv.evaluation import controller_names, evaluate, make_controller
from subenv_agents import jax_ppo
from subenv_agents.difficulty import table_difficulties
from subenv_agents.jax_ppo import (
    JaxPPOController,
    PPOConfig,
    Rollout,
    RunningStats,
    advantages,
    init_network,
    load,
    main,
    make_train,
    policy_mean,
    policy_step,
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
    memory=0,
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
        for a, b in zip(jax.tree_util.tree_leaves(first), leaves, strict=True)
    )
    # The observation statistics are those of everything observed: the resets, then every step.
    assert float(state.obs_stats.count) == pytest.approx(32 * (1 + 2 * 16), rel=1e-6)
    assert env.num_actions == 2
    # (Nominal's episodes last 400 steps: none of these 32 x 32 steps ended one by its time, so none was won)
    assert np.all(np.asarray(metrics.won) == 0) and np.all(
        np.asarray(metrics.won) <= np.asarray(metrics.episodes)
    )


def test_a_saved_model_loads_and_acts_as_the_policy_mean(trained, tmp_path):
    state, *_ = trained
    folder = save(tmp_path / "model", TINY, state.network, state.obs_stats, {"env_steps": 1024})
    config, network, _ = load(folder)
    assert config == TINY
    for a, b in zip(
        jax.tree_util.tree_leaves(network), jax.tree_util.tree_leaves(state.network), strict=True
    ):
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
        ({"env_kwargs": ["control"]}, "env_kwargs"),
        ({"hidden": (16, True)}, "hidden"),
        ({"hidden": 16}, "hidden"),
        ({"anneal_lr": "yes"}, "anneal_lr"),
        ({"env_id": ["subenv/Nominal-v0"]}, "env_id"),
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


def test_the_defaults_are_the_shipped_models_settings():
    """``python -m subenv_agents.jax_ppo --out DIR`` trains the shipped agent's settings (its command
    names them only because they were not yet the defaults when it was trained)."""
    shipped, _, _ = jax_ppo.load(jax_ppo.shipped_folder())
    assert PPOConfig() == shipped


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


# The other settings the shipped agent trains with, in one tiny training (one compiled program: 13 s from
# an empty cache): a memory, the depth-error integral, and the difficulty curriculum on BallastOffset's
# first 12 episodes, 2 of which cannot be won.
MEMORY = PPOConfig(
    **{
        **TINY.__dict__,
        "memory": 8,
        "depth_integral_s": 100.0,
        "env_id": "subenv/BallastOffset-v0",
        "episodes": 12,
        "num_envs": 128,
        "total_timesteps": 2 * 128 * 16,
        "curriculum": "difficulty",
    }
)


@pytest.fixture(scope="module")
def trained_memory():
    """Two updates of a tiny training of a policy with a memory and the depth-error integral, on the
    difficulty curriculum."""
    train, env = make_train(MEMORY)
    state, metrics = jax.block_until_ready(jax.jit(train)(jax.random.key(1)))
    return state, metrics, env


def _episode(controller, seed, steps):
    """The controller's actions over ``steps`` steps of Nominal's episode ``seed``, and its observations."""
    env = gym.make("subenv/Nominal-v0", control="independent")
    obs, info = env.reset(seed=seed)
    controller.reset(info, env.unwrapped.vehicle)
    observations, actions = [], []
    for _ in range(steps):
        observations.append(obs)
        actions.append(controller.act(obs))
        obs, *_ = env.step(actions[-1])
    return np.array(observations), np.array(actions)


def test_a_policy_with_memory_trains_and_acts_as_its_memory_and_integral_say(trained_memory, tmp_path):
    from subenv_agents.config import DepthIntegralConfig
    from subenv_agents.features import DepthIntegral

    state, metrics, _ = trained_memory
    assert state.memory.shape == (128, 8) and np.all(np.isfinite(np.asarray(metrics.reward)))
    first = init_network(jax.random.split(jax.random.key(1), 3)[1], 9, 2, MEMORY.hidden, memory=8)
    assert not np.array_equal(np.asarray(first["gru"]["wh"]), np.asarray(state.network["gru"]["wh"]))
    folder = save(tmp_path / "model", MEMORY, state.network, state.obs_stats, {"env_steps": 1024})
    config, network, stats = load(folder)
    assert config == MEMORY and config.observation[-1] == "depth_error_integral_ms"
    np.testing.assert_array_equal(np.asarray(network["gru"]["wi"]), np.asarray(state.network["gru"]["wi"]))
    controller = JaxPPOController(folder)
    observations, actions = _episode(controller, seed=1, steps=6)
    # By hand: the Stable-Baselines3 agents' integral (I_0 = 0, then advanced by each observation) and the
    # policy's memory, carried from step to step
    integral = DepthIntegral(1, 0.5, DepthIntegralConfig(time_constant_s=100.0))
    memory = jnp.zeros((1, 8))
    for k, obs in enumerate(observations):
        if k:
            integral.update(obs[None])
        observed = jnp.asarray(integral.append(obs[None], integral.value), dtype=jnp.float64)
        memory, mean = policy_step(network, stats, memory, observed)
        np.testing.assert_allclose(actions[k], np.clip(np.asarray(mean)[0], -1, 1), rtol=1e-5, atol=1e-6)
    # The memory is used: the last observation alone, at an episode's start, is acted on otherwise
    controller.reset_batch([{}], None)
    assert not np.allclose(controller.act(observations[-1]), actions[-1])


def test_a_policy_with_memory_keeps_each_rows_own_in_a_batch(trained_memory, tmp_path):
    state, _, _ = trained_memory
    controller = JaxPPOController.of(MEMORY, state.network, state.obs_stats, "memory")
    alone = [_episode(controller, seed, steps=5) for seed in (1, 2)]
    controller.reset_batch([{}, {}], None)
    together = [controller.act_batch(np.stack([alone[0][0][k], alone[1][0][k]])) for k in range(5)]
    for row in (0, 1):
        np.testing.assert_allclose(np.array(together)[:, row], alone[row][1], rtol=1e-5, atol=1e-6)


def test_a_model_trained_for_another_observation_space_is_refused_naming_both(trained, tmp_path, monkeypatch):
    state, *_ = trained
    folder = save(tmp_path / "model", TINY, state.network, state.obs_stats, {"env_steps": 1024})
    names = list(jax_ppo.OBSERVATION_NAMES)
    monkeypatch.setattr(
        jax_ppo, "OBSERVATION_NAMES", (*names, "salinity_psu")
    )  # (the environment observes more)
    trained_for = re.escape(f"trained for the observation space {names} (8 components)")
    observes = re.escape(
        f"subenv/Nominal-v0 with its settings observes {[*names, 'salinity_psu']} (9 components)"
    )
    with pytest.raises(ValueError, match=rf"config\.json: the model was {trained_for}, and {observes}"):
        load(folder)
    with pytest.raises(ValueError, match="salinity_psu"):
        JaxPPOController(folder)
    monkeypatch.undo()
    settings_ = json.loads((folder / "config.json").read_text())
    settings_["depth_integral_s"] = 100.0  # (it did not observe the integral the settings now name)
    (folder / "config.json").write_text(json.dumps(settings_))
    with pytest.raises(ValueError, match=r"observes \[.*'depth_error_integral_ms'\] \(9 components\)"):
        load(folder)


def test_the_difficulty_curriculum_resets_only_to_episodes_that_can_be_won(trained_memory):
    winnable = [d.winnable for d in table_difficulties(MEMORY.env_id, MEMORY.env_kwargs, range(12))]
    assert winnable.count(False) == 2  # (of 128 uniform resets, all winnable: (10/12)^128 = 7e-11)
    state, _, env = trained_memory
    table = np.asarray(env.default_params.table.episode.params)
    drawn = np.asarray(state.env_state.episode.params)
    rows = [int(np.flatnonzero(np.all(table == row, axis=1))[0]) for row in drawn]
    assert all(winnable[row] for row in rows) and len(set(rows)) > 5


def test_the_command_refuses_an_output_folder_it_did_not_write_in_one_line(tmp_path, capsys):
    """It raised FileExistsError with a traceback (check_output_dir's), not argparse's one-line error."""
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "notes.txt").write_text("mine")
    with pytest.raises(SystemExit) as exited:
        main(["--out", str(tmp_path / "taken"), "--total-timesteps", "1024", "--num-envs", "16"])
    assert exited.value.code == 2
    assert (
        "output folder" in capsys.readouterr().err
        and (tmp_path / "taken" / "notes.txt").read_text() == "mine"
    )


def test_the_command_writes_into_the_next_free_run_folder_by_default(tmp_path, monkeypatch, capsys):
    """Without --out: results/agents/ppo_jax/<env>_<k> (subenv train's layout), k the first free."""
    written = []
    monkeypatch.setattr(jax_ppo, "train_model", lambda config, out, *a, **k: written.append((config, out)))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results" / "agents" / "ppo_jax" / "subenv-Mixed-v0_1").mkdir(parents=True)
    assert main(["--total-timesteps", "1024", "--num-envs", "16"]) == 0
    assert written[0][1] == str(Path("results", "agents", "ppo_jax", "subenv-Mixed-v0_2"))
    assert written[0][0] == PPOConfig(total_timesteps=1024, num_envs=16)  # (the defaults otherwise)
    assert capsys.readouterr().out.strip() == f"wrote {written[0][1]}"


def _report(path, settings):
    """A report.json of benchmarks/jax_ppo.py report with one variant of ``settings``, seeds 0 to 2."""
    variant = {
        "settings": settings,
        "runs": 3,
        "seeds": [0, 1, 2],
        "episodes": 50,
        "score": [968.1, 930.4, 951.0],
        "score_mean": 949.8,
        "score_mean_ci": [930.4, 968.1],
        "hard_score": [446.9, 401.2, 420.0],
        "hard_score_mean": 422.7,
        "hard_score_mean_ci": [401.2, 446.9],
        "ballast_wins": ["37/47", "30/47", "35/47"],
        "ballast_median_wins": 35.0,
        "iqm": 0.987,
        "iqm_ci": [0.95, 1.0],
    }
    path.write_text(json.dumps({"variants": {"other": {"settings": {}}, "tiny": variant}}))
    return path


def test_the_card_states_the_seed_spread_of_its_settings_and_refuses_another_report(tmp_path):
    mine = json.loads(json.dumps({**TINY.__dict__, "hidden": list(TINY.hidden)}))
    mine.pop("seed")
    report = _report(tmp_path / "report.json", mine)
    section = jax_ppo.seed_spread(TINY, report)
    assert "| 0 (this model) | 968 | 447 | 37/47 |" in section and "| 1 | 930 | 401 | 30/47 |" in section
    assert "| mean [95% CI] | 950 [930, 968] | 423 [401, 447] | median 35 |" in section
    assert "IQM over seeds x scenarios: 98.7 [95.0, 100.0]" in section
    with pytest.raises(
        ValueError, match=r"no variant with these settings but the seed: .*\['other', 'tiny'\]"
    ):
        jax_ppo.seed_spread(PPOConfig(**{**TINY.__dict__, "lr": 1e-3}), report)
    (tmp_path / "damaged.json").write_text("{")
    with pytest.raises(ValueError, match=r"damaged\.json' is not a report of benchmarks/jax_ppo\.py"):
        jax_ppo.seed_spread(TINY, tmp_path / "damaged.json")


def test_the_command_refuses_a_seed_spread_of_other_settings_before_it_trains(tmp_path, capsys):
    report = _report(tmp_path / "report.json", {"env_id": "subenv/Nominal-v0"})
    with pytest.raises(SystemExit) as exited:
        main(["--out", str(tmp_path / "model"), "--seed-spread", str(report)])
    assert exited.value.code == 2 and "holds no variant with these settings" in capsys.readouterr().err
    assert not (tmp_path / "model").exists()


def test_a_truncated_episode_bootstraps_from_its_final_observations_value():
    """Three steps of one environment: the first goes on, the second is truncated (the third is a new
    episode's), the third terminated. Each bootstraps from where it led: the next step's value, the
    final observation's value (gymnax 1.0's info["final_observation"]; before, the value of the state
    the truncated step started from), nothing."""
    column = lambda *values: jnp.asarray(values, dtype=jnp.float32)[:, None]  # noqa: E731 (a table's column)
    rollout = Rollout(
        obs=jnp.zeros((3, 1, 8)),
        first=jnp.asarray([[True], [False], [True]]),
        action=jnp.zeros((3, 1, 2)),
        log_prob=column(0.0, 0.0, 0.0),
        value=column(1.0, 2.0, 3.0),
        reward=column(0.5, 0.25, 0.125),
        terminated=jnp.asarray([[False], [False], [True]]),
        done=jnp.asarray([[False], [True], [True]]),
        final_value=column(9.0, 7.0, 5.0),
    )
    gamma, lam = 0.9, 0.8
    adv, target = advantages(rollout, jnp.asarray([4.0], dtype=jnp.float32), gamma, lam)
    third = 0.125 - 3.0
    second = 0.25 + gamma * 7.0 - 2.0  # (the next episode's advantage does not run on into it)
    first = 0.5 + gamma * 2.0 - 1.0 + gamma * lam * second
    np.testing.assert_allclose(np.asarray(adv)[:, 0], [first, second, third], rtol=1e-6)
    np.testing.assert_allclose(np.asarray(target)[:, 0], [first + 1.0, second + 2.0, third + 3.0], rtol=1e-6)


# --- damaged model folders --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def model_folder(tmp_path_factory):
    """A model folder of TINY's network (not trained: what load reads is the same)."""
    network = init_network(jax.random.key(0), 8, 2, TINY.hidden)
    stats = RunningStats.empty((8,)).update(jnp.asarray(np.random.default_rng(0).normal(size=(64, 8))))
    return save(tmp_path_factory.mktemp("models") / "tiny", TINY, network, stats, {"env_steps": 0})


def _arrays(folder):
    with np.load(folder / "network.npz") as data:
        return {name: data[name] for name in data.files}


def _damage(folder, kind, *args):
    """Change one file of a model folder: ``kind`` is "truncate" (file, fraction kept), "flip" (file,
    position as a fraction, xor mask), "array" (name, new array) or "setting" (name, new JSON value)."""
    if kind in ("truncate", "flip"):
        path = folder / args[0]
        data = bytearray(path.read_bytes())
        if not data:
            return
        at = min(int(args[1] * len(data)), len(data) - 1)
        path.write_bytes(
            bytes(data[:at])
            if kind == "truncate"
            else bytes(data[:at] + bytes([data[at] ^ args[2]]) + data[at + 1 :])
        )
    elif kind == "array":
        arrays = _arrays(folder)
        arrays[args[0]] = args[1]
        np.savez(folder / "network.npz", **arrays)
    elif kind == "setting":
        settings_ = json.loads((folder / "config.json").read_text())
        settings_[args[0]] = args[1]
        (folder / "config.json").write_text(json.dumps(settings_))


DAMAGE = {
    "truncated network.npz": (
        ("truncate", "network.npz", 0.5),
        r"network\.npz does not read as np.savez's arrays",
    ),
    "truncated config.json": (("truncate", "config.json", 0.5), r"config\.json is not a JSON file"),
    "truncated train.json": (("truncate", "train.json", 0.5), r"train\.json is not a JSON file"),
    "a layer more": (
        ("setting", "hidden", [16, 16, 16]),
        r"network\.npz does not hold the network config\.json describes: hidden=\[16, 16, 16\], 2 action "
        r"components: it lacks \['actor/3/b', 'actor/3/w', 'critic/3/b', 'critic/3/w'\]",
    ),
    "a weight's shape": (
        ("array", "actor/1/w", np.zeros((16, 15), np.float32)),
        r"network\.npz: actor/1/w has shape \(16, 15\): must have shape \(16, 16\)",
    ),
    "another control": (
        ("setting", "env_kwargs", {}),
        r"network\.npz: log_std has shape \(2,\): must have shape \(1,\)",
    ),
    "a zero variance": (
        ("array", "obs_var", np.r_[np.ones(7), 0.0]),
        r"network\.npz: obs_var=\[1\.0, .*, 0\.0\] is invalid: must be > 0",
    ),
    "an infinite mean": (
        ("array", "obs_mean", np.r_[np.inf, np.zeros(7)]),
        r"network\.npz: obs_mean has 1 NaN or infinite",
    ),
    "NaN weights": (
        ("array", "critic/2/w", np.full((16, 1), np.nan, np.float32)),
        r"network\.npz: critic/2/w has 16 NaN or infinite",
    ),
    "weights beyond float32": (
        ("array", "actor/0/w", np.full((8, 16), 1e300)),
        r"network\.npz: actor/0/w has 128 NaN or infinite values \(as float32\)",
    ),
    "weights that overflow": (
        ("array", "actor/1/w", np.full((16, 16), 3e37, np.float32)),
        r"network\.npz: actor/1/w and actor/1/b are invalid: .* beyond float32's range",
    ),
    "integer weights": (
        ("array", "log_std", np.zeros(2, np.int64)),
        r"network\.npz: log_std has dtype int64: must be floating point",
    ),
    "an unknown setting": (
        ("setting", "colour", "red"),
        r"config\.json is invalid: unknown settings \['colour'\]",
    ),
    "a setting PPOConfig refuses": (
        ("setting", "gamma", "high"),
        r"config\.json is invalid: gamma='high' is invalid",
    ),
}


@pytest.mark.parametrize("name", list(DAMAGE))
def test_a_damaged_model_folder_is_refused_naming_the_file_and_field(model_folder, tmp_path, name):
    """Issue 34: a truncated network.npz gave BadZipFile without the file's name, a truncated config.json
    a bare JSONDecodeError, hidden=[64, 64, 64] a KeyError; wrong shapes loaded and failed in dot_general,
    obs_var=0 and obs_mean=inf loaded and ran, NaN weights failed late."""
    folder = Path(shutil.copytree(model_folder, tmp_path / "model"))
    damage, match = DAMAGE[name]
    _damage(folder, *damage)
    with pytest.raises(ValueError, match=match):
        load(folder)
    with pytest.raises(ValueError, match=match):
        JaxPPOController(folder)


@pytest.fixture(scope="module")
def memory_folder(tmp_path_factory):
    """A model folder of MEMORY's network: a GRU of 8 units, the integral observed (not trained)."""
    network = init_network(jax.random.key(0), 9, 2, MEMORY.hidden, memory=8)
    stats = RunningStats.empty((9,)).update(jnp.asarray(np.random.default_rng(0).normal(size=(64, 9))))
    return save(tmp_path_factory.mktemp("models") / "memory", MEMORY, network, stats, {"env_steps": 0})


MEMORY_DAMAGE = {
    "settings without the memory": (
        ("setting", "memory", 0),
        r"network\.npz does not hold the network config\.json describes: hidden=\[16, 16\], 2 action "
        r"components: unknown \['embed/b', 'embed/w', 'gru/bhn', 'gru/bi', 'gru/wh', 'gru/wi'\]",
    ),
    "a memory of another width": (
        ("setting", "memory", 4),
        r"network\.npz: actor/0/w has shape \(17, 16\): must have shape \(13, 16\)",
    ),
    "a GRU weight's shape": (
        ("array", "gru/wh", np.zeros((8, 16), np.float32)),
        r"network\.npz: gru/wh has shape \(8, 16\): must have shape \(8, 24\)",
    ),
    "NaN in the GRU": (
        ("array", "gru/bhn", np.full(8, np.nan, np.float32)),
        r"network\.npz: gru/bhn has 8 NaN or infinite",
    ),
    "GRU weights that overflow": (
        ("array", "gru/wi", np.full((8, 24), 5e37, np.float32)),  # (8 x 5e37 > 3.4e38)
        r"network\.npz: gru/wi and gru/wh and gru/bi and gru/bhn are invalid: .* beyond float32's range",
    ),
    "an embedding that overflows": (
        ("array", "embed/w", np.full((9, 8), 1e37, np.float32)),  # (9 x 10 x 1e37 > 3.4e38)
        r"network\.npz: embed/w and embed/b are invalid: .* beyond float32's range",
    ),
}


def test_a_model_with_memory_loads_whole_and_acts_with_finite_numbers(memory_folder):
    config, network, stats = load(memory_folder)
    assert config == MEMORY and sorted(network["gru"]) == ["bhn", "bi", "wh", "wi"]
    high = np.finfo(np.float32).max
    obs = jnp.asarray(np.stack([np.zeros(9), np.full(9, high), np.full(9, -high)]), jnp.float32)
    memory, mean = policy_step(network, stats, jnp.ones((3, 8)), obs)
    assert np.all(np.isfinite(np.asarray(mean))) and np.all(np.abs(np.asarray(memory)) <= 1.0)


@pytest.mark.parametrize("name", list(MEMORY_DAMAGE))
def test_a_damaged_model_folder_with_memory_is_refused_naming_the_file_and_field(
    memory_folder, tmp_path, name
):
    folder = Path(shutil.copytree(memory_folder, tmp_path / "model"))
    damage, match = MEMORY_DAMAGE[name]
    _damage(folder, *damage)
    with pytest.raises(ValueError, match=match):
        load(folder)
    with pytest.raises(ValueError, match=match):
        JaxPPOController(folder)


def test_a_model_with_memory_lacking_an_array_is_refused_naming_it(memory_folder, tmp_path):
    folder = Path(shutil.copytree(memory_folder, tmp_path / "model"))
    arrays = _arrays(folder)
    del arrays["gru/bhn"]
    np.savez(folder / "network.npz", **arrays)
    with pytest.raises(ValueError, match=r"memory=8, 2 action components: it lacks \['gru/bhn'\]"):
        load(folder)


def test_the_shipped_model_loads_as_it_was_saved():
    _, network, stats = load(jax_ppo.shipped_folder())
    arrays = _arrays(jax_ppo.shipped_folder())
    np.testing.assert_array_equal(np.asarray(network["actor"][0]["w"]), arrays["actor/0/w"])
    np.testing.assert_array_equal(np.asarray(stats.var), arrays["obs_var"])
    assert network["actor"][0]["w"].dtype == jnp.float32 and stats.mean.dtype == jnp.float64


def _filled(shape, dtype, value):
    """An array of ``shape`` and ``dtype`` filled with ``value`` (cast as NumPy casts, overflow and all)."""
    with np.errstate(all="ignore"):
        return np.full(shape, value).astype(dtype)


_ARRAY_NAMES = ["actor/0/w", "actor/2/b", "critic/1/w", "log_std", "obs_mean", "obs_var"]
_JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner, max_size=3),
    max_leaves=6,
)
_CORRUPTIONS = st.one_of(
    st.tuples(st.just("truncate"), st.sampled_from(jax_ppo._FILES), st.floats(0.0, 1.0)),
    st.tuples(st.just("flip"), st.sampled_from(jax_ppo._FILES), st.floats(0.0, 1.0), st.integers(1, 255)),
    st.tuples(
        st.just("array"),
        st.sampled_from(_ARRAY_NAMES),
        st.builds(
            _filled,
            st.sampled_from([(), (2,), (8,), (16,), (8, 16), (16, 2), (16, 16)]),
            st.sampled_from([np.float16, np.float32, np.float64, np.int32, np.bool_]),
            st.floats(allow_nan=True, allow_infinity=True),
        ),
    ),
    st.tuples(st.just("setting"), st.sampled_from([*TINY.__dict__, "colour"]), _JSON),
)


@settings(max_examples=120, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(corruptions=st.lists(_CORRUPTIONS, min_size=1, max_size=2))
def test_any_damage_is_refused_naming_the_file_or_loads_a_model_with_finite_actions(
    model_folder, corruptions
):
    with tempfile.TemporaryDirectory() as scratch, np.errstate(all="ignore"):
        folder = Path(shutil.copytree(model_folder, Path(scratch) / "model"))
        # (arrays and settings first, while the files read; then their bytes)
        for corruption in sorted(corruptions, key=lambda c: c[0] in ("truncate", "flip")):
            _damage(folder, *corruption)
        try:
            config, network, stats = load(folder)
        except ValueError as refused:
            assert any(name in str(refused) for name in jax_ppo._FILES), refused
            return
    high = np.finfo(np.float32).max
    obs = np.stack([np.zeros(8), np.full(8, high), np.full(8, -high), np.linspace(-50, 50, 8)]).astype(
        np.float32
    )
    mean = np.asarray(policy_mean(network, jnp.asarray(obs), stats))
    assert mean.shape == (4, config.n_actions) and np.all(np.isfinite(mean))
