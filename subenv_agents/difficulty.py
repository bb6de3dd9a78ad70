"""A curriculum the analysis places: training episodes sampled by how hard the physics makes them.

The JAX PPO (:mod:`subenv_agents.jax_ppo`) resets from a table of episodes drawn ahead
(:func:`subenv.jax.make`). Each row's difficulty is known before training from its draw alone
(:func:`subenv.analysis.curriculum.episode_difficulty`): its distance to the critical speed
|u/u_cr - 1| at the speed it holds at its end (near u_cr the planes hardly move depth; Riedel 1993
Ch. III) and the trim load, the fraction of the plane limit the depth-holding trim of its loading needs
(a ballast offset, excess buoyancy, the surface's suction; Ch. IV-V), and so whether it can be won at all.

:func:`curriculum_weights` turns them into the probabilities training resets with: no episode that
cannot be won (no trim within the plane limits: a loss there teaches nothing), and of the others a
share drawn uniformly and the rest in proportion to their hardness, :func:`hardness` (the trim load plus
the nearness to u_cr). ``uniform`` is the environment's own sampling, every row alike.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Final

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding

from subenv import _validation as check
from subenv.analysis.curriculum import EpisodeDifficulty, episode_difficulty
from subenv.dynamics.free_surface import NO_FREE_SURFACE
from subenv.envs.config import DivePlaneConfig
from subenv.envs.episodes import Loadings, draw_episode
from subenv.evaluation.classify import EpisodeDraw

__all__ = ["CURRICULA", "NEAR_CRITICAL", "curriculum_weights", "hardness", "table_difficulties"]

CURRICULA: Final = ("uniform", "difficulty")
"""How training resets pick their episodes: every row of the table alike, or by :func:`curriculum_weights`."""

NEAR_CRITICAL: Final = 0.5
"""|u/u_cr - 1| below which an episode counts as near the critical speed, the harder the nearer: the band
in which the analysis's controllers lose depth control (``lqr``'s failures at 0.85-1.15 u_cr,
NearCritical's range; the allocation switch of ``reversal_aware`` keeps a 22% controllability margin)."""


def table_difficulties(
    env_id: str, env_kwargs: Mapping[str, Any], seeds: Sequence[int]
) -> list[EpisodeDifficulty]:
    """The difficulty of every episode of a table of ``env_id``'s episodes: row ``k`` is the episode of
    ``reset(seed=seeds[k])`` (as :func:`subenv.envs.episodes.episode_table` draws it, from the same
    generator), judged at the speed it holds at its end and, near the surface, at its ordered depth with
    its suction and sea (as :func:`subenv.evaluation.classify.winnable_episode` judges it)."""
    config = DivePlaneConfig(**{**gym.spec(env_id).kwargs, **env_kwargs})
    loadings = Loadings(config)
    out = []
    for k, seed in enumerate(seeds):
        rng, _ = seeding.np_random(check.integer(f"seeds[{k}]", seed, 0))
        episode, loading, _, _ = draw_episode(config, rng, loadings)
        draw = EpisodeDraw(
            config.scenario.name,
            seed,
            loading.vehicle,
            episode,
            loading.critical_speed_mps,
            config.max_pitch_rad,
        )
        surface = episode.free_surface is not None or episode.sea_state is not None
        out.append(
            episode_difficulty(
                loading.vehicle,
                draw.final_speed_mps,
                loading.critical_speed_mps,
                config.max_pitch_rad,
                draw.depth_command_m if surface else 0.0,
                episode.free_surface or NO_FREE_SURFACE,
                episode.sea_state,
            )
        )
    return out


def hardness(difficulty: EpisodeDifficulty) -> float:
    """The trim load (0: a neutral loading, 1: the trim needs the whole plane limit) plus the nearness to
    u_cr (1 at u_cr, 0 from :data:`NEAR_CRITICAL` away), in [0, 2] for a winnable episode."""
    near = 1.0 - min(difficulty.critical_distance / NEAR_CRITICAL, 1.0)
    return max(difficulty.trim_load, 0.0) + near


def curriculum_weights(difficulties: Sequence[EpisodeDifficulty], share: float) -> np.ndarray:
    """The probability of each row of the table at a reset: 0 for an episode that cannot be won; of the
    winnable ones, ``1 - share`` of the resets uniform and ``share`` in proportion to :func:`hardness`.

    Raises ``ValueError`` for a ``share`` outside [0, 1] or a table without a winnable episode.
    """
    check.require("share", share, check.is_finite(share) and 0.0 <= share <= 1.0, "a number in [0, 1]")
    winnable = np.array([d.winnable for d in difficulties], dtype=bool)
    if not winnable.any():
        raise ValueError(
            f"difficulties={len(difficulties)} episodes is invalid: none of them can be won (no trim within "
            "the plane limits), so none can be trained on"
        )
    hard = np.where(winnable, [hardness(d) for d in difficulties], 0.0)
    uniform = winnable / winnable.sum()
    by_hardness = hard / hard.sum() if hard.sum() > 0 else uniform
    weights = (1.0 - share) * uniform + share * by_hardness
    return weights / weights.sum()
