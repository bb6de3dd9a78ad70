"""A full-information reference solution per episode: the plan that certifies an episode achievable.

A prototype for issue 37's Hard track. It is a certificate, not a contestant: it knows what no
controller may know (the true state, the episode's loading, its whole drawn disturbance sequence, its
sea, the ordered depth's future) and produces a **plan**, the episode's action sequence. The
certificate is the plan itself, checked by replaying it in the environment (:func:`replay`): the
environment is deterministic given its seed and the actions, so a plan that wins on replay proves the
episode can be won. An episode the oracle cannot win is *not certified*, never "impossible".

**Why the episode's future can be known.** A step draws, from the environment's own generator and in
this order, the heave force's new term (where the episode has a disturbance) and then the eight
sensor-noise numbers (where it has sensor noise) (:mod:`subenv.envs.transition`, ``_step_block``);
a reset draws the scenario's numbers, the first heave force, then one observation's noise
(:func:`subenv.envs.episodes.draw_episode`, :func:`subenv.envs.transition.observe`). How many numbers a
step draws never depends on the action (only a diverged state skips its noise, and that ends the
episode), so the disturbance sequence is a function of the seed alone: :class:`ExactEpisode` draws it
ahead from a copy of the generator, and the tests check it against the environment's ``info``.

**One copy of the physics.** The oracle steps the environments' own compiled transition
(:func:`subenv.envs.transition.step` over the records of :mod:`subenv.envs.episodes`): its predictions
are the environment's steps, bit for bit, sea and free surface included. Its plans are searched in
two stages:

1. **Full-information MPC** (:func:`mpc_plan`): the MPC baseline (:class:`~subenv_baselines.mpc.DepthMPC`)
   fed the true state instead of the noisy observation, the episode's loading as its design model, the
   environment's limits, and the ordered depth of the moment; run to the end of the episode in the
   exact copy. Cheap (the MPC's 0.1 ms per step), and enough for most episodes.
2. **Sampling MPC with preview** (:func:`sampling_plan`), where stage 1's plan does not win: receding
   horizon, every ``replan_every`` steps the plan over the next ``horizon_steps`` is chosen among
   ``samples`` candidates (the last plan shifted, stage 1's plan, smooth random perturbations of the
   best), each rolled out in a batch of exact copies of the episode from its present state, with its
   future disturbances, by a cost of the depth error from the ordered depth of each moment, pitch,
   pitch rate and plane motion, barriers short of the pitch limit and the surface, and the termination.
   No gradients: the transition's clips and the episode's ends are not smooth, and the rollouts are the
   environment's own steps (the JAX twin's exact gradients cost 25 forward passes per gradient on
   this CPU, measured in the design note).

The actions are float32, as the environments take them; a plan is stored as they are, and replays bit
for bit.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np
from gymnasium.utils import seeding
from numba import typed

from subenv.envs import transition as tr
from subenv.envs.config import OBSERVATION_NAMES, DivePlaneConfig
from subenv.envs.dive_plane import DivePlaneEnv
from subenv.envs.episodes import Loadings, draw_episode, new_seas, write_episode, write_sea
from subenv.envs.info import step_info
from subenv.evaluation.metrics import HOLD_WINDOW_S, EpisodeMetrics
from subenv.evaluation.rollout import TrajectoryRecorder
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "Certificate",
    "ExactEpisode",
    "OracleSettings",
    "certify",
    "mpc_plan",
    "replay",
    "sampling_plan",
]

OrderedOffset = Callable[[Any], Any]
"""The ordered depth of the moment less the environment's [m], as a function of time [s] (arrays in,
arrays out): how an ordered depth that changes during the episode is given (None: it does not)."""

_ROW: Final = {key: k for k, key in enumerate(tr.REPORT_KEYS)}
_FIRST: Final = np.zeros(1, dtype=np.intp)


@dataclass(frozen=True)
class OracleSettings:
    """How hard the oracle searches, and its cost's weights (SI units, per control period).

    ``pitch_fractions``: the full-information MPC's soft pitch bounds tried in stage 1, as fractions of
    the environment's pitch limit, in order; ``sampling``: whether stage 2 runs where stage 1 fails;
    ``preview_orders``: whether stage 2 knows the ordered depth's future (False: over its horizon it
    plans for the order in force at the present, and learns of a change when it is given, as a
    controller does; the heave force and the sea it always knows ahead).
    """

    pitch_fractions: tuple[float, ...] = (0.5, 0.8)
    sampling: bool = True
    preview_orders: bool = True
    horizon_steps: int = 60
    replan_every: int = 2
    samples: int = 48
    iterations: int = 3
    knot_steps: int = 8
    noise_rad: float = 0.06
    depth: float = 1.0
    pitch: float = 10.0
    pitch_rate: float = 300.0
    plane: float = 0.05
    move: float = 20.0
    terminal_depth: float = 20.0
    band: float = 1e3
    band_m: float = 0.35
    barrier: float = 1e4
    pitch_margin: float = 0.85
    surface_margin_m: float = 0.1
    termination: float = 1e7


@dataclass(frozen=True)
class Certificate:
    """The oracle's plan for one episode and what its replay gave.

    ``actions``: float32, one row per step, as the environment takes them (``control="independent"``:
    stern, bow, normalised); ``success``: the replay's :attr:`EpisodeMetrics.success
    <subenv.evaluation.EpisodeMetrics.success>`, so the episode is *achievable* where it is True.
    """

    seed: int
    actions: np.ndarray
    success: bool
    outcome: str
    hold_max_abs_error_m: float
    stage: str  # "mpc" (stage 1), "sampling" (stage 2), or "" (not certified: the best plan tried)
    seconds: float
    tried: dict[str, bool] = field(default_factory=dict)


class ExactEpisode:
    """One seeded episode of an environment configuration, stepped through the environments' own
    transition, and copied into batches to try plans from its present state.

    The reset is :class:`~subenv.envs.DivePlaneEnv`'s (the same generator from the seed, the same
    draws in the same order, :func:`~subenv.envs.episodes.draw_episode`); ``tests/baselines/test_oracle.py``
    checks that a plan steps this copy and the environment through the same states, bit for bit.
    """

    def __init__(
        self, config: DivePlaneConfig, seed: int, ordered_offset: OrderedOffset | None = None
    ) -> None:
        self.config, self.seed = config, seed
        self.ordered_offset = ordered_offset
        rng, _ = seeding.np_random(seed)
        draw, loading, episode, state = draw_episode(config, rng, Loadings(config))
        self.draw = draw
        assert loading.vehicle is not None  # (one episode's draw: only a batch's loadings have none)
        self.vehicle: Vehicle = loading.vehicle
        self.state = np.zeros(1, dtype=tr.STATE_DTYPE)
        self.episode = np.zeros(1, dtype=tr.EPISODE_DTYPE)
        self.seas = new_seas(1)
        write_episode(self.episode, 0, episode)
        write_episode(self.state, 0, state)
        write_sea(self.seas, 0, episode)
        self.constants = config.constants()
        self.hull = config.hull
        self.obs = np.zeros((1, tr.N_OBS), dtype=np.float32)
        self.report = np.zeros((len(tr.REPORT_KEYS), 1))
        self._rngs = typed.List([rng])
        tr.observe(self.state, self.episode, _FIRST, self.obs, self._rngs, self.constants, self.report)
        self.dt_s = config.dt
        self.steps_total = math.ceil(float(self.episode[0]["duration_s"]) / self.dt_s - 1e-9)
        self.disturbances = self._disturbances(copy.deepcopy(rng))
        self.ended = False
        self.terminated = False
        # The copies that try plans: no generator drawn from (the disturbance is written in from the
        # sequence drawn ahead, the noise is not wanted), otherwise this episode.
        self._plan_episode = self.episode.copy()
        self._plan_episode["disturbance_std_N"] = 0.0
        self._plan_episode["sensor_noise"] = False

    def _disturbances(self, rng: np.random.Generator) -> np.ndarray:
        """The heave force held over each step [N] (index k: over step k, from time k dt), drawn ahead
        from a copy of the episode's generator in the transition's order (the module docstring)."""
        e, s = self.episode[0], self.state[0]
        std, noisy = float(e["disturbance_std_N"]), bool(e["sensor_noise"])
        cfg = self.constants[0]
        decay, gain = float(cfg["disturbance_decay"]), float(cfg["disturbance_gain"])
        d = np.empty(self.steps_total + 1)
        d[0] = float(s["disturbance_N"])
        for k in range(self.steps_total):
            d[k + 1] = d[k]
            if std > 0.0:
                d[k + 1] = decay * d[k] + gain * rng.normal(0.0, std)
            if noisy:
                for _ in range(tr.N_OBS):
                    rng.normal(0.0, 1.0)
        return d

    # --- the episode itself ----------------------------------------------------------------------
    @property
    def steps(self) -> int:
        """Steps taken since the reset."""
        return int(self.state[0]["steps"])

    @property
    def info(self) -> dict[str, Any]:
        """The last step's ``info`` (the reset's before the first step), as the environment reports it."""
        return step_info(self.report[:, 0].tolist())

    def ordered_depth_m(self, time_s: Any) -> Any:
        """The ordered depth at ``time_s`` [m]."""
        command = float(self.episode[0]["depth_command_m"])
        return command if self.ordered_offset is None else command + self.ordered_offset(time_s)

    def true_observation(self) -> np.ndarray:
        """The observation without sensor noise, its depth error from the ordered depth of the moment
        (:data:`~subenv.envs.config.OBSERVATION_NAMES` order, float32 as the environment's)."""
        s = self.state[0]
        depth = float(s["depth_m"])
        values = {
            "depth_error_m": depth - float(self.ordered_depth_m(float(s["time_s"]))),
            "pitch_rad": s["pitch_rad"],
            "heave_mps": s["heave_mps"],
            "pitch_rate_radps": s["pitch_rate_radps"],
            "speed_mps": s["speed_mps"],
            "stern_plane_rad": s["stern_plane_rad"],
            "bow_plane_rad": s["bow_plane_rad"],
            "depth_m": depth,
        }
        return np.array([values[name] for name in OBSERVATION_NAMES], dtype=np.float32)

    def step(self, action: np.ndarray) -> None:
        """One step of the episode with ``action`` (rounded to float32, as the environment takes it)."""
        a = np.asarray(action, dtype=np.float32).astype(np.float64).reshape(1, -1)
        active = np.ones(1, dtype=bool)
        if (
            tr.step(
                self.state,
                self.episode,
                self.seas,
                a,
                active,
                self.obs,
                self._rngs,
                self.constants,
                self.hull,
                self.report,
            )
            >= 0
        ):
            raise ValueError(f"action={action!r} is invalid: must be finite")
        self.terminated = bool(self.report[_ROW["terminated"], 0] > 0.0)
        self.ended = self.terminated or bool(self.report[_ROW["truncated"], 0] > 0.0)

    def copy(self) -> ExactEpisode:
        """An independent copy at the present state (its generator too)."""
        other = copy.copy(self)
        other.state, other.obs, other.report = self.state.copy(), self.obs.copy(), self.report.copy()
        rng = copy.deepcopy(self._rngs[0])
        other._rngs = typed.List([rng])
        return other

    # --- plans tried from the present state ------------------------------------------------------
    def rollout(self, plans: np.ndarray) -> np.ndarray:
        """The reports (:data:`~subenv.envs.transition.REPORT_KEYS`) of each plan of ``plans`` (shape
        (K, H, n_actions), actions) from the present state, shape (H', len(REPORT_KEYS), K) with H' the
        steps left in the episode, at most H: K copies of the episode stepped together, each holding
        the episode's future heave force. (A copy steps on after its episode ended; its report says so.)"""
        K, H = plans.shape[:2]
        H = min(H, self.steps_total - self.steps)
        state = np.repeat(self.state, K)
        episode = np.repeat(self._plan_episode, K)
        seas = np.repeat(self.seas, K, axis=0) if self.episode[0]["n_waves"] > 0 else new_seas(K)
        obs = np.zeros((K, tr.N_OBS), dtype=np.float32)
        active = np.ones(K, dtype=bool)
        actions = plans.astype(np.float32).astype(np.float64)
        reports = np.zeros((H, len(tr.REPORT_KEYS), K))
        for h in range(H):
            state["disturbance_N"] = self.disturbances[self.steps + h]
            tr.step(
                state,
                episode,
                seas,
                np.ascontiguousarray(actions[:, h]),
                active,
                obs,
                self._rngs,
                self.constants,
                self.hull,
                reports[h],
            )
        return reports

    def rollout_costs(self, plans: np.ndarray, settings: OracleSettings) -> np.ndarray:
        """The cost (:class:`OracleSettings`) of each plan of ``plans`` from the present state
        (:meth:`rollout`), shape (K,)."""
        reports = self.rollout(plans)
        cfg = self.constants[0]
        limit, pitch_limit = float(cfg["plane_limit_rad"]), float(cfg["max_pitch_rad"])
        broach = float(cfg["broach_depth_m"])
        end_s = float(self.episode[0]["duration_s"])
        w = settings
        t = reports[:, _ROW["time_s"]]
        depth, pitch = reports[:, _ROW["depth_m"]], reports[:, _ROW["pitch_rad"]]
        now = float(self.state[0]["time_s"])
        error = depth - self.ordered_depth_m(t if w.preview_orders else np.full_like(t, now))
        planes = reports[:, [_ROW["stern_plane_rad"], _ROW["bow_plane_rad"]]]  # (H, 2, K)
        before = np.array([self.state[0]["stern_plane_rad"], self.state[0]["bow_plane_rad"]])
        moves = np.diff(
            planes, axis=0, prepend=np.broadcast_to(before[None, :, None], (1, *planes.shape[1:]))
        )
        stage = (
            w.depth * error**2
            + w.pitch * pitch**2
            + w.pitch_rate * reports[:, _ROW["pitch_rate_radps"]] ** 2
            + w.plane * np.sum((planes / limit) ** 2, axis=1)
            + w.move * np.sum(moves**2, axis=1)
            + w.barrier * np.maximum(np.abs(pitch) - w.pitch_margin * pitch_limit, 0.0) ** 2
            + w.barrier * np.maximum(broach + w.surface_margin_m - depth, 0.0) ** 2
            + np.where(
                t >= end_s - HOLD_WINDOW_S - 10.0,
                w.band * np.maximum(np.abs(error) - w.band_m, 0.0) ** 2,
                0.0,
            )
        )
        ended = reports[:, _ROW["terminated"]] > 0.0
        # Up to and including the step that ended it; then the termination's penalty, larger the earlier.
        alive: np.ndarray = (np.cumsum(ended, axis=0) - ended) == 0
        cost = np.sum(np.where(alive, stage, 0.0), axis=0)
        first_end = alive & ended
        cost += np.sum(np.where(first_end, w.termination * (1.0 + (end_s - t) / end_s), 0.0), axis=0)
        survived = ~np.any(ended, axis=0)
        return cost + np.where(survived, w.terminal_depth * error[-1] ** 2, 0.0)


# --- stage 1: the MPC baseline with full information ---------------------------------------------
def mpc_plan(episode: ExactEpisode, pitch_fraction: float = 0.5) -> np.ndarray:
    """Stage 1: run :class:`~subenv_baselines.mpc.DepthMPC` on ``episode`` (a copy is stepped) with full
    information; its actions, float32, one row per step."""
    from subenv_baselines.mpc import DepthMPC

    config = episode.config
    mpc = DepthMPC(
        plane_rate_limit_radps=config.plane_rate_limit_radps,
        max_pitch_rad=config.max_pitch_rad,
        max_depth_error_m=config.max_depth_error_m,
        pitch_fraction=pitch_fraction,
    )
    run = episode.copy()
    mpc.reset_batch([run.info], run.vehicle)
    actions = []
    while not run.ended:
        action = mpc.act_batch(run.true_observation()[None])[0].astype(np.float32)
        actions.append(action)
        run.step(action)
    return np.array(actions, dtype=np.float32)


# --- stage 2: sampling MPC over exact copies, with preview ---------------------------------------
def sampling_plan(
    episode: ExactEpisode,
    guide: np.ndarray,
    settings: OracleSettings = OracleSettings(),
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """Stage 2: receding-horizon sampling over exact copies of ``episode`` (a copy is stepped), started
    from ``guide`` (a plan, e.g. stage 1's); its actions, float32, one row per step."""
    rng = np.random.default_rng(episode.seed) if rng is None else rng
    run = episode.copy()
    n_actions = guide.shape[1]
    total = run.steps_total
    # (held at its last action to the episode's end and a horizon beyond: a guide that ended early too)
    padded = np.concatenate(
        [guide, np.repeat(guide[-1:], total + settings.horizon_steps - len(guide), axis=0)]
    )
    plan = padded[: settings.horizon_steps].astype(np.float64)
    executed: list[np.ndarray] = []
    knots = np.arange(0, settings.horizon_steps + settings.knot_steps, settings.knot_steps)
    while not run.ended:
        k = run.steps
        H = min(settings.horizon_steps, total - k)
        # Candidates: the last plan shifted (held at its end), and the guide's continuation.
        base = np.stack([plan[:H], padded[k : k + H]])
        best, best_cost = base[0], math.inf
        costs = run.rollout_costs(base, settings)
        order = np.argsort(costs)
        best, best_cost = base[order[0]], float(costs[order[0]])
        sigma = settings.noise_rad / config_limit(run)
        for _ in range(settings.iterations):
            noise = rng.normal(0.0, sigma, (settings.samples, len(knots), n_actions))
            smooth = np.stack(
                [
                    np.stack(
                        [np.interp(np.arange(H), knots, noise[j, :, a]) for a in range(n_actions)], axis=1
                    )
                    for j in range(settings.samples)
                ]
            )
            tries = np.clip(best[None] + smooth, -1.0, 1.0)
            costs = run.rollout_costs(tries, settings)
            # The elite's mean, tried too: it often beats each of its members.
            elite = tries[np.argsort(costs)[: max(2, settings.samples // 8)]]
            mean = np.clip(elite.mean(axis=0), -1.0, 1.0)
            mean_cost = float(run.rollout_costs(mean[None], settings)[0])
            j = int(np.argmin(costs))
            for candidate, value in ((tries[j], float(costs[j])), (mean, mean_cost)):
                if value < best_cost:
                    best, best_cost = candidate, value
            sigma *= 0.6
        for h in range(min(settings.replan_every, H)):
            action = best[h].astype(np.float32)
            executed.append(action)
            run.step(action)
            if run.ended:
                break
        done = min(settings.replan_every, H)
        plan = np.concatenate([best[done:], np.repeat(best[-1:], done, axis=0)])
        if len(plan) < settings.horizon_steps:
            plan = np.concatenate([plan, np.repeat(plan[-1:], settings.horizon_steps - len(plan), axis=0)])
    return np.array(executed, dtype=np.float32)


def config_limit(episode: ExactEpisode) -> float:
    """The planes' limit [rad] of the episode's environment."""
    return float(episode.config.plane_limit_rad)


# --- the certificate --------------------------------------------------------------------------------
def replay(config: DivePlaneConfig, seed: int, actions: np.ndarray) -> EpisodeMetrics:
    """Replay ``actions`` in the environment (:class:`~subenv.envs.DivePlaneEnv`, reset with ``seed``)
    and judge the episode as the evaluation harness does (:meth:`Trajectory.metrics
    <subenv.evaluation.Trajectory.metrics>`): its outcome and success. Steps past the plan's end hold
    its last action (a plan shorter than the episode is not a certificate unless it ended it)."""
    env = DivePlaneEnv(config=config)
    _, info = env.reset(seed=seed)
    recorder = TrajectoryRecorder(info)
    k, terminated, truncated = 0, False, False
    hold = np.zeros(config.n_actions, dtype=np.float32) if len(actions) == 0 else actions[-1]
    while not (terminated or truncated):
        action = actions[k] if k < len(actions) else hold
        _, _, terminated, truncated, info = env.step(action)
        recorder.record(action, info)
        k += 1
    assert env.episode is not None
    trajectory = recorder.finish(
        info["termination_reason"] if terminated else "",
        float(config.plane_limit_rad),
        float(env.episode.duration_s),
        config.length_ratio,
    )
    return trajectory.metrics()


def certify(
    config: DivePlaneConfig,
    seed: int,
    ordered_offset: OrderedOffset | None = None,
    settings: OracleSettings = OracleSettings(),
) -> Certificate:
    """The oracle's plan for the episode of ``reset(seed=seed)`` of an environment of ``config``
    (``control="independent"``), validated by :func:`replay`; stops at the first plan that wins.

    ``ordered_offset``: an ordered depth that changes during the episode (:data:`OrderedOffset`); the
    replay then judges the episode against the environment's ordered depth, the final one.
    """
    if config.control != "independent":
        raise ValueError(f"control={config.control!r} is invalid for the oracle: must be 'independent'")
    start = time.perf_counter()
    episode = ExactEpisode(config, seed, ordered_offset)
    tried: dict[str, bool] = {}
    best: tuple[np.ndarray, EpisodeMetrics] | None = None
    guide: np.ndarray | None = None
    for fraction in settings.pitch_fractions:
        plan = mpc_plan(episode, fraction)
        metrics = replay(config, seed, plan)
        tried[f"mpc{fraction:g}"] = metrics.success
        if guide is None or _better(metrics, best[1] if best else None):
            guide = plan
            best = (plan, metrics)
        if metrics.success:
            return _certificate(seed, plan, metrics, "mpc", start, tried)
    assert best is not None and guide is not None
    if settings.sampling:
        plan = sampling_plan(episode, guide, settings)
        metrics = replay(config, seed, plan)
        tried["sampling"] = metrics.success
        if metrics.success:
            return _certificate(seed, plan, metrics, "sampling", start, tried)
        if _better(metrics, best[1]):
            best = (plan, metrics)
    return _certificate(seed, best[0], best[1], "", start, tried)


def _better(metrics: EpisodeMetrics, than: EpisodeMetrics | None) -> bool:
    """Whether an unsuccessful plan came closer: not terminated, then a smaller largest error over the
    hold window."""
    if than is None:
        return True
    return (not metrics.terminated, -metrics.hold_max_abs_error_m) > (
        not than.terminated,
        -than.hold_max_abs_error_m,
    )


def _certificate(
    seed: int, plan: np.ndarray, metrics: EpisodeMetrics, stage: str, start: float, tried: dict[str, bool]
) -> Certificate:
    return Certificate(
        seed=seed,
        actions=plan,
        success=bool(metrics.success),
        outcome=metrics.outcome,
        hold_max_abs_error_m=float(metrics.hold_max_abs_error_m),
        stage=stage if metrics.success else "",
        seconds=time.perf_counter() - start,
        tried=tried,
    )
