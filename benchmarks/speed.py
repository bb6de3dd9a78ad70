"""How fast subenv steps, next to Gymnasium's own environments, measured in one run on one machine.

    .venv/bin/python benchmarks/speed.py [--seconds 1.0] [--repeats 3] [--quick] [--baseline DIR]
                                         [--json PATH]

Prints Markdown tables of ratios against references measured in the same process (absolute
numbers depend on the machine; the ratios are what to compare):

1. single environment steps/s, raw (``env.unwrapped``) and through ``gym.make``, next to
   Pendulum-v1 and CartPole-v1;
2. vector environment env-steps/s at N = 1, 64, 1024, 4096: ``gym.make_vec(id, num_envs=N)``
   (DivePlaneVectorEnv, on one thread per 512 envs up to the cores, and on one thread), next to
   ``SyncVectorEnv`` over the single environment and Gymnasium's ``CartPoleVectorEnv``;
3. integrator cost: simulated seconds per wall second, the envs' compiled RK4 against
   ``rk4`` over ``derivatives`` and ``scipy.integrate.solve_ivp``;
   and where an env-step's time goes: the compiled step without resets and its parts (control
   period, right-hand side, its sine and cosine, the hull integral), the resets (per episode, in
   batches of 1 and 64, as ratios to Nominal-v0's), and the ceiling the compiled step puts on two
   cores next to ``CartPoleVectorEnv``;
4. peak memory at N = 4096 (a fresh process per environment);
5. numba compile time: the first calls in a fresh process with an empty cache, then with the
   cache written by that process;
6. with ``--baseline DIR`` (a checkout of another commit, e.g. ``git worktree add /tmp/base HEAD~1``):
   the single env and the vector env on one and two threads, measured through the public API in
   child processes that take turns between this tree and DIR, and the ratios between them.

Every rate is the best of ``--repeats`` runs of ``--seconds`` each, taken in turns across the
environments of a table (machines share their cores; the two-thread probe printed before and
after tells whether both cores were free); actions are uniform random, drawn before timing;
resets are included in the time. ``--json PATH`` also writes what was printed as a record (machine,
date, command, the tables: ``benchmarks/_record.py``), from which the documentation draws its figures.
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numba
import numpy as np
from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

import subenv  # registers the environments
from subenv.dynamics import integrate as ig
from subenv.dynamics.waves import WAVE_FIELDS

SUBENV_IDS = ("subenv/Nominal-v0", "subenv/DivePlane-v0")
VECTOR_SIZES = (1, 64, 1024, 4096)
RESET_BATCHES = (1, 64)
"""The batch sizes of the resets measured (per episode, as a ratio to Nominal-v0's)."""
ROOT = Path(__file__).resolve().parents[1]


@functools.cache
def _inputs_of_the_periods(n: int) -> tuple[Any, ...]:
    zeros = np.zeros(n)
    # t0, dt, speed0, its slope, stern, bow, force (per state), then after prm and hull: substeps, distance,
    # and no sea
    return (zeros, ig.CONTROL_PERIOD_S, np.ones(n), zeros, np.full(n, 0.05), zeros, zeros), (
        ig.SUBSTEPS,
        zeros,
        np.zeros((1, WAVE_FIELDS, 0)),
    )


def control_periods_in_blocks(x: np.ndarray, prm: np.ndarray, hull: np.ndarray, out: np.ndarray) -> None:
    """One control period (0.5 s, speed 1 m/s, stern planes 0.05 rad) of the states ``x`` (rows) with
    the loadings ``prm`` into ``out``: the environments' block integrator, 64 states at a time
    (:func:`subenv.dynamics.integrate.control_period_rows`; also ``benchmarks/jax_dynamics.py``'s
    reference)."""
    before, after = _inputs_of_the_periods(x.shape[0])
    ig.control_period_rows(x, *before, prm, hull, *after, out)


# --- timing ----------------------------------------------------------------------------------
def _from_states(
    step: Callable[..., None], states: np.ndarray, source: np.ndarray, args: tuple[Any, ...]
) -> None:
    """``step(*args)`` from the states ``source`` holds, copied into ``states`` (which ``args`` hold)."""
    states[:] = source
    step(*args)


def best_rate(run: Callable[[int], None], per_call: int, seconds: float, repeats: int) -> float:
    """Best over ``repeats`` of (env-steps per second) for ``run(k)``.

    ``run(k)`` makes call k, of ``per_call`` env-steps.
    """
    best = 0.0
    calls_per_check = max(1, 4096 // per_call)
    for _ in range(repeats):
        calls = 0
        start = time.perf_counter()
        deadline = start + seconds
        while True:
            for _ in range(calls_per_check):
                run(calls)
                calls += 1
            now = time.perf_counter()
            if now >= deadline:
                break
        best = max(best, calls * per_call / (now - start))
    return best


def single_env_rate(env: gym.Env, seconds: float, repeats: int) -> float:  # type: ignore[type-arg]
    """Steps/s of one environment with random actions; an ended episode is reset (timed)."""
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(4096)]
    env.reset(seed=0)

    def run(k: int) -> None:
        _, _, terminated, truncated, _ = env.step(actions[k % 4096])
        if terminated or truncated:
            env.reset()

    for k in range(100):  # warm-up (and the first compiled call)
        run(k)
    return best_rate(run, 1, seconds, repeats)


def vector_env_rate(env: gym.vector.VectorEnv, seconds: float, repeats: int) -> float:  # type: ignore[type-arg]
    """Env-steps/s of a vector environment with random actions (it autoresets)."""
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(16)]
    env.reset(seed=0)

    def run(k: int) -> None:
        env.step(actions[k % 16])

    for k in range(3):
        run(k)
    return best_rate(run, env.num_envs, seconds, repeats)


