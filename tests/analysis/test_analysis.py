"""subenv.analysis: critical speed three ways, equilibria, continuation, bifurcation sets, reversal."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from subenv.analysis import critical_froude, critical_speed, linear_model
from subenv.analysis.bifurcation import (
    exact_bifurcation_set,
    exact_cusp,
    offset_from_beta,
    saturation_cusp,
    saturation_cusp_closed_form,
    speed_from_lambda,
    zeta,
)
from subenv.analysis.continuation import continue_equilibria
from subenv.analysis.critical import critical_speeds
from subenv.analysis.curriculum import speed_curriculum
from subenv.analysis.design import (
    closed_loop_eigenvalues,
    controllability_losses,
    place_gain,
    scheduled_depth_gain,
    thesis_gain,
)
from subenv.analysis.equilibria import equilibria, steady_state_residual, symmetric_pitchfork
from subenv.analysis.report import REPORT_FILE, critical_speed_three_ways, reproduce_numbers, write_findings
from subenv.analysis.reversal import level_flight_trim
from subenv.dynamics import derivatives, model_params


@pytest.fixture(scope="module")
def thesis_boat(suboff):
    """The thesis's Ch. III-IV boat: C_D = 0."""
    return suboff.variant(crossflow_drag=0.0)


def _fn_speed(vehicle, fn: float) -> float:
    return fn * math.sqrt(vehicle.gravity_m_s2 * vehicle.z_GB_m)


@pytest.mark.parametrize("alpha", [-1.0, -0.5, 0.0, 0.5, 1.0])
@pytest.mark.parametrize("loading", [{}, {"z_GB_m": 0.06}, {"x_GB_m": 0.002, "excess_buoyancy_N": 2.0}])
def test_critical_speed_three_ways(suboff, alpha, loading):
    vehicle = suboff.variant(**loading)
    three = critical_speed_three_ways(vehicle, alpha)
    assert three["eigenvalue"] == pytest.approx(three["closed_form"], rel=1e-9)
    assert three["controllability"] == pytest.approx(three["closed_form"], rel=1e-9)


@pytest.mark.parametrize("alpha", [-1.0, 0.0, 0.5, "bow"])
def test_critical_speeds_of_many_loadings_are_each_critical_speed_bit_for_bit(suboff, alpha):
    # Negative metacentric heights among them: nan where critical_speed raises (no critical speed).
    rng = np.random.default_rng(3)
    z_GB, excess = rng.uniform(-0.01, 0.03, 300), rng.normal(0, 3, 300)
    fields = suboff.loading_fields(z_GB_m=z_GB, excess_buoyancy_N=excess)
    speeds = critical_speeds(suboff, alpha, fields)
    for i in range(300):
        try:
            expected = critical_speed(suboff.variant(z_GB_m=z_GB[i], excess_buoyancy_N=excess[i]), alpha)
        except ValueError:
            expected = math.nan
        assert np.float64(expected).tobytes() == speeds[i].tobytes(), i
    assert 0 < np.isnan(speeds).sum() < 300
    assert critical_speeds(suboff, alpha, {}) == critical_speed(suboff, alpha)  # no loading: the vehicle's


def test_any_stabilising_gain_loses_stability_at_the_same_speed(suboff):
    ucr = critical_speed(suboff)
    for poles in [(-0.3, -0.31, -0.32, -0.33), (-0.8, -0.5, -0.6, -0.7), (-0.2, -0.25, -1.0, -1.5)]:
        gain = place_gain(suboff, 1.2, poles)
        above, below = closed_loop_eigenvalues(suboff, [ucr * 1.001, ucr * 0.999], gain)
        assert above.real.max() < 0 < below.real.max()


def test_controllability_is_lost_at_u_cr_in_the_depth_mode(suboff):
    ucr = critical_speed(suboff)
    losses = controllability_losses(suboff, np.linspace(0.5 * ucr, 1.5 * ucr, 301))
    depth_mode = [u for u, eig in losses if abs(eig) < 1e-8]
    assert depth_mode == [pytest.approx(ucr, rel=1e-10)]
    # The other loss is a stable mode (harmless), documented in controllability_losses.
    assert all(eig.real < 0 for u, eig in losses if abs(eig) >= 1e-8)


def test_published_numbers_are_reproduced(suboff):
    tolerance = {"ft units": 1e-4, "fps": 5e-5, "-": 0.01, "deg": 0.5, "sqrt(lambda)": 0.02, "x_GB/L": 1e-5}
    rows = reproduce_numbers(suboff)
    assert len(rows) == 18
    for row in rows:
        assert abs(row.difference) <= tolerance[row.unit], row


