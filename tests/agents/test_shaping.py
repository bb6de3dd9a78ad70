"""The training-only L1 plane-effort penalty: exactly weight * mean(|a|) off each reward, nothing else."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from agents.shaping import PlaneEffortL1VecEnv
from subenv.envs.sb3 import make_sb3_vec_env


def test_penalty_is_weight_times_mean_absolute_command() -> None:
    plain = make_sb3_vec_env("subenv/LowSpeed-v0", n_envs=3, seed=7, control="independent")
    shaped = PlaneEffortL1VecEnv(make_sb3_vec_env("subenv/LowSpeed-v0", n_envs=3, seed=7, control="independent"), 0.5)
    np.testing.assert_array_equal(plain.reset(), shaped.reset())
    rng = np.random.default_rng(0)
    for _ in range(20):
        actions = rng.uniform(-1.5, 1.5, size=(3, 2)).astype(np.float32)  # beyond the bounds: clipped first
        obs, rewards, dones, _ = plain.step(actions)
        obs_s, rewards_s, dones_s, _ = shaped.step(actions)
        np.testing.assert_array_equal(obs, obs_s)
        np.testing.assert_array_equal(dones, dones_s)
        expected = rewards - 0.5 * np.abs(np.clip(actions, -1, 1)).mean(axis=1)
        np.testing.assert_allclose(rewards_s, expected, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("weight", [-1.0, float("nan"), float("inf")])
def test_bad_weight_is_refused(weight: float) -> None:
    with pytest.raises(ValueError, match="plane_effort_l1"):
        PlaneEffortL1VecEnv(make_sb3_vec_env("subenv/LowSpeed-v0", n_envs=1), weight)
