"""Rolling out controllers: episodes recorded as :class:`Trajectory` objects, and whole suites.

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
possibly noisy observation) at the reset and after every step. Sub-environment ``i`` reset with
seed ``s`` is, step for step and bit for bit, ``gym.make(id)`` reset with seed ``s``
(:class:`~subenv.envs.DivePlaneVectorEnv`), so an episode's result does not depend on the episodes
run beside it: ``tests/evaluation/test_batched_harness.py`` checks every baseline and agent batched
against one episode at a time.

A controller that raises in ``reset``, ``act`` (or their batch versions), or returns an action the
environment refuses (NaN, None, a wrong shape), fails: the harness raises :class:`ControllerError`,
whose :class:`ControllerFailure` names the controller, the scenario, the seed (the seeds of the
batch, when the failure is the batch's) and the error in one line. :func:`evaluate` raises it, or,
given ``on_failure``, reports it and runs on with the other scenarios and controllers.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Final, TypeVar

import gymnasium as gym
import numpy as np

from subenv.analysis.winnable import winnable
from subenv.dynamics.free_surface import NO_FREE_SURFACE, FreeSurface
from subenv.dynamics.waves import SeaState
from subenv.envs import DivePlaneVectorEnv
from subenv.evaluation.controller import BatchController, Controller, make_controller
from subenv.evaluation.metrics import EpisodeMetrics, episode_metrics
from subenv.evaluation.progress import Progress
from subenv.evaluation.suites import DEFAULT_SEED, Suite, check_scenarios, get_suite, suite_names
from subenv.scenarios.registry import get_scenario, scenario_for_env_id, scenario_names
from subenv.scenarios.scenario import EpisodeConfig, Scenario
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.scaling import froude_factor
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
    "run_episode",
    "run_episodes",
]

MAX_BATCH: Final = 512
"""Episodes stepped together at most: the vector environment's one-thread size
(:data:`subenv.envs.vector.ENVS_PER_THREAD`); the recorded samples of a batch of 600 s episodes take
about 50 MB."""

_RECORDED = (
    "time_s",
    "depth_error_m",
    "pitch_rad",
    "heave_mps",
    "pitch_rate_radps",
    "speed_mps",
    "stern_plane_rad",
    "bow_plane_rad",
    "depth_m",
)  # info keys recorded at every sample, in Trajectory's field order


@dataclass(frozen=True)
class Trajectory:
    """The true state of one episode, sampled at the reset and after every step (SI units).

    Arrays have one entry per sample (``steps + 1``); ``actions`` has one row per step. Plane
    angles of sample k >= 1 are those applied during the step ending at ``time_s[k]``.
    """

    time_s: np.ndarray
    depth_error_m: np.ndarray
    pitch_rad: np.ndarray
    heave_mps: np.ndarray
    pitch_rate_radps: np.ndarray
    speed_mps: np.ndarray
    stern_plane_rad: np.ndarray
    bow_plane_rad: np.ndarray
    depth_m: np.ndarray
    actions: np.ndarray
    termination_reason: str
    """The environment's reason; "" when the episode ran to its time limit (truncated)."""
    depth_command_m: float
    critical_speed_mps: float
    plane_limit_rad: float
    episode_duration_s: float
    """The scheduled length of the episode [s] (the scenario's, or the suite's cap)."""
    length_ratio: float = 1.0
    """lambda of the episode's Froude scaling (:attr:`subenv.envs.config.DivePlaneConfig.length_ratio`):
    its metrics' tolerances are scaled with it."""

    @property
    def steps(self) -> int:
        """Steps of the episode (samples less one)."""
        return int(self.time_s.shape[0] - 1)

    def metrics(self, **kwargs: Any) -> EpisodeMetrics:
        """:func:`~subenv.evaluation.metrics.episode_metrics` of this trajectory (kwargs: its tolerances)."""
        return episode_metrics(
            self.time_s,
            self.depth_error_m,
            self.pitch_rad,
            self.pitch_rate_radps,
            self.stern_plane_rad,
            self.bow_plane_rad,
            termination_reason=self.termination_reason,
            plane_limit_rad=self.plane_limit_rad,
            episode_duration_s=self.episode_duration_s,
            length_ratio=self.length_ratio,
            **kwargs,
        )


