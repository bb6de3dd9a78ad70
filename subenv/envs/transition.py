"""The dive-plane environment's transition, compiled, for one sub-environment or a batch of them.

Both :class:`~subenv.envs.DivePlaneEnv` and :class:`~subenv.envs.DivePlaneVectorEnv` step through
:func:`step_batch` (Gymnasium's functional-env split: a pure transition over arrays, thin ``Env``
classes around it; the single env is a batch of one). It applies the action to the planes
(:func:`set_planes`), integrates one control period over the shared right-hand side
:func:`subenv.dynamics.rhs_point` (:func:`~subenv.dynamics.integrate.control_period_lanes` for
blocks of sub-environments, :func:`~subenv.dynamics.integrate.control_period_point` for a few),
and then (:func:`finish_step`) advances the disturbance, classifies the episode end, computes the
reward terms and the observation (with sensor noise drawn from the sub-environment's own
``numpy.random.Generator``, in the order the single environment always drew it).

Each sub-environment is one row of a float64 array (columns below); the environment's constants
are one float64 array (``C_*`` indices). Resets stay in Python (they draw a scenario); the vector
environment draws their random numbers here (:func:`draw_reset_numbers`).
"""

from __future__ import annotations

import math
from typing import Final

import numba
import numpy as np

from subenv._typing import FloatArray
from subenv.dynamics._jit import inline_kernel, kernel
from subenv.dynamics.integrate import (
    LANE_PITCH,
    LANE_ROWS,
    LANES,
    control_period_lanes,
    control_period_point,
    set_lane,
)
from subenv.dynamics.model import PARAM_FIELDS

__all__ = [
    "N_COLUMNS",
    "N_CONFIG",
    "N_REPORT",
    "REASONS",
    "REPORT_KEYS",
    "draw_reset_numbers",
    "finish_step",
    "first_non_finite",
    "observe_batch",
    "observe_env",
    "set_planes",
    "speed_at_point",
    "step_batch",
]

# --- columns of a sub-environment's row ------------------------------------------------------
PITCH, HEAVE, PITCH_RATE, DEPTH = 0, 1, 2, 3  # the state (theta, w, q, Z) [rad, m/s, rad/s, m]
PARAMS: Final = 4  # ModelParams in PARAM_FIELDS order (pack_params)
N_PARAMS: Final = len(PARAM_FIELDS)
STERN: Final = PARAMS + N_PARAMS  # applied plane angles [rad]
BOW: Final = STERN + 1
TIME: Final = BOW + 1  # [s] since reset
MAX_KNOTS: Final = 4
N_KNOTS: Final = TIME + 1  # speed profile: piecewise linear through (t, u) knots, held after the last
KNOT_T: Final = N_KNOTS + 1
KNOT_U: Final = KNOT_T + MAX_KNOTS
COMMAND: Final = KNOT_U + MAX_KNOTS  # ordered depth [m]
DISTURBANCE: Final = COMMAND + 1  # heave force [N]
DISTURBANCE_STD: Final = DISTURBANCE + 1  # [N]; 0: none
NOISE: Final = DISTURBANCE_STD + 1  # 1.0: sensor noise on
DURATION: Final = NOISE + 1  # [s]
CRITICAL_SPEED: Final = DURATION + 1  # [m/s] (nan: none)
SQRT_G_ZGB: Final = CRITICAL_SPEED + 1  # sqrt(g z_GB) [m/s], the Froude number's scale (nan: z_GB <= 0)
SPEED: Final = SQRT_G_ZGB + 1  # speed at TIME [m/s]
ELAPSED: Final = SPEED + 1  # steps since reset
REWARD_DEPTH: Final = ELAPSED + 1  # the reward terms of the last step
REWARD_PITCH: Final = REWARD_DEPTH + 1
REWARD_EFFORT: Final = REWARD_PITCH + 1
REWARD_TERMINATION: Final = REWARD_EFFORT + 1
REWARD: Final = REWARD_TERMINATION + 1
REASON: Final = REWARD + 1  # index into REASONS
TERMINATED: Final = REASON + 1  # 1.0 / 0.0
TRUNCATED: Final = TERMINATED + 1
N_COLUMNS: Final = TRUNCATED + 1

