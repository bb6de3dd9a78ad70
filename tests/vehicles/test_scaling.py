"""Froude scaling (Riedel 1993 Ch. VI): what scales how, the critical speed's sqrt(lambda) law, equal
Froude numbers, time scales, the full-scale SUBOFF file, and bad ratios refused."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from subenv import load_vehicle
from subenv.analysis.critical import critical_froude, critical_speed
from subenv.analysis.design import thesis_gain
from subenv.analysis.equilibria import equilibria
from subenv.analysis.linear import linear_model
from subenv.vehicles import Vehicle, available_vehicles, froude_factor, froude_scaled
from subenv.vehicles.fullscale import (
    SUBOFF_FULLSCALE_LENGTH_RATIO,
    SUBOFF_FULLSCALE_NAME,
    suboff_fullscale,
    suboff_fullscale_toml,
)
from subenv.vehicles.loader import vehicle_to_toml
from subenv.vehicles.vehicle import LENGTH_RANGE_M

# Scaling multiplies each quantity once by a power of lambda: a few ulps of rounding, nothing more.
SCALING_RTOL = 1e-12
# Equilibria: roots of eq. 4.3 by brentq (xtol 1e-14 rad) and eigenvalues of a central-difference
# Jacobian (step 1e-7 in SI state units, so cancellation near 1e-9 of the largest term).
EQUILIBRIUM_RTOL = 1e-6
# Ratios from a 0.5 m model to a 200 m boat, for a 4.26 m SUBOFF.
RATIOS = st.floats(min_value=0.12, max_value=47.0, allow_nan=False, allow_infinity=False)
ALLOCATIONS = (-1.0, -0.5, 0.0, 0.5, 1.0, "bow")


def _froude_length(vehicle: Vehicle, speed_mps: float) -> float:
    """u / sqrt(g L), the Froude number on the hull length."""
    return speed_mps / math.sqrt(vehicle.gravity_m_s2 * vehicle.length_m)


def _state_scale(ratio: float) -> np.ndarray:
    """x' = S x for x = (theta [rad], w [m/s], q [1/s], Z [m]) at equal Froude number."""
    return np.array(
        [1.0, froude_factor("speed", ratio), froude_factor("rate", ratio), froude_factor("length", ratio)]
    )


# --- the critical speed: Riedel (1993) eq. 3.9 and Ch. VI's claim ---------------------------------
@settings(max_examples=40)
@given(ratio=RATIOS)
def test_critical_speed_scales_with_sqrt_ratio_and_the_critical_froude_number_stays(suboff, ratio):
    scaled = froude_scaled(suboff, ratio)
    for alpha in ALLOCATIONS:
        u_model, u_scaled = critical_speed(suboff, alpha), critical_speed(scaled, alpha)
        assert u_scaled == pytest.approx(math.sqrt(ratio) * u_model, rel=SCALING_RTOL)
        # Both Froude numbers: on the metacentric height (eq. 4.25, the thesis's) and on the length.
        assert critical_froude(scaled, alpha) == pytest.approx(
            critical_froude(suboff, alpha), rel=SCALING_RTOL
        )
        assert _froude_length(scaled, u_scaled) == pytest.approx(
            _froude_length(suboff, u_model), rel=SCALING_RTOL
        )


def test_full_scale_suboff_has_the_thesis_critical_froude_numbers():
    """Fig. 3-9 (eq. 3.9: 0.8033 .. 1.2169 over alpha in [-1, 1]) and Fig. 5-4 (bow only: 2.05), at full
    scale."""
    full = load_vehicle(SUBOFF_FULLSCALE_NAME)
    assert critical_froude(full, -1.0) == pytest.approx(0.8033, abs=5e-5)
    assert critical_froude(full, 1.0) == pytest.approx(1.2169, abs=5e-5)
    assert critical_froude(full, "bow") == pytest.approx(2.05, abs=5e-3)
    # Published u_cr = 1.8979 fps for the model at alpha = 0: sqrt(24) times that at full scale.
    assert critical_speed(full, 0.0) == pytest.approx(math.sqrt(24.0) * 1.8979 * 0.3048, rel=1e-4)


