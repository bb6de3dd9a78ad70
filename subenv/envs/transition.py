"""The dive-plane environment's transition, compiled, over named records of state.

Both :class:`~subenv.envs.DivePlaneEnv` and :class:`~subenv.envs.DivePlaneVectorEnv` step through
:func:`step` (Gymnasium's functional-env split, as in ``gymnasium/experimental/functional.py``: a
transition over arrays, thin ``Env`` classes around it; the single env is a batch of one).

What a sub-environment is made of, each a NumPy structured dtype whose fields numba reads by name:

- :data:`STATE_DTYPE`, what a step changes: the vehicle's state, the applied planes, the time, the
  disturbance, the speed;
- :data:`EPISODE_DTYPE`, what a reset draws and a step only reads: the model parameters of the
  episode's loading, the speed profile, the ordered depth, noise, duration, critical speed, the
  number of its sea's waves;
- the seas, a float64 array of shape (n, :data:`~subenv.dynamics.waves.WAVE_FIELDS`,
  :data:`~subenv.dynamics.waves.MAX_WAVES`): row i the sea of sub-environment i
  (:meth:`subenv.dynamics.waves.SeaState.components`), read only where ``episode[i].n_waves`` > 0.
  (Not a field of the episode's record: 1.7 kB in every record made every step of every
  sub-environment, calm or not, a third slower at N = 4096.)
- :data:`CONFIG_DTYPE`, one record the environment's configuration fixes
  (:meth:`subenv.envs.config.DivePlaneConfig.constants`);
- the step's report, one row per :data:`REPORT_KEYS` and one column per sub-environment: the
  ``info`` values, the reward and the episode's end, computed here and only here
  (:mod:`subenv.envs.info` hands them out).

The physics is pure functions of scalars that return values: the planes (:func:`plane_angles`),
the speed profile (:func:`speed_at`), a control period's start (:func:`period_start`: planes, effort,
speed) and end (:func:`episode_end`, :func:`period_end`, :func:`episode_outcome`: the new state and
the episode's end), the reward (:func:`reward_terms`), the observation (:func:`noise_values`,
:func:`observation_values`) and the ``info`` (:func:`report_values`), around one control period of
the shared right-hand side, integrated by :func:`subenv.dynamics.integrate.control_period_lanes` for
a block of up to :data:`~subenv.dynamics.integrate.LANES` sub-environments (one SIMD-compiled path
for any number of them). :func:`step` only reads the records, calls them and writes the results.
The functions are branch-free (selects, fixed loops, branches on the static configuration only), so
that :mod:`subenv.jax` traces these same functions into its functional environment
(:func:`subenv.jax.make`), the randomness given as standard normal numbers; the contract they keep
for it is :mod:`subenv.jax._trace`'s (``tests/jax/test_contract.py`` checks it).

Random numbers come from each sub-environment's own ``numpy.random.Generator`` (numba runs NumPy's
algorithms over the generator's own bit generator), in one order per step: the disturbance's
normal draw, then the eight observation-noise draws. So a sub-environment's numbers depend only on
its own seed, never on the number of sub-environments, the blocks or the threads.
"""

from __future__ import annotations

import math
from typing import Any, Final, Protocol, TypeAlias

import numba
import numpy as np

from subenv._typing import FloatArray
from subenv.dynamics._jit import KERNEL_SOURCES as DYNAMICS_KERNEL_SOURCES
from subenv.dynamics._jit import (
    Static,
    clip,
    declare_kernel_sources,
    inline_kernel,
    kernel,
    minimum,
    parallel_kernel,
    select,
    threading_layer_available,
)
from subenv.dynamics.integrate import (
    LANE_PITCH,
    LANE_ROWS,
    LANE_SPEED0,
    LANES,
    control_period_lanes,
    set_lane,
)
from subenv.dynamics.model import PARAM_FIELDS
from subenv.dynamics.waves import MAX_WAVES, WAVE_FIELDS

__all__ = [
    "BLOCKS_PER_RUN",
    "CONFIG_DTYPE",
    "EPISODE_DTYPE",
    "MAX_KNOTS",
    "N_OBS",
    "REASONS",
    "REPORT_KEYS",
    "STATE_DTYPE",
    "ConfigRecord",
    "EpisodeRecord",
    "Record",
    "StateRecord",
    "draw_initial_disturbances",
    "draw_reset_numbers",
    "episode_end",
    "episode_outcome",
    "noise_values",
    "observation",
    "observation_values",
    "observe",
    "period_end",
    "period_start",
    "plane_angles",
    "report_values",
    "reward_terms",
    "sensor_noise",
    "speed_at",
    "step",
    "step_blocks",
    "step_parallel",
    "threading_layer_available",
]

