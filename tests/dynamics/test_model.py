"""The right-hand side: batching, physical signs, equilibria and agreement with the linear model."""

from __future__ import annotations

import numpy as np
import pytest

from subenv.analysis import linear_model, numerical_jacobian
from subenv.dynamics import derivatives, derivatives_with, dual_plane_angles, model_params, stack_params
from subenv.dynamics.free_surface import FreeSurface
from subenv.dynamics.model import PARAM_FIELDS, pack_params


def test_level_flight_is_an_equilibrium_of_the_neutral_boat(suboff):
    p = model_params(suboff)
    for u in (0.2, 0.6, 1.5):
        f = derivatives(np.zeros(4), u, 0.0, 0.0, p)
        np.testing.assert_allclose(f, 0.0, atol=1e-15)


def test_batched_equals_one_at_a_time(suboff):
    rng = np.random.default_rng(1)
    n = 9
    states = rng.normal(0, [0.1, 0.1, 0.05, 5.0], size=(n, 4))
    speeds = rng.uniform(0.15, 1.8, n)
    stern, bow = rng.uniform(-0.4, 0.4, n), rng.uniform(-0.4, 0.4, n)
    vehicles = [
        suboff.variant(x_GB_m=float(x), excess_buoyancy_N=float(e), crossflow_drag=float(c))
        for x, e, c in zip(rng.normal(0, 2e-3, n), rng.normal(0, 3, n), rng.uniform(0, 0.6, n), strict=True)
    ]
    batch = derivatives(states, speeds, stern, bow, stack_params([model_params(v) for v in vehicles]))
    for i, v in enumerate(vehicles):
        one = derivatives(states[i], speeds[i], stern[i], bow[i], model_params(v))
        np.testing.assert_allclose(batch[i], one, rtol=1e-14, atol=1e-16)


def test_one_compiled_signature_whatever_the_inputs_flags_and_one_states_bits_are_the_batchs(suboff):
    # numba types a read-only array apart from a writable one: derivatives hands its kernel read-only
    # rows always (subenv.dynamics._jit.rows), so writable, read-only, scalar and batched inputs share
    # one compiled signature (four compiled, 5 s each, in one subenv evaluate before), and the path for
    # one state gives the bits of the batch's rows.
    from subenv.dynamics.model import _derivatives_rows

    prm = model_params(suboff)
    states = np.array([[0.01, 0.02, 0.001, 10.0], [-0.02, 0.01, 0.003, 12.0]])
    frozen = states.copy()
    frozen.flags.writeable = False
    speeds = np.array([0.4, 1.1])
    batch = derivatives(states, speeds, 0.1, np.array([0.0, -0.05]), prm, force=np.array([3.0, 0.0]))
    for i, state in enumerate([states[0], frozen[1]]):
        one = derivatives(state, float(speeds[i]), 0.1, [0.0, -0.05][i], prm, force=[3.0, 0.0][i])
        assert one.tobytes() == batch[i].tobytes()
    derivatives(frozen, speeds, np.float64(0.1), 0.0, prm)
    assert len(_derivatives_rows.signatures) == 1, _derivatives_rows.signatures


