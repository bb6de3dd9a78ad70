"""The right-hand side and the control period of :mod:`subenv.dynamics`, on JAX (:mod:`subenv.jax`)."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from subenv.dynamics import integrate, model
from subenv.dynamics.waves import wave_force_point
from subenv.jax._trace import traced

__all__ = ["control_period", "derivatives", "rhs_point"]

rhs_point = traced(model.rhs_point)
""":func:`subenv.dynamics.model.rhs_point` on JAX: d/dt (theta, w, q, Z) of one state, as a tuple of
four scalars."""


def derivatives(
    state: Any,
    speed: Any,
    stern: Any,
    bow: Any,
    prm: Any,
    hull: Any,
    force: Any = 0.0,
    moment: Any = 0.0,
    free_surface: bool = True,
) -> Any:
    """d/dt (theta, w, q, Z), shape ``state.shape``: :func:`subenv.dynamics.derivatives` on JAX.

    Parameters
    ----------
    state : array, shape (..., 4)
        Pitch [rad], heave velocity [m/s], pitch rate [rad/s], depth [m].
    speed, stern, bow, force, moment : array
        Forward speed [m/s], the stern and bow planes [rad], the heave force [N] and the pitch
        moment [N m] held: scalars or arrays that broadcast with ``state.shape[:-1]``.
    prm : array, shape (..., len(PARAM_FIELDS))
        The loadings, packed (:func:`subenv.dynamics.model.pack_params` of
        :func:`subenv.dynamics.model_params`): one, or one per state.
    hull : array
        The vehicle's hull table, :attr:`subenv.dynamics.HullTable.packed` (one for the batch).
    free_surface : bool
        Static (part of the traced program: under ``jax.jit``, a Python bool, in
        ``static_argnames``). True computes the free surface's suction for every state, zero where
        a loading has none (``rho_suction`` 0); False leaves it out of the trace
        (:func:`~subenv.jax.traced`), several times faster in deep water, and gives NaN for any
        loading that has one.
    """
    hull = jnp.asarray(hull)
    rhs = traced(model.rhs_point, free_surface)

    def one(x: Any, u: Any, s: Any, b: Any, f: Any, m: Any, p: Any) -> Any:
        return jnp.stack(rhs(x[0], x[1], x[2], x[3], u, s, b, f, m, p, hull))

    return jnp.vectorize(one, signature="(4),(),(),(),(),(),(k)->(4)")(
        jnp.asarray(state), speed, stern, bow, force, moment, jnp.asarray(prm)
    )


def control_period(
    state: Any,
    t0: Any,
    dt: float,
    speed0: Any,
    speed_slope: Any,
    stern: Any,
    bow: Any,
    prm: Any,
    hull: Any,
    force: Any = 0.0,
    substeps: int = integrate.SUBSTEPS,
    free_surface: bool = True,
    waves: Any = None,
    distance0: Any = 0.0,
) -> Any:
    """The state after one control period ``dt`` [s] from time ``t0`` [s]: the environments' integrator,
    :func:`subenv.dynamics.rk4` (``substeps`` RK4 steps of the reference's own code) over
    :func:`derivatives`, with the planes and the heave ``force`` held and the speed
    ``speed0 + speed_slope (t - t0)`` [m/s]. Arguments as :func:`derivatives`'s; batched the same way.

    ``waves``: the sea of each state, shape (..., WAVE_FIELDS, MAX_WAVES)
    (:meth:`subenv.dynamics.waves.SeaState.components`; zeros for a calm one), whose force
    (:func:`~subenv.dynamics.waves.wave_force_point`, all MAX_WAVES columns: the unused ones are zero)
    acts at every stage, at the stage's time, depth and distance travelled
    (:func:`~subenv.dynamics.integrate.distance_travelled` from ``distance0`` [m] at ``t0``), as in
    the environments. (``free_surface`` is :func:`derivatives`'s: the suction depends on the loadings
    alone; a sea in deep water has none.)
    """
    wave_force = _wave_force(waves)

    def rhs(t: Any, x: Any) -> Any:
        speed = speed0 + speed_slope * (t - t0)
        if wave_force is None:
            return derivatives(x, speed, stern, bow, prm, hull, force, free_surface=free_surface)
        distance = traced(integrate.distance_travelled)(distance0, t - t0, speed0, speed_slope)
        heave, pitch = wave_force(t, distance, x[..., 3], speed, waves)
        return derivatives(x, speed, stern, bow, prm, hull, force + heave, pitch, free_surface=free_surface)

    # The reference's rk4 (NumPy's and JAX's alike), its steps in a loop of XLA's: the program holds the
    # right-hand side once per stage, not once per stage and step. The environments' step, traced,
    # lowered and compiled, 3 runs each: PeriscopeDepthWaves-v1 6.6-7.1 s unrolled, 3.7-4.2 s so;
    # PeriscopeDepth-v2 5.1-5.4 -> 3.3-3.6 s; Nominal-v0 2.6-3.0 -> 2.3-2.7 s. It steps as fast or
    # faster (benchmarks/jax_env.py).
    x0: Any = jnp.asarray(state)
    return integrate.rk4(rhs, t0, x0, dt, substeps, loop=jax.lax.fori_loop)


def _wave_force(waves: Any) -> Any:
    """The sea's (heave force, pitch moment) at (t, distance, depth, speed) for seas ``waves`` (None:
    calm)."""
    if waves is None:
        return None
    force_point = traced(wave_force_point)
    columns = jnp.shape(waves)[-1]

    def one(t: Any, distance: Any, depth: Any, speed: Any, sea: Any) -> Any:
        return jnp.stack(force_point(t, distance, depth, speed, sea, columns))

    vectorized = jnp.vectorize(one, signature="(),(),(),(),(f,w)->(2)")

    def force(t: Any, distance: Any, depth: Any, speed: Any, seas: Any) -> tuple[Any, Any]:
        both = vectorized(t, distance, depth, speed, jnp.asarray(seas))
        return both[..., 0], both[..., 1]

    return force