KERNEL_SOURCES: Final = declare_kernel_sources(
    __file__, ("transition.py",), inlines=(DYNAMICS_KERNEL_SOURCES,)
)
"""The environments' kernel sources (:func:`subenv.dynamics._jit.declare_kernel_sources`): this file, whose
kernels inline the dynamics'."""

MAX_KNOTS: Final = 4
"""Knots of an episode's speed profile, at most (a constant speed is one, a ramp three)."""
N_OBS: Final = 8
"""Observation components (:data:`subenv.envs.config.OBSERVATION_NAMES`)."""

STATE_DTYPE: Final = np.dtype(
    [
        ("pitch_rad", np.float64),  # theta, nose-up positive
        ("heave_mps", np.float64),  # w, body axes, down positive
        ("pitch_rate_radps", np.float64),  # q
        ("depth_m", np.float64),  # Z, of midship, down positive
        ("stern_plane_rad", np.float64),  # applied (after saturation and rate limit)
        ("bow_plane_rad", np.float64),
        ("time_s", np.float64),  # since the reset
        ("steps", np.int64),  # since the reset
        ("disturbance_N", np.float64),  # heave force, held over a control period
        ("speed_mps", np.float64),  # of the profile at time_s
        ("distance_m", np.float64),  # travelled since the reset (the phase of a sea's waves)
    ]
)
"""What a step changes, per sub-environment."""

EPISODE_DTYPE: Final = np.dtype(
    [
        ("params", np.float64, (len(PARAM_FIELDS),)),  # ModelParams of the loading, PARAM_FIELDS order
        ("n_knots", np.int64),
        ("knot_time_s", np.float64, (MAX_KNOTS,)),  # speed profile: piecewise linear through the
        ("knot_speed_mps", np.float64, (MAX_KNOTS,)),  # knots, held after the last
        ("depth_command_m", np.float64),
        ("disturbance_std_N", np.float64),  # 0: no disturbance
        ("sensor_noise", np.bool_),
        ("duration_s", np.float64),
        ("critical_speed_mps", np.float64),  # nan: none (z_GB <= 0)
        ("froude_scale_mps", np.float64),  # sqrt(g z_GB), nan for z_GB <= 0
        ("n_waves", np.int64),  # 0: no sea; else the sea is the row of the seas
    ]
)
"""What a reset draws, per sub-environment (read-only during the episode)."""

CONFIG_DTYPE: Final = np.dtype(
    [
        ("dt_s", np.float64),
        ("substeps", np.int64),
        ("dual", np.bool_),  # one command, bow planes slaved (eq. 2.58)
        ("alpha", np.float64),
        ("plane_limit_rad", np.float64),
        ("rate_limited", np.bool_),
        ("max_move_rad", np.float64),  # per control period, with rate_limited
        ("max_pitch_rad", np.float64),
        ("max_depth_error_m", np.float64),
        ("broach_depth_m", np.float64),
        ("depth_scale_m", np.float64),
        ("pitch_weight", np.float64),
        ("effort_weight", np.float64),
        ("termination_penalty", np.float64),
        ("disturbance_decay", np.float64),  # Gauss-Markov: d' = decay d + gain N(0, std)
        ("disturbance_gain", np.float64),
        ("max_steps", np.float64),  # a TimeLimit (inf: none)
        ("max_heave_mps", np.float64),  # beyond these the state has diverged
        ("max_pitch_rate_radps", np.float64),
        ("obs_low", np.float64, (N_OBS,)),
        ("obs_high", np.float64, (N_OBS,)),
        ("noise_std", np.float64, (N_OBS,)),
    ]
)
"""The environment's constants (one record)."""


class Record(Protocol):
    """One record of a structured dtype (an ``np.void``; in :mod:`subenv.jax`, a dataclass of arrays),
    whose fields the kernels read and write by name. The dtype is the one list of its fields: this type
    lets any name through, and the contract test of the traced kernels (``tests/jax/test_contract.py``)
    checks each name a kernel reads against the dtype of its parameter's alias below."""

    def __getattr__(self, name: str) -> Any: ...
    def __setattr__(self, name: str, value: Any) -> None: ...


StateRecord: TypeAlias = Record
"""A record of :data:`STATE_DTYPE`."""
EpisodeRecord: TypeAlias = Record
"""A record of :data:`EPISODE_DTYPE`."""
ConfigRecord: TypeAlias = Static[Record]
"""The record of :data:`CONFIG_DTYPE`: static (:data:`~subenv.dynamics._jit.Static`), the kernels
branch on it (``if cfg.dual:``); :mod:`subenv.jax` passes its values as Python's."""


