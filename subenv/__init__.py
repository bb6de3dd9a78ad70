"""subenv: a Gymnasium benchmark for submarine depth control at low speed.

Importing the package registers one environment id per scenario, ``subenv/<Name>-v0``
(``subenv/DivePlane-v0`` is the randomized one), so ``gym.make("subenv/DivePlane-v0")`` works
after ``import subenv``, and ``gym.make("subenv:subenv/DivePlane-v0")`` works without it.
"""

from subenv.envs import DivePlaneEnv, env_ids, register_envs
from subenv.scenarios import Scenario, get_scenario, register_scenario, scenario_names
from subenv.vehicles import Vehicle, available_vehicles, load_vehicle

__version__ = "0.2.0"

__all__ = [
    "DivePlaneEnv",
    "Scenario",
    "Vehicle",
    "__version__",
    "available_vehicles",
    "env_ids",
    "get_scenario",
    "load_vehicle",
    "register_envs",
    "register_scenario",
    "scenario_names",
]

register_envs()
