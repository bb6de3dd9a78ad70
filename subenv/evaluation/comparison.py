"""The comparison behind ``subenv evaluate``: the evaluation's stages, one after the other.

1. **resolve** (:func:`subenv.evaluation.plan.resolve`): the suite, the controllers, the episodes and
   seeds, the vehicle and the environment's settings, once, each checked before the first episode
   (with an existing output folder or one that cannot be created, and a missing matplotlib);
2. **roll out** (:func:`subenv.evaluation.rollout.roll_out`), batched, each batch then
3. **classified** (:mod:`subenv.evaluation.classify`: winnable, and whether the score counts it) and
4. **measured** (:mod:`subenv.evaluation.measure`, :mod:`subenv.evaluation.metrics`);
5. **report**: the scores with their intervals and the paired comparisons
   (:mod:`subenv.evaluation.score`), the tables (:mod:`subenv.evaluation.results`) and the figures
   (:mod:`subenv.evaluation.plots`), written as::

    <out_dir>/
        leaderboard.md      the score per controller (and per scenario), success, quality, intervals,
                            paired comparisons, success and failures per scenario
        summary.md          every metric per controller x scenario, with intervals
        summary.csv         the same, machine-readable
        results.csv         the tidy per-episode table (one row per controller x scenario x episode)
        run.json            what was run (suite, scenarios, episodes, seeds, controllers, settings,
                            tolerances) and the scores, intervals and paired tests
        plots/trajectories_<Scenario>.png   a typical episode of each outcome that occurred
        plots/metrics_vs_speed.png          success rate and IAE against u / u_cr, per scenario

The fields and units of ``results.csv`` and ``run.json`` are :mod:`subenv.evaluation.results_format`.

The folder appears complete or not at all, and replaces an earlier one atomically
(:func:`subenv.atomic.atomic_output_dir`); it holds a marker file saying it is a result of
``subenv evaluate``, and ``overwrite`` replaces only such a folder.

A controller that fails (:class:`~subenv.evaluation.failures.ControllerFailure`: an exception in its
``reset`` or ``act``, an action the environment refuses) costs no other controller its results. It
goes on with its other scenarios; the scenarios it completed are in ``results.csv`` and the summary
(every row there is complete, on the same seeds as everyone's), the one it failed on has no episodes.
The leaderboard and the figures leave it out (a leaderboard must not rank an incomplete controller),
listing its failures instead, and ``run.json`` records them.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

from subenv.evaluation import metrics as m
from subenv.evaluation import score as sc
from subenv.evaluation.controller import Controller, informed
from subenv.evaluation.failures import ControllerFailure
from subenv.evaluation.measure import EpisodeResult
from subenv.evaluation.plan import Plan, resolve, resolve_controllers
from subenv.evaluation.results import (
    atomic_output_dir,
    atomic_write_text,
    episode_table,
    failures_markdown,
    leaderboard_markdown,
    summarize,
    summary_markdown,
    write_csv,
)
from subenv.evaluation.results_format import FORMAT_VERSION
from subenv.evaluation.rollout import roll_out
from subenv.evaluation.stats import CONFIDENCE_LEVEL
from subenv.evaluation.suites import BENCHMARK_SUITES, DEFAULT_SEED, DEFAULT_SUITE, Suite
from subenv.evaluation.trajectory import Trajectory
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "DEFAULT_OUT_DIR",
    "RESULTS_KIND",
    "Comparison",
    "run_benchmark",
    "run_comparison",
    "write_comparison",
]

DEFAULT_OUT_DIR = "results/evaluation"

RESULTS_KIND = "subenv evaluate"
"""What a results folder's marker file says (:data:`subenv.atomic.MARKER_FILE`): ``overwrite``
replaces only a folder that says so."""


@dataclass(frozen=True)
class Comparison:
    """What :func:`run_comparison` ran and produced.

    Attributes
    ----------
    suite : Suite
    controllers : tuple of str
        Controller names, in the order run.
    episodes, seed : int
        Episodes per scenario and controller; base seed (episode i: ``seed + i``).
    results : list of EpisodeResult
        Per episode, ordered by controller, scenario, episode (none of a controller on a scenario
        where it failed).
    summary : list of dict
        Aggregates per controller x scenario (:func:`~subenv.evaluation.results.summarize`).
    leaderboard : str
        The Markdown leaderboard (what ``subenv evaluate`` prints).
    out_dir : Path or None
        The folder written (None if not asked to write).
    elapsed_s : float
        Wall-clock time of the rollouts [s] (not counting tables and plots).
    failures : tuple of ControllerFailure
        The controllers' failures, in the order they happened (empty when every controller ran
        every episode); a controller with one is not ranked.
    scores : list of Score
        Per controller that completed the suite: its score on each scenario and pooled
        (:func:`~subenv.evaluation.score.scores`).
    paired : list of PairedComparison
        Every pair of those controllers, pooled and per scenario
        (:func:`~subenv.evaluation.score.paired_comparisons`).
    env_kwargs : dict
        The environment's settings the caller gave.
    informed : tuple of str
        The controllers told the environment's settings.
    report_s : float
        Wall-clock time of the scores, intervals, paired tests and tables [s].
    """

    suite: Suite
    controllers: tuple[str, ...]
    episodes: int
    seed: int
    results: list[EpisodeResult] = field(repr=False)
    summary: list[dict[str, Any]] = field(repr=False)
    leaderboard: str = field(repr=False)
    out_dir: Path | None
    elapsed_s: float
    failures: tuple[ControllerFailure, ...] = ()
    scores: list[sc.Score] = field(default_factory=list, repr=False)
    paired: list[sc.PairedComparison] = field(default_factory=list, repr=False)
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    informed: tuple[str, ...] = ()
    report_s: float = 0.0
    vehicle_name: str = "suboff"

    @property
    def failed(self) -> tuple[str, ...]:
        """The controllers that failed on some scenario, in the order run."""
        names = {f.controller for f in self.failures}
        return tuple(name for name in self.controllers if name in names)


def run_comparison(
    controllers: Sequence[Controller | str] | None = None,
    suite: Suite | str | Sequence[str] | None = DEFAULT_SUITE,
    episodes: int | None = None,
    out_dir: str | os.PathLike[str] | None = DEFAULT_OUT_DIR,
    overwrite: bool = False,
    seed: int = DEFAULT_SEED,
    progress: bool = True,
    *,
    plots: bool = True,
    vehicle: str | Vehicle = "suboff",
    env_kwargs: Mapping[str, Any] | None = None,
) -> Comparison:
    """Compare controllers on a suite and write the results folder.

    Parameters
    ----------
    controllers : sequence of Controller or str, optional
        Registered names (``subenv.evaluation.controller_names()``; ``<name>:uninformed`` for one not
        told the environment's settings) or instances; None runs every registered controller.
    suite : Suite, str or sequence of str
        A registered suite name (``suite_names()``), a :class:`Suite`, or scenario names.
    episodes : int, optional
        Episodes per scenario and controller; default the suite's.
    out_dir : path, optional
        The results folder; None writes nothing.
    overwrite : bool
        Replace ``out_dir`` if it is an earlier results folder (otherwise FileExistsError, raised
        before any episode).
    seed : int
        Base seed; episode i of every scenario is ``reset(seed=seed + i)`` for every controller.
    progress : bool
        Progress bar on stderr.
    plots : bool
        Write the figures (needs matplotlib, checked before any episode).
    vehicle : str or Vehicle
        The vehicle of every environment.
    env_kwargs : mapping, optional
        The environment's other arguments (:func:`subenv.evaluation.evaluate`), recorded in ``run.json``.

    Raises
    ------
    ValueError
        Unknown controller, suite or scenario (the message lists the known names); bad
        ``episodes``, ``seed`` or ``env_kwargs``.
    FileExistsError
        ``out_dir`` exists and ``overwrite`` is false, or it is not an earlier results folder.
    OutputDirError
        ``out_dir`` cannot be created (a file in the way, no permission); a ValueError.
    ImportError
        ``plots`` without matplotlib installed.
    """
    plan = resolve(controllers, suite, episodes, seed, vehicle=vehicle, env_kwargs=env_kwargs)
    (comparison,) = _run_plans([plan], out_dir, overwrite, progress, plots, nested=False)
    return comparison


def run_benchmark(
    controllers: Sequence[Controller | str] | None = None,
    suites: Sequence[Suite | str] = BENCHMARK_SUITES,
    episodes: int | None = None,
    out_dir: str | os.PathLike[str] | None = DEFAULT_OUT_DIR,
    overwrite: bool = False,
    seed: int = DEFAULT_SEED,
    progress: bool = True,
    *,
    plots: bool = True,
    vehicle: str | Vehicle = "suboff",
    env_kwargs: Mapping[str, Any] | None = None,
) -> list[Comparison]:
    """Compare controllers on several suites, each its own leaderboard (``subenv evaluate`` without
    ``--suite``: :data:`~subenv.evaluation.suites.BENCHMARK_SUITES`, the default and the Hard track).

    The arguments are :func:`run_comparison`'s, for every suite (``episodes`` None: each suite's own).
    Every suite is resolved and checked before the first episode. ``out_dir`` holds one results folder
    per suite, ``<out_dir>/<suite>/`` (:func:`run_comparison`'s files), and ``leaderboard.md``, the
    suites' leaderboards one after the other; it appears complete or not at all.
    """
    plans = [
        resolve(controllers, suite, episodes, seed, vehicle=vehicle, env_kwargs=env_kwargs)
        for suite in suites
    ]
    names = [plan.suite.name for plan in plans]
    if len(set(names)) != len(names):
        raise ValueError(f"suites={names!r} is invalid: each suite once")
    return _run_plans(plans, out_dir, overwrite, progress, plots, nested=True)


def _run_plans(
    plans: Sequence[Plan],
    out_dir: str | os.PathLike[str] | None,
    overwrite: bool,
    progress: bool,
    plots: bool,
    *,
    nested: bool,
) -> list[Comparison]:
    """Roll out, classify, measure and report each plan; write the results folder (each plan's in a
    subfolder named after its suite where ``nested``)."""
    if out_dir is not None and plots:
        from subenv.evaluation.plots import require_matplotlib

        require_matplotlib()
    # The results folder is created (in its temporary place) before the first episode, so that a
    # folder that cannot be written fails now, not after the rollouts.
    folder_block = (
        contextlib.nullcontext()
        if out_dir is None
        else atomic_output_dir(out_dir, overwrite=overwrite, kind=RESULTS_KIND)
    )
    comparisons = []
    with folder_block as folder:
        for plan in plans:
            start = time.perf_counter()
            failures: list[ControllerFailure] = []
            results = roll_out(plan, progress, keep_trajectories=1, on_failure=failures.append)
            elapsed = time.perf_counter() - start
            if progress:  # (what follows the progress line's 100% takes seconds: say what it is)
                writes = "" if folder is None else " and writing the tables" + (" and plots" if plots else "")
                print(f"(scoring the {len(results)} episodes{writes})", file=sys.stderr, flush=True)
            where = None if out_dir is None else Path(out_dir) / (plan.suite.name if nested else "")
            comparison = report(plan, results, failures, elapsed, out_dir=where)
            if folder is not None:
                inside = folder / plan.suite.name if nested else folder
                inside.mkdir(exist_ok=True)
                _write_files(
                    comparison, inside, plots=plots, controllers=plan.controllers, vehicle=plan.vehicle
                )
            comparisons.append(comparison)
        if folder is not None and nested:
            atomic_write_text(folder / "leaderboard.md", "\n".join(c.leaderboard for c in comparisons))
    return comparisons


def report(
    plan: Plan,
    results: list[EpisodeResult],
    failures: Sequence[ControllerFailure] = (),
    elapsed_s: float = math.nan,
    *,
    out_dir: Path | None = None,
) -> Comparison:
    """The report stage of ``plan``'s ``results``: scores with intervals, paired comparisons, tables."""
    start = time.perf_counter()
    failed = {f.controller for f in failures}
    ranked = [r for r in results if r.controller not in failed]
    every_score = sc.scores(results)  # (each controller's on its own: the failed ones' for the summary)
    score_table = [s for s in every_score if s.controller not in failed]
    summary = summarize(results, score_table=every_score)
    board = leaderboard_markdown(
        ranked,
        title=f"Leaderboard: suite '{plan.suite.name}'",
        failures=failures,
        score_table=score_table,
        scored_by=plan.suite.scored_by,
    )
    paired = sc.paired_comparisons(ranked)
    return Comparison(
        suite=plan.suite,
        controllers=tuple(c.name for c in plan.controllers),
        episodes=plan.episodes,
        seed=plan.seed,
        results=results,
        summary=summary,
        leaderboard=board,
        out_dir=out_dir,
        elapsed_s=elapsed_s,
        failures=tuple(failures),
        scores=score_table,
        paired=paired,
        env_kwargs=dict(plan.env_kwargs),
        informed=tuple(c.name for c in plan.controllers if informed(c)),
        report_s=time.perf_counter() - start,
        vehicle_name=plan.vehicle_name,
    )


def _json_safe(value: Any) -> Any:
    """``value`` with every nan or inf float made None (JSON has neither)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value


def _run_record(comparison: Comparison, controllers: Sequence[Controller] | None) -> dict[str, Any]:
    try:
        version = metadata.version("subenv")
    except metadata.PackageNotFoundError:
        version = "unknown"
    suite = comparison.suite
    by_name = {c.name: c for c in controllers or ()}
    failed = comparison.failed
    record = {
        "format": FORMAT_VERSION,
        "subenv_version": version,
        "suite": suite.name,
        "scenarios": list(suite.scenarios),
        "max_duration_s": suite.max_duration_s,
        "vehicle": comparison.vehicle_name,
        "episodes": comparison.episodes,
        "seeds": [comparison.seed, comparison.seed + comparison.episodes - 1],
        "env_kwargs": comparison.env_kwargs,
        "scored_by": suite.scored_by,
        "controllers": [
            {"name": name}
            | (
                {"control": by_name[name].control, "alpha": float(by_name[name].alpha)}
                if name in by_name
                else {}
            )
            | {"informed": name in comparison.informed, "complete": name not in failed}
            for name in comparison.controllers
        ],
        "failures": [dataclasses.asdict(f) | {"message": f.message} for f in comparison.failures],
        "depth_tolerance_m": m.DEPTH_TOLERANCE_M,
        "hold_window_s": m.HOLD_WINDOW_S,
        "saturation_level": m.SATURATION_LEVEL,
        "pinned_fraction": m.PINNED_FRACTION,
        "non_level_pitch_deg": math.degrees(m.NON_LEVEL_PITCH_RAD),
        "steady_pitch_rate_degps": math.degrees(m.STEADY_PITCH_RATE_RADPS),
        "steady_depth_change_m": m.STEADY_DEPTH_CHANGE_M,
        "regulation_band_m": m.REGULATION_BAND_M,
        "approach_s": m.APPROACH_S,
        "confidence_level": CONFIDENCE_LEVEL,
        "score": {
            "formula": sc.SCORE_FORMULA,
            "quality": f"q = {m.QUALITY_ACCURACY_WEIGHT:g} a + {m.QUALITY_EFFORT_WEIGHT:g} (1 - e^2)",
            "quality_accuracy_weight": m.QUALITY_ACCURACY_WEIGHT,
            "quality_effort_weight": m.QUALITY_EFFORT_WEIGHT,
            "bootstrap_resamples": sc.BOOTSTRAP_RESAMPLES,
            "bootstrap_seed": sc.BOOTSTRAP_SEED,
        },
        "scores": [s.as_dict() for s in comparison.scores],
        "paired": [p.as_dict() for p in comparison.paired],
        "rollout_seconds": round(comparison.elapsed_s, 2),
        "report_seconds": round(comparison.report_s, 2),
    }
    return dict(_json_safe(record))


def write_comparison(
    comparison: Comparison,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    plots: bool = True,
    controllers: Sequence[Controller] | None = None,
    vehicle: str | Vehicle = "suboff",
) -> Path:
    """Write the results folder of ``comparison`` (complete or not at all); returns its path.

    The plots replay the episodes they show from their seeds, with ``controllers`` (default: the
    registered ones of the comparison's names) on ``vehicle``, which must be the run's.
    """
    with atomic_output_dir(out_dir, overwrite=overwrite, kind=RESULTS_KIND) as folder:
        _write_files(comparison, folder, plots=plots, controllers=controllers, vehicle=vehicle)
    return Path(out_dir)


def _write_files(
    comparison: Comparison,
    folder: Path,
    *,
    plots: bool,
    controllers: Sequence[Controller] | None,
    vehicle: str | Vehicle,
) -> None:
    write_csv(folder / "results.csv", episode_table(comparison.results))
    write_csv(folder / "summary.csv", comparison.summary)
    atomic_write_text(folder / "leaderboard.md", comparison.leaderboard)
    atomic_write_text(
        folder / "summary.md",
        summary_markdown(comparison.summary, title=f"Suite '{comparison.suite.name}'")
        + failures_markdown(comparison.failures),
    )
    atomic_write_text(
        folder / "run.json",
        json.dumps(_run_record(comparison, controllers), indent=2, allow_nan=False) + "\n",
    )
    # The figures compare the controllers that completed the suite (and replay no failed controller).
    shown = [r for r in comparison.results if r.controller not in comparison.failed]
    if plots and shown:
        from subenv.evaluation.plots import plot_metrics_vs_speed, plot_outcomes, replay_trajectory

        by_name = {c.name: c for c in controllers or resolve_controllers(list(comparison.controllers))}

        def trajectory_of(r: EpisodeResult) -> Trajectory:
            return replay_trajectory(
                r,
                by_name[r.controller],
                vehicle=vehicle,
                max_duration_s=comparison.suite.max_duration_s,
                env_kwargs=comparison.env_kwargs,
            )

        for scenario in comparison.suite.scenarios:
            mine = [r for r in shown if r.scenario == scenario]
            if mine:
                plot_outcomes(mine, folder / "plots" / f"trajectories_{scenario}.png", trajectory_of)
        plot_metrics_vs_speed(shown, folder / "plots" / "metrics_vs_speed.png")