REASONS: Final = ("", "diverged", "pitch_limit", "broached", "left_depth_band")
"""``info["termination_reason"]`` for each reason code of the report."""
_DIVERGED, _PITCH_LIMIT, _BROACHED, _LEFT_DEPTH_BAND = 1, 2, 3, 4

REPORT_KEYS: Final = (
    "time_s",
    "depth_m",
    "depth_command_m",
    "depth_error_m",
    "pitch_rad",
    "heave_mps",
    "pitch_rate_radps",
    "stern_plane_rad",
    "bow_plane_rad",
    "speed_mps",
    "froude_number",
    "critical_speed_mps",
    "critical_froude",
    "disturbance_N",
    "reward_depth",
    "reward_pitch",
    "reward_effort",
    "reward_termination",
    "reason",
    "reward",
    "terminated",
    "truncated",
)
"""The rows of a step's report: the ``info`` keys (``reason`` is ``termination_reason``'s code),
then the step's reward and end."""
(
    _TIME,
    _DEPTH,
    _COMMAND,
    _DEPTH_ERROR,
    _PITCH,
    _HEAVE,
    _PITCH_RATE,
    _STERN,
    _BOW,
    _SPEED,
    _FROUDE,
    _CRITICAL_SPEED,
    _CRITICAL_FROUDE,
    _DISTURBANCE,
    _REWARD_DEPTH,
    _REWARD_PITCH,
    _REWARD_EFFORT,
    _REWARD_TERMINATION,
    _REASON,
    _REWARD,
    _TERMINATED,
    _TRUNCATED,
) = range(len(REPORT_KEYS))
_N_REPORT: Final = len(REPORT_KEYS)


# --- the physics of a step, pure functions of scalars --------------------------------------------
@inline_kernel
def speed_at(t: float, n_knots: int, knot_time_s: FloatArray, knot_speed_mps: FloatArray) -> float:
    """Speed [m/s] of a profile at time ``t`` [s]: ``numpy.interp`` over its first ``n_knots`` knots (in
    order of time)."""
    xs, ys = knot_time_s, knot_speed_mps
    last = n_knots - 1
    # numpy.interp (numpy/_core/src/multiarray/compiled_base.c, arr_interp), operation for operation,
    # with its branches as selects (each value computed, one taken) so that JAX traces this code too.
    # Its search for the interval of t, as a count: the knots are in order.
    j = 0
    for k in range(1, MAX_KNOTS):
        j = j + select((k <= last) & (t >= xs[k]), 1, 0)
    after = minimum(j + 1, last)
    x0, x1, y0, y1 = xs[j], xs[after], ys[j], ys[after]
    slope = (y1 - y0) / select(x1 != x0, x1 - x0, 1.0)  # (x1 == x0 only where the slope is not used)
    u = slope * (t - x0) + y0
    u = select(math.isnan(u), slope * (t - x1) + y1, u)
    u = select(math.isnan(u) & (y0 == y1), y0, u)
    u = select((j == last) | (xs[j] == t), ys[j], u)
    u = select(t > xs[last], ys[last], u)
    u = select(t < xs[0], ys[0], u)
    u = select(math.isnan(t), t, u)
    return select(n_knots == 1, ys[0], u)


@inline_kernel
def plane_angles(
    stern_rad: float, bow_rad: float, action0: float, action1: float, cfg: ConfigRecord
) -> tuple[float, float, float]:
    """The applied (stern, bow) angles [rad] after an action (finite; clipped to [-1, 1]; ``action1``
    only with independent control) from the angles before, and the effort term's mean squared command."""
    limit = cfg.plane_limit_rad
    a0 = clip(action0, -1.0, 1.0)
    stern = a0 * limit
    if cfg.dual:
        effort = a0 * a0
        bow = cfg.alpha * stern  # Riedel (1993) eq. 2.58
    else:
        a1 = clip(action1, -1.0, 1.0)
        effort = (a0 * a0 + a1 * a1) / 2.0
        bow = a1 * limit
    if cfg.rate_limited:
        move = cfg.max_move_rad
        stern = stern_rad + clip(stern - stern_rad, -move, move)
        bow = bow_rad + clip(bow - bow_rad, -move, move)
    return clip(stern, -limit, limit), clip(bow, -limit, limit), effort


