"""RK4 at the environments' step against scipy's solve_ivp (rtol 1e-10) over 600 s, and the
environments' block integrator against the same scheme one state at a time.

Both integrate the same problem: planes held over each 0.5 s control period (zero-order hold),
set either by an open-loop schedule or by the thesis's full-state feedback of the state each
integrator has reached (closed loop). The worst errors are printed in the "measured" summary.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.signal import place_poles

from subenv.analysis import linear_model
from subenv.dynamics import (
    CONTROL_PERIOD_S,
    SUBSTEPS,
    ModelParams,
    control_period,
    derivatives,
    model_params,
    rk4,
)
from subenv.dynamics.model import PARAM_FIELDS, pack_params
from subenv.dynamics.waves import WAVE_FIELDS
from subenv.units import fps_to_mps

DURATION_S = 600.0
DEPTH_TOL_M = 1e-3
PITCH_TOL_RAD = 1e-5


def _thesis_gain(vehicle) -> np.ndarray:
    lm = linear_model(vehicle, fps_to_mps(5.0))
    return place_poles(lm.A, lm.B[:, None], [-0.3, -0.31, -0.32, -0.33]).gain_matrix[0]


def _held(speed, planes: float, params: ModelParams):
    """The right-hand side over a control period, its planes held at ``planes`` (zero-order hold)."""
    return lambda t, x: derivatives(x, speed(t), planes, 0.0, params)


def _planes(mode: str, gain: np.ndarray, x: np.ndarray, t: float) -> float:
    if mode == "open":
        return 0.1 * np.sin(0.05 * t)  # a slow open-loop sweep of the stern planes
    return float(np.clip(-gain @ (x - np.array([0.0, 0.0, 0.0, 10.0])), -0.4, 0.4))


@pytest.mark.parametrize("mode", ["open", "closed"])
@pytest.mark.parametrize("speed", [0.15, 0.5, 1.0, 1.8])
def test_rk4_matches_solve_ivp_over_600_s(suboff, report, mode, speed):
    params = model_params(suboff)
    gain = _thesis_gain(suboff)

    def steady(t: float) -> float:
        return speed

    x_rk = x_ref = np.array([0.05, 0.0, 0.0, 8.0])
    worst_depth = worst_pitch = 0.0
    for k in range(round(DURATION_S / CONTROL_PERIOD_S)):
        t = k * CONTROL_PERIOD_S
        x_rk = rk4(_held(steady, _planes(mode, gain, x_rk, t), params), t, x_rk, CONTROL_PERIOD_S, SUBSTEPS)
        sol = solve_ivp(
            _held(steady, _planes(mode, gain, x_ref, t), params),
            (t, t + CONTROL_PERIOD_S),
            x_ref,
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
        )
        assert sol.success, sol.message
        x_ref = sol.y[:, -1]
        worst_depth = max(worst_depth, abs(x_rk[3] - x_ref[3]))
        worst_pitch = max(worst_pitch, abs(x_rk[0] - x_ref[0]))
    report(
        f"RK4 dt={CONTROL_PERIOD_S / SUBSTEPS} s vs solve_ivp, {mode} loop, u={speed} m/s, 600 s",
        f"worst depth error {worst_depth:.2e} m, worst pitch error {worst_pitch:.2e} rad",
    )
    # The trajectory must actually move, or a small error would prove nothing.
    assert abs(x_ref[3] - 8.0) > 0.05 or abs(x_ref[0]) > 0.01
    assert worst_depth < DEPTH_TOL_M
    assert worst_pitch < PITCH_TOL_RAD


def test_rk4_matches_solve_ivp_through_a_deceleration(suboff, report):
    """Closed loop while the speed ramps from 1.8 to 0.15 m/s over 600 s, through u_cr."""
    params = model_params(suboff)
    gain = _thesis_gain(suboff)

    def speed(t: float) -> float:
        return 1.8 + (0.15 - 1.8) * t / DURATION_S

    x_rk = x_ref = np.array([0.05, 0.0, 0.0, 8.0])
    worst_depth = worst_pitch = 0.0
    for k in range(round(DURATION_S / CONTROL_PERIOD_S)):
        t = k * CONTROL_PERIOD_S
        x_rk = rk4(
            _held(speed, _planes("closed", gain, x_rk, t), params), t, x_rk, CONTROL_PERIOD_S, SUBSTEPS
        )
        sol = solve_ivp(
            _held(speed, _planes("closed", gain, x_ref, t), params),
            (t, t + CONTROL_PERIOD_S),
            x_ref,
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
        )
        x_ref = sol.y[:, -1]
        worst_depth = max(worst_depth, abs(x_rk[3] - x_ref[3]))
        worst_pitch = max(worst_pitch, abs(x_rk[0] - x_ref[0]))
    report(
        "RK4 vs solve_ivp, closed loop, speed 1.8 -> 0.15 m/s over 600 s",
        f"worst depth error {worst_depth:.2e} m, worst pitch error {worst_pitch:.2e} rad",
    )
    assert abs(x_ref[3] - 8.0) > 1.0  # the trajectory moved (to the ordered depth)
    assert worst_depth < DEPTH_TOL_M
    assert worst_pitch < PITCH_TOL_RAD


# --- the block integrator ----------------------------------------------------------------------
def _periods_by_the_reference(x, t0, u0, slope, stern, bow, force, prm, hull_table, dt, substeps):
    """rk4 over derivatives (the NumPy reference), one state at a time, each with its own speed ramp
    u0 + slope (t - t0), planes, force and parameters."""
    for i in range(x.shape[0]):
        params = ModelParams(*prm[i].tolist(), hull=hull_table)

        def f(t, state, i=i, params=params):
            return derivatives(
                state, u0[i] + slope[i] * (t - t0[i]), stern[i], bow[i], params, force=force[i]
            )

        x[i] = rk4(f, t0[i], x[i], dt, substeps)


@pytest.mark.parametrize("n", [1, 63, 64, 65, 1000])
def test_block_integrator_gives_the_bits_of_the_reference(suboff, n):
    rng = np.random.default_rng(n)
    params = model_params(suboff)
    hull = params.hull.packed
    x = np.column_stack(
        [
            rng.uniform(-0.5, 0.5, n),
            rng.uniform(-0.5, 0.5, n),
            rng.uniform(-0.2, 0.2, n),
            rng.uniform(1.0, 30.0, n),
        ]
    )
    # Roots of w - x q on stations, at the ends and off the hull; q = 0; w = 0; states that do not
    # stay finite; a pitch beyond the sine's range.
    stations = hull[0]
    x[::5, 1] = x[::5, 2] * rng.choice(stations, x[::5].shape[0])
    x[1::7, 2] = 0.0
    x[2::11, 1] = 0.0
    if n >= 65:
        x[3, 0], x[4, 1], x[5, 2], x[6, 0] = np.nan, np.inf, -np.inf, 1e7
    # Each state its own time, speed ramp, planes, force and loading.
    t0 = rng.uniform(0.0, 600.0, n)
    u0, slope = rng.uniform(0.1, 2.5, n), rng.uniform(-0.02, 0.02, n) * (rng.random(n) < 0.5)
    stern, bow, force = rng.uniform(-0.4, 0.4, n), rng.uniform(-0.4, 0.4, n), rng.normal(0.0, 2.0, n)
    prm = pack_params(params)[None, :] * rng.uniform(0.8, 1.2, (n, len(PARAM_FIELDS)))
    # Half the states near the free surface (its suction depends on depth: the one state variable the
    # right-hand side did not read before), half in deep water.
    surface = PARAM_FIELDS.index("rho_suction")
    prm[:, surface] = np.where(rng.random(n) < 0.5, 0.0, rng.uniform(500.0, 1500.0, n))
    x[::3, 3] = rng.uniform(0.3, 2.0, x[::3].shape[0])
    one = x.copy()
    with np.errstate(all="ignore"):
        _periods_by_the_reference(
            one, t0, u0, slope, stern, bow, force, prm, params.hull, CONTROL_PERIOD_S, SUBSTEPS
        )
    loadings = ModelParams(*prm.T, hull=params.hull)  # (a row each: stack_params' form)
    block = control_period(x, t0, CONTROL_PERIOD_S, u0, slope, stern, bow, loadings, force, SUBSTEPS)
    np.testing.assert_array_equal(block, one)  # bit for bit (NaN where NaN)
    assert np.isfinite(one[: min(n, 3)]).all() and not np.array_equal(one, x)  # and the states moved


def test_control_period_broadcasts_its_arguments_and_gives_each_state_the_references_bits(suboff):
    params = model_params(suboff)
    x = np.array([0.01, 0.02, -0.003, 10.0])
    speeds, sterns = np.array([[1.0], [0.6]]), np.array([0.05, -0.1, 0.0])
    got = control_period(x, 3.0, CONTROL_PERIOD_S, speeds, 0.01, sterns, 0.02, params, force=5.0)
    assert got.shape == (2, 3, 4)  # (the arguments' shapes broadcast, then the state's 4)
    for i, j in np.ndindex(2, 3):

        def f(t, state, i=i, j=j):
            return derivatives(state, speeds[i, 0] + 0.01 * (t - 3.0), sterns[j], 0.02, params, force=5.0)

        np.testing.assert_array_equal(got[i, j], rk4(f, 3.0, x, CONTROL_PERIOD_S, SUBSTEPS))
    assert not np.array_equal(got[0, 0], got[1, 0]) and not np.array_equal(got[0, 0], got[0, 1])
    sea = np.zeros((0, WAVE_FIELDS, 3))  # (no state, each its own sea)
    empty = control_period(np.zeros((0, 4)), 0.0, CONTROL_PERIOD_S, 1.0, 0.0, 0.0, 0.0, params, waves=sea)
    assert empty.shape == (0, 4)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"state": np.zeros(3)}, r"state has shape \(3,\): must have shape \(\.\.\., 4\)"),
        ({"dt": 0.0}, r"dt=0\.0 is invalid: must be a finite number of seconds > 0"),
        ({"dt": np.nan}, r"dt=nan is invalid"),
        ({"dt": "0.5"}, r"dt='0\.5' is invalid"),
        ({"substeps": 0}, r"substeps=0 is invalid: must be an integer >= 1"),
        ({"substeps": 1.5}, r"substeps=1\.5 is invalid"),
        ({"waves": np.zeros((3, 4))}, rf"waves has shape \(3, 4\): must have shape \(\S+, {WAVE_FIELDS}, W"),
    ],
)
def test_control_period_refuses_bad_arguments_by_name(suboff, change, message):
    arguments = {
        "state": np.array([0.0, 0.0, 0.0, 10.0]),
        "t0": 0.0,
        "dt": CONTROL_PERIOD_S,
        "speed0": 1.0,
        "speed_slope": 0.0,
        "stern": 0.0,
        "bow": 0.0,
        "params": model_params(suboff),
    }
    with pytest.raises(ValueError, match=message):
        control_period(**{**arguments, **change})
