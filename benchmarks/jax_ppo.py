"""PPO in one JAX program (subenv_agents.jax_ppo) next to Stable-Baselines3's PPO, in one run.

    .venv/bin/python benchmarks/jax_ppo.py [--timesteps N ...] [--episodes E] [--sb3-timesteps N]

1. The shipped ``ppo_jax`` settings (``subenv_agents/models/ppo_jax/config.json``) trained to each of
   ``--timesteps`` (default 2.5M, 5M, 10M env-steps; the learning rate annealed over each budget), on
   this machine's default JAX device: wall time (compilation included) and the success and plane RMS
   of the final policy on the reversal scenarios (LowSpeed, NearCritical, SpeedTransient;
   ``--episodes`` each, the harness of ``subenv evaluate``, seeds 10000 + i).
2. Stable-Baselines3's PPO with the shipped ``ppo``'s hyperparameters (``python -m
   subenv_agents.train --algo ppo``, 16 environments of the native vector env, one torch thread) for
   ``--sb3-timesteps``: its env-steps per second, the reference of the ratio.
3. The shipped ``ppo``'s own record (``subenv_agents/models/ppo``: its training time, all its runs
   included, and its success on the same episodes): what the JAX runs are set against. It is read,
   not re-run here (24 minutes).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import jax

from subenv.evaluation import evaluate
from subenv_agents import shipped_models
from subenv_agents.card import total_training_time_s
from subenv_agents.jax_ppo import JaxPPOController, PPOConfig, load, make_train, shipped_folder
from subenv_agents.records import REVERSAL_SCENARIOS, evaluation_record


def jax_run(config: PPOConfig, episodes: int) -> tuple[float, dict[str, dict[str, float]]]:
    """Wall time of the training (compilation included) and the final policy's record."""
    start = time.perf_counter()
    train, _ = make_train(config)
    state, _ = jax.block_until_ready(jax.jit(train)(jax.random.key(config.seed)))
    wall = time.perf_counter() - start
    controller = JaxPPOController.of(config, state.network, state.obs_stats, "ppo_jax")
    record = evaluation_record(
        evaluate([controller], list(REVERSAL_SCENARIOS), episodes=episodes, progress=False)
    )
    return wall, record["ppo_jax"]


def sb3_rate(timesteps: int) -> tuple[float, int]:
    """SB3 PPO's env-steps per second (its train.json: the learning itself) and the steps it made."""
    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp) / "run"
        subprocess.run(
            [
                sys.executable,
                "-m",
                "subenv_agents.train",
                "--algo",
                "ppo",
                "--env",
                "subenv/SpeedTransient-v0",
                "-n",
                str(timesteps),
                "--run-dir",
                str(run),
                "--eval-freq",
                "0",
                "--save-freq",
                "0",
                "-q",
                "--no-progress",
                "--threads",
                "1",
            ],
            check=True,
            stdout=subprocess.DEVNULL,
        )
        record = json.loads((run / "train.json").read_text())
    return record["timesteps"] / record["wall_time_s"], record["timesteps"]


def _cells(record: dict[str, dict[str, float]]) -> str:
    return " | ".join(
        f"{100 * record[s]['success_rate']:.0f}% ({record[s]['plane_rms_rad']:.3f})"
        for s in REVERSAL_SCENARIOS
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--timesteps", type=float, nargs="+", default=[2.5e6, 5e6, 1e7])
    parser.add_argument(
        "--episodes", type=int, default=100, help="evaluation episodes per scenario (default: 100)"
    )
    parser.add_argument("--sb3-timesteps", type=int, default=100_000, help="SB3's steps (default: 100000)")
    args = parser.parse_args()
    shipped, _, _ = load(shipped_folder())
    print(
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; jax {jax.__version__} on "
        f"{jax.devices()[0]}; the shipped ppo_jax settings on {shipped.env_id}, "
        f"{shipped.num_envs} environments\n"
    )
    header = " | ".join(f"{s}: success (plane RMS)" for s in REVERSAL_SCENARIOS)
    print(f"| run | env-steps | wall time, s | env-steps/s | {header} |")
    print("|---|---:|---:|---:|" + "---|" * len(REVERSAL_SCENARIOS))
    rates = []
    for steps in args.timesteps:
        config = dataclasses.replace(shipped, total_timesteps=int(steps))
        done = config.num_updates * config.num_envs * config.num_steps
        wall, record = jax_run(config, args.episodes)
        rates.append(done / wall)
        print(f"| JAX PPO | {done:,} | {wall:.0f} | {done / wall:,.0f} | {_cells(record)} |", flush=True)
    sb3, sb3_steps = sb3_rate(args.sb3_timesteps)
    folder = shipped_models()["ppo"]
    train = json.loads((folder / "train.json").read_text())
    stored = json.loads((folder / "evaluation.json").read_text())["suite"]["ppo"]
    print(
        f"| SB3 PPO, this run | {sb3_steps:,} | {sb3_steps / sb3:.0f} | {sb3:,.0f} "
        "| (not evaluated: a rate only) |"
    )
    print(
        f"| SB3 PPO, shipped `ppo` (its record) | {train['timesteps']:,} (its last run) | "
        f"{total_training_time_s(train):.0f} (all its runs) | | {_cells(stored)} |"
    )
    print(f"\nJAX PPO / SB3 PPO, env-steps per second: {min(rates) / sb3:.1f} to {max(rates) / sb3:.1f}")


if __name__ == "__main__":
    main()