class TrajectoryRecorder:
    """Collects the ``info`` of N episodes stepped together (Gymnasium's vector ``info``, an array per
    key) or of one (a dict of floats), at the reset and after every step, into :class:`Trajectory` objects.
    """

    def __init__(self, reset_info: Mapping[str, Any]) -> None:
        self._samples = [self._sample(reset_info)]  # each (len(_RECORDED), N)
        self._actions: list[np.ndarray] = []  # each (N, n_actions)
        self._depth_command_m = np.atleast_1d(np.asarray(reset_info["depth_command_m"], dtype=float))
        self._critical_speed_mps = np.atleast_1d(np.asarray(reset_info["critical_speed_mps"], dtype=float))
        self._stacked: tuple[np.ndarray, np.ndarray] | None = None

    @staticmethod
    def _sample(info: Mapping[str, Any]) -> np.ndarray:
        return np.array([info[key] for key in _RECORDED], dtype=float).reshape(len(_RECORDED), -1)

    def record(self, actions: np.ndarray, info: Mapping[str, Any]) -> None:
        """The actions of a step (shape (N, n_actions), or (n_actions,) for one episode) and its ``info``."""
        episodes = self._samples[0].shape[1]
        self._actions.append(np.array(actions, dtype=np.float32).reshape(episodes, -1))
        self._samples.append(self._sample(info))
        self._stacked = None

    def trajectory(
        self,
        episode: int,
        steps: int,
        termination_reason: str,
        plane_limit_rad: float,
        episode_duration_s: float,
        length_ratio: float = 1.0,
    ) -> Trajectory:
        """Episode ``episode``'s (its row) first ``steps`` steps."""
        if self._stacked is None:
            episodes = self._samples[0].shape[1]
            actions = (
                np.stack(self._actions) if self._actions else np.zeros((0, episodes, 1), dtype=np.float32)
            )
            self._stacked = np.stack(self._samples), actions
        samples, actions = self._stacked
        time_s, error, pitch, heave, rate, speed, stern, bow, depth = (
            np.ascontiguousarray(column) for column in samples[: steps + 1, :, episode].T
        )
        return Trajectory(
            time_s=time_s,
            depth_error_m=error,
            pitch_rad=pitch,
            heave_mps=heave,
            pitch_rate_radps=rate,
            speed_mps=speed,
            stern_plane_rad=stern,
            bow_plane_rad=bow,
            depth_m=depth,
            actions=np.ascontiguousarray(actions[:steps, episode]),
            termination_reason=termination_reason,
            depth_command_m=float(self._depth_command_m[episode]),
            critical_speed_mps=float(self._critical_speed_mps[episode]),
            plane_limit_rad=plane_limit_rad,
            episode_duration_s=episode_duration_s,
            length_ratio=length_ratio,
        )

    def finish(
        self,
        termination_reason: str,
        plane_limit_rad: float,
        episode_duration_s: float,
        length_ratio: float = 1.0,
    ) -> Trajectory:
        """The trajectory of one episode, recorded to its end."""
        return self.trajectory(
            0, len(self._actions), termination_reason, plane_limit_rad, episode_duration_s, length_ratio
        )


