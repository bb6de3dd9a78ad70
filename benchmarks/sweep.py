"""A sweep's episodes per second: the serial harness, then Ray with one and with two CPUs, in one run.

::

    .venv/bin/python benchmarks/sweep.py              # 3 controllers x 8 points x 40 episodes (~1-2 min)
    .venv/bin/python benchmarks/sweep.py --episodes 20 --points 4

The same chunks three ways: ``subenv.sweep.run_chunk`` one after another in this process (the serial
harness, warm: the controllers built and the kernels compiled by a first pass that is not timed), then
``subenv.sweep.run_sweep`` on a fresh local Ray instance with ``num_cpus=1`` and with ``num_cpus=2``
(each from an empty folder; Ray's start counted, as a user pays it). The rows of the three are checked
equal, and the rates are given as ratios to the serial harness.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from subenv.sweep import SweepSpec, _read_rows, run_chunk, run_sweep


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--controllers", default="lqr,reversal_aware,thesis")
    parser.add_argument(
        "--points", type=int, default=8, help="speed ratios from 0.4 to 1.6 (default: %(default)s)"
    )
    parser.add_argument("--episodes", type=int, default=40, help="episodes per point (default: %(default)s)")
    args = parser.parse_args()
    spec = SweepSpec(
        controllers=tuple(args.controllers.split(",")),
        scenarios=("LowSpeed",),
        grid=(("speed_ratio", tuple(np.round(np.linspace(0.4, 1.6, args.points), 6).tolist())),),
        episodes=args.episodes,
        chunk_episodes=max(1, args.episodes // 2),
    )
    chunks = spec.chunks()
    episodes = len(chunks) and sum(c.count for c in chunks)
    print(
        f"{len(spec.controllers)} controllers x {args.points} points x {args.episodes} episodes = {episodes} "
        f"episodes in {len(chunks)} chunks, on {os.cpu_count()} CPUs",
        flush=True,
    )

    for chunk in chunks[:: max(1, len(chunks) // len(spec.controllers))]:
        run_chunk(chunk, spec.seed)  # (warm-up: compile, build the controllers' designs)
    start = time.perf_counter()
    serial = [row for c in chunks for row in run_chunk(c, spec.seed)]
    serial_s = time.perf_counter() - start
    rates = {"serial harness (this process)": (serial_s, episodes / serial_s)}
    for cpus in (1, 2):
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            path = run_sweep(spec, Path(tmp) / "sweep", num_cpus=cpus, progress=False)
            wall = time.perf_counter() - start
            rows = _read_rows(path)
        if not pd.DataFrame(rows).equals(pd.DataFrame(serial)):  # (NaN equal to NaN)
            print(f"Ray with {cpus} CPU(s) gave other rows than the serial harness", file=sys.stderr)
            return 1
        rates[f"Ray, num_cpus={cpus} (start included)"] = (wall, episodes / wall)
    base = rates["serial harness (this process)"][1]
    print("| run | wall [s] | episodes/s | / serial |\n|---|---|---|---|")
    for name, (wall, rate) in rates.items():
        print(f"| {name} | {wall:.1f} | {rate:.1f} | {rate / base:.2f} |")
    print("rows: identical in all three")
    return 0


if __name__ == "__main__":
    sys.exit(main())
