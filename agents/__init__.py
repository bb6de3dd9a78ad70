"""Stable-Baselines3 agents for subenv: training, a physics-placed curriculum, and shipped models.

- ``python -m agents.train --algo ppo`` (or ``subenv train``) trains PPO, SAC or TD3 with the
  hyperparameters of ``agents/hyperparams/<algo>.yml`` (:mod:`agents.train`, :mod:`agents.config`);
- :mod:`agents.curriculum` moves the training speeds down through the critical speed as the agent
  succeeds;
- :func:`load_agent` loads a model with its normalisation statistics in one call;
- the models shipped in ``agents/models/<name>/`` (each with its ``MODEL_CARD.md``) are
  registered as controllers of :mod:`subenv.evaluation` under ``<name>`` when this package is
  imported (``subenv evaluate`` does), so the comparison shows them next to the baselines.

Needs the ``rl`` extra (stable-baselines3, torch, PyYAML). Without Stable-Baselines3 installed
the shipped models are not registered, and the rest of subenv works as before.
"""

from __future__ import annotations

from importlib.util import find_spec
from pathlib import Path
from typing import Any, Final

from subenv.evaluation import controller_names, register_controller

__all__ = ["MODELS_DIR", "load_agent", "shipped_models"]

MODELS_DIR: Final = Path(__file__).parent / "models"
"""The shipped models: one folder each, with model.zip, vecnormalize.pkl, config.yml, MODEL_CARD.md."""


def shipped_models() -> dict[str, Path]:
    """The shipped models by name (their folder names), in name order."""
    if not MODELS_DIR.is_dir():
        return {}
    return {p.name: p for p in sorted(MODELS_DIR.iterdir()) if (p / "model.zip").is_file()}


def load_agent(path: str | Path, env: Any = None) -> Any:
    """:func:`agents.policy.load_agent` (imported on first use: it needs torch)."""
    from agents.policy import load_agent as _load

    return _load(path, env)


def _factory(path: Path, name: str) -> Any:
    def make() -> Any:
        from agents.controller import AgentController

        return AgentController(path, name=name)

    return make


if find_spec("stable_baselines3") is not None and find_spec("yaml") is not None:
    for _name, _path in shipped_models().items():
        if _name not in controller_names():
            register_controller(_name, _factory(_path, _name))
