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

The interface is gymnax 1.0's: ``step`` returns ``(obs, state, reward, terminated, truncated, info)``
with ``info["final_observation"]``, the observation the step reached before an ended episode was
replaced by a new one (the one to bootstrap a truncated episode from).

The states and the episodes carry, as static data of their pytrees, what they were made for
(:class:`MadeFor`: the id, the configuration, the free surface and the sea the program computes):
an environment refuses, while it is traced, states and episodes made for another one, and actions
of another shape or type than its own (a batch of actions is ``jax.vmap``'s).

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
import hashlib
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

__all__ = ["N_NORMALS", "DivePlaneJaxEnv", "EnvParams", "EnvState", "Episode", "MadeFor", "make"]

N_NORMALS: Final = 1 + tr.N_OBS
"""Standard normal numbers a step takes (:meth:`DivePlaneJaxEnv.transition`): the heave force's, then
the sensors'."""
_DIVERGED: Final = tr.REASONS.index("diverged")
_RHO_SUCTION: Final = PARAM_FIELDS.index("rho_suction")
_STATE_FIELDS: Final[tuple[str, ...]] = tr.STATE_DTYPE.names or ()
_EPISODE_FIELDS: Final[tuple[str, ...]] = tr.EPISODE_DTYPE.names or ()
_CONFIG_FIELDS: Final[tuple[str, ...]] = tr.CONFIG_DTYPE.names or ()


@dataclasses.dataclass(frozen=True)
class MadeFor:
    """What an environment's states and episodes are made for: static data of their pytrees (part of the
    compiled program, compared while it is traced), so that an environment refuses another's.

    Two are equal when their configurations (by a digest of :class:`~subenv.envs.DivePlaneConfig`'s
    fields: the scenario, the vehicle, the control, ...) and their ``free_surface`` and ``sea`` are;
    the id is only shown.
    """

    env_id: str | None = dataclasses.field(compare=False)
    """The registered id (None: an environment made from a configuration)."""
    config: DivePlaneConfig = dataclasses.field(compare=False, repr=False)
    """The configuration."""
    free_surface: bool
    """Whether the program computes the free surface's suction."""
    sea: bool
    """Whether the program computes a sea's force (and the episodes hold their seas)."""
    digest: str = dataclasses.field(repr=False)
    """Of the configuration's fields."""

    @classmethod
    def of(cls, env_id: str | None, config: DivePlaneConfig, free_surface: bool, sea: bool) -> MadeFor:
        """The identity of an environment."""
        digest = hashlib.sha256(repr(config).encode()).hexdigest()[:16]
        return cls(env_id, config, free_surface, sea, digest)

    def __str__(self) -> str:
        return (
            f"{self.env_id or self.config.base_scenario.name} (vehicle {self.config.base_vehicle.name!r}, "
            f"control={self.config.control!r}, free_surface={self.free_surface}, sea={self.sea})"
        )

    def differences(self, other: MadeFor) -> list[str]:
        """The names of what differs from ``other``: configuration fields, ``free_surface``, ``sea``."""
        names = [
            field.name
            for field in dataclasses.fields(self.config)
            if repr(getattr(self.config, field.name)) != repr(getattr(other.config, field.name))
        ]
        return names + [
            name for name in ("free_surface", "sea") if getattr(self, name) != getattr(other, name)
        ]


def _record(name: str, fields: Sequence[str], doc: str, meta: Sequence[str] = ()) -> type:
    """A frozen dataclass with ``fields`` (leaves or subtrees) and ``meta`` (static data), registered as a
    JAX pytree."""
    cls = dataclasses.make_dataclass(name, [(field, Any) for field in (*fields, *meta)], frozen=True)
    cls.__module__, cls.__doc__ = __name__, doc
    return jax.tree_util.register_dataclass(cls, data_fields=list(fields), meta_fields=list(meta))


Episode = _record(
    "Episode",
    (*_EPISODE_FIELDS, "waves"),
    """\
What a reset draws and a step only reads: the fields of :data:`subenv.envs.transition.EPISODE_DTYPE`,
by name, and ``waves``, the episode's sea (shape (WAVE_FIELDS, MAX_WAVES): its
:meth:`~subenv.dynamics.waves.SeaState.components`; shape (0,) in an environment without seas).""",
)

EnvState = _record(
    "EnvState",
    (*_STATE_FIELDS, "obs", "episode"),
    """\
One environment's state: the fields of :data:`subenv.envs.transition.STATE_DTYPE`, by name (the
vehicle's state, the applied planes, the time and steps since the reset, the heave force, the speed,
the distance travelled), ``obs``, the last observation (float32, shape (8,)), ``episode``, its
:class:`Episode`, and ``made_for``, the environment it belongs to (:class:`MadeFor`, static).""",
    meta=("made_for",),
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

    @property
    def made_for(self) -> MadeFor:
        """The environment the episodes were drawn for (static)."""
        made_for: MadeFor = self.table.made_for
        return made_for


jax.tree_util.register_dataclass(EnvParams, data_fields=["table"], meta_fields=[])


class DivePlaneJaxEnv:
    """:class:`~subenv.envs.DivePlaneEnv` as a functional JAX environment, with gymnax 1.0's interface.

    ``reset(key, params) -> (obs, state)`` and ``step(key, state, action, params) -> (obs, state,
    reward, terminated, truncated, info)`` are pure functions of arrays: ``jax.jit`` and ``jax.vmap``
    them (one key per environment). ``step`` resets an environment whose episode ended (terminated or
    truncated) within the same call, by a select, as gymnax does: then ``obs`` and ``state`` are the
    new episode's, ``reward``, ``terminated``, ``truncated`` and ``info`` the ended step's, and
    ``info["final_observation"]`` the observation the step reached (the ``obs`` of every step that
    did not end an episode). ``info`` holds the Gymnasium environment's ``info`` values
    (``termination_reason`` as its code, ``reason``: :data:`subenv.envs.transition.REASONS`) with
    ``reward``, ``terminated`` and ``truncated`` (booleans), ``discount`` (0 where terminated,
    gymnax's convention) and ``final_observation``.

    Made by :func:`make`. The configuration (:class:`~subenv.envs.DivePlaneConfig`) is static, part of
    the compiled program; the episodes are data (:class:`EnvParams`). Both the states and the
    episodes carry the environment they were made for (:class:`MadeFor`), and any other's are
    refused while the program is traced (``ValueError``).

    An action has the action space's shape, ``(num_actions,)`` (or ``()`` with one component), and
    real numbers (integers or floats; not bools or complex numbers): anything else is refused while
    the program is traced (``ValueError``). Actions are clipped to [-1, 1] as in the Gymnasium
    environment; as a compiled program cannot raise, a NaN or infinite action counts as 0 (the
    Gymnasium environment raises ``ValueError``).
    """

    def __init__(
        self,
        config: DivePlaneConfig,
        max_episode_steps: int | None,
        free_surface: bool,
        sea: bool,
        env_id: str | None = None,
    ) -> None:
        for name, value in (("free_surface", free_surface), ("sea", sea)):
            check.require(name, value, isinstance(value, bool | np.bool_), "True or False")
        self.config = config
        """The environment's configuration."""
        self.max_episode_steps = max_episode_steps
        """Truncate after this many steps, as ``gymnasium.wrappers.TimeLimit`` (None: the scenario's duration
        only)."""
        self.free_surface = bool(free_surface)
        """Whether the episodes may have a free surface (its suction is computed for every state)."""
        self.sea = bool(sea)
        """Whether the episodes may have a sea (its force is computed for every state)."""
        self.made_for = MadeFor.of(env_id, config, self.free_surface, self.sea)
        """What this environment's states and episodes are made for."""
        record = config.constants(max_episode_steps)[0]
        self._cfg = types.SimpleNamespace(**{name: _python(record[name]) for name in _CONFIG_FIELDS})
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
        return self.config.n_actions

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
        self, key: jax.Array, state: Any, action: Any, params: EnvParams | None = None
    ) -> tuple[jax.Array, Any, jax.Array, jax.Array, jax.Array, dict[str, jax.Array]]:
        """One control period; an ended episode is followed by a new one at once (see the class):
        ``(obs, state, reward, terminated, truncated, info)``."""
        params = self.default_params if params is None else params
        key, key_reset = jax.random.split(key)
        obs_stepped, stepped, reward, terminated, info = self.step_env(key, state, action, params)
        truncated = info["truncated"]
        done = terminated | truncated
        obs_reset, reset = self.reset_env(key_reset, params)
        state = jax.tree_util.tree_map(lambda a, b: jnp.where(done, a, b), reset, stepped)
        info = {**info, "final_observation": obs_stepped}
        return jnp.where(done, obs_reset, obs_stepped), state, reward, terminated, truncated, info

    def reset_env(self, key: jax.Array, params: EnvParams) -> tuple[jax.Array, Any]:
        """A reset to a row of the table drawn with ``key`` (:meth:`reset_to`)."""
        key_row, key_noise = jax.random.split(key)
        row = jax.random.randint(key_row, (), 0, params.n_episodes)
        state = self.reset_to(row, params, jax.random.normal(key_noise, (tr.N_OBS,)))
        return state.obs, state

    def step_env(
        self, key: jax.Array, state: Any, action: Any, params: EnvParams | None = None
    ) -> tuple[jax.Array, Any, jax.Array, jax.Array, dict[str, jax.Array]]:
        """One control period without the reset (:meth:`transition` with normals from ``key``):
        ``(obs, state, reward, terminated, info)``, gymnax's (``info["truncated"]``: whether the episode
        was truncated)."""
        state, info = self.transition(state, action, jax.random.normal(key, (N_NORMALS,)))
        return state.obs, state, info["reward"], info["terminated"], info

    def get_obs(self, state: Any, params: EnvParams | None = None, key: jax.Array | None = None) -> jax.Array:
        """The state's observation."""
        self._check_made_for("state", state)
        return state.obs

    def is_terminated(self, state: Any, params: EnvParams | None = None) -> jax.Array:
        """Whether the episode ended at ``state`` for a reason of its own (a ``termination_reason``)."""
        return self._outcome(state)[0]

    def is_truncated(self, state: Any, params: EnvParams | None = None) -> jax.Array:
        """Whether the episode was truncated at ``state``: by the scenario's duration or the time limit."""
        return self._outcome(state)[1]

    def is_terminal(self, state: Any, params: EnvParams | None = None) -> jax.Array:
        """:meth:`is_terminated` (gymnax 1.0: time limits are truncations, not terminal states)."""
        return self.is_terminated(state, params)

    def discount(self, state: Any, params: EnvParams | None = None) -> jax.Array:
        """0.0 where :meth:`is_terminated`, else 1.0."""
        return jnp.where(self.is_terminated(state, params), 0.0, 1.0)

    def _outcome(self, state: Any) -> tuple[jax.Array, jax.Array]:
        """(terminated, truncated) of ``state``, from its fields
        (:func:`~subenv.envs.transition.episode_outcome`)."""
        self._check_made_for("state", state)
        cfg, e = self._cfg, state.episode
        reason = self._episode_end(
            state.pitch_rad, state.heave_mps, state.pitch_rate_radps, state.depth_m, e.depth_command_m, cfg
        )
        return self._episode_outcome(reason, state.time_s, state.steps, e.duration_s, cfg)

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
                f"seeds={_short(seeds)} draw episodes with a {'free surface' if suction else 'sea'} that "
                f"this environment was made without (free_surface={self.free_surface}, sea={self.sea})"
            )
        episode = Episode(
            **{name: jnp.asarray(episodes[name]) for name in _EPISODE_FIELDS},
            waves=jnp.asarray(seas) if self.sea else jnp.zeros((len(episodes), 0)),
        )
        fields = {name: jnp.asarray(states[name]) for name in _STATE_FIELDS}
        obs = jnp.zeros((len(states), tr.N_OBS), dtype=jnp.float32)
        return EnvParams(EnvState(**fields, obs=obs, episode=episode, made_for=self.made_for))

    def reset_to(self, row: Any, params: EnvParams, normals: Any) -> Any:
        """The state at the reset of episode ``row`` of the table, observed with the sensor noise of
        ``normals`` (:data:`~subenv.envs.transition.N_OBS` standard normal numbers; read only where the
        episode has sensor noise), as the Gymnasium environment's reset observes it."""
        self._check_made_for("params", params.table)
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
        self._check_made_for("state", state)
        a = self._action(action)
        cfg, s, e = self._cfg, state, state.episode
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
        report = self._report_values(new, e, *rewards, reason, terminated, truncated)
        info = dict(zip(tr.REPORT_KEYS, report, strict=True))
        info["terminated"], info["truncated"] = jnp.asarray(terminated), jnp.asarray(truncated)
        info["discount"] = jnp.where(terminated, 0.0, 1.0)
        return new, info

    def _action(self, action: Any) -> jax.Array:
        """``action``, checked (while traced: its shape and type are static), as float64 of shape
        (num_actions,), a NaN or infinite component as 0."""
        n = self.num_actions
        try:
            a = jnp.asarray(action)
        except (TypeError, ValueError):
            raise ValueError(
                f"action={action!r} is invalid: must be an array of real numbers of shape ({n},)"
            ) from None
        if not (jnp.issubdtype(a.dtype, jnp.integer) or jnp.issubdtype(a.dtype, jnp.floating)):
            raise ValueError(
                f"action has dtype {a.dtype}: must hold real numbers (integers or floats; not bools or "
                "complex numbers)"
            )
        shapes = [(n,), ()] if n == 1 else [(n,)]
        if a.shape not in shapes:
            raise ValueError(
                f"action has shape {a.shape}: must have shape {' or '.join(map(str, shapes))} "
                f"(control={self.config.control!r}; a batch of actions is jax.vmap's)"
            )
        a = jnp.reshape(a.astype(jnp.float64), (n,))
        return jnp.where(jnp.isfinite(a), a, 0.0)

    def _check_made_for(self, name: str, record: Any) -> None:
        """Refuse a state or a table of episodes (``record``, an :data:`EnvState`) of another environment."""
        theirs = getattr(record, "made_for", None)
        if not isinstance(theirs, MadeFor):
            raise ValueError(
                f"{name}={type(record).__name__} is invalid: must be an EnvState of this environment "
                f"({self.made_for})"
            )
        if theirs != self.made_for:
            raise ValueError(
                f"{name} was made for {theirs}, not for this environment, {self.made_for} (they differ "
                f"in {', '.join(self.made_for.differences(theirs)) or 'the configuration'}): use this "
                "environment's own (its params(seeds), or the params subenv.jax.make returned with it)"
            )


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
        every state); by default, whether the table's episodes have one. Static: the environment's
        states and episodes carry them (:class:`MadeFor`).
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
    for name, value in (("free_surface", free_surface), ("sea", sea)):
        check.require(name, value, value is None or isinstance(value, bool | np.bool_), "True, False or None")
    config = DivePlaneConfig(**{**spec.kwargs, **kwargs})
    seeds = range(first, first + n)
    episodes_, states, seas = episode_table(config, seeds)
    suction, waves = _needs(episodes_)
    env = DivePlaneJaxEnv(
        config,
        steps,
        suction if free_surface is None else bool(free_surface),
        waves if sea is None else bool(sea),
        env_id,
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