def test_critical_froude_range_and_bad_input(suboff):
    fns = [critical_froude(suboff, a) for a in np.linspace(-1, 1, 21)]
    assert np.all(np.diff(fns) > 0)  # more bow planes (alpha up) raises the critical speed (Fig. 3-9)
    with pytest.raises(
        ValueError, match=r"z_GB=-0\.01 m gives restoring moment .*; a critical speed exists only"
    ):
        critical_speed(suboff.variant(z_GB_m=-0.01))
    with pytest.raises(ValueError, match=r"alpha=1\.5 is invalid: must be a number in \[-1, 1\]"):
        critical_speed(suboff, 1.5)
    with pytest.raises(ValueError, match=r"speed_mps=-1\.0 is invalid: must be a finite number >= 0"):
        linear_model(suboff, -1.0)
    with pytest.raises(ValueError, match=r"speed_mps=0\.0 is invalid"):
        equilibria(suboff, 0.0)


def test_thesis_gain_places_the_poles(suboff):
    lm = linear_model(suboff, 5 * 0.3048)
    eig = np.linalg.eigvals(lm.A - np.outer(lm.B, thesis_gain(suboff)))
    np.testing.assert_allclose(np.sort(eig.real), [-0.33, -0.32, -0.31, -0.3], atol=1e-9)


@pytest.mark.parametrize("fn", [0.7, 0.95, 1.03, 1.055, 1.2])
def test_equilibria_are_steady_states_of_the_dynamics(thesis_boat, fn):
    vehicle = thesis_boat.variant(x_GB_m=-1e-4 * thesis_boat.length_m)
    u = _fn_speed(vehicle, fn)
    params = model_params(vehicle)
    found = equilibria(vehicle, u)
    assert found
    for e in found:
        f = derivatives(np.array([e.pitch_rad, e.heave_mps, 0.0, 0.0]), u, e.plane_rad, 0.0, params)
        assert abs(f[1]) < 1e-10 and abs(f[2]) < 1e-10  # heave and pitch balance
        assert abs(e.plane_rad) <= vehicle.planes.limit_rad + 1e-12
        if e.saturated:
            assert f[3] == pytest.approx(e.depth_rate_mps, abs=1e-12) and abs(e.depth_rate_mps) > 0
        else:
            assert abs(f[3]) < 1e-10


def test_symmetric_pitchfork_closed_form_matches_the_exact_solver(thesis_boat):
    ucr = critical_speed(thesis_boat)
    for ratio in (0.6, 0.9, 0.995, 1.2):
        sym = symmetric_pitchfork(thesis_boat, ratio * ucr)
        exact = equilibria(thesis_boat, ratio * ucr)
        assert [e.saturated for e in sym] == [e.saturated for e in exact]
        np.testing.assert_allclose([e.pitch_rad for e in sym], [e.pitch_rad for e in exact], atol=1e-9)
    # Supercritical pitchfork: level flight stable above u_cr, unstable below; outer pair stable.
    above = symmetric_pitchfork(thesis_boat, 1.01 * ucr)
    below = symmetric_pitchfork(thesis_boat, 0.999 * ucr)
    assert len(above) == 1 and above[0].stable
    assert [e.stable for e in below] == [True, False, True]
    assert not below[0].saturated and below[0].pitch_rad == pytest.approx(
        -math.acos((0.999) ** 2), rel=1e-9
    )  # eq. 3.17: cos(theta) = (u/u_cr)^2
    with pytest.raises(ValueError, match="symmetric pitchfork needs all three 0"):
        symmetric_pitchfork(thesis_boat.variant(x_GB_m=0.001), 0.5)


def test_continuation_over_ballast_finds_the_folds_of_the_exact_equation(thesis_boat):
    L = thesis_boat.length_m
    u = _fn_speed(thesis_boat, 1.0)
    branch = continue_equilibria(
        thesis_boat, "x_GB", -5e-4 * L, 5e-4 * L, speed_mps=u, initial_pitch_rad=-0.5
    )
    assert branch.residual_max < 1e-9
    # Eq. 4.3's terms are of order |Z_delta| W z_GB (about 1e4 in SI); its residual is ~1e-9 of that.
    scale = abs(thesis_boat.coefficients.Z_delta_s) * thesis_boat.weight_N * thesis_boat.z_GB_m
    for x, theta in zip(branch.values, branch.states[:, 0], strict=True):
        residual = steady_state_residual(thesis_boat.variant(x_GB_m=float(x)), u, float(theta))
        assert abs(residual) < 1e-9 * scale
    assert len(branch.folds) == 2
    low, high = exact_bifurcation_set(thesis_boat, np.array([u]))
    folds = np.sort(branch.values[branch.folds])
    np.testing.assert_allclose(folds, [low[0], high[0]], rtol=0.02)  # within one continuation step
    # Path B (Fn 1.1) is outside the cusp: a single-valued branch.
    branch_b = continue_equilibria(
        thesis_boat, "x_GB", -5e-4 * L, 5e-4 * L, speed_mps=_fn_speed(thesis_boat, 1.1)
    )
    assert len(branch_b.folds) == 0


