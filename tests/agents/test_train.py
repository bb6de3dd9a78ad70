"""Training runs per algorithm: a thousand steps that save, reload and evaluate, seeded."""

from __future__ import annotations

import json
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")
pytest.importorskip("yaml", reason="the 'rl' extra is not installed")

from subenv.evaluation import evaluate
from subenv_agents.card import lineage, total_training_time_s
from subenv_agents.config import ALGORITHMS, algorithm_class, load_config
from subenv_agents.controller import AgentController
from subenv_agents.curriculum import write_state
from subenv_agents.policy import (
    CHECKPOINT_DIR,
    CONFIG_FILE,
    MODEL_FILE,
    SELECTED_DIR,
    load_agent,
    model_folder,
    training_run,
)
from subenv_agents.train import main, train

# Small enough for the default suite: a thousand steps (one evaluation and one checkpoint, at step 1000,
# and for SAC and TD3 500 gradient steps after learning_starts), small networks.
_SMALL = {
    "ppo": {"n_timesteps": 1024, "n_envs": 4, "n_steps": 256, "batch_size": 256, "n_epochs": 2},
    "sac": {
        "n_timesteps": 1000,
        "n_envs": 2,
        "learning_starts": 500,
        "buffer_size": 5000,
        "gradient_steps": 1,
        "train_freq": 1,
    },
    "td3": {
        "n_timesteps": 1000,
        "n_envs": 2,
        "learning_starts": 500,
        "buffer_size": 5000,
        "gradient_steps": 1,
        "train_freq": 1,
    },
}
_ENV_ID = "subenv/LowSpeed-v0"


def _config(algo: str, **changes):  # type: ignore[no-untyped-def]
    """The shipped hyperparameters made small; without the depth-integral observation unless asked."""
    overrides = {**_SMALL[algo], "policy_kwargs": {"net_arch": [16, 16]}, "depth_integral": False, **changes}
    return load_config(algo, _ENV_ID, overrides=overrides)


def _observations(n: int = 32) -> np.ndarray:
    env = gym.make(_ENV_ID, control="independent")
    return np.stack([env.reset(seed=1000 + i)[0] for i in range(n)])


@pytest.fixture(scope="module", params=ALGORITHMS)
def trained(request, tmp_path_factory):  # type: ignore[no-untyped-def]
    """Two runs of the same algorithm and seed, and one with another seed."""
    algo = request.param
    root = tmp_path_factory.mktemp(algo)
    runs = [
        train(
            _config(algo),
            seed=seed,
            run_dir=root / f"run{k}",
            eval_freq=1000,
            eval_episodes=2,
            save_freq=1000,
            verbose=0,
        )
        for k, seed in enumerate((3, 3, 4))
    ]
    return algo, runs