@dataclass(frozen=True)
class EpisodeResult:
    """One controller on one episode: what was run, and its metrics (and trajectory, if kept)."""

    controller: str
    scenario: str
    episode: int
    seed: int
    control: str
    alpha: float
    initial_speed_mps: float
    final_speed_mps: float
    """Speed at the end of the episode [m/s]: the speed over the hold window, on which success
    depends (equal to the initial speed except in ``SpeedTransient``)."""
    critical_speed_mps: float
    """Critical speed of the episode's loading and the controller's alpha (info at reset)."""
    depth_command_m: float
    initial_depth_error_m: float
    episode_duration_s: float
    steps: int
    metrics: EpisodeMetrics
    trajectory: Trajectory | None = field(default=None, repr=False, compare=False)
    winnable: bool | None = None
    """Whether the episode's loading has a depth-holding trim within the plane limits and the pitch limit
    at the speed it is to hold at its end, with every plane pair the vehicle has free
    (:func:`subenv.analysis.winnable`): where it has none no controller can succeed. None: not determined."""

    def row(self) -> dict[str, Any]:
        """One flat row of the tidy per-episode table."""
        base = {
            "controller": self.controller,
            "scenario": self.scenario,
            "episode": self.episode,
            "seed": self.seed,
            "control": self.control,
            "alpha": self.alpha,
            "initial_speed_mps": self.initial_speed_mps,
            "final_speed_mps": self.final_speed_mps,
            "critical_speed_mps": self.critical_speed_mps,
            "final_speed_ratio": self.final_speed_mps / self.critical_speed_mps,
            "depth_command_m": self.depth_command_m,
            "initial_depth_error_m": self.initial_depth_error_m,
            "episode_duration_s": self.episode_duration_s,
            "steps": self.steps,
            "winnable": self.winnable,
        }
        return base | self.metrics.as_dict()


@dataclass(frozen=True)
class ControllerFailure:
    """A controller that failed on a scenario: where, on which episodes, and why.

    The harness stops running the controller on that scenario (its episodes there are not kept); the
    one-line :attr:`message` is what ``subenv evaluate`` prints and records.
    """

    controller: str
    scenario: str
    seeds: tuple[int, ...]
    """The episodes it failed on: the one episode run alone, or the batch's rows whose actions the
    environment refused (NaN or inf); every episode of the batch when the failure is the whole batch's
    (an exception in ``reset_batch`` or ``act_batch``, actions of the wrong type or shape)."""
    call: str
    """The controller's method: ``reset``, ``act``, ``reset_batch`` or ``act_batch``."""
    step: int | None
    """The step whose action failed (1: the first action after the reset); None in a reset."""
    error: str
    """The exception it raised (``"RuntimeError: ..."``), or the environment's refusal of its action
    (``"action=[nan] is invalid: must be finite (no NaN or inf)"``), on one line."""

    @property
    def message(self) -> str:
        """One line: ``controller 'x' failed on LowSpeed, seed 10000, in act at step 3: <error>``."""
        where = self.call if self.step is None else f"{self.call} at step {self.step}"
        return (
            f"controller {self.controller!r} failed on {self.scenario}, {_seeds_text(self.seeds)}, in "
            f"{where}: {self.error}"
        )

    def __str__(self) -> str:
        return self.message


class ControllerError(RuntimeError):
    """A controller failed (:class:`ControllerFailure`, in :attr:`failure`); the message is its one line,
    and the exception the controller raised, if any, is the ``__cause__``."""

    def __init__(self, failure: ControllerFailure) -> None:
        super().__init__(failure)  # (the one argument: the exception pickles, as a Ray task's error does)
        self.failure = failure

    def __str__(self) -> str:
        return self.failure.message


def _seeds_text(seeds: Sequence[int]) -> str:
    """``seed 3``, ``seeds 3-9`` (consecutive) or ``seeds 3, 5, 8``."""
    if len(seeds) == 1:
        return f"seed {seeds[0]}"
    if list(seeds) == list(range(seeds[0], seeds[0] + len(seeds))):
        return f"seeds {seeds[0]}-{seeds[-1]}"
    return "seeds " + ", ".join(str(s) for s in seeds)


def _one_line(text: str) -> str:
    """``text`` with its line breaks (a plugin's multi-line message) made spaces."""
    return " ".join(line.strip() for line in text.strip().splitlines() if line.strip())


_T = TypeVar("_T")


