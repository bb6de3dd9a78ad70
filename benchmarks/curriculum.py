"""Does the speed curriculum help? The same budget with and without it, several seeds.

    .venv/bin/python benchmarks/curriculum.py                       # PPO, 1.5M steps, seeds 0 1 2
    .venv/bin/python benchmarks/curriculum.py --algo ppo -n 3000000 --seeds 0 1 2 3

Trains every (seed, curriculum on/off) pair with ``python -m subenv_agents.train`` (two runs at a time,
one torch thread each, on a 2-core machine), then evaluates every final model with the harness
of ``subenv evaluate`` on the ``reversal`` suite (LowSpeed, NearCritical, SpeedTransient) and the
whole ``default`` suite, the same episodes for every model, and prints one table: success rate
per scenario, plane RMS, the curriculum's final stage and when it advanced, training time.
Run folders and the evaluation tables go to ``results/benchmarks/curriculum/<date-time>/``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

# subenv_agents is this checkout's (not an installed copy's): run from any directory.
REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


def _train(args: argparse.Namespace, root: Path, seed: int, curriculum: bool) -> Path:
    run = root / f"{'with' if curriculum else 'without'}_seed{seed}"
    cmd = [
        sys.executable,
        "-m",
        "subenv_agents.train",
        "--algo",
        args.algo,
        "--env",
        args.env,
        "-n",
        str(args.n_timesteps),
        "--seed",
        str(seed),
        "--run-dir",
        str(run),
        "--curriculum" if curriculum else "--no-curriculum",
        "--save-freq",
        "0",
        "--eval-freq",
        "0",
        "-q",
        "--no-progress",
    ]
    with (root / f"{run.name}.log").open("w") as log:
        subprocess.run(cmd, check=True, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
    return run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--algo", default="ppo")
    parser.add_argument("--env", default="subenv/Mixed-v0")
    parser.add_argument("-n", "--n-timesteps", type=int, default=1_500_000)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--episodes", type=int, default=50, help="evaluation episodes per scenario")
    parser.add_argument("--parallel", type=int, default=2, help="training runs at a time")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()

    from subenv.evaluation import evaluate
    from subenv.evaluation.results import summarize
    from subenv_agents.controller import AgentController

    root = (args.out or Path("results/benchmarks/curriculum") / time.strftime("%Y%m%d-%H%M%S")).resolve()
    root.mkdir(parents=True, exist_ok=False)
    jobs = [(seed, c) for seed in args.seeds for c in (False, True)]
    start = time.perf_counter()
    with ThreadPoolExecutor(args.parallel) as pool:
        runs = list(pool.map(lambda job: _train(args, root, *job), jobs))
    print(
        f"trained {len(runs)} runs of {args.n_timesteps} steps in {time.perf_counter() - start:.0f} s "
        f"({args.parallel} at a time)\n"
    )

    scenarios = ("LowSpeed", "NearCritical", "SpeedTransient", "Nominal", "PeriscopeDepth", "BallastOffset")
    header = (
        f"| curriculum | seed | {' | '.join(scenarios)} | all | plane RMS (reversal suite) | final stage | "
        "advances (step: stage) | train s |"
    )
    lines = [header, "|" + "---|" * (header.count("|") - 1)]
    totals: dict[bool, list[float]] = {False: [], True: []}
    for (seed, curriculum), run in zip(jobs, runs, strict=True):
        controller = AgentController(run, name=run.name)
        results = evaluate([controller], list(scenarios), episodes=args.episodes, progress=False)
        rows = {r["scenario"]: r for r in summarize(results)}
        rates = [rows[s]["success_rate"] for s in scenarios]
        rms = np.mean([rows[s]["plane_rms_rad_mean"] for s in scenarios[:3]])
        record = json.loads((run / "train.json").read_text())
        advances = ", ".join(f"{step}: {stage}" for step, stage in record["curriculum_advances"]) or "-"
        totals[curriculum].append(float(np.mean(rates)))
        lines.append(
            f"| {'with' if curriculum else 'without'} | {seed} | "
            + " | ".join(f"{100 * r:.0f}%" for r in rates)
            + f" | {100 * np.mean(rates):.1f}% | {rms:.3f} | "
            f"{record['final_stage'] if curriculum else '-'} | {advances} | {record['wall_time_s']:.0f} |"
        )
    table = "\n".join(lines)
    summary = (
        f"\nMean success over all scenarios: without {100 * np.mean(totals[False]):.1f}% "
        f"(seeds: {', '.join(f'{100 * v:.0f}' for v in totals[False])}), with "
        f"{100 * np.mean(totals[True]):.1f}% (seeds: {', '.join(f'{100 * v:.0f}' for v in totals[True])}); "
        f"{args.algo}, {args.n_timesteps} steps on {args.env}, {args.episodes} episodes per scenario "
        f"(seed 10000 + i)."
    )
    print(table + "\n" + summary)
    (root / "table.md").write_text(table + "\n" + summary + "\n")


if __name__ == "__main__":
    main()
