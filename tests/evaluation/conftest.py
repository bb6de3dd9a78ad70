"""Fixtures of the evaluation tests."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest

from subenv.evaluation import DEFAULT_SEED, Controller, evaluate, make_controller
from subenv.evaluation.metrics import episode_metrics
from subenv.evaluation.rollout import EpisodeResult


@pytest.fixture
def make_result() -> Callable[..., EpisodeResult]:
    """A hand-made EpisodeResult: 120 s at the ordered depth (success) or 2 m off it (steady offset)."""

    def _result(
        controller: str, scenario: str, episode: int, success: bool, iae: float = 1.0
    ) -> EpisodeResult:
        t = np.arange(0.0, 121.0, 1.0)
        e = np.full_like(t, 0.0 if success else 2.0)
        e[0] = iae  # only to vary the IAE a little
        zeros = np.zeros_like(t)
        metrics = episode_metrics(
            t, e, zeros, zeros, zeros, zeros, termination_reason="", plane_limit_rad=0.4
        )
        return EpisodeResult(
            controller=controller,
            scenario=scenario,
            episode=episode,
            seed=100 + episode,
            control="dual",
            alpha=0.0,
            initial_speed_mps=0.4,
            final_speed_mps=0.4,
            critical_speed_mps=0.5785,
            depth_command_m=10.0,
            initial_depth_error_m=float(e[0]),
            episode_duration_s=120.0,
            steps=120,
            metrics=metrics,
        )

    return _result


@dataclass(frozen=True)
class SmallRun:
    """Results of a small real evaluation, and the controllers that produced them."""

    controllers: dict[str, Controller]
    results: list[EpisodeResult]


@pytest.fixture(scope="session")
def small_run() -> SmallRun:
    """``thesis`` and ``reversal_aware`` on four scenarios, 4 episodes each, no trajectories kept (a few
    seconds). The seeds (10003-10006) give the thesis controller every kind of failure in few episodes:
    wrong branch (on BallastOffset two that then broach), broached, steady offset, unsettled."""
    controllers = {name: make_controller(name) for name in ("thesis", "reversal_aware")}
    scenarios = ["LowSpeed", "PeriscopeDepth", "SpeedTransient", "BallastOffset"]
    results = evaluate(
        list(controllers.values()),
        scenarios,
        episodes=4,
        seed=DEFAULT_SEED + 3,
        progress=False,
        keep_trajectories=0,
    )
    return SmallRun(controllers, results)