@inline_kernel
def episode_end(x0: float, x1: float, x2: float, x3: float, depth_command_m: float, cfg: ConfigRecord) -> int:
    """The reason code (:data:`REASONS`) of the state (theta, w, q, Z) at the end of a step: 0 while
    the episode goes on (the first reason that holds, in the order of :data:`REASONS`)."""
    bounded = (
        math.isfinite(x0)
        & math.isfinite(x1)
        & math.isfinite(x2)
        & math.isfinite(x3)
        & (math.fabs(x1) <= cfg.max_heave_mps)
        & (math.fabs(x2) <= cfg.max_pitch_rate_radps)
    )
    reason = select(math.fabs(x3 - depth_command_m) > cfg.max_depth_error_m, _LEFT_DEPTH_BAND, 0)
    reason = select(x3 < cfg.broach_depth_m, _BROACHED, reason)
    reason = select(math.fabs(x0) > cfg.max_pitch_rad, _PITCH_LIMIT, reason)
    return select(bounded, reason, _DIVERGED)


@inline_kernel
def reward_terms(
    pitch_rad: float, depth_error_m: float, effort: float, terminated: bool, cfg: ConfigRecord
) -> tuple[float, float, float, float]:
    """(depth, pitch, effort, termination) terms of the reward (``DivePlaneEnv``'s Rewards section)."""
    ratio = pitch_rad / cfg.max_pitch_rad
    # 1 - tanh(x) as 2 / (1 + e^(2x)), the same number: libm's exp costs a third of its tanh, and the
    # small rewards far off depth keep their relative precision.
    r_depth = 2.0 / (1.0 + math.exp(2.0 * math.fabs(depth_error_m) / cfg.depth_scale_m))
    r_pitch = -cfg.pitch_weight * (ratio * ratio)
    r_effort = -cfg.effort_weight * effort
    r_termination = select(terminated, -cfg.termination_penalty, 0.0)
    return r_depth, r_pitch, r_effort, r_termination


@inline_kernel
def period_start(
    s: StateRecord, e: EpisodeRecord, action0: float, action1: float, cfg: ConfigRecord
) -> tuple[float, float, float, float, float, float]:
    """What a control period of state ``s`` in episode ``e`` holds, after the action (``action1``
    read only with independent control): the applied planes (stern, bow) [rad], the effort term's
    mean squared command, and the speed [m/s] at its start and end and its slope [m/s^2] (the
    period's speed is linear in time)."""
    stern, bow, effort = plane_angles(s.stern_plane_rad, s.bow_plane_rad, action0, action1, cfg)
    t0 = s.time_s
    u0 = speed_at(t0, e.n_knots, e.knot_time_s, e.knot_speed_mps)
    u1 = speed_at(t0 + cfg.dt_s, e.n_knots, e.knot_time_s, e.knot_speed_mps)
    return stern, bow, effort, u0, u1, (u1 - u0) / cfg.dt_s


@inline_kernel
def period_end(
    s: StateRecord,
    e: EpisodeRecord,
    x0: float,
    x1: float,
    x2: float,
    x3: float,
    u0: float,
    u1: float,
    reason: int,
    disturbance_draw: float,
    cfg: ConfigRecord,
) -> tuple[Any, ...]:
    """The state's fields after a control period from ``s`` that integrated to (theta, w, q, Z) =
    (``x0``, ``x1``, ``x2``, ``x3``) with the speed going from ``u0`` to ``u1``, and ended for
    ``reason`` (:func:`episode_end`); ``disturbance_draw`` is the heave force's new random term
    (normal, of the episode's standard deviation; read only where it is > 0).

    Returns (pitch, heave, pitch rate, depth, time, steps, distance, speed, disturbance, terminated,
    truncated): a diverged state keeps the last valid one.
    """
    dt = cfg.dt_s
    distance = s.distance_m + 0.5 * (u0 + u1) * dt  # exact for the linear speed of the period
    time = s.time_s + dt
    # a first-order Gauss-Markov process with stationary standard deviation disturbance_std_N
    disturbance = select(
        e.disturbance_std_N > 0.0,
        cfg.disturbance_decay * s.disturbance_N + cfg.disturbance_gain * disturbance_draw,
        s.disturbance_N,
    )
    kept = reason == _DIVERGED
    pitch, heave = select(kept, s.pitch_rad, x0), select(kept, s.heave_mps, x1)
    rate, depth = select(kept, s.pitch_rate_radps, x2), select(kept, s.depth_m, x3)
    steps = s.steps + 1
    terminated, truncated = episode_outcome(reason, time, steps, e.duration_s, cfg)
    return pitch, heave, rate, depth, time, steps, distance, u1, disturbance, terminated, truncated


@inline_kernel
def episode_outcome(
    reason: int, time_s: float, steps: int, duration_s: float, cfg: ConfigRecord
) -> tuple[bool, bool]:
    """(terminated, truncated) of a state reached at ``time_s`` after ``steps`` steps, ended for
    ``reason`` (:func:`episode_end`) in an episode of ``duration_s``."""
    terminated = reason != 0
    # truncated at the scenario's duration, and as gymnasium.wrappers.TimeLimit (even on a terminal step)
    truncated = ((reason == 0) & (time_s >= duration_s - 1e-9)) | (steps >= cfg.max_steps)
    return terminated, truncated


