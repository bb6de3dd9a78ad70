"""Single-environment steps per second, next to Gymnasium's Pendulum-v1, measured in one run.

    .venv/bin/python benchmarks/steps_per_second.py [--seconds 3]

Prints a table: raw (the unwrapped env) and through ``gym.make`` (with its wrappers), and the
ratio to Pendulum-v1 measured the same way on the same machine, in the same process.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import subenv  # noqa: F401  (registers the environments)


def steps_per_second(env: gym.Env, seconds: float, seed: int = 0) -> float:  # type: ignore[type-arg]
    """Step with fixed random actions for about ``seconds``; resets are counted in the time."""
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1, 1, size=(4096, *env.action_space.shape)).astype(env.action_space.dtype)
    env.reset(seed=seed)
    steps = 0
    start = time.perf_counter()
    deadline = start + seconds
    while True:
        for i in range(1000):
            _, _, terminated, truncated, _ = env.step(actions[(steps + i) % 4096])
            if terminated or truncated:
                env.reset()
        steps += 1000
        now = time.perf_counter()
        if now >= deadline:
            return steps / (now - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="time per measurement (default: %(default)s)")
    args = parser.parse_args()
    rows = []
    for env_id in ("Pendulum-v1", "subenv/Nominal-v0", "subenv/DivePlane-v0"):
        made = gym.make(env_id)
        raw = steps_per_second(made.unwrapped, args.seconds)
        wrapped = steps_per_second(made, args.seconds)
        rows.append((env_id, raw, wrapped))
    ref_raw, ref_wrapped = rows[0][1], rows[0][2]
    print(f"{'environment':<22} {'raw steps/s':>12} {'x Pendulum':>11} {'gym.make steps/s':>17} {'x Pendulum':>11}")
    for env_id, raw, wrapped in rows:
        print(f"{env_id:<22} {raw:12,.0f} {raw / ref_raw:11.3f} {wrapped:17,.0f} {wrapped / ref_wrapped:11.3f}")


if __name__ == "__main__":
    main()
