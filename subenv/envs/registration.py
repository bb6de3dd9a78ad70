"""Gymnasium registration of one id per scenario, ``subenv/<Name>-v<version>``, on ``import subenv``."""

from __future__ import annotations

import math

import gymnasium as gym

from subenv.dynamics.integrate import CONTROL_PERIOD_S
from subenv.scenarios.registry import registry_snapshot

__all__ = ["ENTRY_POINT", "HEADLINE_ID", "VECTOR_ENTRY_POINT", "env_ids", "register_envs"]

ENTRY_POINT = "subenv.envs.dive_plane:DivePlaneEnv"
VECTOR_ENTRY_POINT = "subenv.envs.vector:DivePlaneVectorEnv"
"""What ``gym.make_vec(id, num_envs=N)`` builds for every id (``vectorization_mode="sync"`` for
SyncVectorEnv)."""
HEADLINE_ID = "subenv/DivePlane-v0"
"""The randomized scenario under the package's headline name."""
_HEADLINE_SCENARIO = "Randomized"


def _max_steps(name: str) -> int:
    scenarios = registry_snapshot()
    scenario = scenarios[name]
    durations = [scenarios[c].duration_s for c in scenario.components] or [scenario.duration_s]
    return math.ceil(max(durations) / CONTROL_PERIOD_S - 1e-9)


def env_ids() -> list[str]:
    """The Gymnasium ids this package registers (after :func:`register_envs`)."""
    return [HEADLINE_ID] + [scenario.env_id for scenario in registry_snapshot().values()]


def register_envs() -> None:
    """Register (or re-register) an id for every scenario in the registry.

    ``import subenv`` calls it. Calling it again is harmless: each id is replaced by the same
    registration, and scenarios registered since (:func:`subenv.register_scenario`) gain theirs. A
    process that makes environments from the ids without importing ``subenv`` first calls it: a Ray
    worker, for example, which builds RLlib's environments from the id alone, through Ray's setup hook
    ``ray.init(runtime_env={"worker_process_setup_hook": "subenv.register_envs"})``.

    ``max_episode_steps`` is the scenario's longest duration at the default ``dt``; the
    environment truncates at the drawn episode's own duration. ``gym.make_vec`` builds the
    native :class:`~subenv.envs.DivePlaneVectorEnv` (:data:`VECTOR_ENTRY_POINT`).
    """
    keys = {scenario.env_id: key for key, scenario in registry_snapshot().items()}
    for env_id in env_ids():
        name = _HEADLINE_SCENARIO if env_id == HEADLINE_ID else keys[env_id]
        if env_id in gym.registry:
            del gym.registry[env_id]
        gym.register(
            id=env_id,
            entry_point=ENTRY_POINT,
            vector_entry_point=VECTOR_ENTRY_POINT,
            kwargs={"scenario": name},
            max_episode_steps=_max_steps(name),
        )
