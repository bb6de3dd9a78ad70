"""Fixtures of the evaluation tests."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

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
            controller=controller, scenario=scenario, episode=episode, seed=100 + episode, control="dual",
            alpha=0.0, initial_speed_mps=0.4, final_speed_mps=0.4, critical_speed_mps=0.5785,
            depth_command_m=10.0, initial_depth_error_m=float(e[0]), episode_duration_s=120.0, steps=120,
            metrics=metrics,
        )

    return _result
