"""The training-only reward shaping: the L1 plane-effort penalty takes exactly weight * mean(|a|) off
each reward, the depth-band bonus adds exactly its bonus where the true depth error is inside the band;
nothing else changes."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")

from subenv.envs.sb3 import make_sb3_vec_env
from subenv_agents.shaping import DEPTH_ERROR_KEY, DepthBandBonusVecEnv, PlaneEffortL1VecEnv


@pytest.mark.parametrize("reference_speed", [None, 0.5])
def test_penalty_is_weight_times_mean_absolute_command(reference_speed: float | None) -> None:
    # SpeedTransient: the speed changes within episodes, and short (50-step) episodes reset on the way.
    kwargs = {"control": "independent", "max_episode_steps": 50}
    plain = make_sb3_vec_env("subenv/SpeedTransient-v0", n_envs=3, seed=7, **kwargs)
    shaped = PlaneEffortL1VecEnv(
        make_sb3_vec_env("subenv/SpeedTransient-v0", n_envs=3, seed=7, **kwargs), 0.5, reference_speed
    )
    obs = plain.reset()
    np.testing.assert_array_equal(obs, shaped.reset())
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(120):
        actions = rng.uniform(-1.5, 1.5, size=(3, 2)).astype(np.float32)  # beyond the bounds: clipped first
        scale = 1.0 if reference_speed is None else obs[:, 4] / reference_speed  # the speed before the step
        obs, rewards, dones, _ = plain.step(actions)
        obs_s, rewards_s, dones_s, _ = shaped.step(actions)
        np.testing.assert_array_equal(obs, obs_s)
        np.testing.assert_array_equal(dones, dones_s)
        expected = rewards - 0.5 * np.abs(np.clip(actions, -1, 1)).mean(axis=1) * scale
        np.testing.assert_allclose(rewards_s, expected, rtol=1e-5, atol=1e-5)
        ends += int(dones.sum())
    assert ends >= 6


@pytest.mark.parametrize("weight", [-1.0, float("nan"), float("inf")])
def test_bad_weight_is_refused(weight: float) -> None:
    with pytest.raises(ValueError, match="plane_effort_l1"):
        PlaneEffortL1VecEnv(make_sb3_vec_env("subenv/LowSpeed-v0", n_envs=1), weight)
    with pytest.raises(ValueError, match="plane_effort_reference_speed_mps"):
        PlaneEffortL1VecEnv(make_sb3_vec_env("subenv/LowSpeed-v0", n_envs=1), 1.0, weight)


def test_band_bonus_is_added_exactly_where_the_true_depth_error_is_inside() -> None:
    # Noise on (DivePlane-v0): the bonus follows the true error in info, not the noisy observation.
    kwargs = {"control": "independent", "max_episode_steps": 40}
    plain = make_sb3_vec_env("subenv/DivePlane-v0", n_envs=4, seed=3, info_keys=(DEPTH_ERROR_KEY,), **kwargs)
    shaped = DepthBandBonusVecEnv(
        make_sb3_vec_env("subenv/DivePlane-v0", n_envs=4, seed=3, info_keys=(DEPTH_ERROR_KEY,), **kwargs),
        0.3,
        0.5,
    )
    np.testing.assert_array_equal(plain.reset(), shaped.reset())
    rng = np.random.default_rng(1)
    inside_steps = outside_steps = ends = 0
    for _ in range(200):
        actions = rng.uniform(-1, 1, size=(4, 2)).astype(np.float32)
        obs, rewards, dones, infos = plain.step(actions)
        obs_s, rewards_s, dones_s, _ = shaped.step(actions)
        np.testing.assert_array_equal(obs, obs_s)
        np.testing.assert_array_equal(dones, dones_s)
        error = np.array([info[DEPTH_ERROR_KEY] for info in infos])
        inside = np.abs(error) <= 0.3
        np.testing.assert_allclose(rewards_s, rewards + 0.5 * inside, rtol=1e-6, atol=1e-6)
        inside_steps += int(inside.sum())
        outside_steps += int((~inside).sum())
        ends += int(dones.sum())
    assert inside_steps > 50 and outside_steps > 50 and ends >= 8  # both branches and episode ends were seen


def test_band_bonus_needs_the_depth_error_in_info() -> None:
    shaped = DepthBandBonusVecEnv(
        make_sb3_vec_env("subenv/LowSpeed-v0", n_envs=2, seed=0, info_keys=()), 0.3, 0.5
    )
    shaped.reset()
    with pytest.raises(ValueError, match=DEPTH_ERROR_KEY):
        shaped.step(np.zeros((2, 1), dtype=np.float32))


@pytest.mark.parametrize(
    ("half_width", "bonus", "named"),
    [
        (0.0, 0.5, "half_width_m"),
        (float("inf"), 0.5, "half_width_m"),
        (0.3, -1.0, "bonus"),
        (0.3, float("nan"), "bonus"),
    ],
)
def test_bad_band_is_refused(half_width: float, bonus: float, named: str) -> None:
    with pytest.raises(ValueError, match=f"depth_band_bonus {named}="):
        DepthBandBonusVecEnv(make_sb3_vec_env("subenv/LowSpeed-v0", n_envs=1), half_width, bonus)
