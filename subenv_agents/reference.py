r"""Multi-seed reference results: PPO, SAC and TD3 (Stable-Baselines3) and the JAX PPO trained with several
seeds as Ray Tune trials, their final policies evaluated on the default suite, and summarised with rliable's
statistics and the benchmark-v1 score.

::

    python -m subenv_agents.reference                       # this machine's budgets (docs/reference/)
    python -m subenv_agents.reference --seeds 10 \
        --timesteps ppo=7000000,sac=600000,td3=300000,ppo_jax=20000000 \
        --address auto                                      # a cluster: the configs' own budgets

Each SB3 trial is :func:`subenv_agents.train.train` of one algorithm's hyperparameter file (its defaults, on
``subenv/Mixed-v0``) with one seed, validated :data:`CURVE_POINTS` times while it trains (the learning
curve: :class:`~subenv_agents.selection.SelectionCallback`, on validation seeds). A ``ppo_jax`` trial is
:func:`subenv_agents.jax_ppo.train_model` of :class:`~subenv_agents.jax_ppo.PPOConfig`'s defaults (the
shipped ``ppo_jax``'s settings: a GRU policy trained on ``subenv/Mixed-v0`` for 20M steps) with one seed; it
has no learning curve here (its training's own is in ``train.json``, and ``benchmarks/jax_ppo.py`` plots
it). Then each trial's **final** policy (not a selected one: no choice made on its results) is evaluated on
the default suite's episodes, the same as the leaderboard's. A trial's success on a scenario is its success
rate over the winnable episodes; its score is the leaderboard's, the benchmark-v1 score pooled over the
suite (:mod:`subenv.evaluation.score`). The classical baselines and the shipped agents (labelled: each is
one run, selected) are evaluated on the same episodes.

Statistics follow Agarwal et al. (2021), "Deep reinforcement learning at the edge of the statistical
precipice" (NeurIPS), with their library rliable: the interquartile mean (IQM) and mean over runs x
scenarios with 95% stratified bootstrap confidence intervals, each scenario's mean over seeds with a
bootstrap interval, performance profiles (the fraction of runs x scenarios above each success
rate), and learning curves as the mean over seeds with a 95% bootstrap band. The score of several
seeds is their scores' mean with a 95% bootstrap interval over the seeds (rliable's, one stratum); that
of one run its own interval, the stratified bootstrap over its episodes (:mod:`subenv.evaluation.score`).
The table is ordered by score, as the leaderboard is.

The folder (``--out``): ``trials/<algo>-seed<k>/`` (each trial's run folder, its ``evaluation.json``
written last), ``scores.csv`` (one row per run and scenario), ``reference.json`` (the plan, the
estimates, the time taken), ``reference.md`` (the tables), ``learning_curves.png`` and
``performance_profiles.png``; every file is written whole or not at all. Run the same command again
to resume: finished trials are kept, an unfinished one is trained again from its start. Needs the
``ray``, ``rl`` and ``stats`` extras, and ``jax-rl`` for ``ppo_jax`` trials.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import shutil
import sys
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any, Final

import numpy as np

from subenv.atomic import atomic_write_text
from subenv.extras import MissingExtra, require
from subenv_agents.config import ALGORITHMS as SB3_ALGORITHMS

__all__ = ["ALGORITHMS", "DEFAULT_TIMESTEPS", "Plan", "main", "run_reference", "summarize_reference"]

ENV_ID: Final = "subenv/Mixed-v0"
"""What every SB3 trial trains on (the shipped agents' training scenario; ``ppo_jax`` trials train on
their defaults', the same)."""
JAX_PPO: Final = "ppo_jax"
ALGORITHMS: Final = (*SB3_ALGORITHMS, JAX_PPO)
"""What a plan can train: the SB3 algorithms of ``subenv_agents/hyperparams/`` and the JAX PPO."""
DEFAULT_TIMESTEPS: Final[dict[str, int]] = {
    "ppo": 1_500_000,
    "sac": 120_000,
    "td3": 300_000,
    JAX_PPO: 20_000_000,
}
"""Steps per trial on this 2-core machine. The SB3 budgets were chosen so that 5 seeds of the three finish
in about 90 minutes (measured alone, one torch thread: PPO ~5,500 steps/s, SAC ~330, TD3 ~800); TD3's is
its config's, PPO's and SAC's are 21% and 20% of theirs (7M, 600k). ``ppo_jax``'s is the shipped agent's
(:class:`~subenv_agents.jax_ppo.PPOConfig`'s default: 7-11 minutes a seed on the quiet machine, both
cores), which adds about 45 minutes."""
CURVE_POINTS: Final = 10
"""Validations per trial while it trains (the learning curve's points)."""
CURVE_EPISODES: Final = 10
"""Validation episodes per selection scenario at each point."""
CONFIDENCE: Final = 0.95
TRIAL_RESULT: Final = "evaluation.json"


@dataclass(frozen=True)
class Plan:
    """What a reference run trains and evaluates.

    Attributes
    ----------
    timesteps : mapping
        Algorithm -> environment steps per trial (rounded up to whole iterations as training rounds).
    seeds : int
        Seeds per algorithm: 0, 1, ..., seeds - 1.
    episodes : int
        Evaluation episodes per scenario of the default suite (its seeds,
        ``subenv.evaluation.DEFAULT_SEED + i``).
    curve_points, curve_episodes : int
        Validations while training, and validation episodes per scenario at each.
    reps : int
        Bootstrap resamples of each interval.
    env_id : str
        The training environment.
    overrides : mapping
        Hyperparameters set for every SB3 trial over its file's (``-params`` style keys); none by default.
    jax_overrides : mapping
        :class:`~subenv_agents.jax_ppo.PPOConfig` fields set for every ``ppo_jax`` trial over its defaults
        (not ``total_timesteps`` or ``seed``: the plan's); none by default.
    """

    timesteps: Mapping[str, int] = field(default_factory=lambda: dict(DEFAULT_TIMESTEPS))
    seeds: int = 5
    episodes: int = 100
    curve_points: int = CURVE_POINTS
    curve_episodes: int = CURVE_EPISODES
    reps: int = 10_000
    env_id: str = ENV_ID
    overrides: Mapping[str, Any] = field(default_factory=dict)
    jax_overrides: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.timesteps:
            raise ValueError("timesteps={} is invalid: name at least one algorithm, e.g. {'ppo': 100000}")
        for algo, steps in self.timesteps.items():
            if algo not in ALGORITHMS:
                raise ValueError(
                    f"timesteps[{algo!r}] is invalid: the algorithm must be one of {list(ALGORITHMS)}"
                )
            _require_int(f"timesteps[{algo!r}]", steps, 1)
        for name in ("total_timesteps", "seed"):
            if name in self.jax_overrides:
                raise ValueError(
                    f"jax_overrides[{name!r}] is invalid: the plan sets it (timesteps['ppo_jax'], the seeds)"
                )
        for name, low in (
            ("seeds", 1),
            ("episodes", 1),
            ("curve_points", 1),
            ("curve_episodes", 1),
            ("reps", 100),
        ):
            _require_int(name, getattr(self, name), low)

    def trials(self) -> list[dict[str, Any]]:
        """One entry per (algorithm, seed): its name (the run folder's) and settings; seed by seed, so that an
        interrupted run has as many seeds of each algorithm as it could."""
        return [
            {"name": f"{algo}-seed{seed}", "algo": algo, "seed": seed, "timesteps": steps}
            for seed in range(self.seeds)
            for algo, steps in self.timesteps.items()
        ]


def _as_dict(plan: Plan) -> dict[str, Any]:
    return asdict(plan) | {
        "timesteps": dict(plan.timesteps),
        "overrides": dict(plan.overrides),
        "jax_overrides": dict(plan.jax_overrides),
    }


def _require_int(name: str, value: Any, low: int) -> None:
    if not (isinstance(value, int) and not isinstance(value, bool) and value >= low):
        raise ValueError(f"{name}={value!r} is invalid: must be an integer >= {low}")


# --- one trial (a Tune worker) ------------------------------------------------------------------
def _trial(config: dict[str, Any], *, plan: dict[str, Any], trials_dir: str) -> None:
    from ray import tune

    from subenv_agents.config import load_config
    from subenv_agents.train import train

    trial = config["trial"]
    run_dir = Path(trials_dir) / trial["name"]
    shutil.rmtree(run_dir, ignore_errors=True)  # an unfinished earlier attempt: trained again from its start
    if trial["algo"] == JAX_PPO:
        timesteps, wall_time_s = _train_jax_ppo(trial, plan["jax_overrides"], run_dir)
    else:
        agent_config = load_config(
            trial["algo"], plan["env_id"], overrides={**plan["overrides"], "n_timesteps": trial["timesteps"]}
        )
        select_freq = max(trial["timesteps"] // plan["curve_points"], 1)
        result = train(
            agent_config,
            seed=trial["seed"],
            run_dir=run_dir,
            eval_freq=0,
            save_freq=0,
            verbose=0,
            progress=False,
            select_freq=select_freq,
            select_episodes=plan["curve_episodes"],
        )
        timesteps, wall_time_s = result.timesteps, result.wall_time_s
    record = {**trial, "timesteps_trained": timesteps, "train_time_s": round(wall_time_s, 1)}
    record = _evaluated(record, run_dir, plan["episodes"])
    tune.report({"score": record["benchmark"]["all"]["score"]})


def _jax_config(timesteps: int, seed: int, overrides: Mapping[str, Any]) -> Any:
    """The ``ppo_jax`` trial's settings: :class:`~subenv_agents.jax_ppo.PPOConfig`'s defaults, ``overrides``,
    the plan's steps and seed (a bad field or value: ValueError naming it)."""
    from subenv_agents.jax_ppo import PPOConfig

    known = {f.name for f in fields(PPOConfig)}
    for name in overrides:
        if name not in known:
            raise ValueError(f"jax_overrides[{name!r}] is invalid: PPOConfig has no such field")
    return PPOConfig(**{**overrides, "total_timesteps": timesteps, "seed": seed})


def _train_jax_ppo(
    trial: Mapping[str, Any], overrides: Mapping[str, Any], run_dir: Path
) -> tuple[int, float]:
    """Train one ``ppo_jax`` trial into ``run_dir`` (a model folder, complete or absent): its steps and
    wall time."""
    from subenv_agents.jax_ppo import train_model

    config = _jax_config(trial["timesteps"], trial["seed"], overrides)
    record = train_model(
        config, run_dir, f"subenv_agents.reference trial {trial['name']}", 0, (), say=lambda line: None
    )
    return int(record["env_steps"]), float(record["wall_time_s"])


def _final_policy(algo: str, run_dir: Path, name: str) -> Any:
    """The controller of a trial's final policy."""
    if algo == JAX_PPO:
        from subenv_agents.jax_ppo import JaxPPOController

        return JaxPPOController(run_dir, name=name)
    from subenv_agents.controller import AgentController
    from subenv_agents.policy import load_agent

    return AgentController(load_agent(run_dir), name=name)


def _evaluated(record: dict[str, Any], run_dir: Path, episodes: int) -> dict[str, Any]:
    """``record`` with its final policy's success and benchmark-v1 scores on the default suite (as it is
    now), written to ``<run_dir>/evaluation.json``."""
    from subenv.evaluation import DEFAULT_SUITE, evaluate
    from subenv_agents.records import score_record

    start = time.perf_counter()
    agent = _final_policy(record["algo"], run_dir, record["name"])
    results = evaluate([agent], DEFAULT_SUITE, episodes, progress=False, keep_trajectories=0)
    record = {
        **record,
        "evaluation_time_s": round(time.perf_counter() - start, 1),
        "scenarios": _scenario_scores(results),
        "benchmark": score_record(results)[record["name"]],
    }
    atomic_write_text(run_dir / TRIAL_RESULT, json.dumps(record, indent=2) + "\n")
    return record


def _scenario_scores(results: Sequence[Any]) -> dict[str, dict[str, Any]]:
    """Per scenario: episodes, winnable ones, successes among each, the score (success over the winnable
    episodes) and the mean plane RMS [rad]."""
    out: dict[str, dict[str, Any]] = {}
    for scenario in dict.fromkeys(r.scenario for r in results):
        rows = [r for r in results if r.scenario == scenario]
        winnable = [r for r in rows if r.winnable is not False]
        wins = sum(r.metrics.success for r in winnable)
        out[scenario] = {
            "episodes": len(rows),
            "winnable": len(winnable),
            "successes": sum(r.metrics.success for r in rows),
            "winnable_successes": wins,
            "score": wins / len(winnable) if winnable else float("nan"),
            "plane_rms_rad": float(np.mean([r.metrics.plane_rms_rad for r in rows])),
        }
    return out


# --- the run -----------------------------------------------------------------------------------
def run_reference(
    out_dir: str | Path,
    plan: Plan = Plan(),
    *,
    max_concurrent: int = 2,
    address: str | None = None,
    progress: bool = True,
    baselines: Sequence[str] | None = None,
) -> dict[str, Any]:
    """Train and evaluate every trial of ``plan`` not yet finished in ``out_dir`` (``max_concurrent`` at
    once, on a local Ray instance or the cluster at ``address``), then write the summary
    (:func:`summarize_reference`, with ``baselines``) and return it."""
    require("ray", "the multi-seed reference results", "ray", "pandas")
    require("rl", "the multi-seed reference results", "stable_baselines3")
    require("stats", "the multi-seed reference results", "rliable")
    if JAX_PPO in plan.timesteps:
        require("jax-rl", "the multi-seed reference results' ppo_jax trials", "jax", "optax")
    from ray import tune

    from subenv_agents.config import load_config
    from subenv_agents.tune import fit

    _require_int("max_concurrent", max_concurrent, 1)
    for algo, steps in plan.timesteps.items():  # (unknown id or bad config: now)
        if algo == JAX_PPO:
            _jax_config(steps, 0, plan.jax_overrides)
        else:
            load_config(algo, plan.env_id, overrides={**plan.overrides, "n_timesteps": steps})
    out = Path(out_dir).resolve()
    trials_dir = out / "trials"
    trials_dir.mkdir(parents=True, exist_ok=True)
    pending = [t for t in plan.trials() if not (trials_dir / t["name"] / TRIAL_RESULT).exists()]
    started = time.perf_counter()
    if pending:
        say = print if progress else (lambda *a, **k: None)
        say(
            f"reference: {len(pending)} of {len(plan.trials())} trials to run "
            f"({', '.join(f'{a} {n:,} steps' for a, n in plan.timesteps.items())}; {max_concurrent} at once)",
            file=sys.stderr,
        )
        trainable = tune.with_parameters(_trial, plan=_as_dict(plan), trials_dir=str(trials_dir))
        fit(
            lambda: tune.Tuner(
                trainable,
                param_space={"trial": tune.grid_search(pending)},
                tune_config=tune.TuneConfig(max_concurrent_trials=max_concurrent),
                # A trial whose worker dies is started once more (from its start: _trial clears its folder).
                run_config=tune.RunConfig(
                    name="reference",
                    storage_path=str(out / "tune"),
                    verbose=0,
                    failure_config=tune.FailureConfig(max_failures=1),
                    callbacks=[_progress_lines(len(pending), say)],
                ),
            ),
            address,
        )
    run_time_s = (
        time.perf_counter() - started if pending else None
    )  # (None: a summary of earlier runs' trials)
    return summarize_reference(out, plan, run_time_s=run_time_s, baselines=baselines)


def _progress_lines(total: int, say: Any) -> Any:
    """A Tune callback printing a line per finished trial, with the time so far and an estimate of what
    is left (Tune's own reporter prints a table every few seconds, which a log does not need)."""
    from ray.tune import Callback

    class ProgressLines(Callback):
        def __init__(self) -> None:
            self.done, self.start = 0, time.perf_counter()

        def on_trial_complete(self, iteration: int, trials: list[Any], trial: Any, **info: Any) -> None:
            self.done += 1
            elapsed = time.perf_counter() - self.start
            eta = elapsed / self.done * (total - self.done)
            say(
                f"reference: {trial.config['trial']['name']} done ({self.done}/{total}, "
                f"{elapsed / 60:.1f} min, about {eta / 60:.0f} min left)",
                file=sys.stderr,
            )

    return ProgressLines()


# --- the statistics ------------------------------------------------------------------------------
def summarize_reference(
    out_dir: str | Path,
    plan: Plan = Plan(),
    *,
    run_time_s: float | None = None,
    baselines: Sequence[str] | None = None,
) -> dict[str, Any]:
    """Rliable's estimates from the finished trials in ``out_dir``, next to the default comparison's
    controllers on the same episodes (``baselines``: registered names; default: every controller of the
    default comparison). Writes ``scores.csv``, ``reference.json``, ``reference.md`` and the figures."""
    require("stats", "the multi-seed reference results", "rliable")
    from rliable import library as rly
    from rliable import metrics

    from subenv.evaluation import DEFAULT_SUITE, evaluate, get_suite
    from subenv.evaluation.rollout import resolve_controllers
    from subenv.evaluation.score import POOLED
    from subenv_agents.records import score_record

    out = Path(out_dir)
    records = []
    for trial in plan.trials():
        path = out / "trials" / trial["name"] / TRIAL_RESULT
        if not path.exists():
            raise FileNotFoundError(
                f"{str(path)!r} is missing: trial {trial['name']} has not finished "
                "(run the reference again to finish it)"
            )
        records.append(json.loads(path.read_text()))
    scenarios = list(get_suite(DEFAULT_SUITE).scenarios)
    for k, record in enumerate(records):
        if (
            list(record["scenarios"]) != scenarios
            or record["scenarios"][scenarios[0]]["episodes"] != plan.episodes
            or "benchmark" not in record
        ):
            # The default suite changed since the trial was evaluated (or the plan's episodes, or the record
            # predates the score): its final policy is evaluated again on the suite as it is, the training
            # kept.
            records[k] = _evaluated(record, out / "trials" / record["name"], plan.episodes)
    controllers = resolve_controllers(list(baselines) if baselines is not None else None)
    results = evaluate(controllers, DEFAULT_SUITE, plan.episodes, progress=False, keep_trajectories=0)
    fixed = {c.name: _scenario_scores([r for r in results if r.controller == c.name]) for c in controllers}
    fixed_benchmark = score_record(results)
    shipped = _shipped_names()

    rows: list[dict[str, Any]] = []
    benchmark: dict[str, list[Mapping[str, Any]]] = {}  # name -> each run's pooled benchmark-v1 score
    for rec in records:
        name = rec["algo"].upper()
        rows += [
            {
                "name": name,
                "kind": "multi-seed",
                "seed": rec["seed"],
                "scenario": s,
                **rec["scenarios"][s],
                **_benchmark_columns(rec["benchmark"][s]),
            }
            for s in scenarios
        ]
        benchmark.setdefault(name, []).append(rec["benchmark"][POOLED])
    for name, per in fixed.items():
        kind = "shipped agent (selected)" if name in shipped else "baseline"
        rows += [
            {
                "name": name,
                "kind": kind,
                "seed": "",
                "scenario": s,
                **per[s],
                **_benchmark_columns(fixed_benchmark[name][s]),
            }
            for s in scenarios
        ]
        benchmark[name] = [fixed_benchmark[name][POOLED]]

    names = list(dict.fromkeys(r["name"] for r in rows))
    kinds = {r["name"]: r["kind"] for r in rows}
    score: dict[str, np.ndarray] = {}
    for name in names:
        mine = [r for r in rows if r["name"] == name]
        runs = list(dict.fromkeys(r["seed"] for r in mine))
        score[name] = np.array(
            [
                [next(r["score"] for r in mine if r["seed"] == run and r["scenario"] == s) for s in scenarios]
                for run in runs
            ]
        )
    rng = np.random.RandomState(0)
    aggregate, aggregate_ci = _estimates(
        score, lambda x: np.array([metrics.aggregate_iqm(x), metrics.aggregate_mean(x)]), plan.reps, rng
    )
    per_scenario: dict[str, dict[str, list[float]]] = {}
    for j, s in enumerate(scenarios):
        point, ci = _estimates({n: score[n][:, [j]] for n in names}, metrics.aggregate_mean, plan.reps, rng)
        per_scenario[s] = {n: [float(point[n]), *(float(v) for v in np.ravel(ci[n]))] for n in names}
    taus = np.linspace(0.0, 1.0, 41)
    profiles, profile_ci = rly.create_performance_profile(score, taus, reps=min(plan.reps, 2000))
    curves = _learning_curves(out, plan, records, rng)
    scores_v1 = _benchmark_scores(benchmark, plan.reps, rng)

    summary = {
        "plan": _as_dict(plan),
        "scenarios": scenarios,
        "score": "success rate over the winnable episodes of each scenario",
        "confidence": CONFIDENCE,
        "runs": {n: int(score[n].shape[0]) for n in names},
        "kinds": kinds,
        "benchmark_score": scores_v1,
        "aggregate": {
            n: {
                "iqm": float(aggregate[n][0]),
                "iqm_ci": [float(v) for v in aggregate_ci[n][:, 0]],
                "mean": float(aggregate[n][1]),
                "mean_ci": [float(v) for v in aggregate_ci[n][:, 1]],
            }
            for n in names
        },
        "per_scenario": per_scenario,
        "learning_curves": curves,
        "time": {
            "trials_run_s": None if run_time_s is None else round(run_time_s, 1),
            "train_s": {a: [r["train_time_s"] for r in records if r["algo"] == a] for a in plan.timesteps},
            "timesteps_trained": {
                a: sorted({r["timesteps_trained"] for r in records if r["algo"] == a}) for a in plan.timesteps
            },
        },
    }
    _write_scores(out / "scores.csv", rows)
    atomic_write_text(out / "reference.json", json.dumps(summary, indent=2) + "\n")
    atomic_write_text(out / "reference.md", reference_markdown(summary))
    _plot(out, summary, profiles, profile_ci, taus)
    return summary


def _estimates(
    scores: Mapping[str, np.ndarray], statistic: Any, reps: int, rng: np.random.RandomState
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Rliable's point estimates and stratified bootstrap intervals (runs resampled within each scenario),
    reproducible through ``rng`` (rliable hands arch a RandomState, which arch now warns about)."""
    from rliable import library as rly

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="random_state is deprecated", category=FutureWarning)
        return rly.get_interval_estimates(
            scores, statistic, reps=reps, confidence_interval_size=CONFIDENCE, random_state=rng
        )


def _benchmark_columns(entry: Mapping[str, Any]) -> dict[str, Any]:
    """A run's benchmark-v1 columns on one scenario (0-1000): the mean quality of its won episodes and
    its score."""
    return {"quality": entry["quality"], "benchmark_score": entry["score"]}


def _benchmark_scores(
    benchmark: Mapping[str, Sequence[Mapping[str, Any]]], reps: int, rng: np.random.RandomState
) -> dict[str, dict[str, Any]]:
    """Each name's benchmark-v1 score pooled over the suite: one run's with its interval over the episodes
    (:mod:`subenv.evaluation.score`'s stratified bootstrap); several runs' mean with a 95% bootstrap
    interval over the runs (rliable's, the runs one stratum)."""
    from rliable import metrics

    out: dict[str, dict[str, Any]] = {}
    for name, entries in benchmark.items():
        runs = [float(e["score"]) for e in entries]
        if len(runs) == 1:
            interval = [float(entries[0]["score_ci_low"]), float(entries[0]["score_ci_high"])]
            out[name] = {"score": runs[0], "ci": interval, "runs": runs, "interval_over": "episodes"}
            continue
        point, ci = _estimates({name: np.array(runs)[:, None]}, metrics.aggregate_mean, reps, rng)
        out[name] = {
            "score": float(point[name]),
            "ci": [float(v) for v in np.ravel(ci[name])],
            "runs": runs,
            "interval_over": "seeds",
        }
    return out


def _shipped_names() -> set[str]:
    """The shipped agents' controller names: the folders of ``subenv_agents/models/`` (SB3's and
    ``ppo_jax``)."""
    from subenv_agents import MODELS_DIR

    return {p.name for p in MODELS_DIR.iterdir() if p.is_dir()} if MODELS_DIR.is_dir() else set()


def _learning_curves(
    out: Path, plan: Plan, records: Sequence[Mapping[str, Any]], rng: np.random.RandomState
) -> dict[str, dict[str, list[float]]]:
    """Per algorithm: the validation success at each point (mean over seeds) with a bootstrap band."""
    curves = {}
    for algo in [a for a in plan.timesteps if a != JAX_PPO]:  # (ppo_jax trials make no selection.json)
        histories = [
            json.loads((out / "trials" / r["name"] / "selection.json").read_text())["history"]
            for r in records
            if r["algo"] == algo
        ]
        points = min(len(h) for h in histories)
        steps = [h["timestep"] for h in histories[0][:points]]
        scores = np.array([[h["success_rate"] for h in history[:points]] for history in histories])[
            :, None, :
        ]
        point, ci = _estimates({algo: scores}, lambda x: np.mean(x, axis=(0, 1)), plan.reps, rng)
        curves[algo.upper()] = {
            "timesteps": steps,
            "mean": point[algo].tolist(),
            "ci_low": ci[algo][0].tolist(),
            "ci_high": ci[algo][1].tolist(),
        }
    return curves


def _write_scores(path: Path, rows: Sequence[Mapping[str, Any]]) -> None:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(path, buffer.getvalue())


def _interval(point: float, low: float, high: float, runs: int) -> str:
    if runs == 1:
        return f"{100 * point:.0f}"
    return f"{100 * point:.0f} [{100 * low:.0f}, {100 * high:.0f}]"


def reference_markdown(summary: Mapping[str, Any]) -> str:
    """The reference table, best score first: the benchmark-v1 score with its 95% interval, then the
    success's IQM and mean over runs x scenarios, and each scenario's mean over runs, in percent with 95%
    stratified bootstrap intervals (none for a single run)."""
    scenarios, runs, kinds = summary["scenarios"], summary["runs"], summary["kinds"]
    scores = summary["benchmark_score"]
    order = sorted(
        summary["aggregate"], key=lambda n: (-scores[n]["score"], -summary["aggregate"][n]["iqm"], n)
    )
    head = ["controller", "runs", "score [95% CI]", "IQM", "mean", *scenarios]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for n in order:
        agg = summary["aggregate"][n]
        label = (
            n
            if kinds[n] == "baseline"
            else (f"{n} (shipped, selected)" if kinds[n].startswith("shipped") else f"**{n}**")
        )
        low, high = scores[n]["ci"]
        cells = [
            label,
            str(runs[n]),
            f"{scores[n]['score']:.1f} [{low:.1f}, {high:.1f}]",
            _interval(agg["iqm"], *agg["iqm_ci"], runs[n]),
            _interval(agg["mean"], *agg["mean_ci"], runs[n]),
        ]
        cells += [_interval(*summary["per_scenario"][s][n], runs[n]) for s in scenarios]
        lines.append("| " + " | ".join(cells) + " |")
    plan = summary["plan"]
    steps = ", ".join(f"{a.upper()} {n:,}" for a, n in plan["timesteps"].items())
    jax_env = plan.get("jax_overrides", {}).get("env_id", ENV_ID)  # (PPOConfig's default is ENV_ID)
    if JAX_PPO in plan["timesteps"] and jax_env != plan["env_id"]:
        steps += f" (PPO_JAX on {jax_env})"
    return "\n".join(
        [
            (
                f"{plan['episodes']} episodes per scenario of the default suite; multi-seed rows: final "
                f"policies after {steps} steps on {plan['env_id']}. Score: the benchmark-v1 score "
                "(0-1000) pooled over the suite, of several seeds their mean with a 95% bootstrap interval "
                "over the seeds, of one run its interval over the episodes. Then success over the winnable "
                "episodes [%]: IQM and mean over runs x scenarios and each scenario's mean over seeds with "
                f"95% stratified bootstrap intervals (rliable, {plan['reps']:,} resamples)."
            ),
            "",
            *lines,
            "",
        ]
    )


def _plot(
    out: Path,
    summary: Mapping[str, Any],
    profiles: Mapping[str, np.ndarray],
    profile_ci: Mapping[str, np.ndarray],
    taus: np.ndarray,
) -> None:
    require("plot", "the reference figures", "matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from subenv.evaluation.plots import save_figure

    fig, ax = plt.subplots(figsize=(7, 4.2))
    for algo, curve in summary["learning_curves"].items():
        x = np.array(curve["timesteps"]) / 1e6
        (line,) = ax.plot(
            x,
            100 * np.array(curve["mean"]),
            marker="o",
            ms=3,
            label=f"{algo.upper()} ({summary['runs'][algo]} seeds)",
        )
        ax.fill_between(
            x,
            100 * np.array(curve["ci_low"]),
            100 * np.array(curve["ci_high"]),
            color=line.get_color(),
            alpha=0.2,
        )
    ax.set_xscale("log")
    ax.set_xlabel("environment steps [millions] (log scale)")
    ax.set_ylabel("validation success [%]")
    ax.set_ylim(-2, 102)
    ax.set_title(
        "Learning curves on Mixed: validation success on LowSpeed, NearCritical, SpeedTransient\n"
        "(mean over seeds, 95% bootstrap band)",
        fontsize=9,
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, out / "learning_curves.png")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(8.4, 4.2))
    for name, profile in profiles.items():
        multi = summary["runs"][name] > 1
        shipped = summary["kinds"][name].startswith("shipped")
        (line,) = ax.plot(
            100 * taus,
            profile,
            lw=2.0 if multi else 1.2,
            ls="-" if multi else "--",
            label=f"{name} ({summary['runs'][name]} seeds)"
            if multi
            else f"{name} (shipped)"
            if shipped
            else name,
        )
        if multi:
            ax.fill_between(
                100 * taus, profile_ci[name][0], profile_ci[name][1], color=line.get_color(), alpha=0.15
            )
    ax.set_xlabel(r"success over winnable episodes $\tau$ [%]")
    ax.set_ylabel(r"fraction of runs x scenarios with success > $\tau$")
    ax.set_title("Performance profiles on the default suite (dashed: one deterministic run)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    save_figure(fig, out / "performance_profiles.png")
    plt.close(fig)


def _timesteps(text: str) -> dict[str, int]:
    out = {}
    for part in text.split(","):
        algo, sep, steps = part.partition("=")
        if not sep or not steps.strip().isdigit():
            raise ValueError(
                f"--timesteps {text!r} is invalid: must be algo=steps[,algo=steps...], "
                "e.g. ppo=100000,sac=50000"
            )
        out[algo.strip()] = int(steps)
    return out


def main(argv: list[str] | None = None) -> int:
    """``python -m subenv_agents.reference``: run the multi-seed reference and print its table; exits
    with a one-line message on bad arguments or a missing extra."""
    parser = argparse.ArgumentParser(
        prog="python -m subenv_agents.reference", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "--timesteps",
        default=",".join(f"{a}={n}" for a, n in DEFAULT_TIMESTEPS.items()),
        help="algorithms and steps per trial (default: %(default)s)",
    )
    parser.add_argument("--seeds", type=int, default=5, help="seeds per algorithm (default: %(default)s)")
    parser.add_argument(
        "--episodes", type=int, default=100, help="evaluation episodes per scenario (default: %(default)s)"
    )
    parser.add_argument("--max-concurrent", type=int, default=2, help="trials at once (default: %(default)s)")
    parser.add_argument("--out", default="results/reference", help="results folder (default: %(default)s)")
    parser.add_argument("--address", help="a Ray cluster's address; default: a local Ray instance")
    args = parser.parse_args(argv)
    try:
        plan = Plan(timesteps=_timesteps(args.timesteps), seeds=args.seeds, episodes=args.episodes)
        summary = run_reference(args.out, plan, max_concurrent=args.max_concurrent, address=args.address)
    except (ValueError, FileNotFoundError, RuntimeError, MissingExtra) as exc:
        raise SystemExit(f"subenv_agents.reference: {exc}") from None
    print(reference_markdown(summary))
    print(
        f"written to {args.out}/: reference.md, reference.json, scores.csv, learning_curves.png, "
        "performance_profiles.png"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
