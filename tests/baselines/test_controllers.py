"""The classical controllers: their designs, and their behaviour on every scenario class."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import subenv_baselines
from subenv.analysis import critical_speed, linear_model, place_gain
from subenv.evaluation import Controller, controller_names, make_controller
from subenv.units import FOOT_M
from subenv_baselines._common import GainSchedule
from subenv_baselines.lqr import lqi_gain
from subenv_baselines.reversal_aware import ReversalAware
from subenv_baselines.scheduled import GainScheduledPolePlacement
from subenv_baselines.thesis import ThesisPolePlacement

SCENARIOS = ["Nominal", "LowSpeed", "NearCritical", "SpeedTransient", "PeriscopeDepth", "BallastOffset"]
HOLD_S = 60.0
TOLERANCE_M = 0.5


def _episode(controller: Controller, scenario: str, seed: int, options: dict | None = None):
    env = gym.make(f"subenv/{scenario}-v0", control=controller.control, alpha=controller.alpha)
    obs, info = env.reset(seed=seed, options=options)
    controller.reset(info, env.unwrapped.base_vehicle)
    errors, planes = [], []
    while True:
        action = controller.act(obs)
        assert action.shape == env.action_space.shape and action.dtype == np.float32
        assert np.all(np.abs(action) <= 1.0) and np.all(np.isfinite(action))
        obs, _, terminated, truncated, info = env.step(action)
        errors.append(info["depth_error_m"])
        planes.append(info["stern_plane_rad"])
        if terminated or truncated:
            break
    hold = int(HOLD_S / env.unwrapped.dt)
    success = not terminated and bool(np.all(np.abs(errors[-hold:]) <= TOLERANCE_M))
    return success, info, np.array(errors), np.array(planes)


def test_all_four_are_registered_and_implement_the_protocol():
    assert {"thesis", "scheduled", "lqr", "reversal_aware"} <= set(controller_names())
    for name in subenv_baselines.CONTROLLERS:
        assert isinstance(make_controller(name), Controller)
    # The error names every registered controller (the shipped agents too, with the rl extra).
    with pytest.raises(ValueError, match=r"controller='pid' is unknown: must be one of \[") as error:
        make_controller("pid")
    assert all(f"'{name}'" in str(error.value) for name in controller_names())


def test_thesis_controller_designs_the_published_gains(suboff):
    controller = ThesisPolePlacement()
    controller.reset({"speed_mps": 1.524}, suboff)
    published_ft = np.array([-0.9917, -0.8333, -0.6026, 0.0351])  # eq. 2.98
    np.testing.assert_allclose(
        controller.gain, published_ft / np.array([1, FOOT_M, 1, FOOT_M]), rtol=1e-3, atol=1e-4 / FOOT_M
    )


def test_gain_schedule_interpolates_the_designs(suboff):
    schedule = GainSchedule.design([0.8, 1.0, 1.2], lambda u: place_gain(suboff, u))
    np.testing.assert_allclose(schedule.at(1.0), place_gain(suboff, 1.0))
    np.testing.assert_allclose(schedule.at(0.9), 0.5 * (place_gain(suboff, 0.8) + place_gain(suboff, 1.0)))
    np.testing.assert_allclose(schedule.at(5.0), place_gain(suboff, 1.2))  # held outside the grid
    with pytest.raises(ValueError, match="at least 2 ascending speeds"):
        GainSchedule.design([1.0, 0.5], lambda u: place_gain(suboff, u))


def test_gain_schedule_near_the_critical_speed(suboff):
    """Documented behaviour: the scheduled depth gain explodes at u_cr and reverses sign below it."""
    controller = GainScheduledPolePlacement()
    controller.reset({"speed_mps": 1.0}, suboff)
    ucr = critical_speed(suboff)
    schedule = controller.schedule
    below = schedule.gains[schedule.points < ucr][-1][3]
    above = schedule.gains[schedule.points > ucr][0][3]
    design = place_gain(suboff, 1.524)[3]
    assert below < 0 < above and min(abs(below), abs(above)) > 20 * abs(design)
    # Between the two straddling points the interpolated depth gain passes through zero.
    speeds = np.linspace(
        schedule.points[schedule.points < ucr][-1], schedule.points[schedule.points > ucr][0], 101
    )
    k4 = np.array([schedule.at(u)[3] for u in speeds])
    assert k4[0] < 0 < k4[-1] and np.all(np.diff(k4) > 0)  # crosses zero once: no depth feedback there


def test_lqi_gain_stabilises_the_augmented_model_on_both_sides_of_critical(suboff):
    ucr = critical_speed(suboff)
    for u in (0.3, 0.8 * ucr, 1.2 * ucr, 1.524):
        lm = linear_model(suboff, u)
        A = np.zeros((5, 5))
        A[:4, :4], A[4, 3] = lm.A, 1.0
        B = np.append(lm.B, 0.0)
        gain = lqi_gain(suboff, u, 0.0, 0.4)
        assert np.linalg.eigvals(A - np.outer(B, gain)).real.max() < 0
        assert np.sign(gain[3]) == (1 if u > ucr else -1)  # the depth gain reverses below u_cr


def test_reversal_aware_allocation_keeps_a_controllability_margin(suboff):
    controller = ReversalAware()
    controller.reset({"speed_mps": 1.0}, suboff)
    ucr = {a: critical_speed(suboff, a) for a in (-1.0, 1.0)}
    assert ucr[-1.0] < controller.switch_speed_mps < ucr[1.0]
    speeds = np.linspace(0.15, 2.0, 200)
    chosen_ucr = np.array([ucr[alpha] for alpha in controller._choose(speeds, None)])
    assert np.all(np.abs(1 - (speeds / chosen_ucr) ** 2) > 0.2)


@pytest.mark.parametrize("speed", [0.3, 0.45, 0.55, 0.6, 0.7, 1.0, 1.8])
@pytest.mark.parametrize("offset", [-2.0, 2.0])
def test_reversal_aware_changes_and_holds_depth_across_the_speed_range(speed, offset):
    success, info, errors, _ = _episode(
        ReversalAware(),
        "LowSpeed",
        0,
        {"speed": speed, "depth_command": 10.0, "initial_state": (0.0, 0.0, 0.0, 10.0 + offset)},
    )
    assert success, (speed, offset, errors[-1], info["termination_reason"])


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("name", list(subenv_baselines.CONTROLLERS))
def test_every_controller_on_every_scenario_class(name, scenario):
    outcomes = [_episode(make_controller(name), scenario, seed)[0] for seed in (0, 1)]
    expected = {
        # The physics: the fixed design fails below the critical speed, everything works at 5 fps,
        # and the reversal-aware design holds depth on the scenarios the issue names.
        ("thesis", "LowSpeed"): [False, False],
        ("thesis", "Nominal"): [True, True],
        ("reversal_aware", "LowSpeed"): [True, True],
        ("reversal_aware", "NearCritical"): [True, True],
        ("reversal_aware", "SpeedTransient"): [True, True],
    }.get((name, scenario))
    if expected is not None:
        assert outcomes == expected
    if name != "thesis" and scenario == "Nominal":
        assert all(outcomes)


def test_thesis_controller_below_critical_ends_on_the_wrong_branch():
    """The thesis's failure mode (Ch. III.A): planes pinned, steady pitch, depth drifting."""
    success, info, _, planes = _episode(ThesisPolePlacement(), "LowSpeed", 3)
    assert not success
    last = planes[-120:]
    assert np.mean(np.abs(last) >= 0.399) > 0.9 or info["termination_reason"] == "broached"
