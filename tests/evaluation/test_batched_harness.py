"""The batched harness gives every episode the result of the one-episode-at-a-time harness it replaced.

The reference is ``run_episodes(..., batched=False)``: one ``gym.make`` environment, one episode at
a time, the controller's single-episode ``reset`` and ``act``, as the harness ran before batching
(and as it runs controllers that cannot batch). The batched harness steps ``gym.make_vec`` with one
sub-environment per episode and the controllers' ``reset_batch`` and ``act_batch``. The physics is
the same compiled step, and every baseline computes each row with elementwise operations only, so
the results must be equal bit for bit, trajectories included.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pytest

import subenv_baselines
from subenv.envs import OBSERVATION_NAMES
from subenv.evaluation import BatchController, Controller, EpisodeResult, make_controller, run_episodes
from subenv.vehicles import Vehicle

SCENARIOS = ("LowSpeed", "NearCritical", "SpeedTransient", "PeriscopeDepth", "BallastOffset")
SEEDS = range(10_004, 10_011)  # episodes of the default comparison; in PeriscopeDepth every baseline broaches
# or leaves its depth in some of them (10010 for all), early, while the others run on


def _nan(value: object) -> bool:
    return isinstance(value, float) and math.isnan(value)


def assert_same(ours: Any, reference: Any) -> None:
    """Equal dataclasses, field by field: arrays bit for bit, NaN equal to NaN."""
    for f in dataclasses.fields(reference):
        a, b = getattr(ours, f.name), getattr(reference, f.name)
        if dataclasses.is_dataclass(b):
            assert_same(a, b)
        elif isinstance(b, np.ndarray):
            assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), f.name
        else:
            assert a == b or (_nan(a) and _nan(b)), (f.name, a, b)


def assert_batched_as_one_at_a_time(make: Any, scenario: str, **kwargs: Any) -> list[EpisodeResult]:
    """Batched results of a fresh ``make()`` equal, field by field, those of another run one at a time."""
    reference = run_episodes(make(), scenario, SEEDS, keep_trajectories=len(SEEDS), batched=False, **kwargs)
    results = run_episodes(make(), scenario, SEEDS, keep_trajectories=len(SEEDS), **kwargs)
    assert [(r.seed, r.episode) for r in results] == [(s, i) for i, s in enumerate(SEEDS)]
    for result, expected in zip(results, reference, strict=True):
        assert result.trajectory is not None and expected.trajectory is not None
        assert_same(result, expected)
        assert_same(result.trajectory, expected.trajectory)
    return results


@pytest.mark.parametrize("name", list(subenv_baselines.CONTROLLERS))
def test_every_baseline_gets_the_one_at_a_time_results_bit_for_bit(name: str) -> None:
    assert isinstance(make_controller(name), BatchController)
    lengths = [
        tuple(r.steps for r in assert_batched_as_one_at_a_time(lambda: make_controller(name), scenario))
        for scenario in SCENARIOS
    ]
    # Some batch had episodes of different lengths: the ended ones were left behind correctly.
    assert any(len(set(steps)) > 1 for steps in lengths)


def test_max_duration_truncates_batched_episodes_as_one_at_a_time() -> None:
    results = assert_batched_as_one_at_a_time(lambda: make_controller("lqr"), "Nominal", max_duration_s=30.0)
    assert all(r.steps == 60 and r.episode_duration_s == 30.0 for r in results)


class SingleOnly:
    """A controller without batch methods, with a per-episode state: the steps since its reset."""

    name = "single_only"
    control = "dual"
    alpha = 0.0

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        self.steps = 0

    def act(self, observation: np.ndarray) -> np.ndarray:
        self.steps += 1
        return np.array([0.5 if self.steps < 40 else -0.2 * float(observation[0])], dtype=np.float32)


def test_a_controller_that_cannot_batch_runs_one_episode_at_a_time() -> None:
    controller: Controller = SingleOnly()
    assert not isinstance(controller, BatchController)
    results = run_episodes(controller, "LowSpeed", SEEDS, keep_trajectories=len(SEEDS))
    for result in results:  # every episode started from its own reset: 39 steps at +0.5, then feedback
        assert result.trajectory is not None
        actions = result.trajectory.actions[:, 0]
        assert np.all(actions[:39] == 0.5) and np.all(actions[39:] != 0.5)


@pytest.mark.parametrize("name", ["lqr", "reversal_aware"])
def test_a_batch_of_the_wrong_size_is_refused(name: str, suboff: Vehicle) -> None:
    controller = make_controller(name)
    assert isinstance(controller, BatchController)
    controller.reset_batch([{"speed_mps": 0.4}, {"speed_mps": 1.0}], suboff)
    n_obs = len(OBSERVATION_NAMES)
    assert controller.act_batch(np.zeros((2, n_obs), dtype=np.float32)).shape == (
        2,
        1 if name == "lqr" else 2,
    )
    with pytest.raises(
        ValueError, match=rf"observations has shape \(3, {n_obs}\): must have shape \(2, obs_dim\)"
    ):
        controller.act_batch(np.zeros((3, n_obs), dtype=np.float32))


@pytest.mark.parametrize("name", ["ppo", "sac"])
def test_the_shipped_agents_get_the_one_at_a_time_results(name: str) -> None:
    pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")
    from subenv_agents import shipped_models
    from subenv_agents.controller import AgentController

    folder = shipped_models()[name]
    assert isinstance(AgentController(folder), BatchController)
    for scenario in ("LowSpeed", "BallastOffset"):
        assert_batched_as_one_at_a_time(lambda: AgentController(folder), scenario)
