"""PPO on subenv's functional JAX environment, the whole training in one compiled program.

PureJaxRL's recipe (Lu et al. 2022, ``purejaxrl/ppo_continuous_action.py``): the environments
(:func:`subenv.jax.make`, ``jax.vmap``-ed), the rollout, the advantages and the updates are one
``jax.jit`` of :func:`make_train`'s ``train(key)``, a ``jax.lax.scan`` over the updates. On an
accelerator that is the fast path; on a CPU it runs too (``benchmarks/jax_ppo.py``).

- The policy: a diagonal Gaussian whose mean is a tanh MLP of the normalised observation, with
  state-independent log standard deviations; the critic a second MLP (orthogonal initialisation, as
  PureJaxRL). :func:`policy_mean` is the one copy of the deterministic policy: training samples
  around it, :class:`JaxPPOController` acts with it.
- Observations are normalised by running statistics (mean and variance over everything the
  environments observed, as PureJaxRL's ``NormalizeVecObservation`` and SB3's ``VecNormalize``),
  rewards scaled by the running deviation of the discounted return; the statistics are saved with
  the network.
- A truncated episode (the scenario's duration, the time limit) bootstraps from the value of the
  observation its last step reached (gymnax 1.0's ``info["final_observation"]``: the step's own
  observation is already the next episode's), a terminated one from zero (:func:`advantages`).
- Optimisation is optax's (global-norm clipping, Adam with a linearly annealed step).

``python -m subenv_agents.jax_ppo --out DIR`` trains and writes a model folder (:func:`save`):
``network.npz``, ``config.json`` and ``train.json``, complete or absent (:mod:`subenv.atomic`).
:func:`load` checks a folder whole (a damaged or inconsistent file is refused, by its name and the
field).
:class:`JaxPPOController` loads one as a controller of :mod:`subenv.evaluation`; the shipped one,
``subenv_agents/models/ppo_jax/``, is the ``ppo_jax`` entry point (``subenv evaluate``).

Needs the ``jax-rl`` extra (jax, optax).
"""

from __future__ import annotations

import argparse
import dataclasses
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
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np

