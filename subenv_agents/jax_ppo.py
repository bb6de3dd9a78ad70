"""PPO on subenv's functional JAX environment, the whole training in one compiled program.

PureJaxRL's recipe (Lu et al. 2022, ``purejaxrl/ppo_continuous_action.py``): the environments
(:func:`subenv.jax.make`, ``jax.vmap``-ed), the rollout, the advantages and the updates are one
``jax.jit`` of :func:`make_train`'s ``train(key)``, a ``jax.lax.scan`` over the updates. On an
accelerator that is the fast path; on a CPU it runs too (``benchmarks/jax_ppo.py``).

- The policy: a diagonal Gaussian whose mean is a tanh MLP of the normalised observation, with
  state-independent log standard deviations; the critic a second MLP (orthogonal initialisation, as
  PureJaxRL). With ``memory`` (:class:`PPOConfig`) both also read the state of a GRU they share over
  an embedding of the observation (PureJaxRL's ``ppo_rnn``: the rollout carries each environment's
  memory, emptied at an episode's first step, and the updates replay whole sequences from the memory
  they started with), so that the policy can identify what one observation does not tell (an unknown
  ballast offset on either side of u_cr); with ``depth_integral_s`` it also observes a leaky integral
  of the depth error. :func:`policy_step` is the one copy of the deterministic policy: training
  samples around it, :class:`JaxPPOController` acts with it.
- Resets draw from a table of episodes, uniformly or (``curriculum="difficulty"``) by the analysis's
  difficulty of each (:mod:`subenv_agents.difficulty`).
- Observations are normalised by running statistics (mean and variance over everything the
  environments observed, as PureJaxRL's ``NormalizeVecObservation`` and SB3's ``VecNormalize``),
  rewards scaled by the running deviation of the discounted return; the statistics are saved with
  the network.
- A truncated episode (the scenario's duration, the time limit) bootstraps from the value of the
  observation its last step reached (gymnax 1.0's ``info["final_observation"]``: the step's own
  observation is already the next episode's), a terminated one from zero (:func:`advantages`).
- Optimisation is optax's (global-norm clipping, Adam with a linearly annealed step).

``python -m subenv_agents.jax_ppo`` trains the shipped agent's settings (:class:`PPOConfig`'s defaults)
and writes a model folder (:func:`save`), by default ``results/agents/ppo_jax/<env>_<k>`` (``--out``
names another): ``network.npz``, ``config.json`` and ``train.json``, complete or absent
(:mod:`subenv.atomic`).
:func:`load` checks a folder whole (a damaged or inconsistent file is refused, by its name and the
field).
:class:`JaxPPOController` loads one as a controller of :mod:`subenv.evaluation`; the shipped one,
``subenv_agents/models/ppo_jax/``, is the ``ppo_jax`` entry point (``subenv evaluate``).

Needs the ``jax-rl`` extra (jax, optax).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import itertools
import json
import math
import os
import platform
import shlex
import struct
import sys
import time
import zipfile
import zlib
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Final, NamedTuple

import gymnasium as gym
import numpy as np

import subenv.envs
from subenv import _validation as check
from subenv.atomic import atomic_output_dir, check_output_dir
from subenv.envs.config import OBSERVATION_NAMES, DivePlaneConfig
from subenv.evaluation import DEFAULT_SEED, DEFAULT_SUITE, SingleRowMixin, check_batch
from subenv.evaluation.metrics import DEPTH_TOLERANCE_M, HOLD_WINDOW_S
from subenv.extras import require
from subenv.vehicles import Vehicle
from subenv_agents.config import DEFAULT_LOG_FOLDER, DepthIntegralConfig, next_run_dir
from subenv_agents.difficulty import CURRICULA, curriculum_weights, table_difficulties
from subenv_agents.records import (
    BASELINE,
    REVERSAL_SCENARIOS,
    check_harness_kwargs,
    evaluation_record,
    score_record,
    score_table,
    table,
    target_met,
)

require("jax-rl", "PPO on the JAX environment (subenv_agents.jax_ppo)", "jax", "optax")

# (after require(), which names the extra to install where they are missing)
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import optax  # noqa: E402

import subenv.jax as sj  # noqa: E402

__all__ = [
    "JaxPPOController",
    "PPOConfig",
    "advantages",
    "load",
    "main",
    "make_train",
    "model_card",
    "policy_mean",
    "save",
    "shipped",
    "shipped_folder",
]

_LOG_2PI = math.log(2.0 * math.pi)
_OBS_CLIP = 10.0  # normalised observations are clipped to +-this (SB3's VecNormalize default)
_FLOAT32_MAX = float(np.finfo(np.float32).max)


@dataclasses.dataclass(frozen=True)
class PPOConfig:
    """The training's settings (PureJaxRL's names, lower case). The defaults are the shipped ``ppo_jax``'s
    (``subenv_agents/models/ppo_jax/config.json``): ``python -m subenv_agents.jax_ppo --out DIR`` trains
    it again."""

    env_id: str = "subenv/Mixed-v0"
    """The registered id trained on (Mixed: every base scenario, the reversal ones twice as often)."""
    env_kwargs: Mapping[str, Any] = dataclasses.field(
        default_factory=lambda: {"control": "independent", "effort_weight": 1.0, "depth_scale_m": 1.0}
    )
    """:class:`~subenv.envs.DivePlaneEnv`'s arguments (``control``, ``alpha``, reward weights, ...); by
    default both plane pairs, independently, with the shipped agent's reward weights."""
    total_timesteps: int = 20_000_000
    num_envs: int = 1024
    num_steps: int = 64
    """Steps per environment per update (with a memory: the length of the sequences it learns from)."""
    update_epochs: int = 4
    num_minibatches: int = 16
    lr: float = 3e-4
    anneal_lr: bool = True
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_eps: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    hidden: tuple[int, ...] = (64, 64)
    """Widths of the actor's and the critic's hidden layers."""
    memory: int = 64
    """Width of the policy's recurrent memory (a GRU the actor and the critic share, PureJaxRL's
    ``ppo_rnn``); 0: a memoryless policy of the observation."""
    depth_integral_s: float = 0.0
    """Leak time constant [s] of the depth-error integral the policy observes besides the environment's
    observation (:func:`next_integral`); 0: not observed."""
    normalize_reward: bool = True
    episodes: int = 4096
    """Rows of the table of episodes the environments reset from (:func:`subenv.jax.make`)."""
    curriculum: str = "uniform"
    """How resets pick a row of the table: ``"uniform"`` (the environment's own sampling) or
    ``"difficulty"`` (:func:`subenv_agents.difficulty.curriculum_weights`: winnable episodes only, a
    share of them by the analysis's hardness)."""
    curriculum_share: float = 0.5
    """With ``curriculum="difficulty"``: the share of resets drawn in proportion to hardness (the rest
    uniformly over the winnable episodes)."""
    seed: int = 0
    """Seeds the table's episodes (``seed``, ``seed + 1``, ...) and the training's key."""

    def __post_init__(self) -> None:
        for name in (
            "total_timesteps",
            "num_envs",
            "num_steps",
            "update_epochs",
            "num_minibatches",
            "episodes",
        ):
            check.integer(name, getattr(self, name), 1)
        check.integer("seed", self.seed, 0)
        check.integer("memory", self.memory, 0)
        for name in ("lr", "max_grad_norm"):
            check.positive(name, getattr(self, name))
        for name in ("gamma", "gae_lambda", "curriculum_share"):
            value = getattr(self, name)
            check.require(
                name, value, isinstance(value, (int, float)) and 0.0 <= value <= 1.0, "a number in [0, 1]"
            )
        for name in ("clip_eps", "ent_coef", "vf_coef", "depth_integral_s"):
            value = getattr(self, name)
            check.require(
                name,
                value,
                isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0,
                "a finite number >= 0",
            )
        check.require(
            "hidden",
            self.hidden,
            isinstance(self.hidden, tuple | list)
            and len(self.hidden) > 0
            and all(isinstance(w, int) and not isinstance(w, bool) and w > 0 for w in self.hidden),
            "a non-empty tuple of positive widths",
        )
        for name in ("anneal_lr", "normalize_reward"):
            check.require(name, getattr(self, name), isinstance(getattr(self, name), bool), "True or False")
        check.require(
            "curriculum", self.curriculum, self.curriculum in CURRICULA, f"one of {list(CURRICULA)}"
        )
        batch = self.num_envs * self.num_steps
        check.require(
            "num_minibatches",
            self.num_minibatches,
            batch % self.num_minibatches == 0,
            f"a divisor of num_envs * num_steps = {batch}",
        )
        if self.memory:  # (minibatches of whole sequences: environments, not steps, are shared out)
            check.require(
                "num_minibatches",
                self.num_minibatches,
                self.num_envs % self.num_minibatches == 0,
                f"a divisor of num_envs = {self.num_envs} (a policy with memory learns from whole sequences)",
            )
        check.require(
            "total_timesteps",
            self.total_timesteps,
            self.total_timesteps >= batch,
            f"at least num_envs * num_steps = {batch} (one update)",
        )
        object.__setattr__(self, "hidden", tuple(self.hidden))
        check.require("env_kwargs", self.env_kwargs, isinstance(self.env_kwargs, Mapping), "a mapping")
        object.__setattr__(self, "env_kwargs", dict(self.env_kwargs))
        check.require(
            "env_id",
            self.env_id,
            isinstance(self.env_id, str) and self.env_id in subenv.envs.env_ids(),
            "a registered subenv id",
        )
        try:  # (the environment's own checks, before anything is drawn or compiled)
            DivePlaneConfig(**{**gym.spec(self.env_id).kwargs, **self.env_kwargs})
        except TypeError as exc:
            raise ValueError(f"env_kwargs={self.env_kwargs!r} is invalid: {exc}") from None

    @property
    def env_config(self) -> DivePlaneConfig:
        """The environment's configuration."""
        return DivePlaneConfig(**{**gym.spec(self.env_id).kwargs, **self.env_kwargs})

    @property
    def n_actions(self) -> int:
        """Components of the environment's action."""
        return self.env_config.n_actions

    @property
    def observation(self) -> tuple[str, ...]:
        """What the policy observes, in order: the environment's observation, then the depth-error
        integral if it is observed."""
        return (*OBSERVATION_NAMES, *((INTEGRAL_NAME,) if self.depth_integral_s > 0 else ()))

    @property
    def num_updates(self) -> int:
        """Updates of the training (its env-steps: ``num_updates * num_envs * num_steps``)."""
        return self.total_timesteps // (self.num_envs * self.num_steps)