_NO_NOISE: Final[tuple[float, ...]] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@inline_kernel
def noise_values(
    z0: float, z1: float, z2: float, z3: float, z4: float, z5: float, z6: float, z7: float, cfg: ConfigRecord
) -> tuple[float, ...]:
    """The observation's noise from :data:`N_OBS` standard normal numbers: each times its standard
    deviation, one depth sensor for components 0 and 7."""
    std = cfg.noise_std
    n7 = z7 * std[7]
    return n7, z1 * std[1], z2 * std[2], z3 * std[3], z4 * std[4], z5 * std[5], z6 * std[6], n7


@inline_kernel
def sensor_noise(rng: np.random.Generator, cfg: ConfigRecord) -> tuple[float, ...]:
    """The observation's noise, :data:`N_OBS` values drawn from ``rng``: ``rng.normal(0, 1, size=8) *
    std``, one depth sensor for components 0 and 7 (:func:`noise_values`)."""
    z0 = rng.normal(0.0, 1.0)
    z1 = rng.normal(0.0, 1.0)
    z2 = rng.normal(0.0, 1.0)
    z3 = rng.normal(0.0, 1.0)
    z4 = rng.normal(0.0, 1.0)
    z5 = rng.normal(0.0, 1.0)
    z6 = rng.normal(0.0, 1.0)
    z7 = rng.normal(0.0, 1.0)
    return noise_values(z0, z1, z2, z3, z4, z5, z6, z7, cfg)


@inline_kernel
def observation_values(
    s: StateRecord, e: EpisodeRecord, noise: tuple[float, ...], cfg: ConfigRecord
) -> tuple[float, ...]:
    """The observation (:data:`N_OBS` values, float64) of state ``s`` in episode ``e``, with ``noise``
    (:func:`noise_values`) added when the episode has sensor noise."""
    depth = s.depth_m
    n0, n1, n2, n3, n4, n5, n6, n7 = noise
    noisy = e.sensor_noise
    v0 = select(noisy, depth - e.depth_command_m + n0, depth - e.depth_command_m)
    v1 = select(noisy, s.pitch_rad + n1, s.pitch_rad)
    v2 = select(noisy, s.heave_mps + n2, s.heave_mps)
    v3 = select(noisy, s.pitch_rate_radps + n3, s.pitch_rate_radps)
    v4 = select(noisy, s.speed_mps + n4, s.speed_mps)
    v5 = select(noisy, s.stern_plane_rad + n5, s.stern_plane_rad)
    v6 = select(noisy, s.bow_plane_rad + n6, s.bow_plane_rad)
    v7 = select(noisy, depth + n7, depth)
    # Only a terminal state (or noise at zero speed) can reach the bounds.
    lo, hi = cfg.obs_low, cfg.obs_high
    return (
        clip(v0, lo[0], hi[0]),
        clip(v1, lo[1], hi[1]),
        clip(v2, lo[2], hi[2]),
        clip(v3, lo[3], hi[3]),
        clip(v4, lo[4], hi[4]),
        clip(v5, lo[5], hi[5]),
        clip(v6, lo[6], hi[6]),
        clip(v7, lo[7], hi[7]),
    )


@inline_kernel
def observation(
    s: StateRecord, e: EpisodeRecord, noise: tuple[float, ...], i: int, cfg: ConfigRecord, obs: np.ndarray
) -> None:
    """Write :func:`observation_values` into row ``i`` of ``obs`` (float32, :data:`N_OBS` columns)."""
    v0, v1, v2, v3, v4, v5, v6, v7 = observation_values(s, e, noise, cfg)
    obs[i, 0], obs[i, 1], obs[i, 2], obs[i, 3] = v0, v1, v2, v3
    obs[i, 4], obs[i, 5], obs[i, 6], obs[i, 7] = v4, v5, v6, v7