def test_continuation_over_speed_matches_the_closed_form_roots(thesis_boat):
    vehicle = thesis_boat.variant(x_GB_m=-1e-4 * thesis_boat.length_m)
    branch = continue_equilibria(vehicle, "speed", _fn_speed(vehicle, 1.4), _fn_speed(vehicle, 0.7))
    assert branch.values[0] > branch.values[-1] and len(branch.folds) == 0
    for u, theta in zip(branch.values[::10], branch.states[::10, 0], strict=True):
        assert min(abs(np.array(_roots_of_eq_4_3(vehicle, float(u))) - theta)) < 1e-8


def _roots_of_eq_4_3(vehicle, u):
    grid = np.linspace(-1.5, 1.5, 30001)
    values = steady_state_residual(vehicle, u, grid)
    from scipy.optimize import brentq

    return [
        brentq(lambda t: steady_state_residual(vehicle, u, t), grid[i], grid[i + 1], xtol=1e-14)
        for i in np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))
    ]


def test_consistent_cusp_matches_the_exact_folds_and_the_printed_one_does_not(thesis_boat):
    lam0 = -1.0 / zeta(thesis_boat)
    lam = np.array([0.97, 0.99]) * lam0
    speeds = speed_from_lambda(thesis_boat, lam)
    _, exact = exact_bifurcation_set(thesis_boat, speeds)
    consistent = -offset_from_beta(thesis_boat, exact_cusp(thesis_boat, lam), speeds)
    printed = -offset_from_beta(thesis_boat, exact_cusp(thesis_boat, lam, form="thesis"), speeds)
    np.testing.assert_allclose(consistent, exact, rtol=0.05)
    assert np.all(np.abs(printed / exact - 1) > 0.5)


def test_saturation_cusp_equals_eq_4_43_without_drag(thesis_boat):
    speeds = np.array([0.45, 0.55, 0.6, 0.7])
    x_plus, x_minus = saturation_cusp(thesis_boat, speeds)
    np.testing.assert_allclose(saturation_cusp_closed_form(thesis_boat, x_plus, 1.0), speeds**2, rtol=1e-10)
    np.testing.assert_allclose(saturation_cusp_closed_form(thesis_boat, x_minus, -1.0), speeds**2, rtol=1e-10)
    np.testing.assert_allclose(x_plus, -x_minus, rtol=1e-12)  # symmetric boat


def test_level_flight_trim_reverses_through_the_critical_speed(thesis_boat):
    ucr = critical_speed(thesis_boat)
    light = thesis_boat.variant(excess_buoyancy_N=0.7)
    trim = level_flight_trim(light, np.array([0.9, 0.999, 1.001, 1.1]) * ucr)
    assert np.sign(trim.pitch_rad[0]) == np.sign(trim.pitch_rad[1]) != np.sign(trim.pitch_rad[2])
    assert np.sign(trim.plane_rad[1]) != np.sign(trim.plane_rad[2])
    assert abs(trim.pitch_rad[1]) > 10 * abs(trim.pitch_rad[0])  # grows without bound at u_cr
    assert abs(trim.plane_rad[1]) > 10 * abs(trim.plane_rad[0])
    # The trim is a steady state of the linear model with the buoyancy bias.
    for u, theta, delta in zip(trim.speeds_mps, trim.pitch_rad, trim.plane_rad, strict=True):
        lm = linear_model(light, float(u))
        x = np.array([theta, u * theta, 0.0, 0.0])
        bias = np.linalg.solve(
            [
                [light.mass_kg - light.coefficients.Z_wdot, -light.coefficients.Z_qdot],
                [-light.coefficients.M_wdot, light.inertia_y_kg_m2 - light.coefficients.M_qdot],
            ],
            [light.weight_N - light.buoyancy_N, 0.0],
        )
        xdot = lm.A @ x + lm.B * delta + np.array([0.0, bias[0], bias[1], 0.0])
        np.testing.assert_allclose(xdot, 0.0, atol=1e-12)
    neutral = level_flight_trim(thesis_boat, np.array([0.3, 1.0]))
    np.testing.assert_allclose(neutral.pitch_rad, 0.0, atol=0)


