"""The scenario registry: every registered scenario is also a Gymnasium id ``subenv/<name>-v<version>``.

A scenario of version 0 is known by its name; a later version by ``<name>-v<version>``
(:attr:`Scenario.key <subenv.scenarios.Scenario.key>`), so that a changed scenario can ship beside
the one whose seeded episodes its users pinned."""

from __future__ import annotations

from typing import TYPE_CHECKING

# The registry holds scenarios but runs no code of theirs: the class for the annotations only, so that
# scenario.py imports this module (a mixture finds its components here) and the two form no cycle.
if TYPE_CHECKING:
    from subenv.scenarios.scenario import Scenario

__all__ = ["get_scenario", "register_scenario", "scenario_for_env_id", "scenario_names"]

_REGISTRY: dict[str, Scenario] = {}


def register_scenario(scenario: Scenario, *, overwrite: bool = False) -> Scenario:
    """Add a scenario to the registry (and so make it selectable by name).

    A scenario registered after ``import subenv`` is selectable with
    ``DivePlaneEnv(scenario=name)`` and in the evaluation's suites (``subenv evaluate --plugins
    my_scenarios.py --suite name``, the harness gives it its id); to get a Gymnasium id for
    ``gym.make`` too, call :func:`subenv.envs.register_envs` afterwards.
    """
    if scenario.key in _REGISTRY and not overwrite:
        raise ValueError(
            f"scenario {scenario.key!r} is already registered; pass overwrite=True to replace it"
        )
    for component in scenario.components:
        if component not in _REGISTRY:
            raise ValueError(
                f"scenario {scenario.name!r}: component {component!r} is unknown; "
                f"known scenarios: {scenario_names()}"
            )
    _REGISTRY[scenario.key] = scenario
    return scenario


def get_scenario(name: str) -> Scenario:
    """The registered scenario called ``name``; a ValueError lists the known names."""
    try:
        return _REGISTRY[name]
    except KeyError:
        raise ValueError(f"scenario={name!r} is unknown: must be one of {scenario_names()}") from None


def scenario_for_env_id(env_id: str) -> str | None:
    """The registry's name (:attr:`Scenario.key <subenv.scenarios.Scenario.key>`) of the scenario
    registered as Gymnasium id ``env_id`` (``subenv/<name>-v<version>``), or None."""
    for key, scenario in _REGISTRY.items():
        if scenario.env_id == env_id:
            return key
    return None


def scenario_names() -> list[str]:
    """Names of the registered scenarios (:attr:`Scenario.key <subenv.scenarios.Scenario.key>`), in
    registration order."""
    return list(_REGISTRY)


def registry_snapshot() -> dict[str, Scenario]:
    """A copy of the registry (name -> scenario)."""
    return dict(_REGISTRY)
