"""The SB3 adapter: DummyVecEnv's semantics over the native vector env, and PPO and SAC training on it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")

from stable_baselines3 import PPO, SAC
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor

from subenv.envs.sb3 import SB3VecEnv, make_sb3_vec_env


def _same_info(a: dict, b: dict) -> None:
    assert a.keys() == b.keys(), a.keys() ^ b.keys()
    for key, expected in b.items():
        if isinstance(expected, np.ndarray):
            np.testing.assert_allclose(a[key], expected, rtol=1e-12, atol=1e-12)
        elif isinstance(expected, float):
            assert a[key] == pytest.approx(expected, rel=1e-12, abs=1e-12, nan_ok=True), key
        else:
            assert a[key] == expected, key


@pytest.mark.parametrize(
    ("env_id", "kwargs"), [("subenv/Nominal-v0", {}), ("subenv/DivePlane-v0", {"max_episode_steps": 30})]
)
def test_adapter_reproduces_dummy_vec_env(env_id, kwargs):
    n = 3
    native = make_sb3_vec_env(env_id, n_envs=n, **kwargs)
    dummy = DummyVecEnv([lambda: gym.make(env_id, **kwargs) for _ in range(n)])
    native.seed(7)
    dummy.seed(7)
    np.testing.assert_array_equal(native.reset(), dummy.reset())
    for a, b in zip(native.reset_infos, dummy.reset_infos, strict=True):
        _same_info(a, b)
    rng = np.random.default_rng(0)
    ends = truncations = 0
    for _ in range(150):
        actions = rng.uniform(-1, 1, size=(n, 1)).astype(np.float32)
        obs, rewards, dones, infos = native.step(actions)
        obs_d, rewards_d, dones_d, infos_d = dummy.step(actions)
        np.testing.assert_array_equal(obs, obs_d)
        assert rewards.dtype == rewards_d.dtype == np.float32
        np.testing.assert_allclose(rewards, rewards_d, rtol=1e-6)
        np.testing.assert_array_equal(dones, dones_d)
        for a, b in zip(infos, infos_d, strict=True):
            _same_info(a, b)
        for a, b in zip(native.reset_infos, dummy.reset_infos, strict=True):
            _same_info(a, b)
        ends += int(dones.sum())
        truncations += sum(info["TimeLimit.truncated"] for info in infos)
    assert ends > 0 and all("terminal_observation" in infos[i] for i in np.flatnonzero(dones))
    if "max_episode_steps" in kwargs:
        assert truncations > 0


def test_adapter_needs_same_step_autoreset_and_reports_its_spaces():
    with pytest.raises(ValueError, match=r"needs AutoresetMode\.SAME_STEP"):
        SB3VecEnv(gym.make_vec("subenv/Nominal-v0", num_envs=2))
    venv = make_sb3_vec_env("subenv/Nominal-v0", n_envs=2, control="independent", info_keys=())
    assert venv.action_space.shape == (2,) and venv.observation_space.shape == (8,)
    venv.reset()
    _, _, _, infos = venv.step(np.zeros((2, 2), dtype=np.float32))
    assert infos == [{"TimeLimit.truncated": False}] * 2  # info_keys=(): only what SB3 needs


def test_ppo_trains_through_the_adapter():
    venv = VecMonitor(make_sb3_vec_env("subenv/Nominal-v0", n_envs=8, seed=0, info_keys=()))
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=128, n_epochs=2, seed=0, device="cpu")
    model.learn(total_timesteps=1024)
    assert model.num_timesteps == 1024
    assert len(model.ep_info_buffer) > 0  # episodes ended and VecMonitor saw them through dones/infos
    mean_reward, _ = evaluate_policy(model, venv, n_eval_episodes=4, warn=False)
    assert np.isfinite(mean_reward)


def test_sac_trains_through_the_adapter():
    venv = make_sb3_vec_env("subenv/Nominal-v0", n_envs=4, seed=0)
    model = SAC(
        "MlpPolicy",
        venv,
        learning_starts=100,
        train_freq=8,
        gradient_steps=2,
        batch_size=64,
        buffer_size=2000,
        seed=0,
        device="cpu",
    )
    model.learn(total_timesteps=384)  # 12 rounds of train_freq=8 steps at 4 envs
    assert model.num_timesteps == 384
    buffer = model.replay_buffer
    assert buffer.size() * venv.num_envs == 384
    # Ended episodes store the real last observation (terminal_observation), not the next reset's:
    # in Nominal they end at the pitch limit (|pitch| > 0.6) or broaching (depth < 0.254 m).
    ended = buffer.dones[: buffer.size()] > 0
    assert ended.any()
    last = buffer.next_observations[: buffer.size()][ended]
    assert np.all((np.abs(last[:, 1]) > 0.6) | (last[:, 7] < 0.26))


def test_set_scenario_moves_the_following_episodes_through_env_method():
    """How a curriculum changes the training distribution: the vector env's set_scenario, once for all."""
    venv = make_sb3_vec_env(
        "subenv/Nominal-v0", n_envs=4, seed=0, info_keys=("speed_mps", "critical_speed_mps")
    )
    venv.reset()
    assert [info["speed_mps"] for info in venv.reset_infos] == pytest.approx([1.524] * 4)  # Nominal: 5 fps
    assert venv.env_method("set_scenario", "LowSpeed") == [None] * 4
    assert venv.get_attr("scenario")[0].name == "LowSpeed"
    venv.reset()
    ratios = [info["speed_mps"] / info["critical_speed_mps"] for info in venv.reset_infos]
    assert all(0.3 <= r <= 0.8 for r in ratios), ratios  # LowSpeed's band, relative to u_cr
    with pytest.raises(NotImplementedError, match="indices=None"):
        venv.env_method("set_scenario", "Nominal", indices=[0])
    with pytest.raises(AttributeError, match="no public method 'fly'"):
        venv.env_method("fly")
    with pytest.raises(ValueError, match="scenario='Nope' is unknown"):
        venv.env_method("set_scenario", "Nope")


def test_single_env_set_scenario_keeps_the_episode_under_way():
    env = gym.make("subenv/Nominal-v0")
    env.reset(seed=0)
    speed = env.unwrapped.speed_at(0.0)
    env.unwrapped.set_scenario("LowSpeed")
    env.step(np.zeros(1, dtype=np.float32))
    assert env.unwrapped.speed_at(1.0) == speed  # the episode under way is unchanged
    _, info = env.reset(seed=0)
    assert info["speed_mps"] < info["critical_speed_mps"]
    with pytest.raises(ValueError, match="scenario=3 is invalid"):
        env.unwrapped.set_scenario(3)
