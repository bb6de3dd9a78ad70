"""The dynamics on JAX (subenv.jax) against the compiled ones: the same source, traced."""

import numpy as np
import pytest

pytest.importorskip("jax", reason="the 'jax' extra is not installed")

import jax
import jax.numpy as jnp

import subenv
import subenv.jax as sj
from subenv.dynamics import control_period, derivatives, integrate, model, model_params, rk4, stack_params
from subenv.dynamics import hull as hull_table
from subenv.dynamics.free_surface import FreeSurface
from subenv.dynamics.model import pack_params
from subenv.dynamics.waves import MAX_WAVES, WAVE_FIELDS, SeaState
from subenv.jax.dynamics import rhs_point

TOLERANCE = 1e-12  # relative, and absolute for components near zero
N = 400


def _loadings(vehicle_name, rng, free_surface):
    """N loadings of one vehicle (one hull): its own, and variants of its metacentric height,
    longitudinal balance, excess buoyancy and cross-flow drag; near the surface with ``free_surface``."""
    vehicle = subenv.load_vehicle(vehicle_name)
    # (both theories of the suction, the loading's picked: FreeSurface.theory)
    surfaces = (
        (FreeSurface(), FreeSurface(theory="sources-only"))
        if free_surface
        else (FreeSurface(suction_factor=0.0),)
    )
    variants = [model_params(vehicle, surfaces[0])]
    for i in range(7):
        variants.append(
            model_params(
                vehicle.variant(
                    z_GB_m=vehicle.z_GB_m * rng.uniform(0.2, 3.0),
                    x_GB_m=rng.uniform(-0.01, 0.01) * vehicle.length_m,
                    excess_buoyancy_N=rng.uniform(-0.01, 0.01) * vehicle.weight_N,
                    crossflow_drag=rng.uniform(0.0, 1.0),
                ),
                surfaces[(i + 1) % len(surfaces)],
            )
        )
    return stack_params([variants[i % len(variants)] for i in range(N)])


def _inputs(rng, vehicle_name, free_surface):
    params = _loadings(vehicle_name, rng, free_surface)
    length = subenv.load_vehicle(vehicle_name).length_m
    depth_low = 0.6 * length / 8.0 if free_surface else 5.0  # periscope depth: the suction is strong
    state = np.column_stack(
        [
            rng.uniform(-0.4, 0.4, N),
            rng.uniform(-0.5, 0.5, N),
            rng.uniform(-0.1, 0.1, N),
            rng.uniform(depth_low, depth_low + 3.0, N),
        ]
    )
    state[:20, 1:3] = 0.0  # level flight: w = q = 0, the cross-flow's root at the hull's end
    state[20:40, 2] = 0.0
    inputs = {
        "speed": rng.uniform(0.2, 2.5, N),
        "stern": rng.uniform(-0.4, 0.4, N),
        "bow": rng.uniform(-0.4, 0.4, N),
        "force": rng.normal(0.0, 0.01 * params.W_minus_B.max() + 10.0, N),
    }
    return state, params, inputs


@pytest.mark.parametrize(
    "vehicle_name, free_surface", [("suboff", False), ("suboff", True), ("remus100", True)]
)
def test_the_right_hand_side_on_jax_is_the_compiled_one(vehicle_name, free_surface):
    rng = np.random.default_rng(11)
    state, params, inputs = _inputs(rng, vehicle_name, free_surface)
    moment = rng.normal(0.0, 50.0, N)
    expected = derivatives(
        state, inputs["speed"], inputs["stern"], inputs["bow"], params, inputs["force"], moment
    )
    got = jax.jit(sj.derivatives)(
        state,
        inputs["speed"],
        inputs["stern"],
        inputs["bow"],
        pack_params(params),
        params.hull.packed,
        inputs["force"],
        moment,
    )
    assert got.dtype == jnp.float64
    np.testing.assert_allclose(np.asarray(got), expected, rtol=TOLERANCE, atol=TOLERANCE)
    if free_surface:  # (the suction is in the comparison: without it the answer differs)
        deep_params = params._replace(rho_suction=0.0 * params.rho_suction)
        deep = derivatives(
            state, inputs["speed"], inputs["stern"], inputs["bow"], deep_params, inputs["force"], moment
        )
        assert np.max(np.abs(deep - expected)) > 1e3 * TOLERANCE


