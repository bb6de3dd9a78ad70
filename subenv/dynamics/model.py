"""The nonlinear vertical-plane equations of motion (Riedel 1993 eqs 2.38-2.43), written once.

State ``x = (theta, w, q, Z)``: pitch [rad, nose-up positive], heave velocity [m/s, down positive],
pitch rate [rad/s] and depth [m, down positive]. Forward speed ``u`` [m/s] is an input.

The equations are written once, for one state, in :func:`rhs_point`, compiled with numba (see
:mod:`subenv.dynamics._jit`): the hull's cross-flow integrals (:mod:`subenv.dynamics.hull`), then
:func:`rhs_given_drag`, the equations given them. Everything that needs the physics calls these:
the environments' block integrator (:func:`subenv.dynamics.integrate.control_period_lanes`, the
same two steps over a block of states), and the linearisation, controller design and analysis
through :func:`derivatives`, the batched form of ``rhs_point``: a pure function over any leading
axes, states ``(..., 4)``, inputs and :class:`ModelParams` fields broadcast against ``(...)``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Final, NamedTuple

import numpy as np

from subenv._typing import ArrayLike, FloatArray
from subenv.dynamics._jit import inline_kernel, kernel, rows
from subenv.dynamics.free_surface import NO_FREE_SURFACE, FreeSurface, suction_point
from subenv.dynamics.hull import SOURCE_ROW, HullTable, crossflow_point
from subenv.dynamics.sincos import sincos_point
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "PARAM_FIELDS",
    "ModelParams",
    "derivatives",
    "dual_plane_angles",
    "model_params",
    "pack_params",
    "rhs_given_drag",
    "rhs_point",
    "stack_params",
    "state_array",
]


class ModelParams(NamedTuple):
    """The vehicle reduced to the numbers :func:`derivatives` uses, in SI.

    Each field but ``hull`` is a float or an array broadcastable against the batch, so one
    vector environment can hold a different loading in every sub-environment.
    Build with :func:`model_params`; never by hand.
    """

    inv_m11: ArrayLike  # inverse of the 2x2 added-mass matrix of (w, q)
    inv_m12: ArrayLike
    inv_m21: ArrayLike
    inv_m22: ArrayLike
    Z_uq: ArrayLike  # m + Z_q [kg]
    m_zG: ArrayLike  # m z_G [kg m]
    Z_w: ArrayLike  # [kg/m]
    M_uq: ArrayLike  # M_q - m x_G [kg m]
    M_w: ArrayLike  # [kg]
    Z_delta_s: ArrayLike  # [kg/m per rad]
    Z_delta_b: ArrayLike
    M_delta_s: ArrayLike  # [kg per rad]
    M_delta_b: ArrayLike
    W_minus_B: ArrayLike  # W - B [N]
    xGW_minus_xBB: ArrayLike  # x_G W - x_B B [N m]
    zGW_minus_zBB: ArrayLike  # z_G W - z_B B [N m]
    half_rho_CD: ArrayLike  # (rho/2) C_D [kg/m^3]
    rho_suction: ArrayLike  # rho times FreeSurface.suction_factor [kg/m^3]; 0: deep water
    suction_model: ArrayLike  # FreeSurface.suction_model: free_surface.SLENDER_BODY or SOURCES_ONLY
    hull: HullTable


PARAM_FIELDS = ModelParams._fields[:-1]
"""The numeric fields of :class:`ModelParams`, in the order of :func:`pack_params` (all but ``hull``)."""
_RHO_SUCTION = PARAM_FIELDS.index("rho_suction")
_SUCTION_MODEL = PARAM_FIELDS.index("suction_model")
_LOADING_FIELDS = (
    "x_G_m",
    "z_G_m",
    "buoyancy_N",
    "crossflow_drag",
)  # a loading's fields (Vehicle.loading_fields)


def model_params(
    vehicle: Vehicle,
    free_surface: FreeSurface = NO_FREE_SURFACE,
    loading: Mapping[str, ArrayLike] | None = None,
) -> ModelParams:
    """Reduce a :class:`~subenv.vehicles.Vehicle` to the parameters of :func:`derivatives`.

    ``free_surface`` adds the free surface's suction (:mod:`subenv.dynamics.free_surface`); the
    default is deep water, Riedel (1993)'s model. ``loading`` replaces the vehicle's loading with
    :meth:`Vehicle.loading_fields <subenv.vehicles.Vehicle.loading_fields>` (``z_G_m``, ``x_G_m``,
    ``buoyancy_N``, ``crossflow_drag``), floats or arrays of many loadings: the parameters of the
    variant with that loading, element for element (the fields that depend on it are then arrays).
    """
    changed = loading or {}
    unknown = set(changed) - set(_LOADING_FIELDS)
    if unknown:
        raise ValueError(f"loading has unknown fields {sorted(unknown)}: allowed are {list(_LOADING_FIELDS)}")
    x_G, z_G, B, C_D = (changed.get(name, getattr(vehicle, name)) for name in _LOADING_FIELDS)
    c = vehicle.coefficients
    m = vehicle.mass_kg
    # Added-mass matrix of eqs 2.38-2.39 (Riedel 1993), left-hand side for (wdot, qdot).
    m11 = m - c.Z_wdot
    m12 = -(c.Z_qdot + m * x_G)
    m21 = -(c.M_wdot + m * x_G)
    m22 = vehicle.inertia_y_kg_m2 - c.M_qdot
    det = m11 * m22 - m12 * m21
    W = vehicle.weight_N
    return ModelParams(
        inv_m11=m22 / det,
        inv_m12=-m12 / det,
        inv_m21=-m21 / det,
        inv_m22=m11 / det,
        Z_uq=m + c.Z_q,
        m_zG=m * z_G,
        Z_w=c.Z_w,
        M_uq=c.M_q - m * x_G,
        M_w=c.M_w,
        Z_delta_s=c.Z_delta_s,
        Z_delta_b=c.Z_delta_b,
        M_delta_s=c.M_delta_s,
        M_delta_b=c.M_delta_b,
        W_minus_B=W - B,
        xGW_minus_xBB=x_G * W - vehicle.x_B_m * B,
        zGW_minus_zBB=z_G * W - vehicle.z_B_m * B,
        half_rho_CD=0.5 * vehicle.water_density_kg_m3 * C_D,
        rho_suction=vehicle.water_density_kg_m3 * free_surface.suction_factor,
        suction_model=free_surface.suction_model,
        hull=_hull_table(vehicle),
    )


_HULL_TABLES: dict[tuple[tuple[float, ...], tuple[float, ...]], HullTable] = {}


def _hull_table(vehicle: Vehicle) -> HullTable:
    key = (vehicle.hull.x_m, vehicle.hull.breadth_m)
    table = _HULL_TABLES.get(key)
    if table is None:
        table = _HULL_TABLES[key] = HullTable.from_offsets(*key)
    return table


def stack_params(params: list[ModelParams]) -> ModelParams:
    """Stack per-environment parameters into one batch (all must share one hull)."""
    hulls = {id(p.hull) for p in params}
    if len(hulls) != 1:
        raise ValueError(f"stack_params: {len(hulls)} different hulls; a batch must share one hull")
    fields = {
        name: np.array([getattr(p, name) for p in params], dtype=float)
        for name in ModelParams._fields
        if name != "hull"
    }
    return ModelParams(**fields, hull=params[0].hull)


_SCALAR_TYPES: Final = frozenset({float, int, np.float64})


def _all_scalars(values: tuple[Any, ...]) -> bool:
    """Whether every one of ``values`` is a float, an int or a NumPy float64: a test of their types as a
    set, which the analysis's million calls a report can afford (``isinstance`` value by value cost
    microseconds)."""
    return set(map(type, values)) <= _SCALAR_TYPES


def pack_params(params: ModelParams) -> FloatArray:
    """The numeric fields of ``params`` as one array, shape ``(..., len(PARAM_FIELDS))``, for
    :func:`rhs_point`."""
    fields: tuple[Any, ...] = params[: len(PARAM_FIELDS)]  # (all but hull)
    if _all_scalars(fields) or not any(isinstance(f, np.ndarray) for f in fields):
        return np.array(fields, dtype=float)
    shape = np.broadcast_shapes(*(np.shape(f) for f in fields))
    # Each field copied into its column, broadcast by the assignment (a vector environment's resets
    # pack many loadings: one array op per field, where broadcast_arrays and stack took four).
    packed = np.empty((*shape, len(fields)))
    for k, field in enumerate(fields):
        packed[..., k] = field
    return packed


def dual_plane_angles(delta: ArrayLike, alpha: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Stern and bow plane angles for the dual-control command ``delta`` (Riedel 1993 eq. 2.58).

    One command drives both pairs with the bow planes slaved to the stern planes,
    ``delta_s = delta``, ``delta_b = alpha delta``, so that Z_delta = Z_ds + alpha Z_db and
    M_delta = M_ds + alpha M_db.
    """
    delta = np.asarray(delta, dtype=float)
    return delta, np.asarray(alpha, dtype=float) * delta


