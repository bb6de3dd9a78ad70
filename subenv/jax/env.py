"""The dive-plane environment as a functional JAX environment, with gymnax's interface (:mod:`subenv.jax`).

Its transition is :mod:`subenv.envs.transition`'s own functions, traced (:func:`~subenv.jax.traced`):
the planes and the speed of a control period (:func:`~subenv.envs.transition.period_start`), the
period itself (:func:`subenv.jax.control_period`, the environments' integrator), its end
(:func:`~subenv.envs.transition.episode_end`, :func:`~subenv.envs.transition.period_end`), the
reward, the observation and the ``info`` (:func:`~subenv.envs.transition.report_values`). Only the
storage differs: the compiled environments write their records in place; here every step returns a
new :data:`EnvState`.

Two things a JAX program cannot do the way the Gymnasium environments do them:

- **Resets.** An episode's draw (the scenario's sampling, the loading's vehicle and critical speed)
  is Python. So the episodes are drawn ahead, by that same code, into a table (:class:`EnvParams`,
  :meth:`DivePlaneJaxEnv.params`): row ``k`` of a table made from ``seeds`` is the episode that
  ``gym.make(id).reset(seed=seeds[k])`` plays (:func:`subenv.envs.episodes.episode_table`). A reset
  picks a row at random; a larger table gives more distinct episodes.
- **Random numbers.** The Gymnasium environments draw the heave force's and the sensors' noise from
  each environment's NumPy generator; here they come from the JAX key of the step, as nine
  standard normal numbers that the transition takes as an input
  (:meth:`DivePlaneJaxEnv.transition`). Given the same numbers, both play the same episode
  (``tests/jax/test_env.py``).

Gymnasium's functional interface (``gymnasium.experimental.functional.FuncEnv``, "predominantly for
internal use" and "likely to change" by its own docstring) is not offered: its wrappers would not
carry this environment. ``FunctionalJaxEnv`` reports no truncation (an episode's end by its duration or
the time limit would read as a termination) and ``FunctionalJaxVectorEnv`` resets by indexing the
state as one array (``state.at[rows].set(...)``), where this state is a pytree of named fields.
gymnax's interface is what JAX learners (PureJaxRL among them) take.

Not bit for bit: XLA contracts multiply-adds, so a state agrees with the compiled one to about
1e-14 after a step, and the difference grows as the dynamics amplify it (at Nominal's speed, the
planes' angles given, a relative difference of 1e-15 grows to 3e-6 in 400 control periods, JAX
against JAX: ``tests/jax/test_env.py``).
"""

from __future__ import annotations

import dataclasses
import types
from collections.abc import Sequence
from typing import Any, Final

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np

from subenv import _validation as check
from subenv.dynamics.model import PARAM_FIELDS
from subenv.envs import transition as tr
from subenv.envs.config import DivePlaneConfig
from subenv.envs.episodes import episode_table
from subenv.jax._trace import traced
from subenv.jax.dynamics import control_period

__all__ = ["N_NORMALS", "DivePlaneJaxEnv", "EnvParams", "EnvState", "Episode", "make"]

N_NORMALS: Final = 1 + tr.N_OBS
"""Standard normal numbers a step takes (:meth:`DivePlaneJaxEnv.transition`): the heave force's, then
the sensors'."""
_DIVERGED: Final = tr.REASONS.index("diverged")
_RHO_SUCTION: Final = PARAM_FIELDS.index("rho_suction")


def _record(name: str, fields: Sequence[str], doc: str) -> type:
    """A frozen dataclass with ``fields``, registered as a JAX pytree (each field a leaf or subtree)."""
    cls = dataclasses.make_dataclass(name, [(field, Any) for field in fields], frozen=True)
    cls.__module__, cls.__doc__ = __name__, doc
    return jax.tree_util.register_dataclass(cls, data_fields=list(fields), meta_fields=[])


Episode = _record(
    "Episode",
    (*tr.EPISODE_DTYPE.names, "waves"),
    """\
What a reset draws and a step only reads: the fields of :data:`subenv.envs.transition.EPISODE_DTYPE`,
by name, and ``waves``, the episode's sea (shape (WAVE_FIELDS, MAX_WAVES): its
:meth:`~subenv.dynamics.waves.SeaState.components`; shape (0,) in an environment without seas).""",
)

EnvState = _record(
    "EnvState",
    (*tr.STATE_DTYPE.names, "obs", "episode"),
    """\
One environment's state: the fields of :data:`subenv.envs.transition.STATE_DTYPE`, by name (the
vehicle's state, the applied planes, the time and steps since the reset, the heave force, the speed,
the distance travelled), ``obs``, the last observation (float32, shape (8,)), and ``episode``, its
:class:`Episode`.""",
)