@dataclass(frozen=True)
class _Blame:
    """Whose episodes run now: a failure of a controller's call there is reported with these."""

    controller: Controller
    scenario: str
    seeds: tuple[int, ...]

    def call(self, method: str, step: int | None, function: Callable[..., _T], *args: Any) -> _T:
        """``function(*args)``, the controller's ``method``; any exception it raises is its failure."""
        try:
            return function(*args)
        except Exception as exc:
            text = _one_line(str(exc))
            raise self.failed(
                method, step, f"{type(exc).__name__}: {text}" if text else type(exc).__name__
            ) from exc

    def failed(
        self, method: str, step: int | None, error: str, seeds: Sequence[int] | None = None
    ) -> ControllerError:
        """The error of the controller's ``method`` failing with ``error``, on ``seeds`` if known (the rows
        the environment refused), otherwise on every episode it runs now."""
        return ControllerError(
            ControllerFailure(
                controller=self.controller.name,
                scenario=self.scenario,
                seeds=self.seeds if not seeds else tuple(seeds),
                call=method,
                step=step,
                error=error,
            )
        )


def _scenario_of(name: str) -> str:
    """The scenario name of ``"LowSpeed"`` or ``"subenv/LowSpeed-v0"`` (checked)."""
    scenario = name
    if name == "subenv/DivePlane-v0":
        scenario = "Randomized"
    elif "/" in name:
        found = scenario_for_env_id(name)
        if found is None:
            parsed = re.fullmatch(r"subenv/(\w+)-v(\d+)", name)
            if parsed is None:
                raise ValueError(
                    f"env id {name!r} is not a subenv id: must be 'subenv/<Scenario>-v<version>'"
                )
            base, version = parsed.groups()
            found = base if version == "0" else f"{base}-v{version}"  # (unknown: check_scenarios says so)
        scenario = found
    check_scenarios([scenario])
    return scenario


def _env_args(
    controller: Controller, scenario: str | Scenario, vehicle: str | Vehicle, max_duration_s: float | None
) -> tuple[str, dict[str, Any]]:
    """The id and keyword arguments of ``scenario``'s environments for ``controller``."""
    kwargs: dict[str, Any]
    if isinstance(scenario, Scenario):
        env_id, kwargs = "subenv/DivePlane-v0", {"scenario": scenario}
    else:
        env_id, kwargs = get_scenario(_scenario_of(scenario)).env_id, {}
    kwargs |= {"control": controller.control, "alpha": controller.alpha, "vehicle": vehicle}
    spec = gym.spec(env_id)
    if max_duration_s is not None:
        dt = spec.kwargs.get("dt", 0.5)
        kwargs["max_episode_steps"] = max(1, math.ceil(max_duration_s / dt - 1e-9))
    else:
        # On a vehicle of another length the episodes are Froude-scaled (Scenario.reference_length_m):
        # their durations by sqrt(lambda), and the id's step limit (the reference vehicle's) with them.
        the_scenario = scenario if isinstance(scenario, Scenario) else get_scenario(_scenario_of(scenario))
        boat = vehicle if isinstance(vehicle, Vehicle) else load_vehicle(vehicle)
        ratio = the_scenario.length_ratio(boat.length_m)
        if ratio != 1.0 and spec.max_episode_steps is not None:
            kwargs["max_episode_steps"] = math.ceil(
                spec.max_episode_steps * froude_factor("time", ratio) - 1e-9
            )
    return env_id, kwargs


def make_env(
    controller: Controller,
    scenario: str | Scenario,
    *,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
) -> gym.Env:
    """The environment of ``scenario`` for ``controller``'s action space.

    ``scenario`` is a registered name, ``subenv/<Name>-v0``, or an unregistered :class:`Scenario`
    (run as ``subenv/DivePlane-v0`` with that scenario). ``max_duration_s`` truncates episodes
    earlier than the scenario does (Gymnasium's ``max_episode_steps``).
    """
    env_id, kwargs = _env_args(controller, scenario, vehicle, max_duration_s)
    return gym.make(env_id, **kwargs)


