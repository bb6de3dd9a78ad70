"""The dynamics on JAX (subenv.jax) next to the compiled kernel the environments run, in one run.

    .venv/bin/python benchmarks/jax_dynamics.py [--seconds S]

Control periods per second (0.5 s, two RK4 steps, SUBOFF, random states near level flight) at
N = 64, 1024 and 4096 states: numba's block integrator on one thread
(:func:`subenv.dynamics.integrate.control_period_lanes`, the environments' path, without the rest of
a step: ``speed.py``'s ``control_periods_in_blocks``) and ``jax.jit`` of
:func:`subenv.jax.control_period` on this machine's CPU (XLA's own threads), in deep water
(``free_surface=False``: the suction left out of the trace) and at periscope depth (the free
surface's suction); then the time JAX takes to trace and compile each. Every cell is the best of
three runs of ``--seconds``.
"""

from __future__ import annotations

import argparse
import functools
import os
import platform
import time
from collections.abc import Callable

import jax
import numba
import numpy as np
from speed import control_periods_in_blocks  # (this folder: the block integrator as speed.py times it)

import subenv
import subenv.jax as sj
from subenv.dynamics import CONTROL_PERIOD_S, SUBSTEPS, model_params
from subenv.dynamics.free_surface import FreeSurface
from subenv.dynamics.model import pack_params


def best_of_three(run: Callable[[], object], items: int, seconds: float) -> float:
    """The best rate of three runs of ``seconds`` each: ``items`` per call of ``run`` (after one call to
    warm up)."""
    run()
    best = 0.0
    for _ in range(3):
        calls, start = 0, time.perf_counter()
        while (now := time.perf_counter()) - start < seconds:
            run()
            calls += 1
        best = max(best, calls * items / (now - start))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=1.0, help="time per run (default: 1.0)")
    args = parser.parse_args()
    vehicle = subenv.load_vehicle("suboff")
    rng = np.random.default_rng(0)
    print(
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; jax {jax.__version__} on "
        f"{jax.devices()[0].platform}, numba {numba.__version__} on one thread\n"
    )
    print("| states | water | numba control periods/s | JAX control periods/s | JAX / numba |")
    print("|---:|---|---:|---:|---:|")
    compile_s = {}
    for label, surface, depth in (
        ("deep", FreeSurface(suction_factor=0.0), (8.0, 15.0)),
        ("periscope depth", FreeSurface(), (0.8, 1.5)),
    ):
        params = model_params(vehicle, surface)
        hull, row = params.hull.packed, pack_params(params)
        period = jax.jit(
            lambda x, prm, hull=hull, surface=label != "deep": sj.control_period(
                x,
                0.0,
                CONTROL_PERIOD_S,
                1.0,
                0.0,
                0.05,
                0.0,
                prm,
                hull,
                substeps=SUBSTEPS,
                free_surface=surface,
            )
        )
        for n in (64, 1024, 4096):
            prm = np.repeat(row[None], n, axis=0)
            x = np.column_stack(
                [
                    rng.uniform(-0.05, 0.05, n),
                    rng.uniform(-0.05, 0.05, n),
                    rng.uniform(-0.01, 0.01, n),
                    rng.uniform(*depth, n),
                ]
            )
            out = np.empty((n, 4))
            start = time.perf_counter()
            period.lower(x, prm).compile()
            compile_s[(label, n)] = time.perf_counter() - start
            xj, prmj = jax.device_put(x), jax.device_put(prm)
            numba_rate = best_of_three(
                functools.partial(control_periods_in_blocks, x, prm, hull, out), n, args.seconds
            )
            jax_rate = best_of_three(
                lambda period=period, xj=xj, prmj=prmj: period(xj, prmj).block_until_ready(), n, args.seconds
            )
            np.testing.assert_allclose(np.asarray(period(xj, prmj)), out, rtol=1e-12, atol=1e-12)
            print(
                f"| {n:,} | {label} | {numba_rate:,.0f} | {jax_rate:,.0f} | {jax_rate / numba_rate:.3f} |",
                flush=True,
            )
    print("\n| JAX trace and compile of the control period | s |\n|---|---:|")
    for (label, n), seconds in compile_s.items():
        print(f"| {label}, {n:,} states | {seconds:.2f} |")


if __name__ == "__main__":
    main()
