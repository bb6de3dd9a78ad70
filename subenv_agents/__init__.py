"""Stable-Baselines3 agents for subenv: training, a physics-placed curriculum, and shipped models.

- ``python -m subenv_agents.train --algo ppo`` (or ``subenv train``) trains PPO, SAC or TD3 with the
  hyperparameters of ``subenv_agents/hyperparams/<algo>.yml`` (:mod:`subenv_agents.train`,
  :mod:`subenv_agents.config`);
- :mod:`subenv_agents.curriculum` moves the training speeds down through the critical speed as the agent
  succeeds;
- :func:`load_agent` loads a model with its normalisation statistics in one call;
- the models shipped in ``subenv_agents/models/<name>/`` (each with its ``MODEL_CARD.md``) are
  controllers of :mod:`subenv.evaluation` under ``<name>``, declared as ``subenv.controllers``
  entry points (:mod:`subenv_agents.shipped`), so the comparison shows them next to the baselines.

Needs the ``rl`` extra (stable-baselines3, torch, PyYAML). Without it ``subenv evaluate`` skips the
shipped models with a one-line note, and the rest of subenv works as before. (The name is
prefixed: other PyPI distributions install a top-level ``agents``.)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Final

__all__ = ["MODELS_DIR", "load_agent", "shipped_models"]

MODELS_DIR: Final = Path(__file__).parent / "models"
"""The shipped models: one folder each, with model.zip, vecnormalize.pkl, config.yml, MODEL_CARD.md."""


def shipped_models() -> dict[str, Path]:
    """The shipped models by name (their folder names), in name order."""
    if not MODELS_DIR.is_dir():
        return {}
    return {p.name: p for p in sorted(MODELS_DIR.iterdir()) if (p / "model.zip").is_file()}


def load_agent(path: str | Path, env: Any = None) -> Any:
    """:func:`subenv_agents.policy.load_agent` (imported on first use: it needs torch)."""
    from subenv_agents.policy import load_agent as _load

    return _load(path, env)