def make_vector_env(
    controller: Controller,
    scenario: str | Scenario,
    num_envs: int,
    *,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
) -> DivePlaneVectorEnv:
    """``num_envs`` environments of ``scenario`` stepped together (``gym.make_vec``), as :func:`make_env`'s.

    Ended sub-environments reset on the next step (``autoreset_mode="NextStep"``).
    """
    env_id, kwargs = _env_args(controller, scenario, vehicle, max_duration_s)
    env = gym.make_vec(env_id, num_envs=num_envs, **kwargs)
    assert isinstance(env, DivePlaneVectorEnv)  # every subenv id's vector entry point
    return env


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
) -> list[EpisodeResult]:
    """Run ``controller`` for one episode from ``reset(seed=s)`` per seed and compute the metrics.

    Parameters
    ----------
    controller : Controller
        A :class:`~subenv.evaluation.BatchController` runs up to :data:`MAX_BATCH` episodes
        together in one vector environment; any other controller one episode at a time, in one
        environment.
    scenario : str or Scenario
        A scenario name, a ``subenv/<Name>-v0`` id, or an unregistered :class:`Scenario`.
    seeds : sequence of int
        The reset seeds, one per episode; results in this order.
    first_episode : int
        The index recorded in the first result (then +1 per seed).
    vehicle, max_duration_s
        See :func:`make_env`.
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

    Raises
    ------
    ControllerError
        The controller failed (:class:`ControllerFailure`): an exception in one of its calls, or an
        action the environment refused. The episodes of ``seeds`` not yet returned are not run.
    """
    seeds = list(seeds)
    results: list[EpisodeResult] = []

    def produced(result: EpisodeResult) -> None:
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
                        controller, scenario, len(wave), vehicle=vehicle, max_duration_s=max_duration_s
                    )
                for result in _run_batch(
                    controller,
                    envs[len(wave)],
                    wave,
                    first_episode + start,
                    keep_trajectories - start,
                    options,
                ):
                    produced(result)
        finally:
            for vector_env in envs.values():
                vector_env.close()
        return results
    env = make_env(controller, scenario, vehicle=vehicle, max_duration_s=max_duration_s)
    try:
        for i, seed in enumerate(seeds):
            produced(_run_single(controller, env, seed, first_episode + i, i < keep_trajectories, options))
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
) -> EpisodeResult:
    """One episode in ``env``, made by :func:`make_env` for ``controller``."""
    base: Any = env.unwrapped  # a DivePlaneEnv: its episode, vehicle and limits
    obs, info = env.reset(seed=seed, options=options)
    blame = _Blame(controller, base.scenario.key, (seed,))
    blame.call("reset", None, controller.reset, info, base.base_vehicle)
    recorder = TrajectoryRecorder(info)
    step = 0
    while True:
        step += 1
        action = blame.call("act", step, controller.act, obs)
        try:
            obs, _, terminated, truncated, info = env.step(action)
        except ValueError as exc:  # the environment checks an action before it steps: this one is refused
            raise blame.failed("act", step, _one_line(str(exc))) from exc
        recorder.record(action, info)
        if terminated or truncated:
            break
    limit = env.spec.max_episode_steps if env.spec is not None else None
    duration_s = _scheduled(float(base.episode.duration_s), limit, float(base.dt))
    trajectory = recorder.finish(
        info["termination_reason"] if terminated else "",
        float(base.plane_limit_rad),
        duration_s,
        base.config.length_ratio,
    )
    can_win = _episode_winnable(
        base.vehicle, base.episode, trajectory.critical_speed_mps, base.config.max_pitch_rad, options
    )
    return _result(controller, base.scenario.key, seed, episode, trajectory, keep, can_win)