# --- what the policy observes ------------------------------------------------------------------------
INTEGRAL_NAME: Final = "depth_error_integral_ms"
"""The name of the depth-error integral in :attr:`PPOConfig.observation`."""
INTEGRAL_LIMIT_MS: Final = DepthIntegralConfig().limit_ms
"""The integral's clipping [m s], the Stable-Baselines3 agents' (:mod:`subenv_agents.features`)."""


class Integral(NamedTuple):
    """The constants of the leaky depth-error integral: its decay per control period, the period [s] and
    the clipping [m s]."""

    decay: float
    dt_s: float
    limit_ms: float

    @classmethod
    def of(cls, config: PPOConfig) -> Integral | None:
        """``config``'s integral (None when the policy does not observe one)."""
        if config.depth_integral_s <= 0:
            return None
        dt = config.env_config.dt
        return cls(math.exp(-dt / config.depth_integral_s), dt, INTEGRAL_LIMIT_MS)


def next_integral(integral: Integral | None, value: jax.Array, obs: jax.Array, first: jax.Array) -> jax.Array:
    """The depth-error integral after the observation ``obs`` (..., 8): 0 at an episode's ``first``
    observation, else ``clip(decay value + dt e, -limit, limit)`` with e its depth error, as
    :class:`subenv_agents.features.DepthIntegral` (the leak keeps it stationary under noise and
    disturbances); ``value`` unchanged without an integral."""
    if integral is None:
        return value
    grown = jnp.clip(
        integral.decay * value + integral.dt_s * obs[..., 0], -integral.limit_ms, integral.limit_ms
    )
    return jnp.where(first, 0.0, grown)


def features(integral: Integral | None, obs: jax.Array, value: jax.Array) -> jax.Array:
    """What the policy observes (:attr:`PPOConfig.observation`): ``obs`` and, with an integral, its
    ``value`` as one more component."""
    return obs if integral is None else jnp.concatenate([obs, value[..., None].astype(obs.dtype)], axis=-1)


# --- the network -----------------------------------------------------------------------------------
def init_network(
    key: jax.Array, obs_dim: int, act_dim: int, hidden: Sequence[int], memory: int = 0
) -> dict[str, Any]:
    """The actor's and the critic's layers (orthogonal weights, zero biases), the log standard deviations
    and, with a ``memory``, the GRU they share and the layer that embeds the observation for it."""

    def mlp(key: jax.Array, sizes: Sequence[int], last_scale: float) -> list[dict[str, jax.Array]]:
        layers = []
        for i, (k, n_in, n_out) in enumerate(
            zip(jax.random.split(key, len(sizes) - 1), sizes[:-1], sizes[1:], strict=True)
        ):
            scale = last_scale if i == len(sizes) - 2 else math.sqrt(2.0)
            layers.append(
                {
                    "w": jax.nn.initializers.orthogonal(scale)(k, (n_in, n_out), jnp.float32),
                    "b": jnp.zeros(n_out, jnp.float32),
                }
            )
        return layers

    key_actor, key_critic = jax.random.split(key)
    network: dict[str, Any] = {
        "actor": mlp(key_actor, (obs_dim + memory, *hidden, act_dim), 0.01),
        "critic": mlp(key_critic, (obs_dim + memory, *hidden, 1), 1.0),
        "log_std": jnp.zeros(act_dim, jnp.float32),
    }
    if memory:  # (a key of its own: a memoryless network is what it was)
        key_embed, key_input, key_hidden = jax.random.split(jax.random.fold_in(key, 1), 3)
        orthogonal = jax.nn.initializers.orthogonal
        network["embed"] = {
            "w": orthogonal(math.sqrt(2.0))(key_embed, (obs_dim, memory), jnp.float32),
            "b": jnp.zeros(memory, jnp.float32),
        }
        network["gru"] = {
            "wi": orthogonal(1.0)(key_input, (memory, 3 * memory), jnp.float32),
            "wh": orthogonal(1.0)(key_hidden, (memory, 3 * memory), jnp.float32),
            "bi": jnp.zeros(3 * memory, jnp.float32),
            "bhn": jnp.zeros(memory, jnp.float32),
        }
    return network


def memory_size(network: Mapping[str, Any]) -> int:
    """The width of ``network``'s memory (0: none)."""
    return int(network["gru"]["bhn"].shape[0]) if "gru" in network else 0


def _mlp(layers: Sequence[Mapping[str, jax.Array]], x: jax.Array) -> jax.Array:
    for layer in layers[:-1]:
        x = jnp.tanh(x @ layer["w"] + layer["b"])
    return x @ layers[-1]["w"] + layers[-1]["b"]