def _readme_run_folder() -> set[str]:
    """The names the training guide's run-folder list gives (``checkpoints/`` as ``checkpoints``)."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "guides" / "training.md").read_text("utf-8")
    block = text[text.index("- **A run folder**") :].split("```text\n", 1)[1].split("```", 1)[0]
    lines = [line for line in block.splitlines() if line.strip()]
    indent = min(len(line) - len(line.lstrip()) for line in lines)  # (deeper lines continue a description)
    columns = [
        re.split(r" {2,}", line.strip())[0] for line in lines if len(line) - len(line.lstrip()) == indent
    ]
    names = {
        name.rstrip("/")
        for column in columns
        if column and not column.startswith("(")
        for name in column.split(", ")
    }
    return names


def test_run_folder_holds_what_the_readme_lists(trained) -> None:  # type: ignore[no-untyped-def]
    algo, runs = trained
    run = runs[0]
    names = {p.name for p in run.run_dir.iterdir()}
    documented = _readme_run_folder()
    # Everything a run with evaluations and checkpoints makes is listed; the listed ones it makes are there.
    assert names <= documented, names - documented
    assert documented - {"curriculum.json", "selected", "selection.json", "tensorboard"} == names - {
        "tensorboard"
    }
    assert any(p.name.startswith("rl_model_vecnormalize_") for p in (run.run_dir / "checkpoints").iterdir())
    record = json.loads((run.run_dir / "train.json").read_text())
    assert record["algo"] == algo and record["seed"] == 3 and record["timesteps"] == run.timesteps
    assert run.timesteps >= _SMALL[algo]["n_timesteps"]
    assert not [p for p in run.run_dir.iterdir() if p.name.startswith(".")]  # no temporary files left


def test_tensorboard_writes_in_the_run_folders_tensorboard_folder(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """With TensorBoard installed, its event files go to ``<run>/tensorboard/``, as the guide lists (a
    stand-in for TensorBoard's writer: the 'rl' extra does not install it)."""
    from stable_baselines3.common import logger as sb3_logger

    import subenv_agents.train as train_module

    written: list[Path] = []

    class EventFiles(sb3_logger.KVWriter):  # type: ignore[misc]
        def __init__(self, folder: str) -> None:
            written.append(Path(folder) / "events.out.tfevents.0")
            written[-1].write_bytes(b"")

        def write(self, *args, **kwargs) -> None:  # type: ignore[no-untyped-def]
            pass

    monkeypatch.setattr(sb3_logger, "TensorBoardOutputFormat", EventFiles)
    real_find_spec = train_module.find_spec
    monkeypatch.setattr(train_module, "find_spec", lambda name: name == "tensorboard" or real_find_spec(name))
    run = train(
        _config("ppo", n_timesteps=1024),
        seed=0,
        run_dir=tmp_path / "run",
        eval_freq=0,
        save_freq=0,
        verbose=0,
    )
    assert written == [run.run_dir / "tensorboard" / "events.out.tfevents.0"]
    names = {p.name for p in run.run_dir.iterdir()}
    assert "tensorboard" in names and names <= _readme_run_folder(), names - _readme_run_folder()


def test_reload_predicts_what_the_trained_model_predicts(trained) -> None:  # type: ignore[no-untyped-def]
    _, runs = trained
    agent = load_agent(runs[0].run_dir)
    obs = _observations()
    normalised = agent.normalize(obs).astype(np.float32)
    expected, _ = agent.model.predict(normalised, deterministic=True)
    actions = agent.predict(obs)  # the NumPy actor
    assert actions.shape == (len(obs), 2) and actions.dtype == np.float32
    np.testing.assert_allclose(actions, expected, atol=1e-5)
    assert np.all(np.abs(actions) <= 1.0)


def test_same_seed_same_model_other_seed_other_model(trained) -> None:  # type: ignore[no-untyped-def]
    _, runs = trained
    a, b, c = (load_agent(r.run_dir) for r in runs)
    obs = _observations()
    np.testing.assert_array_equal(a.predict(obs), b.predict(obs))
    np.testing.assert_array_equal(a.obs_mean, b.obs_mean)
    assert not np.array_equal(a.predict(obs), c.predict(obs))


def test_trained_agent_runs_in_the_evaluation_harness_deterministically(trained) -> None:  # type: ignore[no-untyped-def]
    _, runs = trained
    controller = AgentController(runs[0].run_dir, name="agent")
    assert controller.control == "independent"
    first = evaluate([controller], "tiny", episodes=1, progress=False)
    second = evaluate([AgentController(runs[1].run_dir, name="agent")], "tiny", episodes=1, progress=False)
    assert [r.trajectory.steps for r in first] == [r.trajectory.steps for r in second]
    for x, y in zip(first, second, strict=True):
        np.testing.assert_array_equal(x.trajectory.depth_m, y.trajectory.depth_m)


def test_checkpoint_loads_with_its_own_statistics(trained) -> None:  # type: ignore[no-untyped-def]
    _, runs = trained
    checkpoints = sorted((runs[0].run_dir / "checkpoints").glob("rl_model_*_steps.zip"))
    assert checkpoints
    agent = load_agent(checkpoints[0])
    steps = checkpoints[0].name.split("_")[-2]
    import pickle

    with (runs[0].run_dir / "checkpoints" / f"rl_model_vecnormalize_{steps}_steps.pkl").open("rb") as f:
        stats = pickle.load(f)
    np.testing.assert_array_equal(agent.obs_mean, stats.obs_rms.mean)


def test_resume_continues_from_a_checkpoint(trained, tmp_path) -> None:  # type: ignore[no-untyped-def]
    algo, runs = trained
    checkpoint = sorted((runs[0].run_dir / "checkpoints").glob("rl_model_*_steps.zip"))[0]
    start = int(checkpoint.name.split("_")[-2])
    config = _config(algo, learning_rate=1.25e-5)  # a new learning rate for the continuation
    result = train(
        config,
        seed=3,
        run_dir=tmp_path / "resumed",
        trained_agent=checkpoint,
        eval_freq=0,
        save_freq=0,
        verbose=0,
    )
    assert result.timesteps >= start + config.n_timesteps  # the step count goes on
    resumed = algorithm_class(algo).load(result.run_dir / "model.zip", device="cpu")
    assert resumed.learning_rate == 1.25e-5 and resumed.lr_schedule(0.5) == 1.25e-5
    with pytest.raises(ValueError, match="cannot change the network"):
        train(
            _config(algo, policy_kwargs={"net_arch": [8, 8]}),
            seed=3,
            run_dir=tmp_path / "other_net",
            trained_agent=checkpoint,
            eval_freq=0,
            save_freq=0,
            verbose=0,
        )
    assert not (tmp_path / "other_net").exists()  # no half-made run folder left behind
    record = json.loads((result.run_dir / "train.json").read_text())
    assert record["trained_agent"] == str(checkpoint)
    # The run it continued is its lineage: a shipped model's training time counts both.
    parent = json.loads((runs[0].run_dir / "train.json").read_text())
    assert lineage(result.run_dir) == [parent]
    assert (
        total_training_time_s({**record, "continued_from": [parent]})
        == record["wall_time_s"] + parent["wall_time_s"]
    )
    assert load_agent(result.run_dir).predict(_observations()).shape == (32, 2)


def test_a_model_path_names_its_config_folder_and_the_run_that_trained_it(tmp_path) -> None:  # type: ignore[no-untyped-def]
    run = tmp_path / "ppo" / "run_1"
    for folder in (run, run / SELECTED_DIR):
        folder.mkdir(parents=True, exist_ok=True)
        (folder / CONFIG_FILE).write_text("algo: ppo\n")
    (run / CHECKPOINT_DIR).mkdir()
    checkpoint = run / CHECKPOINT_DIR / "rl_model_1024_steps.zip"
    cases = {  # path: (the folder with its config.yml, the run that trained it)
        run / MODEL_FILE: (run, run),
        run / "best_model.zip": (run, run),
        checkpoint: (run, run),
        run / SELECTED_DIR / MODEL_FILE: (run / SELECTED_DIR, run),
    }
    for path, (config_folder, trained_by) in cases.items():
        assert (model_folder(path), training_run(path)) == (config_folder, trained_by), path
    assert (
        training_run(run) == training_run(run / SELECTED_DIR) == training_run(str(run / SELECTED_DIR)) == run
    )


def test_resume_takes_the_curriculum_stage_of_the_models_step(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """A checkpoint or the selected policy resumes at the stage training was at when it was saved."""
    config = _config("ppo", n_timesteps=2048, curriculum=True)
    first = train(
        config,
        seed=0,
        run_dir=tmp_path / "first",
        eval_freq=0,
        save_freq=256,
        select_freq=1024,
        select_episodes=1,
        verbose=0,
    )
    assert json.loads((first.run_dir / "curriculum.json").read_text())["start_stage"] == 0
    # As if the curriculum had advanced to stage 2 at step 1500 (too few steps here to earn it).
    write_state(first.run_dir, 2, [(1500, 2)], start_stage=0)
    checkpoint = first.run_dir / "checkpoints" / "rl_model_1024_steps.zip"
    selected = first.run_dir / "selected" / "model.zip"
    selected_step = algorithm_class("ppo").load(selected, device="cpu").num_timesteps
    for k, (model, expected) in enumerate(
        [(checkpoint, 0), (first.run_dir, 2), (selected, 2 if selected_step >= 1500 else 0)]
    ):
        resumed = train(
            _config("ppo", n_timesteps=1024, curriculum=True),
            seed=1,
            run_dir=tmp_path / f"resumed{k}",
            trained_agent=model,
            eval_freq=0,
            save_freq=0,
            verbose=0,
        )
        state = json.loads((resumed.run_dir / "curriculum.json").read_text())
        assert state["start_stage"] == expected, model


def test_resume_with_the_depth_integral_observation(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """The training env appends the integral; the continued run sees the space the model was trained on."""
    config = _config("ppo", n_timesteps=512, depth_integral={"time_constant_s": 100.0})
    first = train(config, seed=0, run_dir=tmp_path / "first", eval_freq=0, save_freq=0, verbose=0)
    second = train(
        config,
        seed=1,
        run_dir=tmp_path / "second",
        trained_agent=first.run_dir,
        eval_freq=0,
        save_freq=0,
        verbose=0,
    )
    assert second.timesteps >= first.timesteps + 512
    assert load_agent(second.run_dir).observation_space.shape == (9,)
    with pytest.raises(ValueError, match="trained on the observation space"):  # an 8-dimensional run cannot
        train(
            _config("ppo", n_timesteps=512),
            seed=1,
            run_dir=tmp_path / "third",
            trained_agent=first.run_dir,
            eval_freq=0,
            save_freq=0,
            verbose=0,
        )


def test_model_for_another_observation_space_is_refused(trained) -> None:  # type: ignore[no-untyped-def]
    _, runs = trained
    other = gym.make(_ENV_ID, control="independent", max_depth_error_m=10.0)  # other observation bounds
    with pytest.raises(ValueError, match="trained on the observation space"):
        load_agent(runs[0].run_dir, env=other)
    with pytest.raises(ValueError, match="trained on the action space"):
        load_agent(runs[0].run_dir, env=gym.make(_ENV_ID))  # dual: one action
    with pytest.raises(ValueError, match="shape"):
        load_agent(runs[0].run_dir).predict(np.zeros(5))


def test_command_line_trains_and_rejects_bad_input(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    args = [
        "--algo",
        "ppo",
        "--env",
        _ENV_ID,
        "-n",
        "512",
        "--seed",
        "1",
        "--run-dir",
        str(tmp_path / "cli"),
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
    ]
    (tmp_path / "cli").mkdir()  # an existing empty run folder is filled (it loses nothing)
    assert main(args) == 0
    assert "trained ppo on subenv/LowSpeed-v0" in capsys.readouterr().out
    assert load_agent(tmp_path / "cli").config.n_envs == 2
    with pytest.raises(SystemExit, match="exists"):
        main(args)  # the run folder exists: nothing is overwritten
    # Without --algo and --run-dir (rl-zoo's defaults): PPO, into <log folder>/ppo/<env>_<k>, k the first
    # free.
    plain = [a for a in args if a not in ("--algo", "ppo", "--run-dir", str(tmp_path / "cli"))]
    (tmp_path / "logs" / "ppo" / "subenv-LowSpeed-v0_1").mkdir(parents=True)
    assert main([*plain, "-f", str(tmp_path / "logs")]) == 0
    assert f"run folder {tmp_path / 'logs' / 'ppo' / 'subenv-LowSpeed-v0_2'}/" in capsys.readouterr().out
    assert load_agent(tmp_path / "logs" / "ppo" / "subenv-LowSpeed-v0_2").config.algo == "ppo"
    with pytest.raises(SystemExit, match="unknown hyperparameter"):
        main(["--algo", "ppo", "--env", _ENV_ID, "-params", "n_step:3", "--run-dir", str(tmp_path / "x")])
    with pytest.raises(SystemExit, match="is not registered"):
        main(["--algo", "ppo", "--env", "subenv/Nope-v0", "--run-dir", str(tmp_path / "y")])
    with pytest.raises(SystemExit):
        main(["--algo", "dqn"])  # argparse names the choices
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_missing_model_is_a_clear_error(tmp_path) -> None:
    with pytest.raises(FileNotFoundError, match="no trained model"):
        load_agent(tmp_path)


def test_depth_integral_is_the_same_in_training_and_in_the_controller(tmp_path) -> None:
    """The controller feeds the agent exactly the observations the training stack gave it."""
    from dataclasses import replace

    from subenv_agents.train import make_vec_env

    config = _config("ppo", depth_integral={"time_constant_s": 50.0}, n_timesteps=1024)
    run = train(config, seed=0, run_dir=tmp_path / "run", eval_freq=0, save_freq=0, verbose=0)
    agent = load_agent(run.run_dir)
    assert agent.observation_space.shape == (9,) and agent.env_observation_space.shape == (8,)
    agent.check_spaces(gym.make(_ENV_ID, control="independent"))  # the environment's own 8 components

    fed: list[np.ndarray] = []
    predict = agent.predict
    # (the controller predicts on batches: one row per episode, here one)
    agent.predict = lambda obs: (fed.extend(np.array(obs, ndmin=2)), predict(obs))[1]  # type: ignore[method-assign]
    controller = AgentController(agent)
    stack = make_vec_env(replace(config, normalize=None), 1, seed=11)  # training's stack, raw observations
    expected = [stack.reset()[0]]
    env = gym.make(_ENV_ID, control="independent")
    obs, info = env.reset(seed=11)
    controller.reset(info, env.unwrapped.base_vehicle)
    for _ in range(80):
        action = controller.act(obs)
        obs, *_ = env.step(action)
        expected.append(stack.step(action[None])[0][0])
    np.testing.assert_array_equal(np.array(fed), np.array(expected[:80]))
    integral = np.array(fed)[:, -1]
    assert integral[0] == 0.0  # I_0 = 0 at the reset
    e = np.array(fed)[:, 0]
    decay = np.exp(-0.5 / 50.0)
    np.testing.assert_allclose(integral[1:], decay * integral[:-1] + 0.5 * e[1:], rtol=1e-6, atol=1e-6)


def test_training_stack_adds_the_band_bonus_on_the_true_depth_error() -> None:
    """``depth_band_bonus`` in a config reaches the rewards: the stack asks the environment for the
    depth error and adds the bonus exactly where it is inside the band."""
    from dataclasses import replace

    from subenv_agents.train import make_vec_env

    config = replace(_config("ppo", n_timesteps=1024), normalize=None)
    banded_config = replace(
        _config("ppo", n_timesteps=1024, depth_band_bonus={"half_width_m": 1.0, "bonus": 0.25}),
        normalize=None,
    )
    plain, banded = make_vec_env(config, 2, seed=4), make_vec_env(banded_config, 2, seed=4)
    np.testing.assert_array_equal(plain.reset(), banded.reset())
    rng = np.random.default_rng(0)
    errors = []
    for _ in range(60):
        actions = rng.uniform(-1, 1, size=(2, *plain.action_space.shape)).astype(np.float32)
        _, rewards, _, _ = plain.step(actions)
        _, rewards_banded, _, infos = banded.step(actions)
        error = np.array([info["depth_error_m"] for info in infos])
        np.testing.assert_allclose(rewards_banded - rewards, 0.25 * (np.abs(error) <= 1.0), atol=1e-6)
        errors.extend(error.tolist())
    assert min(map(abs, errors)) <= 1.0 < max(map(abs, errors))  # both sides of the band were seen
