"""DivePlaneVectorEnv: N dive-plane environments stepped as arrays through the compiled transition."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Final

import numba
import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numba import typed

from subenv import _validation as check
from subenv.dynamics._jit import read_only
from subenv.envs import transition as tr
from subenv.envs._compiling import first_call
from subenv.envs._interrupts import interrupts_deferred
from subenv.envs.config import DivePlaneConfig
from subenv.envs.episodes import (
    Loadings,
    check_options,
    draw_episode,
    draw_episode_batch,
    for_vehicle,
    new_seas,
    write_episode,
    write_sea,
)
from subenv.envs.info import step_infos
from subenv.envs.validity import SurfaceValidityWatch
from subenv.scenarios.scenario import EpisodeConfig, Scenario
from subenv.vehicles.vehicle import Vehicle

__all__ = ["ENVS_PER_THREAD", "DivePlaneVectorEnv"]

_AUTORESET_MODES: Final = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED)
_BATCH_RESETS: Final = 4
"""Draw this many resets or more as arrays (:func:`~subenv.envs.episodes.draw_episode_batch`): about
where it costs less than one at a time."""
ENVS_PER_THREAD: Final = 512
"""``threads=None`` uses one thread per this many sub-environments, up to numba's thread count."""
_REWARD, _TERMINATED, _TRUNCATED = (
    tr.REPORT_KEYS.index(key) for key in ("reward", "terminated", "truncated")
)
_TIME, _DEPTH, _COMMAND, _SPEED = (
    tr.REPORT_KEYS.index(key) for key in ("time_s", "depth_m", "depth_command_m", "speed_mps")
)


