"""The winnable-episode classifier: depth-holding trims with both plane pairs free, on constructed
loadings."""

from __future__ import annotations

import numpy as np
import pytest

from subenv.analysis import equilibria
from subenv.analysis.winnable import depth_holding_trim, winnable
from subenv.dynamics import derivatives, model_params

MAX_PITCH_RAD = 0.6  # the environments' default pitch limit


def _residual(vehicle, trim) -> np.ndarray:
    """(theta_dot, w_dot, q_dot, Z_dot) at the trim: all zero for a depth-holding steady state."""
    state = np.array([trim.pitch_rad, trim.heave_mps, 0.0, 10.0])
    return derivatives(state, trim.speed_mps, trim.stern_rad, trim.bow_rad, model_params(vehicle))


def test_a_neutral_boat_trims_level_with_the_planes_at_zero(suboff):
    for u in (0.2, 0.578, 1.5):
        trim = depth_holding_trim(suboff, u, MAX_PITCH_RAD)
        assert (
            trim.exists and abs(trim.pitch_rad) < 1e-9 and max(abs(trim.stern_rad), abs(trim.bow_rad)) < 1e-9
        )
        assert trim.plane_margin_rad == pytest.approx(suboff.planes.limit_rad)


@pytest.mark.parametrize(
    "loading, speed, expected",
    [
        ({"excess_buoyancy_N": 50.0}, 0.3, False),  # suction far beyond what the planes lift at 0.3 m/s
        ({"excess_buoyancy_N": 2.0}, 1.0, True),
        ({"x_GB_m": 3e-3}, 0.45, False),  # the largest ballast offset of BallastOffset, near u_cr
        ({"x_GB_m": -3e-3}, 0.45, False),
        ({"x_GB_m": 3e-3}, 0.9, True),
        ({"x_GB_m": 0.5e-3}, 0.45, True),
    ],
)
def test_loadings_with_and_without_a_trim(suboff, loading, speed, expected):
    vehicle = suboff.variant(**loading)
    trim = depth_holding_trim(vehicle, speed, MAX_PITCH_RAD)
    assert trim.exists is expected and winnable(vehicle, [speed], MAX_PITCH_RAD) is expected
    assert (trim.plane_margin_rad >= 0) is expected and abs(trim.pitch_rad) < MAX_PITCH_RAD
    # Found or not, it is a steady state that holds depth (with its planes, beyond the limit if need be).
    np.testing.assert_allclose(_residual(vehicle, trim), 0.0, atol=1e-10)


def test_a_dual_control_trim_is_one_of_its_trims(suboff):
    """Each allocation alpha is one line through the plane square: an unsaturated depth-holding equilibrium of
    dual control (Riedel 1993 eq. 4.3) within the limit means a trim exists, needing no more plane."""
    vehicle = suboff.variant(x_GB_m=1e-3)
    for u in (0.45, 0.9):
        held = [e for e in equilibria(vehicle, u, 0.0) if not e.saturated]
        assert held
        trim = depth_holding_trim(vehicle, u, MAX_PITCH_RAD)
        assert trim.exists
        assert max(abs(trim.stern_rad), abs(trim.bow_rad)) <= min(abs(e.plane_rad) for e in held) + 1e-9


def test_winnable_needs_a_trim_at_every_speed(suboff):
    vehicle = suboff.variant(x_GB_m=3e-3)
    assert winnable(vehicle, [0.9], MAX_PITCH_RAD) and not winnable(vehicle, [0.9, 0.45], MAX_PITCH_RAD)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"speed_mps": 0.0}, r"speed_mps=0.0 is invalid: must be a finite number > 0"),
        ({"max_pitch_rad": 2.0}, r"max_pitch_rad=2.0 is invalid: must be a number in \(0, pi/2\)"),
    ],
)
def test_invalid_arguments_name_the_parameter(suboff, kwargs, match):
    with pytest.raises(ValueError, match=match):
        depth_holding_trim(suboff, **({"speed_mps": 1.0, "max_pitch_rad": MAX_PITCH_RAD} | kwargs))
