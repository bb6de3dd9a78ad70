"""subenv.envs.register_env: a user's own id, with the native vector environment behind gym.make_vec."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import SyncVectorEnv

import subenv  # noqa: F401  (registers the shipped ids)
from subenv.envs import DivePlaneVectorEnv, register_env
from subenv.envs.registration import ENTRY_POINT
from subenv.scenarios import get_scenario

HOVER = get_scenario("LowSpeed").replace(
    name="Hover", description="LowSpeed, one fixed speed", speed_ratio=(0.5, 0.5)
)


@pytest.fixture
def registry():  # type: ignore[no-untyped-def]
    """The ids a test registers are removed afterwards."""
    before = set(gym.registry)
    yield
    for env_id in set(gym.registry) - before:
        del gym.registry[env_id]


def test_make_vec_on_a_plain_registration_falls_back_to_sync_vector_env(registry):
    # What register_env is for: Gymnasium's own register gives no vector entry point.
    gym.register("user/Plain-v0", entry_point=ENTRY_POINT, kwargs={"scenario": "LowSpeed"})
    envs = gym.make_vec("user/Plain-v0", num_envs=2)
    assert isinstance(envs, SyncVectorEnv)
    envs.close()


def test_register_env_gives_the_native_vector_env_with_the_single_env_s_episodes(registry):
    spec = register_env("user/Hover-v0", HOVER, control="independent", effort_weight=0.2)
    assert spec.vector_entry_point == "subenv.envs.vector:DivePlaneVectorEnv"
    assert spec.max_episode_steps == 1200  # LowSpeed's 600 s at 0.5 s
    envs = gym.make_vec("user/Hover-v0", num_envs=3)
    assert isinstance(envs, DivePlaneVectorEnv) and envs.single_action_space.shape == (2,)
    obs, _ = envs.reset(seed=7)
    actions = np.tile([[0.3, -0.2]], (3, 1)).astype(np.float32)
    for _ in range(5):
        obs, rewards, *_ = envs.step(actions)
    envs.close()
    for i in range(3):  # sub-environment i is gym.make(id) reset with seed 7 + i
        env = gym.make("user/Hover-v0")
        single, _ = env.reset(seed=7 + i)
        assert env.unwrapped.config.effort_weight == 0.2
        for _ in range(5):
            single, reward, *_ = env.step(actions[i])
        np.testing.assert_array_equal(single, obs[i])
        assert reward == rewards[i]
        env.close()


def test_max_episode_steps_follow_dt_and_the_vehicle_s_scale(registry):
    assert register_env("user/Slow-v0", "LowSpeed", dt=1.0).max_episode_steps == 600
    # SUBOFF x 24: durations x sqrt(24) (Froude scaling), 600 s -> 2939 s, in steps of 0.5 s
    assert register_env("user/Full-v0", "LowSpeed", vehicle="suboff_fullscale").max_episode_steps == 5879
    assert register_env("user/Given-v0", "LowSpeed", max_episode_steps=10).max_episode_steps == 10


@pytest.mark.parametrize(
    ("args", "kwargs", "message"),
    [
        (("user/Bad-v0", "Nowhere"), {}, r"scenario='Nowhere' is unknown"),
        (("user/Bad-v0", "LowSpeed"), {"weight": 1.0}, r"keyword argument\(s\) \['weight'\] invalid"),
        (("user/Bad-v0", "LowSpeed"), {"alpha": 2.0}, r"alpha=2\.0"),
        (("user/Bad-v0", "LowSpeed"), {"max_episode_steps": 0}, r"max_episode_steps=0 is invalid"),
        (("not an id", "LowSpeed"), {}, r"env_id='not an id' is invalid"),
        (("subenv/LowSpeed-v0", "Nominal"), {}, r"'subenv/LowSpeed-v0' is already registered"),
    ],
)
def test_bad_registrations_are_one_line_errors_that_register_nothing(registry, args, kwargs, message):
    before = dict(gym.registry)
    with pytest.raises(ValueError, match=message):
        register_env(*args, **kwargs)
    assert dict(gym.registry) == before


def test_overwrite_replaces_an_id(registry):
    register_env("user/Twice-v0", "LowSpeed")
    assert register_env("user/Twice-v0", "Nominal", overwrite=True).kwargs == {"scenario": "Nominal"}