class DivePlaneVectorEnv(VectorEnv[np.ndarray, np.ndarray, np.ndarray]):
    """``num_envs`` :class:`~subenv.envs.DivePlaneEnv` stepped together as arrays.

    ``gym.make_vec(id, num_envs=N)`` returns this for every subenv id. The sub-environments are
    arrays of named records (:mod:`subenv.envs.transition`) that the compiled transition, the same
    one :class:`~subenv.envs.DivePlaneEnv` steps through, advances in one call; nothing of the
    physics is copied. Each sub-environment has its own ``numpy.random.Generator``, seeded by
    ``SyncVectorEnv``'s rule (``reset(seed=s)``: ``s + i`` for sub-environment ``i``), its own
    scenario draws, episode length and resets. So sub-environment ``i`` is, step for step and bit
    for bit, ``gym.make(id)`` reset with seed ``s + i``, whatever ``num_envs`` and ``threads`` are
    (``tests/envs/test_vector_env.py``).

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
        ``render()`` returns a tuple with one frame per sub-environment (as Gymnasium's
        ``CartPoleVectorEnv``), so that Gymnasium's vector ``RecordVideo`` and ``HumanRendering``
        tile them.
    threads : int, optional
        Share the compiled step among this many of numba's threads (``numba.prange`` over blocks
        of 64 sub-environments, on numba's TBB threading layer, which is safe under ``fork`` and
        when several threads step environments). Default: one per :data:`ENVS_PER_THREAD`
        sub-environments, at most ``numba.config.NUMBA_NUM_THREADS`` (the cores; the
        ``NUMBA_NUM_THREADS`` environment variable sets it), and 1 where the TBB layer cannot be
        loaded. Results do not depend on it. Threads wait in TBB's scheduler between steps; none
        polls.
    config : DivePlaneConfig, optional
        The sub-environments' configuration, instead of the keyword arguments below.
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
    one at a time. When several sub-environments reset together and the scenario draws every
    episode with one loading, their episodes are drawn as arrays
    (:meth:`Scenario.sample_batch <subenv.scenarios.Scenario.sample_batch>`): the same numbers from
    the same generators as one reset at a time.
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
        config: DivePlaneConfig | None = None,
        **kwargs: Any,
    ) -> None:
        n = check.integer("num_envs", num_envs, 1)
        if max_episode_steps is not None:
            max_episode_steps = check.integer("max_episode_steps", max_episode_steps, 1)
        try:
            mode = AutoresetMode(autoreset_mode)
        except ValueError:
            modes = [m.value for m in _AUTORESET_MODES]
            raise ValueError(
                f"autoreset_mode={autoreset_mode!r} is invalid: must be one of {modes}"
            ) from None
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            allowed = self.metadata["render_modes"]
            raise ValueError(f"render_mode={render_mode!r} is invalid: must be None or one of {allowed}")
        # (numba's config sets NUMBA_NUM_THREADS from the environment at import: mypy does not see it)
        most = numba.config.NUMBA_NUM_THREADS if tr.threading_layer_available() else 1  # type: ignore[attr-defined]
        if threads is None:
            threads = min(most, max(1, n // ENVS_PER_THREAD))
        else:
            check.require(
                "threads",
                threads,
                isinstance(threads, (int, np.integer)) and not isinstance(threads, bool) and threads >= 1,
                "None or an integer >= 1",
            )
            check.require(
                "threads",
                threads,
                threads <= most,
                f"at most {most} (numba's NUMBA_NUM_THREADS)"
                if most > 1
                else "1 here: numba's TBB threading layer is not available (pip install tbb)",
            )
        if config is None:
            config = DivePlaneConfig(**kwargs)
        elif kwargs:
            raise ValueError(
                f"config and keyword arguments {sorted(kwargs)} were given: give one or the other"
            )
        elif not isinstance(config, DivePlaneConfig):
            raise ValueError(f"config={config!r} is invalid: must be a DivePlaneConfig")

        self.config = config
        """The sub-environments' configuration; :meth:`set_scenario` replaces its scenario."""
        self._validity = SurfaceValidityWatch(config)
        self.num_envs = n
        self.max_episode_steps = max_episode_steps
        self.autoreset_mode = mode
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        self.render_mode = render_mode
        self.threads = min(int(threads), n)
        """numba threads that share a step (1: the calling thread alone)."""
        self.single_action_space = config.action_space()
        self.action_space = batch_space(self.single_action_space, n)
        self.single_observation_space = config.observation_space()
        self.observation_space = batch_space(self.single_observation_space, n)

        self._constants = config.constants(max_episode_steps)
        self._loadings = Loadings(config)
        self._state = np.zeros(n, dtype=tr.STATE_DTYPE)
        self._episode = np.zeros(n, dtype=tr.EPISODE_DTYPE)
        self._episode["critical_speed_mps"] = np.nan
        self._seas = new_seas(n)
        self._obs = np.zeros((n, tr.N_OBS), dtype=np.float32)
        self._generators: list[np.random.Generator | None] = [None] * n
        self._seeds: list[int | None] = [None] * n
        self._rngs: Any = None  # numba typed list of the generators, built on the first reset
        self._done = np.zeros(n, dtype=bool)  # the episode ended on the last step
        self._any_done = False
        self._started = np.zeros(n, dtype=bool)
        self._ready = False  # every sub-environment has been reset once
        self._everyone = np.ones(n, dtype=bool)
        self._no_reasons = np.full(n, "", dtype=object)  # every termination_reason "" (for step_infos)
        self._episodes: list[EpisodeConfig | None] = [None] * n
        self._vehicles = np.full(n, config.base_vehicle, dtype=object)  # None: not built yet
        # Episodes drawn in a batch are kept as their configuration, pick and uniform numbers until
        # someone asks for them (as arrays: a batch stores them without a Python loop over its resets).
        self._unbuilt = np.zeros(n, dtype=bool)
        self._unbuilt_config = np.full(n, None, dtype=object)
        self._unbuilt_pick = np.zeros(n, dtype=np.int64)
        self._unbuilt_uniforms = np.empty((n, 0))
        # (time, depth, ordered depth) of each sub-environment's episode so far, for render()
        self._histories: list[list[tuple[float, float, float]]] = (
            [[] for _ in range(n)] if render_mode else []
        )
        self._interrupted = (
            False  # a step or reset was left midway (KeyboardInterrupt): reset() before stepping
        )
        # The first reset and step may load (or, with a cold cache, compile) the kernels: under the
        # compile notice (subenv.envs._compiling), as DivePlaneEnv's.
        self._first_calls = {"reset", "step"}

    # --- Gymnasium API ----------------------------------------------------------------------
    def reset(
        self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset all sub-environments (or those in ``options["reset_mask"]``).

        ``seed``: None (each sub-environment keeps its generator, or gets a random one), an int
        ``s`` (sub-environment ``i`` is seeded with ``s + i``) or one seed per sub-environment.
        Other ``options`` are :class:`~subenv.envs.DivePlaneEnv`'s, applied to every reset one.
        """
        if "reset" in self._first_calls:
            return first_call(self._first_calls, "reset", self.reset, seed=seed, options=options)
        n = self.num_envs
        seeds = _seeds(seed, n)
        options = check.mapping("options", options)  # (a copy: reset_mask is taken out of it)
        mask = options.pop("reset_mask", None)
        if mask is None:
            mask = self._everyone
        else:  # SyncVectorEnv's checks, with its exception types and messages (Gymnasium 1.4)
            if not isinstance(mask, np.ndarray):
                raise TypeError(f"`options['reset_mask']` must be a numpy array, got {type(mask)}")
            if mask.shape != (n,):
                raise ValueError(f"`options['reset_mask']` must have shape `({n},)`, got {mask.shape}")
            if mask.dtype != np.bool_:
                raise TypeError(f"`options['reset_mask']` must have `dtype=np.bool_`, got {mask.dtype}")
            if not mask.any():
                raise ValueError(
                    "`options['reset_mask']` must contain a boolean array with at least one True value, "
                    f"got reset_mask={mask}"
                )
            if self._interrupted:
                raise RuntimeError(
                    "a step or reset was interrupted: reset every sub-environment (no reset_mask)"
                )
        checked = check_options(self.config, options)
        indices = np.flatnonzero(mask)
        # A Ctrl-C arriving during the reset is delivered when it is complete (numba's typed list
        # is rebuilt here: see subenv.envs._interrupts); an error leaves it as it was.
        with interrupts_deferred():
            saved = self._saved() if checked else None
            self._interrupted = True  # until this reset is complete
            try:
                result = self._reset(indices, seeds, checked, mask)
            except ValueError:  # an option out of range for an episode drawn (initial depth and order)
                if saved is not None:
                    self._restore(saved)
                raise
            self._interrupted = False
        return result

    def _reset(
        self, indices: np.ndarray, seeds: list[int | None], options: dict[str, Any], mask: np.ndarray
    ) -> tuple[np.ndarray, dict[str, Any]]:
        seeded = [i for i in indices.tolist() if seeds[i] is not None or self._generators[i] is None]
        if seeded:
            for i in seeded:
                self._generators[i], self._seeds[i] = seeding.np_random(seeds[i])
            self._bind_generators()
        report = np.zeros((len(tr.REPORT_KEYS), self.num_envs))
        self._reset_envs(indices, options, report)
        self._done[indices] = False
        self._any_done = bool(self._done.any())
        return self._obs.copy(), step_infos(
            report, None if mask is self._everyone else mask, self._no_reasons
        )

    def _saved(self) -> dict[str, Any]:
        """What a reset changes (kept while its options are checked against the episodes drawn)."""
        return {
            "generators": list(self._generators),
            "seeds": list(self._seeds),
            "rngs": self._rngs,
            "states": [g.bit_generator.state if g is not None else None for g in self._generators],
            "records": (self._state.copy(), self._episode.copy(), self._seas.copy(), self._obs.copy()),
            "flags": (self._done.copy(), self._any_done, self._started.copy(), self._unbuilt.copy()),
            "lists": (self._vehicles.copy(), list(self._episodes)),
            "interrupted": self._interrupted,
        }

    def _restore(self, saved: dict[str, Any]) -> None:
        self._generators, self._seeds, self._rngs = saved["generators"], saved["seeds"], saved["rngs"]
        for g, state in zip(self._generators, saved["states"], strict=True):
            if g is not None:
                g.bit_generator.state = state
        self._state[:], self._episode[:], self._seas[:], self._obs[:] = saved["records"]
        done, self._any_done, started, unbuilt = saved["flags"]
        self._done[:], self._started[:], self._unbuilt[:] = done, started, unbuilt
        self._vehicles, self._episodes = saved["lists"]
        self._interrupted = saved["interrupted"]

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step every sub-environment with its row of ``actions`` (``autoreset_mode`` resets the ended ones).

        A NaN or infinite action, or ``actions`` of another shape, raises ``ValueError`` before any
        sub-environment steps.
        """
        if "step" in self._first_calls:
            return first_call(self._first_calls, "step", self.step, actions)
        if not self._ready:
            if not self._started.any():  # what Gymnasium's OrderEnforcing says, in SyncVectorEnv too
                raise ResetNeeded("Cannot call env.step() before calling env.reset()")
            if not self._started.all():  # (a first reset with a reset_mask, which SyncVectorEnv refuses)
                never = np.flatnonzero(~self._started).tolist()[:10]
                raise ResetNeeded(
                    f"Cannot call step() before reset(): sub-environments {never} were never reset"
                )
            self._ready = True
        if self._interrupted:
            raise RuntimeError(
                "a step or reset of this vector environment was interrupted (e.g. by KeyboardInterrupt) and "
                "its sub-environments may be midway: call reset() before stepping again"
            )
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
        report = np.empty((len(tr.REPORT_KEYS), self.num_envs))  # one row per info key, filled by the kernels
        # From here until the step returns the sub-environments are midway: an exception raised in
        # between (a KeyboardInterrupt arrives between any two bytecodes) leaves the environment
        # refusing to step until reset() (the compiled step itself runs to its end: no signal stops it).
        self._interrupted = True
        bad = self._step_active(actions, active, report)
        if bad >= 0:
            self._interrupted = False  # (nothing was stepped)
            raise ValueError(
                f"actions[{bad}]={actions[bad].tolist()!r} is invalid: must be finite (no NaN or inf)"
            )
        if resetting is not None:
            self._reset_envs(resetting, {}, report)  # reported as reward 0, not terminated, not truncated
        if self.render_mode is not None:
            for i in np.flatnonzero(active).tolist():
                self._histories[i].append((report[_TIME, i], report[_DEPTH, i], report[_COMMAND, i]))
        self._validity.check_all(report[_DEPTH], report[_SPEED])
        rewards = report[_REWARD].copy()
        terminated, truncated = report[_TERMINATED : _TRUNCATED + 1] > 0.0
        done = terminated | truncated
        self._any_done = bool(np.count_nonzero(done))
        self._done = done
        if mode is not AutoresetMode.SAME_STEP or not self._any_done:
            result = (
                self._obs.copy(),
                rewards,
                terminated,
                truncated,
                step_infos(report, None, self._no_reasons),
            )
            self._interrupted = False
            return result
        final_obs = np.full(self.num_envs, None, dtype=object)
        ended = np.flatnonzero(done)
        for i in ended:
            final_obs[i] = self._obs[i].copy()
        final = {
            "final_obs": final_obs,
            "_final_obs": done.copy(),
            "final_info": step_infos(report.copy(), done, self._no_reasons),
            "_final_info": done.copy(),
        }
        self._reset_envs(ended, {}, report)
        self._done = np.zeros(self.num_envs, dtype=bool)
        self._any_done = False
        infos = step_infos(report, None, self._no_reasons)
        infos.update(final)
        self._interrupted = False
        return self._obs.copy(), rewards, terminated, truncated, infos

    def render(self) -> tuple[np.ndarray, ...] | None:
        """One frame per sub-environment (``render_mode="rgb_array"``), as Gymnasium's
        ``CartPoleVectorEnv``."""
        if self.render_mode is None:
            from gymnasium import logger

            logger.warn(
                "You are calling render method without specifying any render mode. "
                'Set render_mode at initialization, e.g. gym.make_vec("subenv/DivePlane-v0", num_envs=4, '
                'render_mode="rgb_array")'
            )
            return None
        from subenv.envs.rendering import Frame, render_rgb

        vehicle = self.config.base_vehicle
        return tuple(
            render_rgb(Frame.of(vehicle, self._state[i], self._episode[i], self._histories[i]))
            for i in range(self.num_envs)
        )

    def set_scenario(self, scenario: str | Scenario) -> None:
        """Draw every sub-environment's following episodes from ``scenario``
        (:meth:`DivePlaneEnv.set_scenario <subenv.envs.DivePlaneEnv.set_scenario>`); episodes under
        way are not changed."""
        self.config = self.config.replace(scenario=scenario)
        self._validity = SurfaceValidityWatch(self.config, self._validity.warned)

    @property
    def scenario(self) -> Scenario:
        """The scenario the sub-environments draw their episodes from."""
        return self.config.base_scenario

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
            for i in np.flatnonzero(self._unbuilt).tolist():
                config, pick = self._unbuilt_config[i], int(self._unbuilt_pick[i])
                scenario = config.base_scenario
                uniforms = self._unbuilt_uniforms[i, : scenario.uniforms_per_pick[pick]]
                self._episodes[i] = for_vehicle(
                    config, scenario.episode_from_uniforms(uniforms, config.base_vehicle.weight_N, pick)
                )
            self._unbuilt[:] = False
        return list(self._episodes)

    @property
    def vehicles(self) -> list[Vehicle]:
        """Each sub-environment's vehicle: the configured one with its episode's loading."""
        missing = [i for i, vehicle in enumerate(self._vehicles.tolist()) if vehicle is None]
        if missing:  # built on demand: a batch of resets computes its loadings' numbers as arrays
            episodes = self.episodes
            for i in missing:
                draw = episodes[i]
                assert draw is not None  # (a vehicle is missing only after a reset)
                self._vehicles[i] = self._loadings.of(draw).vehicle
        return self._vehicles.tolist()

    @property
    def state(self) -> np.ndarray:
        """(pitch [rad], heave [m/s], pitch rate [rad/s], depth [m]) of every sub-environment, shape
        (num_envs, 4), a copy."""
        s = self._state
        return np.stack([s["pitch_rad"], s["heave_mps"], s["pitch_rate_radps"], s["depth_m"]], axis=1)

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_rngs"] = None  # a numba typed list does not pickle
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        read_only(self._constants)  # (as the original's: the same compiled step; the hull is the config's)
        if any(g is not None for g in self._generators):
            self._bind_generators()

    # --- helpers ----------------------------------------------------------------------------
    def _bind_generators(self) -> None:
        """The compiled step's view of the generators: a numba typed list, built whole and then
        swapped in (an interrupted build leaves the last one); a never-reset sub-environment holds a
        placeholder its steps never draw from."""
        placeholder = np.random.default_rng(0)
        with interrupts_deferred():
            rngs = typed.List([g if g is not None else placeholder for g in self._generators])
        self._rngs = rngs

    def _step_active(self, actions: np.ndarray, active: np.ndarray, report: np.ndarray) -> int:
        """The compiled step of the ``active`` sub-environments, on :attr:`threads` of numba's threads
        (:func:`subenv.envs.transition.step`: -1, or the first with a non-finite action)."""
        args = (
            self._state,
            self._episode,
            self._seas,
            actions,
            active,
            self._obs,
            self._rngs,
            self._constants,
            self.config.hull,
            report,
        )
        if self.threads == 1:
            return int(tr.step(*args))
        before = numba.get_num_threads()
        numba.set_num_threads(self.threads)  # (for launches from this thread)
        try:
            return int(tr.step_parallel(*args))
        finally:
            numba.set_num_threads(before)

    def _check_actions(self, actions: Any) -> np.ndarray:
        n, shape = self.num_envs, tuple(self.single_action_space.shape or ())
        a = check.real_array("actions", actions)
        if a.shape != (n, *shape):
            if shape == (1,) and a.shape == (n,):
                a = a.reshape(n, 1)
            else:
                raise ValueError(
                    f"actions has shape {np.shape(actions)}: must have shape {(n, *shape)} "
                    f"(num_envs={n}, control={self.config.control!r})"
                )
        return a if a.flags.c_contiguous else np.ascontiguousarray(a)

    def _reset_envs(self, indices: np.ndarray, options: dict[str, Any], report: np.ndarray) -> None:
        """Draw new episodes for ``indices`` (and write their columns of ``report``)."""
        index = np.asarray(indices, dtype=np.intp)
        if len(index) >= _BATCH_RESETS and not options and self.config.base_scenario.samples_in_batches:
            self._draw_batch(index)
        else:
            config, generators, loadings = self.config, self._generators, self._loadings
            for i in index.tolist():
                draw, loading, episode, state = draw_episode(config, generators[i], loadings, options)
                write_episode(self._episode, i, episode)
                write_episode(self._state, i, state)
                write_sea(self._seas, i, episode)
                self._vehicles[i], self._episodes[i] = loading.vehicle, draw
            self._unbuilt[index] = False
        tr.observe(self._state, self._episode, index, self._obs, self._rngs, self._constants, report)
        if not self._ready:
            self._started[index] = True
        if self.render_mode is not None:
            for i in index.tolist():
                self._histories[i] = [(0.0, self._state[i]["depth_m"], self._episode[i]["depth_command_m"])]

    def _draw_batch(self, index: np.ndarray) -> None:
        """Draw the episodes of ``index`` as arrays (no options): each sub-environment's generator gives
        the numbers of its own reset, turned into records as one reset's are
        (:func:`~subenv.envs.episodes.draw_episode_batch`); its episode and vehicle are made when asked
        for (:attr:`episodes`, :attr:`vehicles`)."""
        batch = draw_episode_batch(self.config, self._rngs, index, self._loadings)
        for group in batch.groups:
            at = index[group.rows]
            write_episode(self._episode, at, group.episode)
            write_episode(self._state, at, group.state)
            write_sea(self._seas, at, group.episode)
            self._vehicles[at] = group.loading.vehicle  # (None: a loading per episode, built on demand)
        k = batch.uniforms.shape[1]
        if self._unbuilt_uniforms.shape[1] < k:  # (a scenario that draws more numbers than any before)
            wider = np.empty((self.num_envs, k))
            wider[:, : self._unbuilt_uniforms.shape[1]] = self._unbuilt_uniforms
            self._unbuilt_uniforms = wider
        self._unbuilt_uniforms[index, :k] = batch.uniforms
        self._unbuilt_pick[index] = batch.picks
        self._unbuilt_config[index] = self.config
        self._unbuilt[index] = True


def _seeds(seed: Any, n: int) -> list[int | None]:
    """Each sub-environment's seed from ``reset(seed=...)``, checked before any is used: the single
    environment's rule (:func:`subenv._validation.seed`) for an integer and for each of a sequence."""
    if seed is None or check.is_integer(seed):
        first = check.seed("seed", seed)
        return [None] * n if first is None else [first + i for i in range(n)]
    check.require(
        "seed",
        seed,
        isinstance(seed, (Sequence, np.ndarray)) and not isinstance(seed, (str, bytes)),
        f"None, an integer >= 0 or a sequence of num_envs={n} such integers (or None)",
    )
    seeds = list(seed)
    if len(seeds) != n:  # SyncVectorEnv's message
        raise ValueError(
            f"If seeds are passed as a list the length must match num_envs={n} but got length={len(seeds)}."
        )
    return [check.seed(f"seed[{i}]", value) for i, value in enumerate(seeds)]