def test_scheduled_depth_gain_is_the_pole_placement_gain(suboff):
    speeds = [0.3, 0.5, 0.7, 1.0, 1.524]
    k4 = scheduled_depth_gain(suboff, speeds)
    placed = [place_gain(suboff, u)[3] for u in speeds]
    np.testing.assert_allclose(k4, placed, rtol=1e-6)
    ucr = critical_speed(suboff)
    near = scheduled_depth_gain(suboff, [0.999 * ucr, 1.001 * ucr])
    assert near[0] < -100 and near[1] > 100  # unbounded, and reversed below u_cr (Fig. 5-3)


def test_curriculum_stages_are_placed_by_the_critical_speed(suboff):
    stages = speed_curriculum(suboff)
    ucr = critical_speed(suboff)
    assert [s.name for s in stages] == ["cruise", "approach", "near_critical", "below_critical"]
    assert stages[-1].speed_high_mps < ucr < stages[-2].speed_high_mps
    assert stages[2].froude_low == pytest.approx(0.85 * critical_froude(suboff))
    with pytest.raises(ValueError, match=r"stage 'x': \(1\.0, 0\.5\) is invalid"):
        speed_curriculum(suboff, stages=[("x", 1.0, 0.5)])


def test_report_is_written_completely_and_not_over_an_existing_folder(analysis_report, suboff):
    # write_findings(folder, SUBOFF) into a folder that did not exist, once per session (tests/conftest.py).
    out = analysis_report.folder
    assert f"findings written to {out / REPORT_FILE}" in analysis_report.printed
    found = json.loads((out / REPORT_FILE).read_text())
    row = next(r for r in found["published"] if r["quantity"] == "u_cr, eq. 3.9 closed form")
    assert (
        row["thesis"] == 1.8979
        and row["computed"] == pytest.approx(1.8979, abs=1e-4)
        and row["unit"] == "fps"
    )
    assert row["difference"] == pytest.approx(row["computed"] - row["thesis"])
    assert found["vehicle"] == "suboff" and found["suboff_shape"] and found["numbers"] == []
    assert found["hopf"]["point"]["criticality"] == "supercritical"
    assert found["hopf"]["point"]["speed_mps"] == analysis_report.hopf.point.speed_mps  # the one computed
    assert set(found["surface"]["held"]) == {"0", "1"}  # stern planes alone; both pairs
    with pytest.raises(FileExistsError, match="exists: choose another output folder or pass overwrite=True"):
        write_findings(out, suboff)
    assert [p.name for p in out.parent.iterdir()] == ["report"]  # no temporary folder left behind


def test_unlimited_planes_return_every_root_of_eq_4_3(thesis_boat):
    """saturation=False: the unsaturated pitchfork of eq. 3.17 even where |delta| > limit."""
    ucr = critical_speed(thesis_boat)
    u = 0.9 * ucr
    unlimited = equilibria(thesis_boat, u, saturation=False)
    expected = math.acos(0.9**2)  # eq. 3.17
    np.testing.assert_allclose([e.pitch_rad for e in unlimited], [-expected, 0.0, expected], atol=1e-9)
    assert not any(e.saturated for e in unlimited)
    assert abs(unlimited[0].plane_rad) > thesis_boat.planes.limit_rad  # beyond what the planes can do
    limited = equilibria(thesis_boat, u)
    assert [e.saturated for e in limited] == [True, False, True]


def test_the_buoyancy_bifurcation_set_is_where_the_number_of_steady_states_changes(suboff):
    # Independent check: count the roots of eq. 4.3 just inside and just outside each edge.
    from subenv.analysis import buoyancy_bifurcation_set

    u = 0.5 * critical_speed(suboff)
    low, high = buoyancy_bifurcation_set(suboff, np.array([u]))
    assert low[0] < 0.0 < high[0]
    W = suboff.weight_N

    def count(fraction: float) -> int:
        return len(
            np.unique(np.round(_roots_of_eq_4_3(suboff.variant(excess_buoyancy_N=fraction * W), u), 6))
        )

    for edge in (low[0], high[0]):  # two steady states merge at the edge and are gone beyond it
        assert count(0.99 * edge) - count(1.01 * edge) == 2
    above, _ = buoyancy_bifurcation_set(suboff, np.array([1.2 * critical_speed(suboff)]))
    assert np.isnan(above[0])  # above the critical speed the pitchfork has no fold