@inline_kernel
def rhs_point(
    theta: float,
    w: float,
    q: float,
    depth: float,
    u: float,
    stern: float,
    bow: float,
    force: float,
    moment: float,
    prm: FloatArray,
    hull: FloatArray,
) -> tuple[float, float, float, float]:
    """d/dt (theta, w, q, Z) for one state (Riedel 1993 eqs 2.38-2.43); see :func:`derivatives`.

    ``prm`` holds the fields of :class:`ModelParams` in :data:`PARAM_FIELDS` order
    (:func:`pack_params`), ``hull`` is :attr:`HullTable.packed`. Depth enters only through the free
    surface's suction (:func:`~subenv.dynamics.free_surface.suction_point`; none in deep water).
    """
    I0, I1 = crossflow_point(w, q, hull)
    Z_fs, M_fs = suction_point(
        theta, w, q, depth, u, prm[_RHO_SUCTION], prm[_SUCTION_MODEL], hull, SOURCE_ROW
    )
    return rhs_given_drag(theta, w, q, u, stern, bow, force, moment, I0, I1, Z_fs, M_fs, prm, 0, 1)


@inline_kernel
def rhs_given_drag(
    theta: float,
    w: float,
    q: float,
    u: float,
    stern: float,
    bow: float,
    force: float,
    moment: float,
    I0: float,
    I1: float,
    Z_fs: float,
    M_fs: float,
    prm: FloatArray,
    at: int,
    stride: int,
) -> tuple[float, float, float, float]:
    """:func:`rhs_point` given the hull's cross-flow integrals ``I0``, ``I1`` (:func:`crossflow_point`)
    and the free surface's suction ``Z_fs`` [N], ``M_fs`` [N m]
    (:func:`~subenv.dynamics.free_surface.suction_point`, exactly 0.0 in deep water).

    Field k of :data:`PARAM_FIELDS` is ``prm[at + k * stride]``: a packed parameter row has
    stride 1; the block integrator (:func:`subenv.dynamics.integrate.control_period_lanes`) keeps
    each field as a row of its block, one sub-environment per column.
    """
    (
        inv_m11,
        inv_m12,
        inv_m21,
        inv_m22,
        Z_uq,
        m_zG,
        Z_w,
        M_uq,
        M_w,
        Z_delta_s,
        Z_delta_b,
        M_delta_s,
        M_delta_b,
        W_minus_B,
        xGW_minus_xBB,
        zGW_minus_zBB,
        half_rho_CD,
    ) = (
        prm[at],
        prm[at + stride],
        prm[at + 2 * stride],
        prm[at + 3 * stride],
        prm[at + 4 * stride],
        prm[at + 5 * stride],
        prm[at + 6 * stride],
        prm[at + 7 * stride],
        prm[at + 8 * stride],
        prm[at + 9 * stride],
        prm[at + 10 * stride],
        prm[at + 11 * stride],
        prm[at + 12 * stride],
        prm[at + 13 * stride],
        prm[at + 14 * stride],
        prm[at + 15 * stride],
        prm[at + 16 * stride],
    )
    sin_t, cos_t = sincos_point(theta)
    uu = u * u
    # Riedel (1993) eqs 2.38 and 2.39, right-hand sides, with the forces of eqs 2.42 and 2.43.
    heave = (
        Z_uq * u * q
        + m_zG * q * q
        + Z_w * u * w
        + W_minus_B * cos_t
        + uu * (Z_delta_s * stern + Z_delta_b * bow)
        - half_rho_CD * I0
        + force
        + Z_fs  # free-surface suction (subenv.dynamics.free_surface)
    )
    pitch = (
        -m_zG * w * q
        + M_uq * u * q
        + M_w * u * w
        - xGW_minus_xBB * cos_t
        - zGW_minus_zBB * sin_t
        + uu * (M_delta_s * stern + M_delta_b * bow)
        + half_rho_CD * I1
        + moment
        + M_fs
    )
    return (
        q,  # Riedel (1993) eq. 2.40
        inv_m11 * heave + inv_m12 * pitch,
        inv_m21 * heave + inv_m22 * pitch,
        -u * sin_t + w * cos_t,  # Riedel (1993) eq. 2.41 (depth kinematics)
    )