# --- time scales: linear model and equilibria --------------------------------------------------------
@settings(max_examples=30)
@given(
    ratio=RATIOS,
    speed_over_critical=st.sampled_from([0.3, 0.8, 1.2, 2.5]),
    alpha=st.sampled_from(ALLOCATIONS),
)
def test_linear_model_at_equal_froude_number_is_the_same_system_in_scaled_time(
    suboff, ratio, speed_over_critical, alpha
):
    """A' = S A S^-1 / sqrt(lambda), B' = S B / sqrt(lambda): eigenvalues x 1/sqrt(lambda) (eqs 2.59-2.68)."""
    scaled = froude_scaled(suboff, ratio)
    u = speed_over_critical * critical_speed(suboff, alpha)
    model = linear_model(suboff, u, alpha)
    big = linear_model(scaled, froude_factor("speed", ratio) * u, alpha)
    S, rate = _state_scale(ratio), froude_factor("rate", ratio)
    np.testing.assert_allclose(big.A, rate * (S[:, None] * model.A / S[None, :]), rtol=SCALING_RTOL, atol=0)
    np.testing.assert_allclose(big.B, rate * S * model.B, rtol=SCALING_RTOL, atol=0)
    eig_model = np.sort_complex(np.linalg.eigvals(model.A))
    eig_big = np.sort_complex(np.linalg.eigvals(big.A))
    np.testing.assert_allclose(eig_big, rate * eig_model, rtol=1e-8, atol=1e-12 * np.abs(eig_model).max())


@pytest.mark.parametrize("speed_over_critical", [0.5, 0.95, 1.5])
@pytest.mark.parametrize("ratio", [0.25, 24.0])
def test_equilibria_at_equal_froude_number_correspond(suboff, ratio, speed_over_critical):
    """Closed-loop steady states (Ch. IV, with drag and a ballast offset) map onto each other: the same
    pitch and plane angle, heave x sqrt(lambda), depth offset x lambda, eigenvalues x 1/sqrt(lambda).
    The gain is the thesis's, carried to the scaled states: K' = K S^-1 gives the same command."""
    model = suboff.variant(x_GB_m=1e-3)
    scaled = froude_scaled(model, ratio)
    u = speed_over_critical * critical_speed(model, 0.0)
    gain = thesis_gain(model, 0.0)
    S = _state_scale(ratio)
    small = equilibria(model, u, 0.0, gain=gain)
    big = equilibria(scaled, froude_factor("speed", ratio) * u, 0.0, gain=gain / S)
    assert len(small) == len(big) >= 1
    for a, b in zip(small, big, strict=True):
        assert (b.saturated, b.stable) == (a.saturated, a.stable)
        assert b.pitch_rad == pytest.approx(a.pitch_rad, rel=EQUILIBRIUM_RTOL, abs=1e-12)
        assert b.plane_rad == pytest.approx(a.plane_rad, rel=EQUILIBRIUM_RTOL, abs=1e-12)
        assert b.heave_mps == pytest.approx(
            froude_factor("speed", ratio) * a.heave_mps, rel=EQUILIBRIUM_RTOL, abs=1e-12
        )
        assert b.depth_rate_mps == pytest.approx(
            froude_factor("speed", ratio) * a.depth_rate_mps, rel=EQUILIBRIUM_RTOL, abs=1e-12
        )
        if a.depth_offset_m is None:
            assert b.depth_offset_m is None
        else:
            assert b.depth_offset_m == pytest.approx(ratio * a.depth_offset_m, rel=EQUILIBRIUM_RTOL, abs=1e-9)
        eig_a = np.sort_complex(a.eigenvalues)
        eig_b = np.sort_complex(b.eigenvalues)
        np.testing.assert_allclose(
            eig_b,
            froude_factor("rate", ratio) * eig_a,
            rtol=EQUILIBRIUM_RTOL,
            atol=EQUILIBRIUM_RTOL * np.abs(eig_a).max(),
        )


