"""Level flight near the free surface: trims, the shallowest depth held, the critical speed's shift."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from subenv.analysis import critical_speed
from subenv.analysis.free_surface import min_level_flight_depth, surface_critical_speed, surface_trim
from subenv.dynamics import derivatives, model_params
from subenv.dynamics.free_surface import FreeSurface, image_distance, image_flow, station_depth
from subenv.dynamics.hull import slender_points
from subenv.scenarios.presets import PERISCOPE_SEA
from subenv.vehicles import HullOffsets, load_vehicle

SUBOFF = load_vehicle("suboff")
U_CR = critical_speed(SUBOFF, 0.0)
RADIUS = max(SUBOFF.hull.breadth_m) / 2


@pytest.mark.parametrize("depth_m", [0.35, 0.6, 1.0, 2.0])
def test_the_critical_speed_near_the_surface_is_the_same_two_ways_and_falls_towards_the_surface(depth_m):
    # The closed form (eq. 3.9 with the suction's pitch derivatives) against the root of the steady
    # depth-rate gain of the linearised right-hand side.
    found = surface_critical_speed(SUBOFF, depth_m)
    assert found.speed_numerical_mps == pytest.approx(found.speed_mps, rel=1e-5)
    assert found.deep_speed_mps == pytest.approx(U_CR, rel=1e-12)
    # In level flight (w = u theta) the bow pitched up is pulled harder: m_theta + m_w > 0, though far from
    # the surface m_theta alone is negative (tests/dynamics/test_free_surface.py, the dipole's limits).
    assert found.speed_mps < U_CR and found.suction_M_theta + found.suction_M_w > 0
    assert found.within_validity == (depth_m >= 2 * RADIUS)


def test_the_critical_speed_shift_grows_monotonically_towards_the_surface_and_vanishes_at_depth():
    # (the images of the hull's cross-flow fade as h^-3: a shift of 2e-6 at 20 m, 1e-7 at 50 m)
    shifts = [surface_critical_speed(SUBOFF, h).shift for h in (0.3, 0.5, 1.0, 2.0, 50.0)]
    assert all(np.diff(shifts) > 0)
    assert abs(shifts[-1]) < 1e-6


@pytest.mark.parametrize("ratio", [0.6, 1.5])
def test_a_trim_balances_the_one_right_hand_side_and_deep_down_a_neutral_boat_flies_level(ratio):
    trim = surface_trim(SUBOFF, ratio * U_CR, 1.0)
    x = np.array([trim.pitch_rad, trim.heave_mps, 0.0, trim.depth_m])
    rates = derivatives(x, trim.speed_mps, trim.plane_rad, 0.0, model_params(SUBOFF, FreeSurface()))
    np.testing.assert_allclose(rates, 0.0, atol=1e-12)
    assert trim.suction_N < 0  # pulled up
    deep = surface_trim(SUBOFF, ratio * U_CR, 40.0)
    assert abs(deep.pitch_rad) < 1e-6 and abs(deep.plane_rad) < 1e-6


@pytest.mark.parametrize("depth_m", [0.6, 1.0])
def test_with_the_planes_held_level_flight_near_the_surface_is_unstable_in_depth(depth_m):
    # Deeper means less suction: a boat pushed down keeps sinking, one pushed up keeps rising. The depth
    # mode (a zero eigenvalue in deep water) turns real positive; for heave alone, Z'' = a Z + c Z' with
    # a = dw_dot/dZ > 0 (the suction's slope) and c = dw_dot/dw < 0 (damping) grows at
    # (c + sqrt(c^2 + 4 a)) / 2, which the 4x4 eigenvalue (with pitch coupled) must be close to.
    trim = surface_trim(SUBOFF, 0.5 * U_CR, depth_m)
    growth = max(trim.eigenvalues.real)
    assert not trim.stable
    params = model_params(SUBOFF, FreeSurface())
    x = np.array([trim.pitch_rad, trim.heave_mps, 0.0, trim.depth_m])

    def slope(i: int) -> float:
        step = np.zeros(4)
        step[i] = 1e-6
        return (
            derivatives(x + step, trim.speed_mps, trim.plane_rad, 0.0, params)[1]
            - derivatives(x - step, trim.speed_mps, trim.plane_rad, 0.0, params)[1]
        ) / 2e-6

    a, c = slope(3), slope(1)
    assert a > 0 > c
    assert growth == pytest.approx((c + math.sqrt(c * c + 4 * a)) / 2, rel=0.05)


def test_bad_depth_and_speed_name_the_parameter():
    with pytest.raises(ValueError, match="depth_m"):
        surface_trim(SUBOFF, 0.5, 0.2)
    with pytest.raises(ValueError, match="speed_mps"):
        surface_trim(SUBOFF, -0.5, 1.0)
    with pytest.raises(ValueError, match="alpha"):
        surface_critical_speed(SUBOFF, 1.0, alpha=3.0)


@pytest.mark.parametrize("ratio", [0.5, 0.7])
def test_well_below_critical_the_shallowest_depth_held_is_where_the_trim_reaches_the_plane_limit(ratio):
    found = min_level_flight_depth(SUBOFF, ratio * U_CR)
    assert found.limited_by == "planes" and found.min_depth_m > RADIUS
    held = surface_trim(SUBOFF, ratio * U_CR, found.min_depth_m)
    assert held.within_limits and abs(held.plane_rad) == pytest.approx(SUBOFF.planes.limit_rad, abs=2e-3)
    above = surface_trim(
        SUBOFF, ratio * U_CR, found.min_depth_m - 2e-3, start=(held.pitch_rad, held.plane_rad)
    )
    assert not above.within_limits


def _balance_determinant(trim, alpha: float) -> float:
    """det d(w_dot, q_dot)/d(theta, delta) at a trim (w = u tan(theta), q = 0 held)."""
    params = model_params(SUBOFF, FreeSurface())

    def balance(theta: float, delta: float) -> np.ndarray:
        x = np.array([theta, trim.speed_mps * math.tan(theta), 0.0, trim.depth_m])
        return derivatives(x, trim.speed_mps, delta, alpha * delta, params)[1:3]

    e = 1e-7
    columns = [
        (balance(trim.pitch_rad + e, trim.plane_rad) - balance(trim.pitch_rad - e, trim.plane_rad)) / (2 * e),
        (balance(trim.pitch_rad, trim.plane_rad + e) - balance(trim.pitch_rad, trim.plane_rad - e)) / (2 * e),
    ]
    return float(np.linalg.det(np.column_stack(columns)))


@pytest.mark.parametrize(("ratio", "alpha"), [(0.9, 0.0), (0.95, 0.0), (1.1, 1.0)])
def test_near_critical_level_flight_is_lost_in_a_fold_near_the_surface(ratio, alpha):
    # At a saddle-node the balance's Jacobian is singular, and along the branch it shrinks as the square
    # root of the distance to the fold: 1 mm from it, about sqrt(1/300) of its value 0.3 m below.
    found = min_level_flight_depth(SUBOFF, ratio * U_CR, alpha)
    assert found.limited_by == "no trim" and found.min_depth_m > RADIUS
    fold = found.min_depth_m
    near = surface_trim(SUBOFF, ratio * U_CR, fold, alpha)
    far = surface_trim(SUBOFF, ratio * U_CR, fold + 0.3, alpha)
    assert near.within_limits
    ratio_det = abs(_balance_determinant(near, alpha) / _balance_determinant(far, alpha))
    assert ratio_det < 0.15


def test_a_seas_mean_suction_deepens_the_shallowest_depth_held():
    calm = min_level_flight_depth(SUBOFF, 0.9 * U_CR).min_depth_m
    sea = min_level_flight_depth(SUBOFF, 0.9 * U_CR, sea_state=PERISCOPE_SEA).min_depth_m
    assert sea > calm
    assert math.isfinite(sea)


def _a33_couple_of_the_source_images(pitch: float, depth: float, speed: float) -> float:
    """Issue 38's first reading of the missing moment, u int a_33 w_img dx [N m] (a_33 = rho S, w_img the
    upward, earth-frame velocity the rigid-lid images of the hull's sources induce at the axis), summed over
    the slender-body theory's axis points with the package's own image flow."""
    x = np.asarray(SUBOFF.hull.x_m)[::-1]
    xs, strength, weight, radius = slender_points(x, np.asarray(SUBOFF.hull.breadth_m)[::-1])
    s, c = math.sin(pitch), math.cos(pitch)
    h = [station_depth(depth, xk, s, rk) for xk, rk in zip(xs, radius, strict=True)]
    couple = 0.0
    for k in range(xs.size):
        normal = axial = 0.0
        for m in range(xs.size):
            D, H = xs[k] - xs[m], h[k] + h[m]
            flow = image_flow(D, H, *image_distance(D, H, c), strength[m], weight[m], 0.0, speed, s, c)
            normal, axial = normal + flow[0], axial + flow[1]
        # (the points' dipole weight is S + a_33 / rho = 2 S: a_33 / rho is half of it)
        couple += speed * 0.5 * weight[k] * (normal * c + axial * s)
    return SUBOFF.water_density_kg_m3 * couple


def test_issue_38s_lagally_stiffness_and_its_a33_couple_are_recomputed_from_the_packages_image_flow():
    # Issue 38's numbers at SUBOFF's u_cr, level flight, 3, 1, 0.5, 0.3 m: the sources' Lagally pitch
    # stiffness +0.119, +3.03, +20.6, +75.6 N m/rad (a continuous line of sources: here the same hull cut 40
    # times finer, one source per segment; the shipped segments give 0.2-1.0% more, issue 38's item 2), and
    # the critical-speed shifts of the sources-only theory as shipped (PeriscopeDepth-v1), -0.76%, -4.82%,
    # -14.87% at 1, 0.5, 0.3 m; the couple u int a_33 w_img dx it proposed, -0.103, -1.59, -6.97, -19.6 N
    # m/rad, with which the shifts would be -0.39%, -3.35%, -11.8%. Tolerances: half a unit of the issue's
    # last printed digit. That couple alone is not the consistent theory (in a uniform cross-flow it gives no
    # Munk moment, tests/dynamics/test_free_surface.py); the shipped slender-body theory's shifts are larger.
    depths = (3.0, 1.0, 0.5, 0.3)
    x, breadth = np.asarray(SUBOFF.hull.x_m)[::-1], np.asarray(SUBOFF.hull.breadth_m)[::-1]
    fine_x = np.unique(np.concatenate([x, np.linspace(x[0], x[-1], 40 * x.size)]))
    continuous = dataclasses.replace(
        SUBOFF, hull=HullOffsets(tuple(fine_x[::-1]), tuple(np.interp(fine_x, x, breadth)[::-1]))
    )
    sources = FreeSurface(theory="sources-only")
    restoring = SUBOFF.z_G_m * SUBOFF.weight_N - SUBOFF.z_B_m * SUBOFF.buoyancy_N
    lagally = [surface_critical_speed(continuous, h, free_surface=sources) for h in depths]
    step = 1e-5
    couple = [
        (_a33_couple_of_the_source_images(step, h, 1.0) - _a33_couple_of_the_source_images(-step, h, 1.0))
        / (2 * step)
        for h in depths
    ]  # per u^2
    # (issue 38's value, half a unit of its last printed digit)
    stiffnesses = ((0.119, 5e-4), (3.03, 5e-3), (20.6, 0.05), (75.6, 0.05))
    a33_stiffnesses = ((-0.103, 5e-4), (-1.59, 5e-3), (-6.97, 5e-3), (-19.6, 0.05))
    for found, a33, lagally_law, a33_law in zip(lagally, couple, stiffnesses, a33_stiffnesses, strict=True):
        assert found.suction_M_theta * U_CR**2 == pytest.approx(lagally_law[0], abs=lagally_law[1])
        assert a33 * U_CR**2 == pytest.approx(a33_law[0], abs=a33_law[1])
    for h, shift in zip(depths[1:], (-0.76, -4.82, -14.87), strict=True):
        shipped = surface_critical_speed(SUBOFF, h, free_surface=sources)
        assert 100 * shipped.shift == pytest.approx(shift, abs=5e-3)
        assert surface_critical_speed(SUBOFF, h).shift < shipped.shift  # the consistent theory: larger
    for found, a33, (shift, tolerance) in zip(
        lagally[1:], couple[1:], ((-0.39, 5e-3), (-3.35, 5e-3), (-11.8, 0.05)), strict=True
    ):
        # Eq. 3.9's denominator gains Z_d dM/dtheta / u^2, so 1 / u_cr^2 grows by
        # (dM/dtheta / u^2) / (z_G W - z_B B).
        speed = 1.0 / math.sqrt(1.0 / found.speed_mps**2 + a33 / restoring)
        assert 100 * (speed / U_CR - 1) == pytest.approx(shift, abs=tolerance)