def state_array(state: ArrayLike) -> FloatArray:
    """``state`` as a float array of states, shape (..., 4); ValueError naming its shape if it is not."""
    array = np.asarray(state, dtype=float)
    if array.shape[-1:] != (4,):
        raise ValueError(
            f"state has shape {array.shape}: must have shape (..., 4) (pitch, heave, pitch rate, depth)"
        )
    return array


def derivatives(
    state: FloatArray,
    speed: ArrayLike,
    stern: ArrayLike,
    bow: ArrayLike,
    params: ModelParams,
    force: ArrayLike = 0.0,
    moment: ArrayLike = 0.0,
) -> FloatArray:
    """Time derivative of the state, d/dt (theta, w, q, Z) (Riedel 1993 eqs 2.38-2.43).

    Parameters
    ----------
    state : ndarray, shape (..., 4)
        Pitch [rad], heave velocity [m/s], pitch rate [rad/s], depth [m].
    speed : array_like
        Forward speed u [m/s].
    stern, bow : array_like
        Applied stern and bow plane angles [rad], already within the plane limits: nothing here
        clips them (the environments do, in :func:`subenv.envs.transition.plane_angles`).
    params : ModelParams
        From :func:`model_params` (or :func:`stack_params` for a batch).
    force, moment : array_like, optional
        External heave force [N, down positive] and pitch moment [N m, nose-up positive], e.g. a
        disturbance.

    Returns
    -------
    ndarray, shape (..., 4)
        (theta_dot, w_dot, q_dot, Z_dot).

    Notes
    -----
    ::

        (m - Z_wdot) wdot - (Z_qdot + m x_G) qdot = (m + Z_q) u q + m z_G q^2 + Z_w u w
            + (W - B) cos(theta) + u^2 (Z_ds delta_s + Z_db delta_b) + Z_drag + force + Z_fs
        -(M_wdot + m x_G) wdot + (I_y - M_qdot) qdot = -m z_G w q + (M_q - m x_G) u q + M_w u w
            - (x_G W - x_B B) cos(theta) - (z_G W - z_B B) sin(theta)
            + u^2 (M_ds delta_s + M_db delta_b) + M_drag + moment + M_fs
        theta_dot = q
        Z_dot = -u sin(theta) + w cos(theta)

    with the hull cross-flow drag Z_drag = -(rho/2) C_D int b w_loc|w_loc| dx and
    M_drag = +(rho/2) C_D int x b w_loc|w_loc| dx, w_loc = w - x q (see
    :func:`subenv.dynamics.hull.crossflow_integrals` for the sign of the moment), and the free
    surface's suction Z_fs(Z, theta, w, q, u), M_fs(Z, theta, w, q, u)
    (:mod:`subenv.dynamics.free_surface`; zero in deep water, ``params.rho_suction`` 0), the one place
    where the depth Z enters.

    This is :func:`rhs_point` broadcast over the batch (a compiled loop over its rows); the environments
    call :func:`rhs_point` itself.
    """
    state = state_array(state)
    prm = pack_params(params)  # (..., P): one set for all, or one per row (stack_params)
    inputs = (speed, stern, bow, force, moment)
    if state.shape == (4,) and prm.ndim == 1 and _all_scalars(inputs):
        return _one_state(state, inputs, rows(prm, prm.shape), params.hull.packed)
    shape = np.broadcast_shapes(state.shape[:-1], prm.shape[:-1], *(np.shape(a) for a in inputs))
    u, delta_s, delta_b, Z_ext, M_ext = (rows(a, shape) for a in inputs)
    states = rows(state, (*shape, 4)).reshape(-1, 4)
    out = np.empty((states.shape[0], 4))
    _derivatives_rows(
        states,
        u,
        delta_s,
        delta_b,
        Z_ext,
        M_ext,
        rows(prm, (*shape, prm.shape[-1])).reshape(-1, prm.shape[-1]),
        params.hull.packed,
        out,
    )
    return out.reshape(*shape, 4)


