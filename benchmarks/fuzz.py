"""A long fuzz run of every environment id: outputs stay finite and inside the spaces, runs repeat.

    .venv/bin/python benchmarks/fuzz.py [--env-steps 2000000] [--num-envs 256] [--seed 0]

For every registered id, ``gym.make_vec(id, num_envs=N)`` is stepped with three kinds of actions
in turn: uniform random in [-1, 1], bang-bang (+-1, switching at random), and extreme (values far
outside the action box: +-1e300, +-1e-300, +-3; the environment clips them). Every 25 steps a random
half of the sub-environments is reset with a speed drawn log-uniformly in [0.01, 10] m/s
(``options={"speed": ...}``), the others run on through their scenario's episodes and autoresets.

Every step checks: observations finite and inside ``single_observation_space``, rewards finite,
every float in ``info`` finite (the critical speed and Froude numbers may be nan where a loading
has no critical speed: counted apart). Then each id is run again, the same seeds and actions, on
numba's other thread count (1 <-> 2) and in a fresh process, and the runs must give the same bits.

Prints a Markdown table (docs/reliability.md's) and exits 1 if any check failed.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import subprocess
import sys
import time
from typing import Any

import gymnasium as gym
import numpy as np

import subenv

_MAY_BE_NAN = ("critical_speed_mps", "critical_froude", "froude_number")
_POLICIES = ("random", "bang-bang", "extreme")


def actions_for(
    policy: str, rng: np.random.Generator, shape: tuple[int, ...], previous: np.ndarray
) -> np.ndarray:
    """One step's actions of a policy (float64; the environments take any real array)."""
    if policy == "random":
        return rng.uniform(-1.0, 1.0, size=shape)
    if policy == "bang-bang":
        switch = rng.random(shape) < 0.1
        return np.where(switch, -previous, previous)
    return rng.choice([1e300, -1e300, 1e-300, -1e-300, 3.0, -3.0, 0.0], size=shape)


def fuzz_id(env_id: str, num_envs: int, steps: int, seed: int, threads: int) -> dict[str, Any]:
    """Step one id for ``steps`` vector steps per policy; the counts of what was checked and a digest."""
    env = gym.make_vec(env_id, num_envs=num_envs, threads=threads)
    space = env.single_observation_space
    rng = np.random.default_rng(seed)
    digest = hashlib.sha256()
    counts = {
        "env_steps": 0,
        "episodes_ended": 0,
        "non_finite": 0,
        "outside_space": 0,
        "nan_info_no_ucr": 0,
        "speed_resets": 0,
    }
    reasons: dict[str, int] = {}
    for p, policy in enumerate(_POLICIES):
        obs, info = env.reset(seed=seed + 1000 * p)
        previous = np.ones((num_envs, *env.single_action_space.shape))
        for k in range(steps):
            if k % 25 == 24:
                mask = rng.random(num_envs) < 0.5
                if mask.any():
                    speed = float(10 ** rng.uniform(-2.0, 1.0))
                    obs_r, _ = env.reset(options={"reset_mask": mask, "speed": speed})
                    counts["speed_resets"] += int(mask.sum())
                    counts["non_finite"] += int((~np.isfinite(obs_r[mask])).any(axis=1).sum())
            previous = actions_for(policy, rng, previous.shape, previous)
            obs, rewards, terminated, truncated, info = env.step(previous)
            counts["env_steps"] += num_envs
            bad = ~np.isfinite(obs).all(axis=1) | ~np.isfinite(rewards)
            for key, value in info.items():
                if key.startswith("_") or value.dtype == object:
                    continue
                finite = np.isfinite(value)
                if key in _MAY_BE_NAN:
                    counts["nan_info_no_ucr"] += int((~finite).sum())
                else:
                    bad |= ~finite
            counts["non_finite"] += int(bad.sum())
            inside = np.all((obs >= space.low) & (obs <= space.high), axis=1)
            counts["outside_space"] += int((~inside).sum())
            ended = terminated | truncated
            counts["episodes_ended"] += int(ended.sum())
            for reason in info["termination_reason"][terminated]:
                reasons[reason] = reasons.get(reason, 0) + 1
            digest.update(obs.tobytes())
            digest.update(rewards.tobytes())
            digest.update(ended.tobytes())
    env.close()
    return {**counts, "reasons": reasons, "digest": digest.hexdigest()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--env-steps", type=int, default=2_000_000, help="in all, over every id (default: %(default)s)"
    )
    parser.add_argument("--num-envs", type=int, default=256, help="sub-environments (default: %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="(default: %(default)s)")
    parser.add_argument("--child", help=argparse.SUPPRESS)  # run one id in this process and print JSON
    args = parser.parse_args(argv)
    ids = subenv.env_ids()
    steps = max(25, math.ceil(args.env_steps / (len(ids) * len(_POLICIES) * args.num_envs)))
    if args.child:
        env_id, threads = args.child.rsplit(":", 1)
        print(json.dumps(fuzz_id(env_id, args.num_envs, steps, args.seed, int(threads))))
        return 0
    print(
        f"Fuzzing {len(ids)} ids, N = {args.num_envs}, {steps} steps per action kind "
        f"({len(_POLICIES)} kinds), seed {args.seed}",
        flush=True,
    )
    print()
    print(
        "| id | env-steps | episodes ended (terminations by reason) | speed resets | non-finite | "
        "outside the space | same bits on 1 and 2 threads, in another process |"
    )
    print("|---|---:|---|---:|---:|---:|---|")
    failed = False
    totals = {"env_steps": 0, "non_finite": 0, "outside_space": 0}
    start = time.perf_counter()
    for env_id in ids:
        here = fuzz_id(env_id, args.num_envs, steps, args.seed, 2)
        child = subprocess.run(
            [
                sys.executable,
                __file__,
                "--env-steps",
                str(args.env_steps),
                "--num-envs",
                str(args.num_envs),
                "--seed",
                str(args.seed),
                "--child",
                f"{env_id}:1",
            ],
            capture_output=True,
            text=True,
            check=True,
        )
        other = json.loads(child.stdout)
        same = here["digest"] == other["digest"] and here["reasons"] == other["reasons"]
        ok = same and here["non_finite"] == 0 and here["outside_space"] == 0
        failed |= not ok
        for key in totals:
            totals[key] += here[key]
        reasons = ", ".join(f"{r}: {n}" for r, n in sorted(here["reasons"].items()))
        print(
            f"| {env_id} | {here['env_steps']:,} | {here['episodes_ended']:,} ({reasons}) | "
            f"{here['speed_resets']:,} | {here['non_finite']} | {here['outside_space']} | "
            f"{'yes' if same else 'NO'} |",
            flush=True,
        )
    print()
    print(
        f"{totals['env_steps']:,} env-steps in {time.perf_counter() - start:.0f} s (and as many again in the "
        f"second processes): {totals['non_finite']} non-finite outputs, {totals['outside_space']} "
        f"observations outside the space. {'FAILED' if failed else 'All checks held.'}"
    )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
