"""The environments a comparison runs in: their ids and arguments, the caller's settings, and what an
informed controller is told.

The harness makes ``gym.make(id, control=..., alpha=..., vehicle=..., **env_kwargs)`` (or its vector
twin) for each scenario and controller: the scenario's registered id, the controller's action space,
the comparison's vehicle, and the caller's ``env_kwargs``, the environment's other arguments (the
planes' rate limit, the pitch limit, the control period, ...). :func:`check_env_kwargs` checks those
once, with the environment's own checks (:class:`~subenv.envs.config.DivePlaneConfig`), before any
episode; :func:`env_settings` is what :meth:`InformedController.inform
<subenv.evaluation.controller.InformedController.inform>` is told.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any, Final

import gymnasium as gym

from subenv.envs import DivePlaneVectorEnv, register_envs
from subenv.envs.config import DEFAULT_ARGUMENTS, DivePlaneConfig
from subenv.evaluation.controller import Controller, InformedController
from subenv.evaluation.suites import scenario_of
from subenv.scenarios.registry import get_scenario
from subenv.scenarios.scenario import Scenario
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.scaling import froude_factor
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "HARNESS_ARGUMENTS",
    "check_env_kwargs",
    "env_id_and_kwargs",
    "env_settings",
    "inform",
    "make_env",
    "make_vector_env",
    "setting_names",
]

HARNESS_ARGUMENTS: Final = {
    "scenario": "the suite's scenarios choose it",
    "vehicle": "the comparison's vehicle argument (subenv evaluate --vehicle) sets it",
    "control": "each controller declares its own",
    "alpha": "each controller declares its own",
}
"""The environment's arguments that the harness sets itself, and why ``env_kwargs`` may not."""


def setting_names() -> list[str]:
    """The environment's arguments ``env_kwargs`` may set: every one of
    :data:`~subenv.envs.config.DEFAULT_ARGUMENTS` but :data:`HARNESS_ARGUMENTS`."""
    return [name for name in DEFAULT_ARGUMENTS if name not in HARNESS_ARGUMENTS]


def _scenario_id(scenario: str | Scenario) -> tuple[str, dict[str, Any]]:
    """The registered id of ``scenario`` and the keyword arguments that make its episodes."""
    if isinstance(scenario, Scenario):
        return "subenv/DivePlane-v0", {"scenario": scenario}
    env_id = get_scenario(scenario_of(scenario)).env_id
    if env_id not in gym.registry:
        # A scenario registered since ``import subenv`` (a plugin's register_scenario) has no id until
        # register_envs gives it one: the harness does, rather than fail with gymnasium's NameNotFound.
        register_envs()
    return env_id, {}


def check_env_kwargs(
    env_kwargs: Mapping[str, Any] | None, scenarios: Iterable[str | Scenario], vehicle: Vehicle
) -> dict[str, Any]:
    """``env_kwargs`` checked as the environment checks its arguments, for every scenario, before
    anything runs; returns a copy (empty for None).

    Raises ValueError in one line naming the key: one the harness sets itself
    (:data:`HARNESS_ARGUMENTS`), one the environment does not take (listing those it does), or a value
    the environment refuses (its own message, which names the value and what is allowed).
    """
    if env_kwargs is None:
        return {}
    if not isinstance(env_kwargs, Mapping):
        raise ValueError(
            f"env_kwargs={env_kwargs!r} is invalid: must be a mapping of the environment's arguments to "
            "values"
        )
    for key in env_kwargs:
        if key in HARNESS_ARGUMENTS:
            raise ValueError(f"env_kwargs: {key!r} cannot be set there: {HARNESS_ARGUMENTS[key]}")
        if key not in setting_names():
            raise ValueError(f"env_kwargs: {key!r} is unknown: must be one of {setting_names()}")
    settings = dict(env_kwargs)
    for scenario in scenarios:
        env_id, kwargs = _scenario_id(scenario)
        try:
            DivePlaneConfig(**{**gym.spec(env_id).kwargs, **kwargs, **settings, "vehicle": vehicle})
        except (TypeError, ValueError) as exc:
            raise ValueError(f"env_kwargs: {exc}") from None
    return settings