def _gru(cell: Mapping[str, jax.Array], h: jax.Array, x: jax.Array) -> jax.Array:
    """A GRU cell (Cho et al. 2014; flax's ``GRUCell``): reset and update gates r, z, candidate n."""
    m = h.shape[-1]
    gi, gh = x @ cell["wi"] + cell["bi"], h @ cell["wh"]
    r = jax.nn.sigmoid(gi[..., :m] + gh[..., :m])
    z = jax.nn.sigmoid(gi[..., m : 2 * m] + gh[..., m : 2 * m])
    n = jnp.tanh(gi[..., 2 * m :] + r * (gh[..., 2 * m :] + cell["bhn"]))
    return (1.0 - z) * n + z * h


def _core(network: Mapping[str, Any], memory: jax.Array, x: jax.Array) -> tuple[jax.Array, jax.Array]:
    """The memory after the normalised features ``x``, and what the actor and the critic read: ``x``
    itself without a memory, ``x`` and the new memory with one."""
    if "gru" not in network:
        return memory, x
    embedded = jnp.tanh(x @ network["embed"]["w"] + network["embed"]["b"])
    memory = _gru(network["gru"], memory, embedded)
    return memory, jnp.concatenate([x, memory], axis=-1)


def policy_step(
    network: Mapping[str, Any], stats: RunningStats, memory: jax.Array, observed: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """The deterministic policy, one step: ``(memory, mean action)`` after the raw features
    ``observed`` (..., :attr:`PPOConfig.observation`), ``memory`` (..., width) the memory before them
    (zeros at an episode's start; width 0 without a memory)."""
    memory, z = _core(network, memory, normalize(stats, observed))
    return memory, _mlp(network["actor"], z)


def policy_mean(network: Mapping[str, Any], obs: jax.Array, stats: RunningStats) -> jax.Array:
    """The policy's mean action for raw observations ``obs`` (..., obs_dim) at an episode's start (from
    an empty memory): the deterministic policy of a memoryless network."""
    empty = jnp.zeros((*obs.shape[:-1], memory_size(network)), jnp.float32)
    return policy_step(network, stats, empty, obs)[1]


def _value(network: Mapping[str, Any], z: jax.Array) -> jax.Array:
    return _mlp(network["critic"], z)[..., 0]


def _log_prob(mean: jax.Array, log_std: jax.Array, action: jax.Array) -> jax.Array:
    """Log N(action; mean, exp(log_std)^2), summed over the action's components."""
    z = (action - mean) * jnp.exp(-log_std)
    return jnp.sum(-0.5 * z * z - log_std - 0.5 * _LOG_2PI, axis=-1)


# --- running statistics ------------------------------------------------------------------------------
class RunningStats(NamedTuple):
    """Mean and variance of everything seen so far (Chan et al.'s parallel update, as Gymnasium's
    ``RunningMeanStd``)."""

    mean: jax.Array
    var: jax.Array
    count: jax.Array

    @classmethod
    def empty(cls, shape: tuple[int, ...]) -> RunningStats:
        return cls(jnp.zeros(shape), jnp.ones(shape), jnp.asarray(1e-4))

    def update(self, batch: jax.Array) -> RunningStats:
        """With ``batch`` (n, *shape) seen."""
        batch = batch.astype(jnp.float64)
        n = batch.shape[0]
        mean, var = batch.mean(axis=0), batch.var(axis=0)
        total = self.count + n
        delta = mean - self.mean
        m2 = self.var * self.count + var * n + delta * delta * self.count * n / total
        return RunningStats(self.mean + delta * n / total, m2 / total, total)


def normalize(stats: RunningStats, obs: jax.Array) -> jax.Array:
    """``obs`` standardised by ``stats`` and clipped to +-10, float32."""
    z = (obs - stats.mean) / jnp.sqrt(stats.var + 1e-8)
    return jnp.clip(z, -_OBS_CLIP, _OBS_CLIP).astype(jnp.float32)


# --- the training ------------------------------------------------------------------------------------
class Rollout(NamedTuple):
    """One step of every environment (a leading time axis in a rollout)."""

    obs: jax.Array  # normalised features
    first: jax.Array  # the observation is its episode's first: the memory starts empty there
    action: jax.Array
    log_prob: jax.Array
    value: jax.Array
    reward: jax.Array  # scaled
    terminated: jax.Array
    done: jax.Array  # terminated or truncated: the next step is a new episode's
    final_value: jax.Array  # the value of the observation the step reached (info["final_observation"])


def advantages(
    rollout: Rollout, last_value: jax.Array, gamma: float, lam: float
) -> tuple[jax.Array, jax.Array]:
    """GAE(gamma, lambda) advantages of a rollout (time first) and the value targets, ``last_value`` the
    value of the observation after its last step.

    Each step bootstraps from the value of where it led: zero after a termination, the final
    observation's after a truncation (the next step of the rollout is a new episode's), the next
    step's otherwise; the advantages do not run on across an episode's end.
    """

    def back(carry: tuple[jax.Array, jax.Array], t: Rollout) -> tuple[tuple[jax.Array, jax.Array], jax.Array]:
        gae, next_value = carry
        bootstrap = jnp.where(t.terminated, 0.0, jnp.where(t.done, t.final_value, next_value))
        delta = t.reward + gamma * bootstrap - t.value
        gae = delta + gamma * lam * (1.0 - t.done) * gae
        return (gae, t.value), gae

    _, adv = jax.lax.scan(back, (jnp.zeros_like(last_value), last_value), rollout, reverse=True)
    return adv, adv + rollout.value


class Metrics(NamedTuple):
    """Per update: the mean reward per env-step, episodes ended, episodes terminated (failed), episodes
    won (not terminated, and within the success tolerance over the final hold window, as
    :func:`subenv.evaluation.metrics.episode_success` judges it)."""

    reward: jax.Array
    episodes: jax.Array
    terminated: jax.Array
    won: jax.Array


class TrainState(NamedTuple):
    network: Any
    opt_state: Any
    obs_stats: RunningStats
    return_stats: RunningStats
    returns: jax.Array
    env_state: Any
    obs: jax.Array  # raw
    integral: jax.Array  # the depth-error integral after obs (0 without one)
    memory: jax.Array  # the memory before obs
    first: jax.Array  # obs is its episode's first
    outside_s: jax.Array  # time of the episode's last sample off depth (-inf: none)
    key: jax.Array


def make_train(
    config: PPOConfig,
    progress: Callable[[int, Metrics], None] | None = None,
    weights: np.ndarray | None = None,
) -> tuple[Callable[[jax.Array], tuple[TrainState, Metrics]], sj.DivePlaneJaxEnv]:
    """``train(key) -> (final state, metrics per update)``, to be ``jax.jit``-ed whole, and the
    environment it trains on. ``progress(update, metrics)`` is called from inside the program after
    every update (``jax.debug.callback``), if given. ``weights``: the probability of each row of the
    table at a reset (default: ``config``'s curriculum's, :func:`reset_weights`)."""
    env, params = sj.make(config.env_id, episodes=config.episodes, seed=config.seed, **config.env_kwargs)
    if weights is None:
        weights = reset_weights(config)
    n, steps = config.num_envs, config.num_steps
    integral = Integral.of(config)
    obs_dim, act_dim = len(config.observation), env.num_actions
    memory_width = config.memory
    updates = config.num_updates
    lr: Any = (
        optax.linear_schedule(config.lr, 0.0, updates * config.update_epochs * config.num_minibatches)
        if config.anneal_lr
        else config.lr
    )
    optimizer = optax.chain(optax.clip_by_global_norm(config.max_grad_norm), optax.adam(lr, eps=1e-5))
    step_envs = jax.vmap(env.step, in_axes=(0, 0, 0, None))
    gamma, lam = config.gamma, config.gae_lambda
    row_logits = None if weights is None else jnp.log(jnp.asarray(weights, dtype=jnp.float64))

    def table(key: jax.Array) -> Any:
        """The episodes resets draw from for one update: the table itself, or (a curriculum) rows of it
        drawn by their weights, as many as it has."""
        if row_logits is None:
            return params
        rows = jax.random.categorical(key, row_logits, shape=(params.n_episodes,))
        return jax.tree_util.tree_map(lambda leaf: leaf[rows], params)

    def env_step(
        carry: tuple[TrainState, Any], _: None
    ) -> tuple[tuple[TrainState, Any], tuple[Rollout, jax.Array]]:
        state, episodes = carry
        key, key_action, key_env = jax.random.split(state.key, 3)
        obs = normalize(state.obs_stats, features(integral, state.obs, state.integral))
        start = jnp.where(state.first[:, None], 0.0, state.memory)
        memory, z = _core(state.network, start, obs)
        mean, value = _mlp(state.network["actor"], z), _value(state.network, z)
        log_std = state.network["log_std"]
        action = mean + jnp.exp(log_std) * jax.random.normal(key_action, mean.shape)
        next_obs, env_state, reward, terminated, truncated, info = step_envs(
            jax.random.split(key_env, n), state.env_state, action, episodes
        )
        done = terminated | truncated
        final_obs = info["final_observation"]
        final_integral = next_integral(integral, state.integral, final_obs, jnp.zeros(n, bool))
        next_integral_value = jnp.where(done, 0.0, final_integral)  # (0 at a new episode's first observation)
        obs_stats = state.obs_stats.update(features(integral, next_obs, next_integral_value))
        # (normalised as the next step's observation is: its value is the next step's where no episode ended)
        _, z_final = _core(
            state.network, memory, normalize(obs_stats, features(integral, final_obs, final_integral))
        )
        final_value = _value(state.network, z_final)
        returns = state.returns * gamma + reward
        return_stats = (
            state.return_stats.update(returns[:, None]) if config.normalize_reward else state.return_stats
        )
        scaled = reward / jnp.sqrt(return_stats.var[0] + 1e-8) if config.normalize_reward else reward
        # (an episode's success, as episode_success judges it from the time of its last sample off depth)
        outside_s = jnp.where(
            ~(jnp.abs(info["depth_error_m"]) <= DEPTH_TOLERANCE_M), info["time_s"], state.outside_s
        )
        won = (
            done
            & ~terminated
            & (info["time_s"] >= HOLD_WINDOW_S)
            & (outside_s < info["time_s"] - HOLD_WINDOW_S)
        )
        rollout = Rollout(
            obs,
            state.first,
            action,
            _log_prob(mean, log_std, action),
            value,
            scaled.astype(jnp.float32),
            terminated,
            done,
            final_value,
        )
        state = state._replace(
            env_state=env_state,
            obs=next_obs,
            integral=next_integral_value,
            memory=memory,
            first=done,
            outside_s=jnp.where(done, -jnp.inf, outside_s),
            key=key,
            return_stats=return_stats,
            returns=jnp.where(done, 0.0, returns),
            obs_stats=obs_stats,
        )
        return (state, episodes), (rollout, jnp.stack([reward, won.astype(reward.dtype)]))

    def heads(network: Any, batch: Rollout, memory: jax.Array | None) -> tuple[jax.Array, jax.Array]:
        """The policy's means and values over ``batch``: step by step through its sequences from their
        first ``memory`` with a memory, all at once without."""
        if memory is None:
            z = batch.obs
        else:

            def run(h: jax.Array, t: tuple[jax.Array, jax.Array]) -> tuple[jax.Array, jax.Array]:
                x, first = t
                return _core(network, jnp.where(first[:, None], 0.0, h), x)

            _, z = jax.lax.scan(run, memory, (batch.obs, batch.first))
        return _mlp(network["actor"], z), _value(network, z)

    def loss(
        network: Any, batch: Rollout, adv: jax.Array, target: jax.Array, memory: jax.Array | None
    ) -> jax.Array:
        mean, value = heads(network, batch, memory)
        log_std = network["log_std"]
        ratio = jnp.exp(_log_prob(mean, log_std, batch.action) - batch.log_prob)
        adv = (adv - adv.mean()) / (adv.std() + 1e-8)
        actor = -jnp.minimum(
            ratio * adv, jnp.clip(ratio, 1 - config.clip_eps, 1 + config.clip_eps) * adv
        ).mean()
        clipped = batch.value + jnp.clip(value - batch.value, -config.clip_eps, config.clip_eps)
        critic = 0.5 * jnp.maximum((value - target) ** 2, (clipped - target) ** 2).mean()
        entropy = jnp.sum(log_std + 0.5 * (_LOG_2PI + 1.0))
        return actor + config.vf_coef * critic - config.ent_coef * entropy

    def minibatches_of(key: jax.Array, data: Any, memory: jax.Array) -> Any:
        """The update's data in minibatches: steps drawn at random without a memory; with one, whole
        sequences of environments drawn at random (time stays the first axis within each)."""
        k = config.num_minibatches
        if not memory_width:
            order = jax.random.permutation(key, n * steps)
            flat = jax.tree_util.tree_map(lambda x: x.reshape((n * steps, *x.shape[2:])), data)
            return jax.tree_util.tree_map(lambda x: x[order].reshape((k, -1, *x.shape[1:])), flat), None
        order = jax.random.permutation(key, n)
        split = jax.tree_util.tree_map(
            lambda x: jnp.swapaxes(x[:, order].reshape((steps, k, -1, *x.shape[2:])), 0, 1), data
        )
        return split, memory[order].reshape((k, -1, memory_width))

    def update(state: TrainState, index: jax.Array) -> tuple[TrainState, Metrics]:
        if row_logits is None:
            episodes = params
        else:  # (a key of its own: without a curriculum the training draws what it drew before)
            key, key_rows = jax.random.split(state.key)
            state, episodes = state._replace(key=key), table(key_rows)
        memory0 = state.memory
        (state, _), (rollout, per_step) = jax.lax.scan(env_step, (state, episodes), None, steps)
        _, z_last = _core(
            state.network,
            jnp.where(state.first[:, None], 0.0, state.memory),
            normalize(state.obs_stats, features(integral, state.obs, state.integral)),
        )
        adv, target = advantages(rollout, _value(state.network, z_last), gamma, lam)

        def epoch(carry: tuple[Any, Any, jax.Array], _: None) -> tuple[tuple[Any, Any, jax.Array], None]:
            network, opt_state, key = carry
            key, key_perm = jax.random.split(key)
            minibatches, memories = minibatches_of(key_perm, (rollout, adv, target), memory0)

            def minibatch(carry: tuple[Any, Any], mb: Any) -> tuple[Any, None]:
                network, opt_state = carry
                (batch, batch_adv, batch_target), memory = mb
                grads = jax.grad(loss)(network, batch, batch_adv, batch_target, memory)
                changes, opt_state = optimizer.update(grads, opt_state, network)
                return (optax.apply_updates(network, changes), opt_state), None

            (network, opt_state), _ = jax.lax.scan(minibatch, (network, opt_state), (minibatches, memories))
            return (network, opt_state, key), None

        key, key_epochs = jax.random.split(state.key)
        (network, opt_state, _), _ = jax.lax.scan(
            epoch, (state.network, state.opt_state, key_epochs), None, config.update_epochs
        )
        state = state._replace(network=network, opt_state=opt_state, key=key)
        metrics = Metrics(
            per_step[:, 0].mean(), rollout.done.sum(), rollout.terminated.sum(), per_step[:, 1].sum()
        )
        if progress is not None:
            jax.debug.callback(progress, index, metrics, ordered=True)
        return state, metrics

    def train(key: jax.Array) -> tuple[TrainState, Metrics]:
        key, key_network, key_reset = jax.random.split(key, 3)
        network = init_network(key_network, obs_dim, act_dim, config.hidden, memory_width)
        episodes = params
        if row_logits is not None:
            key_reset, key_rows = jax.random.split(key_reset)
            episodes = table(key_rows)
        obs, env_state = jax.vmap(env.reset, in_axes=(0, None))(jax.random.split(key_reset, n), episodes)
        state = TrainState(
            network,
            optimizer.init(network),
            RunningStats.empty((obs_dim,)).update(features(integral, obs, jnp.zeros(n))),
            RunningStats.empty((1,)),
            jnp.zeros(n),
            env_state,
            obs,
            jnp.zeros(n),
            jnp.zeros((n, memory_width), jnp.float32),
            jnp.ones(n, bool),
            jnp.full(n, -jnp.inf),
            key,
        )
        return jax.lax.scan(update, state, jnp.arange(updates))

    return train, env


def reset_weights(config: PPOConfig) -> np.ndarray | None:
    """The probability of each row of ``config``'s table at a reset: None for ``curriculum="uniform"``
    (the environment's own sampling), :func:`subenv_agents.difficulty.curriculum_weights` for
    ``"difficulty"`` (the analysis judges every row: about 5 ms each)."""
    if config.curriculum == "uniform":
        return None
    seeds = range(config.seed, config.seed + config.episodes)
    return curriculum_weights(
        table_difficulties(config.env_id, config.env_kwargs, seeds), config.curriculum_share
    )


# --- the model folder ------------------------------------------------------------------------------
_FILES = ("network.npz", "config.json", "train.json")
_OBSERVATION_KEY = "observation"
"""The key of ``config.json`` that names what the model observes (:attr:`PPOConfig.observation`)."""
_BEFORE_NAMES: Final = (
    "depth_error_m",
    "pitch_rad",
    "heave_mps",
    "pitch_rate_radps",
    "speed_mps",
    "stern_plane_rad",
    "bow_plane_rad",
    "depth_m",
)
"""What a model whose ``config.json`` names no observation observes (those saved before it was named:
the environment's observation of the time)."""


def save(
    path: str | Path,
    config: PPOConfig,
    network: Any,
    obs_stats: RunningStats,
    record: Mapping[str, Any],
    overwrite: bool = False,
    texts: Mapping[str, str] | None = None,
) -> Path:
    """Write a model folder: the network and the observation statistics (``network.npz``, arrays by
    their path in the network, ``obs_mean``/``obs_var``), the settings and what the policy observes
    (``config.json``), the training's record (``train.json``) and ``texts`` (file name: text). The
    folder is complete or absent at every instant."""
    arrays = {"obs_mean": np.asarray(obs_stats.mean), "obs_var": np.asarray(obs_stats.var)}
    for keys, leaf in jax.tree_util.tree_leaves_with_path(network):
        arrays["/".join(str(getattr(k, "key", getattr(k, "idx", k))) for k in keys)] = np.asarray(leaf)
    settings = {
        **dataclasses.asdict(config),
        "hidden": list(config.hidden),
        _OBSERVATION_KEY: list(config.observation),
    }
    with atomic_output_dir(path, overwrite=overwrite, kind="jax-ppo model") as out:
        np.savez(out / "network.npz", **arrays)
        (out / "config.json").write_text(json.dumps(settings, indent=2) + "\n")
        (out / "train.json").write_text(json.dumps(dict(record), indent=2) + "\n")
        for name, text in (texts or {}).items():
            (out / name).write_text(text)
    return Path(path)


def load(path: str | Path) -> tuple[PPOConfig, dict[str, Any], RunningStats]:
    """A model folder's settings, network and observation statistics (:func:`save`), checked whole.

    Raises ``FileNotFoundError`` for a folder without the model's files, and ``ValueError`` naming the
    file and the field for a damaged or inconsistent one: a file that does not read (truncated, not
    JSON, not NumPy's archive), a setting :class:`PPOConfig` refuses, a model trained for another
    observation than the environment's with its settings (both named), arrays missing or unknown to the
    network ``config.json`` describes, of another shape, not floating point, NaN or infinite, large
    enough that the network could overflow float32 for some observation (so a model that loads acts
    with finite numbers on every observation), or variances of the observations that are not > 0.
    """
    folder = Path(path)
    missing = [name for name in _FILES if not (folder / name).is_file()]
    if missing:
        raise FileNotFoundError(f"path={str(path)!r} is not a jax-ppo model folder: it lacks {missing}")
    config = _load_config(folder / "config.json")
    _read_json_object(folder / "train.json")  # (the training's record: not used here, but part of the model)
    file = folder / "network.npz"
    try:
        data = np.load(file, allow_pickle=False)
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError(f"it holds one array, not an archive of named arrays ({type(data).__name__})")
        with data:
            arrays = {name: data[name] for name in data.files}
    # (a damaged archive fails in zipfile's, zlib's, struct's or NumPy's format's own ways)
    except (
        OSError,
        ValueError,
        EOFError,
        KeyError,
        MemoryError,
        NotImplementedError,
        struct.error,
        zipfile.BadZipFile,
        zlib.error,
    ) as exc:
        raise ValueError(f"{file} does not read as np.savez's arrays: {type(exc).__name__}: {exc}") from None
    return config, *_network_of(arrays, config, file)


def _read_json_object(file: Path) -> dict[str, Any]:
    """The JSON object in ``file``, or ``ValueError`` naming it."""
    try:
        value = json.loads(file.read_bytes())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{file} is not a JSON file: {exc}") from None
    if not isinstance(value, dict):
        raise ValueError(f"{file} is invalid: must hold a JSON object (it holds a {type(value).__name__})")
    return value


def _load_config(file: Path) -> PPOConfig:
    """The :class:`PPOConfig` of a model's ``config.json``, checked as :class:`PPOConfig` checks its
    fields, and the observation it names checked against what the environment observes now."""
    settings = _read_json_object(file)
    observed = settings.pop(_OBSERVATION_KEY, list(_BEFORE_NAMES))
    known = [field.name for field in dataclasses.fields(PPOConfig)]
    unknown = sorted(set(settings) - set(known))
    if unknown:
        raise ValueError(
            f"{file} is invalid: unknown settings {unknown} (known: {[*known, _OBSERVATION_KEY]})"
        )
    if isinstance(settings.get("hidden"), list):
        settings["hidden"] = tuple(settings["hidden"])
    try:
        config = PPOConfig(**settings)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{file} is invalid: {exc}") from None
    if not (isinstance(observed, list) and all(isinstance(name, str) for name in observed)):
        raise ValueError(f"{file}: {_OBSERVATION_KEY}={observed!r} is invalid: must be a list of names")
    if tuple(observed) != config.observation:
        raise ValueError(
            f"{file}: the model was trained for the observation space {observed} ({len(observed)} "
            f"components), and {config.env_id} with its settings observes {list(config.observation)} "
            f"({len(config.observation)} components): train it again for this one"
        )
    return config


def _array_shapes(
    config: PPOConfig,
) -> tuple[dict[str, tuple[int, ...]], list[tuple[list[str], list[str], float]]]:
    """The arrays of ``config``'s network (name: shape), and its affine maps: (weights, biases, bound on
    |input|) of each (the normalised observation is clipped to +-10, tanh's and the memory's values are
    within +-1)."""
    obs_dim, act_dim, m = len(config.observation), config.n_actions, config.memory
    shapes: dict[str, tuple[int, ...]] = {
        "obs_mean": (obs_dim,),
        "obs_var": (obs_dim,),
        "log_std": (act_dim,),
    }
    maps = []
    for part, out in (("actor", act_dim), ("critic", 1)):
        sizes = (obs_dim + m, *config.hidden, out)
        for i, (n_in, n_out) in enumerate(itertools.pairwise(sizes)):
            shapes[f"{part}/{i}/w"], shapes[f"{part}/{i}/b"] = (n_in, n_out), (n_out,)
            maps.append(([f"{part}/{i}/w"], [f"{part}/{i}/b"], _OBS_CLIP if i == 0 else 1.0))
    if m:
        shapes |= {"embed/w": (obs_dim, m), "embed/b": (m,)}
        shapes |= {"gru/wi": (m, 3 * m), "gru/wh": (m, 3 * m), "gru/bi": (3 * m,), "gru/bhn": (m,)}
        maps += [(["embed/w"], ["embed/b"], _OBS_CLIP), (["gru/wi", "gru/wh"], ["gru/bi", "gru/bhn"], 1.0)]
    return shapes, maps


def _network_of(
    arrays: Mapping[str, np.ndarray], config: PPOConfig, file: Path
) -> tuple[dict[str, Any], RunningStats]:
    """The network and the observation statistics of ``network.npz``'s arrays, checked against ``config``."""
    described = (
        f"the network config.json describes: hidden={list(config.hidden)}, "
        + (f"memory={config.memory}, " if config.memory else "")
        + f"{config.n_actions} action components"
    )
    shapes, maps = _array_shapes(config)
    lacking, unknown = sorted(set(shapes) - set(arrays)), sorted(set(arrays) - set(shapes))
    if lacking or unknown:
        raise ValueError(
            f"{file} does not hold {described}: "
            + "; ".join(
                f"{what} {names}" for what, names in (("it lacks", lacking), ("unknown", unknown)) if names
            )
        )
    checked = {}
    for name, shape in shapes.items():
        array = arrays[name]
        if array.dtype.kind != "f":
            raise ValueError(f"{file}: {name} has dtype {array.dtype}: must be floating point")
        if array.shape != shape:
            raise ValueError(f"{file}: {name} has shape {array.shape}: must have shape {shape} ({described})")
        # (the network computes in float32, the statistics in float64; what overflows is refused below)
        with np.errstate(over="ignore", invalid="ignore"):
            array = array.astype(np.float64 if name.startswith("obs_") else np.float32)
        bad = int(np.count_nonzero(~np.isfinite(array)))
        if bad:
            raise ValueError(f"{file}: {name} has {bad} NaN or infinite values (as float32): must be finite")
        checked[name] = array
    if np.any(checked["obs_var"] <= 0.0):
        raise ValueError(
            f"{file}: obs_var={checked['obs_var'].tolist()} is invalid: must be > 0 (the variances of the "
            "observations, by which they are normalised)"
        )
    for weights, biases, bound in maps:
        # (each output's largest |sum| over inputs within the bound: |input| <= bound for the first layer's
        # normalised observation, 1 for tanh's outputs and the memory's)
        w = sum(np.abs(checked[name].astype(np.float64)).sum(axis=0) for name in weights)
        # (a GRU's bhn adds to its candidate, the last third of the outputs)
        b = sum(
            np.pad(np.abs(checked[name].astype(np.float64)), (w.size - checked[name].size, 0))
            for name in biases
        )
        largest = float(np.max(bound * w + b))
        if not largest < _FLOAT32_MAX:
            names = " and ".join([*weights, *biases])
            raise ValueError(
                f"{file}: {names} are invalid: they reach {largest:.3g} for some observation, beyond "
                f"float32's range: must keep |sum| below {_FLOAT32_MAX:.3g}"
            )
    layers = len(config.hidden) + 1
    network: dict[str, Any] = {
        part: [
            {"w": jnp.asarray(checked[f"{part}/{i}/w"]), "b": jnp.asarray(checked[f"{part}/{i}/b"])}
            for i in range(layers)
        ]
        for part in ("actor", "critic")
    }
    network["log_std"] = jnp.asarray(checked["log_std"])
    for part in ("embed", "gru") if config.memory else ():
        network[part] = {
            name.split("/")[1]: jnp.asarray(array)
            for name, array in checked.items()
            if name.startswith(part + "/")
        }
    stats = RunningStats(jnp.asarray(checked["obs_mean"]), jnp.asarray(checked["obs_var"]), jnp.asarray(0.0))
    return network, stats


def _control(
    integral: Integral | None,
    network: Any,
    stats: RunningStats,
    memory: jax.Array,
    value: jax.Array,
    first: jax.Array,
    obs: jax.Array,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """One step of the deterministic policy over a batch of episodes: the integral after ``obs``
    (:func:`next_integral`), the memory after the features, the mean action."""
    value = next_integral(integral, value, obs, first)
    memory, mean = policy_step(network, stats, jnp.where(first, 0.0, memory), features(integral, obs, value))
    return memory, value, mean


_compiled_control = jax.jit(_control, static_argnums=0)
""":func:`_control` compiled once per integral, network shape and batch size, for every controller alike
(not once per controller)."""


class JaxPPOController(SingleRowMixin):
    """A model folder of :func:`save` as a controller of :mod:`subenv.evaluation`: the policy's mean
    action (:func:`policy_step`, the function training sampled around), clipped to [-1, 1], with each
    episode's memory and depth-error integral (where the policy has them) kept per row.

    Parameters
    ----------
    path : path
        The model folder.
    name : str, optional
        The name in tables (default: the folder's name).
    """

    def __init__(self, path: str | Path, name: str | None = None) -> None:
        self._setup(*load(path), name or Path(path).name, repr(str(path)))

    @classmethod
    def of(cls, config: PPOConfig, network: Any, obs_stats: RunningStats, name: str) -> JaxPPOController:
        """A controller of a network not saved (yet)."""
        controller = cls.__new__(cls)
        controller._setup(config, network, obs_stats, name, name)
        return controller

    def _setup(self, config: PPOConfig, network: Any, stats: RunningStats, name: str, source: str) -> None:
        self.config, self._network, self._stats = config, network, stats
        check_harness_kwargs(self.config.env_kwargs, f"model {source}")
        self.name = name
        self.control = self.config.env_kwargs.get("control", "dual")
        self.alpha = float(self.config.env_kwargs.get("alpha", 0.0))
        self._integral_config = Integral.of(config)
        self._episodes = 0
        self._memory = jnp.zeros((0, config.memory), jnp.float32)
        self._integral = jnp.zeros(0)
        self._first = True

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Start ``len(infos)`` episodes: each with an empty memory and a zero depth-error integral."""
        self._episodes = len(infos)
        self._memory = jnp.zeros((self._episodes, self.config.memory), jnp.float32)
        self._integral = jnp.zeros(self._episodes)
        self._first = True

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The policy's mean actions of a batch of observations (one row per episode), clipped to [-1, 1]
        (float32)."""
        obs = check_batch(observations, self._episodes)
        self._memory, self._integral, mean = _compiled_control(
            self._integral_config,
            self._network,
            self._stats,
            self._memory,
            self._integral,
            np.bool_(self._first),  # (NumPy values: jit takes them as they are, faster than jnp.asarray)
            np.asarray(obs, dtype=np.float32),
        )
        self._first = False
        return np.clip(np.asarray(mean), -1.0, 1.0).astype(np.float32)


def shipped_folder() -> Path:
    """The shipped model's folder, ``subenv_agents/models/ppo_jax/``."""
    return Path(__file__).parent / "models" / "ppo_jax"


def shipped() -> JaxPPOController:
    """The shipped model (the ``ppo_jax`` entry point)."""
    return JaxPPOController(shipped_folder(), name="ppo_jax")


# --- the command line ----------------------------------------------------------------------------------
def main(argv: Sequence[str] | None = None) -> int:
    """``python -m subenv_agents.jax_ppo``: train, evaluate and write a model folder; the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m subenv_agents.jax_ppo", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "--out",
        default=None,
        help="the model folder to write, complete or absent (default: "
        f"{DEFAULT_LOG_FOLDER}/ppo_jax/<env>_<k>, k the first number free)",
    )
    parser.add_argument("--force", action="store_true", help="replace a model folder this command wrote")
    defaults = PPOConfig()
    for field in dataclasses.fields(PPOConfig):
        if field.name in ("env_kwargs", "hidden"):
            continue
        value = getattr(defaults, field.name)
        kind = (lambda s: s.lower() in ("1", "true", "yes")) if isinstance(value, bool) else type(value)
        parser.add_argument(
            f"--{field.name.replace('_', '-')}", type=kind, default=value, help=f"(default: {value})"
        )
    parser.add_argument(
        "--hidden",
        type=int,
        nargs="+",
        default=list(defaults.hidden),
        help=f"hidden layer widths (default: {' '.join(map(str, defaults.hidden))})",
    )
    parser.add_argument(
        "--env-kwargs",
        type=json.loads,
        default=dict(defaults.env_kwargs),
        help='the environment\'s arguments as JSON, e.g. \'{"control": "independent"}\' (default: '
        f"'{json.dumps(dict(defaults.env_kwargs))}')",
    )
    parser.add_argument(
        "--eval-episodes",
        type=int,
        default=100,
        help="episodes per scenario of the evaluation written with the model (evaluation.json, "
        f"MODEL_CARD.md) on the {DEFAULT_SUITE!r} suite, next to the baselines; 0: none (default: 100)",
    )
    parser.add_argument(
        "--seed-spread",
        type=Path,
        default=None,
        help="a report.json of benchmarks/jax_ppo.py report holding these settings trained with several "
        "seeds: the card states their spread (default: none)",
    )
    parser.add_argument(
        "--baselines",
        default=BASELINE,
        help=f"the controllers evaluated beside it, comma-separated; '' for none (default: {BASELINE})",
    )
    args = parser.parse_args(argv)
    settings = {f.name: getattr(args, f.name) for f in dataclasses.fields(PPOConfig)}
    try:
        config = PPOConfig(**{**settings, "hidden": tuple(args.hidden)})
        spread = None if args.seed_spread is None else seed_spread(config, args.seed_spread)
        out = (
            args.out
            if args.out is not None
            else str(next_run_dir(DEFAULT_LOG_FOLDER, "ppo_jax", config.env_id))
        )
        check_output_dir(out, args.force, kind="jax-ppo model")
    except (ValueError, FileExistsError) as exc:
        parser.error(str(exc))
    command = shlex.join(["python", "-m", "subenv_agents.jax_ppo", *(sys.argv[1:] if argv is None else argv)])
    baselines = [name for name in args.baselines.split(",") if name]
    train_model(config, out, command, args.eval_episodes, baselines, overwrite=args.force, spread=spread)
    print(f"wrote {out}")
    return 0


def train_model(
    config: PPOConfig,
    out: str | Path,
    command: str,
    eval_episodes: int = 100,
    baselines: Sequence[str] = (BASELINE,),
    *,
    overwrite: bool = False,
    say: Callable[[str], None] | None = None,
    spread: str | None = None,
) -> dict[str, Any]:
    """Train ``config``, evaluate the final policy (``eval_episodes`` per scenario of the default suite,
    next to ``baselines``; none for 0) and write the model folder ``out`` (:func:`save`, with
    ``evaluation.json`` and ``MODEL_CARD.md``, which ends with ``spread``: :func:`seed_spread`'s section);
    returns the training's record (``train.json``).

    The record holds the wall time and the process's CPU time of the training, compilation included,
    the load averages before and after it (the machine may be shared), and what the policy did per
    update (reward per step, episodes ended, terminated and won)."""
    say = say or functools.partial(print, flush=True)
    total = config.num_updates * config.num_envs * config.num_steps
    say(
        f"PPO on {config.env_id} ({jax.devices()[0].platform}): {config.num_updates} updates of "
        f"{config.num_envs} envs x {config.num_steps} steps = {total:,} env-steps"
    )
    load_before, cpu = os.getloadavg(), time.process_time()
    start = time.perf_counter()
    every = max(1, config.num_updates // 20)

    def progress(index: Any, metrics: Metrics) -> None:
        k = int(index) + 1
        if k % every == 0 or k == config.num_updates:
            say(
                f"  update {k}/{config.num_updates}: {k * config.num_envs * config.num_steps:,} env-steps, "
                f"{time.perf_counter() - start:.0f} s; reward/step {float(metrics.reward):.3f}, "
                f"episodes ended {int(metrics.episodes)} ({int(metrics.terminated)} terminated, "
                f"{int(metrics.won)} won)"
            )

    train, _ = make_train(config, progress)
    state, metrics = jax.block_until_ready(jax.jit(train)(jax.random.key(config.seed)))
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    record = {
        "env_steps": total,
        "wall_time_s": round(wall, 1),
        "cpu_time_s": round(cpu, 1),
        "env_steps_per_s": round(total / wall),
        "load_average": {
            "before": [round(v, 2) for v in load_before],
            "after": [round(v, 2) for v in os.getloadavg()],
        },
        "device": str(jax.devices()[0]),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores",
        "versions": {"jax": jax.__version__, "optax": optax.__version__, "python": platform.python_version()},
        "command": command,
        "final_reward_per_step": float(metrics.reward[-1]),
        "per_update": {name: np.asarray(value).tolist() for name, value in metrics._asdict().items()},
    }
    say(f"trained: {total:,} env-steps in {wall:.0f} s ({total / wall:,.0f}/s, compile included)")
    texts = {}
    if eval_episodes > 0:
        name = Path(out).name
        evaluation = evaluation_of(
            JaxPPOController.of(config, state.network, state.obs_stats, name), eval_episodes, baselines
        )
        texts = {
            "evaluation.json": json.dumps(evaluation, indent=2) + "\n",
            "MODEL_CARD.md": model_card(name, config, record, evaluation) + (spread or ""),
        }
        say(score_table(evaluation["scores"]))
    save(out, config, state.network, state.obs_stats, record, overwrite=overwrite, texts=texts)
    return record


def evaluation_of(
    controller: JaxPPOController, episodes: int, baselines: Sequence[str] = (BASELINE,)
) -> dict[str, Any]:
    """The controller and ``baselines`` on the default suite, ``episodes`` each (the harness of
    ``subenv evaluate``, seeds 10000 + i): ``{"episodes", "suite", "scores", "target_met", "target"}``,
    the success and plane RMS (:func:`~subenv_agents.records.evaluation_record`), the benchmark-v1 scores
    (:func:`~subenv_agents.records.score_record`) and the reversal target against ``reversal_aware`` (None
    without it)."""
    from subenv.evaluation import evaluate, make_controller

    results = evaluate(
        [controller, *(make_controller(name) for name in baselines)],
        DEFAULT_SUITE,
        episodes=episodes,
        progress=False,
        keep_trajectories=0,
    )
    suite = evaluation_record(results)
    met, sentence = target_met(suite, controller.name) if BASELINE in baselines else (None, None)
    return {
        "episodes": episodes,
        "suite": suite,
        "scores": score_record(results),
        "target_met": met,
        "target": sentence,
    }


def model_card(name: str, config: PPOConfig, record: Mapping[str, Any], evaluation: Mapping[str, Any]) -> str:
    """The model's card: how it was trained, on what, and how it did (every number from the run)."""
    kwargs = config.env_kwargs
    rewards = (
        "rewards scaled by the running deviation of the discounted return"
        if config.normalize_reward
        else "rewards as the environment gives them"
    )
    policy = (
        f"hidden layers {list(config.hidden)} (tanh)"
        if not config.memory
        else f"a GRU of {config.memory} units over an embedding of the observation, shared by the actor and "
        f"the critic, each an MLP of hidden layers {list(config.hidden)} (tanh) on the observation and the "
        "GRU's state"
    )
    observed = (
        "what the Gymnasium environment observes (no extra features)"
        if not config.depth_integral_s
        else "what the Gymnasium environment observes and the leaky integral of its depth error "
        f"(time constant {config.depth_integral_s:g} s)"
    )
    episodes = (
        "reset from at random"
        if config.curriculum == "uniform"
        else "reset from by the analysis's curriculum (`subenv_agents.difficulty`): the winnable ones only, "
        f"{config.curriculum_share:g} of the resets in proportion to their hardness (trim load and nearness "
        "to u_cr), the rest uniformly"
    )
    others = ", ".join(f"`{c}`" for c in evaluation["scores"] if c != name) or "no baseline"
    target = (
        ""
        if evaluation.get("target_met") is None
        else f"""
**Target** (at least the baseline's success with less plane effort on {", ".join(REVERSAL_SCENARIOS)}):
**{"met" if evaluation["target_met"] else "not met"}**. {evaluation["target"]}.
"""
    )
    return f"""# Model card: `{name}` (PPO in one JAX program on `{config.env_id}`)

A PPO agent trained by `subenv_agents.jax_ppo` (PureJaxRL's recipe: the environments, the rollouts and
the updates in one `jax.jit`) on the functional JAX environment of `{config.env_id}`
(`subenv.jax.make`), with the environment arguments `{dict(kwargs)}`. It observes {observed}; its
observation statistics are saved with it. Load it with `subenv_agents.jax_ppo.JaxPPOController(folder)`;
the shipped one is the controller `ppo_jax` of `subenv evaluate`.

## Training

- Command: `{record["command"]}`
- {record["env_steps"]:,} env-steps: {config.num_updates} updates of {config.num_envs} environments x \
{config.num_steps} steps, {config.update_epochs} epochs of {config.num_minibatches} minibatches each, \
Adam at {config.lr:g}{" annealed to 0" if config.anneal_lr else ""}, gamma {config.gamma}, \
GAE lambda {config.gae_lambda}, clip {config.clip_eps}, entropy coefficient {config.ent_coef}, \
{policy}; {rewards}.
- Episodes: a table of {config.episodes} episodes of the scenario, those of the seeds {config.seed} to \
{config.seed + config.episodes - 1} (`reset(seed=...)` of the Gymnasium environment), {episodes}.
- Wall time: {record["wall_time_s"]} s on {record["machine"]} ({record["device"]}), compilation included: \
{record["env_steps_per_s"]:,} env-steps/s{_load_note(record)}.
- Versions: {", ".join(f"{k} {v}" for k, v in record["versions"].items())}.

## Evaluation

The harness of `subenv evaluate` on the `{DEFAULT_SUITE}` suite, {evaluation["episodes"]} episodes per
scenario (seeds {DEFAULT_SEED} + i), next to {others} on the same episodes. Wins over the scored
(winnable) episodes and the benchmark-v1 score
(S = 1000 (W - 1 + Q) / N, `subenv.evaluation.score`; 95% stratified bootstrap intervals):

{score_table(evaluation["scores"])}

Success over all episodes (95% Wilson intervals) and plane RMS (sqrt of the time mean of stern^2 + bow^2):

{table(evaluation["suite"], list(next(iter(evaluation["suite"].values()))))}
{target}"""


def seed_spread(config: PPOConfig, report: str | Path) -> str:
    """The card's section on what other seeds of ``config``'s settings gave: the variant of ``report``
    (the ``report.json`` of ``benchmarks/jax_ppo.py report``) trained with the same settings but the
    seed, each seed's final policy on the default suite and the Hard track. ValueError where the report
    holds no such variant, naming the report's variants."""
    path = Path(report)
    try:
        summary = json.loads(path.read_text())
        variants = summary["variants"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ValueError(
            f"seed_spread={str(path)!r} is not a report of benchmarks/jax_ppo.py: {exc}"
        ) from None
    mine = json.loads(json.dumps({**dataclasses.asdict(config), "hidden": list(config.hidden)}))
    mine.pop("seed")
    found = [(name, v) for name, v in variants.items() if v.get("settings") == mine]
    if not found:
        raise ValueError(
            f"seed_spread={str(path)!r} holds no variant with these settings but the seed: its variants are "
            f"{list(variants)}"
        )
    name, v = found[0]
    hard = v.get("hard_score") or [math.nan] * len(v["seeds"])
    rows = [
        f"| {seed}{' (this model)' if seed == config.seed else ''} | {score:.0f} | {h:.0f} | {wins} |"
        for seed, score, h, wins in zip(v["seeds"], v["score"], hard, v["ballast_wins"], strict=True)
    ]
    default_mean = f"{v['score_mean']:.0f} [{v['score_mean_ci'][0]:.0f}, {v['score_mean_ci'][1]:.0f}]"
    iqm = f"{100 * v['iqm']:.1f} [{100 * v['iqm_ci'][0]:.1f}, {100 * v['iqm_ci'][1]:.1f}]"
    hard_mean = (
        f"{v['hard_score_mean']:.0f} [{v['hard_score_mean_ci'][0]:.0f}, {v['hard_score_mean_ci'][1]:.0f}]"
        if v.get("hard_score_mean") is not None
        else "-"
    )
    return f"""
## Seed spread

These settings trained with {v["runs"]} seeds (variant `{name}` of `benchmarks/jax_ppo.py`, its report
`{path.as_posix()}`), each final policy evaluated on the default suite ({v["episodes"]} episodes per
scenario, seeds {DEFAULT_SEED} + i) and on the Hard track (its suite's episodes): the benchmark-v1 score
pooled over each suite, and BallastOffset's wins over its winnable episodes.

| seed | default score | Hard score | BallastOffset wins |
|---|---:|---:|---:|
{chr(10).join(rows)}
| mean [95% CI] | {default_mean} | {hard_mean} | median {v["ballast_median_wins"]:.0f} |

Success over the winnable episodes of the default suite, IQM over seeds x scenarios: {iqm}
(rliable, 95% stratified bootstrap).
"""


def _load_note(record: Mapping[str, Any]) -> str:
    """The machine's load while it trained, where the record has it (a shared machine trains slower)."""
    load = record.get("load_average")
    if not load:
        return ""
    return (
        f" (load average {load['before'][0]:.1f} before, {load['after'][0]:.1f} after; "
        f"{record['cpu_time_s']:.0f} s of CPU time)"
    )


if __name__ == "__main__":
    raise SystemExit(main())