REASONS: Final = ("", "diverged", "pitch_limit", "broached", "left_depth_band")
"""``info["termination_reason"]`` for each value of the ``REASON`` column."""
_DIVERGED, _PITCH_LIMIT, _BROACHED, _LEFT_DEPTH_BAND = 1, 2, 3, 4

# --- rows of a step's report, one column per sub-environment: the single env's info
# (subenv.envs.dive_plane._info), key by key, then the step's outcome. The vector env hands each
# row out as an array over the sub-environments.
REPORT_KEYS: Final = ("time_s", "depth_m", "depth_command_m", "depth_error_m", "pitch_rad", "heave_mps",
                      "pitch_rate_radps", "stern_plane_rad", "bow_plane_rad", "speed_mps", "froude_number",
                      "critical_speed_mps", "critical_froude", "disturbance_N", "reward_depth", "reward_pitch",
                      "reward_effort", "reward_termination", "reason", "reward", "terminated", "truncated")
(R_TIME, R_DEPTH, R_COMMAND, R_DEPTH_ERROR, R_PITCH, R_HEAVE, R_PITCH_RATE, R_STERN, R_BOW, R_SPEED, R_FROUDE,
 R_CRITICAL_SPEED, R_CRITICAL_FROUDE, R_DISTURBANCE, R_REWARD_DEPTH, R_REWARD_PITCH, R_REWARD_EFFORT,
 R_REWARD_TERMINATION, R_REASON, R_REWARD, R_TERMINATED, R_TRUNCATED) = range(len(REPORT_KEYS))
N_REPORT: Final = len(REPORT_KEYS)

# --- the environment's constants ---------------------------------------------------------------
C_DT, C_SUBSTEPS, C_DUAL, C_ALPHA, C_PLANE_LIMIT, C_RATE_LIMITED, C_MAX_MOVE = 0, 1, 2, 3, 4, 5, 6
C_MAX_PITCH, C_MAX_DEPTH_ERROR, C_BROACH_DEPTH, C_DEPTH_SCALE = 7, 8, 9, 10
C_PITCH_WEIGHT, C_EFFORT_WEIGHT, C_TERMINATION_PENALTY = 11, 12, 13
C_DISTURBANCE_DECAY, C_DISTURBANCE_GAIN, C_MAX_STEPS, C_MAX_HEAVE, C_MAX_PITCH_RATE = 14, 15, 16, 17, 18
N_OBS: Final = 8
C_OBS_LOW: Final = 19
C_OBS_HIGH: Final = C_OBS_LOW + N_OBS
C_NOISE_STD: Final = C_OBS_HIGH + N_OBS
N_CONFIG: Final = C_NOISE_STD + N_OBS

_LANES_FROM: Final = 8
"""step_batch of fewer rows integrates them one at a time (the block integrator's loops cost more than
they save on a few states; the same bits either way)."""


def episode_time_limit(max_episode_steps: int | None) -> float:
    """The ``C_MAX_STEPS`` constant: a TimeLimit after that many steps (inf: none)."""
    return math.inf if max_episode_steps is None else float(max_episode_steps)


