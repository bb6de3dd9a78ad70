"""RLlib's PPO on a subenv id, as the training guide's ``rllib_ppo.py`` configures it: two env runners,
each stepping the native vector environment, on a local Ray instance with 2 CPUs started here.

Needs the ``rllib`` extra, which holds gymnasium at 1.2.2: ``./dev test`` runs this file in its second
environment, ``.venv-gym12/`` (``./dev test-gym12``)."""

from __future__ import annotations

import importlib.util
import math
import os
import re
from pathlib import Path

import pytest

pytest.importorskip(
    "ray.rllib", reason="the 'rllib' extra is not installed (./dev test runs this file in .venv-gym12/)"
)
import ray
from ray.rllib.utils.metrics import (
    ENV_RUNNER_RESULTS,
    EPISODE_RETURN_MEAN,
    NUM_ENV_STEPS_SAMPLED_LIFETIME,
    NUM_EPISODES_LIFETIME,
)

from subenv.envs import DivePlaneVectorEnv

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "guides" / "training.md"
ITERATIONS = 2
TRAIN_BATCH = 256  # env-steps per iteration: 2 runners x 2 envs x 64 steps
EPISODE_STEPS = 32  # short episodes, so that some end within the two iterations


@pytest.fixture(scope="module")
def recipe(tmp_path_factory):  # type: ignore[no-untyped-def]
    """The training guide's ``rllib_ppo.py``, imported as a reader's file."""
    block = re.search(r"```python\n(# rllib_ppo\.py\n.*?)```", GUIDE.read_text("utf-8"), flags=re.DOTALL)
    assert block, "docs/guides/training.md has no rllib_ppo.py block"
    path = tmp_path_factory.mktemp("readme") / "rllib_ppo.py"
    path.write_text(block.group(1))
    spec = importlib.util.spec_from_file_location("rllib_ppo", path)
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def local_ray(recipe):  # type: ignore[no-untyped-def]
    # The guide's set-up hook: the runners import nothing of subenv until it registers the ids.
    hook = re.search(r'"worker_process_setup_hook": "([\w.]+)"', Path(recipe.__file__).read_text())
    assert hook and hook.group(1) == "subenv.register_envs"
    ray.init(
        num_cpus=2,
        include_dashboard=False,
        log_to_driver=False,
        configure_logging=False,
        runtime_env={"worker_process_setup_hook": hook.group(1)},
    )
    yield
    ray.shutdown()


def test_ppo_trains_on_two_env_runners_each_stepping_the_native_vector_env(recipe, local_ray) -> None:  # type: ignore[no-untyped-def]
    config = (
        recipe.ppo_config("subenv/Nominal-v0")
        .environment(env_config={"max_episode_steps": EPISODE_STEPS})
        .env_runners(num_envs_per_env_runner=2)
        .training(train_batch_size_per_learner=TRAIN_BATCH, minibatch_size=128, num_epochs=1)
        .debugging(seed=0)
    )
    assert config.num_env_runners == 2 and config.gym_env_vectorize_mode == "vector_entry_point"
    algo = config.build_algo()
    try:
        results = [algo.train() for _ in range(ITERATIONS)]
        runners = algo.env_runner_group.foreach_env_runner(
            lambda runner: (os.getpid(), type(runner.env.unwrapped), runner.env.unwrapped.num_envs),
            local_env_runner=False,
        )
    finally:
        algo.stop()

    assert [r["training_iteration"] for r in results] == list(range(1, ITERATIONS + 1))
    sampled = results[-1][ENV_RUNNER_RESULTS]
    assert sampled[NUM_ENV_STEPS_SAMPLED_LIFETIME] >= ITERATIONS * TRAIN_BATCH
    # Two runner processes, neither of them this one, each with one vector env of ours (not SyncVectorEnv).
    assert len({pid for pid, _, _ in runners} - {os.getpid()}) == 2
    assert [(cls, n) for _, cls, n in runners] == [(DivePlaneVectorEnv, 2)] * 2
    # Episodes ended (truncated at EPISODE_STEPS), with returns that are finite and at most 1 per step
    # (the depth reward 1 - tanh(|e| / 2 m) less non-negative penalties).
    assert sampled[NUM_EPISODES_LIFETIME] > 0
    episode_return = sampled[EPISODE_RETURN_MEAN]
    assert math.isfinite(episode_return) and episode_return <= EPISODE_STEPS