def test_derivatives_with_a_fixed_loading_are_derivatives_bits_for_any_input(suboff):
    # (the analysis's solvers call it for one state at a time; batches and batched loadings go through)
    prm = model_params(suboff, FreeSurface())
    rhs = derivatives_with(prm)
    state = np.array([0.01, 0.02, 0.001, 0.9])  # near the surface: the suction's branch too
    for args in [(0.4, 0.1, -0.05), (np.float64(1.1), 0.0, 0.0, 3.0, -2.0), (0.7, 0.2, 0.0, 0.0, 1.5)]:
        assert rhs(state, *args).tobytes() == derivatives(state, *args[:3], prm, *args[3:]).tobytes()
    states = np.array([[0.01, 0.02, 0.001, 10.0], [-0.02, 0.01, 0.003, 0.8]])
    speeds = np.array([0.4, 1.1])
    assert rhs(states, speeds, 0.1, 0.0).tobytes() == derivatives(states, speeds, 0.1, 0.0, prm).tobytes()
    assert rhs(list(state), 0.5, 0.1, 0.0).tobytes() == derivatives(state, 0.5, 0.1, 0.0, prm).tobytes()
    many = stack_params([model_params(suboff), model_params(suboff.variant(z_GB_m=0.02))])
    assert (
        derivatives_with(many)(states, 0.6, 0.0, 0.0).tobytes()
        == derivatives(states, 0.6, 0.0, 0.0, many).tobytes()
    )
    with pytest.raises(ValueError, match=r"state has shape \(3,\): must have shape \(\.\.\., 4\)"):
        rhs(np.zeros(3), 0.5, 0.0, 0.0)


def test_params_of_many_loadings_are_each_variants_bit_for_bit(suboff):
    # A vector environment's batch of resets computes its loadings' parameters as arrays: the same
    # arithmetic as one variant's (NumPy's +, -, *, / are correctly rounded, as Python's), so the same bits.
    rng = np.random.default_rng(2)
    n = 200
    z_GB, x_GB = rng.uniform(-0.01, 0.03, n), rng.normal(0, 2e-3, n)
    excess, C_D = rng.normal(0, 3, n), rng.uniform(0, 0.6, n)
    fields = suboff.loading_fields(z_GB_m=z_GB, x_GB_m=x_GB, excess_buoyancy_N=excess, crossflow_drag=C_D)
    batch = pack_params(model_params(suboff, FreeSurface(), fields))
    assert batch.shape == (n, len(PARAM_FIELDS))
    for i in range(n):
        vehicle = suboff.variant(
            z_GB_m=z_GB[i], x_GB_m=x_GB[i], excess_buoyancy_N=excess[i], crossflow_drag=C_D[i]
        )
        assert batch[i].tobytes() == pack_params(model_params(vehicle, FreeSurface())).tobytes(), i
    with pytest.raises(ValueError, match=r"loading has unknown fields \['z_GB_m'\]: allowed are \['x_G_m'"):
        model_params(suboff, loading={"z_GB_m": 0.01})


def test_physical_signs(suboff):
    p = model_params(suboff)
    heavy = model_params(suboff.variant(excess_buoyancy_N=-10.0))
    assert derivatives(np.zeros(4), 0.0, 0.0, 0.0, heavy)[1] > 0  # heavier than buoyant: sinks
    # z_GB > 0: a nose-up pitch is restored nose-down.
    assert derivatives(np.array([0.1, 0, 0, 0]), 0.0, 0.0, 0.0, p)[2] < 0
    # A positive stern plane lifts the stern: upward force, nose-down moment (Z'_ds, M'_ds < 0).
    f = derivatives(np.zeros(4), 1.0, 0.1, 0.0, model_params(suboff.variant(crossflow_drag=0.0)))
    assert f[1] < 0 and f[2] < 0
    # Depth kinematics: nose-down pitch at speed increases depth (eq. 2.41).
    assert derivatives(np.array([-0.1, 0, 0, 5.0]), 1.0, 0.0, 0.0, p)[3] > 0


def test_hull_drag_dissipates_energy(suboff):
    """Z_drag w + M_drag q <= 0: the consistent moment sign never feeds energy into the motion."""
    rng = np.random.default_rng(2)
    w, q = rng.normal(0, 0.3, 500), rng.normal(0, 0.2, 500)
    states = np.stack([np.zeros(500), w, q, np.zeros(500)], axis=1)
    with_drag = model_params(suboff.variant(crossflow_drag=0.5))
    no_drag = model_params(suboff.variant(crossflow_drag=0.0))
    # Forces recovered through the mass matrix: M (f_drag - f_nodrag) gives (Z_drag, M_drag).
    df = derivatives(states, 0.0, 0.0, 0.0, with_drag) - derivatives(states, 0.0, 0.0, 0.0, no_drag)
    inv = np.array([[with_drag.inv_m11, with_drag.inv_m12], [with_drag.inv_m21, with_drag.inv_m22]])
    forces = df[:, 1:3] @ np.linalg.inv(inv).T
    power = forces[:, 0] * w + forces[:, 1] * q
    assert np.all(power <= 1e-12)
    assert power.min() < -1e-3


