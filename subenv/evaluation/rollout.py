"""The roll-out stage: controllers run on episodes, batched in the vector environment.

The harness steps the native vector environment, ``gym.make_vec(f"subenv/{scenario}-v0",
num_envs=N, control=controller.control, alpha=controller.alpha)``: the episodes of a scenario run
together, up to :data:`MAX_BATCH` at a time, sub-environment ``i`` reset with its own episode's
seed (``reset(seed=[seed_0, seed_1, ...])``), and a :class:`~subenv.evaluation.BatchController`
acts on all of them in one call (``reset_batch`` with every episode's reset ``info`` and the
design vehicle, then ``act_batch`` on the (N, obs_dim) observations). An episode that has ended is
left behind (its sub-environment resets and steps on, unrecorded) until the batch's last one ends.
A controller without the batch methods runs one episode at a time in one environment
(``gym.make``), with ``reset(info, vehicle)`` and ``act(obs)``, as the harness did before batching.

Either way the harness records the true state the environment reports in ``info`` (not the
possibly noisy observation) at the reset and after every step (:mod:`subenv.evaluation.trajectory`).
Sub-environment ``i`` reset with seed ``s`` is, step for step and bit for bit, ``gym.make(id)`` reset
with seed ``s`` (:class:`~subenv.envs.DivePlaneVectorEnv`), so an episode's result does not depend on
the episodes run beside it: ``tests/evaluation/test_batched_harness.py`` checks every baseline and
agent batched against one episode at a time.

Each batch, once rolled out, is classified (:mod:`subenv.evaluation.classify`) and measured
(:mod:`subenv.evaluation.measure`) before the next runs, so that only the kept trajectories stay in
memory. A controller that takes the environment's settings is told them before each scenario
(:func:`subenv.evaluation.environments.inform`).

A controller that raises in ``reset``, ``act`` (or their batch versions), or returns an action the
environment refuses (NaN, None, a wrong shape), fails: the harness raises :class:`ControllerError`
(:mod:`subenv.evaluation.failures`). :func:`evaluate` raises it, or, given ``on_failure``, reports it
and runs on with the other scenarios and controllers.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import gymnasium as gym
import numpy as np

from subenv.envs import DivePlaneVectorEnv
from subenv.evaluation.classify import EpisodeDraw, classify
from subenv.evaluation.controller import BatchController, Controller
from subenv.evaluation.environments import inform, make_env, make_vector_env
from subenv.evaluation.failures import Blame, ControllerError, ControllerFailure, one_line
from subenv.evaluation.measure import EpisodeResult, measure
from subenv.evaluation.plan import Plan, needs_bow_planes, resolve, resolve_controllers
from subenv.evaluation.progress import Progress
from subenv.evaluation.suites import DEFAULT_SEED, Suite, resolve_suite
from subenv.evaluation.trajectory import Trajectory, TrajectoryRecorder
from subenv.scenarios.scenario import Scenario
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "MAX_BATCH",
    "ControllerError",
    "ControllerFailure",
    "EpisodeResult",
    "Trajectory",
    "TrajectoryRecorder",
    "evaluate",
    "make_env",
    "make_vector_env",
    "needs_bow_planes",
    "resolve_controllers",
    "resolve_suite",
    "roll_out",
    "run_episode",
    "run_episodes",
]

MAX_BATCH: Final = 512
"""Episodes stepped together at most: the vector environment's one-thread size
(:data:`subenv.envs.vector.ENVS_PER_THREAD`); the recorded samples of a batch of 600 s episodes take
about 50 MB."""


@dataclass(frozen=True)
class _Rollout:
    """One episode as rolled out: its record, and what was drawn for it (for the classifier)."""

    seed: int
    episode: int
    trajectory: Trajectory
    draw: EpisodeDraw
    keep: bool


def run_episode(
    controller: Controller,
    scenario: str | Scenario,
    seed: int,
    *,
    episode: int = 0,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
    keep_trajectory: bool = True,
    options: dict[str, Any] | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> EpisodeResult:
    """Run ``controller`` for one episode from ``reset(seed=seed)`` and compute its metrics.

    ``episode`` is the index recorded in the result; ``keep_trajectory`` attaches the
    :class:`Trajectory` (memory: ~100 kB per 600 s episode); the other arguments are those of
    :func:`run_episodes`.
    """
    (result,) = run_episodes(
        controller,
        scenario,
        [seed],
        first_episode=episode,
        vehicle=vehicle,
        max_duration_s=max_duration_s,
        keep_trajectories=int(keep_trajectory),
        options=options,
        env_kwargs=env_kwargs,
    )
    return result


def run_episodes(
    controller: Controller,
    scenario: str | Scenario,
    seeds: Sequence[int],
    *,
    first_episode: int = 0,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
    keep_trajectories: int = 0,
    options: dict[str, Any] | None = None,
    on_episode: Callable[[EpisodeResult], None] | None = None,
    batched: bool = True,
    env_kwargs: Mapping[str, Any] | None = None,
    scored_by: str = "winnable",
) -> list[EpisodeResult]:
    """Run ``controller`` for one episode from ``reset(seed=s)`` per seed and compute the metrics.

    Parameters
    ----------
    controller : Controller
        A :class:`~subenv.evaluation.BatchController` runs up to :data:`MAX_BATCH` episodes
        together in one vector environment; any other controller one episode at a time, in one
        environment. One that takes the environment's settings
        (:class:`~subenv.evaluation.controller.InformedController`) is told them first.
    scenario : str or Scenario
        A scenario name, a ``subenv/<Name>-v0`` id, or an unregistered :class:`Scenario`.
    seeds : sequence of int
        The reset seeds, one per episode; results in this order.
    first_episode : int
        The index recorded in the first result (then +1 per seed).
    vehicle, max_duration_s, env_kwargs
        See :func:`~subenv.evaluation.environments.make_env` (``env_kwargs`` checked by the caller:
        :func:`~subenv.evaluation.environments.check_env_kwargs`).
    keep_trajectories : int
        Attach the :class:`Trajectory` to the first this-many results.
    options : dict, optional
        ``env.reset`` options (``speed``, ``depth_command``, ``initial_state``), applied to every
        episode, to place it exactly.
    on_episode : callable, optional
        Called with each result as it is produced.
    batched : bool
        False runs a batch controller one episode at a time as well, with its ``reset`` and ``act``
        (the same results: ``tests/evaluation/test_batched_harness.py``; ``benchmarks/harness.py``
        times both).
    scored_by : str
        The classifier that decides which episodes the score counts
        (:attr:`EpisodeResult.scored`; :mod:`subenv.evaluation.classify`).

    Raises
    ------
    ControllerError
        The controller failed (:class:`ControllerFailure`): an exception in one of its calls, or an
        action the environment refused. The episodes of ``seeds`` not yet returned are not run.
    """
    seeds = list(seeds)
    results: list[EpisodeResult] = []
    told = inform(controller, scenario, env_kwargs)

    def produced(rollouts: list[_Rollout]) -> None:
        for r in rollouts:
            result = measure(
                controller,
                r.draw.scenario,
                r.seed,
                r.episode,
                r.trajectory,
                classify(r.draw, scored_by),
                keep=r.keep,
                informed=told,
            )
            results.append(result)
            if on_episode is not None:
                on_episode(result)

    if batched and isinstance(controller, BatchController):
        envs: dict[int, DivePlaneVectorEnv] = {}  # by number of sub-environments
        try:
            for start in range(0, len(seeds), MAX_BATCH):
                wave = seeds[start : start + MAX_BATCH]
                if len(wave) not in envs:
                    envs[len(wave)] = make_vector_env(
                        controller,
                        scenario,
                        len(wave),
                        vehicle=vehicle,
                        max_duration_s=max_duration_s,
                        env_kwargs=env_kwargs,
                    )
                produced(
                    _run_batch(
                        controller,
                        envs[len(wave)],
                        wave,
                        first_episode + start,
                        keep_trajectories - start,
                        options,
                    )
                )
        finally:
            for vector_env in envs.values():
                vector_env.close()
        return results
    env = make_env(
        controller, scenario, vehicle=vehicle, max_duration_s=max_duration_s, env_kwargs=env_kwargs
    )
    try:
        for i, seed in enumerate(seeds):
            produced([_run_single(controller, env, seed, first_episode + i, i < keep_trajectories, options)])
    finally:
        env.close()
    return results


def _run_single(
    controller: Controller,
    env: gym.Env,
    seed: int,
    episode: int,
    keep: bool,
    options: dict[str, Any] | None,
) -> _Rollout:
    """One episode in ``env``, made by :func:`make_env` for ``controller``."""
    base: Any = env.unwrapped  # a DivePlaneEnv: its episode, vehicle and limits
    obs, info = env.reset(seed=seed, options=options)
    blame = Blame(controller, base.scenario.key, (seed,))
    blame.call("reset", None, controller.reset, info, base.base_vehicle)
    recorder = TrajectoryRecorder(info)
    step = 0
    while True:
        step += 1
        action = blame.call("act", step, controller.act, obs)
        try:
            obs, _, terminated, truncated, info = env.step(action)
        except ValueError as exc:  # the environment checks an action before it steps: this one is refused
            raise blame.failed("act", step, one_line(str(exc))) from exc
        recorder.record(action, info)
        if terminated or truncated:
            break
    config = base.config
    limit = env.spec.max_episode_steps if env.spec is not None else None
    trajectory = recorder.finish(
        info["termination_reason"] if terminated else "",
        float(config.plane_limit_rad),
        _scheduled(float(base.episode.duration_s), limit, float(config.dt)),
        config.length_ratio,
        _plane_count(config.base_vehicle),
    )
    draw = EpisodeDraw(
        base.scenario.key,
        seed,
        base.vehicle,
        base.episode,
        trajectory.critical_speed_mps,
        config.max_pitch_rad,
        options,
        config,
        limit,
    )
    return _Rollout(seed, episode, trajectory, draw, keep)


def _run_batch(
    controller: BatchController,
    env: DivePlaneVectorEnv,
    seeds: list[int],
    first_episode: int,
    keep: int,
    options: dict[str, Any] | None,
) -> list[_Rollout]:
    """One episode per sub-environment of ``env`` (one per seed), stepped until the last has ended;
    the first ``keep`` keep their trajectories."""
    config = env.config
    obs, info = env.reset(seed=seeds, options=options)
    drawn = env.episodes  # (before an ended sub-environment resets to another episode)
    loadings = list(env.vehicles)
    columns = {key: value.tolist() for key, value in info.items() if not key.startswith("_")}
    blame = Blame(controller, env.scenario.key, tuple(seeds))
    infos = [{key: column[i] for key, column in columns.items()} for i in range(len(seeds))]
    blame.call("reset_batch", None, controller.reset_batch, infos, config.base_vehicle)
    recorder = TrajectoryRecorder(info)
    running = np.ones(len(seeds), dtype=bool)
    steps = np.zeros(len(seeds), dtype=int)
    reasons = [""] * len(seeds)
    step = 0
    while running.any():
        actions = blame.call("act_batch", step + 1, controller.act_batch, obs)
        try:
            obs, _, terminated, truncated, info = env.step(actions)
        except ValueError as exc:  # refused before anything stepped: the rows with NaN or inf, or the batch
            bad = [seeds[i] for i in _non_finite_rows(actions, len(seeds))]
            raise blame.failed("act_batch", step + 1, one_line(str(exc)), bad) from exc
        step += 1
        recorder.record(actions, info)
        ended = running & (terminated | truncated)
        for i in np.flatnonzero(ended).tolist():
            steps[i] = step
            reasons[i] = info["termination_reason"][i] if terminated[i] else ""
        running &= ~ended
    rollouts = []
    for i, (seed, draw) in enumerate(zip(seeds, drawn, strict=True)):
        assert draw is not None
        trajectory = recorder.trajectory(
            i,
            int(steps[i]),
            reasons[i],
            float(config.plane_limit_rad),
            _scheduled(float(draw.duration_s), env.max_episode_steps, float(config.dt)),
            config.length_ratio,
            _plane_count(config.base_vehicle),
        )
        drawn_for = EpisodeDraw(
            env.scenario.key,
            seed,
            loadings[i],
            draw,
            trajectory.critical_speed_mps,
            config.max_pitch_rad,
            options,
            config,
            env.max_episode_steps,
        )
        rollouts.append(_Rollout(seed, first_episode + i, trajectory, drawn_for, i < keep))
    return rollouts


def _plane_count(vehicle: Vehicle) -> int:
    """The planes ``vehicle`` has: 2 (stern and bow) or 1 (stern alone)."""
    return 2 if vehicle.planes.has_bow_planes else 1


def _non_finite_rows(actions: Any, rows: int) -> list[int]:
    """The rows of a batch of actions that hold a NaN or inf; none when it is not ``rows`` rows of real
    numbers (then the environment refused the batch as a whole)."""
    try:
        array = np.asarray(actions)
        if array.dtype.kind not in "iuf":
            return []
        array = array.reshape(rows, -1)
    except ValueError:  # ragged, or another number of rows
        return []
    return np.flatnonzero(~np.isfinite(array).all(axis=1)).tolist()


def _scheduled(duration_s: float, max_episode_steps: int | None, dt: float) -> float:
    """The scheduled length of an episode [s]: its scenario's, or the step limit's if shorter."""
    return duration_s if max_episode_steps is None else min(duration_s, max_episode_steps * dt)


def roll_out(
    plan: Plan,
    progress: bool = True,
    *,
    keep_trajectories: int = 1,
    on_episode: Callable[[EpisodeResult], None] | None = None,
    batched: bool = True,
    on_failure: Callable[[ControllerFailure], None] | None = None,
) -> list[EpisodeResult]:
    """Run every controller of ``plan`` on the same episodes of every scenario of its suite (the
    arguments are :func:`evaluate`'s); results ordered by controller, then scenario, then episode."""
    results: list[EpisodeResult] = []
    n = plan.episodes
    bar = Progress(len(plan.controllers) * len(plan.suite.scenarios) * n, enabled=progress)
    try:
        for controller in plan.controllers:
            for scenario in plan.suite.scenarios:
                bar.describe(f"{controller.name} on {scenario}")
                before = bar.done
                try:
                    completed = run_episodes(
                        controller,
                        scenario,
                        plan.seeds,
                        vehicle=plan.vehicle,
                        max_duration_s=plan.suite.max_duration_s,
                        keep_trajectories=keep_trajectories,
                        on_episode=lambda _: bar.update(1),
                        batched=batched,
                        env_kwargs=plan.env_kwargs,
                        scored_by=plan.suite.scored_by,
                    )
                except ControllerError as error:
                    if on_failure is None:
                        raise
                    bar.update(before + n - bar.done)  # (the episodes left out count as done)
                    on_failure(error.failure)
                    continue
                results += completed
                if on_episode is not None:
                    for result in completed:
                        on_episode(result)
    finally:
        bar.close()
    return results


def evaluate(
    controllers: Sequence[Controller | str] | None,
    suite: Suite | str | Sequence[str],
    episodes: int | None = None,
    seed: int = DEFAULT_SEED,
    progress: bool = True,
    *,
    vehicle: str | Vehicle = "suboff",
    keep_trajectories: int = 1,
    on_episode: Callable[[EpisodeResult], None] | None = None,
    batched: bool = True,
    on_failure: Callable[[ControllerFailure], None] | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> list[EpisodeResult]:
    """Run every controller on the same episodes of every scenario of ``suite``.

    Parameters
    ----------
    controllers : sequence of Controller or str, or None
        Instances or registered names; None runs every registered controller.
    suite : Suite, str or sequence of str
        A suite, a registered suite name (``suite_names()``), or scenario names.
    episodes : int, optional
        Episodes per scenario and controller (default: the suite's).
    seed : int
        Base seed: episode ``i`` of each scenario is ``reset(seed=seed + i)`` for every controller.
    progress : bool
        Show the progress over all episodes on stderr: a bar on a terminal, otherwise a log line
        every 5% (:class:`~subenv.evaluation.progress.Progress`).
    vehicle : str or Vehicle
        The vehicle of every environment; loaded once and shared, so a controller that designs
        itself per design model does so once.
    keep_trajectories : int
        Attach trajectories to the results of the first this-many episodes of each scenario
        (for plots); 0 keeps none.
    on_episode : callable, optional
        Called with each result of a controller on a scenario once it has run every episode there.
    batched : bool
        Run the episodes of a scenario together (controllers that can; see :func:`run_episodes`).
    on_failure : callable, optional
        Called with each :class:`ControllerFailure` instead of raising it: the controller that failed
        goes on with the next scenario, and the others run as if it had not failed. None (the default)
        raises the first failure, so that a caller never takes a shorter list for a complete one.
    env_kwargs : mapping, optional
        The environment's other arguments (``plane_rate_limit_radps``, ``max_pitch_rad``, ``dt``, ...:
        :func:`subenv.evaluation.environments.setting_names`), for every scenario; checked with the
        environment's own checks before any episode. A controller that takes them
        (:class:`~subenv.evaluation.controller.InformedController`) is told them.

    Returns
    -------
    list of EpisodeResult
        Ordered by controller, then scenario, then episode. A controller that failed on a scenario has
        no results there (not even the episodes that ended before the failure: in a batch those are the
        early terminations, and the results must not depend on batching), and every result on the
        scenarios it completed.

    Raises
    ------
    ValueError
        Bad input (:func:`~subenv.evaluation.plan.resolve`), before any episode.
    ControllerError
        A controller failed and ``on_failure`` is None.
    """
    plan = resolve(controllers, suite, episodes, seed, vehicle=vehicle, env_kwargs=env_kwargs)
    return roll_out(
        plan,
        progress,
        keep_trajectories=keep_trajectories,
        on_episode=on_episode,
        batched=batched,
        on_failure=on_failure,
    )