# --- what scales how --------------------------------------------------------------------------------
def test_each_field_scales_by_its_power_and_the_coefficients_stay(suboff):
    ratio = 3.0
    scaled = froude_scaled(suboff.variant(x_GB_m=2e-3, excess_buoyancy_N=1.5), ratio)
    base = suboff.variant(x_GB_m=2e-3, excess_buoyancy_N=1.5)
    for name, power in [
        ("length_m", 1),
        ("x_G_m", 1),
        ("z_G_m", 1),
        ("x_B_m", 1),
        ("z_B_m", 1),
        ("weight_N", 3),
        ("buoyancy_N", 3),
        ("inertia_y_kg_m2", 5),
        ("mass_kg", 3),
        ("z_GB_m", 1),
        ("x_GB_m", 1),
        ("excess_buoyancy_N", 3),
        ("hull_area_m2", 2),
        ("hull_centroid_x_m", 1),
    ]:
        assert getattr(scaled, name) == pytest.approx(ratio**power * getattr(base, name), rel=SCALING_RTOL), (
            name
        )
    np.testing.assert_allclose(scaled.hull.x_m, ratio * np.asarray(base.hull.x_m), rtol=SCALING_RTOL)
    np.testing.assert_allclose(
        scaled.hull.breadth_m, ratio * np.asarray(base.hull.breadth_m), rtol=SCALING_RTOL
    )
    assert scaled.hydro == base.hydro and scaled.planes == base.planes
    assert (scaled.water_density_kg_m3, scaled.gravity_m_s2, scaled.crossflow_drag) == (
        base.water_density_kg_m3,
        base.gravity_m_s2,
        base.crossflow_drag,
    )
    # The dimensional derivatives follow rho/2 L^n by themselves (Appendix A): Z_w ~ L^2 .. M_qdot ~ L^5.
    c, d = base.coefficients, scaled.coefficients
    for name, power in [
        ("Z_w", 2),
        ("Z_delta_s", 2),
        ("Z_q", 3),
        ("Z_wdot", 3),
        ("M_w", 3),
        ("M_delta_s", 3),
        ("Z_qdot", 4),
        ("M_wdot", 4),
        ("M_q", 4),
        ("M_qdot", 5),
    ]:
        assert getattr(d, name) == pytest.approx(ratio**power * getattr(c, name), rel=SCALING_RTOL), name


@settings(max_examples=50)
@given(ratio=RATIOS)
def test_scaling_by_a_ratio_then_its_inverse_returns_the_vehicle(suboff, ratio):
    back = froude_scaled(froude_scaled(suboff, ratio), 1.0 / ratio, name=suboff.name)
    for f in dataclasses.fields(Vehicle):
        original, returned = getattr(suboff, f.name), getattr(back, f.name)
        if f.name == "hull":
            np.testing.assert_allclose(returned.x_m, original.x_m, rtol=SCALING_RTOL, atol=1e-15)
            np.testing.assert_allclose(returned.breadth_m, original.breadth_m, rtol=SCALING_RTOL, atol=1e-15)
        elif isinstance(original, float):
            assert returned == pytest.approx(original, rel=SCALING_RTOL, abs=1e-15), f.name
        elif f.name != "description":  # (it records the scalings)
            assert returned == original, f.name


def test_scaling_by_one_changes_no_number(suboff):
    same = froude_scaled(suboff, 1.0, name=suboff.name)
    assert dataclasses.replace(same, description=suboff.description) == suboff


def test_froude_factor_has_the_documented_powers():
    assert froude_factor("speed", 16.0) == 4.0
    assert froude_factor("time", 16.0) == 4.0
    assert froude_factor("rate", 16.0) == 0.25
    assert froude_factor("inertia", 2.0) == 32.0
    with pytest.raises(ValueError, match=r"quantity='velocity' is invalid: must be one of \[.*'speed'"):
        froude_factor("velocity", 2.0)  # type: ignore[arg-type]


# --- bad ratios -------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "ratio", [0, 0.0, -1.0, -0.0, math.nan, math.inf, -math.inf, 10**400, "2", None, True, 1j]
)
def test_ratio_that_is_not_a_finite_positive_number_is_refused(suboff, ratio):
    with pytest.raises(ValueError, match=r"length_ratio=.* is invalid: must be a finite number > 0"):
        froude_scaled(suboff, ratio)
    with pytest.raises(ValueError, match=r"length_ratio=.* is invalid: must be a finite number > 0"):
        froude_factor("speed", ratio)