@inline_kernel
def report_values(
    s: StateRecord,
    e: EpisodeRecord,
    r_depth: float,
    r_pitch: float,
    r_effort: float,
    r_termination: float,
    reason: int,
    terminated: bool,
    truncated: bool,
) -> tuple[float, ...]:
    """The report (:data:`REPORT_KEYS`, in order, as floats) of state ``s`` in episode ``e``: its ``info``
    and the step's outcome."""
    depth, command, speed = s.depth_m, e.depth_command_m, s.speed_mps
    froude_scale, ucr = (
        e.froude_scale_mps,
        e.critical_speed_mps,
    )  # nan when z_GB <= 0 (then no Froude numbers)
    return (
        s.time_s,
        depth,
        command,
        depth - command,
        s.pitch_rad,
        s.heave_mps,
        s.pitch_rate_radps,
        s.stern_plane_rad,
        s.bow_plane_rad,
        speed,
        speed / froude_scale,  # Fn = u / sqrt(g z_GB)
        ucr,
        ucr / froude_scale,
        s.disturbance_N,
        r_depth,
        r_pitch,
        r_effort,
        r_termination,
        reason * 1.0,
        r_depth + r_pitch + r_effort + r_termination,
        select(terminated, 1.0, 0.0),
        select(truncated, 1.0, 0.0),
    )


@inline_kernel
def _report(
    report: FloatArray,
    j: int,
    s: StateRecord,
    e: EpisodeRecord,
    r_depth: float,
    r_pitch: float,
    r_effort: float,
    r_termination: float,
    reason: int,
    terminated: bool,
    truncated: bool,
) -> None:
    """Column ``j`` of a report: :func:`report_values`."""
    values = report_values(s, e, r_depth, r_pitch, r_effort, r_termination, reason, terminated, truncated)
    for c in range(_N_REPORT):
        report[c, j] = values[c]


# --- the kernels ------------------------------------------------------------------------------
@inline_kernel
def _first_non_finite(actions: FloatArray, active: np.ndarray) -> int:
    for i in range(actions.shape[0]):
        if active[i]:
            for j in range(actions.shape[1]):
                if not math.isfinite(actions[i, j]):
                    return i
    return -1


BLOCKS_PER_RUN: Final = 4
"""Blocks of :data:`~subenv.dynamics.integrate.LANES` sub-environments per call of :func:`step_blocks` (a
thread's unit of work in :func:`step_parallel`): few enough runs that the threads rarely meet at the
arguments' reference counts, enough that two or four threads share 1,024 sub-environments evenly."""


@kernel
def step_blocks(
    state: np.ndarray,
    episode: np.ndarray,
    seas: FloatArray,
    actions: FloatArray,
    active: np.ndarray,
    obs: np.ndarray,
    rngs: numba.typed.List,
    config: np.ndarray,
    hull: FloatArray,
    report: FloatArray,
    first: int,
    stop: int,
) -> None:
    """One control period of the active sub-environments of blocks ``first`` up to ``stop`` (block ``b``: rows
    ``b * LANES`` up to ``(b + 1) * LANES``), each block's lanes integrated together; arguments as
    :func:`step`'s. Compiled once, as its own function, and called by both :func:`step` and
    :func:`step_parallel`, once per thread with a run of blocks.

    The run of blocks and the copy of ``hull`` keep the threads apart: numba counts references to an
    array at each call that takes it (here: the ten arguments, and ``hull`` once per Runge-Kutta
    stage), and two threads counting on one array take turns at one cache line. Called per block
    with the shared ``hull``, two threads made 1.1-1.3 times one thread's rate at N = 4096.
    """
    n_rows = state.shape[0]
    last_action = actions.shape[1] - 1
    cfg = config[0]
    dt = cfg.dt_s
    if stop - first < (n_rows + LANES - 1) // LANES:
        hull = hull.copy()  # (this thread's own where the blocks are shared: see above)
    block = np.empty(LANE_ROWS * LANES)
    block_report = np.empty((_N_REPORT, LANES))
    efforts = np.empty(LANES)
    speeds_end = np.empty(LANES)
    members = np.empty(LANES, dtype=np.int64)
    for b in range(first, stop):
        _step_block(
            state,
            episode,
            seas,
            actions,
            active,
            obs,
            rngs,
            cfg,
            hull,
            report,
            b,
            n_rows,
            last_action,
            dt,
            block,
            block_report,
            efforts,
            speeds_end,
            members,
        )