def _run_batch(
    controller: BatchController,
    env: DivePlaneVectorEnv,
    seeds: list[int],
    first_episode: int,
    keep: int,
    options: dict[str, Any] | None,
) -> list[EpisodeResult]:
    """One episode per sub-environment of ``env`` (one per seed), stepped until the last has ended;
    the first ``keep`` keep their trajectories."""
    config = env.config
    obs, info = env.reset(seed=seeds, options=options)
    drawn = env.episodes  # (before an ended sub-environment resets to another episode)
    loadings = list(env.vehicles)
    columns = {key: value.tolist() for key, value in info.items() if not key.startswith("_")}
    blame = _Blame(controller, env.scenario.key, tuple(seeds))
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
            raise blame.failed("act_batch", step + 1, _one_line(str(exc)), bad) from exc
        step += 1
        recorder.record(actions, info)
        ended = running & (terminated | truncated)
        for i in np.flatnonzero(ended).tolist():
            steps[i] = step
            reasons[i] = info["termination_reason"][i] if terminated[i] else ""
        running &= ~ended
    results = []
    for i, (seed, draw) in enumerate(zip(seeds, drawn, strict=True)):
        assert draw is not None
        duration_s = _scheduled(float(draw.duration_s), env.max_episode_steps, float(config.dt))
        trajectory = recorder.trajectory(
            i, int(steps[i]), reasons[i], float(config.plane_limit_rad), duration_s, config.length_ratio
        )
        can_win = _episode_winnable(
            loadings[i], draw, trajectory.critical_speed_mps, config.max_pitch_rad, options
        )
        results.append(
            _result(controller, env.scenario.key, seed, first_episode + i, trajectory, i < keep, can_win)
        )
    return results


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


@lru_cache(maxsize=4096)
def _winnable(
    loading: Vehicle,
    final_speed_mps: float,
    max_pitch_rad: float,
    depth_m: float = 0.0,
    free_surface: FreeSurface = NO_FREE_SURFACE,
    sea_state: SeaState | None = None,
) -> bool:
    """:func:`subenv.analysis.winnable` (about 4 ms), once per loading and speed (and ordered depth, near
    the surface): every controller of a comparison runs the same episodes."""
    return winnable(loading, (final_speed_mps,), max_pitch_rad, depth_m, free_surface, sea_state)


def _episode_winnable(
    loading: Vehicle,
    draw: EpisodeConfig,
    critical_speed_mps: float,
    max_pitch_rad: float,
    options: Mapping[str, Any] | None,
) -> bool:
    """Whether the episode can be won at the speed it holds at its end (its profile's last knot)."""
    if options and "speed" in options:
        final = float(options["speed"])
    else:
        last = draw.speed_knots[-1][1]
        final = float(last) * (critical_speed_mps if draw.speed_relative else 1.0)
    if draw.free_surface is None and draw.sea_state is None:
        return _winnable(loading, final, max_pitch_rad)
    depth = (
        float(options["depth_command"])
        if options and "depth_command" in options
        else float(draw.depth_command_m)
    )
    return _winnable(
        loading, final, max_pitch_rad, depth, draw.free_surface or NO_FREE_SURFACE, draw.sea_state
    )


def _result(
    controller: Controller,
    scenario: str,
    seed: int,
    episode: int,
    trajectory: Trajectory,
    keep: bool,
    winnable_episode: bool | None = None,
) -> EpisodeResult:
    return EpisodeResult(
        controller=controller.name,
        scenario=scenario,
        episode=episode,
        seed=seed,
        control=controller.control,
        alpha=float(controller.alpha),
        initial_speed_mps=float(trajectory.speed_mps[0]),
        final_speed_mps=float(trajectory.speed_mps[-1]),
        critical_speed_mps=trajectory.critical_speed_mps,
        depth_command_m=trajectory.depth_command_m,
        initial_depth_error_m=float(trajectory.depth_error_m[0]),
        episode_duration_s=trajectory.episode_duration_s,
        steps=trajectory.steps,
        metrics=trajectory.metrics(),
        trajectory=trajectory if keep else None,
        winnable=winnable_episode,
    )


def needs_bow_planes(controller: Controller) -> bool:
    """Whether ``controller`` moves the bow planes (``control="independent"``, or dual control with
    alpha != 0)."""
    return controller.control == "independent" or float(controller.alpha) != 0.0


