"""The shipped models as controller factories: what the ``subenv.controllers`` entry points name.

``pyproject.toml`` declares ``ppo = "subenv_agents.shipped:ppo"`` (one line per folder of
``subenv_agents/models/``); the attribute is a factory of an
:class:`~subenv_agents.controller.AgentController` for that folder. Importing this module needs the
``rl`` extra to be installed (it is only looked up: torch loads when a controller is made); without
it the import raises :class:`~subenv.extras.MissingExtra`, and ``subenv evaluate`` skips the models
with its message.
"""

from __future__ import annotations

from collections.abc import Callable

from subenv.extras import require
from subenv_agents import shipped_models

require("rl", "the shipped agents", "stable_baselines3", "yaml")


def __getattr__(name: str) -> Callable[[], object]:
    """The factory of the shipped model ``name`` (AttributeError if there is no such folder)."""
    models = shipped_models()
    if name not in models:
        raise AttributeError(
            f"module {__name__!r} has no attribute {name!r}: the shipped models are {sorted(models)}"
        )
    path = models[name]

    def make() -> object:
        from subenv_agents.controller import AgentController

        return AgentController(path, name=name)

    return make