def _one_state(
    state: FloatArray, inputs: tuple[ArrayLike, ...], prm: FloatArray, hull: FloatArray
) -> FloatArray:
    """:func:`derivatives` of one state (4 numbers) with the scalar ``inputs`` (speed, stern, bow, force,
    moment) and one packed parameter set ``prm`` (shape (P,), read-only): :func:`rhs_point` called on
    floats (its own compiled entry point, numba's for Python callers), without the arrays the batched path
    makes (the analysis's solvers call this a million times a report)."""
    pitch, heave, rate, depth = state
    speed, stern, bow, force, moment = inputs
    return np.array(
        rhs_point(
            float(pitch),
            float(heave),
            float(rate),
            float(depth),
            float(speed),
            float(stern),
            float(bow),
            float(force),
            float(moment),
            prm,
            hull,
        )
    )


def derivatives_with(params: ModelParams) -> Callable[..., FloatArray]:
    """:func:`derivatives` with ``params`` fixed: ``f(state, speed, stern, bow, force=0.0, moment=0.0)``,
    the same numbers, its parameters packed once (:func:`pack_params`) rather than on every call: for a
    solver that calls it for one state at a time (the analysis's periodic orbits and surface trims, a
    million calls a report)."""
    packed = pack_params(params)
    one_set = packed.ndim == 1  # (else a batch of parameter sets: derivatives' general path)
    prm, hull = rows(packed, packed.shape), params.hull.packed

    def rhs(
        state: FloatArray,
        speed: ArrayLike,
        stern: ArrayLike,
        bow: ArrayLike,
        force: ArrayLike = 0.0,
        moment: ArrayLike = 0.0,
    ) -> FloatArray:
        inputs = (speed, stern, bow, force, moment)
        if one_set and np.shape(state) == (4,) and _all_scalars(inputs):
            return _one_state(state, inputs, prm, hull)
        return derivatives(state, speed, stern, bow, params, force, moment)

    return rhs


@kernel
def _derivatives_rows(
    state: FloatArray,
    u: FloatArray,
    stern: FloatArray,
    bow: FloatArray,
    force: FloatArray,
    moment: FloatArray,
    prm: FloatArray,
    hull: FloatArray,
    out: FloatArray,
) -> None:
    # A loop over rows, not a generalized ufunc (see subenv.dynamics._jit).
    for i in range(state.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = rhs_point(
            state[i, 0],
            state[i, 1],
            state[i, 2],
            state[i, 3],
            u[i],
            stern[i],
            bow[i],
            force[i],
            moment[i],
            prm[i],
            hull,
        )