def env_settings(scenario: str | Scenario, env_kwargs: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The settings of ``scenario``'s environments with ``env_kwargs``: each of :func:`setting_names`
    with its value there (the environment's default, its id's, or the caller's), as given
    (``max_depth_error_m`` None: the environment's default for the vehicle).

    What :meth:`InformedController.inform <subenv.evaluation.controller.InformedController.inform>` is
    told.
    """
    env_id, _ = _scenario_id(scenario)
    registered = gym.spec(env_id).kwargs
    given = env_kwargs or {}
    return {name: given.get(name, registered.get(name, DEFAULT_ARGUMENTS[name])) for name in setting_names()}


def inform(controller: Controller, scenario: str | Scenario, env_kwargs: Mapping[str, Any] | None) -> bool:
    """Tell ``controller`` the settings of ``scenario``'s environments (:func:`env_settings`) if it takes
    them (:class:`~subenv.evaluation.controller.InformedController`); returns whether it was told."""
    if not isinstance(controller, InformedController):
        return False
    controller.inform(env_settings(scenario, env_kwargs))
    return True


def env_id_and_kwargs(
    controller: Controller,
    scenario: str | Scenario,
    vehicle: str | Vehicle,
    max_duration_s: float | None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> tuple[str, dict[str, Any]]:
    """The id and keyword arguments of ``scenario``'s environments for ``controller``."""
    env_id, kwargs = _scenario_id(scenario)
    kwargs |= {
        **(env_kwargs or {}),
        "control": controller.control,
        "alpha": controller.alpha,
        "vehicle": vehicle,
    }
    spec = gym.spec(env_id)
    if max_duration_s is not None:
        dt = kwargs.get("dt", spec.kwargs.get("dt", DEFAULT_ARGUMENTS["dt"]))
        kwargs["max_episode_steps"] = max(1, math.ceil(max_duration_s / dt - 1e-9))
    else:
        # On a vehicle of another length the episodes are Froude-scaled (Scenario.reference_length_m):
        # their durations by sqrt(lambda), and the id's step limit (the reference vehicle's) with them.
        the_scenario = scenario if isinstance(scenario, Scenario) else get_scenario(scenario_of(scenario))
        boat = vehicle if isinstance(vehicle, Vehicle) else load_vehicle(vehicle)
        ratio = the_scenario.length_ratio(boat.length_m)
        if ratio != 1.0 and spec.max_episode_steps is not None:
            kwargs["max_episode_steps"] = math.ceil(
                spec.max_episode_steps * froude_factor("time", ratio) - 1e-9
            )
    return env_id, kwargs


def make_env(
    controller: Controller,
    scenario: str | Scenario,
    *,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> gym.Env:
    """The environment of ``scenario`` for ``controller``'s action space.

    ``scenario`` is a registered name, ``subenv/<Name>-v0``, or an unregistered :class:`Scenario`
    (run as ``subenv/DivePlane-v0`` with that scenario). ``max_duration_s`` truncates episodes
    earlier than the scenario does (Gymnasium's ``max_episode_steps``); ``env_kwargs`` are the
    environment's other arguments (:func:`check_env_kwargs`).
    """
    env_id, kwargs = env_id_and_kwargs(controller, scenario, vehicle, max_duration_s, env_kwargs)
    return gym.make(env_id, **kwargs)


def make_vector_env(
    controller: Controller,
    scenario: str | Scenario,
    num_envs: int,
    *,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> DivePlaneVectorEnv:
    """``num_envs`` environments of ``scenario`` stepped together (``gym.make_vec``), as :func:`make_env`'s.

    Ended sub-environments reset on the next step (``autoreset_mode="NextStep"``).
    """
    env_id, kwargs = env_id_and_kwargs(controller, scenario, vehicle, max_duration_s, env_kwargs)
    env = gym.make_vec(env_id, num_envs=num_envs, **kwargs)
    assert isinstance(env, DivePlaneVectorEnv)  # every subenv id's vector entry point
    return env