# --- the sections ---------------------------------------------------------------------------
def round_robin(cells: dict[str, Callable[[], float]], repeats: int) -> dict[str, float]:
    """Best of ``repeats`` runs of every cell, the runs taken in turns across the cells, so that a
    burst of load from another process costs one run of several cells, not every run of one."""
    best = dict.fromkeys(cells, 0.0)
    for _ in range(repeats):
        for key, measure in cells.items():
            best[key] = max(best[key], measure())
    return best


def single_env_table(seconds: float, repeats: int) -> list[str]:
    ids = ("Pendulum-v1", "CartPole-v1", *SUBENV_IDS)
    cells: dict[str, Callable[[], float]] = {}
    for env_id in ids:
        for kind, env in (("raw", gym.make(env_id).unwrapped), ("make", gym.make(env_id))):
            cells[f"{env_id} {kind}"] = functools.partial(single_env_rate, env, seconds, 1)
    best = round_robin(cells, repeats)
    ref_raw, ref_made = best["Pendulum-v1 raw"], best["Pendulum-v1 make"]
    lines = [
        "| environment | raw steps/s | x Pendulum-v1 raw | gym.make steps/s | x Pendulum-v1 gym.make |",
        "|---|---:|---:|---:|---:|",
    ]
    for env_id in ids:
        raw_rate, made_rate = best[f"{env_id} raw"], best[f"{env_id} make"]
        lines.append(
            f"| {env_id} | {raw_rate:,.0f} | {raw_rate / ref_raw:.2f} | {made_rate:,.0f} "
            f"| {made_rate / ref_made:.2f} |"
        )
    return lines


