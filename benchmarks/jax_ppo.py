"""The JAX PPO (subenv_agents.jax_ppo): its speed next to Stable-Baselines3's, and experiments over seeds.

    .venv/bin/python benchmarks/jax_ppo.py [speed] [--timesteps N ...] [--episodes E] [--sb3-timesteps N]
    .venv/bin/python benchmarks/jax_ppo.py run --out DIR --variants gru mlp --seeds 0 1 2 3 4 [--set k=v ...]
    .venv/bin/python benchmarks/jax_ppo.py report --out DIR [--variants ...]

``speed`` (the default):

1. The ``shipped`` variant's settings (those of the first shipped ``ppo_jax``: a memoryless policy on
   SpeedTransient, :data:`VARIANTS`) trained to each of ``--timesteps`` (default 2.5M, 5M, 10M
   env-steps; the learning rate annealed over each budget), on this machine's default JAX device: wall
   time (compilation included) and the success and plane RMS of the final policy on the reversal
   scenarios (LowSpeed, NearCritical, SpeedTransient;
   ``--episodes`` each, the harness of ``subenv evaluate``, seeds 10000 + i).
2. Stable-Baselines3's PPO with the shipped ``ppo``'s hyperparameters (``python -m
   subenv_agents.train --algo ppo``, 16 environments of the native vector env, one torch thread) for
   ``--sb3-timesteps``: its env-steps per second, the reference of the ratio.
3. The shipped ``ppo``'s own record (``subenv_agents/models/ppo``: its training time, all its runs
   included, and its success on the same episodes): what the JAX runs are set against. It is read,
   not re-run here (24 minutes).

``run`` trains every (variant, seed) of :data:`VARIANTS` not yet done in ``DIR``, one at a time, each in a
process of its own (``one``): the final policy evaluated on the default suite (wins over the winnable
episodes and the benchmark-v1 score, :func:`subenv_agents.jax_ppo.train_model`), the model folder in
``DIR/models/<variant>-seed<k>/``, and the run's record, written whole, in
``DIR/runs/<variant>-seed<k>.json``.
Stop it at any time and run it again: finished runs are kept, an unfinished one starts again.

**Timing on a shared machine.** Each run also times, in its own process before and after its training, a
reference: two updates of the ``shipped`` variant's program (its compilation cached and not timed), whose
rate on the quiet development machine is :data:`REFERENCE_QUIET_RATE`. A run's time on the quiet machine
is estimated twice (:func:`quiet_estimate`): its wall time scaled by the reference's slowdown (reference
rate now against quiet), and its CPU time in units of the reference's CPU time per env-step (what the
load does not change as much).

``report`` summarises the finished runs: per variant, the success over the winnable episodes per scenario,
IQM and mean over seeds x scenarios with 95% stratified bootstrap intervals (rliable), the benchmark-v1
score per seed and its mean with a bootstrap interval, the targets of issue 35, the times; the learning
curves and each variant's failure outcomes, plotted (``report.md``, ``report.json``,
``learning_curves.png``, ``failures.png``, and ``episodes-<variant>.png``: what the median seed does on
BallastOffset, a typical episode of each outcome). With pairs ``<base>`` and ``<base>-curriculum`` among the
variants, the curriculum ablation: the probability that the difficulty curriculum beats uniform resets,
with its interval and a one-line verdict (:func:`ablations`), e.g.::

    .venv/bin/python benchmarks/jax_ppo.py run --out DIR --variants mlp mlp-curriculum --seeds 0 1 2 3 4
    .venv/bin/python benchmarks/jax_ppo.py report --out DIR
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
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Final

# subenv and subenv_agents are this checkout's (not an installed copy's): run from any directory.
REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402

BASE: Final[dict[str, Any]] = {
    "env_id": "subenv/Mixed-v0",
    "env_kwargs": {"control": "independent", "effort_weight": 1.0, "depth_scale_m": 1.0},
    "total_timesteps": 20_000_000,
    "memory": 0,
}
"""What every variant shares unless it says otherwise: the shipped ``ppo_jax``'s environment arguments, on
the agents' training scenario (Mixed: every base scenario, the reversal ones twice as often, mildly
randomised), memoryless (the ``gru`` variants add the memory; ``gru`` is the shipped agent's settings,
:class:`~subenv_agents.jax_ppo.PPOConfig`'s defaults)."""

VARIANTS: Final[dict[str, dict[str, Any]]] = {
    "mlp": {},
    "mlp-curriculum": {"curriculum": "difficulty"},
    "gru": {"memory": 64},
    "gru-curriculum": {"memory": 64, "curriculum": "difficulty"},
    "gru-integral": {"memory": 64, "depth_integral_s": 100.0},
    "mlp-integral": {"depth_integral_s": 100.0},
    "shipped": {"env_id": "subenv/SpeedTransient-v0", "total_timesteps": 15_000_000},
    "shipped-previous-bootstrap": {
        "env_id": "subenv/SpeedTransient-v0",
        "total_timesteps": 15_000_000,
        "bootstrap": "previous",
    },
}
"""Named settings of :class:`~subenv_agents.jax_ppo.PPOConfig` over :data:`BASE` (the seed is the run's), and
``bootstrap="previous"``: a truncated episode bootstrapped as the JAX PPO did before gymnax 1.0's
``final_observation`` (:func:`previous_advantages`), to measure what that change did."""


def previous_advantages(rollout: Any, last_value: Any, gamma: float, lam: float) -> tuple[Any, Any]:
    """:func:`subenv_agents.jax_ppo.advantages` as it was before commit b5b6aec: a truncated episode
    bootstrapped from the value of the state its last step started from (``t.value``), not from the
    value of the observation that step reached."""
    import jax
    import jax.numpy as jnp

    def back(carry: tuple[Any, Any], t: Any) -> tuple[tuple[Any, Any], Any]:
        gae, next_value = carry
        bootstrap = jnp.where(t.terminated, 0.0, jnp.where(t.done, t.value, next_value))
        delta = t.reward + gamma * bootstrap - t.value
        gae = delta + gamma * lam * (1.0 - t.done) * gae
        return (gae, t.value), gae

    _, adv = jax.lax.scan(back, (jnp.zeros_like(last_value), last_value), rollout, reverse=True)
    return adv, adv + rollout.value


REFERENCE_QUIET_RATE: Final = 126_760
"""Env-steps per second of :func:`reference_rate`'s program on the quiet 2-core development machine, its
compilation excluded as there: the median of four measurements in one process (2026-12-05, load 0.7:
124,885, 124,925, 128,595 and 128,952)."""
REFERENCE_UPDATES: Final = 2


# --- one run -------------------------------------------------------------------------------------
def settings_of(variant: str, seed: int, overrides: Mapping[str, Any]) -> dict[str, Any]:
    """The :class:`PPOConfig` settings of ``variant`` with ``seed`` and ``overrides``."""
    if variant not in VARIANTS:
        raise SystemExit(f"variant={variant!r} is unknown: must be one of {list(VARIANTS)}")
    return {**BASE, **VARIANTS[variant], **overrides, "seed": seed}


def reference_rate() -> dict[str, float]:
    """The ``shipped`` variant's program (the memoryless PPO the JAX agent shipped first) for
    :data:`REFERENCE_UPDATES` updates, timed without its compilation: env-steps per second of wall time and
    CPU microseconds per env-step of this process."""
    import jax

    from subenv_agents.jax_ppo import PPOConfig, make_train

    shipped = PPOConfig(**settings_of("shipped", 0, {}))
    config = dataclasses.replace(
        shipped, total_timesteps=REFERENCE_UPDATES * shipped.num_envs * shipped.num_steps
    )
    train, _ = make_train(config)
    compiled = jax.jit(train).lower(jax.random.key(0)).compile()
    cpu, start = time.process_time(), time.perf_counter()
    jax.block_until_ready(compiled(jax.random.key(0)))
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    steps = config.num_updates * config.num_envs * config.num_steps
    return {"env_steps_per_s": steps / wall, "cpu_us_per_step": 1e6 * cpu / steps, "load": os.getloadavg()[0]}


def one(out: Path, variant: str, seed: int, overrides: Mapping[str, Any], episodes: int) -> None:
    """Train, evaluate and record one (variant, seed) in ``out`` (see the module's docstring)."""
    import jax

    from subenv.atomic import atomic_write_text
    from subenv_agents import jax_ppo
    from subenv_agents.jax_ppo import PPOConfig, train_model

    jax.config.update("jax_compilation_cache_dir", str(out / "jax-cache"))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
    name = f"{variant}-seed{seed}"
    settings = settings_of(variant, seed, overrides)
    bootstrap = settings.pop("bootstrap", "final")
    if bootstrap == "previous":  # (make_train calls the module's advantages when it is traced)
        jax_ppo.advantages = previous_advantages
    config = PPOConfig(**settings)
    before = reference_rate()
    command = shlex_join(sys.argv)
    record = train_model(config, out / "models" / name, command, episodes, baselines=(), overwrite=True)
    after = reference_rate()
    evaluation = json.loads((out / "models" / name / "evaluation.json").read_text())
    run = {
        "variant": variant,
        "seed": seed,
        "settings": dataclasses.asdict(config) | {"hidden": list(config.hidden)},
        "overrides": dict(overrides),
        "bootstrap": bootstrap,
        "env_steps": record["env_steps"],
        "wall_time_s": record["wall_time_s"],
        "cpu_time_s": record["cpu_time_s"],
        "load_average": record["load_average"],
        "reference": {"before": before, "after": after},
        "per_update": record["per_update"],
        "episodes": episodes,
        "scores": evaluation["scores"][name],
        "machine": f"{platform.machine()}, {os.cpu_count()} cores",
    }
    atomic_write_text(out / "runs" / f"{name}.json", json.dumps(run, indent=1) + "\n")


def quiet_estimate(run: Mapping[str, Any]) -> dict[str, float]:
    """A run's training time on the quiet machine [s], estimated twice from its record (the module's
    docstring): its wall time scaled by the reference's slowdown, and its CPU time in units of the
    reference's CPU time per env-step, both against :data:`REFERENCE_QUIET_RATE`."""
    before, after = run["reference"]["before"], run["reference"]["after"]
    ref_rate = (before["env_steps_per_s"] + after["env_steps_per_s"]) / 2
    ref_cpu = (before["cpu_us_per_step"] + after["cpu_us_per_step"]) / 2
    return {
        "by_wall_time": round(run["wall_time_s"] * ref_rate / REFERENCE_QUIET_RATE, 1),
        "by_cpu_time": round(1e6 * run["cpu_time_s"] / ref_cpu / REFERENCE_QUIET_RATE, 1),
    }


def shlex_join(argv: Sequence[str]) -> str:
    import shlex

    return shlex.join([sys.executable.rsplit("/", 1)[-1], *argv])


def run_all(
    out: Path, variants: Sequence[str], seeds: Sequence[int], overrides: Mapping[str, Any], episodes: int
) -> None:
    """Every (variant, seed) not yet in ``out/runs``, seed by seed, each in a process of its own."""
    (out / "logs").mkdir(parents=True, exist_ok=True)
    for seed in seeds:
        for variant in variants:
            name = f"{variant}-seed{seed}"
            if (out / "runs" / f"{name}.json").exists():
                continue
            settings_of(variant, seed, overrides)  # (an unknown variant: now)
            cmd = [
                sys.executable,
                __file__,
                "one",
                "--out",
                str(out),
                "--variant",
                variant,
                "--seed",
                str(seed),
            ]
            cmd += ["--episodes", str(episodes)] + [
                f"--set={k}={json.dumps(v)}" for k, v in overrides.items()
            ]
            print(f"{time.strftime('%H:%M:%S')} {name} (load {os.getloadavg()[0]:.1f})", flush=True)
            with (out / "logs" / f"{name}.log").open("w") as log:
                done = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
            if done.returncode:
                raise SystemExit(
                    f"{name} failed (exit {done.returncode}): see {out / 'logs' / f'{name}.log'}"
                )


# --- the report ---------------------------------------------------------------------------------
def read_runs(out: Path, variants: Sequence[str] | None = None) -> dict[str, list[dict[str, Any]]]:
    """The finished runs in ``out``, by variant (in ``variants``' order, or as found), seeds in order."""
    runs: dict[str, list[dict[str, Any]]] = {}
    for path in sorted((out / "runs").glob("*.json")):
        run = json.loads(path.read_text())
        if variants is None or run["variant"] in variants:
            runs.setdefault(run["variant"], []).append(run)
    order = list(variants) if variants is not None else sorted(runs)
    return {v: sorted(runs[v], key=lambda r: r["seed"]) for v in order if v in runs}


def success_matrix(runs: Sequence[Mapping[str, Any]], scenarios: Sequence[str]) -> np.ndarray:
    """Success over the winnable episodes, runs x scenarios."""
    return np.array([[r["scores"][s]["success_rate"] for s in scenarios] for r in runs])


HARD_BASELINES: Final = ("mpc", "reversal_aware")
"""Shown beside the agents on the Hard track (``mpc`` told the environment's settings, as on the
leaderboard)."""


def hard_scores(out: Path, runs: Mapping[str, Sequence[Mapping[str, Any]]]) -> dict[str, dict[str, Any]]:
    """The benchmark-v1 score on the Hard track (its suite's episodes and seeds, as the leaderboard's) of
    every run's final policy and of :data:`HARD_BASELINES`: ``{name: pooled score record}``
    (:func:`subenv_agents.records.score_record`), each evaluated once and kept in ``out/hard/<name>.json``."""
    from subenv.atomic import atomic_write_text
    from subenv.evaluation import evaluate, make_controller
    from subenv_agents.jax_ppo import JaxPPOController
    from subenv_agents.records import score_record

    out_dir = out / "hard"
    out_dir.mkdir(exist_ok=True)
    names = [f"{r['variant']}-seed{r['seed']}" for rs in runs.values() for r in rs] + list(HARD_BASELINES)
    scores = {}
    for name in names:
        path = out_dir / f"{name}.json"
        if not path.exists():
            controller = (
                make_controller(name)
                if name in HARD_BASELINES
                else JaxPPOController(out / "models" / name, name=name)
            )
            record = score_record(evaluate([controller], "hard", progress=False, keep_trajectories=0))[name]
            atomic_write_text(path, json.dumps(record, indent=1) + "\n")
        scores[name] = json.loads(path.read_text())["all"]
    return scores


def summarize(
    runs: Mapping[str, Sequence[Mapping[str, Any]]],
    hard: Mapping[str, Mapping[str, Any]] | None = None,
    reps: int = 10_000,
) -> dict[str, Any]:
    """Per variant: rliable's IQM and mean over runs x scenarios (95% stratified bootstrap), each
    scenario's mean over runs, the pooled score's mean over runs with a bootstrap interval (and the Hard
    track's, from ``hard``: :func:`hard_scores`), the targets of issue 35, the times."""
    import warnings

    from rliable import library as rly
    from rliable import metrics

    first = next(iter(runs.values()))[0]
    scenarios = [s for s in first["scores"] if s != "all"]
    matrices = {v: success_matrix(rs, scenarios) for v, rs in runs.items()}
    pooled = {v: np.array([[r["scores"]["all"]["score"]] for r in rs]) for v, rs in runs.items()}
    hard = hard or {}
    hard_pooled = {
        v: np.array([[hard[f"{v}-seed{r['seed']}"]["score"]] for r in rs])
        for v, rs in runs.items()
        if all(f"{v}-seed{r['seed']}" in hard for r in rs)
    }

    def estimates(scores: Mapping[str, np.ndarray], statistic: Any) -> tuple[dict[str, Any], dict[str, Any]]:
        """Rliable's point estimates and intervals, each variant's from a generator of its own (seeded
        alike): a variant's numbers do not change when the report holds more or fewer variants."""
        point: dict[str, Any] = {}
        ci: dict[str, Any] = {}
        for v, score in scores.items():
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", category=FutureWarning)
                p, c = rly.get_interval_estimates(
                    {v: score}, statistic, reps=reps, random_state=np.random.RandomState(0)
                )
            point[v], ci[v] = p[v], c[v]
        return point, ci

    point, ci = estimates(matrices, lambda x: np.array([metrics.aggregate_iqm(x), metrics.aggregate_mean(x)]))
    score_point, score_ci = estimates(pooled, lambda x: np.array([np.mean(x)]))
    hard_point, hard_ci = estimates(hard_pooled, lambda x: np.array([np.mean(x)]))
    out: dict[str, Any] = {
        "scenarios": scenarios,
        "variants": {},
        "ablations": ablations(matrices, reps),
        "hard_baselines": {n: hard[n] for n in HARD_BASELINES if n in hard},
    }
    for v, rs in runs.items():
        m = matrices[v]
        ballast = [r["scores"]["BallastOffset"] for r in rs]
        mean_success = m.mean(axis=1)
        median_seed = int(np.argsort(mean_success)[len(mean_success) // 2])
        quiet = [quiet_estimate(r) for r in rs]
        out["variants"][v] = {
            "settings": {k: value for k, value in rs[0]["settings"].items() if k != "seed"},
            "runs": len(rs),
            "seeds": [r["seed"] for r in rs],
            "iqm": float(point[v][0]),
            "iqm_ci": [float(x) for x in ci[v][:, 0]],
            "mean": float(point[v][1]),
            "mean_ci": [float(x) for x in ci[v][:, 1]],
            "per_scenario": {s: [float(x) for x in m[:, j]] for j, s in enumerate(scenarios)},
            "score": [r["scores"]["all"]["score"] for r in rs],
            "score_mean": float(score_point[v][0]),
            "score_mean_ci": [float(x) for x in score_ci[v][:, 0]],
            "hard_score": [float(x) for x in hard_pooled[v][:, 0]] if v in hard_pooled else None,
            "hard_score_mean": float(hard_point[v][0]) if v in hard_pooled else None,
            "hard_score_mean_ci": [float(x) for x in hard_ci[v][:, 0]] if v in hard_pooled else None,
            "ballast_wins": [f"{b['wins']}/{b['scored']}" for b in ballast],
            "ballast_median_wins": float(np.median([b["wins"] for b in ballast])),
            "ballast_scored": sorted({b["scored"] for b in ballast}),
            "median_seed": rs[median_seed]["seed"],
            "median_seed_lowest": float(m[median_seed].min()),
            "targets": {
                "iqm >= 97": bool(point[v][0] >= 0.97),
                # (of 90 winnable episodes in 100; as a fraction for another number of episodes)
                "BallastOffset median >= 85/90": bool(
                    np.median([b["wins"] / b["scored"] for b in ballast]) >= 85 / 90
                ),
                "median seed >= 95% on every scenario": bool(m[median_seed].min() >= 0.95),
                "<= 15 min quiet (both estimates, every seed)": bool(
                    all(max(q.values()) <= 900 for q in quiet)
                ),
            },
            "quiet_estimate_s": quiet,
            "wall_time_s": [r["wall_time_s"] for r in rs],
            "load_average": [r["load_average"] for r in rs],
            "env_steps": rs[0]["env_steps"],
            "episodes": rs[0]["episodes"],
            "failures": _failures(rs),
        }
    return out


CURRICULUM_SUFFIX: Final = "-curriculum"
"""A variant ``<base>-curriculum`` is ``<base>`` with ``curriculum="difficulty"``: the ablation's pair."""


def ablations(matrices: Mapping[str, np.ndarray], reps: int) -> dict[str, dict[str, Any]]:
    """The curriculum ablation: for each pair of variants ``<base>`` and ``<base>-curriculum`` among the
    runs, the probability that the curriculum's run beats the uniform one on a scenario (rliable's
    probability of improvement: the Mann-Whitney statistic over their seeds, averaged over the
    scenarios; 0.5 for none) with a 95% stratified bootstrap interval, and the verdict it supports
    (Agarwal et al. 2021: an improvement when the interval's lower end is above 0.5, worse when its
    upper end is below)."""
    import warnings

    from rliable import library as rly
    from rliable import metrics

    pairs = {
        f"{v} vs {v.removesuffix(CURRICULUM_SUFFIX)}": [m, matrices[v.removesuffix(CURRICULUM_SUFFIX)]]
        for v, m in matrices.items()
        if v.endswith(CURRICULUM_SUFFIX) and v.removesuffix(CURRICULUM_SUFFIX) in matrices
    }
    if not pairs:
        return {}
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=FutureWarning)
        # (each replication runs a Mann-Whitney test per scenario: fewer than the aggregates')
        point, ci = rly.get_interval_estimates(
            pairs,
            metrics.probability_of_improvement,
            reps=min(reps, 2000),
            random_state=np.random.RandomState(1),
        )
    out = {}
    for name, (curriculum, uniform) in pairs.items():
        low, high = (float(x) for x in np.ravel(ci[name]))
        p = float(np.ravel(point[name])[0])
        verdict = "helps" if low > 0.5 else "hurts" if high < 0.5 else "makes no difference we can tell"
        out[name] = {
            "runs": [len(curriculum), len(uniform)],
            "probability_of_improvement": p,
            "ci": [low, high],
            "verdict": f"the difficulty curriculum {verdict} ({name}, {len(curriculum)} and {len(uniform)} "
            f"seeds: P(curriculum > uniform) = {p:.2f} [{low:.2f}, {high:.2f}])",
        }
    return out


def _failures(runs: Sequence[Mapping[str, Any]]) -> dict[str, dict[str, int]]:
    """Failure outcomes over every run, per scenario (winnable episodes)."""
    out: dict[str, dict[str, int]] = {}
    for r in runs:
        for s, rec in r["scores"].items():
            if s == "all":
                continue
            for o, k in rec["outcomes"].items():
                out.setdefault(s, {}).setdefault(o, 0)
                out[s][o] += k
    return out


def _cell(values: Sequence[float]) -> str:
    return f"{100 * float(np.mean(values)):.0f} ({', '.join(f'{100 * v:.0f}' for v in values)})"


def report_markdown(summary: Mapping[str, Any]) -> str:
    """The report's tables."""
    scenarios = summary["scenarios"]
    head = [
        "variant",
        "runs",
        "IQM [95% CI]",
        "mean [95% CI]",
        *scenarios,
        "score (per seed)",
        "Hard score (per seed)",
        "quiet min",
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for v, s in summary["variants"].items():
        quiet = [max(q.values()) / 60 for q in s["quiet_estimate_s"]]
        cells = [
            v,
            str(s["runs"]),
            f"{100 * s['iqm']:.1f} [{100 * s['iqm_ci'][0]:.1f}, {100 * s['iqm_ci'][1]:.1f}]",
            f"{100 * s['mean']:.1f} [{100 * s['mean_ci'][0]:.1f}, {100 * s['mean_ci'][1]:.1f}]",
            *(_cell(s["per_scenario"][sc]) for sc in scenarios),
            f"{s['score_mean']:.0f} [{s['score_mean_ci'][0]:.0f}, {s['score_mean_ci'][1]:.0f}] "
            f"({', '.join(f'{x:.0f}' for x in s['score'])})",
            "-"
            if s["hard_score"] is None
            else f"{s['hard_score_mean']:.0f} [{s['hard_score_mean_ci'][0]:.0f}, "
            f"{s['hard_score_mean_ci'][1]:.0f}] ({', '.join(f'{x:.0f}' for x in s['hard_score'])})",
            f"{min(quiet):.1f}-{max(quiet):.1f}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    baselines = [
        f"{name} {b['score']:.1f} [{b['score_ci_low']:.1f}, {b['score_ci_high']:.1f}]"
        for name, b in summary["hard_baselines"].items()
    ]
    if baselines:
        lines += ["", "On the Hard track, the same episodes: " + ", ".join(baselines) + "."]
    targets = ["", "| variant | " + " | ".join(next(iter(summary["variants"].values()))["targets"]) + " |"]
    targets.append("|---|" + "---|" * (len(targets[1].split("|")) - 3))
    for v, s in summary["variants"].items():
        marks = ["met" if ok else "not met" for ok in s["targets"].values()]
        targets.append(f"| {v} | " + " | ".join(marks) + " |")
    ballast = [
        "",
        "| variant | BallastOffset wins per seed | median | median seed (lowest scenario) |",
        "|---|---|---|---|",
    ]
    for v, s in summary["variants"].items():
        ballast.append(
            f"| {v} | {', '.join(s['ballast_wins'])} | {s['ballast_median_wins']:.0f} | "
            f"seed {s['median_seed']} ({100 * s['median_seed_lowest']:.0f}%) |"
        )
    ablation = []
    if summary["ablations"]:
        ablation = [
            "",
            "The curriculum ablation (the analysis's difficulty curriculum against uniform resets, the same "
            "budget and seeds): the probability that a curriculum run beats a uniform one on a scenario "
            "(rliable's probability of improvement, averaged over the scenarios) with its 95% stratified "
            "bootstrap interval.",
            "",
            "| pair | seeds | P(curriculum > uniform) [95% CI] |",
            "|---|---|---|",
            *(
                f"| {name} | {a['runs'][0]}, {a['runs'][1]} | {a['probability_of_improvement']:.2f} "
                f"[{a['ci'][0]:.2f}, {a['ci'][1]:.2f}] |"
                for name, a in summary["ablations"].items()
            ),
            "",
            *(f"Verdict: {a['verdict']}." for a in summary["ablations"].values()),
        ]
    return "\n".join(
        [
            "Success over the winnable episodes [%] of the default suite "
            f"({'/'.join(sorted({str(s['episodes']) for s in summary['variants'].values()}))} episodes per "
            "scenario, seeds 10000 + i), final policies: IQM and mean over seeds x scenarios with 95% "
            "stratified bootstrap intervals (rliable), each scenario's mean over seeds (the seeds' values in "
            "brackets); "
            "the benchmark-v1 score pooled over the suite, its mean over seeds with a 95% bootstrap "
            "interval (and each seed's), and the same on the Hard track (its suite's episodes); the "
            "estimated training time on the quiet 2-core machine (the larger of the two estimates, module "
            "docstring), the fastest and slowest seed.",
            "",
            *lines,
            *targets,
            *ballast,
            *ablation,
            "",
        ]
    )


def plot(out: Path, runs: Mapping[str, Sequence[Mapping[str, Any]]]) -> list[Path]:
    """Learning curves (training success and terminations per update, mean over seeds and each seed) and
    the failure outcomes per scenario of each variant."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from subenv.evaluation.plots import save_figure

    paths = []
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for (variant, rs), color in zip(
        runs.items(), plt.rcParams["axes.prop_cycle"].by_key()["color"], strict=False
    ):
        curves = []
        for r in rs:
            u = r["per_update"]
            ended = np.asarray(u["episodes"], float)
            steps = (np.arange(len(ended)) + 1) * r["env_steps"] / len(ended) / 1e6
            won, term = _rate(u["won"], ended), _rate(u["terminated"], ended)
            curves.append((steps, won, term))
            axes[0].plot(steps, 100 * won, color=color, alpha=0.25, lw=0.8)
            axes[1].plot(steps, 100 * term, color=color, alpha=0.25, lw=0.8)
        steps = curves[0][0]
        axes[0].plot(
            steps,
            100 * np.nanmean([c[1] for c in curves], axis=0),
            color=color,
            lw=2,
            label=f"{variant} ({len(rs)} seeds)",
        )
        axes[1].plot(
            steps, 100 * np.nanmean([c[2] for c in curves], axis=0), color=color, lw=2, label=variant
        )
    axes[0].set(xlabel="env-steps [millions]", ylabel="training episodes won [%]", ylim=(-2, 102))
    axes[1].set(xlabel="env-steps [millions]", ylabel="training episodes terminated [%]", ylim=(-2, 102))
    axes[0].set_title("Won (not terminated, within 0.5 m over the last 60 s)", fontsize=9)
    axes[1].set_title("Terminated (broached, pitch limit, left the depth band)", fontsize=9)
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(
        "Learning curves on the training episodes (thin: seeds; thick: mean; over 10 updates)",
        fontsize=10,
    )
    fig.tight_layout()
    paths.append(save_figure(fig, out / "learning_curves.png"))
    plt.close(fig)

    # The failure outcomes: per variant and scenario, the failed winnable episodes of all its seeds
    failures = {v: _failures(rs) for v, rs in runs.items()}
    scenarios = [s for s in next(iter(runs.values()))[0]["scores"] if s != "all"]
    outcomes = sorted({o for f in failures.values() for per in f.values() for o in per})
    fig, axes = plt.subplots(1, len(runs), figsize=(4.5 * len(runs), 3.8), sharey=True, squeeze=False)
    for ax, (variant, per) in zip(axes[0], failures.items(), strict=True):
        bottom = np.zeros(len(scenarios))
        for outcome in outcomes:
            counts = np.array([per.get(s, {}).get(outcome, 0) for s in scenarios], float)
            ax.bar(scenarios, counts, bottom=bottom, label=outcome)
            bottom += counts
        ax.set_title(f"{variant} ({len(runs[variant])} seeds)", fontsize=9)
        ax.tick_params(axis="x", labelrotation=60, labelsize=7)
        ax.grid(alpha=0.3, axis="y")
    axes[0][0].set_ylabel("failed winnable episodes (all seeds)")
    if outcomes:
        axes[0][-1].legend(fontsize=7)
    fig.suptitle("How the final policies fail, per scenario", fontsize=10)
    fig.tight_layout()
    paths.append(save_figure(fig, out / "failures.png"))
    plt.close(fig)
    return paths


def plot_failed_episodes(
    out: Path, summary: Mapping[str, Any], scenario: str = "BallastOffset"
) -> list[Path]:
    """What each variant's median seed does on ``scenario``: its final policy (``out/models``) played again
    on the run's evaluation episodes of that scenario, and a typical episode of each outcome plotted
    (depth error, pitch and planes against time: :func:`subenv.evaluation.plots.plot_outcomes`), into
    ``episodes-<variant>.png``."""
    from subenv.evaluation import evaluate
    from subenv.evaluation.plots import plot_outcomes
    from subenv_agents.jax_ppo import JaxPPOController

    paths = []
    for variant, s in summary["variants"].items():
        name = f"{variant}-seed{s['median_seed']}"
        agent = JaxPPOController(out / "models" / name, name=name)
        results = evaluate(
            [agent], [scenario], s["episodes"], progress=False, keep_trajectories=s["episodes"]
        )
        scored = [r for r in results if r.winnable is not False]
        wins = sum(r.metrics.success for r in scored)
        paths.append(
            plot_outcomes(
                results,
                out / f"episodes-{variant}.png",
                title=f"{scenario}: what {name} (the median seed of {variant}) does, a typical episode of "
                f"each outcome\n({wins} of {len(scored)} winnable episodes won)",
            )
        )
    return paths


def _rate(counts: Sequence[float], ended: np.ndarray, k: int = 10) -> np.ndarray:
    """The fraction of the episodes ended around each update that ``counts`` counts: both summed over a
    window of ``k`` updates (fewer at the ends), NaN where none ended."""
    window = np.ones(min(k, ended.size))
    ended_sum = np.convolve(ended, window, mode="same")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(
            ended_sum > 0, np.convolve(np.asarray(counts, float), window, mode="same") / ended_sum, np.nan
        )


# --- the speed comparison (the default) ----------------------------------------------------------
def speed(args: argparse.Namespace) -> None:
    """The ``shipped`` variant's settings (the memoryless PPO the JAX agent shipped first) to three budgets
    next to SB3's PPO (the module's docstring, ``speed``)."""
    import jax

    from subenv.evaluation import evaluate
    from subenv_agents import shipped_models
    from subenv_agents.card import total_training_time_s
    from subenv_agents.jax_ppo import JaxPPOController, PPOConfig, make_train
    from subenv_agents.records import REVERSAL_SCENARIOS, evaluation_record

    def jax_run(config: Any, episodes: int) -> tuple[float, dict[str, dict[str, float]]]:
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
        with tempfile.TemporaryDirectory() as tmp:
            run = Path(tmp) / "run"
            cmd = [
                sys.executable,
                "-m",
                "subenv_agents.train",
                "--algo",
                "ppo",
                "--env",
                "subenv/SpeedTransient-v0",
            ]
            cmd += ["-n", str(timesteps), "--run-dir", str(run), "--eval-freq", "0", "--save-freq", "0"]
            cmd += ["-q", "--no-progress", "--threads", "1"]
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, cwd=REPO)
            record = json.loads((run / "train.json").read_text())
        return record["timesteps"] / record["wall_time_s"], record["timesteps"]

    def cells(record: dict[str, dict[str, float]]) -> str:
        return " | ".join(
            f"{100 * record[s]['success_rate']:.0f}% ({record[s]['plane_rms_rad']:.3f})"
            for s in REVERSAL_SCENARIOS
        )

    shipped = PPOConfig(**settings_of("shipped", 0, {}))
    print(
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; jax {jax.__version__} on "
        f"{jax.devices()[0]}; the shipped variant's settings (a memoryless policy) on {shipped.env_id}, "
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
        print(f"| JAX PPO | {done:,} | {wall:.0f} | {done / wall:,.0f} | {cells(record)} |", flush=True)
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
        f"{total_training_time_s(train):.0f} (all its runs) | | {cells(stored)} |"
    )
    print(f"\nJAX PPO / SB3 PPO, env-steps per second: {min(rates) / sb3:.1f} to {max(rates) / sb3:.1f}")


def _setting(text: str) -> tuple[str, Any]:
    key, sep, value = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"--set {text!r} is invalid: must be key=JSON value")
    return key, json.loads(value)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command")
    fast = commands.add_parser("speed", help="the shipped settings to three budgets next to SB3's PPO")
    for p in (parser, fast):
        p.add_argument("--timesteps", type=float, nargs="+", default=[2.5e6, 5e6, 1e7])
        p.add_argument(
            "--episodes", type=int, default=100, help="evaluation episodes per scenario (default: 100)"
        )
        p.add_argument("--sb3-timesteps", type=int, default=100_000, help="SB3's steps (default: 100000)")
    runner = commands.add_parser("run", help="train every (variant, seed) not yet done, one at a time")
    single = commands.add_parser("one", help="train, evaluate and record one (variant, seed)")
    report = commands.add_parser("report", help="summarise the finished runs")
    for p in (runner, single, report):
        p.add_argument("--out", type=Path, required=True, help="the experiment's folder")
    for p in (runner, single):
        p.add_argument(
            "--set", type=_setting, action="append", default=[], help="a setting over the variants'"
        )
        p.add_argument(
            "--episodes", type=int, default=100, help="evaluation episodes per scenario (default: 100)"
        )
    runner.add_argument("--variants", nargs="+", default=["gru"], choices=list(VARIANTS))
    runner.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    single.add_argument("--variant", required=True, choices=list(VARIANTS))
    single.add_argument("--seed", type=int, required=True)
    report.add_argument("--variants", nargs="+", choices=list(VARIANTS))
    args = parser.parse_args(argv)
    if args.command in (None, "speed"):
        speed(args)
    elif args.command == "run":
        run_all(args.out.resolve(), args.variants, args.seeds, dict(args.set), args.episodes)
    elif args.command == "one":
        one(args.out.resolve(), args.variant, args.seed, dict(args.set), args.episodes)
    else:
        from subenv.atomic import atomic_write_text

        runs = read_runs(args.out, args.variants)
        summary = summarize(runs, hard_scores(args.out, runs))
        text = report_markdown(summary)
        atomic_write_text(args.out / "report.json", json.dumps(summary, indent=1) + "\n")
        atomic_write_text(args.out / "report.md", text)
        plot(args.out, runs)
        plot_failed_episodes(args.out, summary)
        print(text)


if __name__ == "__main__":
    main()
