"""The MPC baseline against reversal_aware on a suite: success with 95% intervals, plane RMS, solve times.

    .venv/bin/python benchmarks/mpc.py                     # default suite, 20 episodes per scenario
    .venv/bin/python benchmarks/mpc.py --episodes 100

Both controllers meet the same episodes (``subenv.evaluation.evaluate``, batched). The MPC's solve time
per control step is the wall time of one QP solve (DAQP) for one episode, collected over the
whole run; the MPC's total time per step (linearisation, observer and QP) is its wall time over its steps.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from subenv.evaluation import Controller, controller_names, evaluate, make_controller
from subenv.evaluation.results import summarize, wilson_interval
from subenv_baselines.mpc import DepthMPC


def _controller(name: str) -> Controller:
    """The registered controller ``name``; the MPC from this checkout where the installed metadata
    predates it."""
    if name == "mpc" and name not in controller_names():
        return DepthMPC()
    return make_controller(name)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="default")
    parser.add_argument("--scenarios", help="comma-separated scenario names instead of the suite's")
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--controllers", nargs="+", default=["reversal_aware", "mpc"])
    args = parser.parse_args()
    rows = {}
    won: dict[tuple[str, str], list[bool]] = {}  # success over the winnable episodes
    can_win: dict[tuple[str, int], bool] = {}
    for name in args.controllers:
        controller = _controller(name)
        start = time.perf_counter()
        suite = args.scenarios.split(",") if args.scenarios else args.suite
        results = evaluate([controller], suite, episodes=args.episodes, progress=False)
        elapsed = time.perf_counter() - start
        steps = sum(r.steps for r in results)
        times = np.array(getattr(controller, "solve_times_s", []))
        timing = (
            f", QP solve per step median {np.median(times) * 1e3:.2f} ms, p99 "
            f"{np.percentile(times, 99) * 1e3:.2f} ms"
            if times.size
            else ""
        )
        print(
            f"{name}: {len(results)} episodes, {steps} steps in {elapsed:.1f} s "
            f"({len(results) / elapsed:.2f} episodes/s, {elapsed / steps * 1e3:.2f} ms per step){timing}",
            flush=True,
        )
        for row in summarize(results):
            rows[(row["scenario"], name)] = row
        for r in results:
            key = (r.scenario, r.seed)
            can_win[key] = bool(r.winnable)  # (the harness's subenv.analysis.winnable of the episode)
            if can_win[key]:
                won.setdefault((r.scenario, name), []).append(r.metrics.outcome == "success")
    scenarios = list(dict.fromkeys(s for s, _ in rows))
    print(
        "\n| scenario | winnable | "
        + " | ".join(
            f"{n} success [95%] | {n} on winnable [95%] | {n} plane RMS [rad]" for n in args.controllers
        )
        + " |"
    )
    print("|---|---|" + "---|---|---|" * len(args.controllers))
    for scenario in scenarios:
        cells = []
        for name in args.controllers:
            row = rows[(scenario, name)]
            n = row["episodes"]
            k = round(row["success_rate"] * n)
            low, high = wilson_interval(k, n)
            wins = won.get((scenario, name), [])
            kw, nw = sum(wins), len(wins)
            wlow, whigh = wilson_interval(kw, nw) if nw else (float("nan"), float("nan"))
            cells += [
                f"{k}/{n} = {100 * k / n:.0f}% [{100 * low:.0f}, {100 * high:.0f}]",
                f"{kw}/{nw} = {100 * kw / max(nw, 1):.0f}% [{100 * wlow:.0f}, {100 * whigh:.0f}]",
                f"{row['plane_rms_rad_mean']:.3f}",
            ]
        winnable_here = sum(v for (s_, _), v in can_win.items() if s_ == scenario)
        total = sum(1 for (s_, _) in can_win if s_ == scenario)
        print(f"| {scenario} | {winnable_here}/{total} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
