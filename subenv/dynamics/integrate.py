"""Fixed-step fourth-order Runge-Kutta integration of the dynamics.

The environments hold the planes and the external force constant over a control step (zero-order
hold) and integrate that step with ``substeps`` classical RK4 steps. The step was chosen by the
accuracy tests in ``tests/dynamics/test_integrator.py``, which compare against
``scipy.integrate.solve_ivp`` at rtol 1e-10 over 600 s trajectories.

:func:`rk4` integrates any batched right-hand side ``f(t, x)``: with
:func:`subenv.dynamics.derivatives` it is the NumPy reference. :func:`control_period` runs the
environments' own integrator over any batch of states (compiled: :func:`control_period_rows`),
the twin of :func:`subenv.jax.control_period`. :func:`control_period_lanes` is the
same scheme, compiled, over one control period of :func:`subenv.dynamics.model.rhs_point` for a block of
up to :data:`LANES` states, one per column, so that the compiler turns each stage into SIMD code
over the block; the environments integrate every step with it, one sub-environment or many. It
performs the same floating-point operations in the same order as ``rk4`` over ``derivatives``, so
each state gets the same bits as the reference, whatever the block holds beside it
(``tests/dynamics/test_integrator.py``, ``tests/envs/test_env_api.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Final

import numpy as np

from subenv import _validation as check
from subenv._typing import ArrayLike, FloatArray
from subenv.dynamics._jit import inline_kernel, kernel, minimum, read_only, rows
from subenv.dynamics.free_surface import suction_point
from subenv.dynamics.hull import (
    SOURCE_ROW,
    crossflow_from_moments,
    crossflow_root,
    hull_segment,
    moments_on_segment,
)
from subenv.dynamics.model import PARAM_FIELDS, ModelParams, pack_params, rhs_given_drag, state_array
from subenv.dynamics.waves import MAX_WAVES, WAVE_FIELDS, wave_force_point

__all__ = [
    "CONTROL_PERIOD_S",
    "LANES",
    "LANE_ROWS",
    "NO_WAVES",
    "SUBSTEPS",
    "Loop",
    "control_period",
    "control_period_lanes",
    "control_period_rows",
    "distance_travelled",
    "rk4",
    "rk4_step",
    "set_lane",
]

CONTROL_PERIOD_S: Final = 0.5
"""Default control period of the environments [s]."""

SUBSTEPS: Final = 2
"""Default RK4 steps per control period (step 0.25 s): worst error over 600 s, 0.15-1.8 m/s, open
and closed loop, below 1 mm in depth and 1e-5 rad in pitch (``tests/dynamics/test_integrator.py``)."""

Rhs = Callable[[float, FloatArray], FloatArray]
"""Right-hand side f(t, x) -> dx/dt, batched over the leading axes of x."""


def rk4_step(f: Rhs, t: float, x: FloatArray, dt: float) -> FloatArray:
    """One classical RK4 step of size ``dt`` from (t, x)."""
    k1 = f(t, x)
    k2 = f(t + 0.5 * dt, x + (0.5 * dt) * k1)
    k3 = f(t + 0.5 * dt, x + (0.5 * dt) * k2)
    k4 = f(t + dt, x + dt * k3)
    return x + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)


Loop = Callable[[int, int, Callable[[int, FloatArray], FloatArray], FloatArray], FloatArray]
"""A loop with ``jax.lax.fori_loop``'s contract: ``loop(lower, upper, body, x)`` applies ``x = body(i, x)``
for i = lower .. upper - 1 and returns x (:func:`rk4`'s ``loop``)."""


def _python_loop(
    lower: int, upper: int, body: Callable[[int, FloatArray], FloatArray], x: FloatArray
) -> FloatArray:
    """:data:`Loop` in Python."""
    for i in range(lower, upper):
        x = body(i, x)
    return x


def rk4(f: Rhs, t: float, x: FloatArray, dt: float, substeps: int, loop: Loop = _python_loop) -> FloatArray:
    """Integrate from t to t + dt with ``substeps`` equal RK4 steps, looped by ``loop`` (JAX passes
    ``jax.lax.fori_loop``: its program holds one step, not ``substeps`` of them)."""
    h = dt / substeps
    return loop(0, substeps, lambda i, x: rk4_step(f, t + i * h, x, h), x)


LANES: Final = 64
"""Columns of a block of :func:`control_period_lanes` (its states are integrated together)."""
# Rows of a block, each LANES wide. The caller fills the inputs of columns 0 .. n-1:
LANE_PITCH, LANE_HEAVE, LANE_PITCH_RATE, LANE_DEPTH = 0, 1, 2, 3  # the state: in, and out after the period
LANE_T0, LANE_SPEED0, LANE_SPEED_SLOPE = 4, 5, 6  # the period starts at t0; u = speed0 + slope (t - t0)
LANE_STERN, LANE_BOW, LANE_FORCE = 7, 8, 9
LANE_DISTANCE, LANE_WAVES = 10, 11  # distance travelled at t0 [m]; the waves of the lane's sea (a count)
LANE_PARAMS: Final = 12  # the PARAM_FIELDS, one row each
# ... and the integrator's working rows:
_STAGE: Final = LANE_PARAMS + len(PARAM_FIELDS)  # (theta, w, q, Z) at which a stage evaluates
_SPEED: Final = _STAGE + 4
_TIME: Final = _SPEED + 1  # the stage's time, and the distance travelled then
_DISTANCE: Final = _TIME + 1
_FREE_SURFACE: Final = _DISTANCE + 1  # heave force and pitch moment of the free surface (suction and waves)
_ROOT: Final = _FREE_SURFACE + 2  # the root of w_loc, clipped to the hull
_SEGMENT: Final = _ROOT + 1  # its hull segment (a count, as a float)
_SEGMENT_COEFFICIENTS: Final = _SEGMENT + 1  # that segment's column of HullTable.packed, rows 1-6
_SLOPE_OUT: Final = _SEGMENT_COEFFICIENTS + 6  # the right-hand side's result, 4 rows
_SLOPES: Final = _SLOPE_OUT + 4  # k1 .. k4, 4 rows each
LANE_ROWS: Final = _SLOPES + 16
"""Rows of a block: a block is a float64 array of ``LANE_ROWS * LANES`` (row r, column j at
``r * LANES + j``)."""

NO_WAVES: Final = np.zeros((1, WAVE_FIELDS, MAX_WAVES))
"""The ``waves`` of :func:`control_period_lanes` for blocks whose lanes have no sea (every
``LANE_WAVES`` 0)."""
read_only(NO_WAVES)
_RHO_SUCTION: Final = PARAM_FIELDS.index("rho_suction")
_SUCTION_MODEL: Final = PARAM_FIELDS.index("suction_model")


@inline_kernel
def set_lane(
    block: FloatArray,
    j: int,
    theta: float,
    w: float,
    q: float,
    depth: float,
    t0: float,
    speed0: float,
    speed_slope: float,
    stern: float,
    bow: float,
    force: float,
    prm: FloatArray,
    distance: float = 0.0,
    n_waves: int = 0,
) -> None:
    """Put one state's inputs of :func:`control_period_lanes` into column ``j`` of a block: the state
    (theta, w, q, depth), the period's start ``t0`` [s] and speed ``speed0 + speed_slope (t - t0)``
    [m/s], the planes and heave ``force`` held over the period, the packed model parameters
    ``prm`` (:func:`subenv.dynamics.model.pack_params`), and for a lane in a sea the distance travelled at
    ``t0`` [m] and the number of its waves (in row ``j`` of :func:`control_period_lanes`'s ``waves``)."""
    L = LANES
    block[LANE_PITCH * L + j] = theta
    block[LANE_HEAVE * L + j] = w
    block[LANE_PITCH_RATE * L + j] = q
    block[LANE_DEPTH * L + j] = depth
    block[LANE_T0 * L + j] = t0
    block[LANE_SPEED0 * L + j] = speed0
    block[LANE_SPEED_SLOPE * L + j] = speed_slope
    block[LANE_STERN * L + j] = stern
    block[LANE_BOW * L + j] = bow
    block[LANE_FORCE * L + j] = force
    block[LANE_DISTANCE * L + j] = distance
    block[LANE_WAVES * L + j] = n_waves
    for r in range(len(PARAM_FIELDS)):
        block[(LANE_PARAMS + r) * L + j] = prm[r]


@inline_kernel
def distance_travelled(distance0: float, elapsed: float, speed0: float, speed_slope: float) -> float:
    """Distance travelled [m] ``elapsed`` seconds into a period that starts at ``distance0`` [m] with the
    speed ``speed0 + speed_slope * elapsed`` [m/s] (a sea's phase:
    :func:`~subenv.dynamics.waves.wave_force_point`)."""
    return distance0 + elapsed * (speed0 + 0.5 * speed_slope * elapsed)


@kernel
def _free_surface_lanes(block: FloatArray, n: int, hull: FloatArray, waves: FloatArray) -> None:
    """The free surface's heave force and pitch moment (suction and waves) on columns 0 .. n-1 at the stage
    in rows _STAGE .. _STAGE + 3, into rows _FREE_SURFACE .. _FREE_SURFACE + 1.

    A function of its own, called, not inlined: inlined into the block integrator, its loops doubled
    the machine code of a step, and every step in deep water, which never runs them, was about a fifth
    slower for it."""
    L = LANES
    theta, w, q, depth = _STAGE * L, (_STAGE + 1) * L, (_STAGE + 2) * L, (_STAGE + 3) * L
    rho_suction = (LANE_PARAMS + _RHO_SUCTION) * L
    suction_model = (LANE_PARAMS + _SUCTION_MODEL) * L
    for j in range(n):  # exactly 0.0 for a lane in deep water without a sea
        Z_fs, M_fs = suction_point(
            block[theta + j],
            block[w + j],
            block[q + j],
            block[depth + j],
            block[_SPEED * L + j],
            block[rho_suction + j],
            block[suction_model + j],
            hull,
            SOURCE_ROW,
        )
        Z_w, M_w = wave_force_point(
            block[_TIME * L + j],
            block[_DISTANCE * L + j],
            block[depth + j],
            block[_SPEED * L + j],
            waves[minimum(j, waves.shape[0] - 1)],
            int(block[LANE_WAVES * L + j]),
        )
        block[_FREE_SURFACE * L + j] = Z_fs + Z_w
        block[(_FREE_SURFACE + 1) * L + j] = M_fs + M_w


@inline_kernel
def _rhs_lanes(block: FloatArray, n: int, hull: FloatArray, waves: FloatArray, free_surface: bool) -> None:
    """rhs_point of columns 0 .. n-1, at the (theta, w, q, Z) in rows _STAGE .. _STAGE + 3 with the speed
    in row _SPEED, into rows _SLOPE_OUT .. _SLOPE_OUT + 3. Without ``free_surface`` (no column has a
    suction or a sea) the rows _FREE_SURFACE .. _FREE_SURFACE + 1 hold 0.0 and are not computed again.

    Each step is a loop over the columns with the same operations in every column, and every
    access is block[row * LANES + column] with a constant row: the compiler can tell the rows
    apart and vectorize. The root's hull segment is :func:`~subenv.dynamics.hull.hull_segment`'s,
    column by column (most roots lie off the hull, where it answers without a search), and the
    segment's coefficients are gathered from the hull table.
    """
    L = LANES
    theta, w, q = _STAGE * L, (_STAGE + 1) * L, (_STAGE + 2) * L
    if free_surface:
        _free_surface_lanes(block, n, hull, waves)
    for j in range(n):
        root = crossflow_root(block[w + j], block[q + j], hull)
        block[_ROOT * L + j] = root
        block[_SEGMENT * L + j] = hull_segment(root, hull)
    for j in range(n):
        i = int(block[_SEGMENT * L + j])
        for r in range(6):
            block[(_SEGMENT_COEFFICIENTS + r) * L + j] = hull[1 + r, i]
    c = _SEGMENT_COEFFICIENTS * L
    for j in range(n):
        w_j, q_j = block[w + j], block[q + j]
        C0, C1, C2, C3 = moments_on_segment(
            block[_ROOT * L + j],
            block[c + j],
            block[c + L + j],
            block[c + 2 * L + j],
            block[c + 3 * L + j],
            block[c + 4 * L + j],
            block[c + 5 * L + j],
        )
        I0, I1 = crossflow_from_moments(w_j, q_j, C0, C1, C2, C3, hull)
        d0, d1, d2, d3 = rhs_given_drag(
            block[theta + j],
            w_j,
            q_j,
            block[_SPEED * L + j],
            block[LANE_STERN * L + j],
            block[LANE_BOW * L + j],
            block[LANE_FORCE * L + j],
            0.0,
            I0,
            I1,
            block[_FREE_SURFACE * L + j],
            block[(_FREE_SURFACE + 1) * L + j],
            block,
            LANE_PARAMS * L + j,
            L,
        )
        block[_SLOPE_OUT * L + j] = d0
        block[(_SLOPE_OUT + 1) * L + j] = d1
        block[(_SLOPE_OUT + 2) * L + j] = d2
        block[(_SLOPE_OUT + 3) * L + j] = d3


@inline_kernel
def control_period_lanes(
    block: FloatArray, n: int, dt: float, substeps: int, hull: FloatArray, waves: FloatArray
) -> None:
    """:func:`rk4` of :func:`~subenv.dynamics.model.rhs_point` over one control period ``dt`` with
    ``substeps`` steps, for columns 0 .. n-1 (n <= :data:`LANES`) of ``block``, in place.

    ``block`` holds the inputs of each column in the ``LANE_*`` rows (:func:`set_lane`); the planes
    and the heave force are held, the speed follows each column's ramp; ``waves`` (shape (LANES,
    WAVE_FIELDS, MAX_WAVES), row j column j's sea: :meth:`subenv.dynamics.waves.SeaState.components`;
    one row such as :data:`NO_WAVES` where no lane has a sea) adds a sea's force at every stage.
    Afterwards rows ``LANE_PITCH`` .. ``LANE_DEPTH`` hold the states at the end of the period: for
    each column the bits of ``rk4`` over :func:`~subenv.dynamics.derivatives`.
    """
    L = LANES
    h = dt / substeps
    half = 0.5 * h
    sixth = h / 6.0
    # Whether any column feels the free surface. In deep water (every scenario but the periscope-depth
    # ones) its force is exactly 0.0: written once here, not computed at every stage.
    free_surface = False
    for j in range(n):
        suction, waves_j = block[(LANE_PARAMS + _RHO_SUCTION) * L + j], block[LANE_WAVES * L + j]
        free_surface = free_surface or suction != 0.0 or waves_j > 0.0
    for j in range(n):
        block[_FREE_SURFACE * L + j] = 0.0
        block[(_FREE_SURFACE + 1) * L + j] = 0.0
    for i in range(substeps):
        # rk4_step, term by term: k1..k4 at (t, x), (t + h/2, x + h/2 k1), (t + h/2, x + h/2 k2),
        # (t + h, x + h k3). (One stage loop, so that the right-hand side is compiled once.)
        for stage in range(4):
            step = 0.0 if stage == 0 else (half if stage < 3 else h)  # the stage's state is x + step k
            offset = 0.0 if stage == 0 else (0.5 * h if stage < 3 else h)  # and its time t + offset
            previous = _SLOPES + 4 * (stage - 1) if stage > 0 else _SLOPES
            for j in range(n):
                t0 = block[LANE_T0 * L + j]
                t = t0 + i * h
                elapsed = t - t0 if stage == 0 else t + offset - t0
                speed0, slope = block[LANE_SPEED0 * L + j], block[LANE_SPEED_SLOPE * L + j]
                block[_SPEED * L + j] = speed0 + slope * elapsed
                if free_surface:  # (the time and distance of the stage: a sea's phase)
                    block[_TIME * L + j] = t0 + elapsed
                    block[_DISTANCE * L + j] = distance_travelled(
                        block[LANE_DISTANCE * L + j], elapsed, speed0, slope
                    )
            for r in range(4):
                for j in range(n):
                    x = block[(LANE_PITCH + r) * L + j]
                    block[(_STAGE + r) * L + j] = (
                        x if stage == 0 else x + step * block[(previous + r) * L + j]
                    )
            _rhs_lanes(block, n, hull, waves, free_surface)
            # Into k_stage here, not in _rhs_lanes: rows that depend on the stage would hide from the
            # compiler that they differ from the rows it reads, and it would not vectorize.
            for r in range(4):
                for j in range(n):
                    block[(_SLOPES + 4 * stage + r) * L + j] = block[(_SLOPE_OUT + r) * L + j]
        k1, k2, k3, k4 = _SLOPES, _SLOPES + 4, _SLOPES + 8, _SLOPES + 12
        for r in range(4):
            for j in range(n):
                x = (LANE_PITCH + r) * L + j
                block[x] = block[x] + sixth * (
                    block[(k1 + r) * L + j]
                    + 2.0 * (block[(k2 + r) * L + j] + block[(k3 + r) * L + j])
                    + block[(k4 + r) * L + j]
                )


@kernel
def control_period_rows(
    x: FloatArray,
    t0: FloatArray,
    dt: float,
    speed0: FloatArray,
    speed_slope: FloatArray,
    stern: FloatArray,
    bow: FloatArray,
    force: FloatArray,
    prm: FloatArray,
    hull: FloatArray,
    substeps: int,
    distance0: FloatArray,
    waves: FloatArray,
    out: FloatArray,
) -> None:
    """:func:`control_period_lanes` over the rows of ``x`` (shape (N, 4)), :data:`LANES` rows at a time,
    into ``out`` (N, 4), each row with its own inputs (1-D arrays of N; ``prm`` (N, P)); ``waves`` (N,
    WAVE_FIELDS, W) is each row's sea and every column of it is summed, or (1, WAVE_FIELDS, W) with W
    0 for none. The columns of a block that no row fills hold NaN: they never reach a row's result."""
    lanes = LANES
    block = np.full(LANE_ROWS * lanes, np.nan)
    n_waves = waves.shape[2]
    seas = np.empty((min(lanes, waves.shape[0]), waves.shape[1], n_waves))  # (row j: lane j's sea)
    seas[0] = waves[0]  # (one sea for all: its only row)
    for b in range(0, x.shape[0], lanes):
        m = min(lanes, x.shape[0] - b)
        for j in range(m):
            i = b + j
            set_lane(
                block,
                j,
                x[i, 0],
                x[i, 1],
                x[i, 2],
                x[i, 3],
                t0[i],
                speed0[i],
                speed_slope[i],
                stern[i],
                bow[i],
                force[i],
                prm[i],
                distance0[i],
                n_waves,
            )
            if waves.shape[0] > 1:
                seas[j] = waves[i]
        control_period_lanes(block, m, dt, substeps, hull, seas)
        for j in range(m):
            for r in range(4):
                out[b + j, r] = block[(LANE_PITCH + r) * lanes + j]


def control_period(
    state: ArrayLike,
    t0: ArrayLike,
    dt: float,
    speed0: ArrayLike,
    speed_slope: ArrayLike,
    stern: ArrayLike,
    bow: ArrayLike,
    params: ModelParams,
    force: ArrayLike = 0.0,
    substeps: int = SUBSTEPS,
    waves: ArrayLike | None = None,
    distance0: ArrayLike = 0.0,
) -> FloatArray:
    """The states after one control period ``dt`` [s] from time ``t0`` [s], integrated as the
    environments integrate them: ``substeps`` RK4 steps of :func:`~subenv.dynamics.model.rhs_point`,
    compiled. In calm water each state gets the bits of :func:`rk4` over
    :func:`~subenv.dynamics.derivatives`; in a sea, within 1e-12 of it with the sea's force passed to it
    (the suction and the sea's force are added before they enter the right-hand side).

    The twin of :func:`subenv.jax.control_period`, for a batch of states on the CPU: a rollout of the
    model as the environments step it, e.g. a controller's prediction.

    Parameters
    ----------
    state : array_like, shape (..., 4)
        Pitch [rad], heave velocity [m/s], pitch rate [rad/s], depth [m].
    t0 : array_like
        The period's start [s] (a sea's phase depends on it).
    dt : float
        The period [s] (the environments': :data:`CONTROL_PERIOD_S`).
    speed0, speed_slope : array_like
        The forward speed ``speed0 + speed_slope (t - t0)`` [m/s] over the period.
    stern, bow : array_like
        Plane angles [rad], held over the period (within the plane limits: nothing here clips them).
    params : ModelParams
        From :func:`~subenv.dynamics.model_params` (or :func:`~subenv.dynamics.stack_params` for a batch of
        loadings).
    force : array_like, optional
        External heave force [N, down positive], held over the period.
    substeps : int, optional
        RK4 steps per period (the environments': :data:`SUBSTEPS`).
    waves : array_like, shape (..., WAVE_FIELDS, W), optional
        Each state's sea (:meth:`subenv.dynamics.waves.SeaState.components`, every one of its W columns
        summed; zeros for a calm one), or one sea for all; its force acts at every stage, at the stage's
        time, depth and distance travelled (:func:`distance_travelled` from ``distance0`` [m] at
        ``t0``). None: calm.
    distance0 : array_like, optional
        Distance travelled at ``t0`` [m] (a sea's phase).

    Returns
    -------
    ndarray, shape (..., 4)
        The states at ``t0 + dt``; the batch shape is that of all the arguments broadcast together.
    """
    check.require("substeps", substeps, check.is_integer(substeps) and substeps >= 1, "an integer >= 1")
    check.require("dt", dt, check.is_finite(dt) and dt > 0, "a finite number of seconds > 0")
    x = state_array(state)
    prm = pack_params(params)
    sea = np.zeros((1, WAVE_FIELDS, 0)) if waves is None else np.asarray(waves, dtype=float)
    if sea.ndim < 2 or sea.shape[-2] != WAVE_FIELDS or sea.shape[-1] > MAX_WAVES:
        raise ValueError(
            f"waves has shape {sea.shape}: must have shape (..., {WAVE_FIELDS}, W) with W <= {MAX_WAVES} "
            "(subenv.dynamics.waves.SeaState.components)"
        )
    inputs = (t0, speed0, speed_slope, stern, bow, force, distance0)
    shape = np.broadcast_shapes(x.shape[:-1], prm.shape[:-1], sea.shape[:-2], *(np.shape(a) for a in inputs))
    n = int(np.prod(shape))
    if n == 0:  # (no state: the kernel's blocks assume one)
        return np.empty((*shape, 4))
    start, u0, slope, delta_s, delta_b, Z_ext, distance = (rows(a, shape) for a in inputs)
    fields = sea.shape[-2:]
    one_sea = sea.ndim == 2  # (for every state)
    seas = rows(sea, fields if one_sea else (*shape, *fields)).reshape(1 if one_sea else n, *fields)
    out = np.empty((n, 4))
    control_period_rows(
        rows(x, (*shape, 4)).reshape(n, 4),
        start,
        float(dt),
        u0,
        slope,
        delta_s,
        delta_b,
        Z_ext,
        rows(prm, (*shape, prm.shape[-1])).reshape(n, prm.shape[-1]),
        params.hull.packed,
        int(substeps),
        distance,
        seas,
        out,
    )
    return out.reshape(*shape, 4)
