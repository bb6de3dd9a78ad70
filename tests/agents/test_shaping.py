"""The training-only L1 plane-effort penalty: exactly weight * mean(|a|) off each reward, nothing else."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from agents.shaping import PlaneEffortL1VecEnv
from subenv.envs.sb3 import make_sb3_vec_env


@pytest.mark.parametrize("reference_speed", [None, 0.5])
def test_penalty_is_weight_times_mean_absolute_command(reference_speed: float | None) -> None:
    # SpeedTransient: the speed changes within episodes, and short (50-step) episodes reset on the way.
    kwargs = {"control": "independent", "max_episode_steps": 50}
    plain = make_sb3_vec_env("subenv/SpeedTransient-v0", n_envs=3, seed=7, **kwargs)
    shaped = PlaneEffortL1VecEnv(make_sb3_vec_env("subenv/SpeedTransient-v0", n_envs=3, seed=7, **kwargs), 0.5,
                                 reference_speed)
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