@inline_kernel
def speed_at_point(t: float, row: FloatArray) -> float:
    """Speed [m/s] of the row's profile at time ``t`` [s]: ``numpy.interp`` over its knots."""
    n = int(row[N_KNOTS])
    if n == 1:
        return row[KNOT_U]
    # numpy.interp (numpy/_core/src/multiarray/compiled_base.c, arr_interp), operation for operation.
    if math.isnan(t):
        return t
    if t < row[KNOT_T]:
        return row[KNOT_U]
    if t > row[KNOT_T + n - 1]:
        return row[KNOT_U + n - 1]
    j = 1
    while j < n and t >= row[KNOT_T + j]:
        j += 1
    j -= 1
    if j == n - 1 or row[KNOT_T + j] == t:
        return row[KNOT_U + j]
    x0, x1, y0, y1 = row[KNOT_T + j], row[KNOT_T + j + 1], row[KNOT_U + j], row[KNOT_U + j + 1]
    slope = (y1 - y0) / (x1 - x0)
    u = slope * (t - x0) + y0
    if math.isnan(u):
        u = slope * (t - x1) + y1
        if math.isnan(u) and y0 == y1:
            u = y0
    return u


@inline_kernel
def observe_env(row: FloatArray, obs: np.ndarray, rngs: numba.typed.List, i: int, cfg: FloatArray) -> None:
    """Write the observation of the row's current state into ``obs`` (float32, 8), drawing its noise
    from the sub-environment's generator ``rngs[i]``."""
    speed = speed_at_point(row[TIME], row)
    row[SPEED] = speed
    depth = row[DEPTH]
    v0 = depth - row[COMMAND]
    v1, v2, v3 = row[PITCH], row[HEAVE], row[PITCH_RATE]
    v4, v5, v6, v7 = speed, row[STERN], row[BOW], depth
    if row[NOISE] > 0.0:
        # rng.normal(0, 1, size=8) * std, one depth sensor for components 0 and 7.
        rng = rngs[i]
        n0 = rng.normal(0.0, 1.0) * cfg[C_NOISE_STD]
        n1 = rng.normal(0.0, 1.0) * cfg[C_NOISE_STD + 1]
        n2 = rng.normal(0.0, 1.0) * cfg[C_NOISE_STD + 2]
        n3 = rng.normal(0.0, 1.0) * cfg[C_NOISE_STD + 3]
        n4 = rng.normal(0.0, 1.0) * cfg[C_NOISE_STD + 4]
        n5 = rng.normal(0.0, 1.0) * cfg[C_NOISE_STD + 5]
        n6 = rng.normal(0.0, 1.0) * cfg[C_NOISE_STD + 6]
        n7 = rng.normal(0.0, 1.0) * cfg[C_NOISE_STD + 7]
        n0 = n7
        v0, v1, v2, v3 = v0 + n0, v1 + n1, v2 + n2, v3 + n3
        v4, v5, v6, v7 = v4 + n4, v5 + n5, v6 + n6, v7 + n7
    # Only a terminal state (or noise at zero speed) can reach the bounds.
    lo, hi = C_OBS_LOW, C_OBS_HIGH
    obs[0] = min(max(v0, cfg[lo]), cfg[hi])
    obs[1] = min(max(v1, cfg[lo + 1]), cfg[hi + 1])
    obs[2] = min(max(v2, cfg[lo + 2]), cfg[hi + 2])
    obs[3] = min(max(v3, cfg[lo + 3]), cfg[hi + 3])
    obs[4] = min(max(v4, cfg[lo + 4]), cfg[hi + 4])
    obs[5] = min(max(v5, cfg[lo + 5]), cfg[hi + 5])
    obs[6] = min(max(v6, cfg[lo + 6]), cfg[hi + 6])
    obs[7] = min(max(v7, cfg[lo + 7]), cfg[hi + 7])


@inline_kernel
def set_planes(row: FloatArray, action: FloatArray, cfg: FloatArray) -> float:
    """Apply an action (finite: see :func:`step_batch`) to the row's planes; returns the effort term's
    mean squared command."""
    limit = cfg[C_PLANE_LIMIT]
    a0 = min(max(action[0], -1.0), 1.0)
    stern = a0 * limit
    if cfg[C_DUAL] > 0.0:
        effort = a0 * a0
        bow = cfg[C_ALPHA] * stern  # Riedel (1993) eq. 2.58
    else:
        a1 = min(max(action[1], -1.0), 1.0)
        effort = (a0 * a0 + a1 * a1) / 2.0
        bow = a1 * limit
    if cfg[C_RATE_LIMITED] > 0.0:
        move = cfg[C_MAX_MOVE]
        stern = row[STERN] + min(max(stern - row[STERN], -move), move)
        bow = row[BOW] + min(max(bow - row[BOW], -move), move)
    row[STERN] = min(max(stern, -limit), limit)
    row[BOW] = min(max(bow, -limit), limit)
    return effort