@pytest.mark.parametrize("ratio", [1e-3, 1e3])
def test_ratio_giving_a_length_outside_the_range_is_refused_with_the_allowed_ratios(suboff, ratio):
    low, high = LENGTH_RANGE_M
    with pytest.raises(
        ValueError,
        match=rf"length_ratio={ratio!r} is invalid: must be a number giving a length in "
        rf"\[{low}, {high}\] m .*so in \[0\.00234\d*, 234\.6\d*\]",
    ):
        froude_scaled(suboff, ratio)


# --- the full-scale file ----------------------------------------------------------------------------
def test_full_scale_file_is_exactly_what_the_scaling_writes():
    """The shipped numbers are generated (python -m subenv.vehicles.fullscale), never typed."""
    from importlib import resources

    shipped = (
        resources.files("subenv.vehicles.data").joinpath(f"{SUBOFF_FULLSCALE_NAME}.toml").read_text("utf-8")
    )
    assert shipped == suboff_fullscale_toml()


def test_full_scale_suboff_loads_as_the_scaled_model(suboff):
    assert SUBOFF_FULLSCALE_NAME in available_vehicles()
    loaded, made = load_vehicle(SUBOFF_FULLSCALE_NAME), suboff_fullscale()
    ratio = SUBOFF_FULLSCALE_LENGTH_RATIO
    assert loaded.length_m == pytest.approx(ratio * suboff.length_m, rel=SCALING_RTOL)
    assert 95.0 < loaded.length_m < 110.0  # about 100 m
    assert (loaded.name, loaded.hydro, loaded.planes) == (made.name, made.hydro, made.planes)
    for name in ("weight_N", "buoyancy_N", "inertia_y_kg_m2", "z_G_m", "hull_area_m2", "hull_centroid_x_m"):
        assert getattr(loaded, name) == pytest.approx(getattr(made, name), rel=SCALING_RTOL), name
    np.testing.assert_allclose(loaded.hull.x_m, made.hull.x_m, rtol=1e-11, atol=1e-11 * loaded.length_m)
    np.testing.assert_allclose(
        loaded.hull.breadth_m, made.hull.breadth_m, rtol=1e-11, atol=1e-11 * loaded.length_m
    )
    for alpha in ALLOCATIONS:
        assert critical_speed(loaded, alpha) == pytest.approx(
            math.sqrt(ratio) * critical_speed(suboff, alpha), rel=1e-11
        )


@pytest.mark.parametrize("name", ["suboff", SUBOFF_FULLSCALE_NAME])
def test_a_written_vehicle_file_loads_back_to_the_same_vehicle(tmp_path, name):
    vehicle = load_vehicle(name)
    path = tmp_path / "written.toml"
    path.write_text(vehicle_to_toml(vehicle, header="a test\nof the header"), "utf-8")
    assert path.read_text("utf-8").startswith("# a test\n# of the header\n")
    back = load_vehicle(path)
    assert dataclasses.replace(back, hull=vehicle.hull) == vehicle
    np.testing.assert_allclose(back.hull.x_m, vehicle.hull.x_m, rtol=1e-11, atol=1e-11 * vehicle.length_m)
    np.testing.assert_allclose(
        back.hull.breadth_m, vehicle.hull.breadth_m, rtol=1e-11, atol=1e-11 * vehicle.length_m
    )


def test_the_report_compares_the_full_scale_boat_with_the_froude_scaled_published_numbers():
    # The thesis's dimensional numbers (gains in ft units, u_cr in fps) are the model's: at full scale the
    # report compares them Froude-scaled, so every row agrees as it does on the model (it printed u_cr 1.8979
    # against 9.2978 fps, "difference +7.4").
    from subenv.analysis.report import reproduce_numbers

    model, full = (reproduce_numbers(load_vehicle(n)) for n in ("suboff", SUBOFF_FULLSCALE_NAME))
    assert len(model) == len(full)
    for m, f in zip(model, full, strict=True):
        # Froude similarity: each row's relative difference is the model's (the rows in fps and ft units
        # included).
        assert f.quantity == m.quantity
        assert f.difference / f.thesis == pytest.approx(m.difference / m.thesis, abs=1e-6), f.quantity
