"""The curriculum the analysis places: each training episode's difficulty from its draw, and the reset
probabilities made of it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from subenv.analysis import depth_holding_trim, winnable
from subenv.analysis.curriculum import EpisodeDifficulty, episode_difficulty
from subenv.envs.episodes import episode_table
from subenv_agents.difficulty import NEAR_CRITICAL, curriculum_weights, hardness, table_difficulties

KWARGS = {"control": "independent"}


@pytest.fixture(scope="module")
def ballast():
    """The difficulties of 40 BallastOffset episodes (seeds 0-39), and their environments' loadings."""
    seeds = range(40)
    difficulties = table_difficulties("subenv/BallastOffset-v0", KWARGS, seeds)
    env = gym.make("subenv/BallastOffset-v0", **KWARGS)
    loadings = []
    for seed in seeds:
        _, info = env.reset(seed=seed)
        loadings.append((env.unwrapped.vehicle, info["speed_mps"], info["critical_speed_mps"]))
    return difficulties, loadings, env.unwrapped.config


def test_an_episodes_difficulty_is_the_analysis_of_the_episode_the_environment_plays(ballast):
    difficulties, loadings, config = ballast
    for d, (vehicle, speed, ucr) in zip(difficulties, loadings, strict=True):
        trim = depth_holding_trim(vehicle, speed, config.max_pitch_rad)
        assert d.speed_ratio == pytest.approx(speed / ucr, rel=1e-12)
        assert d.trim_margin_rad == pytest.approx(trim.plane_margin_rad, abs=1e-12)
        assert d.winnable == winnable(vehicle, (speed,), config.max_pitch_rad)
        assert d.trim_load == pytest.approx(1.0 - trim.plane_margin_rad / vehicle.planes.limit_rad)
    # BallastOffset's larger offsets at its lower speeds cannot be held: both kinds are among them
    assert {d.winnable for d in difficulties} == {True, False}


def test_a_neutral_loading_needs_no_trim_and_a_transient_is_judged_at_its_final_speed():
    (transient,) = table_difficulties("subenv/SpeedTransient-v0", KWARGS, [3])
    env = gym.make("subenv/SpeedTransient-v0", **KWARGS)
    episodes, _, _ = episode_table(env.unwrapped.config, [3])
    final_mps = episodes["knot_speed_mps"][0][episodes["n_knots"][0] - 1]
    assert transient.speed_ratio == pytest.approx(final_mps / episodes["critical_speed_mps"][0], rel=1e-12)
    assert 0.4 <= transient.speed_ratio <= 0.7  # (SpeedTransient ends at 0.4-0.7 u_cr; it starts at 2-2.6)
    assert transient.trim_load == pytest.approx(0.0, abs=1e-6) and transient.winnable


def test_hardness_is_the_trim_load_plus_the_nearness_to_the_critical_speed():
    limit = 0.4
    at_critical = EpisodeDifficulty(speed_ratio=1.0, trim_margin_rad=limit, plane_limit_rad=limit)
    far = EpisodeDifficulty(speed_ratio=1.0 + 2 * NEAR_CRITICAL, trim_margin_rad=limit, plane_limit_rad=limit)
    loaded = EpisodeDifficulty(speed_ratio=2.5, trim_margin_rad=0.1, plane_limit_rad=limit)
    assert (hardness(at_critical), hardness(far), hardness(loaded)) == pytest.approx((1.0, 0.0, 0.75))
    assert not EpisodeDifficulty(1.0, -0.01, limit).winnable


def test_curriculum_weights_leave_out_what_cannot_be_won_and_share_the_rest(ballast):
    difficulties, _, _ = ballast
    can = np.array([d.winnable for d in difficulties])
    hard = np.array([hardness(d) for d in difficulties])
    uniform = curriculum_weights(difficulties, 0.0)
    assert np.all(uniform[~can] == 0.0) and np.allclose(uniform[can], 1.0 / can.sum())
    by_hardness = curriculum_weights(difficulties, 1.0)
    np.testing.assert_allclose(by_hardness[can], hard[can] / hard[can].sum())
    half = curriculum_weights(difficulties, 0.5)
    np.testing.assert_allclose(half, 0.5 * uniform + 0.5 * by_hardness)
    assert half.sum() == pytest.approx(1.0)
    with pytest.raises(ValueError, match=r"share=1\.5 is invalid"):
        curriculum_weights(difficulties, 1.5)
    with pytest.raises(ValueError, match="none of them can be won"):
        curriculum_weights([d for d in difficulties if not d.winnable], 0.5)


def test_episode_difficulty_refuses_a_loading_without_a_critical_speed(ballast):
    _, loadings, config = ballast
    vehicle, speed, _ = loadings[0]
    with pytest.raises(ValueError, match="critical_speed_mps=nan is invalid"):
        episode_difficulty(vehicle, speed, float("nan"), config.max_pitch_rad)
