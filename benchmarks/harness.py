"""How much faster the batched harness runs the default comparison than one episode at a time.

    .venv/bin/python benchmarks/harness.py [--episodes 100] [--single-episodes 5] [--controllers a,b]

Runs every registered controller (the baselines, and the shipped agents where Stable-Baselines3 is
installed) on the default suite's six scenarios twice in one process, after a warm-up that loads the
compiled physics:

- batched: ``evaluate(..., batched=True)``, what ``subenv evaluate`` runs: the ``--episodes``
  episodes of a scenario stepped together in one vector environment;
- one at a time: ``evaluate(..., batched=False)``, the harness before batching (one ``gym.make``
  environment, one episode at a time), on the first ``--single-episodes`` of those episodes: its cost
  per episode does not depend on how many there are, and the full default would take minutes.

It prints a Markdown table of episodes per second per controller and their ratio, and checks that the
episodes both runs share have equal results. Rates are episodes of the default suite's seeds
(10000 + i); the ratio is what carries over to other machines.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

# subenv and its controller packages are this checkout's, run from any directory; the controllers
# are those its installation declares (entry points: ./dev reinstalls when pyproject.toml changes).
REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
from subenv.evaluation import EpisodeResult, controller_names, evaluate, get_suite  # noqa: E402 (after sys.path)


def timed(
    controller: str, scenarios: tuple[str, ...], episodes: int, batched: bool
) -> tuple[float, list[EpisodeResult]]:
    start = time.perf_counter()
    results = evaluate(
        [controller], list(scenarios), episodes, progress=False, keep_trajectories=0, batched=batched
    )
    return time.perf_counter() - start, results


def _nan(value: object) -> bool:
    return isinstance(value, float) and math.isnan(value)


def same(a: EpisodeResult, b: EpisodeResult) -> bool:
    """Equal results, metrics included (NaN equal to NaN)."""
    return all(
        x == y or (_nan(x) and _nan(y)) for x, y in zip(a.row().values(), b.row().values(), strict=True)
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--episodes", type=int, default=100, help="episodes per scenario, batched (default: 100)"
    )
    parser.add_argument(
        "--single-episodes",
        type=int,
        default=5,
        help="the first this-many of them, one at a time (default: 5)",
    )
    parser.add_argument("--controllers", help="comma-separated names (default: every registered controller)")
    args = parser.parse_args()
    names = args.controllers.split(",") if args.controllers else controller_names()
    scenarios = get_suite("default").scenarios

    warm_start = time.perf_counter()
    evaluate([names[0]], ["Nominal"], 4, progress=False)  # loads (or compiles) the physics
    evaluate([names[0]], ["Nominal"], 1, progress=False, batched=False)
    print(f"warm-up (loads or compiles the compiled physics): {time.perf_counter() - warm_start:.1f} s\n")

    print(
        f"default suite, {len(scenarios)} scenarios; batched: {args.episodes} episodes per scenario; one at "
        f"a time: the first {args.single_episodes}\n"
    )
    print(
        "| controller | one at a time, episodes/s | batched, episodes/s | ratio "
        "| equal results on shared episodes |"
    )
    print("|---|---:|---:|---:|---|")
    totals = [0.0, 0, 0.0, 0]  # single seconds, episodes; batched seconds, episodes
    for name in names:
        single_s, single = timed(name, scenarios, args.single_episodes, batched=False)
        batched_s, batched = timed(name, scenarios, args.episodes, batched=True)
        shared = {(r.scenario, r.episode): r for r in batched}
        equal = sum(same(r, shared[(r.scenario, r.episode)]) for r in single)
        for i, (seconds, results) in enumerate(((single_s, single), (batched_s, batched))):
            totals[2 * i] += seconds
            totals[2 * i + 1] += len(results)
        single_rate, batched_rate = len(single) / single_s, len(batched) / batched_s
        print(
            f"| {name} | {single_rate:.1f} | {batched_rate:.1f} | {batched_rate / single_rate:.1f}x | "
            f"{equal}/{len(single)} |",
            flush=True,
        )
    single_rate, batched_rate = totals[1] / totals[0], totals[3] / totals[2]
    print(
        f"| all (time-weighted) | {single_rate:.1f} | {batched_rate:.1f} "
        f"| **{batched_rate / single_rate:.1f}x** | |"
    )
    default_episodes = len(names) * len(scenarios) * get_suite("default").episodes
    print(
        f"\nthe default comparison ({default_episodes} episodes): about "
        f"{math.ceil(default_episodes / single_rate)} s one at a time, "
        f"{math.ceil(default_episodes / batched_rate)} s batched (rollouts only)"
    )


if __name__ == "__main__":
    main()