def vector_env_table(seconds: float, repeats: int, sizes: tuple[int, ...]) -> list[str]:
    lines = [
        (
            "| environment | N | native env-steps/s | native, 1 thread | SyncVectorEnv | CartPoleVectorEnv "
            "| native / Sync | native / CartPoleVectorEnv |"
        ),
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for n in sizes:
        envs: dict[str, gym.vector.VectorEnv] = {"cartpole": CartPoleVectorEnv(num_envs=n)}  # type: ignore[type-arg]
        for env_id in SUBENV_IDS:
            envs[f"{env_id} native"] = gym.make_vec(env_id, num_envs=n)
            envs[f"{env_id} serial"] = gym.make_vec(env_id, num_envs=n, threads=1)
            envs[f"{env_id} sync"] = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync")
        best = round_robin(
            {key: functools.partial(vector_env_rate, env, seconds, 1) for key, env in envs.items()}, repeats
        )
        for env in envs.values():
            env.close()
        cartpole = best["cartpole"]
        for env_id in SUBENV_IDS:
            native, serial, sync = (best[f"{env_id} {kind}"] for kind in ("native", "serial", "sync"))
            lines.append(
                f"| {env_id} | {n} | {native:,.0f} | {serial:,.0f} | {sync:,.0f} | {cartpole:,.0f} "
                f"| {native / sync:.1f} | {native / cartpole:.2f} |"
            )
    return lines


def integrator_table(seconds: float) -> list[str]:
    from scipy.integrate import solve_ivp

    from subenv.dynamics import CONTROL_PERIOD_S, SUBSTEPS, derivatives, model_params, rk4
    from subenv.dynamics.model import pack_params

    vehicle = subenv.load_vehicle("suboff")  # C_D = 0.3: hull drag on
    params = model_params(vehicle)
    prm, hull = pack_params(params), params.hull.packed
    speed, plane, x0 = 1.0, 0.05, np.array([0.02, 0.0, 0.0, 10.0])
    horizon_s = 600.0
    periods = round(horizon_s / CONTROL_PERIOD_S)

    @numba.njit
    def compiled(x: np.ndarray, periods: int) -> np.ndarray:
        block = np.empty(ig.LANE_ROWS * ig.LANES)
        a, b, c, d = x[0], x[1], x[2], x[3]
        for k in range(periods):  # a block of one state, as the single environment steps
            ig.set_lane(block, 0, a, b, c, d, k * CONTROL_PERIOD_S, speed, 0.0, plane, 0.0, 0.0, prm)
            ig.control_period_lanes(block, 1, CONTROL_PERIOD_S, SUBSTEPS, hull, ig.NO_WAVES)
            L = ig.LANES
            a, b, c, d = (
                block[ig.LANE_PITCH * L],
                block[(ig.LANE_PITCH + 1) * L],
                block[(ig.LANE_PITCH + 2) * L],
                block[(ig.LANE_PITCH + 3) * L],
            )
        return np.array([a, b, c, d])

    def python_rk4(x: np.ndarray, periods: int) -> np.ndarray:
        for k in range(periods):
            x = rk4(
                lambda t, s: derivatives(s, speed, plane, 0.0, params),
                k * CONTROL_PERIOD_S,
                x,
                CONTROL_PERIOD_S,
                SUBSTEPS,
            )
        return x

    def scipy(rtol: float, atol: float) -> Callable[[np.ndarray, int], np.ndarray]:
        def run(x: np.ndarray, periods: int) -> np.ndarray:
            for k in range(periods):  # the planes are held over a control period: one solve per period
                t = k * CONTROL_PERIOD_S
                x = solve_ivp(
                    lambda _, s: derivatives(s, speed, plane, 0.0, params),
                    (t, t + CONTROL_PERIOD_S),
                    x,
                    rtol=rtol,
                    atol=atol,
                ).y[:, -1]
            return x

        return run

    rows = []
    integrators: list[tuple[str, Callable[[np.ndarray, int], np.ndarray]]] = [
        ("RK4, compiled, one state (`control_period_lanes` over a block of one)", compiled),
        ("RK4, `rk4` over `derivatives` (Python loop)", python_rk4),
        ("`solve_ivp` RK45, default tolerances", scipy(1e-3, 1e-6)),
        ("`solve_ivp` RK45, rtol 1e-10, atol 1e-12", scipy(1e-10, 1e-12)),
    ]
    for label, run in integrators:
        run(x0, 1)  # compiled (or loaded from the cache) before the clock starts
        count, start = 0, time.perf_counter()
        while True:
            run(x0, periods)
            count += 1
            elapsed = time.perf_counter() - start
            if elapsed >= seconds:
                break
        rows.append((label, count * horizon_s / elapsed))
    lines = [
        (
            "| integrator (600 s at 1 m/s, dt 0.5 s held planes, hull drag on) | simulated s per wall s "
            "| x compiled RK4 |"
        ),
        "|---|---:|---:|",
    ]
    for label, rate in rows:
        lines.append(f"| {label} | {rate:,.0f} | {rate / rows[0][1]:.2g} |")
    return lines


def cost_table(seconds: float) -> list[str]:
    """Where an env-step's time goes, on one thread: the compiled step without resets and its parts,
    then the resets, and the ceiling they put on two cores (the compiled step on numba's threads)
    next to CartPoleVectorEnv."""
    import math

    from subenv.dynamics import CONTROL_PERIOD_S, SUBSTEPS, model_params
    from subenv.dynamics.hull import crossflow_point
    from subenv.dynamics.model import pack_params, rhs_point
    from subenv.dynamics.sincos import sincos_point
    from subenv.envs import transition as tr

    n = 4096
    params = model_params(subenv.load_vehicle("suboff"))
    hull = params.hull.packed
    prm = np.repeat(pack_params(params)[None], n, axis=0)  # one parameter row per state, as in the envs
    rng = np.random.default_rng(0)
    states = np.column_stack(
        [
            rng.uniform(-0.05, 0.05, n),
            rng.uniform(-0.05, 0.05, n),
            rng.uniform(-0.01, 0.01, n),
            rng.uniform(8.0, 15.0, n),
        ]
    )
    out = np.zeros((n, 4))

    @numba.njit
    def periods(x: np.ndarray, prm: np.ndarray, out: np.ndarray) -> None:
        L = ig.LANES
        block = np.empty(ig.LANE_ROWS * L)
        for i in range(x.shape[0]):  # a block of one state at a time
            ig.set_lane(block, 0, x[i, 0], x[i, 1], x[i, 2], x[i, 3], 0.0, 1.0, 0.0, 0.05, 0.0, 0.0, prm[i])
            ig.control_period_lanes(block, 1, CONTROL_PERIOD_S, SUBSTEPS, hull, ig.NO_WAVES)
            for r in range(4):
                out[i, r] = block[(ig.LANE_PITCH + r) * L]

    def periods_in_blocks(x: np.ndarray, prm: np.ndarray, out: np.ndarray) -> None:
        control_periods_in_blocks(x, prm, hull, out)

    @numba.njit
    def rhs(x: np.ndarray, prm: np.ndarray, out: np.ndarray) -> None:
        for i in range(x.shape[0]):
            out[i, 0], out[i, 1], out[i, 2], out[i, 3] = rhs_point(
                x[i, 0], x[i, 1], x[i, 2], x[i, 3], 1.0, 0.05, 0.0, 0.0, 0.0, prm[i], hull
            )

    pitch, sin_cos = states[:, 0].copy(), np.empty((2, n))  # contiguous: a loop over them is SIMD

    @numba.njit
    def trig(x: np.ndarray, prm: np.ndarray, out: np.ndarray) -> None:
        for i in range(x.shape[0]):
            out[0, i], out[1, i] = sincos_point(x[i])

    @numba.njit
    def libm_trig(x: np.ndarray, prm: np.ndarray, out: np.ndarray) -> None:
        for i in range(x.shape[0]):
            out[0, i], out[1, i] = math.sin(x[i]), math.cos(x[i])

    @numba.njit
    def drag(x: np.ndarray, prm: np.ndarray, out: np.ndarray) -> None:
        for i in range(x.shape[0]):
            out[i, 0], out[i, 1] = crossflow_point(x[i, 1], x[i, 2], hull)

    def ns_per_item(run: Callable[[], None], items: int) -> float:
        run()
        best = math.inf
        deadline = time.perf_counter() + seconds
        while True:
            start = time.perf_counter()
            for _ in range(10):
                run()
            best = min(best, (time.perf_counter() - start) / 10 / items * 1e9)
            if time.perf_counter() >= deadline:
                return best

    lines = ["| on one thread, N = 4096 | ns |", "|---|---:|"]
    kernel: dict[str, float] = {}
    two_threads: dict[str, float] = {}
    resets: dict[str, tuple[float, dict[int, float]]] = {}
    for env_id in SUBENV_IDS:
        env = gym.make_vec(env_id, num_envs=n, threads=1)
        env.action_space.seed(0)
        actions = [env.action_space.sample() for _ in range(16)]
        env.reset(seed=0)
        ends = 0
        for k in range(200):  # random actions, as in the vector table: how often does an episode end?
            _, _, terminated, truncated, _ = env.step(actions[k % 16])
            ends += int((terminated | truncated).sum())
        vec = env.unwrapped
        a = np.asarray(actions[0], dtype=float).reshape(n, -1)
        report = np.empty((len(tr.REPORT_KEYS), n))
        active = np.ones(n, dtype=bool)
        state = vec._state.copy()
        args = (
            state,
            vec._episode,
            vec._seas,
            a,
            active,
            vec._obs,
            vec._rngs,
            vec._constants,
            vec.config.hull,
            report,
        )

        # The same states every time (no episode ends inside the timing): the copy's time is taken off.
        copy_ns = ns_per_item(functools.partial(np.copyto, state, vec._state), n)
        kernel[env_id] = ns_per_item(functools.partial(_from_states, tr.step, state, vec._state, args), n)
        kernel[env_id] -= copy_ns

        # The same steps shared among two of numba's threads, as the vector env shares them with threads=2:
        # what two cores make of the kernel alone.
        on_two_threads = functools.partial(_from_states, tr.step_parallel, state, vec._state, args)
        before = numba.get_num_threads()
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two_threads[env_id] = ns_per_item(on_two_threads, n) - copy_ns
        numba.set_num_threads(before)
        # A running vector env resets the few sub-environments whose episodes ended at a step (a batch's
        # fixed cost matters), a first reset all of them: per episode, in batches of each size.
        reset_ns = {
            size: ns_per_item(functools.partial(vec._reset_envs, np.arange(size), {}, report), size)
            for size in RESET_BATCHES
        }
        resets[env_id] = (ends / (200 * n), reset_ns)
        env.close()
    for env_id in SUBENV_IDS:
        lines.append(
            f"| {env_id}: compiled step of one sub-environment (`transition.step`, no reset) "
            f"| {kernel[env_id]:.0f} |"
        )
    per_state, per_pitch = (states, prm, out), (pitch, prm, sin_cos)
    parts = (
        (
            "of which: one control period (2 RK4 steps = 8 right-hand sides) in a block of 64 states "
            "(`control_period_lanes`, SIMD code), per state",
            periods_in_blocks,
            per_state,
            ".0f",
        ),
        ("the same control period, one state at a time (a block of one)", periods, per_state, ".0f"),
        ("one right-hand side, one state (`rhs_point`)", rhs, per_state, ".1f"),
        (
            "the sine and cosine of the pitch (`sincos_point`), in a loop over an array of pitches (SIMD)",
            trig,
            per_pitch,
            ".1f",
        ),
        (
            "the same loop with the C library's `sin` and `cos` (calls, one value at a time)",
            libm_trig,
            per_pitch,
            ".1f",
        ),
        ("the exact hull drag integral, one state (`crossflow_point`)", drag, per_state, ".1f"),
    )
    for label, fn, args, fmt in parts:
        lines.append(f"| {label} | {ns_per_item(functools.partial(fn, *args), n):{fmt}} |")
    nominal_reset_ns = resets[SUBENV_IDS[0]][1]
    for env_id in SUBENV_IDS:
        rate, reset_ns = resets[env_id]
        for size in RESET_BATCHES:
            lines.append(
                f"| {env_id}: a reset in a batch of {size} (draw, loading, records, observation), per "
                f"episode; x {SUBENV_IDS[0]}'s: {reset_ns[size] / nominal_reset_ns[size]:.1f} "
                f"| {reset_ns[size]:,.0f} |"
            )
        lines.append(
            f"| {env_id}: resets per env-step with random actions: {rate:.4f}, so per env-step (batches "
            f"of {RESET_BATCHES[-1]}) | {rate * reset_ns[RESET_BATCHES[-1]]:.0f} |"
        )
    cartpole = CartPoleVectorEnv(num_envs=n)
    cartpole_rate = vector_env_rate(cartpole, seconds, 3)
    cartpole.close()
    lines.append("")
    # Two cores share the compiled steps (measured on two of numba's threads); the resets run in Python
    # after them, on the calling thread.
    lines.append(
        "| ceiling on 2 cores | compiled steps alone, on 2 threads: env-steps/s | x CartPoleVectorEnv "
        "| with the resets: env-steps/s | x CartPoleVectorEnv |"
    )
    lines.append("|---|---:|---:|---:|---:|")
    for env_id in SUBENV_IDS:
        t2_s = two_threads[env_id] * 1e-9
        r_s = resets[env_id][0] * resets[env_id][1][RESET_BATCHES[-1]] * 1e-9
        alone, with_resets = 1 / t2_s, 1 / (t2_s + r_s)
        lines.append(
            f"| {env_id} | {alone:,.0f} | {alone / cartpole_rate:.2f} | {with_resets:,.0f} "
            f"| {with_resets / cartpole_rate:.2f} |"
        )
    lines.append(f"| CartPoleVectorEnv at N = 4096 (measured) | {cartpole_rate:,.0f} | 1 | | |")
    return lines


_MEMORY_PROBE = r"""
import json, os, sys, time, tracemalloc
import numpy as np, gymnasium as gym, subenv
from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv
kind, n, traced = sys.argv[1], int(sys.argv[2]), sys.argv[3] == "traced"
warm = gym.make_vec("subenv/DivePlane-v0", num_envs=2)  # load the compiled kernels before measuring
warm.reset(seed=0); warm.step(np.zeros((2, 1))); del warm
def rss_kib():
    return int(open("/proc/self/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE") // 1024
base = rss_kib()
if traced:  # (tracing costs memory of its own: the resident size is measured in another run)
    tracemalloc.start()
if kind == "native":
    env = gym.make_vec("subenv/DivePlane-v0", num_envs=n)
elif kind == "sync":
    env = gym.make_vec("subenv/DivePlane-v0", num_envs=n, vectorization_mode="sync")
else:
    env = CartPoleVectorEnv(num_envs=n)
env.reset(seed=0)
env.action_space.seed(0)
for _ in range(50):
    env.step(env.action_space.sample())
peak = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM:"))
print(json.dumps({"traced_peak_bytes": tracemalloc.get_traced_memory()[1] if traced else None,
                  "rss_growth_kib": rss_kib() - base, "peak_rss_kib": peak}))
"""


def memory_table(n: int) -> list[str]:
    lines = [
        (
            f"| at N = {n}: make, reset, 50 steps | peak allocations (tracemalloc) | resident memory added "
            "| peak RSS of the process |"
        ),
        "|---|---:|---:|---:|",
    ]
    for kind, label in [
        ("native", "subenv/DivePlane-v0, native"),
        ("sync", "subenv/DivePlane-v0, SyncVectorEnv"),
        ("cartpole", "CartPoleVectorEnv"),
    ]:
        m = {}
        for mode in ("traced", "resident"):
            out = subprocess.run(
                [sys.executable, "-c", _MEMORY_PROBE, kind, str(n), mode],
                capture_output=True,
                text=True,
                check=True,
                cwd=ROOT,
            )
            m[mode] = json.loads(out.stdout.strip().splitlines()[-1])
        lines.append(
            f"| {label} | {m['traced']['traced_peak_bytes'] / 2**20:.1f} MiB "
            f"| {m['resident']['rss_growth_kib'] / 1024:.1f} MiB "
            f"| {m['resident']['peak_rss_kib'] / 1024:.0f} MiB |"
        )
    return lines


_COMPILE_PROBE = r"""
import json, time
t0 = time.perf_counter()
import numpy as np, gymnasium as gym, subenv
from subenv.dynamics import derivatives, model_params
t1 = time.perf_counter()
env = gym.make("subenv/DivePlane-v0"); env.reset(seed=0); env.step(np.zeros(1, dtype=np.float32))
t2 = time.perf_counter()
venv = gym.make_vec("subenv/Nominal-v0", num_envs=8, threads=2)
venv.reset(seed=0); venv.step(np.zeros((8, 1)))
t3 = time.perf_counter()
derivatives(np.zeros(4), 1.0, 0.0, 0.0, model_params(subenv.load_vehicle("suboff")))
t4 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "single env": t2 - t1, "vector env": t3 - t2, "derivatives": t4 - t3}))
"""


def compile_table() -> list[str]:
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        runs = []
        for _ in range(2):  # empty cache, then the cache the first process wrote
            out = subprocess.run(
                [sys.executable, "-c", _COMPILE_PROBE],
                capture_output=True,
                text=True,
                check=True,
                env=env,
                cwd=ROOT,
            )
            runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    lines = ["| first call in a fresh process | empty numba cache (compiles) | cached |", "|---|---:|---:|"]
    labels = {
        "import": "`import subenv` (compiles nothing)",
        "single env": "`gym.make` + `reset` + `step` (single env kernels)",
        "vector env": "`make_vec` + `reset` + `step` on 2 threads (the vector env's parallel kernel)",
        "derivatives": "`derivatives` (its generalized ufunc)",
    }
    for key, label in labels.items():
        lines.append(f"| {label} | {runs[0][key]:.2f} s | {runs[1][key]:.2f} s |")
    total_cold, total_warm = sum(runs[0].values()), sum(runs[1].values())
    lines.append(f"| total | {total_cold:.2f} s | {total_warm:.2f} s |")
    return lines


def free_cores_probe() -> str:
    """How many cores this process really gets: a compiled loop on 1 thread, then on 2 (another
    process using a core shows as a speedup near 1)."""
    import threading

    @numba.njit(nogil=True)
    def spin(n: int) -> float:
        total = 0.0
        for i in range(n):
            total += np.sin(i * 1e-6)
        return total

    spin(10)
    n = 20_000_000
    start = time.perf_counter()
    spin(n)
    one = time.perf_counter() - start
    threads = [threading.Thread(target=spin, args=(n,)) for _ in range(2)]
    start = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    two = time.perf_counter() - start
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return f"two-thread speedup of a compute probe {2 * one / two:.2f}x; load average {load}"


_BASELINE_SIZES = (1, 64, 1024, 4096)
_TWO_THREADS_FROM = 1024


def public_api_cells(seconds: float, sizes: tuple[int, ...], repeats: int = 5) -> dict[str, float]:
    """The rates the comparison with another commit takes: through the public API only (``gym.make``,
    ``gym.make_vec(..., threads=k)``), so that the same code measures both trees. Every cell is
    made first and then measured ``repeats`` times in turns (best kept), so that a slow spell of the
    machine costs one run of several cells, not every run of one."""
    cells: dict[str, Callable[[], float]] = {}
    for env_id in SUBENV_IDS:
        cells[f"{env_id} single env"] = functools.partial(
            single_env_rate, gym.make(env_id).unwrapped, seconds, 1
        )
        for n in sizes:
            for threads in (1, 2) if n >= _TWO_THREADS_FROM else (1,):
                env = gym.make_vec(env_id, num_envs=n, threads=threads)
                cells[f"{env_id} N={n} threads={threads}"] = functools.partial(
                    vector_env_rate, env, seconds, 1
                )
    return round_robin(cells, repeats)


def baseline_table(baseline: Path, seconds: float, repeats: int, sizes: tuple[int, ...]) -> list[str]:
    """This tree against ``baseline``: child processes alternate between the two, ``repeats`` each, and each
    measures every cell three times in turns; the best of all is kept."""
    trees = {"now": ROOT, "previous": baseline.resolve()}
    best: dict[str, dict[str, float]] = {name: {} for name in trees}
    for _ in range(repeats):
        for name, tree in trees.items():
            env = {**os.environ, "PYTHONPATH": str(tree)}
            out = subprocess.run(
                [
                    sys.executable,
                    str(Path(__file__).resolve()),
                    "--cells",
                    "--seconds",
                    str(seconds),
                    "--repeats",
                    "3",
                    "--sizes",
                    ",".join(map(str, sizes)),
                ],
                capture_output=True,
                text=True,
                check=True,
                env=env,
                cwd=tree,
            )
            found = json.loads(out.stdout.strip().splitlines()[-1])
            if not found.pop("__file__").startswith(str(tree)):
                raise RuntimeError(f"the child process did not import subenv from {tree}")
            for key, rate in found.items():
                best[name][key] = max(best[name].get(key, 0.0), rate)
    now, previous = best["now"], best["previous"]
    lines = [
        "| measured through the public API | previous env-steps/s | now env-steps/s | now / previous |",
        "|---|---:|---:|---:|",
    ]
    for key in now:
        lines.append(f"| {key} | {previous[key]:,.0f} | {now[key]:,.0f} | {now[key] / previous[key]:.2f} |")
    lines += ["", "| two threads / one thread | previous | now |", "|---|---:|---:|"]
    for env_id in SUBENV_IDS:
        for n in sizes:
            if n >= _TWO_THREADS_FROM:
                one, two = f"{env_id} N={n} threads=1", f"{env_id} N={n} threads=2"
                lines.append(
                    f"| {env_id} N={n} | {previous[two] / previous[one]:.2f} | {now[two] / now[one]:.2f} |"
                )
    return lines


def machine() -> str:
    cpu = platform.processor() or "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (
        f"{cpu}, {os.cpu_count()} cores; "
        f"Python {platform.python_version()}, NumPy {np.__version__}, numba {numba.__version__}, "
        f"Gymnasium {gym.__version__}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=1.0, help="time per run (default: %(default)s)")
    parser.add_argument(
        "--repeats", type=int, default=3, help="runs per measurement, best kept (default: %(default)s)"
    )
    parser.add_argument(
        "--quick", action="store_true", help="0.2 s, one run, N up to 1024, no memory/compile probes"
    )
    parser.add_argument(
        "--baseline", type=Path, help="a checkout of another commit to compare with (section 6)"
    )
    parser.add_argument("--only-baseline", action="store_true", help="with --baseline: that section alone")
    parser.add_argument("--json", type=Path, help="also write the tables as a JSON record to this file")
    parser.add_argument("--cells", action="store_true", help=argparse.SUPPRESS)  # (a child of --baseline)
    parser.add_argument("--sizes", default=",".join(map(str, _BASELINE_SIZES)), help=argparse.SUPPRESS)
    args = parser.parse_args()
    seconds, repeats = (0.2, 1) if args.quick else (args.seconds, args.repeats)
    sizes = VECTOR_SIZES[:-1] if args.quick else VECTOR_SIZES
    if args.cells:
        cells: dict[str, Any] = public_api_cells(
            args.seconds, tuple(int(n) for n in args.sizes.split(",")), args.repeats
        )
        print(json.dumps({**cells, "__file__": subenv.__file__}))
        return
    print(f"Machine: {machine()}")
    before = free_cores_probe()
    print(f"Before: {before}\n")
    sections: list[tuple[str, Callable[[], list[str]]]] = []
    if args.baseline is not None:
        baseline = args.baseline
        sections.append(
            (
                f"Against {baseline} (child processes taking turns)",
                lambda: baseline_table(baseline, seconds, repeats, sizes),
            )
        )
    if args.only_baseline:
        sections = sections[:1]
    else:
        sections += [
            ("Single environment", lambda: single_env_table(seconds, repeats)),
            (
                "Vector environment (random actions, autoreset)",
                lambda: vector_env_table(seconds, repeats, sizes),
            ),
            ("Integrator cost", lambda: integrator_table(max(seconds, 1.0))),
            ("Where an env-step's time goes", lambda: cost_table(max(seconds, 1.0))),
        ]
        if not args.quick:
            sections += [("Peak memory", lambda: memory_table(4096)), ("numba compile time", compile_table)]
    printed = []
    for title, table in sections:
        lines = table()
        printed.append((title, lines))
        print(f"### {title}\n")
        print("\n".join(lines))
        print(flush=True)
    after = free_cores_probe()
    print(f"After: {after}")
    if args.json is not None:
        from _record import write_record

        write_record(args.json, "speed", machine(), printed, probe_before=before, probe_after=after)


if __name__ == "__main__":
    main()
