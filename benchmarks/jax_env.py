"""The functional JAX environment (subenv.jax.make) next to the compiled vector environment, in one run.

    .venv/bin/python benchmarks/jax_env.py [--envs N] [--seconds S] [--ids ID ...]

Env-steps per second at ``--envs`` environments (default 4096), every environment stepping with the
planes at zero and ended episodes reset (both do it within a step: the vector env by Gymnasium's
next-step autoreset, the JAX env by its select):

- the vector env, ``gym.make_vec(id, num_envs=N)``, on one of numba's threads and on its default
  (one per 512 environments up to the cores), through ``step`` (its ``info`` built as Gymnasium's);
- the JAX env, ``jax.jit`` of a ``jax.lax.scan`` of ``--scan`` steps of ``jax.vmap(env.step)``
  (the program a JAX learner would hold the environment in), on this machine's CPU with XLA's own
  threads, its table of episodes 1024 rows.

Every cell is the best of three runs of ``--seconds``; the JAX env's time to trace and compile is
printed beside it. The ratio is the JAX env's rate over the vector env's on its default threads.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import gymnasium as gym
import jax
import jax.numpy as jnp
import numba
import numpy as np
from jax_dynamics import best_of_three  # (this folder: the best of three timed runs)

import subenv.jax as sj


def vector_rate(env_id: str, n: int, seconds: float, threads: int | None) -> float:
    """Env-steps/s of the vector env at ``n`` environments, zero actions."""
    env = gym.make_vec(env_id, num_envs=n, **({} if threads is None else {"threads": threads}))
    env.reset(seed=0)
    actions = np.zeros((n, *env.single_action_space.shape), dtype=np.float32)
    rate = best_of_three(lambda: env.step(actions), n, seconds)
    env.close()
    return rate


def jax_rate(env_id: str, n: int, scan: int, seconds: float) -> tuple[float, float]:
    """Env-steps/s of the JAX env at ``n`` environments in scans of ``scan`` steps, zero actions; and
    the seconds to trace and compile the scan."""
    env, params = sj.make(env_id, episodes=1024, seed=0)
    actions = jnp.zeros((n, env.num_actions))
    step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    @jax.jit
    def run(keys: jax.Array, state: object) -> tuple[jax.Array, object, jax.Array]:
        def body(carry: tuple[jax.Array, object], _: None) -> tuple[tuple[jax.Array, object], jax.Array]:
            keys, state = carry
            split = jax.vmap(jax.random.split)(keys)
            _, state, reward, _, _, _ = step(split[:, 1], state, actions, params)
            return (split[:, 0], state), reward

        (keys, state), rewards = jax.lax.scan(body, (keys, state), None, length=scan)
        return keys, state, rewards.sum()

    keys = jax.random.split(jax.random.key(0), n)
    _, state = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(keys, params)
    start = time.perf_counter()
    compiled = run.lower(keys, state).compile()
    compile_s = time.perf_counter() - start
    carry = [keys, state]

    def once() -> None:
        carry[0], carry[1], total = compiled(carry[0], carry[1])
        total.block_until_ready()

    return best_of_three(once, n * scan, seconds), compile_s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--envs", type=int, default=4096, help="environments (default: 4096)")
    parser.add_argument("--scan", type=int, default=50, help="JAX steps per compiled call (default: 50)")
    parser.add_argument("--seconds", type=float, default=1.0, help="time per run (default: 1.0)")
    parser.add_argument(
        "--ids",
        nargs="+",
        default=["subenv/DivePlane-v0", "subenv/SpeedTransient-v0", "subenv/PeriscopeDepthWaves-v0"],
    )
    args = parser.parse_args()
    n = args.envs
    print(
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; jax {jax.__version__} on "
        f"{jax.devices()[0].platform}, numba {numba.__version__}; {n:,} environments\n"
    )
    print(
        "| id | vector env, 1 thread: env-steps/s | vector env, default threads | JAX env: env-steps/s "
        "| JAX / vector env | JAX trace + compile, s |"
    )
    print("|---|---:|---:|---:|---:|---:|")
    for env_id in args.ids:
        one = vector_rate(env_id, n, args.seconds, threads=1)
        default = vector_rate(env_id, n, args.seconds, threads=None)
        rate, compile_s = jax_rate(env_id, n, args.scan, args.seconds)
        print(
            f"| {env_id} | {one:,.0f} | {default:,.0f} | {rate:,.0f} | {rate / default:.3f} "
            f"| {compile_s:.1f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