def test_dual_control_slaves_the_bow_planes():
    stern, bow = dual_plane_angles(np.array([0.2, -0.4]), 0.5)
    np.testing.assert_array_equal(stern, [0.2, -0.4])
    np.testing.assert_array_equal(bow, [0.1, -0.2])


@pytest.mark.parametrize("u", [0.15, 0.58, 1.0, 1.8])
@pytest.mark.parametrize("alpha", [-1.0, 0.0, 0.5])
def test_numerical_jacobian_equals_closed_form_linear_model(suboff, u, alpha):
    no_drag = suboff.variant(crossflow_drag=0.0)
    lm = linear_model(no_drag, u, alpha)
    A, B = numerical_jacobian(no_drag, u, np.zeros(4), 0.0, 0.0)
    np.testing.assert_allclose(A, lm.A, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(B[:, 0] + alpha * B[:, 1], lm.B, rtol=1e-6, atol=1e-12)
    # Drag is quadratic in (w, q): it leaves the linearisation unchanged (up to the O(eps)
    # error of central differences across the kink of w|w|).
    A_drag, _ = numerical_jacobian(suboff, u, np.zeros(4), 0.0, 0.0, eps=1e-8)
    np.testing.assert_allclose(A_drag, lm.A, rtol=0, atol=1e-6)


def test_linear_model_with_ballast_offset_matches_jacobian(suboff):
    v = suboff.variant(x_GB_m=0.01, crossflow_drag=0.0)
    lm = linear_model(v, 1.0)
    A, B = numerical_jacobian(v, 1.0, np.zeros(4), 0.0, 0.0)
    np.testing.assert_allclose(A, lm.A, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(B[:, 0], lm.B, rtol=1e-6, atol=1e-12)


_COLD_CACHE_PROGRAM = """
import numpy as np
from subenv.dynamics import crossflow_integrals, derivatives, model_params
from subenv.dynamics.free_surface import suction
from subenv.vehicles import load_vehicle
v = load_vehicle("suboff")
params = model_params(v)
x = np.linspace(-1.0, 1.0, 7)
states = np.stack([0.1 * x, 0.05 * x, 0.01 * x, 10 + x], axis=-1)
d = derivatives(states, 1.2, 0.05 * x, -0.02, params)
i0, i1 = crossflow_integrals(params.hull, 0.05 * x, 0.01 * x)
zs, ms = suction(params.hull, 0.1 * x, 1.0 + 0.2 * x, 1.0, 1000.0)
print(repr(np.concatenate([d.ravel(), i0, i1, zs, ms]).tolist()))
"""


def test_two_processes_compiling_the_batched_functions_at_once_on_a_cold_cache_both_get_the_answer(
    tmp_path,
) -> None:  # type: ignore[no-untyped-def]
    # numba's cached generalized ufuncs could segfault here (numba#10128: two Ray workers did); the batched
    # functions are plain kernels over rows instead (subenv/dynamics/_jit.py).
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}

    def start() -> subprocess.Popen[str]:
        return subprocess.Popen(
            [sys.executable, "-c", _COLD_CACHE_PROGRAM],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )

    procs = [start(), start()]
    outputs = [p.communicate(timeout=600) for p in procs]
    later = start()  # then one that loads what they cached
    outputs.append(later.communicate(timeout=600))
    assert [p.returncode for p in (*procs, later)] == [0, 0, 0], [err[-2000:] for _, err in outputs]
    assert outputs[0][0] == outputs[1][0] == outputs[2][0] and outputs[0][0].startswith("[")
