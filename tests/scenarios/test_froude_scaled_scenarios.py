"""The shipped scenarios on a vehicle of another size: every episode Froude-scaled, so that the full-scale
SUBOFF flies the model's episodes (Riedel 1993 Ch. VI; subenv.vehicles.froude_scaled)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import subenv
from subenv.envs.config import DEPTH_BAND_M, DivePlaneConfig
from subenv.evaluation import evaluate
from subenv.scenarios import get_scenario
from subenv.vehicles import load_vehicle

MODEL, FULL = load_vehicle("suboff"), load_vehicle("suboff_fullscale")
RATIO = FULL.length_m / MODEL.length_m
KEYS = ("time_s", "depth_m", "pitch_rad", "heave_mps", "pitch_rate_radps", "speed_mps", "depth_command_m")
SCALES = np.array(
    [math.sqrt(RATIO), RATIO, 1.0, math.sqrt(RATIO), 1 / math.sqrt(RATIO), math.sqrt(RATIO), RATIO]
)


def _fly(env, steps: int) -> tuple[np.ndarray, list[float], str]:  # type: ignore[no-untyped-def]
    """A fixed command sequence (planes are angles: the same at any scale); the info's states and rewards."""
    commands = np.sin(np.arange(steps) / 7.0).astype(np.float32)
    _, info = env.reset(seed=7)
    rows, rewards = [[info[k] for k in KEYS]], []
    for a in commands:
        _, reward, terminated, truncated, info = env.step(np.array([a]))
        rows.append([info[k] for k in KEYS])
        rewards.append(float(reward))
        if terminated or truncated:
            break
    return np.array(rows), rewards, info["termination_reason"]


@pytest.mark.parametrize(
    "scenario",
    [
        "LowSpeed",
        "NearCritical",
        "BallastOffset",
        "PeriscopeDepth",
        "PeriscopeDepth-v1",
        "PeriscopeDepthWaves",
        "PeriscopeDepth-v2",
        "PeriscopeDepthWaves-v1",
    ],
)
def test_the_full_scale_boat_flies_the_models_episode_froude_scaled(scenario) -> None:  # type: ignore[no-untyped-def]
    """With the control period scaled too (dt x sqrt(lambda)), the full-scale episode is the model's in
    scaled units, step by step, with the same rewards and the same end. (NearCritical's heave-force
    disturbance keeps its 30 s time constant, which is not scaled: its draws match, not its states.)
    Near the surface this checks that the free surface's suction and the sea's forces scale as lambda^3
    (the suction as rho u^2 S^2 / h^2, the sea through its height and period)."""
    env_id = get_scenario(scenario).env_id
    model = gym.make(env_id, vehicle=MODEL)
    full = gym.make(env_id, vehicle=FULL, dt=0.5 * math.sqrt(RATIO))
    (a, rewards_a, end_a), (b, rewards_b, end_b) = _fly(model, 400), _fly(full, 400)
    assert len(a) == len(b) and end_a == end_b
    if scenario == "NearCritical":
        assert b[0] / SCALES == pytest.approx(a[0], rel=1e-12)  # the drawn start
        return
    assert b / SCALES == pytest.approx(a, rel=1e-7, abs=1e-12)
    assert rewards_b == pytest.approx(rewards_a, rel=1e-7, abs=1e-12)


def test_batched_resets_of_the_vector_env_scale_as_single_resets() -> None:
    """The vector env draws 4 or more resets of a one-loading scenario as arrays: scaled the same way,
    and its episodes (built on demand) say so."""
    envs = gym.make_vec("subenv/LowSpeed-v0", num_envs=4, vehicle=FULL)
    _, infos = envs.reset(seed=[0, 1, 2, 3])
    for i in range(4):
        single = gym.make("subenv/LowSpeed-v0", vehicle=FULL)
        _, info = single.reset(seed=i)
        assert [infos[k][i] for k in KEYS] == pytest.approx([info[k] for k in KEYS], rel=1e-15)
        assert envs.episodes[i] == single.unwrapped.episode


def test_on_the_reference_vehicle_nothing_is_scaled() -> None:
    draw = get_scenario("LowSpeed").sample(np.random.default_rng(0), MODEL.weight_N)
    assert draw.froude_scaled(1.0) is draw
    assert DivePlaneConfig(scenario="LowSpeed").max_depth_error_m == DEPTH_BAND_M
    assert DivePlaneConfig(scenario="LowSpeed", vehicle=FULL).max_depth_error_m == pytest.approx(
        DEPTH_BAND_M * RATIO
    )
    assert (
        DivePlaneConfig(scenario="LowSpeed", vehicle=FULL, max_depth_error_m=30.0).max_depth_error_m == 30.0
    )
    with pytest.raises(ValueError, match=r"length_ratio=0 is invalid: must be a finite number > 0"):
        draw.froude_scaled(0)


@pytest.mark.parametrize("vehicle", subenv.available_vehicles())
@pytest.mark.parametrize("env_id", subenv.env_ids())
def test_every_scenario_runs_on_every_shipped_vehicle(env_id, vehicle) -> None:  # type: ignore[no-untyped-def]
    env = gym.make(env_id, vehicle=vehicle)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    for _ in range(5):
        obs, reward, *_ = env.step(env.action_space.sample())
        assert np.isfinite(reward) and env.observation_space.contains(obs)


def test_the_harness_runs_the_scaled_episodes_to_their_scaled_end() -> None:
    """The id's step limit is the model's episode's; the harness scales it with the durations."""
    (result,) = evaluate(["thesis"], ["LowSpeed"], episodes=1, progress=False, vehicle=FULL)
    assert result.metrics.duration_s == pytest.approx(600.0 * math.sqrt(RATIO), abs=0.5)
