"""Gymnasium registration of one id per scenario, ``subenv/<Name>-v<version>``, on ``import subenv``,
and of a user's own ids (:func:`register_env`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, Final

import gymnasium as gym
from gymnasium.envs.registration import EnvSpec

from subenv.dynamics.integrate import CONTROL_PERIOD_S
from subenv.scenarios.registry import get_scenario, registry_snapshot
from subenv.scenarios.scenario import Scenario
from subenv.vehicles.scaling import froude_factor

__all__ = [
    "ENTRY_POINT",
    "HEADLINE_ID",
    "ID_ARGUMENTS",
    "VECTOR_ENTRY_POINT",
    "env_ids",
    "register_env",
    "register_envs",
]

ENTRY_POINT = "subenv.envs.dive_plane:DivePlaneEnv"
VECTOR_ENTRY_POINT = "subenv.envs.vector:DivePlaneVectorEnv"
"""What ``gym.make_vec(id, num_envs=N)`` builds for every id (``vectorization_mode="sync"`` for
SyncVectorEnv)."""
HEADLINE_ID = "subenv/DivePlane-v0"
"""The randomized scenario under the package's headline name."""
_HEADLINE_SCENARIO = "Randomized"

ID_ARGUMENTS: Final[Mapping[str, Mapping[str, Any]]] = MappingProxyType(
    {
        "HardRateTransient": MappingProxyType({"plane_rate_limit_radps": 0.05}),
        "HardBallastLimits": MappingProxyType({"plane_rate_limit_radps": 0.03, "max_pitch_rad": 0.3}),
    }
)
"""The environment's arguments of the shipped ids that have some besides their scenario, by scenario
(:attr:`Scenario.key <subenv.scenarios.Scenario.key>`): registered with the id, so that ``gym.make(id)``
and ``gym.make_vec(id)`` make them, and what the evaluation harness, the certificates and the
documentation read (``gym.spec(id).kwargs``). The Hard track's limits: the planes' rate [rad/s] that an
MPC not told of it meets unprepared (0.05 through the critical speed: it won 52% against 100% told), and
with a ballast offset a slower rate with a pitch limit of 0.3 rad (17 deg) instead of 0.6."""


def _max_steps(scenario: Scenario, dt: float = CONTROL_PERIOD_S, time_factor: float = 1.0) -> int:
    """The scenario's longest episode (its components' longest, for a mixture) in steps of ``dt``, its
    durations times ``time_factor`` (Froude scaling)."""
    durations = [get_scenario(c).duration_s for c in scenario.components] or [scenario.duration_s]
    return math.ceil(max(durations) * time_factor / dt - 1e-9)


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
        arguments = {"scenario": name, **ID_ARGUMENTS.get(name, {})}
        _register(env_id, arguments, _max_steps(registry_snapshot()[name]))


def _register(env_id: str, kwargs: dict[str, Any], max_episode_steps: int) -> None:
    """(Re-)register ``env_id``: the single and the native vector environment with ``kwargs``."""
    if env_id in gym.registry:
        del gym.registry[env_id]
    gym.register(
        id=env_id,
        entry_point=ENTRY_POINT,
        vector_entry_point=VECTOR_ENTRY_POINT,
        kwargs=kwargs,
        max_episode_steps=max_episode_steps,
    )


def register_env(
    env_id: str,
    scenario: str | Scenario,
    *,
    max_episode_steps: int | None = None,
    overwrite: bool = False,
    **kwargs: Any,
) -> EnvSpec:
    """Register your own Gymnasium id: :class:`~subenv.envs.DivePlaneEnv` with ``scenario`` and the
    environment's keyword arguments ``kwargs``, and :class:`~subenv.envs.DivePlaneVectorEnv` as its
    vector entry point, as the shipped ids are registered.

    ``gym.register(env_id, entry_point=...)`` alone gives an id without a vector entry point, and
    ``gym.make_vec`` then falls back, silently, to ``SyncVectorEnv`` over single environments (20-40
    times slower at 64 sub-environments); ``gym.make_vec(env_id, num_envs=N)`` on an id registered here
    builds the native vector environment, whose sub-environment ``i`` of ``reset(seed=s)`` is
    ``gym.make(env_id)`` reset with ``seed=s + i``.

    Parameters
    ----------
    env_id : str
        The id, ``[namespace/]Name-v<version>`` as Gymnasium spells them (``"my/Hover-v0"``).
    scenario : str or Scenario
        A registered scenario's name (:func:`subenv.scenarios.scenario_names`) or a
        :class:`~subenv.scenarios.Scenario` (it need not be registered; its ``components`` must be).
    max_episode_steps : int or None
        Where ``gym.make`` truncates; None: the scenario's longest episode at the ``dt`` given (or
        0.5 s), its durations Froude-scaled to the vehicle given, as the shipped ids have it.
    overwrite : bool
        Replace an id that is already registered; otherwise that is an error.
    **kwargs
        The environment's arguments (``vehicle``, ``control``, ``alpha``, ``dt``, the reward weights,
        ...: :class:`~subenv.envs.DivePlaneConfig`'s fields), checked here, before anything is
        registered.

    Returns
    -------
    gymnasium.envs.registration.EnvSpec
        The id's registration.

    Raises
    ------
    ValueError
        An id already registered (without ``overwrite``), an unknown scenario, an unknown keyword or a
        value the environment refuses, named with what is allowed; the registry is then unchanged.
    """
    from subenv.envs.config import DivePlaneConfig

    try:
        EnvSpec(id=env_id, entry_point=ENTRY_POINT)  # (parses the id)
    except (gym.error.Error, TypeError, AttributeError):
        raise ValueError(
            f"env_id={env_id!r} is invalid: must be an id as Gymnasium spells them, "
            "[namespace/]Name-v<version> such as 'my/Hover-v0'"
        ) from None
    if env_id in gym.registry and not overwrite:
        raise ValueError(f"env_id={env_id!r} is already registered; pass overwrite=True to replace it")
    known = [f.name for f in dataclasses.fields(DivePlaneConfig)]
    unknown = sorted(set(kwargs) - set(known) - {"render_mode"})
    if unknown or "scenario" in kwargs:
        raise ValueError(
            f"keyword argument(s) {unknown or ['scenario']} invalid: the environment's arguments are "
            f"{[k for k in known if k != 'scenario']} and render_mode (the scenario is the second argument)"
        )
    config = DivePlaneConfig(scenario=scenario, **{k: v for k, v in kwargs.items() if k != "render_mode"})
    if max_episode_steps is None:
        max_episode_steps = _max_steps(
            config.base_scenario, config.dt, froude_factor("time", config.length_ratio)
        )
    elif (
        isinstance(max_episode_steps, bool) or not isinstance(max_episode_steps, int) or max_episode_steps < 1
    ):
        raise ValueError(
            f"max_episode_steps={max_episode_steps!r} is invalid: must be None or an integer >= 1"
        )
    _register(env_id, {"scenario": scenario, **kwargs}, max_episode_steps)
    return gym.spec(env_id)