import subenv.envs
from subenv import _validation as check
from subenv.atomic import atomic_output_dir, check_output_dir
from subenv.envs.config import OBSERVATION_NAMES, DivePlaneConfig
from subenv.evaluation import SingleRowMixin, check_batch
from subenv.extras import require
from subenv.vehicles import Vehicle
from subenv_agents.records import (
    BASELINE,
    REVERSAL_SCENARIOS,
    check_harness_kwargs,
    evaluation_record,
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
    """The training's settings (PureJaxRL's names, lower case)."""

    env_id: str = "subenv/SpeedTransient-v0"
    """The registered id trained on."""
    env_kwargs: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    """:class:`~subenv.envs.DivePlaneEnv`'s arguments (``control``, ``alpha``, reward weights, ...)."""
    total_timesteps: int = 20_000_000
    num_envs: int = 1024
    num_steps: int = 64
    """Steps per environment per update."""
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
    normalize_reward: bool = True
    episodes: int = 4096
    """Rows of the table of episodes the environments reset from (:func:`subenv.jax.make`)."""
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
        for name in ("lr", "max_grad_norm"):
            check.positive(name, getattr(self, name))
        for name in ("gamma", "gae_lambda"):
            value = getattr(self, name)
            check.require(
                name, value, isinstance(value, (int, float)) and 0.0 <= value <= 1.0, "a number in [0, 1]"
            )
        for name in ("clip_eps", "ent_coef", "vf_coef"):
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
        batch = self.num_envs * self.num_steps
        check.require(
            "num_minibatches",
            self.num_minibatches,
            batch % self.num_minibatches == 0,
            f"a divisor of num_envs * num_steps = {batch}",
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
    def n_actions(self) -> int:
        """Components of the environment's action."""
        return DivePlaneConfig(**{**gym.spec(self.env_id).kwargs, **self.env_kwargs}).n_actions

    @property
    def num_updates(self) -> int:
        """Updates of the training (its env-steps: ``num_updates * num_envs * num_steps``)."""
        return self.total_timesteps // (self.num_envs * self.num_steps)


# --- the network -----------------------------------------------------------------------------------
def init_network(key: jax.Array, obs_dim: int, act_dim: int, hidden: Sequence[int]) -> dict[str, Any]:
    """The actor's and the critic's layers (orthogonal weights, zero biases) and the log standard
    deviations."""

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
    return {
        "actor": mlp(key_actor, (obs_dim, *hidden, act_dim), 0.01),
        "critic": mlp(key_critic, (obs_dim, *hidden, 1), 1.0),
        "log_std": jnp.zeros(act_dim, jnp.float32),
    }


def _mlp(layers: Sequence[Mapping[str, jax.Array]], x: jax.Array) -> jax.Array:
    for layer in layers[:-1]:
        x = jnp.tanh(x @ layer["w"] + layer["b"])
    return x @ layers[-1]["w"] + layers[-1]["b"]


def policy_mean(network: Mapping[str, Any], obs: jax.Array, stats: RunningStats) -> jax.Array:
    """The policy's mean action for raw observations ``obs`` (..., obs_dim): the deterministic policy."""
    return _mlp(network["actor"], normalize(stats, obs))


def _value(network: Mapping[str, Any], obs_normalized: jax.Array) -> jax.Array:
    return _mlp(network["critic"], obs_normalized)[..., 0]


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

    obs: jax.Array  # normalised
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
    """Per update: the mean reward per env-step, episodes ended, episodes terminated (failed)."""

    reward: jax.Array
    episodes: jax.Array
    terminated: jax.Array


class TrainState(NamedTuple):
    network: Any
    opt_state: Any
    obs_stats: RunningStats
    return_stats: RunningStats
    returns: jax.Array
    env_state: Any
    obs: jax.Array  # raw
    key: jax.Array


def make_train(
    config: PPOConfig, progress: Callable[[int, Metrics], None] | None = None
) -> tuple[Callable[[jax.Array], tuple[TrainState, Metrics]], sj.DivePlaneJaxEnv]:
    """``train(key) -> (final state, metrics per update)``, to be ``jax.jit``-ed whole, and the
    environment it trains on. ``progress(update, metrics)`` is called from inside the program after
    every update (``jax.debug.callback``), if given."""
    env, params = sj.make(config.env_id, episodes=config.episodes, seed=config.seed, **config.env_kwargs)
    n, steps = config.num_envs, config.num_steps
    obs_dim, act_dim = env.observation_space().shape[0], env.num_actions
    updates = config.num_updates
    lr: Any = (
        optax.linear_schedule(config.lr, 0.0, updates * config.update_epochs * config.num_minibatches)
        if config.anneal_lr
        else config.lr
    )
    optimizer = optax.chain(optax.clip_by_global_norm(config.max_grad_norm), optax.adam(lr, eps=1e-5))
    step_envs = jax.vmap(env.step, in_axes=(0, 0, 0, None))
    gamma, lam = config.gamma, config.gae_lambda

    def env_step(state: TrainState, _: None) -> tuple[TrainState, Rollout]:
        key, key_action, key_env = jax.random.split(state.key, 3)
        obs = normalize(state.obs_stats, state.obs)
        mean, value = _mlp(state.network["actor"], obs), _value(state.network, obs)
        log_std = state.network["log_std"]
        action = mean + jnp.exp(log_std) * jax.random.normal(key_action, mean.shape)
        next_obs, env_state, reward, terminated, truncated, info = step_envs(
            jax.random.split(key_env, n), state.env_state, action, params
        )
        done = terminated | truncated
        obs_stats = state.obs_stats.update(next_obs)
        # (normalised as the next step's observation is: its value is the next step's where no episode ended)
        final_value = _value(state.network, normalize(obs_stats, info["final_observation"]))
        returns = state.returns * gamma + reward
        return_stats = (
            state.return_stats.update(returns[:, None]) if config.normalize_reward else state.return_stats
        )
        scaled = reward / jnp.sqrt(return_stats.var[0] + 1e-8) if config.normalize_reward else reward
        rollout = Rollout(
            obs,
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
            key=key,
            return_stats=return_stats,
            returns=jnp.where(done, 0.0, returns),
            obs_stats=obs_stats,
        )
        return state, (rollout, reward)

    def loss(network: Any, batch: Rollout, adv: jax.Array, target: jax.Array) -> jax.Array:
        mean, value = _mlp(network["actor"], batch.obs), _value(network, batch.obs)
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

    def update(state: TrainState, index: jax.Array) -> tuple[TrainState, Metrics]:
        state, (rollout, rewards) = jax.lax.scan(env_step, state, None, steps)
        last_value = _value(state.network, normalize(state.obs_stats, state.obs))
        adv, target = advantages(rollout, last_value, gamma, lam)
        batch = jax.tree_util.tree_map(lambda x: x.reshape((n * steps, *x.shape[2:])), (rollout, adv, target))

        def epoch(carry: tuple[Any, Any, jax.Array], _: None) -> tuple[tuple[Any, Any, jax.Array], None]:
            network, opt_state, key = carry
            key, key_perm = jax.random.split(key)
            order = jax.random.permutation(key_perm, n * steps)
            minibatches = jax.tree_util.tree_map(
                lambda x: x[order].reshape((config.num_minibatches, -1, *x.shape[1:])), batch
            )

            def minibatch(
                carry: tuple[Any, Any], mb: tuple[Rollout, jax.Array, jax.Array]
            ) -> tuple[Any, None]:
                network, opt_state = carry
                grads = jax.grad(loss)(network, *mb)
                changes, opt_state = optimizer.update(grads, opt_state, network)
                return (optax.apply_updates(network, changes), opt_state), None

            (network, opt_state), _ = jax.lax.scan(minibatch, (network, opt_state), minibatches)
            return (network, opt_state, key), None

        key, key_epochs = jax.random.split(state.key)
        (network, opt_state, _), _ = jax.lax.scan(
            epoch, (state.network, state.opt_state, key_epochs), None, config.update_epochs
        )
        state = state._replace(network=network, opt_state=opt_state, key=key)
        metrics = Metrics(rewards.mean(), rollout.done.sum(), rollout.terminated.sum())
        if progress is not None:
            jax.debug.callback(progress, index, metrics, ordered=True)
        return state, metrics

    def train(key: jax.Array) -> tuple[TrainState, Metrics]:
        key, key_network, key_reset = jax.random.split(key, 3)
        network = init_network(key_network, obs_dim, act_dim, config.hidden)
        obs, env_state = jax.vmap(env.reset, in_axes=(0, None))(jax.random.split(key_reset, n), params)
        state = TrainState(
            network,
            optimizer.init(network),
            RunningStats.empty((obs_dim,)).update(obs),
            RunningStats.empty((1,)),
            jnp.zeros(n),
            env_state,
            obs,
            key,
        )
        return jax.lax.scan(update, state, jnp.arange(updates))

    return train, env


# --- the model folder ------------------------------------------------------------------------------
_FILES = ("network.npz", "config.json", "train.json")


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
    their path in the network, ``obs_mean``/``obs_var``), the settings (``config.json``), the
    training's record (``train.json``) and ``texts`` (file name: text). The folder is complete or
    absent at every instant."""
    arrays = {"obs_mean": np.asarray(obs_stats.mean), "obs_var": np.asarray(obs_stats.var)}
    for keys, leaf in jax.tree_util.tree_leaves_with_path(network):
        arrays["/".join(str(getattr(k, "key", getattr(k, "idx", k))) for k in keys)] = np.asarray(leaf)
    settings = {**dataclasses.asdict(config), "hidden": list(config.hidden)}
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
    JSON, not NumPy's archive), a setting :class:`PPOConfig` refuses, arrays missing or unknown to the
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
    fields."""
    settings = _read_json_object(file)
    known = [field.name for field in dataclasses.fields(PPOConfig)]
    unknown = sorted(set(settings) - set(known))
    if unknown:
        raise ValueError(f"{file} is invalid: unknown settings {unknown} (known: {known})")
    if isinstance(settings.get("hidden"), list):
        settings["hidden"] = tuple(settings["hidden"])
    try:
        return PPOConfig(**settings)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{file} is invalid: {exc}") from None


def _network_of(
    arrays: Mapping[str, np.ndarray], config: PPOConfig, file: Path
) -> tuple[dict[str, Any], RunningStats]:
    """The network and the observation statistics of ``network.npz``'s arrays, checked against ``config``."""
    obs_dim, act_dim = len(OBSERVATION_NAMES), config.n_actions
    described = (
        f"the network config.json describes: hidden={list(config.hidden)}, {act_dim} action components"
    )
    layers = {
        "actor": (obs_dim, *config.hidden, act_dim),
        "critic": (obs_dim, *config.hidden, 1),
    }
    shapes: dict[str, tuple[int, ...]] = {
        "obs_mean": (obs_dim,),
        "obs_var": (obs_dim,),
        "log_std": (act_dim,),
    }
    for part, sizes in layers.items():
        for i, (n_in, n_out) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
            shapes[f"{part}/{i}/w"], shapes[f"{part}/{i}/b"] = (n_in, n_out), (n_out,)
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
    for part, sizes in layers.items():
        bound = _OBS_CLIP  # |input| of the first layer: the normalised observation, clipped
        for i in range(len(sizes) - 1):
            w, b = checked[f"{part}/{i}/w"].astype(np.float64), checked[f"{part}/{i}/b"].astype(np.float64)
            largest = float(np.max(bound * np.abs(w).sum(axis=0) + np.abs(b)))
            if not largest < _FLOAT32_MAX:
                raise ValueError(
                    f"{file}: {part}/{i}/w and {part}/{i}/b are invalid: they reach {largest:.3g} for some "
                    f"observation, beyond float32's range: must keep |sum| below {_FLOAT32_MAX:.3g}"
                )
            bound = 1.0  # (tanh's outputs)
    network: dict[str, Any] = {
        part: [
            {"w": jnp.asarray(checked[f"{part}/{i}/w"]), "b": jnp.asarray(checked[f"{part}/{i}/b"])}
            for i in range(len(sizes) - 1)
        ]
        for part, sizes in layers.items()
    }
    network["log_std"] = jnp.asarray(checked["log_std"])
    stats = RunningStats(jnp.asarray(checked["obs_mean"]), jnp.asarray(checked["obs_var"]), jnp.asarray(0.0))
    return network, stats


class JaxPPOController(SingleRowMixin):
    """A model folder of :func:`save` as a controller of :mod:`subenv.evaluation`: the policy's mean
    action (:func:`policy_mean`, the function training sampled around), clipped to [-1, 1].

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
        self._act = jax.jit(policy_mean)
        self._episodes = 0

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Start ``len(infos)`` episodes (the policy keeps no state between steps)."""
        self._episodes = len(infos)

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The policy's mean actions of a batch of observations, clipped to [-1, 1] (float32)."""
        obs = check_batch(observations, self._episodes)
        mean = np.asarray(self._act(self._network, jnp.asarray(obs, dtype=jnp.float32), self._stats))
        return np.clip(mean, -1.0, 1.0).astype(np.float32)


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
    parser.add_argument("--out", required=True, help="the model folder to write (complete or absent)")
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
        default={},
        help='the environment\'s arguments as JSON, e.g. \'{"control": "independent"}\'',
    )
    parser.add_argument(
        "--eval-episodes",
        type=int,
        default=100,
        help="episodes per scenario of the evaluation written with the model (evaluation.json, "
        "MODEL_CARD.md), next to the reversal_aware baseline; 0: none (default: 100)",
    )
    args = parser.parse_args(argv)
    settings = {f.name: getattr(args, f.name) for f in dataclasses.fields(PPOConfig)}
    try:
        config = PPOConfig(**{**settings, "hidden": tuple(args.hidden)})
        check_output_dir(args.out, args.force, kind="jax-ppo model")
    except ValueError as exc:
        parser.error(str(exc))
    total = config.num_updates * config.num_envs * config.num_steps
    print(
        f"PPO on {config.env_id} ({jax.devices()[0].platform}): {config.num_updates} updates of "
        f"{config.num_envs} envs x {config.num_steps} steps = {total:,} env-steps",
        flush=True,
    )
    start = time.perf_counter()
    every = max(1, config.num_updates // 20)

    def progress(index: Any, metrics: Metrics) -> None:
        k = int(index) + 1
        if k % every == 0 or k == config.num_updates:
            print(
                f"  update {k}/{config.num_updates}: {k * config.num_envs * config.num_steps:,} env-steps, "
                f"{time.perf_counter() - start:.0f} s; reward/step {float(metrics.reward):.3f}, "
                f"episodes ended {int(metrics.episodes)} ({int(metrics.terminated)} terminated)",
                flush=True,
            )

    train, _ = make_train(config, progress)
    state, metrics = jax.block_until_ready(jax.jit(train)(jax.random.key(config.seed)))
    wall = time.perf_counter() - start
    record = {
        "env_steps": total,
        "wall_time_s": round(wall, 1),
        "env_steps_per_s": round(total / wall),
        "device": str(jax.devices()[0]),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores",
        "versions": {"jax": jax.__version__, "optax": optax.__version__, "python": platform.python_version()},
        "command": shlex.join(
            ["python", "-m", "subenv_agents.jax_ppo", *(sys.argv[1:] if argv is None else argv)]
        ),
        "final_reward_per_step": float(metrics.reward[-1]),
    }
    print(
        f"trained: {total:,} env-steps in {wall:.0f} s ({total / wall:,.0f}/s, compile included)", flush=True
    )
    texts = {}
    if args.eval_episodes > 0:
        name = Path(args.out).name
        evaluation = evaluation_of(
            JaxPPOController.of(config, state.network, state.obs_stats, name), args.eval_episodes
        )
        texts = {
            "evaluation.json": json.dumps(evaluation, indent=2) + "\n",
            "MODEL_CARD.md": model_card(name, config, record, evaluation),
        }
        print(table(evaluation["suite"], REVERSAL_SCENARIOS))
    save(args.out, config, state.network, state.obs_stats, record, overwrite=args.force, texts=texts)
    print(f"wrote {args.out}")
    return 0


def evaluation_of(controller: JaxPPOController, episodes: int) -> dict[str, Any]:
    """The controller and the ``reversal_aware`` baseline on the reversal scenarios, ``episodes`` each
    (the harness of ``subenv evaluate``, seeds 10000 + i): ``{"episodes", "suite", "target_met",
    "target"}``."""
    from subenv.evaluation import evaluate, make_controller

    results = evaluate(
        [controller, make_controller(BASELINE)], list(REVERSAL_SCENARIOS), episodes=episodes, progress=False
    )
    suite = evaluation_record(results)
    met, sentence = target_met(suite, controller.name)
    return {"episodes": episodes, "suite": suite, "target_met": met, "target": sentence}


def model_card(name: str, config: PPOConfig, record: Mapping[str, Any], evaluation: Mapping[str, Any]) -> str:
    """The model's card: how it was trained, on what, and how it did (every number from the run)."""
    from subenv.evaluation import DEFAULT_SEED

    kwargs = config.env_kwargs
    rewards = (
        "rewards scaled by the running deviation of the discounted return"
        if config.normalize_reward
        else "rewards as the environment gives them"
    )
    return f"""# Model card: `{name}` (PPO in one JAX program on `{config.env_id}`)

A PPO agent trained by `subenv_agents.jax_ppo` (PureJaxRL's recipe: the environments, the rollouts and
the updates in one `jax.jit`) on the functional JAX environment of `{config.env_id}`
(`subenv.jax.make`), with the environment arguments `{dict(kwargs)}`. It observes what the
Gymnasium environment observes (no extra features); its observation statistics are saved with it. Load it with
`subenv_agents.jax_ppo.JaxPPOController(folder)`; the shipped one is the controller `ppo_jax` of
`subenv evaluate`.

## Training

- Command: `{record["command"]}`
- {record["env_steps"]:,} env-steps: {config.num_updates} updates of {config.num_envs} environments x \
{config.num_steps} steps, {config.update_epochs} epochs of {config.num_minibatches} minibatches each, \
Adam at {config.lr:g}{" annealed to 0" if config.anneal_lr else ""}, gamma {config.gamma}, \
GAE lambda {config.gae_lambda}, clip {config.clip_eps}, entropy coefficient {config.ent_coef}, \
hidden layers {list(config.hidden)} (tanh); {rewards}.
- Episodes: a table of {config.episodes} episodes of the scenario, those of the seeds {config.seed} to \
{config.seed + config.episodes - 1} (`reset(seed=...)` of the Gymnasium environment), reset from at random.
- Wall time: {record["wall_time_s"]} s on {record["machine"]} ({record["device"]}), compilation included: \
{record["env_steps_per_s"]:,} env-steps/s.
- Versions: {", ".join(f"{k} {v}" for k, v in record["versions"].items())}.

## Evaluation

The harness of `subenv evaluate`, {evaluation["episodes"]} episodes per scenario (seeds {DEFAULT_SEED} + i),
next to the `{BASELINE}` baseline on the same episodes. Success: not terminated and |depth error| <= 0.5 m
over the final 60 s (95% Wilson intervals). Plane RMS: sqrt of the time mean of stern^2 + bow^2.

{table(evaluation["suite"], REVERSAL_SCENARIOS)}

**Target** (at least the baseline's success with less plane effort on {", ".join(REVERSAL_SCENARIOS)}):
**{"met" if evaluation["target_met"] else "not met"}**. {evaluation["target"]}.
"""


if __name__ == "__main__":
    raise SystemExit(main())