@inline_kernel
def finish_step(row: FloatArray, x0: float, x1: float, x2: float, x3: float, speed_end: float, effort: float,
                obs: np.ndarray, rngs: numba.typed.List, i: int, cfg: FloatArray) -> None:
    """The rest of sub-environment ``i``'s step, given the state (x0..x3) at the end of the control
    period and the speed then: disturbance, episode end, reward terms, observation."""
    row[TIME] = row[TIME] + cfg[C_DT]
    std = row[DISTURBANCE_STD]
    if std > 0.0:
        # First-order Gauss-Markov process with stationary standard deviation std.
        row[DISTURBANCE] = cfg[C_DISTURBANCE_DECAY] * row[DISTURBANCE] + cfg[C_DISTURBANCE_GAIN] * rngs[i].normal(0.0, std)

    reason = 0
    if not (math.isfinite(x0) and math.isfinite(x1) and math.isfinite(x2) and math.isfinite(x3)
            and abs(x1) <= cfg[C_MAX_HEAVE] and abs(x2) <= cfg[C_MAX_PITCH_RATE]):
        reason = _DIVERGED  # keep the last valid state
    else:
        row[PITCH], row[HEAVE], row[PITCH_RATE], row[DEPTH] = x0, x1, x2, x3
        if abs(x0) > cfg[C_MAX_PITCH]:
            reason = _PITCH_LIMIT
        elif x3 < cfg[C_BROACH_DEPTH]:
            reason = _BROACHED
        elif abs(x3 - row[COMMAND]) > cfg[C_MAX_DEPTH_ERROR]:
            reason = _LEFT_DEPTH_BAND
    terminated = reason != 0
    truncated = not terminated and row[TIME] >= row[DURATION] - 1e-9
    row[ELAPSED] += 1.0
    if row[ELAPSED] >= cfg[C_MAX_STEPS]:
        truncated = True  # as gymnasium.wrappers.TimeLimit: truncated even on a terminal step

    ratio = row[PITCH] / cfg[C_MAX_PITCH]
    # 1 - tanh(x) as 2 / (1 + e^(2x)), the same number: libm's exp costs a third of its tanh (about 20 ns
    # less per step), and the small rewards far off depth keep their relative precision.
    r_depth = 2.0 / (1.0 + math.exp(2.0 * abs(row[DEPTH] - row[COMMAND]) / cfg[C_DEPTH_SCALE]))
    r_pitch = -cfg[C_PITCH_WEIGHT] * (ratio * ratio)
    r_effort = -cfg[C_EFFORT_WEIGHT] * effort
    r_termination = -cfg[C_TERMINATION_PENALTY] if terminated else 0.0
    row[REWARD_DEPTH], row[REWARD_PITCH], row[REWARD_EFFORT], row[REWARD_TERMINATION] = (
        r_depth, r_pitch, r_effort, r_termination)
    row[REWARD] = r_depth + r_pitch + r_effort + r_termination
    row[REASON] = reason
    row[TERMINATED] = 1.0 if terminated else 0.0
    row[TRUNCATED] = 1.0 if truncated else 0.0
    if reason == _DIVERGED:
        row[SPEED] = speed_end  # the observation stays the last valid one
    else:
        observe_env(row, obs, rngs, i, cfg)


