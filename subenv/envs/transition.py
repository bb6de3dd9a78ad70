"""The dive-plane environment's transition, compiled, for one sub-environment or a batch of them.

Both :class:`~subenv.envs.DivePlaneEnv` and :class:`~subenv.envs.DivePlaneVectorEnv` step through
:func:`step_env` (Gymnasium's functional-env split: a pure transition over arrays, thin ``Env``
classes around it). It applies the action to the planes, integrates one control period with
:func:`subenv.dynamics.integrate.control_period_point` over the shared right-hand side
:func:`subenv.dynamics.rhs_point`, advances the disturbance, classifies the episode end, computes
the reward terms and the observation (with sensor noise drawn from the sub-environment's own
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
from subenv.dynamics.integrate import control_period_point
from subenv.dynamics.model import PARAM_FIELDS

__all__ = [
    "N_COLUMNS",
    "N_CONFIG",
    "N_REPORT",
    "REASONS",
    "REPORT_KEYS",
    "draw_reset_numbers",
    "first_non_finite",
    "observe_batch",
    "observe_env",
    "speed_at_point",
    "step_batch",
    "step_env",
]

# --- columns of a sub-environment's row ------------------------------------------------------
PITCH, HEAVE, PITCH_RATE, DEPTH = 0, 1, 2, 3  # the state (theta, w, q, Z) [rad, m/s, rad/s, m]
PARAMS: Final = 4  # ModelParams in PARAM_FIELDS order (pack_params)
STERN: Final = PARAMS + len(PARAM_FIELDS)  # applied plane angles [rad]
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

# --- columns of a step's report, one row per sub-environment: the single env's info
# (subenv.envs.dive_plane._info), key by key, then the step's outcome. The vector env hands each
# column out as an array over the sub-environments.
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
def step_env(row: FloatArray, action: FloatArray, obs: np.ndarray, rngs: numba.typed.List, i: int,
             cfg: FloatArray, hull: FloatArray) -> None:
    """One control period of sub-environment ``i`` (its action must be finite: see :func:`step_batch`)."""
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
    stern = min(max(stern, -limit), limit)
    bow = min(max(bow, -limit), limit)
    row[STERN] = stern
    row[BOW] = bow

    t0 = row[TIME]
    dt = cfg[C_DT]
    u0 = speed_at_point(t0, row)
    u1 = speed_at_point(t0 + dt, row)
    x0, x1, x2, x3 = control_period_point(
        row[PITCH], row[HEAVE], row[PITCH_RATE], row[DEPTH], t0, dt, int(cfg[C_SUBSTEPS]), u0, (u1 - u0) / dt,
        stern, bow, row[DISTURBANCE], row[PARAMS:PARAMS + len(PARAM_FIELDS)], hull)
    row[TIME] = t0 + dt
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
    r_depth = 1.0 - math.tanh(abs(row[DEPTH] - row[COMMAND]) / cfg[C_DEPTH_SCALE])
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
        row[SPEED] = u1  # the observation stays the last valid one
    else:
        observe_env(row, obs, rngs, i, cfg)


@inline_kernel
def report_env(row: FloatArray, report: FloatArray, j: int) -> None:
    """Write row ``j`` of a step's report (columns ``R_*``) from a transition row, as the single env's
    info computes it. (Row-major: one env's report is contiguous, which the threads write fastest.)"""
    depth, command, speed = row[DEPTH], row[COMMAND], row[SPEED]
    froude_scale, ucr = row[SQRT_G_ZGB], row[CRITICAL_SPEED]  # nan when z_GB <= 0 (then no Froude numbers)
    report[j, R_TIME] = row[TIME]
    report[j, R_DEPTH] = depth
    report[j, R_COMMAND] = command
    report[j, R_DEPTH_ERROR] = depth - command
    report[j, R_PITCH] = row[PITCH]
    report[j, R_HEAVE] = row[HEAVE]
    report[j, R_PITCH_RATE] = row[PITCH_RATE]
    report[j, R_STERN] = row[STERN]
    report[j, R_BOW] = row[BOW]
    report[j, R_SPEED] = speed
    report[j, R_FROUDE] = speed / froude_scale
    report[j, R_CRITICAL_SPEED] = ucr
    report[j, R_CRITICAL_FROUDE] = ucr / froude_scale
    report[j, R_DISTURBANCE] = row[DISTURBANCE]
    report[j, R_REWARD_DEPTH] = row[REWARD_DEPTH]
    report[j, R_REWARD_PITCH] = row[REWARD_PITCH]
    report[j, R_REWARD_EFFORT] = row[REWARD_EFFORT]
    report[j, R_REWARD_TERMINATION] = row[REWARD_TERMINATION]
    report[j, R_REASON] = row[REASON]
    report[j, R_REWARD] = row[REWARD]
    report[j, R_TERMINATED] = row[TERMINATED]
    report[j, R_TRUNCATED] = row[TRUNCATED]


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


@kernel
def step_batch(rows: FloatArray, actions: FloatArray, active: np.ndarray, obs: np.ndarray, rngs: numba.typed.List,
               first: int, cfg: FloatArray, hull: FloatArray, report: FloatArray) -> int:
    """:func:`step_env` and :func:`report_env` for each row with ``active`` set; the single env is one row.

    Returns -1, or the index (in ``rows``) of the first active row with a non-finite action, and
    then steps nothing. ``rows``, ``actions``, ``active`` and ``obs`` may be a slice of the
    sub-environments starting at ``first`` (``rngs`` and ``report`` are for all of them): slices
    can be stepped on separate threads (the kernel releases the GIL).
    """
    bad = _first_non_finite(actions, active)
    if bad >= 0:
        return bad
    for i in range(rows.shape[0]):
        if active[i]:
            step_env(rows[i], actions[i], obs[i], rngs, first + i, cfg, hull)
            report_env(rows[i], report, first + i)
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