@kernel
def _step_block(
    state: np.ndarray,
    episode: np.ndarray,
    seas: FloatArray,
    actions: FloatArray,
    active: np.ndarray,
    obs: np.ndarray,
    rngs: numba.typed.List,
    cfg: ConfigRecord,
    hull: FloatArray,
    report: FloatArray,
    b: int,
    n_rows: int,
    last_action: int,
    dt: float,
    block: FloatArray,
    block_report: FloatArray,
    efforts: FloatArray,
    speeds_end: FloatArray,
    members: np.ndarray,
) -> None:
    """Block ``b`` of :func:`step_blocks`, in its work arrays.

    Called, not inlined into :func:`step_blocks`: inlined, the one function took numba 40 s of a cold
    first step's 49 s to compile (25 s in all called), for no step rate we could measure
    (``benchmarks/speed.py --baseline``: 0.98-1.02 of the inlined build's env-steps/s but one
    two-thread row within its run-to-run spread)."""
    in_sea = False
    for i in range(b * LANES, minimum((b + 1) * LANES, n_rows)):
        in_sea = in_sea or (active[i] and episode[i].n_waves > 0)
    # (the seas' rows only where a lane has one: a block of them is larger than the rest of the step's memory)
    waves = np.zeros((LANES if in_sea else 1, WAVE_FIELDS, MAX_WAVES))
    # int64 from the start: from a literal 0 numba's type inference first compiled the free surface's
    # kernel for n = Literal[int](0), then again for int64 (a second compile in every cold process)
    n = np.int64(0)
    for i in range(b * LANES, minimum((b + 1) * LANES, n_rows)):
        if active[i]:
            s, e = state[i], episode[i]
            stern, bow, efforts[n], u0, speeds_end[n], slope = period_start(
                s, e, actions[i, 0], actions[i, last_action], cfg
            )
            s.stern_plane_rad, s.bow_plane_rad = stern, bow
            set_lane(
                block,
                n,
                s.pitch_rad,
                s.heave_mps,
                s.pitch_rate_radps,
                s.depth_m,
                s.time_s,
                u0,
                slope,
                stern,
                bow,
                s.disturbance_N,
                e.params,
                s.distance_m,
                e.n_waves,
            )
            if e.n_waves > 0:  # (element by element: a view of seas[i] would count references to seas)
                for f in range(WAVE_FIELDS):
                    for k in range(MAX_WAVES):
                        waves[n, f, k] = seas[i, f, k]
            members[n] = i
            n += 1
    control_period_lanes(block, n, dt, cfg.substeps, hull, waves)
    L = LANES
    for j in range(n):
        i = members[j]
        s, e = state[i], episode[i]
        x0, x1 = block[LANE_PITCH * L + j], block[(LANE_PITCH + 1) * L + j]
        x2, x3 = block[(LANE_PITCH + 2) * L + j], block[(LANE_PITCH + 3) * L + j]
        reason = episode_end(x0, x1, x2, x3, e.depth_command_m, cfg)
        std = e.disturbance_std_N
        noisy = e.sensor_noise and reason != _DIVERGED  # (a diverged state is not observed again)
        draw, noise = 0.0, _NO_NOISE
        if std > 0.0 or noisy:
            # The generator is taken from the list once per step, and only by an episode that draws:
            # every item taken costs a reference count (two per step took a third off what a second
            # thread adds; one per step where none is needed, a tenth off one thread's rate).
            rng = rngs[i]
            if std > 0.0:
                draw = rng.normal(0.0, std)
            if noisy:
                noise = sensor_noise(rng, cfg)
        (
            s.pitch_rad,
            s.heave_mps,
            s.pitch_rate_radps,
            s.depth_m,
            s.time_s,
            s.steps,
            s.distance_m,
            s.speed_mps,
            s.disturbance_N,
            terminated,
            truncated,
        ) = period_end(s, e, x0, x1, x2, x3, block[LANE_SPEED0 * L + j], speeds_end[j], reason, draw, cfg)
        r_depth, r_pitch, r_effort, r_termination = reward_terms(
            s.pitch_rad, s.depth_m - e.depth_command_m, efforts[j], terminated, cfg
        )
        if reason != _DIVERGED:  # (a diverged state keeps its last observation)
            observation(s, e, noise, i, cfg, obs)
        _report(
            block_report, j, s, e, r_depth, r_pitch, r_effort, r_termination, reason, terminated, truncated
        )
    # Key by key into the step's report (each key's row written in order, not 22 rows per env).
    for c in range(_N_REPORT):
        for j in range(n):
            report[c, members[j]] = block_report[c, j]


