"""The free surface's suction and a seaway's forces, against laws derived independently of the code."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from subenv.dynamics import HullTable, derivatives, integrate, model_params, rk4
from subenv.dynamics.free_surface import NO_FREE_SURFACE, FreeSurface, dipole_suction_N, suction
from subenv.dynamics.model import pack_params as pack
from subenv.dynamics.waves import SeaState, hull_wave_integrals, wave_force_point
from subenv.vehicles import load_vehicle

SUBOFF = load_vehicle("suboff")
RHO = SUBOFF.water_density_kg_m3


def _volume(vehicle) -> float:
    x, b = np.asarray(vehicle.hull.x_m), np.asarray(vehicle.hull.breadth_m)
    fine = np.linspace(x.min(), x.max(), 200_001)
    return float(np.trapezoid(0.25 * math.pi * np.interp(fine, x[::-1], b[::-1]) ** 2, fine))


def test_far_from_the_surface_the_hull_is_a_dipole_attracted_by_its_image():
    # h >> L: the pairs of sources act as one dipole of moment u V; its image at 2 h pulls it up with
    # 3 rho u^2 V^2 / (64 pi h^4) (the sphere's 3 pi rho u^2 a^6 / (16 h^4) with V = 4/3 pi a^3 and the
    # sphere's dipole moment 1.5 u V instead of u V), a law not in the code's sum over pairs.
    # The next term (the source distribution's second moment) is smaller by (L / h)^2: each doubling of
    # the depth divides the difference by 4.
    params = model_params(SUBOFF, FreeSurface())
    depths = np.array([40.0, 80.0, 160.0, 320.0])
    Z, _ = suction(params.hull, 0.0, depths, 0.7, params.rho_suction)
    error = -Z / dipole_suction_N(_volume(SUBOFF), depths, 0.7, RHO) - 1.0
    assert abs(error[-1]) < 1e-4
    np.testing.assert_allclose(error[:-1] / error[1:], 4.0, rtol=0.02)


def test_suction_pulls_up_grows_towards_the_surface_and_goes_as_speed_squared():
    params = model_params(SUBOFF, FreeSurface())
    depths = np.linspace(0.3, 3.0, 28)
    Z, _ = suction(params.hull, 0.0, depths, 0.6, params.rho_suction)
    assert np.all(Z < 0) and np.all(np.diff(Z) > 0)  # up, weaker with depth
    Z2, M2 = suction(params.hull, 0.05, 1.0, 1.2, params.rho_suction)
    Z1, M1 = suction(params.hull, 0.05, 1.0, 0.6, params.rho_suction)
    assert Z2 / Z1 == pytest.approx(4.0, rel=1e-13) and M2 / M1 == pytest.approx(4.0, rel=1e-13)
    # suction_factor scales it, 0 is deep water.
    Zh, _ = suction(params.hull, 0.05, 1.0, 0.6, 0.5 * params.rho_suction)
    assert Zh == pytest.approx(0.5 * Z1, rel=1e-13)


def test_a_fore_aft_symmetric_hull_level_feels_no_moment_and_pitching_the_bow_up_adds_one():
    x = np.linspace(2.0, -2.0, 81)
    breadth = 0.5 * np.sqrt(np.clip(1.0 - (x / 2.0) ** 2, 0.0, None))  # an ellipsoid of revolution
    hull = HullTable.from_offsets(tuple(x), tuple(breadth))
    Z0, M0 = suction(hull, 0.0, 0.8, 1.0, RHO)
    assert abs(float(M0)) < 1e-12 * abs(float(Z0))
    _, M_up = suction(hull, 0.05, 0.8, 1.0, RHO)
    _, M_down = suction(hull, -0.05, 0.8, 1.0, RHO)
    assert M_up > 0 > M_down and float(M_up) == pytest.approx(
        -float(M_down), rel=1e-12
    )  # bow nearer: nose-up


def test_deep_water_is_riedels_model_bit_for_bit_and_the_suction_fades_with_depth():
    rng = np.random.default_rng(0)
    states = np.column_stack(
        [rng.normal(0, 0.1, 50), rng.normal(0, 0.05, 50), rng.normal(0, 0.02, 50), rng.uniform(0.5, 20, 50)]
    )
    deep = derivatives(states, 0.6, 0.1, 0.0, model_params(SUBOFF))
    assert np.array_equal(derivatives(states, 0.6, 0.1, 0.0, model_params(SUBOFF, NO_FREE_SURFACE)), deep)
    far = states.copy()
    far[:, 3] = 1e4
    np.testing.assert_allclose(
        derivatives(far, 0.6, 0.1, 0.0, model_params(SUBOFF, FreeSurface())),
        derivatives(far, 0.6, 0.1, 0.0, model_params(SUBOFF)),
        rtol=0,
        atol=1e-15,
    )
    near = derivatives(states, 0.6, 0.1, 0.0, model_params(SUBOFF, FreeSurface()))
    assert np.all(near[:, 0] == deep[:, 0]) and np.all(near[:, 3] == deep[:, 3])  # kinematics untouched
    assert np.all(near[:, 1] < deep[:, 1])  # the heave acceleration is upward-shifted everywhere


def test_bad_free_surface_and_sea_parameters_name_the_parameter():
    with pytest.raises(ValueError, match="suction_factor"):
        FreeSurface(suction_factor=-1.0)
    with pytest.raises(ValueError, match="significant_height_m"):
        SeaState(significant_height_m=0.0, peak_period_s=2.0)
    with pytest.raises(ValueError, match="waves"):
        SeaState(significant_height_m=0.03, peak_period_s=2.0, waves=100)
    with pytest.raises(ValueError, match="band"):
        SeaState(significant_height_m=0.03, peak_period_s=2.0, band=(1.2, 3.0))


SEA = SeaState(significant_height_m=0.03, peak_period_s=2.0)


def test_the_seeded_waves_carry_the_spectrums_variance():
    # E[A_i^2 / 2] = int_bin S: the mean over many draws of the waves' variance is the band's integral
    # (adaptive quadrature of S), and the band holds nearly all of H_s^2 / 16.
    rng = np.random.default_rng(7)
    variances = [np.sum(SEA.amplitudes(SEA.frequencies(rng.random(SEA.waves))) ** 2) / 2 for _ in range(2000)]
    band = SEA.band_variance_m2()
    assert np.mean(variances) == pytest.approx(band, rel=3e-3)
    assert 0.97 * SEA.significant_height_m**2 / 16 < band < SEA.significant_height_m**2 / 16
    # One seeded sea's elevation, sampled over a long time, has its own sum A_i^2 / 2 as variance.
    jitter, phase = rng.random(SEA.waves), rng.uniform(0, 2 * math.pi, SEA.waves)
    omega, amplitude = SEA.frequencies(jitter), SEA.amplitudes(SEA.frequencies(jitter))
    t = np.arange(0.0, 20_000.0, 0.1)
    eta = (amplitude[:, None] * np.cos(omega[:, None] * t + phase[:, None])).sum(0)
    assert np.var(eta) == pytest.approx(np.sum(amplitude**2) / 2, rel=0.02)


@numba.njit
def _force_series(times, speed, depth, waves, n):
    out = np.empty((2, times.size))
    for j in range(times.size):
        out[0, j], out[1, j] = wave_force_point(times[j], speed * times[j], depth, waves, n)
    return out


def test_first_order_wave_force_has_zero_mean_and_the_mean_is_the_second_order_suction():
    rng = np.random.default_rng(3)
    waves = SEA.components(
        rng.random(SEA.waves),
        rng.uniform(0, 2 * math.pi, SEA.waves),
        SUBOFF.hull.x_m,
        SUBOFF.hull.breadth_m,
        RHO,
        SUBOFF.gravity_m_s2,
    )
    t = np.arange(0.0, 40_000.0, 0.05)
    depth, speed = 1.1, 0.6
    force, _ = _force_series(t, speed, depth, waves, SEA.waves)
    first = waves.copy()
    first[7:] = 0.0  # the mean terms off: first order only
    f1, m1 = _force_series(t, speed, depth, first, SEA.waves)
    assert abs(f1.mean()) < 0.01 * f1.std() and abs(m1.mean()) < 0.01 * m1.std()
    # The first-order force's variance is sum |F_i|^2 / 2 of the waves' complex amplitudes.
    k = waves[0, : SEA.waves]
    amp2 = (waves[3, : SEA.waves] ** 2 + waves[4, : SEA.waves] ** 2) * np.exp(-2 * k * depth)
    assert f1.var() == pytest.approx(amp2.sum() / 2, rel=0.03)
    # What is left when the first order is taken away is the constant mean suction, upward.
    mean_force = force - f1
    assert np.ptp(mean_force) < 1e-9 * abs(mean_force[0]) and mean_force[0] < 0
    expected = -(waves[7, : SEA.waves] * np.exp(-2 * k * depth)).sum()
    assert mean_force[0] == pytest.approx(expected, rel=1e-12)


def test_long_waves_push_the_hull_with_twice_its_displaced_mass():
    # K -> 0: Froude-Krylov plus added mass of a slender body of circular sections, 2 rho V.
    heave, pitch, total, moment = hull_wave_integrals(
        np.array([1e-9]), SUBOFF.hull.x_m, SUBOFF.hull.breadth_m, RHO
    )
    assert heave[0].real == pytest.approx(2 * RHO * _volume(SUBOFF), rel=1e-4)
    assert total == pytest.approx(heave[0].real, rel=1e-9) and pitch[0].real == pytest.approx(
        moment, rel=1e-9
    )


def test_the_expected_mean_suction_falls_as_the_spectrum_weighted_exp_minus_2_k_h():
    Z1, _ = SEA.mean_suction(1.0, SUBOFF.hull.x_m, SUBOFF.hull.breadth_m, RHO, SUBOFF.gravity_m_s2)
    Z2, _ = SEA.mean_suction(2.0, SUBOFF.hull.x_m, SUBOFF.hull.breadth_m, RHO, SUBOFF.gravity_m_s2)
    kp = SEA.peak_frequency_radps**2 / SUBOFF.gravity_m_s2
    assert Z1 < Z2 < 0
    # Dominated by waves near the peak: decays between exp(-2 k h) of the band's ends, near the peak's.
    ratio = Z2 / Z1
    low, high = (f**2 * kp for f in SEA.band)
    assert math.exp(-2 * high) < ratio < math.exp(-2 * low)


@numba.njit(error_model="numpy")
def _one_period_in_a_block(x, t0, u, plane, prm, hull, waves, n_waves, distance):
    block = np.zeros(integrate.LANE_ROWS * integrate.LANES)
    integrate.set_lane(block, 0, x[0], x[1], x[2], x[3], t0, u, 0.0, plane, 0.0, 0.0, prm, distance, n_waves)
    integrate.control_period_lanes(block, 1, integrate.CONTROL_PERIOD_S, integrate.SUBSTEPS, hull, waves)
    return np.array([block[(integrate.LANE_PITCH + r) * integrate.LANES] for r in range(4)])


@numba.njit
def _wave_at(t, distance, depth, waves, n):
    return wave_force_point(t, distance, depth, waves, n)


def test_the_block_integrator_in_a_sea_is_rk4_over_the_one_right_hand_side_with_the_waves_as_inputs():
    # The environments' integrator evaluates the sea at every stage, at the stage's time, depth and
    # distance travelled; the NumPy reference passes the same force and moment to derivatives.
    rng = np.random.default_rng(11)
    params = model_params(SUBOFF, FreeSurface())
    waves = SEA.components(
        rng.random(SEA.waves),
        rng.uniform(0, 2 * math.pi, SEA.waves),
        SUBOFF.hull.x_m,
        SUBOFF.hull.breadth_m,
        RHO,
        SUBOFF.gravity_m_s2,
    )
    x0, t0, u, plane, distance = np.array([0.02, 0.01, -0.003, 1.1]), 37.5, 0.6, 0.1, 22.5

    def f(t, state):
        force, moment = _wave_at(t, distance + u * (t - t0), state[3], waves, SEA.waves)
        return derivatives(state, u, plane, 0.0, params, force, moment)

    reference = rk4(f, t0, x0, integrate.CONTROL_PERIOD_S, integrate.SUBSTEPS)
    block = _one_period_in_a_block(
        x0,
        t0,
        u,
        plane,
        np.ascontiguousarray(pack(params)),
        params.hull.packed,
        waves[None],
        SEA.waves,
        distance,
    )
    np.testing.assert_allclose(block, reference, rtol=1e-12, atol=1e-15)
    calm = _one_period_in_a_block(
        x0, t0, u, plane, np.ascontiguousarray(pack(params)), params.hull.packed, waves[None], 0, distance
    )
    assert np.abs(block - calm).max() > 1e-6  # and the sea moved the boat
