"""Timing of the analysis: critical_speed per call, and the reproduction's findings (``subenv analyze``).

.venv/bin/python benchmarks/analysis_timing.py
"""

from __future__ import annotations

import tempfile
import time
import timeit

from subenv import load_vehicle
from subenv.analysis import critical_speed
from subenv.analysis.report import write_findings


def main() -> None:
    vehicle = load_vehicle("suboff")
    critical_speed(vehicle)  # warm the vehicle's cached coefficients
    n = 20000
    per_call = min(timeit.repeat(lambda: critical_speed(vehicle, 0.3), number=n, repeat=5)) / n
    print(f"critical_speed: {per_call * 1e6:.2f} us per call (best of 5 x {n})")
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        write_findings(f"{tmp}/report", vehicle)
        print(f"the reproduction's findings (subenv analyze): {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
