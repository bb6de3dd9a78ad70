"""DivePlaneVectorEnv: N dive-plane environments stepped as one array through the compiled transition."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Final

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numba import typed

from subenv.envs import transition as tr
from subenv.envs.dive_plane import DivePlaneEnv
from subenv.scenarios.scenario import EpisodeConfig
from subenv.vehicles.vehicle import Vehicle

__all__ = ["DivePlaneVectorEnv"]

_REASONS: Final = np.array(tr.REASONS, dtype=object)
# info key -> row column, in the single environment's order (subenv.envs.dive_plane._info).
_COLUMNS: Final = {"time_s": tr.TIME, "depth_m": tr.DEPTH, "depth_command_m": tr.COMMAND}
_STATE_COLUMNS: Final = {"pitch_rad": tr.PITCH, "heave_mps": tr.HEAVE, "pitch_rate_radps": tr.PITCH_RATE,
                         "stern_plane_rad": tr.STERN, "bow_plane_rad": tr.BOW, "speed_mps": tr.SPEED}
_REWARD_COLUMNS: Final = {"reward_depth": tr.REWARD_DEPTH, "reward_pitch": tr.REWARD_PITCH,
                          "reward_effort": tr.REWARD_EFFORT, "reward_termination": tr.REWARD_TERMINATION}
_AUTORESET_MODES: Final = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED)
PARALLEL_MIN_ENVS: Final = 256
"""From this many sub-environments on, ``parallel=None`` steps them on numba's threads."""


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
    parallel : bool, optional
        Step the sub-environments on numba's threads (``numba.set_num_threads``). Default:
        from :data:`PARALLEL_MIN_ENVS` sub-environments on. Results do not depend on it.
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
        parallel: bool | None = None,
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
        if parallel is not None and not isinstance(parallel, bool):
            raise ValueError(f"parallel={parallel!r} is invalid: must be None, True or False")
        self.single_env = DivePlaneEnv(**kwargs)
        """An environment that is never stepped: it holds the configuration all sub-environments share."""

        self.num_envs = int(num_envs)
        self.max_episode_steps = None if max_episode_steps is None else int(max_episode_steps)
        self.autoreset_mode = mode
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        self.render_mode = render_mode
        self.parallel = self.num_envs >= PARALLEL_MIN_ENVS if parallel is None else parallel
        self.single_action_space = self.single_env.action_space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.single_observation_space = self.single_env.observation_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)

        n = self.num_envs
        self._cfg = self.single_env._constants(self.max_episode_steps)
        self._hull = self.single_env._hull
        self._rows = np.zeros((n, tr.N_COLUMNS))
        self._rows[:, tr.CRITICAL_SPEED] = np.nan
        self._obs = np.zeros((n, *self.single_observation_space.shape), dtype=np.float32)
        self._generators: list[np.random.Generator | None] = [None] * n
        self._seeds: list[int | None] = [None] * n
        self._rngs: Any = None  # numba typed list of the generators, built on the first reset
        self._done = np.zeros(n, dtype=bool)  # the episode ended on the last step
        self._started = np.zeros(n, dtype=bool)
        self._everyone = np.ones(n, dtype=bool)
        self.vehicles: list[Vehicle] = [self.single_env.base_vehicle] * n
        """Each sub-environment's vehicle (its episode's loading)."""
        self.episodes: list[EpisodeConfig | None] = [None] * n
        """Each sub-environment's episode draw."""
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
            seeds = list(seed)
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
        self._reset_envs(indices, options)
        self._done[indices] = False
        return self._obs.copy(), self._infos(None if mask is self._everyone else mask)

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._started.all():
            raise _reset_needed(np.flatnonzero(~self._started))
        actions = self._check_actions(actions)
        mode = self.autoreset_mode
        resetting = np.flatnonzero(self._done) if mode is AutoresetMode.NEXT_STEP else ()
        if mode is AutoresetMode.DISABLED and self._done.any():
            raise RuntimeError(
                f"sub-environments {np.flatnonzero(self._done).tolist()} have ended their episodes and "
                "autoreset_mode is DISABLED: reset them with reset(options={'reset_mask': mask})"
            )
        active = self._everyone if len(resetting) == 0 else ~self._done
        step = tr.step_batch_parallel if self.parallel else tr.step_batch
        bad = step(self._rows, actions, active, self._obs, self._rngs, self._cfg, self._hull)
        if bad >= 0:
            raise ValueError(
                f"actions[{bad}]={actions[bad].tolist()!r} is invalid: must be finite (no NaN or inf)"
            )
        rows = self._rows
        if self.render_mode is not None and active[0]:
            self._history.append((rows[0, tr.TIME], rows[0, tr.DEPTH], rows[0, tr.COMMAND]))
        if len(resetting):
            self._reset_envs(resetting, {})  # their rows now give reward 0, not terminated, not truncated
        rewards = rows[:, tr.REWARD].copy()
        terminated = rows[:, tr.TERMINATED] > 0.0
        truncated = rows[:, tr.TRUNCATED] > 0.0
        final: dict[str, Any] = {}
        done = terminated | truncated
        if mode is AutoresetMode.SAME_STEP and done.any():
            ended = np.flatnonzero(done)
            final_obs = np.full(self.num_envs, None, dtype=object)
            for i in ended:
                final_obs[i] = self._obs[i].copy()
            final = {"final_obs": final_obs, "_final_obs": done.copy(), "final_info": self._infos(done),
                     "_final_info": done.copy()}
            self._reset_envs(ended, {})
            done = np.zeros(self.num_envs, dtype=bool)
        self._done = done
        infos = self._infos(None)
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

    @property
    def np_random(self) -> tuple[np.random.Generator | None, ...]:  # type: ignore[override]
        """Each sub-environment's generator (None before its first reset), as ``SyncVectorEnv.np_random``."""
        return tuple(self._generators)

    @property
    def np_random_seed(self) -> tuple[int | None, ...]:  # type: ignore[override]
        """Each sub-environment's seed (-1 for a random one, None before its first reset)."""
        return tuple(self._seeds)

    @property
    def state(self) -> np.ndarray:
        """(pitch [rad], heave [m/s], pitch rate [rad/s], depth [m]) of every sub-environment, a copy."""
        return self._rows[:, tr.PITCH:tr.DEPTH + 1].copy()

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_rngs"] = None  # a numba typed list does not pickle
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        if any(g is not None for g in self._generators):
            self._rngs = typed.List([g if g is not None else np.random.default_rng() for g in self._generators])

    # --- helpers ----------------------------------------------------------------------------
    def _check_actions(self, actions: Any) -> np.ndarray:
        n, shape = self.num_envs, self.single_action_space.shape
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != (n, *shape):
            if shape == (1,) and a.shape == (n,):
                a = a.reshape(n, 1)
            else:
                raise ValueError(
                    f"actions has shape {np.shape(actions)}: must have shape {(n, *shape)} "
                    f"(num_envs={n}, control={self.single_env.control!r})"
                )
        return np.ascontiguousarray(a)

    def _reset_envs(self, indices: Sequence[int] | np.ndarray, options: dict[str, Any]) -> None:
        begin = self.single_env._begin_episode
        rows, generators = self._rows, self._generators
        for i in indices:
            self.vehicles[i], self.episodes[i] = begin(rows[i], generators[i], options)  # type: ignore[arg-type]
        index = np.asarray(indices, dtype=np.intp)
        tr.observe_batch(rows, index, self._obs, self._rngs, self._cfg)
        self._started[index] = True
        if self.render_mode is not None and 0 in index:
            self._history = [(0.0, rows[0, tr.DEPTH], rows[0, tr.COMMAND])]

    def _infos(self, mask: np.ndarray | None) -> dict[str, Any]:
        """Gymnasium's vector ``info`` of the rows; with ``mask``, only those sub-environments report."""
        rows = self._rows
        depth = rows[:, tr.DEPTH].copy()
        command = rows[:, tr.COMMAND].copy()
        speed = rows[:, tr.SPEED].copy()
        froude_scale = rows[:, tr.SQRT_G_ZGB]
        ucr = rows[:, tr.CRITICAL_SPEED].copy()
        values: dict[str, np.ndarray] = {"time_s": rows[:, tr.TIME].copy(), "depth_m": depth,
                                         "depth_command_m": command, "depth_error_m": depth - command}
        for key, column in _STATE_COLUMNS.items():
            values[key] = speed if column == tr.SPEED else rows[:, column].copy()
        values["froude_number"] = speed / froude_scale  # nan when z_GB <= 0, as the single env
        values["critical_speed_mps"] = ucr
        values["critical_froude"] = ucr / froude_scale
        values["disturbance_N"] = rows[:, tr.DISTURBANCE].copy()
        values["termination_reason"] = _REASONS[rows[:, tr.REASON].astype(np.intp)]
        for key, column in _REWARD_COLUMNS.items():
            values[key] = rows[:, column].copy()
        infos: dict[str, Any] = {}
        if mask is None:
            for key, value in values.items():
                infos[key] = value
                infos["_" + key] = np.ones(self.num_envs, dtype=bool)
        else:  # SyncVectorEnv leaves the others at zero (None for strings)
            for key, value in values.items():
                value[~mask] = None if value.dtype == object else 0.0
                infos[key] = value
                infos["_" + key] = mask.copy()
        return infos


def _reset_needed(indices: np.ndarray) -> Exception:
    from gymnasium.error import ResetNeeded

    return ResetNeeded(f"Cannot call step() before reset(): sub-environments {indices.tolist()[:10]} were never reset")
