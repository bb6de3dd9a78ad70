"""Rolling out controllers: one episode recorded as a :class:`Trajectory`, and whole suites.

The harness makes each environment with the controller's own action space
(``gym.make(f"subenv/{scenario}-v0", control=controller.control, alpha=controller.alpha)``),
calls ``controller.reset(info, env.unwrapped.base_vehicle)`` after every ``env.reset`` and
records the true state the environment reports in ``info`` (not the possibly noisy observation)
at the reset and after every step.

Episodes are run one environment at a time. At about 10-30 us per step (environment plus a
baseline controller's ``act``), the default comparison takes seconds per controller; batching
through ``gym.make_vec`` would need one controller instance per sub-environment and is left for
when controllers are slow enough to matter. The seeds follow ``gym.make_vec``'s convention
(episode ``i`` is ``reset(seed=base_seed + i)``), so a batched run would draw the same episodes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from subenv.evaluation.controller import Controller, make_controller
from subenv.evaluation.metrics import EpisodeMetrics, episode_metrics
from subenv.evaluation.suites import DEFAULT_SEED, Suite, check_scenarios, get_suite, suite_names
from subenv.scenarios.registry import scenario_names
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "EpisodeResult",
    "Trajectory",
    "TrajectoryRecorder",
    "evaluate",
    "make_env",
    "resolve_controllers",
    "resolve_suite",
    "run_episode",
]

_RECORDED = (
    "time_s", "depth_error_m", "pitch_rad", "heave_mps", "pitch_rate_radps", "speed_mps",
    "stern_plane_rad", "bow_plane_rad", "depth_m",
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

    @property
    def steps(self) -> int:
        return int(self.time_s.shape[0] - 1)

    def metrics(self, **kwargs: Any) -> EpisodeMetrics:
        """:func:`~subenv.evaluation.metrics.episode_metrics` of this trajectory (kwargs: its tolerances)."""
        return episode_metrics(
            self.time_s, self.depth_error_m, self.pitch_rad, self.pitch_rate_radps,
            self.stern_plane_rad, self.bow_plane_rad,
            termination_reason=self.termination_reason, plane_limit_rad=self.plane_limit_rad,
            episode_duration_s=self.episode_duration_s, **kwargs,
        )


class TrajectoryRecorder:
    """Collects ``info`` dicts (reset, then every step) into a :class:`Trajectory`."""

    def __init__(self, reset_info: dict[str, Any]) -> None:
        self._columns: list[list[float]] = [[float(reset_info[k])] for k in _RECORDED]
        self._actions: list[np.ndarray] = []
        self._depth_command_m = float(reset_info["depth_command_m"])
        self._critical_speed_mps = float(reset_info["critical_speed_mps"])

    def record(self, action: np.ndarray, info: dict[str, Any]) -> None:
        self._actions.append(np.asarray(action, dtype=np.float32).reshape(-1))
        for column, key in zip(self._columns, _RECORDED):
            column.append(float(info[key]))

    def finish(
        self, termination_reason: str, plane_limit_rad: float, episode_duration_s: float
    ) -> Trajectory:
        time_s, error, pitch, heave, rate, speed, stern, bow, depth = (
            np.asarray(c, dtype=float) for c in self._columns
        )
        actions = np.stack(self._actions) if self._actions else np.zeros((0, 1), dtype=np.float32)
        return Trajectory(
            time_s=time_s, depth_error_m=error, pitch_rad=pitch, heave_mps=heave, pitch_rate_radps=rate,
            speed_mps=speed, stern_plane_rad=stern, bow_plane_rad=bow, depth_m=depth,
            actions=actions, termination_reason=termination_reason,
            depth_command_m=self._depth_command_m, critical_speed_mps=self._critical_speed_mps,
            plane_limit_rad=plane_limit_rad, episode_duration_s=episode_duration_s,
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
        }
        return base | self.metrics.as_dict()


def _scenario_of(name: str) -> str:
    """The scenario name of ``"LowSpeed"`` or ``"subenv/LowSpeed-v0"`` (checked)."""
    scenario = name
    if "/" in name:
        scenario = name.removeprefix("subenv/").removesuffix("-v0")
        if name != f"subenv/{scenario}-v0":
            raise ValueError(f"env id {name!r} is not a subenv id: must be 'subenv/<Scenario>-v0'")
    if scenario == "DivePlane":
        scenario = "Randomized"
    check_scenarios([scenario])
    return scenario


def make_env(
    controller: Controller,
    scenario: str,
    *,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
) -> gym.Env:  # type: ignore[type-arg]
    """The environment of ``scenario`` (a name or ``subenv/<Name>-v0``) for ``controller``'s action space.

    ``max_duration_s`` truncates episodes earlier than the scenario does (Gymnasium's
    ``max_episode_steps``).
    """
    env_id = f"subenv/{_scenario_of(scenario)}-v0"
    kwargs: dict[str, Any] = {"control": controller.control, "alpha": controller.alpha, "vehicle": vehicle}
    if max_duration_s is not None:
        dt = gym.spec(env_id).kwargs.get("dt", 0.5)
        kwargs["max_episode_steps"] = max(1, math.ceil(max_duration_s / dt - 1e-9))
    return gym.make(env_id, **kwargs)


def run_episode(
    controller: Controller,
    env_id_or_scenario: str | gym.Env,  # type: ignore[type-arg]
    seed: int,
    *,
    episode: int = 0,
    vehicle: str | Vehicle = "suboff",
    max_duration_s: float | None = None,
    keep_trajectory: bool = True,
    options: dict[str, Any] | None = None,
) -> EpisodeResult:
    """Run ``controller`` for one episode from ``reset(seed=seed)`` and compute its metrics.

    Parameters
    ----------
    controller : Controller
        Reset with the reset ``info`` and the environment's design vehicle.
    env_id_or_scenario : str or gymnasium.Env
        A scenario name, a ``subenv/<Name>-v0`` id, or an environment made by :func:`make_env`
        (reused: pass one to run many episodes without rebuilding it). A given environment
        must have the controller's ``control`` and ``alpha``.
    seed : int
        The reset seed.
    episode : int
        Index recorded in the result.
    vehicle, max_duration_s
        For a new environment, see :func:`make_env`.
    keep_trajectory : bool
        Attach the :class:`Trajectory` to the result (memory: ~100 kB per 600 s episode).
    options : dict, optional
        ``env.reset`` options (``speed``, ``depth_command``, ``initial_state``) to place the
        episode exactly.
    """
    if isinstance(env_id_or_scenario, str):
        env = make_env(controller, env_id_or_scenario, vehicle=vehicle, max_duration_s=max_duration_s)
        try:
            return _run(controller, env, seed, episode, keep_trajectory, options)
        finally:
            env.close()
    return _run(controller, env_id_or_scenario, seed, episode, keep_trajectory, options)


def _run(
    controller: Controller,
    env: gym.Env,  # type: ignore[type-arg]
    seed: int,
    episode: int,
    keep: bool,
    options: dict[str, Any] | None = None,
) -> EpisodeResult:
    base: Any = env.unwrapped  # a DivePlaneEnv: its episode, vehicle and limits
    if (base.control, base.alpha) != (controller.control, float(controller.alpha)):
        raise ValueError(
            f"the environment has control={base.control!r}, alpha={base.alpha!r}; controller "
            f"{controller.name!r} drives control={controller.control!r}, alpha={controller.alpha!r}"
        )
    obs, info = env.reset(seed=seed, options=options)
    controller.reset(info, base.base_vehicle)
    recorder = TrajectoryRecorder(info)
    reason = ""
    while True:
        action = controller.act(obs)
        obs, _, terminated, truncated, info = env.step(action)
        recorder.record(action, info)
        if terminated or truncated:
            reason = info["termination_reason"] if terminated else ""
            break
    scheduled = float(base.episode.duration_s)
    limit = env.spec.max_episode_steps if env.spec is not None else None
    if limit is not None:
        scheduled = min(scheduled, limit * float(base.dt))
    trajectory = recorder.finish(reason, float(base.plane_limit_rad), scheduled)
    metrics = trajectory.metrics()
    return EpisodeResult(
        controller=controller.name,
        scenario=base.scenario.name,
        episode=episode,
        seed=seed,
        control=controller.control,
        alpha=float(controller.alpha),
        initial_speed_mps=float(trajectory.speed_mps[0]),
        final_speed_mps=float(trajectory.speed_mps[-1]),
        critical_speed_mps=trajectory.critical_speed_mps,
        depth_command_m=trajectory.depth_command_m,
        initial_depth_error_m=float(trajectory.depth_error_m[0]),
        episode_duration_s=scheduled,
        steps=trajectory.steps,
        metrics=metrics,
        trajectory=trajectory if keep else None,
    )


def resolve_controllers(controllers: Sequence[Controller | str] | None) -> list[Controller]:
    """Controllers from instances or registered names (None: every registered controller).

    Raises ValueError for an unknown name (listing the known ones), an empty selection, or two
    controllers with one name; TypeError for an object that is not a
    :class:`~subenv.evaluation.Controller`.
    """
    from subenv.evaluation.controller import controller_names

    if controllers is None:
        names = controller_names()
        if not names:
            raise ValueError(
                "no controllers are registered: import a package that registers some (e.g. baselines) "
                "or call subenv.evaluation.register_controller"
            )
        controllers = names
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
        Show a progress bar (tqdm, on stderr) over all episodes.
    vehicle : str or Vehicle
        The vehicle of every environment; loaded once and shared, so a controller that designs
        itself per design model does so once.
    keep_trajectories : int
        Attach trajectories to the results of the first this-many episodes of each scenario
        (for plots); 0 keeps none.
    on_episode : callable, optional
        Called with each result as it is produced.

    Returns
    -------
    list of EpisodeResult
        Ordered by controller, then scenario, then episode.
    """
    ctrls = resolve_controllers(controllers)
    the_suite = resolve_suite(suite)
    n = the_suite.episodes if episodes is None else episodes
    if not (isinstance(n, int) and not isinstance(n, bool) and n >= 1):
        raise ValueError(f"episodes={episodes!r} is invalid: must be an integer >= 1")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise ValueError(f"seed={seed!r} is invalid: must be an integer >= 0")
    design_vehicle = vehicle if isinstance(vehicle, Vehicle) else load_vehicle(vehicle)

    from tqdm.auto import tqdm

    total = len(ctrls) * len(the_suite.scenarios) * n
    results: list[EpisodeResult] = []
    with tqdm(total=total, desc="evaluate", unit="episode", disable=not progress, dynamic_ncols=True) as bar:
        for controller in ctrls:
            for scenario in the_suite.scenarios:
                bar.set_description(f"{controller.name} on {scenario}")
                env = make_env(controller, scenario, vehicle=design_vehicle,
                               max_duration_s=the_suite.max_duration_s)
                try:
                    for i in range(n):
                        result = _run(controller, env, seed + i, i, keep=i < keep_trajectories)
                        results.append(result)
                        if on_episode is not None:
                            on_episode(result)
                        bar.update(1)
                finally:
                    env.close()
    return results