def resolve_controllers(
    controllers: Sequence[Controller | str] | None, vehicle: Vehicle | None = None
) -> list[Controller]:
    """Controllers from instances or registered names (None: every registered controller but those whose
    ``in_default_comparison`` attribute is False, and on a ``vehicle`` without bow planes those that move
    them, :func:`needs_bow_planes`).

    Raises ValueError for an unknown name (listing the known ones), an empty selection, two
    controllers with one name, or a named controller that moves bow planes ``vehicle`` does not have;
    TypeError for an object that is not a :class:`~subenv.evaluation.Controller`.
    """
    from subenv.evaluation.controller import controller_names

    named = controllers is not None
    if controllers is None:
        names = controller_names()
        if not names:
            raise ValueError(
                "no controllers are registered: install a package that declares some in the "
                "'subenv.controllers' entry-point group, or call subenv.evaluation.register_controller"
            )
        # A controller whose class says in_default_comparison = False (a plugin's that is too slow for
        # the comparison of every registered one, say) runs when named only.
        made = [make_controller(name) for name in names]
        controllers = [c for c in made if getattr(c, "in_default_comparison", True)] or made
    if isinstance(controllers, str):
        controllers = [controllers]
    resolved = [make_controller(c) if isinstance(c, str) else c for c in controllers]
    if not resolved:
        raise ValueError("controllers is empty: name at least one")
    for c in resolved:
        if not isinstance(c, Controller):
            raise TypeError(f"{c!r} is not a Controller (needs name, control, alpha, reset(), act())")
        if c.control not in ("dual", "independent"):
            raise ValueError(f"controller {c.name!r}: control={c.control!r} must be 'dual' or 'independent'")
    names = [c.name for c in resolved]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ValueError(f"controller names {duplicates} appear more than once: the tables are keyed by name")
    if vehicle is not None and not vehicle.planes.has_bow_planes:
        bow = [c.name for c in resolved if needs_bow_planes(c)]
        if bow and named:
            raise ValueError(
                f"controllers {bow} move the bow planes (control='independent' or alpha != 0), and "
                f"vehicle {vehicle.name!r} has none: leave them out"
            )
        resolved = [c for c in resolved if not needs_bow_planes(c)] or resolved
    return resolved


def resolve_suite(suite: Suite | str | Sequence[str]) -> Suite:
    """A :class:`Suite` from itself, a registered suite name, a scenario name, or a list of them.

    A name that is both a suite and a scenario is the suite. Raises ValueError naming an unknown
    name and listing the known suites and scenarios.
    """
    if isinstance(suite, Suite):
        check_scenarios(suite.scenarios)
        return suite
    if isinstance(suite, str):
        if suite in suite_names():
            return get_suite(suite)
        try:
            suite = [_scenario_of(suite)]
        except ValueError:
            raise ValueError(
                f"suite={suite!r} is unknown: must be a suite name (one of {suite_names()}) or a scenario "
                f"name (one of {scenario_names()})"
            ) from None
    names = tuple(_scenario_of(s) for s in suite)
    return Suite(name="custom", description="scenarios chosen by the caller", scenarios=names, episodes=10)


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

    Returns
    -------
    list of EpisodeResult
        Ordered by controller, then scenario, then episode. A controller that failed on a scenario has
        no results there (not even the episodes that ended before the failure: in a batch those are the
        early terminations, and the results must not depend on batching), and every result on the
        scenarios it completed.

    Raises
    ------
    ControllerError
        A controller failed and ``on_failure`` is None.
    """
    design_vehicle = vehicle if isinstance(vehicle, Vehicle) else load_vehicle(vehicle)
    ctrls = resolve_controllers(controllers, design_vehicle)
    the_suite = resolve_suite(suite)
    n = the_suite.episodes if episodes is None else episodes
    if not (isinstance(n, int) and not isinstance(n, bool) and n >= 1):
        raise ValueError(f"episodes={episodes!r} is invalid: must be an integer >= 1")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise ValueError(f"seed={seed!r} is invalid: must be an integer >= 0")

    results: list[EpisodeResult] = []
    bar = Progress(len(ctrls) * len(the_suite.scenarios) * n, enabled=progress)
    try:
        for controller in ctrls:
            for scenario in the_suite.scenarios:
                bar.describe(f"{controller.name} on {scenario}")
                before = bar.done
                try:
                    completed = run_episodes(
                        controller,
                        scenario,
                        range(seed, seed + n),
                        vehicle=design_vehicle,
                        max_duration_s=the_suite.max_duration_s,
                        keep_trajectories=keep_trajectories,
                        on_episode=lambda _: bar.update(1),
                        batched=batched,
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
