"""Seeded behaviour, pinned: the same seed gives the same rollout, release after release.

A change to what a seed gives (a draw moved, a physics constant, even the order of a sum in the
hull's area) changes these digests. Then every id's version must be bumped (``subenv/Name-v1``) with a
Version History entry in ``DivePlaneEnv``'s docstring, and the digests written again
(``python tests/envs/test_seeded_rollouts.py`` prints them). The values are rounded to 6 decimals
before hashing over 50 steps, so that a last-bit difference between CPUs does not count, and anything
larger does.
"""

from __future__ import annotations

import hashlib

import gymnasium as gym
import numpy as np
import pytest

import subenv

DIGESTS = {
    "subenv/DivePlane-v0": "50a7988a56b86775",
    "subenv/Nominal-v0": "6f78ad88d87ed019",
    "subenv/LowSpeed-v0": "44e8cecf7e46e703",
    "subenv/NearCritical-v0": "5712025b255e31a2",
    "subenv/SpeedTransient-v0": "36e1ad991eb88bfc",
    "subenv/PeriscopeDepth-v0": "5e9fe2ac8e9a8d4a",
    "subenv/BallastOffset-v0": "4eacfa9d874a9a06",
    "subenv/Randomized-v0": "50a7988a56b86775",
    "subenv/Mixed-v0": "6d5dcd26c5f265b6",
    "subenv/PeriscopeDepth-v1": "3aa630265a7c8a5f",
    "subenv/PeriscopeDepthWaves-v0": "1e534e3e9bfb06ca",
    "subenv/HardRateTransient-v0": "811431cef0e47b61",
    "subenv/HardBallastLimits-v0": "3e425f44c6bff80b",
    "subenv/HardWaves18-v0": "e94a0bd4778f5125",
    "subenv/HardGusts-v0": "b5fc47623e250235",
}


def digest(env_id: str) -> str:
    env = gym.make(env_id)
    obs, _ = env.reset(seed=3)
    rng = np.random.default_rng(0)
    h = hashlib.sha256(np.round(obs.astype(np.float64), 6).tobytes())
    for _ in range(50):
        action = rng.uniform(-1, 1, size=env.action_space.shape).astype(np.float32)
        obs, reward, terminated, truncated, _ = env.step(action)
        h.update(np.round(obs.astype(np.float64), 6).tobytes())
        h.update(np.round(np.float64(reward), 6).tobytes())
        if terminated or truncated:
            obs, _ = env.reset()
    return h.hexdigest()[:16]


@pytest.mark.parametrize("env_id", subenv.env_ids())
def test_a_seed_gives_the_rollout_it_gave_when_the_id_was_released(env_id):
    assert digest(env_id) == DIGESTS[env_id], (
        f"{env_id}: seeded rollouts changed; bump every id's version with a Version History entry, then "
        "update DIGESTS (python tests/envs/test_seeded_rollouts.py)"
    )


if __name__ == "__main__":
    for env_id in subenv.env_ids():
        print(f"    {env_id!r}: {digest(env_id)!r},")