@pytest.mark.parametrize(
    "vehicle_name, free_surface", [("suboff", False), ("suboff", True), ("remus100", False)]
)
def test_twenty_control_periods_on_jax_are_the_compiled_ones(vehicle_name, free_surface):
    """The environments' integrator (rk4 over the right-hand side, two steps per 0.5 s period; the
    block integrator gives its bits, tests/dynamics/test_integrator.py) with speed ramps."""
    rng = np.random.default_rng(12)
    state, params, inputs = _inputs(rng, vehicle_name, free_surface)
    slope = rng.uniform(-0.01, 0.01, N)
    slope[: N // 2] = 0.0
    prm, hull = pack_params(params), params.hull.packed
    period = jax.jit(
        lambda x, t0: sj.control_period(
            x,
            t0,
            0.5,
            inputs["speed"] + slope * t0,
            slope,
            inputs["stern"],
            inputs["bow"],
            prm,
            hull,
            inputs["force"],
        )
    )
    expected, got = state.copy(), jnp.asarray(state)
    for k in range(20):
        t0 = 0.5 * k
        speed0 = inputs["speed"] + slope * t0

        def rhs(t, x, t0=t0, speed0=speed0):
            return derivatives(
                x, speed0 + slope * (t - t0), inputs["stern"], inputs["bow"], params, inputs["force"]
            )

        expected = rk4(rhs, t0, expected, 0.5, 2)
        got = period(got, t0)
    assert np.all(np.isfinite(expected))
    assert np.max(np.abs(expected - state)) > 0.01  # (the states moved)
    np.testing.assert_allclose(np.asarray(got), expected, rtol=TOLERANCE, atol=TOLERANCE)


def test_the_jax_functions_run_the_kernels_own_code():
    """No second copy of an equation: the twin is the compiled function's code object, re-bound."""
    assert rhs_point.__code__ is model.rhs_point.py_func.__code__
    assert sj.traced(model.rhs_given_drag).__code__ is model.rhs_given_drag.py_func.__code__
    assert sj.traced(model.rhs_point) is rhs_point  # (one twin per kernel)


@pytest.mark.parametrize("vehicle_name", ["suboff", "remus100"])
def test_the_hull_segment_on_jax_is_the_compiled_loops_count(vehicle_name):
    """The hull's segment search is replaced on JAX by a count over the row of stations
    (subenv.jax._trace): the same integer as the compiled loop's at, between, just aft of and beyond
    every station, for NaN and the infinities. (Not for subnormal numbers, which XLA compares as zeros on
    a CPU: a station at 0.0 is not told from -5e-324, as for subenv.dynamics._jit.maximum.)"""
    hull = model_params(subenv.load_vehicle(vehicle_name)).hull.packed
    x = hull[0]
    aft = np.where(x == 0.0, -1e-300, np.nextafter(x, -np.inf))  # (the next number aft, or a normal one)
    points = np.concatenate([x, 0.5 * (x[:-1] + x[1:]), aft, [x[0] - 1.0, x[-1] + 1.0, 0.0, -0.0]])
    points = np.concatenate([points, [np.nan, np.inf, -np.inf]])
    twin = sj.traced(hull_table.hull_segment)
    assert twin.__code__ is not hull_table.hull_segment.py_func.__code__  # (replaced, not its code traced)
    got = np.asarray(jax.jit(jax.vmap(lambda s: twin(s, jnp.asarray(hull))))(jnp.asarray(points)))
    expected = np.array([hull_table.hull_segment(float(s), hull) for s in points])
    np.testing.assert_array_equal(got, expected)
    assert set(expected) == set(range(x.size - 1))  # (every segment, and the ends clipped)


def test_the_jax_right_hand_side_batches_and_differentiates():
    params = model_params(subenv.load_vehicle("suboff"))
    prm, hull = pack_params(params), params.hull.packed
    state = jnp.array([0.01, 0.02, 0.001, 10.0])
    # (Each under jit: one program, where op-by-op dispatch compiles each operation's own; the functions
    # run without jit too: test_deep_water_leaves_the_suction_out_and_gives_nan_for_a_free_surface.)
    one = jax.jit(sj.derivatives)(state, 1.0, 0.1, 0.0, prm, hull)
    assert one.shape == (4,)
    many = jax.jit(jax.vmap(lambda x: sj.derivatives(x, 1.0, 0.1, 0.0, prm, hull)))(
        jnp.stack([state, 2 * state])
    )
    np.testing.assert_array_equal(np.asarray(many[0]), np.asarray(one))
    # d(depth rate)/d(heave) = cos(theta) (Riedel 1993 eq. 2.41), through the traced code.
    slope = jax.jit(jax.grad(lambda w: sj.derivatives(state.at[1].set(w), 1.0, 0.1, 0.0, prm, hull)[3]))(0.02)
    assert float(slope) == pytest.approx(np.cos(0.01), rel=1e-12)


def test_a_control_period_differentiates_through_its_loop_of_steps():
    """Reverse mode (jax.grad's) through the control period's RK4 steps, which run in a loop of XLA's (its
    bounds static, as reverse mode needs): the Jacobian of the state after a period, against central
    differences of the compiled integrator. In deep water (``free_surface=False``: the loop is the subject,
    and a program without the suction compiles in half the time)."""
    params = model_params(subenv.load_vehicle("suboff"))
    prm, hull = pack_params(params), params.hull.packed
    state = np.array([0.01, 0.02, 0.001, 10.0])
    args = (0.0, 0.5, 1.0, 0.002, 0.1, -0.05)  # t0, dt, speed0, speed_slope, stern, bow
    period = jax.jacrev(lambda x: sj.control_period(x, *args, prm, hull, free_surface=False))
    jacobian = jax.jit(period)(jnp.asarray(state))

    def after(x):  # (the compiled integrator's batch of one state)
        return control_period(x, *args, params).reshape(4)

    eps = 1e-6
    differences = np.column_stack(
        [(after(state + step) - after(state - step)) / (2 * eps) for step in eps * np.eye(4)]
    )
    np.testing.assert_allclose(np.asarray(jacobian), differences, rtol=1e-6, atol=1e-8)


def test_deep_water_leaves_the_suction_out_and_gives_nan_for_a_free_surface():
    """``free_surface`` is static: False leaves the suction out of the program, under jit as without, and
    a loading that has one gets NaN, never the deep-water derivatives (before, under jit, a traced ``prm``
    was not looked at and such loadings got them silently)."""
    rng = np.random.default_rng(13)
    state, deep, inputs = _inputs(rng, "suboff", free_surface=False)
    args = (state, inputs["speed"], inputs["stern"], inputs["bow"])
    prm, hull = pack_params(deep), deep.hull.packed
    without = sj.derivatives(*args, prm, hull, free_surface=False)
    np.testing.assert_allclose(np.asarray(without), derivatives(*args, deep), rtol=TOLERANCE, atol=TOLERANCE)
    near = pack_params(_loadings("suboff", rng, free_surface=True))
    mixed = np.where((np.arange(N) % 2 == 0)[:, None], near, prm)  # (every other loading near the surface)
    nan = np.zeros((N, 4), dtype=bool)
    nan[0::2, 1:3] = True  # (the rates of w and q, which the suction enters, where a loading has one)
    for run in (sj.derivatives, jax.jit(sj.derivatives, static_argnames="free_surface")):
        got = np.asarray(run(*args, mixed, hull, free_surface=False))
        np.testing.assert_array_equal(np.isnan(got), nan)
        np.testing.assert_allclose(got[1::2], np.asarray(without)[1::2], rtol=TOLERANCE, atol=TOLERANCE)
    with pytest.raises(ValueError, match=r"free_surface='no' is invalid: must be True or False"):
        sj.derivatives(*args, prm, hull, free_surface="no")
    with pytest.raises(ValueError, match=r"free_surface=.*Tracer.* is invalid: must be True or False"):
        jax.jit(sj.derivatives)(*args, prm, hull, free_surface=False)  # (not static: refused by name)


def test_twenty_control_periods_in_a_sea_on_jax_are_the_environments_block_integrator():
    """Waves at every stage (each state its own sea, some calm), the suction, speed ramps: JAX's control
    period against the compiled block integrator itself."""
    rng = np.random.default_rng(14)
    _, _, inputs = _inputs(rng, "suboff", free_surface=True)
    params = stack_params(
        [model_params(subenv.load_vehicle("suboff"), FreeSurface())] * N
    )  # (one loading: a sea
    # drives the light variants of the other tests out of the water within 20 periods)
    state = np.column_stack(
        [
            rng.uniform(-0.05, 0.05, N),
            rng.uniform(-0.05, 0.05, N),
            rng.uniform(-0.01, 0.01, N),
            rng.uniform(1.0, 2.0, N),
        ]
    )  # near level flight at periscope depth (SUBOFF: 4.4 m long)
    inputs["stern"], inputs["bow"], inputs["force"] = (
        0.1 * inputs["stern"],
        0.1 * inputs["bow"],
        0.1 * inputs["force"],
    )
    inputs["speed"] = rng.uniform(
        0.3, 1.0, N
    )  # (PeriscopeDepth's speeds: faster, the suction broaches the boat)
    vehicle = subenv.load_vehicle("suboff")
    sea = SeaState(significant_height_m=0.03, peak_period_s=2.0, waves=12)
    seas = np.stack(
        [
            sea.components(
                rng.random(sea.waves),
                rng.uniform(0.0, 2.0 * np.pi, sea.waves),
                vehicle.hull.x_m,
                vehicle.hull.breadth_m,
                vehicle.water_density_kg_m3,
                vehicle.gravity_m_s2,
            )
            for _ in range(N)
        ]
    )
    seas[: N // 4] = 0.0  # calm
    assert seas.shape[1:] == (WAVE_FIELDS, MAX_WAVES)
    slope = rng.uniform(-0.01, 0.01, N)
    prm, hull = pack_params(params), params.hull.packed
    distance = rng.uniform(0.0, 100.0, N)

    @jax.jit
    def period(x, t0, speed0, distance0):
        return sj.control_period(
            x,
            t0,
            integrate.CONTROL_PERIOD_S,
            speed0,
            slope,
            inputs["stern"],
            inputs["bow"],
            prm,
            hull,
            inputs["force"],
            waves=seas,
            distance0=distance0,
        )

    expected, got = state.copy(), jnp.asarray(state)
    for k in range(20):
        t0 = integrate.CONTROL_PERIOD_S * k
        speed0 = inputs["speed"] + slope * t0
        expected = control_period(
            expected,
            t0,
            integrate.CONTROL_PERIOD_S,
            speed0,
            slope,
            inputs["stern"],
            inputs["bow"],
            params,
            inputs["force"],
            waves=seas,
            distance0=distance,
        )
        got = period(got, t0, speed0, distance)
        speed1 = speed0 + slope * integrate.CONTROL_PERIOD_S
        distance = (
            distance + 0.5 * (speed0 + speed1) * integrate.CONTROL_PERIOD_S
        )  # as the transition keeps it
    assert np.all(np.isfinite(expected))
    np.testing.assert_allclose(np.asarray(got), expected, rtol=TOLERANCE, atol=TOLERANCE)
    # (The compiled integrator without a sea: JAX's program without one is the other tests'.)
    calm = control_period(
        state,
        0.0,
        integrate.CONTROL_PERIOD_S,
        inputs["speed"],
        slope,
        inputs["stern"],
        inputs["bow"],
        params,
        inputs["force"],
    )
    first = np.asarray(period(jnp.asarray(state), 0.0, inputs["speed"], rng.uniform(0.0, 100.0, N)))
    assert np.abs(first - calm)[N // 4 :].max() > 1e-9  # (and the sea moves the states that have one)
    np.testing.assert_allclose(
        first[: N // 4], calm[: N // 4], rtol=TOLERANCE, atol=TOLERANCE
    )  # (calm: not moved)
