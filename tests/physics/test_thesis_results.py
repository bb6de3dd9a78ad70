"""Published results of Riedel (1993), recomputed through the package.

The thesis's simulations (Ch. III.A) use C_D = 0, W = B, x_G = x_B and planes limited to
+-0.4 rad; its controller is full-state feedback placed at 5 fps (eq. 2.98).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import place_poles

import subenv
from subenv import get_scenario, load_vehicle
from subenv.analysis import critical_froude, critical_speed, equilibria, linear_model
from subenv.units import FOOT_M, fps_to_mps, mps_to_fps

# Published numbers (validation targets; never used to compute anything).
PUBLISHED_GAIN_FT = np.array([-0.9917, -0.8333, -0.6026, 0.0351])  # eq. 2.98, (theta, w, q, Z), ft units
PUBLISHED_UCR_FPS = 1.8979  # eq. 3.9, alpha = 0
THESIS_POLES = [-0.3, -0.31, -0.32, -0.33]


def _to_si(gain_ft: np.ndarray) -> np.ndarray:
    """delta = -K x: gains on w [per ft/s] and Z [per ft] become per m/s and per m."""
    return gain_ft / np.array([1.0, FOOT_M, 1.0, FOOT_M])


def test_pole_placement_at_5_fps_reproduces_eq_2_98(suboff):
    lm = linear_model(suboff, fps_to_mps(5.0), alpha=0.0)
    gain = place_poles(lm.A, lm.B[:, None], THESIS_POLES).gain_matrix[0]
    np.testing.assert_allclose(gain, _to_si(PUBLISHED_GAIN_FT), rtol=1e-3, atol=1e-4 / FOOT_M)
    eig = np.sort(np.linalg.eigvals(lm.A - np.outer(lm.B, gain)).real)
    np.testing.assert_allclose(eig, sorted(THESIS_POLES), atol=1e-9)


def test_critical_speed_reproduces_eq_3_9(suboff):
    assert mps_to_fps(critical_speed(suboff)) == pytest.approx(PUBLISHED_UCR_FPS, abs=5e-5)
    # Fig. 3-9: about 0.81 (alpha = -1) to 1.22 (alpha = +1).
    assert critical_froude(suboff, -1.0) == pytest.approx(0.81, abs=0.01)
    assert critical_froude(suboff, 1.0) == pytest.approx(1.22, abs=0.01)


def _fly_thesis_controller(speed_fps: float, duration_s: float = 3000.0) -> dict:
    """Thesis gains of eq. 2.98 in SI, through the environment, from 1 ft below the ordered depth
    (the thesis's initial condition x0 = (0, 0, 0, 1 ft), program THESIS1.M)."""
    vehicle = load_vehicle("suboff").variant(crossflow_drag=0.0)
    scenario = get_scenario("Nominal").replace(name="ThesisRun", duration_s=duration_s)
    env = subenv.DivePlaneEnv(scenario=scenario, vehicle=vehicle, max_depth_error_m=1e4)
    gain = _to_si(PUBLISHED_GAIN_FT)
    obs, info = env.reset(
        seed=0,
        options={
            "speed": fps_to_mps(speed_fps),
            "depth_command": 50.0,
            "initial_state": (0.0, 0.0, 0.0, 50.0 + FOOT_M),
        },
    )
    times, depth_errors = [], []
    while True:
        x = np.array([obs[1], obs[2], obs[3], obs[0]])  # theta, w, q, depth error
        action = np.array([np.clip(-(gain @ x) / env.plane_limit_rad, -1.0, 1.0)], dtype=np.float32)
        obs, _, terminated, truncated, info = env.step(action)
        times.append(info["time_s"])
        depth_errors.append(info["depth_error_m"])
        if terminated or truncated:
            break
    assert info["termination_reason"] == ""
    info["times_s"] = np.array(times)
    info["depth_errors"] = np.array(depth_errors)
    return info


def test_thesis_controller_holds_depth_at_design_speed():
    info = _fly_thesis_controller(5.0, duration_s=600.0)
    assert abs(info["depth_error_m"]) < 1e-4
    assert abs(info["pitch_rad"]) < 1e-5
    assert abs(info["stern_plane_rad"]) < 1e-5


@pytest.mark.parametrize("speed_fps", [1.7, 1.8])
def test_below_critical_thesis_controller_settles_pitched_with_planes_pinned(speed_fps):
    """Ch. III.A, Fig. 3-3: a constant pitch near 8 deg, planes at 23 deg, depth not recovered."""
    info = _fly_thesis_controller(speed_fps)
    pitch_deg = math.degrees(info["pitch_rad"])
    assert 7.0 < pitch_deg < 9.0
    assert abs(info["stern_plane_rad"]) == pytest.approx(0.4)  # pinned at the limit
    assert abs(info["pitch_rate_radps"]) < 1e-6  # steady pitch
    errors = info["depth_errors"]
    # Sinking steadily, not returning: the depth error keeps growing at a constant rate.
    rate_late = (errors[-1] - errors[-201]) / 100.0
    rate_earlier = (errors[-201] - errors[-401]) / 100.0
    assert errors[-1] > 10.0
    assert rate_late > 1e-3 and rate_late == pytest.approx(rate_earlier, rel=1e-3)


def test_just_below_critical_no_unsaturated_pitched_state_exists_and_the_boat_ends_saturated(suboff):
    """At 1.85 fps, just below u_cr = 1.8979 fps, the depth-holding pitched pair (eqs 3.17, 3.21)
    needs more plane than the 0.4 rad limit, so the only pitched steady states are the saturated
    ones (eq. 4.42). Level flight is unstable, but barely: this close to u_cr its growth rate is
    small, and the boat is still leaving it at 3000 s. By 6000 s it has reached the saturated state
    of its side, planes pinned, and loses depth at that state's drift rate.
    """
    vehicle = suboff.variant(crossflow_drag=0.0)
    speed = fps_to_mps(1.85)
    limit = vehicle.planes.limit_rad
    # With unlimited planes the pitched pair exists, at plane angles beyond the limit.
    pitched_free = [e for e in equilibria(vehicle, speed, saturation=False) if e.pitch_rad != 0.0]
    assert len(pitched_free) == 2 and all(abs(e.plane_rad) > limit for e in pitched_free)
    states = equilibria(vehicle, speed)
    level = [e for e in states if not e.saturated]
    saturated = [e for e in states if e.saturated]
    assert [e.pitch_rad for e in level] == [0.0] and not level[0].stable
    assert len(saturated) == 2 and all(e.stable for e in saturated)
    assert saturated[0].pitch_rad == pytest.approx(-saturated[1].pitch_rad)  # the symmetric pitchfork

    info = _fly_thesis_controller(1.85, duration_s=6000.0)
    times, errors = info["times_s"], info["depth_errors"]
    # Up to 3000 s the boat is still leaving level flight, at the rate of its one unstable
    # eigenvalue (about 1 / 1500 s).
    growth_per_s = max(level[0].eigenvalues.real)
    e_1000, e_3000 = errors[times == 1000.0][0], errors[times == 3000.0][0]
    assert math.log(e_3000 / e_1000) / 2000.0 == pytest.approx(growth_per_s, rel=0.02)
    # It ends on the saturated state of its side.
    reached = min(saturated, key=lambda e: abs(e.pitch_rad - info["pitch_rad"]))
    assert info["pitch_rad"] == pytest.approx(reached.pitch_rad, abs=1e-9)
    assert info["heave_mps"] == pytest.approx(reached.heave_mps, abs=1e-9)
    assert info["stern_plane_rad"] == pytest.approx(reached.plane_rad, abs=1e-12)  # pinned at the limit
    assert abs(info["pitch_rate_radps"]) < 1e-9  # steady pitch
    # Depth lost: the error grows at the saturated state's drift rate.
    rate_late = (errors[-1] - errors[times == 5500.0][0]) / (times[-1] - 5500.0)
    assert rate_late == pytest.approx(reached.depth_rate_mps, rel=1e-6)
    assert abs(info["depth_error_m"]) > 1.0