@inline_kernel
def report_env(row: FloatArray, report: FloatArray, j: int) -> None:
    """Write column ``j`` of ``report`` (rows ``R_*``) from a transition row, as the single env's info
    computes it."""
    depth, command, speed = row[DEPTH], row[COMMAND], row[SPEED]
    froude_scale, ucr = row[SQRT_G_ZGB], row[CRITICAL_SPEED]  # nan when z_GB <= 0 (then no Froude numbers)
    report[R_TIME, j] = row[TIME]
    report[R_DEPTH, j] = depth
    report[R_COMMAND, j] = command
    report[R_DEPTH_ERROR, j] = depth - command
    report[R_PITCH, j] = row[PITCH]
    report[R_HEAVE, j] = row[HEAVE]
    report[R_PITCH_RATE, j] = row[PITCH_RATE]
    report[R_STERN, j] = row[STERN]
    report[R_BOW, j] = row[BOW]
    report[R_SPEED, j] = speed
    report[R_FROUDE, j] = speed / froude_scale
    report[R_CRITICAL_SPEED, j] = ucr
    report[R_CRITICAL_FROUDE, j] = ucr / froude_scale
    report[R_DISTURBANCE, j] = row[DISTURBANCE]
    report[R_REWARD_DEPTH, j] = row[REWARD_DEPTH]
    report[R_REWARD_PITCH, j] = row[REWARD_PITCH]
    report[R_REWARD_EFFORT, j] = row[REWARD_EFFORT]
    report[R_REWARD_TERMINATION, j] = row[REWARD_TERMINATION]
    report[R_REASON, j] = row[REASON]
    report[R_REWARD, j] = row[REWARD]
    report[R_TERMINATED, j] = row[TERMINATED]
    report[R_TRUNCATED, j] = row[TRUNCATED]


@inline_kernel
def _first_non_finite(actions: FloatArray, active: np.ndarray) -> int:
    for i in range(actions.shape[0]):
        if active[i]:
            for j in range(actions.shape[1]):
                if not math.isfinite(actions[i, j]):
                    return i
    return -1


@kernel
def first_non_finite(actions: FloatArray, active: np.ndarray) -> int:
    """The index of the first ``active`` row of ``actions`` with a NaN or infinite entry, or -1."""
    return _first_non_finite(actions, active)


@inline_kernel
def _begin_step(row: FloatArray, action: FloatArray, cfg: FloatArray) -> tuple[float, float, float, float]:
    """Set the planes (:func:`set_planes`); returns the effort, the time and the speeds at the start and
    the end of the control period."""
    effort = set_planes(row, action, cfg)
    t0 = row[TIME]
    return effort, t0, speed_at_point(t0, row), speed_at_point(t0 + cfg[C_DT], row)


