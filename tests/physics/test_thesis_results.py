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
from subenv.analysis import critical_froude, critical_speed, linear_model
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
    obs, info = env.reset(seed=0, options={"speed": fps_to_mps(speed_fps), "depth_command": 50.0,
                                           "initial_state": (0.0, 0.0, 0.0, 50.0 + FOOT_M)})
    depth_errors = []
    while True:
        x = np.array([obs[1], obs[2], obs[3], obs[0]])  # theta, w, q, depth error
        action = np.array([np.clip(-(gain @ x) / env.plane_limit_rad, -1.0, 1.0)], dtype=np.float32)
        obs, _, terminated, truncated, info = env.step(action)
        depth_errors.append(info["depth_error_m"])
        if terminated or truncated:
            break
    assert info["termination_reason"] == ""
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


def test_just_below_critical_the_depth_is_lost_on_the_unsaturated_branch():
    """At 1.85 fps (below u_cr = 1.8979 fps) the boat settles pitched, away from the ordered depth."""
    info = _fly_thesis_controller(1.85)
    assert abs(info["depth_error_m"]) > 1.0
    assert math.degrees(info["pitch_rad"]) > 2.0
    assert abs(info["stern_plane_rad"]) < 0.4  # planes not yet at their limit
