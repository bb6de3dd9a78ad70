"""DivePlaneVectorEnv: N dive-plane environments stepped as one array through the compiled transition."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Final, cast

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numba import typed

from subenv.envs import transition as tr
from subenv.envs.dive_plane import OBSERVATION_NAMES, DivePlaneEnv
from subenv.envs.handoff import SPIN_S, SPIN_WHEN_GAP_S, Crew
from subenv.scenarios.scenario import EpisodeConfig, Scenario
from subenv.vehicles.vehicle import Vehicle

__all__ = ["DivePlaneVectorEnv"]

_REASONS: Final = np.array(tr.REASONS, dtype=object)
_INFO_KEYS: Final = (*tr.REPORT_KEYS[: tr.R_REASON], "termination_reason")
"""The single environment's info keys (subenv.envs.dive_plane._info), as the report's rows."""
_MASK_KEYS: Final = tuple("_" + key for key in _INFO_KEYS)
_AUTORESET_MODES: Final = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED)
_BATCH_RESETS: Final = 4
"""Draw this many resets or more as arrays (``_draw_batch``): about where it costs less than one at a time."""
_GAP_CAP_S: Final = 2e-3
"""A pause longer than this counts as this long in the moving average of the time between steps (so that
the workers poll again a dozen steps after a pause)."""
_COPY_REASONS_FROM: Final = 1024
"""From this many sub-environments the info's termination reasons start as a copy of an array of ""
(below it the fixed cost of the copy and the indexing outweighs what it saves: 3 µs a step)."""
ENVS_PER_THREAD: Final = 512
"""``threads=None`` uses one thread per this many sub-environments, up to the available cores."""


class DivePlaneVectorEnv(VectorEnv[np.ndarray, np.ndarray, np.ndarray]):
    """``num_envs`` :class:`~subenv.envs.DivePlaneEnv` stepped together as arrays.

    ``gym.make_vec(id, num_envs=N)`` returns this for every subenv id. Every sub-environment is
    one row of a float table that the compiled transition (:mod:`subenv.envs.transition`, the
    same one :class:`~subenv.envs.DivePlaneEnv` steps through) advances in one call; nothing of
    the physics is copied. Each sub-environment has its own ``numpy.random.Generator``, seeded
    as ``SyncVectorEnv`` seeds its sub-environments (``reset(seed=s)``: ``s + i`` for env ``i``),
    its own scenario draws, episode length and resets, so the results equal ``SyncVectorEnv``
    over ``gym.make(id)`` step for step (``tests/envs/test_vector_env.py``).

    Parameters
    ----------
    num_envs : int
        Number of sub-environments, >= 1.
    max_episode_steps : int, optional
        Truncate an episode after this many steps, as ``gymnasium.wrappers.TimeLimit`` does
        (``gym.make_vec`` passes the id's value); the scenario's own duration applies as well.
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default: the step after an episode ends resets that sub-environment and
        returns its first observation, reward 0), ``SAME_STEP`` (the step that ends an episode
        resets at once; the last observation and info are in ``info["final_obs"]`` and
        ``info["final_info"]``) or ``DISABLED`` (reset ended sub-environments with
        ``reset(options={"reset_mask": mask})``). Stored in ``metadata["autoreset_mode"]``.
    render_mode : {None, "rgb_array"}
        ``render()`` returns a one-element tuple with the first sub-environment's frame.
    threads : int, optional
        Step the sub-environments on this many threads, the calling one and pool threads (the
        compiled transition releases the GIL): each has a range of the rows and, once done with
        it, steps chunks of the others', so they finish together (:mod:`subenv.envs.handoff`).
        Default: one per :data:`ENVS_PER_THREAD` sub-environments, at most the cores available to
        the process. Results do not depend on it. While the caller's steps come close together
        (under :data:`~subenv.envs.handoff.SPIN_WHEN_GAP_S` apart on average) and there are no
        more threads than cores, the pool threads poll for the next step for up to
        :data:`~subenv.envs.handoff.SPIN_S` instead of sleeping; ``close()`` sends them away at once.
    **kwargs
        The arguments of :class:`~subenv.envs.DivePlaneEnv` (scenario, vehicle, control, ...),
        shared by all sub-environments.

    Notes
    -----
    ``info`` is Gymnasium's vector form: for every key of the single environment's ``info``
    an array over the sub-environments and a ``"_" + key`` mask. Actions are a
    ``(num_envs, n_actions)`` array (``(num_envs,)`` is accepted with one action);
    out-of-range actions are clipped; a NaN or infinite action raises before any
    sub-environment steps.

    The compiled transition integrates the control periods of 64 sub-environments at a time
    (SIMD code: :func:`subenv.dynamics.integrate.control_period_lanes`), with the same bits as
    one at a time. When several sub-environments reset together and the scenario's loading is the
    same in every episode, their episodes are drawn as arrays (:meth:`_draw_batch`): the same
    numbers from the same generators as one reset at a time, without the Python cost of one draw
    each.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012 - Gymnasium's convention
        "render_modes": ["rgb_array"],
        "render_fps": 30,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        *,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        render_mode: str | None = None,
        threads: int | None = None,
        **kwargs: Any,
    ) -> None:
        if not (isinstance(num_envs, (int, np.integer)) and not isinstance(num_envs, bool) and num_envs >= 1):
            raise ValueError(f"num_envs={num_envs!r} is invalid: must be an integer >= 1")
        if max_episode_steps is not None and not (
            isinstance(max_episode_steps, (int, np.integer)) and not isinstance(max_episode_steps, bool)
            and max_episode_steps >= 1
        ):
            raise ValueError(f"max_episode_steps={max_episode_steps!r} is invalid: must be None or an integer >= 1")
        try:
            mode = AutoresetMode(autoreset_mode)
        except ValueError:
            raise ValueError(
                f"autoreset_mode={autoreset_mode!r} is invalid: must be one of {[m.value for m in _AUTORESET_MODES]}"
            ) from None
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode={render_mode!r} is invalid: must be None or one of {self.metadata['render_modes']} "
                "(the vector environment renders its first sub-environment)"
            )
        if threads is not None and not (
            isinstance(threads, (int, np.integer)) and not isinstance(threads, bool) and threads >= 1
        ):
            raise ValueError(f"threads={threads!r} is invalid: must be None or an integer >= 1")
        self.single_env = DivePlaneEnv(**kwargs)
        """An environment that is never stepped: it holds the configuration all sub-environments share."""

        self.num_envs = int(num_envs)
        self.max_episode_steps = None if max_episode_steps is None else int(max_episode_steps)
        self.autoreset_mode = mode
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        self.render_mode = render_mode
        if threads is None:
            threads = min(_available_cores(), max(1, self.num_envs // ENVS_PER_THREAD))
        self.threads = min(int(threads), self.num_envs)
        self._crew = Crew(self.threads - 1)
        self._may_poll = self.threads <= _available_cores()  # (polling threads beyond the cores would take turns)
        self._gap_s = math.inf  # moving average of the caller's time between steps (workers poll when short)
        self._returned_at: float | None = None  # when step() last returned
        self.single_action_space = self.single_env.action_space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.single_observation_space = self.single_env.observation_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)

        n = self.num_envs
        self._cfg = self.single_env._constants(self.max_episode_steps)
        self._hull = self.single_env._hull
        self._rows = np.zeros((n, tr.N_COLUMNS))
        self._rows[:, tr.CRITICAL_SPEED] = np.nan
        self._obs = np.zeros((n, len(OBSERVATION_NAMES)), dtype=np.float32)
        self._generators: list[np.random.Generator | None] = [None] * n
        self._seeds: list[int | None] = [None] * n
        self._rngs: Any = None  # numba typed list of the generators, built on the first reset
        self._done = np.zeros(n, dtype=bool)  # the episode ended on the last step
        self._any_done = False
        self._started = np.zeros(n, dtype=bool)
        self._ready = False  # every sub-environment has been reset once
        self._everyone = np.ones(n, dtype=bool)
        self._no_reasons = np.full(n, _REASONS[0], dtype=object)  # every termination_reason "" (not terminated)
        self.vehicles: list[Vehicle] = [self.single_env.base_vehicle] * n
        """Each sub-environment's vehicle (its episode's loading)."""
        self._episodes: list[EpisodeConfig | None] = [None] * n
        # Episodes drawn in a batch are kept as their scenario and uniform numbers until someone asks
        # for them (as arrays: a batch stores them without a Python loop over its resets).
        self._unbuilt = np.zeros(n, dtype=bool)
        self._unbuilt_scenario = np.full(n, None, dtype=object)
        self._unbuilt_units = np.empty((n, 0))
        self._history: list[tuple[float, float, float]] = []  # of the first sub-environment, for render()

    # --- Gymnasium API ----------------------------------------------------------------------
    def reset(
        self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset all sub-environments (or those in ``options["reset_mask"]``).

        ``seed``: None (each sub-environment keeps its generator, or gets a random one), an int
        ``s`` (sub-environment ``i`` is seeded with ``s + i``) or one seed per sub-environment.
        Other ``options`` are :class:`~subenv.envs.DivePlaneEnv`'s, applied to every reset one.
        """
        n = self.num_envs
        if seed is None:
            seeds: list[int | None] = [None] * n
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(cast(Sequence[Any], seed))
            if len(seeds) != n:
                raise ValueError(f"seed has {len(seeds)} entries: a list of seeds must have num_envs={n} entries")
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is None:
            mask = self._everyone
        elif not (isinstance(mask, np.ndarray) and mask.dtype == np.bool_ and mask.shape == (n,) and mask.any()):
            raise ValueError(
                f"options['reset_mask']={mask!r} is invalid: must be a bool array of shape ({n},) with a True value"
            )
        indices = np.flatnonzero(mask)
        for i in indices:
            if seeds[i] is not None or self._generators[i] is None:
                self._generators[i], self._seeds[i] = seeding.np_random(seeds[i])
                if self._rngs is not None:
                    self._rngs[i] = self._generators[i]
        if self._rngs is None:
            self._rngs = typed.List(self._generators)
        report = np.zeros((tr.N_REPORT, n))
        self._reset_envs(indices, options, report)
        self._done[indices] = False
        self._any_done = bool(self._done.any())
        return self._obs.copy(), self._infos(report, None if mask is self._everyone else mask)

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if self._returned_at is not None:
            gap = min(time.perf_counter() - self._returned_at, _GAP_CAP_S)
            self._gap_s = gap if math.isinf(self._gap_s) else self._gap_s + 0.2 * (gap - self._gap_s)
        try:
            return self._step(actions)
        finally:
            self._returned_at = time.perf_counter()

    def _step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._ready:
            if not self._started.all():
                raise _reset_needed(np.flatnonzero(~self._started))
            self._ready = True
        actions = self._check_actions(actions)
        mode = self.autoreset_mode
        active = self._everyone
        resetting: np.ndarray | None = None
        if self._any_done:
            if mode is AutoresetMode.DISABLED:
                raise RuntimeError(
                    f"sub-environments {np.flatnonzero(self._done).tolist()} have ended their episodes and "
                    "autoreset_mode is DISABLED: reset them with reset(options={'reset_mask': mask})"
                )
            resetting = np.flatnonzero(self._done)  # NEXT_STEP: these reset instead of stepping
            active = ~self._done
        report = np.empty((tr.N_REPORT, self.num_envs))  # one row per info key, filled by the kernels
        if self.threads == 1:  # (step_batch checks the actions before it steps anything)
            _check_finite(tr.step_batch(self._rows, actions, active, self._obs, self._rngs, 0, self._cfg, self._hull,
                                        report), actions)
            if resetting is not None:
                self._reset_envs(resetting, {}, report)  # reported as reward 0, not terminated, not truncated
        else:
            _check_finite(tr.first_non_finite(actions, active), actions)
            self._step_rows(actions, active, report, resetting)
        if self.render_mode is not None and active[0]:
            row = self._rows[0]
            self._history.append((row[tr.TIME], row[tr.DEPTH], row[tr.COMMAND]))
        rewards = report[tr.R_REWARD].copy()
        terminated, truncated = report[tr.R_TERMINATED:tr.R_TRUNCATED + 1] > 0.0
        done = terminated | truncated
        self._any_done = np.count_nonzero(done) > 0
        self._done = done
        if mode is not AutoresetMode.SAME_STEP or not self._any_done:
            return self._obs.copy(), rewards, terminated, truncated, self._infos(report, None)
        final_obs = np.full(self.num_envs, None, dtype=object)
        ended = np.flatnonzero(done)
        for i in ended:
            final_obs[i] = self._obs[i].copy()
        final = {"final_obs": final_obs, "_final_obs": done.copy(), "final_info": self._infos(report.copy(), done),
                 "_final_info": done.copy()}
        self._reset_envs(ended, {}, report)
        self._done = np.zeros(self.num_envs, dtype=bool)
        self._any_done = False
        infos = self._infos(report, None)
        infos.update(final)
        return self._obs.copy(), rewards, terminated, truncated, infos

    def render(self) -> tuple[np.ndarray, ...] | None:
        """A one-element tuple with the first sub-environment's frame (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            from gymnasium import logger

            logger.warn(
                "You are calling render method without specifying any render mode. "
                'Set render_mode at initialization, e.g. gym.make_vec("subenv/DivePlane-v0", num_envs=4, '
                'render_mode="rgb_array")'
            )
            return None
        from subenv.envs.rendering import render_rgb

        return (render_rgb(self.single_env._frame(self._rows[0], self._history)),)

    def set_scenario(self, scenario: str | Scenario) -> None:
        """Draw every sub-environment's following episodes from ``scenario``
        (:meth:`DivePlaneEnv.set_scenario <subenv.envs.DivePlaneEnv.set_scenario>`); episodes under
        way are not changed."""
        self.single_env.set_scenario(scenario)

    @property
    def scenario(self) -> Scenario:
        """The scenario the sub-environments draw their episodes from."""
        return self.single_env.scenario

    @property  # type: ignore[misc]  # a tuple, as SyncVectorEnv.np_random
    def np_random(self) -> tuple[np.random.Generator | None, ...]:  # type: ignore[override]
        """Each sub-environment's generator (None before its first reset), as ``SyncVectorEnv.np_random``."""
        return tuple(self._generators)

    @property
    def np_random_seed(self) -> tuple[int | None, ...]:  # type: ignore[override]
        """Each sub-environment's seed (-1 for a random one, None before its first reset)."""
        return tuple(self._seeds)

    @property
    def episodes(self) -> list[EpisodeConfig | None]:
        """Each sub-environment's episode draw (None before its first reset)."""
        if self._unbuilt.any():  # built on demand: a batch of resets draws numbers, not EpisodeConfigs
            weight_N = self.single_env.base_vehicle.weight_N
            for i in np.flatnonzero(self._unbuilt).tolist():
                scenario = self._unbuilt_scenario[i]
                units = self._unbuilt_units[i, : scenario._units_per_draw].copy()
                self._episodes[i] = scenario._episode_from_units(units, weight_N)
            self._unbuilt[:] = False
        return list(self._episodes)

    @property
    def state(self) -> np.ndarray:
        """(pitch [rad], heave [m/s], pitch rate [rad/s], depth [m]) of every sub-environment, a copy."""
        return self._rows[:, tr.PITCH:tr.DEPTH + 1].copy()

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_rngs"] = None  # a numba typed list does not pickle
        state["_crew"] = len(self._crew.workers)  # (threads and mailboxes are this process's)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._crew = Crew(state["_crew"])
        if any(g is not None for g in self._generators):
            self._rngs = typed.List([g if g is not None else np.random.default_rng() for g in self._generators])

    # --- helpers ----------------------------------------------------------------------------
    def _step_rows(self, actions: np.ndarray, active: np.ndarray, report: np.ndarray,
                   resetting: np.ndarray | None) -> None:
        """Step the active rows on :attr:`threads` threads (this one and the workers'), and reset
        ``resetting`` on this one meanwhile (:meth:`Crew.step <subenv.envs.handoff.Crew.step>`).

        Resets run in Python and hold the GIL; the compiled steps release it. The threads claim the rows
        in chunks, so this thread steps fewer of them when it has resets to draw. The threads touch
        different rows, generators and report columns.
        """
        spin_s = SPIN_S if self._may_poll and self._gap_s < SPIN_WHEN_GAP_S else 0.0
        self._crew.step(_thread_pool(self.threads), (self._rows, self._obs, self._rngs, self._cfg, self._hull),
                        actions, active, report, spin_s,
                        None if resetting is None else lambda: self._reset_envs(resetting, {}, report))

    def close_extras(self, **kwargs: Any) -> None:
        """Tell polling workers to leave."""
        self._crew.stop()

    def _check_actions(self, actions: Any) -> np.ndarray:
        n, shape = self.num_envs, tuple(self.single_action_space.shape or ())
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != (n, *shape):
            if shape == (1,) and a.shape == (n,):
                a = a.reshape(n, 1)
            else:
                raise ValueError(
                    f"actions has shape {np.shape(actions)}: must have shape {(n, *shape)} "
                    f"(num_envs={n}, control={self.single_env.control!r})"
                )
        return a if a.flags.c_contiguous else np.ascontiguousarray(a)

    def _reset_envs(self, indices: Sequence[int] | np.ndarray, options: dict[str, Any], report: np.ndarray) -> None:
        """Draw new episodes for ``indices`` (and write their columns of ``report``)."""
        rows, vehicles, index = self._rows, self.vehicles, np.asarray(indices, dtype=np.intp)
        if len(index) >= _BATCH_RESETS and not options and self.single_env.scenario._batch_ready:
            self._draw_batch(index)
        else:
            draw, generators, episodes = self.single_env._draw_episode, self._generators, self._episodes
            for i in index.tolist():
                vehicles[i], episodes[i], rows[i] = draw(generators[i], options)  # type: ignore[arg-type]
            self._unbuilt[index] = False
        tr.observe_batch(rows, index, self._obs, self._rngs, self._cfg, report)
        if not self._ready:
            self._started[index] = True
        if self.render_mode is not None and 0 in index:
            self._history = [(0.0, rows[0, tr.DEPTH], rows[0, tr.COMMAND])]

    def _draw_batch(self, index: np.ndarray) -> None:
        """Draw the episodes of ``index`` as arrays (a scenario with one loading, no options).

        Each sub-environment's generator gives the numbers its single environment's reset would
        (:func:`~subenv.envs.transition.draw_reset_numbers`), and the same code turns them into the
        draw and the row, over arrays (:meth:`DivePlaneEnv._episode_row
        <subenv.envs.DivePlaneEnv._episode_row>`): the rows are those of one reset at a time, value
        for value, without a Python episode per reset (resets hold the GIL).
        """
        single = self.single_env
        scenario = single.scenario
        units = np.empty((len(index), scenario._units_per_draw))
        disturbances = np.empty(len(index))
        tr.draw_reset_numbers(self._rngs, index, units, scenario.disturbance_std_N, disturbances)
        vehicle, values = single._episode_row(scenario._sample_batch(units, single.base_vehicle.weight_N), {},
                                              disturbances)
        block = np.empty((len(index), tr.N_COLUMNS))
        drawn = [(column, value) for column, value in enumerate(values) if isinstance(value, np.ndarray)]
        for column, _ in drawn:
            values[column] = 0.0
        block[:] = values  # the columns every episode shares
        for column, value in drawn:
            block[:, column] = value
        self._rows[index] = block
        vehicles = self.vehicles
        for i in index.tolist():
            vehicles[i] = vehicle
        k = units.shape[1]
        if self._unbuilt_units.shape[1] < k:  # (a scenario that draws more numbers than any before)
            wider = np.empty((self.num_envs, k))
            wider[:, : self._unbuilt_units.shape[1]] = self._unbuilt_units
            self._unbuilt_units = wider
        self._unbuilt_units[index, :k] = units
        self._unbuilt_scenario[index] = scenario
        self._unbuilt[index] = True

    def _infos(self, report: np.ndarray, mask: np.ndarray | None) -> dict[str, Any]:
        """Gymnasium's vector ``info`` from a step's report (whose rows it hands out); with ``mask``,
        only those sub-environments report, as in ``SyncVectorEnv``."""
        values = list(report[: tr.R_REASON])
        codes = report[tr.R_REASON]
        if self.num_envs < _COPY_REASONS_FROM:
            reasons = _REASONS.take(codes.astype(np.intp))
        else:  # copying an array of one string costs a third of a take; then set the few that ended
            ended = np.flatnonzero(codes != 0.0)
            reasons = self._no_reasons.copy()
            reasons[ended] = _REASONS.take(codes[ended].astype(np.intp))
        values.append(reasons)
        if mask is None:
            masks = np.ones((len(_INFO_KEYS), self.num_envs), dtype=bool)
        else:  # SyncVectorEnv leaves the others at zero (None for strings)
            for value in values:
                value[~mask] = None if value.dtype == object else 0.0
            masks = np.tile(mask, (len(_INFO_KEYS), 1))
        infos: dict[str, Any] = dict(zip(_INFO_KEYS, values))
        infos.update(zip(_MASK_KEYS, masks))
        return infos


def _check_finite(bad: int, actions: np.ndarray) -> None:
    if bad >= 0:
        raise ValueError(f"actions[{bad}]={actions[bad].tolist()!r} is invalid: must be finite (no NaN or inf)")


def _available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


_POOL: list[Any] = []  # (pid, ThreadPoolExecutor): a pool does not survive fork, so it is per process


def _thread_pool(workers: int) -> ThreadPoolExecutor:
    if not _POOL or _POOL[0][0] != os.getpid() or _POOL[0][1]._max_workers < workers:
        _POOL[:] = [(os.getpid(), ThreadPoolExecutor(max_workers=max(workers, _available_cores()),
                                                     thread_name_prefix="subenv-vector"))]
    return _POOL[0][1]


def _reset_needed(indices: np.ndarray) -> Exception:
    from gymnasium.error import ResetNeeded

    return ResetNeeded(f"Cannot call step() before reset(): sub-environments {indices.tolist()[:10]} were never reset")