@dataclasses.dataclass(frozen=True)
class EnvParams:
    """The episodes resets draw from: ``table``, an :data:`EnvState` whose every leaf has a leading axis
    of one row per episode, each row the state at that episode's reset (speed and ``obs`` not yet
    set) (:meth:`DivePlaneJaxEnv.params`)."""

    table: Any

    @property
    def n_episodes(self) -> int:
        """Rows of the table."""
        return int(self.table.time_s.shape[0])


jax.tree_util.register_dataclass(EnvParams, data_fields=["table"], meta_fields=[])


class DivePlaneJaxEnv:
    """:class:`~subenv.envs.DivePlaneEnv` as a functional JAX environment, with gymnax's interface.

    ``reset(key, params) -> (obs, state)`` and ``step(key, state, action, params) -> (obs, state,
    reward, done, info)`` are pure functions of arrays: ``jax.jit`` and ``jax.vmap`` them (one key per
    environment). ``step`` resets an environment whose episode ended (``done``: terminated or
    truncated) within the same call, by a select, as gymnax does: then ``obs`` and ``state`` are the
    new episode's, and ``reward`` and ``info`` the ended step's. ``info`` holds the Gymnasium
    environment's ``info`` values (``termination_reason`` as its code, ``reason``:
    :data:`subenv.envs.transition.REASONS`) with ``reward``, ``terminated``, ``truncated`` and
    ``discount`` (0 where terminated, gymnax's convention).

    Made by :func:`make`. The configuration (:class:`~subenv.envs.DivePlaneConfig`) is static, part of
    the compiled program; the episodes are data (:class:`EnvParams`).

    Actions are clipped to [-1, 1] as in the Gymnasium environment; as a compiled program cannot raise,
    a NaN or infinite action counts as 0 (the Gymnasium environment raises ``ValueError``).
    """

    def __init__(
        self, config: DivePlaneConfig, max_episode_steps: int | None, free_surface: bool, sea: bool
    ) -> None:
        self.config = config
        """The environment's configuration."""
        self.max_episode_steps = max_episode_steps
        """Truncate after this many steps, as ``gymnasium.wrappers.TimeLimit`` (None: the scenario's duration only)."""
        self.free_surface = free_surface
        """Whether the episodes may have a free surface (its suction is computed for every state)."""
        self.sea = sea
        """Whether the episodes may have a sea (its force is computed for every state)."""
        record = config.constants(max_episode_steps)[0]
        self._cfg = types.SimpleNamespace(**{name: _python(record[name]) for name in tr.CONFIG_DTYPE.names})
        self._hull = np.asarray(config.hull)
        self._period_start = traced(tr.period_start)
        self._period_end = traced(tr.period_end)
        self._episode_end = traced(tr.episode_end)
        self._episode_outcome = traced(tr.episode_outcome)
        self._reward_terms = traced(tr.reward_terms)
        self._noise_values = traced(tr.noise_values)
        self._observation_values = traced(tr.observation_values)
        self._report_values = traced(tr.report_values)
        self._speed_at = traced(tr.speed_at)
        self._default_params: EnvParams | None = None

    # --- gymnax's interface ----------------------------------------------------------------------
    @property
    def name(self) -> str:
        """The scenario's name."""
        return self.config.base_scenario.name

    @property
    def num_actions(self) -> int:
        """Components of an action (1: dual control, 2: independent)."""
        return 1 if self.config.control == "dual" else 2

    def action_space(self, params: EnvParams | None = None) -> gym.spaces.Box:
        """The Gymnasium environment's action space."""
        return self.config.action_space()

    def observation_space(self, params: EnvParams | None = None) -> gym.spaces.Box:
        """The Gymnasium environment's observation space."""
        return self.config.observation_space()

    @property
    def default_params(self) -> EnvParams:
        """The table :func:`make` drew."""
        if self._default_params is None:
            raise ValueError("this environment has no default episodes: pass params (DivePlaneJaxEnv.params)")
        return self._default_params

    def reset(self, key: jax.Array, params: EnvParams | None = None) -> tuple[jax.Array, Any]:
        """An episode drawn at random from the table: (observation, state)."""
        return self.reset_env(key, self.default_params if params is None else params)

    def step(
        self, key: jax.Array, state: Any, action: jax.Array, params: EnvParams | None = None
    ) -> tuple[jax.Array, Any, jax.Array, jax.Array, dict[str, jax.Array]]:
        """One control period; an ended episode is followed by a new one at once (see the class)."""
        params = self.default_params if params is None else params
        key, key_reset = jax.random.split(key)
        obs, stepped, reward, done, info = self.step_env(key, state, action, params)
        obs_reset, reset = self.reset_env(key_reset, params)
        state = jax.tree_util.tree_map(lambda a, b: jnp.where(done, a, b), reset, stepped)
        return jnp.where(done, obs_reset, obs), state, reward, done, info

    def reset_env(self, key: jax.Array, params: EnvParams) -> tuple[jax.Array, Any]:
        """A reset to a row of the table drawn with ``key`` (:meth:`reset_to`)."""
        key_row, key_noise = jax.random.split(key)
        row = jax.random.randint(key_row, (), 0, params.n_episodes)
        state = self.reset_to(row, params, jax.random.normal(key_noise, (tr.N_OBS,)))
        return state.obs, state

    def step_env(
        self, key: jax.Array, state: Any, action: jax.Array, params: EnvParams
    ) -> tuple[jax.Array, Any, jax.Array, jax.Array, dict[str, jax.Array]]:
        """One control period without the reset (:meth:`transition` with normals from ``key``)."""
        state, info = self.transition(state, action, jax.random.normal(key, (N_NORMALS,)))
        terminated, truncated = info["terminated"] > 0.0, info["truncated"] > 0.0
        return state.obs, state, info["reward"], terminated | truncated, info

    def get_obs(self, state: Any) -> jax.Array:
        """The state's observation."""
        return state.obs

    def is_terminal(self, state: Any, params: EnvParams | None = None) -> jax.Array:
        """Whether the episode has ended at ``state`` (terminated or truncated)."""
        cfg, e = self._cfg, state.episode
        reason = self._episode_end(
            state.pitch_rad, state.heave_mps, state.pitch_rate_radps, state.depth_m, e.depth_command_m, cfg
        )
        terminated, truncated = self._episode_outcome(reason, state.time_s, state.steps, e.duration_s, cfg)
        return terminated | truncated

    # --- the episodes and the transition ---------------------------------------------------------
    def params(self, seeds: Sequence[int]) -> EnvParams:
        """A table of the episodes of ``seeds``: row ``k`` is the episode of
        ``gym.make(id).reset(seed=seeds[k])`` (:func:`subenv.envs.episodes.episode_table`)."""
        return self._table(*episode_table(self.config, seeds), seeds)

    def _table(
        self, episodes: np.ndarray, states: np.ndarray, seas: np.ndarray, seeds: Sequence[int]
    ) -> EnvParams:
        """:meth:`params` of the records of :func:`~subenv.envs.episodes.episode_table`."""
        suction, waves = _needs(episodes)
        if (suction and not self.free_surface) or (waves and not self.sea):
            raise ValueError(
                f"seeds={_short(seeds)} draw episodes with a {'free surface' if suction else 'sea'} that this "
                f"environment was made without (free_surface={self.free_surface}, sea={self.sea})"
            )
        episode = Episode(
            **{name: jnp.asarray(episodes[name]) for name in tr.EPISODE_DTYPE.names},
            waves=jnp.asarray(seas) if self.sea else jnp.zeros((len(episodes), 0)),
        )
        fields = {name: jnp.asarray(states[name]) for name in tr.STATE_DTYPE.names}
        return EnvParams(
            EnvState(**fields, obs=jnp.zeros((len(states), tr.N_OBS), dtype=jnp.float32), episode=episode)
        )

    def reset_to(self, row: Any, params: EnvParams, normals: Any) -> Any:
        """The state at the reset of episode ``row`` of the table, observed with the sensor noise of
        ``normals`` (:data:`~subenv.envs.transition.N_OBS` standard normal numbers; read only where the
        episode has sensor noise), as the Gymnasium environment's reset observes it."""
        cfg = self._cfg
        state = jax.tree_util.tree_map(lambda leaf: leaf[row], params.table)
        e = state.episode
        state = dataclasses.replace(
            state, speed_mps=self._speed_at(state.time_s, e.n_knots, e.knot_time_s, e.knot_speed_mps)
        )
        noise = self._noise_values(*(normals[k] for k in range(tr.N_OBS)), cfg)
        return dataclasses.replace(state, obs=_float32(self._observation_values(state, e, noise, cfg)))

    def transition(self, state: Any, action: Any, normals: Any) -> tuple[Any, dict[str, jax.Array]]:
        """One control period of the :mod:`~subenv.envs.transition`: (the new state, ``info``).

        ``normals``: :data:`N_NORMALS` standard normal numbers, the step's randomness: the heave
        force's new term (times the episode's standard deviation), then the sensors' noise
        (:func:`~subenv.envs.transition.noise_values`). No reset: an ended episode's state is returned
        as it ended (a diverged one as it was before the step).
        """
        cfg, s, e = self._cfg, state, state.episode
        a = jnp.reshape(jnp.asarray(action, dtype=jnp.float64), (-1,))
        a = jnp.where(jnp.isfinite(a), a, 0.0)
        stern, bow, effort, u0, u1, slope = self._period_start(s, e, a[0], a[-1], cfg)
        x = control_period(
            jnp.stack([s.pitch_rad, s.heave_mps, s.pitch_rate_radps, s.depth_m]),
            s.time_s,
            cfg.dt_s,
            u0,
            slope,
            stern,
            bow,
            e.params,
            self._hull,
            s.disturbance_N,
            cfg.substeps,
            free_surface=self.free_surface,
            waves=e.waves if self.sea else None,
            distance0=s.distance_m,
        )
        x0, x1, x2, x3 = x[0], x[1], x[2], x[3]
        reason = self._episode_end(x0, x1, x2, x3, e.depth_command_m, cfg)
        (pitch, heave, rate, depth, time, steps, distance, speed, disturbance, terminated, truncated) = (
            self._period_end(s, e, x0, x1, x2, x3, u0, u1, reason, e.disturbance_std_N * normals[0], cfg)
        )
        new = dataclasses.replace(
            s,
            pitch_rad=pitch,
            heave_mps=heave,
            pitch_rate_radps=rate,
            depth_m=depth,
            stern_plane_rad=stern,
            bow_plane_rad=bow,
            time_s=time,
            steps=steps,
            disturbance_N=disturbance,
            speed_mps=speed,
            distance_m=distance,
        )
        rewards = self._reward_terms(pitch, depth - e.depth_command_m, effort, terminated, cfg)
        noise = self._noise_values(*(normals[k] for k in range(1, N_NORMALS)), cfg)
        obs = jnp.where(reason == _DIVERGED, s.obs, _float32(self._observation_values(new, e, noise, cfg)))
        new = dataclasses.replace(new, obs=obs)
        info = dict(zip(tr.REPORT_KEYS, self._report_values(new, e, *rewards, reason, terminated, truncated)))
        info["discount"] = jnp.where(terminated, 0.0, 1.0)
        return new, info


