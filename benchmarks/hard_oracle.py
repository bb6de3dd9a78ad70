"""The oracle's certificates for the Hard candidates: which episodes are achievable, and what a plan costs.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/hard_oracle.py --episodes 20 --out /tmp/oracle.json \
        [--candidates HardGusts,HardWaves18] [--plans /tmp/plans] [--no-sampling]

For every candidate of ``hard_candidates.py`` and every seed, :func:`subenv_baselines.oracle.certify`
searches a full-information plan in an environment of the candidate's settings with independent planes,
and replays it in the environment; the episode is achievable where the replay wins. The JSON has one
row per episode (the stage that found the winning plan, the replay's outcome, the seconds the search
took); with ``--plans`` each candidate's plans are written to ``<plans>/<candidate>.npz`` (one float32
array per seed, ``seed_<seed>``, as the environment takes the actions; compressed), whose size is
printed: what storing the certificates costs.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import time
from typing import Any

import numpy as np
from hard_candidates import Candidate, candidates, register  # (this folder)

from subenv.atomic import atomic_write_bytes, atomic_write_text
from subenv.envs.config import DivePlaneConfig
from subenv.evaluation import DEFAULT_SEED
from subenv_baselines.oracle import OracleSettings, certify


def oracle_config(candidate: Candidate) -> DivePlaneConfig:
    """The environment the oracle plans in: the candidate's, with independent planes."""
    return DivePlaneConfig(scenario=candidate.scenario, control="independent", **candidate.env_kwargs)


def main() -> None:
    known = candidates()
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--candidates", default=",".join(known), help="comma-separated (default: all)")
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED)
    parser.add_argument("--out", required=True, help="the per-episode rows (JSON), rewritten as they come")
    parser.add_argument("--plans", help="a folder for the plans, one .npz per candidate")
    parser.add_argument("--no-sampling", action="store_true", help="stage 1 only (the full-information MPC)")
    parser.add_argument(
        "--no-order-preview",
        action="store_true",
        help="stage 2 learns of a change of the ordered depth when it is given (preview_orders)",
    )
    args = parser.parse_args()
    settings = OracleSettings(sampling=not args.no_sampling, preview_orders=not args.no_order_preview)
    rows: list[dict[str, Any]] = []
    for name in args.candidates.split(","):
        candidate = known[name]
        register(candidate)
        config = oracle_config(candidate)
        offset = candidate.depth_step.offset_m if candidate.depth_step is not None else None
        plans: dict[str, np.ndarray] = {}
        for seed in range(args.seed, args.seed + args.episodes):
            start = time.perf_counter()
            cert = certify(config, seed, offset, settings)
            rows.append(
                {
                    "candidate": name,
                    "seed": seed,
                    "achievable": cert.success,
                    "stage": cert.stage,
                    "outcome": cert.outcome,
                    "hold_max_abs_error_m": cert.hold_max_abs_error_m,
                    "tried": cert.tried,
                    "seconds": time.perf_counter() - start,
                }
            )
            plans[f"seed_{seed}"] = cert.actions
            verdict = "achievable" if cert.success else "not certified"
            print(
                f"{name} {seed}: {verdict} {cert.stage or cert.outcome} "
                f"{cert.hold_max_abs_error_m:.3f} m, {rows[-1]['seconds']:.1f} s",
                flush=True,
            )
            atomic_write_text(args.out, json.dumps({"settings": repr(settings), "episodes": rows}, indent=1))
        if args.plans:
            os.makedirs(args.plans, exist_ok=True)
            buffer = io.BytesIO()
            np.savez_compressed(buffer, **plans)
            path = os.path.join(args.plans, f"{name}.npz")
            atomic_write_bytes(path, buffer.getvalue())
            raw = sum(p.nbytes for p in plans.values())
            print(
                f"{name}: plans {raw / 1e3:.0f} kB raw, {len(buffer.getvalue()) / 1e3:.0f} kB compressed",
                flush=True,
            )
    for name in args.candidates.split(","):
        mine = [r for r in rows if r["candidate"] == name]
        won = sum(r["achievable"] for r in mine)
        seconds = np.array([r["seconds"] for r in mine])
        stages = {
            stage: sum((r["stage"] or "-") == stage for r in mine) for stage in ("mpc", "sampling", "-")
        }
        print(
            f"{name}: achievable {won}/{len(mine)}; seconds per episode median {np.median(seconds):.1f}, "
            f"max {seconds.max():.1f}; episodes by stage {stages}"
        )


if __name__ == "__main__":
    main()
