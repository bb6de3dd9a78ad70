"""The right-hand side and the control period of :mod:`subenv.dynamics`, on JAX (:mod:`subenv.jax`)."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

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
    free_surface: bool | None = None,
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
    free_surface : bool, optional
        Whether any loading has a free surface (``rho_suction`` > 0): False leaves its suction out of
        the trace (:func:`~subenv.jax.traced`). By default, found from ``prm`` where it is an array
        of numbers; under ``jax.jit``, where ``prm`` is traced, True.
    """
    hull = jnp.asarray(hull)
    rhs = traced(model.rhs_point, _free_surface(prm, free_surface))

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
    free_surface: bool | None = None,
    waves: Any = None,
    distance0: Any = 0.0,
) -> Any:
    """The state after one control period ``dt`` [s] from time ``t0`` [s]: the environments' integrator,
    :func:`subenv.dynamics.rk4` (``substeps`` RK4 steps, the reference's own code) over
    :func:`derivatives`, with the planes and the heave ``force`` held and the speed
    ``speed0 + speed_slope (t - t0)`` [m/s]. Arguments as :func:`derivatives`'s; batched the same way.

    ``waves``: the sea of each state, shape (..., WAVE_FIELDS, MAX_WAVES)
    (:meth:`subenv.dynamics.waves.SeaState.components`; zeros for a calm one), whose force
    (:func:`~subenv.dynamics.waves.wave_force_point`, all MAX_WAVES columns: the unused ones are zero)
    acts at every stage, at the stage's time, depth and distance travelled
    (:func:`~subenv.dynamics.integrate.distance_travelled` from ``distance0`` [m] at ``t0``), as in
    the environments. (Whether the suction is computed depends on the loadings alone, as in
    :func:`derivatives`: a sea in deep water has none.)
    """
    free_surface = _free_surface(prm, free_surface)
    wave_force = _wave_force(waves)

    def rhs(t: Any, x: Any) -> Any:
        speed = speed0 + speed_slope * (t - t0)
        if wave_force is None:
            return derivatives(x, speed, stern, bow, prm, hull, force, free_surface=free_surface)
        distance = traced(integrate.distance_travelled)(distance0, t - t0, speed0, speed_slope)
        heave, pitch = wave_force(t, distance, x[..., 3], speed, waves)
        return derivatives(x, speed, stern, bow, prm, hull, force + heave, pitch, free_surface=free_surface)

    # (the reference's own RK4, typed for NumPy arrays, run on JAX's: the same arithmetic)
    return integrate.rk4(rhs, t0, jnp.asarray(state), dt, substeps)  # type: ignore[arg-type]


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


def _free_surface(prm: Any, free_surface: bool | None) -> bool:
    """Whether the loadings ``prm`` need the free surface's suction (see :func:`derivatives`)."""
    if isinstance(prm, jax.core.Tracer):
        return True if free_surface is None else bool(free_surface)
    rho_suction = np.asarray(prm)[..., model.PARAM_FIELDS.index("rho_suction")]
    present = bool(np.any(rho_suction != 0.0))
    if free_surface is None:
        return present
    if present and not free_surface:
        raise ValueError(
            f"free_surface={free_surface!r} is invalid for these loadings: {np.count_nonzero(rho_suction)} "
            "of them have a free surface (rho_suction > 0); pass True or None"
        )
    return bool(free_surface)