def make(
    env_id: str = "subenv/DivePlane-v0",
    *,
    episodes: int = 1024,
    seed: int = 0,
    free_surface: bool | None = None,
    sea: bool | None = None,
    max_episode_steps: int | None = None,
    **kwargs: Any,
) -> tuple[DivePlaneJaxEnv, EnvParams]:
    """A registered subenv id as a functional JAX environment, and its episodes: ``(env, params)``, as
    ``gymnax.make``.

    Parameters
    ----------
    env_id : str
        A ``subenv/...`` id (its scenario and ``max_episode_steps``).
    episodes : int
        Rows of the table of episodes (:meth:`DivePlaneJaxEnv.params`), seeded ``seed``,
        ``seed + 1``, ...: the episodes ``gym.make(env_id).reset(seed=seed + k)`` plays.
    free_surface, sea : bool, optional
        Whether episodes may have a free surface or a sea (each costs computation in every step, for
        every state); by default, whether the table's episodes have one.
    max_episode_steps : int, optional
        The id's by default.
    **kwargs
        :class:`~subenv.envs.DivePlaneEnv`'s arguments (``vehicle``, ``control``, ``alpha``, ...).
    """
    check.require(
        "env_id",
        env_id,
        isinstance(env_id, str)
        and env_id in gym.registry
        and gym.registry[env_id].entry_point == "subenv.envs.dive_plane:DivePlaneEnv",
        "a registered subenv id (subenv.envs.env_ids())",
    )
    n = check.integer("episodes", episodes, 1, 10**7)
    first = check.integer("seed", seed, 0)
    spec = gym.registry[env_id]
    steps = (
        spec.max_episode_steps
        if max_episode_steps is None
        else check.integer("max_episode_steps", max_episode_steps, 1)
    )
    config = DivePlaneConfig(**{**spec.kwargs, **kwargs})
    seeds = range(first, first + n)
    episodes_, states, seas = episode_table(config, seeds)
    suction, waves = _needs(episodes_)
    env = DivePlaneJaxEnv(
        config,
        steps,
        suction if free_surface is None else bool(free_surface),
        waves if sea is None else bool(sea),
    )
    env._default_params = env._table(episodes_, states, seas, seeds)
    return env, env._default_params


def _needs(episodes: np.ndarray) -> tuple[bool, bool]:
    """Whether any of the episodes' records has a free surface, and whether any has a sea."""
    return bool(np.any(episodes["params"][:, _RHO_SUCTION] != 0.0)), bool(np.any(episodes["n_waves"] > 0))


def _python(value: Any) -> Any:
    """A record's value as Python's (a static constant of the traced program) or a NumPy array."""
    if isinstance(value, np.ndarray):
        return value.copy()
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    return float(value)


def _float32(values: tuple[Any, ...]) -> jax.Array:
    """An observation's values (float64, as computed) as the environments return it."""
    return jnp.stack(values).astype(jnp.float32)


def _short(seeds: Sequence[int]) -> str:
    values = list(seeds)
    return repr(values) if len(values) <= 4 else f"[{values[0]}, ..., {values[-1]}]"