@kernel
def step_batch(rows: FloatArray, actions: FloatArray, active: np.ndarray, obs: np.ndarray, rngs: numba.typed.List,
               first: int, cfg: FloatArray, hull: FloatArray, report: FloatArray) -> int:
    """One control period of each row with ``active`` set, and its column of ``report``
    (:func:`report_env`, shape ``(N_REPORT, number of sub-environments)``); the single env is one row.

    Each row's step: set the planes (:func:`set_planes`), integrate the control period, finish the
    step (:func:`finish_step`). With :data:`_LANES_FROM` rows or more, the active rows go in blocks
    of :data:`~subenv.dynamics.integrate.LANES` and each block's control period is integrated
    together (:func:`~subenv.dynamics.integrate.control_period_lanes`, SIMD code); fewer rows are
    integrated one at a time (:func:`~subenv.dynamics.integrate.control_period_point`). The two give
    the same bits.

    Returns -1, or the index (in ``rows``) of the first active row with a non-finite action, and
    then steps nothing. ``rows``, ``actions``, ``active`` and ``obs`` may be a slice of the
    sub-environments starting at ``first`` (``rngs`` and ``report`` are for all of them): slices
    can be stepped on separate threads (the kernel releases the GIL).
    """
    bad = _first_non_finite(actions, active)
    if bad >= 0:
        return bad
    dt = cfg[C_DT]
    substeps = int(cfg[C_SUBSTEPS])
    if rows.shape[0] < _LANES_FROM:
        for i in range(rows.shape[0]):
            if active[i]:
                row = rows[i]
                effort, t0, u0, u1 = _begin_step(row, actions[i], cfg)
                x0, x1, x2, x3 = control_period_point(
                    row[PITCH], row[HEAVE], row[PITCH_RATE], row[DEPTH], t0, dt, substeps, u0, (u1 - u0) / dt,
                    row[STERN], row[BOW], row[DISTURBANCE], row[PARAMS:PARAMS + N_PARAMS], hull)
                finish_step(row, x0, x1, x2, x3, u1, effort, obs[i], rngs, first + i, cfg)
                report_env(row, report, first + i)
        return -1
    L = LANES
    block = np.empty(LANE_ROWS * L)
    block_report = np.empty((N_REPORT, L))  # (the columns of the step's report, written in rows below)
    efforts = np.empty(L)
    speeds_end = np.empty(L)
    members = np.empty(L, dtype=np.int64)
    i = 0
    while i < rows.shape[0]:
        n = 0
        while i < rows.shape[0] and n < L:
            if active[i]:
                row = rows[i]
                efforts[n], t0, u0, u1 = _begin_step(row, actions[i], cfg)
                speeds_end[n] = u1
                set_lane(block, n, row[PITCH], row[HEAVE], row[PITCH_RATE], row[DEPTH], t0, u0, (u1 - u0) / dt,
                         row[STERN], row[BOW], row[DISTURBANCE], row[PARAMS:PARAMS + N_PARAMS])
                members[n] = i
                n += 1
            i += 1
        control_period_lanes(block, n, dt, substeps, hull)
        for j in range(n):
            k = members[j]
            finish_step(rows[k], block[LANE_PITCH * L + j], block[(LANE_PITCH + 1) * L + j],
                        block[(LANE_PITCH + 2) * L + j], block[(LANE_PITCH + 3) * L + j], speeds_end[j], efforts[j],
                        obs[k], rngs, first + k, cfg)
            report_env(rows[k], block_report, j)
        # Key by key into the step's report (each key's row written in order, not 22 rows per env).
        for c in range(N_REPORT):
            for j in range(n):
                report[c, first + members[j]] = block_report[c, j]
    return -1


@kernel
def draw_reset_numbers(rngs: numba.typed.List, indices: np.ndarray, units: FloatArray, disturbance_std: float,
                       disturbances: FloatArray) -> None:
    """The random numbers a reset takes from each sub-environment's generator, for those in ``indices``.

    In the single environment's order: ``units.shape[1]`` uniform numbers in [0, 1) (as
    ``rng.random(k)``, the scenario's draw) into row ``j`` of ``units``, then, with
    ``disturbance_std`` > 0, the initial heave force (as ``rng.normal(0, disturbance_std)``) into
    ``disturbances[j]`` (else 0). numba's generator methods are NumPy's algorithms over the same
    bit generator: the same numbers (``tests/envs/test_vector_env.py``).
    """
    for j in range(indices.shape[0]):
        rng = rngs[indices[j]]
        for k in range(units.shape[1]):
            units[j, k] = rng.random()
        disturbances[j] = rng.normal(0.0, disturbance_std) if disturbance_std > 0.0 else 0.0


@kernel
def observe_batch(rows: FloatArray, indices: np.ndarray, obs: np.ndarray, rngs: numba.typed.List, cfg: FloatArray,
                  report: FloatArray) -> None:
    """:func:`observe_env` and :func:`report_env` for the rows in ``indices`` (after their reset)."""
    for k in range(indices.shape[0]):
        i = indices[k]
        observe_env(rows[i], obs[i], rngs, i, cfg)
        report_env(rows[i], report, i)
