"""RL Baselines3 Zoo (``rl_zoo3``) trains the registered environments as they are.

Each test runs ``python -m rl_zoo3.train ... --gym-packages subenv`` in a subprocess (its working
directory is pytest's tmp_path, not the repository) for a few thousand steps, then loads the saved
model with Stable-Baselines3 and asks it for an action on an observation from ``gym.make``.

rl_zoo3 replaces the ``/`` of ``subenv/LowSpeed-v0`` with ``-`` in its folder and file names
(``<log>/<algo>/subenv-LowSpeed-v0_1/subenv-LowSpeed-v0.zip``); its hyperparameter YAML is keyed
by the id itself. ``--num-threads 1`` because torch's default of one thread per core is many times
slower for these small networks when the cores are shared.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pytest

# Only look rl_zoo3 up: importing it replaces gymnasium's TimeLimit for the whole process
# (rl_zoo3/gym_patches.py adds info["TimeLimit.truncated"]), which would change what every later
# test sees from gym.make. rl_zoo3 runs in subprocesses below.
if importlib.util.find_spec("rl_zoo3") is None:
    pytest.skip("the 'zoo' extra is not installed", allow_module_level=True)
pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")

import yaml
from stable_baselines3 import PPO, SAC

import subenv

ENV_ID = "subenv/LowSpeed-v0"
ENV_NAME = "subenv-LowSpeed-v0"  # rl_zoo3's folder and file name for ENV_ID
ALGOS = {"ppo": PPO, "sac": SAC}

# Minimal hyperparameters in rl_zoo3's layout (top-level key: the env id), small enough for seconds: PPO two
# rollouts and updates, SAC 300 gradient steps after its learning_starts (what is tested is that rl_zoo3
# trains with them and saves a model that loads and acts, not what it learns).
HYPERPARAMS = {
    "ppo": {"n_timesteps": 1024, "policy": "MlpPolicy", "n_steps": 512, "batch_size": 64, "n_epochs": 2},
    "sac": {
        "n_timesteps": 600,
        "policy": "MlpPolicy",
        "learning_starts": 300,
        "batch_size": 64,
        "policy_kwargs": "dict(net_arch=[64, 64])",
    },
}


def _run_zoo(module: str, args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    # The subprocess imports subenv from the same place as this process, whatever its working directory.
    repo_root = str(Path(subenv.__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (repo_root, env.get("PYTHONPATH")) if p)
    proc = subprocess.run(
        [sys.executable, "-m", module, *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, (
        f"{module} exited {proc.returncode}\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    )
    return proc


def _train(algo: str, log_folder: Path, cwd: Path, extra: list[str]) -> subprocess.CompletedProcess[str]:
    return _run_zoo(
        "rl_zoo3.train",
        [
            "--algo",
            algo,
            "--env",
            ENV_ID,
            "--gym-packages",
            "subenv",
            "-f",
            str(log_folder),
            "--seed",
            "0",
            "--num-threads",
            "1",
            *extra,
        ],
        cwd,
    )


def _check_model(algo: str, log_folder: Path) -> None:
    run_dir = log_folder / algo / f"{ENV_NAME}_1"
    model_path = run_dir / f"{ENV_NAME}.zip"
    assert model_path.is_file(), sorted(p.name for p in log_folder.rglob("*"))
    assert (run_dir / ENV_NAME / "config.yml").is_file()

    model = ALGOS[algo].load(model_path, device="cpu")
    env = gym.make(ENV_ID)
    try:
        assert model.observation_space == env.observation_space
        assert model.action_space == env.action_space
        obs, _ = env.reset(seed=0)
        action, _ = model.predict(obs, deterministic=True)
        assert env.action_space.contains(action), action
        env.step(action)
    finally:
        env.close()


@pytest.fixture(scope="module")
def conf_file_run(tmp_path_factory):  # type: ignore[no-untyped-def]
    """``conf_file_run(algo)``: ``(log folder, process)`` of rl_zoo3.train with ``HYPERPARAMS[algo]`` as
    its conf file (seed 0), trained on first use and then shared: the PPO run is the one rl_zoo3.enjoy
    loads. Tests only read the log folder."""
    runs: dict[str, tuple[Path, subprocess.CompletedProcess[str]]] = {}

    def run(algo: str) -> tuple[Path, subprocess.CompletedProcess[str]]:
        if algo not in runs:
            cwd = tmp_path_factory.mktemp(f"zoo-{algo}")
            conf = cwd / f"{algo}.yml"
            conf.write_text(yaml.safe_dump({ENV_ID: HYPERPARAMS[algo]}))
            logs = cwd / "logs"
            runs[algo] = logs, _train(algo, logs, cwd, ["--conf-file", str(conf)])
        return runs[algo]

    return run


@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_rl_zoo_trains_with_conf_file(algo, conf_file_run):
    logs, proc = conf_file_run(algo)
    assert f"Saving to {logs / algo / f'{ENV_NAME}_1'}" in proc.stdout
    _check_model(algo, logs)


def test_rl_zoo_trains_with_shipped_default_hyperparameters(tmp_path):
    """Without a conf file rl_zoo3 falls back to the ``default`` entry of its own ppo.yml."""
    logs = tmp_path / "logs"
    proc = _train("ppo", logs, tmp_path, ["-n", "2048"])
    assert "Using 'default' hyperparameters" in proc.stdout
    _check_model("ppo", logs)


def test_rl_zoo_enjoy_loads_the_trained_agent(tmp_path, conf_file_run):
    # rl_zoo3 2.9.2's enjoy imports `requests` (rl_zoo3/load_from_hub.py) without declaring it.
    pytest.importorskip("requests", reason="rl_zoo3.enjoy imports requests, which rl_zoo3 does not install")
    logs, _ = conf_file_run("ppo")  # enjoy writes nothing into the log folder (no --reward-log)
    proc = _run_zoo(
        "rl_zoo3.enjoy",
        [
            "--algo",
            "ppo",
            "--env",
            ENV_ID,
            "--gym-packages",
            "subenv",
            "-f",
            str(logs),
            "--exp-id",
            "0",
            "-n",
            str(gym.spec(ENV_ID).max_episode_steps + 100),
            "--no-render",
            "--deterministic",
            "--num-threads",
            "1",
        ],
        tmp_path,
    )
    assert f"Loading {logs / 'ppo' / f'{ENV_NAME}_1' / f'{ENV_NAME}.zip'}" in proc.stdout
    # At least one whole episode (truncated at the id's max_episode_steps at the latest) was played.
    assert "Episode Length" in proc.stdout, proc.stdout[-2000:]