def _step(
    state: np.ndarray,
    episode: np.ndarray,
    seas: FloatArray,
    actions: FloatArray,
    active: np.ndarray,
    obs: np.ndarray,
    rngs: numba.typed.List,
    config: np.ndarray,
    hull: FloatArray,
    report: FloatArray,
) -> int:
    """The blocks of :func:`step_blocks`, in one run (:func:`step`) or one run per thread
    (:func:`step_parallel`)."""
    bad = _first_non_finite(actions, active)
    if bad >= 0:
        return bad
    n_blocks = (state.shape[0] + LANES - 1) // LANES
    runs = (n_blocks + BLOCKS_PER_RUN - 1) // BLOCKS_PER_RUN
    for r in numba.prange(runs):  # (a plain range in step: one thread)
        # (int64 bounds in both kernels: a parallel loop counts in uint64, and a second signature
        # would compile the blocks' code again)
        step_blocks(
            state,
            episode,
            seas,
            actions,
            active,
            obs,
            rngs,
            config,
            hull,
            report,
            np.int64(r * n_blocks // runs),
            np.int64((r + 1) * n_blocks // runs),
        )
    return -1


step = kernel(_step)
"""One control period of every sub-environment with ``active`` set, on the calling thread.

Parameters
----------
state : ndarray of STATE_DTYPE, shape (n,)
    Updated in place.
episode : ndarray of EPISODE_DTYPE, shape (n,)
seas : ndarray, shape (n, WAVE_FIELDS, MAX_WAVES)
    Row i: the sea of sub-environment i, read where ``episode[i].n_waves`` > 0
    (:func:`subenv.envs.episodes.write_sea`).
actions : ndarray, shape (n, n_actions)
    Clipped to [-1, 1]; a non-finite one stops the step before anything changes (see Returns).
active : ndarray of bool, shape (n,)
    The sub-environments to step; the others are left as they are.
obs : ndarray of float32, shape (n, N_OBS)
    The observations, written for the stepped sub-environments.
rngs : numba.typed.List of numpy.random.Generator
    Each sub-environment's generator.
config : ndarray of CONFIG_DTYPE, shape (1,)
hull : ndarray
    :attr:`subenv.dynamics.HullTable.packed` of the vehicle.
report : ndarray, shape (len(REPORT_KEYS), n)
    The step's report, written for the stepped sub-environments.

Returns
-------
int
    -1, or the index of the first active sub-environment whose action has a NaN or infinite
    entry: then nothing was stepped.
"""

step_parallel = parallel_kernel(_step)
""":func:`step` with its blocks of :data:`~subenv.dynamics.integrate.LANES` sub-environments shared among
numba's threads (``numba.set_num_threads``); the same results for any number of threads. Only where
:func:`threading_layer_available` (numba's TBB layer: safe under ``fork`` and from several threads)."""


@kernel
def draw_reset_numbers(
    rngs: numba.typed.List,
    indices: np.ndarray,
    counts: np.ndarray,
    picks: np.ndarray,
    uniforms: FloatArray,
) -> None:
    """The random numbers of a reset's draw, from each sub-environment's generator, for those in ``indices``.

    As :meth:`subenv.scenarios.Scenario.sample` takes them from one generator: a mixture of
    ``len(counts)`` > 1 components picks one, ``rng.integers(len(counts))``, into ``picks[j]`` (with one
    count, a plain scenario, nothing is drawn and the pick is 0, as ``rng.integers(1)`` draws nothing),
    then ``counts[pick]`` numbers uniform in [0, 1) (``rng.random(k)``) into row ``j`` of ``uniforms``.
    (numba's ``Generator.integers`` gives NumPy's numbers for a range below 2**32, not beyond:
    tests/envs/test_vector_env.py.)
    """
    choices = counts.shape[0]
    for j in range(indices.shape[0]):
        rng = rngs[indices[j]]
        pick = rng.integers(0, choices) if choices > 1 else 0
        picks[j] = pick
        for k in range(counts[pick]):
            uniforms[j, k] = rng.random()


@kernel
def draw_initial_disturbances(
    rngs: numba.typed.List, indices: np.ndarray, disturbance_std_N: FloatArray, disturbances: FloatArray
) -> None:
    """After :func:`draw_reset_numbers`, each episode's initial heave force, as
    :func:`subenv.envs.episodes.draw_episode` draws it: ``rng.normal(0, disturbance_std_N[j])`` into
    ``disturbances[j]`` where the standard deviation is > 0 (else 0, and nothing is drawn)."""
    for j in range(indices.shape[0]):
        std = disturbance_std_N[j]
        disturbances[j] = rngs[indices[j]].normal(0.0, std) if std > 0.0 else 0.0


@kernel
def observe(
    state: np.ndarray,
    episode: np.ndarray,
    indices: np.ndarray,
    obs: np.ndarray,
    rngs: numba.typed.List,
    config: np.ndarray,
    report: FloatArray,
) -> None:
    """After a reset of the sub-environments in ``indices``: their speed, observation and report column
    (reward terms 0, not ended)."""
    cfg = config[0]
    for k in range(indices.shape[0]):
        i = indices[k]
        s, e = state[i], episode[i]
        s.speed_mps = speed_at(s.time_s, e.n_knots, e.knot_time_s, e.knot_speed_mps)
        observation(s, e, sensor_noise(rngs[i], cfg) if e.sensor_noise else _NO_NOISE, i, cfg, obs)
        _report(report, i, s, e, 0.0, 0.0, 0.0, 0.0, 0, False, False)
