"""The Hard suite's achievability certificates: the oracle's plans, replayed, written as the package's data.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/hard_certificates.py \
        --plans /work/notes/hard/plans20,/work/notes/hard/plans50tail [--stages a.json,b.json] [--compute]

For every scenario of the suite (``--suite``, default ``hard``) and each of its seeds (the harness's:
``DEFAULT_SEED`` + i, ``--episodes``, default the suite's), the episode's plan is taken from the
``--plans`` folders (``<folder>/<scenario>.npz``, one float32 array per seed, ``seed_<seed>``, as
``benchmarks/hard_oracle.py --plans`` writes them; a later folder's plan replaces an earlier one's), or,
with ``--compute``, searched by the oracle (:func:`subenv_baselines.oracle.certify`, in the id's own
environment with independent planes, without preview of the ordered depth; minutes per episode in a
rough sea). Every plan is then replayed through the evaluation harness in the registered id
(:class:`subenv.evaluation.achievable.PlanReplay`, the vector environment): the replay's success is the
certificate. Written, each complete or absent:

- ``subenv/evaluation/data/achievable-<suite>.json``: the flags the leaderboard reads (the replay's
  outcome and hold error, the plan's SHA-256, the oracle's stage where ``--stages`` gives the oracle's
  JSON rows);
- ``tests/data/certificates/<scenario>.npz``: the plans of the first ``--sample`` seeds of each scenario
  and of its first episode not certified, which ``tests/evaluation/test_achievable.py`` replays.

Prints per scenario the achievable count and the seconds the replays took.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import time
from typing import Any

import gymnasium as gym
import numpy as np

from subenv.atomic import atomic_write_bytes, atomic_write_text
from subenv.envs.config import DivePlaneConfig
from subenv.evaluation import DEFAULT_SEED, get_suite, run_episodes
from subenv.evaluation.achievable import (
    CERTIFICATE_FORMAT,
    CERTIFIED_SETTINGS,
    DATA_PACKAGE,
    PlanReplay,
    plan_sha256,
)
from subenv.scenarios.registry import get_scenario

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SAMPLE_DIR = os.path.join(ROOT, "tests", "data", "certificates")


def read_plans(folders: list[str], scenario: str) -> dict[int, np.ndarray]:
    """The stored plans of ``scenario`` by seed (a later folder's replaces an earlier one's)."""
    plans: dict[int, np.ndarray] = {}
    for folder in folders:
        path = os.path.join(folder, f"{scenario}.npz")
        if os.path.exists(path):
            with np.load(path) as stored:
                plans |= {int(k.removeprefix("seed_")): stored[k].astype(np.float32) for k in stored.files}
    return plans


def read_stages(files: list[str]) -> dict[tuple[str, int], str]:
    """The oracle's stage per (scenario, seed), from ``hard_oracle.py``'s JSON rows."""
    stages: dict[tuple[str, int], str] = {}
    for path in files:
        with open(path, encoding="utf-8") as f:
            for row in json.load(f)["episodes"]:
                stages[(row["candidate"], int(row["seed"]))] = row["stage"]
    return stages


def compute(env_id: str, seed: int) -> tuple[np.ndarray, str]:
    """The oracle's plan for one episode (imported here: only ``--compute`` needs the oracle)."""
    from subenv_baselines.oracle import OracleSettings, certify

    config = DivePlaneConfig(**{**gym.spec(env_id).kwargs, "control": "independent"})
    cert = certify(config, seed, None, OracleSettings(preview_orders=False))
    return cert.actions, cert.stage


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--suite", default="hard")
    parser.add_argument("--episodes", type=int, help="seeds per scenario (default: the suite's)")
    parser.add_argument("--plans", default="", help="comma-separated folders of stored plans")
    parser.add_argument("--stages", default="", help="comma-separated hard_oracle.py JSON files")
    parser.add_argument("--compute", action="store_true", help="search the plans the folders lack")
    parser.add_argument("--sample", type=int, default=2, help="plans kept in tests/data per scenario")
    parser.add_argument("--out", help="the flags' file (default: the package's)")
    parser.add_argument("--sample-dir", default=SAMPLE_DIR, help="the sampled plans' folder")
    args = parser.parse_args()
    suite = get_suite(args.suite)
    episodes = args.episodes or suite.episodes
    folders = [f for f in args.plans.split(",") if f]
    stages = read_stages([f for f in args.stages.split(",") if f])
    seeds = list(range(DEFAULT_SEED, DEFAULT_SEED + episodes))
    ids: dict[str, Any] = {}
    for name in suite.scenarios:
        scenario = get_scenario(name)
        env_id = scenario.env_id
        plans = read_plans(folders, name)
        for seed in seeds:
            if seed not in plans:
                if not args.compute:
                    raise SystemExit(f"{name}: no plan for seed {seed} (pass --compute to search it)")
                plans[seed], stages[(name, seed)] = compute(env_id, seed)
        start = time.perf_counter()
        results = run_episodes(PlanReplay([plans[s] for s in seeds]), env_id, seeds)
        elapsed = time.perf_counter() - start
        config = DivePlaneConfig(**{**gym.spec(env_id).kwargs, "control": "independent"})
        flags = {}
        for r in results:
            flags[str(r.seed)] = {
                "achievable": bool(r.metrics.success),
                "outcome": r.metrics.outcome,
                "hold_max_abs_error_m": round(float(r.metrics.hold_max_abs_error_m), 6),
                "plan_sha256": plan_sha256(plans[r.seed]),
                "stage": stages.get((name, r.seed), "") if r.metrics.success else "",
            }
        ids[env_id] = {
            "scenario": scenario.key,
            "vehicle": "suboff",
            "settings": {key: getattr(config, key) for key in CERTIFIED_SETTINGS},
            "episodes": flags,
        }
        won = sum(f["achievable"] for f in flags.values())
        print(f"{env_id}: achievable {won}/{len(flags)}; replays {elapsed:.1f} s", flush=True)
        lost = [s for s in seeds if not flags[str(s)]["achievable"]]
        sample = {f"seed_{s}": plans[s] for s in seeds[: args.sample] + lost[:1]}
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **sample)
        os.makedirs(args.sample_dir, exist_ok=True)
        atomic_write_bytes(os.path.join(args.sample_dir, f"{name}.npz"), buffer.getvalue())
    data = {
        "format": CERTIFICATE_FORMAT,
        "suite": suite.name,
        "oracle": "subenv_baselines.oracle.certify, OracleSettings(preview_orders=False), independent planes",
        "ids": ids,
    }
    out = args.out or os.path.join(ROOT, *DATA_PACKAGE.split("."), f"achievable-{suite.name}.json")
    atomic_write_text(out, json.dumps(data, indent=1) + "\n")
    print(f"written: {out}")


if __name__ == "__main__":
    main()
