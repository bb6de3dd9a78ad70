"""Scenarios: named, documented episode distributions, and their registry."""

from subenv.scenarios import presets as _presets  # noqa: F401  (registers the shipped scenarios)
from subenv.scenarios.registry import get_scenario, register_scenario, scenario_names
from subenv.scenarios.scenario import EpisodeConfig, Interval, Scenario, SpeedRamp

__all__ = [
    "EpisodeConfig",
    "Interval",
    "Scenario",
    "SpeedRamp",
    "get_scenario",
    "register_scenario",
    "scenario_names",
]
