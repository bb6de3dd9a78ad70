"""Held-out evaluation: speeds, loadings and conditions outside everything the agents trained on.

The shipped agents train on ``subenv/Mixed-v0``: the six base scenarios, speeds of 0.3-2.6 u_cr
(and the design speed, 2.63 u_cr), metacentric height z_GB scaled by 0.9-1.1, ballast offsets
|x_GB| <= 3 mm, excess buoyancy <= 0.1% of the weight, hull drag C_D in 0.2-0.4, a 0.3 N
heave-force disturbance. The scenarios below lie outside those ranges, one axis at a time,
noise-free and undisturbed like the evaluation suites; they are not registered (nobody should
train on them) and run through the same harness (:func:`subenv.evaluation.run_episodes`). The
registered ``Randomized`` scenario (``subenv/DivePlane-v0``: z_GB 0.8-1.25, C_D 0-0.6, a 2 N
disturbance) is held out too, as harder conditions.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

from subenv.evaluation import Controller, run_episodes
from subenv.evaluation.rollout import EpisodeResult
from subenv.evaluation.suites import DEFAULT_SEED
from subenv.scenarios import Scenario, get_scenario

__all__ = ["HELD_OUT", "evaluate_held_out"]

_COMMON: Final = {
    "depth_command_m": (8.0, 15.0),
    "initial_depth_offset_m": (-2.0, 2.0),
    "initial_pitch_rad": (-0.05, 0.05),
    "duration_s": 600.0,
}

HELD_OUT: Final = (
    Scenario(
        name="HeldOutVerySlow",
        description="0.15-0.3 u_cr: slower than any training episode.",
        speed_ratio=(0.15, 0.3),
        **_COMMON,
    ),
    Scenario(
        name="HeldOutFast",
        description="3-4 u_cr: faster than any training episode.",
        speed_ratio=(3.0, 4.0),
        **_COMMON,
    ),
    Scenario(
        name="HeldOutLowStability",
        description="z_GB scaled by 0.6-0.8 (trained: 0.9-1.1), 0.3-1.15 u_cr.",
        speed_ratio=(0.3, 1.15),
        z_GB_scale=(0.6, 0.8),
        **_COMMON,
    ),
    Scenario(
        name="HeldOutHighStability",
        description="z_GB scaled by 1.25-1.6 (trained: 0.9-1.1), 0.3-1.15 u_cr.",
        speed_ratio=(0.3, 1.15),
        z_GB_scale=(1.25, 1.6),
        **_COMMON,
    ),
    Scenario(
        name="HeldOutBallast",
        description="|x_GB| 3-5 mm (trained: <= 3 mm), 0.6-2 u_cr.",
        speed_ratio=(0.6, 2.0),
        x_GB_m=(3e-3, 5e-3),
        x_GB_sign_random=True,
        **_COMMON,
    ),
    get_scenario("Randomized"),
)
"""The held-out scenarios, one axis outside the training ranges each, then ``Randomized``."""


def evaluate_held_out(
    controllers: Sequence[Controller],
    episodes: int = 50,
    seed: int = DEFAULT_SEED,
    scenarios: Sequence[Scenario] = HELD_OUT,
) -> list[EpisodeResult]:
    """Every controller on the same ``episodes`` seeded episodes (``seed + i``) of every held-out scenario."""
    return [
        result
        for controller in controllers
        for scenario in scenarios
        for result in run_episodes(controller, scenario, range(seed, seed + episodes))
    ]
