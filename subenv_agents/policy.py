"""Trained agents: a model and its normalisation statistics loaded together, acting in NumPy.

:func:`load_agent` takes a run folder (what ``python -m subenv_agents.train`` writes, or a shipped
model in ``subenv_agents/models/``) or a model file, and returns a :class:`TrainedAgent` that holds the
Stable-Baselines3 model, the ``VecNormalize`` statistics it was trained with and its config.
``agent.predict(obs)`` normalises the raw observation and returns the deterministic action.

The deterministic actor is evaluated with NumPy (:class:`NumpyActor`, its weights copied from
the torch modules once): one episode step then costs a few microseconds instead of the ~100 us
of ``model.predict``, which is what lets the evaluation harness run RL agents next to the
classical controllers at the same speed. ``tests/agents`` checks it against ``model.predict``.
"""

from __future__ import annotations

import io
import math
import pickle
import re
import uuid
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
from gymnasium import spaces

from subenv.evaluation.results import atomic_write_bytes
from subenv_agents.config import AgentConfig, load_config, read_yaml_file

__all__ = [
    "CHECKPOINT_DIR",
    "CONFIG_FILE",
    "MODEL_FILE",
    "RUN_ID_ATTRIBUTE",
    "SELECTED_DIR",
    "VECNORMALIZE_FILE",
    "NumpyActor",
    "TrainedAgent",
    "load_agent",
    "mark_run",
    "model_folder",
    "save_model",
    "save_statistics",
    "statistics_file",
    "training_run",
]

MODEL_FILE: Final = "model.zip"
VECNORMALIZE_FILE: Final = "vecnormalize.pkl"
CONFIG_FILE: Final = "config.yml"
"""The resolved hyperparameters of the run (one entry, keyed by its env id), with ``algo``."""
CHECKPOINT_DIR: Final = "checkpoints"
"""A run's sub-folder of SB3 checkpoints, ``rl_model_<N>_steps.zip``."""
SELECTED_DIR: Final = "selected"
"""A run's sub-folder with the policy that did best on validation episodes
(:mod:`subenv_agents.selection`)."""
RUN_ID_ATTRIBUTE: Final = "subenv_run_id"
"""The attribute, saved with a run's models and statistics, that ties them together (:func:`mark_run`)."""
_CHECKPOINT = re.compile(r"^(?P<prefix>.+)_(?P<steps>\d+)_steps\.zip$")


class NumpyActor:
    """The deterministic action of an SB3 PPO, SAC or TD3 MLP policy, computed with NumPy.

    The layers are read from the policy: PPO ``mlp_extractor.policy_net`` then ``action_net``
    (the Gaussian mean, clipped to the action bounds as ``predict`` does); SAC ``latent_pi`` then
    ``mu`` then tanh; TD3 ``actor.mu`` (which ends in tanh). Actions are then unscaled from
    [-1, 1] to the action space for the squashing policies, as ``predict`` does.
    """

    def __init__(self, model: Any) -> None:
        from torch import nn

        policy = model.policy
        extractors = [getattr(policy, n, None) for n in ("features_extractor", "pi_features_extractor")]
        if hasattr(policy, "actor"):
            extractors.append(policy.actor.features_extractor)
        for extractor in extractors:
            if extractor is not None and type(extractor).__name__ != "FlattenExtractor":
                raise NotImplementedError(
                    f"NumpyActor supports MLP policies only, not {type(extractor).__name__}"
                )
        if hasattr(policy, "mlp_extractor"):  # PPO (ActorCriticPolicy)
            modules = [*policy.mlp_extractor.policy_net, policy.action_net]
            self.squashed = False
        elif hasattr(policy.actor, "latent_pi"):  # SAC
            modules = [*policy.actor.latent_pi, policy.actor.mu, nn.Tanh()]
            self.squashed = True
        else:  # TD3
            modules = [*policy.actor.mu]
            self.squashed = True
        self.layers: list[tuple[str, np.ndarray | None, np.ndarray | None]] = []
        for module in modules:
            if isinstance(module, nn.Linear):
                self.layers.append(
                    (
                        "linear",
                        module.weight.detach().cpu().numpy().T.astype(np.float64),
                        module.bias.detach().cpu().numpy().astype(np.float64),
                    )
                )
            elif isinstance(module, (nn.Tanh, nn.ReLU, nn.ELU, nn.LeakyReLU)):
                slope = getattr(module, "negative_slope", getattr(module, "alpha", None))
                self.layers.append(
                    (type(module).__name__.lower(), None if slope is None else np.float64(slope), None)
                )
            elif not isinstance(module, (nn.Identity, nn.Flatten)):
                raise NotImplementedError(f"NumpyActor does not know the layer {module!r}")
        space = model.action_space
        self.low = space.low.astype(np.float64)
        self.high = space.high.astype(np.float64)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """Actions (float32) for a batch of normalised observations, shape (n, obs_dim)."""
        x = np.asarray(obs, dtype=np.float64)
        for kind, a, b in self.layers:
            if kind == "linear":
                x = x @ a + b  # type: ignore[operator]
            elif kind == "tanh":
                x = np.tanh(x)
            elif kind == "relu":
                x = np.maximum(x, 0.0)
            elif kind == "elu":
                x = np.where(x > 0, x, a * np.expm1(np.minimum(x, 0.0)))  # type: ignore[operator]
            else:  # leakyrelu
                x = np.where(x > 0, x, a * x)  # type: ignore[operator]
        if self.squashed:
            x = self.low + 0.5 * (x + 1.0) * (self.high - self.low)
        return np.clip(x, self.low, self.high).astype(np.float32)


@dataclass
class TrainedAgent:
    """A trained model with the normalisation statistics and config it was trained with.

    Attributes
    ----------
    path : Path
        The model file.
    model : stable_baselines3.common.base_class.BaseAlgorithm
    config : AgentConfig
    obs_mean, obs_var : numpy.ndarray or None
        ``VecNormalize``'s running statistics (None: trained without observation normalisation).
    clip_obs, epsilon : float
        ``VecNormalize``'s clipping and epsilon.
    """

    path: Path
    model: Any
    config: AgentConfig
    obs_mean: np.ndarray | None
    obs_var: np.ndarray | None
    clip_obs: float
    epsilon: float

    def __post_init__(self) -> None:
        self.actor = NumpyActor(self.model)

    @classmethod
    def from_model(cls, path: Path, model: Any, config: AgentConfig, stats: Any = None) -> TrainedAgent:
        """The agent of ``model`` with the observation statistics of ``stats`` (a ``VecNormalize``; None:
        trained without observation normalisation)."""
        if stats is None:
            return cls(path, model, config, None, None, 10.0, 1e-8)
        return cls(
            path,
            model,
            config,
            np.asarray(stats.obs_rms.mean, dtype=float),
            np.asarray(stats.obs_rms.var, dtype=float),
            float(stats.clip_obs),
            float(stats.epsilon),
        )

    @property
    def observation_space(self) -> spaces.Box:
        """The observations the model takes (the depth-error integral appended, if it observes one)."""
        return self.model.observation_space  # type: ignore[no-any-return]

    @property
    def action_space(self) -> spaces.Box:
        """The actions the model gives: the environment's normalised plane commands."""
        return self.model.action_space  # type: ignore[no-any-return]

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        """``VecNormalize.normalize_obs`` with the stored statistics."""
        obs = np.asarray(obs, dtype=np.float64)
        if self.obs_mean is None or self.obs_var is None:
            return obs
        return np.clip(
            (obs - self.obs_mean) / np.sqrt(self.obs_var + self.epsilon), -self.clip_obs, self.clip_obs
        )

    def predict(self, obs: np.ndarray) -> np.ndarray:
        """The deterministic action for an observation (shape (obs_dim,)) or a batch (n, obs_dim), as the
        model observes it: the environment's, with the depth-error integral appended if the agent
        has one (:class:`subenv_agents.controller.AgentController` appends it for you)."""
        obs = np.asarray(obs)
        single = obs.ndim == 1
        if obs.shape[-1:] != self.observation_space.shape:
            raise ValueError(
                f"observation has shape {obs.shape}: the agent {str(self.path)!r} was trained on "
                f"observations of shape {self.observation_space.shape}"
            )
        action = self.actor(self.normalize(obs.reshape(1, -1) if single else obs))
        return action[0] if single else action

    def make_env(self, **overrides: Any) -> Any:
        """The environment the agent was trained on (``gym.make`` of its id and ``env_kwargs``, with
        ``overrides`` such as ``render_mode``), its observations as the agent takes them (the
        depth-error integral appended where the agent observes it): ``agent.predict(obs)`` acts on them.
        """
        import gymnasium as gym

        import subenv  # noqa: F401  (registers the ids)

        env = gym.make(self.config.env_id, **{**self.config.env_kwargs, **overrides})
        if self.config.depth_integral is None:
            return env
        from subenv_agents.features import DepthIntegralEnv

        return DepthIntegralEnv(env, self.config.depth_integral, env.unwrapped.config.dt)

    @property
    def env_observation_space(self) -> spaces.Box:
        """The environment's observation space the agent was trained on (without the appended
        depth-error integral, if it has one)."""
        space = self.observation_space
        if self.config.depth_integral is None:
            return space
        return spaces.Box(space.low[:-1], space.high[:-1], dtype=space.dtype)  # type: ignore[arg-type]

    def check_spaces(self, env: Any, with_features: bool = False) -> None:
        """Raise ValueError if ``env``'s observation or action space is not the one the agent was trained on.

        ``env`` is a plain environment, or with ``with_features`` one that appends the agent's
        features (the depth-error integral) itself, as the training environments do.
        """
        expected = self.observation_space if with_features else self.env_observation_space
        for what, ours, theirs in (
            ("observation", expected, env.observation_space),
            ("action", self.action_space, env.action_space),
        ):
            same = (
                isinstance(theirs, spaces.Box)
                and theirs.shape == ours.shape
                and np.allclose(theirs.low, ours.low)
                and np.allclose(theirs.high, ours.high)
            )
            if not same:
                raise ValueError(
                    f"the agent {str(self.path)!r} was trained on the {what} space {ours} "
                    f"({self.config.env_id}, env_kwargs={self.config.env_kwargs}); this environment has "
                    f"{theirs}"
                )


def load_agent(path: str | Path, env: Any = None, device: str = "cpu") -> TrainedAgent:
    """Load a trained agent with its normalisation statistics and config, in one call.

    Parameters
    ----------
    path : path
        A run folder or shipped model folder (with ``model.zip``, ``vecnormalize.pkl``,
        ``config.yml``), or a model file in one: ``model.zip``, ``best_model.zip`` or a checkpoint
        ``checkpoints/rl_model_<N>_steps.zip`` (whose statistics are
        ``rl_model_vecnormalize_<N>_steps.pkl``).
    env : gymnasium.Env, optional
        Checked against the agent's spaces (ValueError naming both if they differ).
    device : str
        Torch device of the model.

    Raises
    ------
    FileNotFoundError
        No model, or no config, where ``path`` says.
    ValueError
        ``env`` has other spaces than the agent; a model, config or statistics file that cannot be read
        (the message names it); the statistics do not fit the model, or are another run's.

    Warns
    -----
    UserWarning
        The model or its statistics were saved without a run id (before :func:`mark_run`), so
        that they belong together cannot be checked.
    """
    from subenv_agents.config import algorithm_class

    path = Path(path)
    model_file = path / MODEL_FILE if path.is_dir() else path
    if not model_file.is_file():
        raise FileNotFoundError(
            f"no trained model at {str(path)!r} (expected a folder with {MODEL_FILE} or a .zip file)"
        )
    run_dir = model_folder(model_file)
    config = read_config(run_dir / CONFIG_FILE)
    try:
        model = algorithm_class(config.algo).load(model_file, device=device)
    except (
        Exception
    ) as exc:  # SB3 fails in its own ways: AssertionError, TypeError, ValueError, zipfile errors
        raise ValueError(
            f"{str(model_file)!r} cannot be loaded ({type(exc).__name__}: {_one_line(exc)}): must be a "
            f"complete {config.algo.upper()} model saved by Stable-Baselines3, the algorithm "
            f"{str(run_dir / CONFIG_FILE)!r} names"
        ) from exc
    stats_file = statistics_file(model_file, run_dir)
    stats = None
    if config.normalize is not None and config.normalize.norm_obs:
        if not stats_file.is_file():
            raise FileNotFoundError(
                f"{str(model_file)!r} was trained with normalised observations, but its "
                f"statistics {str(stats_file)!r} are missing"
            )
        stats = _read_statistics(stats_file)
        shape = np.shape(stats.obs_rms.mean)
        if shape != model.observation_space.shape:
            raise ValueError(
                f"{str(stats_file)!r} has statistics of shape {shape}; the model observes "
                f"{model.observation_space.shape}"
            )
        _check_same_run(model, model_file, stats, stats_file)
    agent = TrainedAgent.from_model(model_file, model, config, stats)
    if env is not None:
        agent.check_spaces(env)
    return agent


def _read_statistics(path: Path) -> Any:
    """The ``VecNormalize`` pickled at ``path`` (as SB3's ``VecNormalize.load`` reads it, without an env)."""
    from stable_baselines3.common.vec_env import VecNormalize

    try:
        with path.open("rb") as f:
            stats = pickle.load(f)  # (our own VecNormalize file, as SB3's VecNormalize.load does)
    except Exception as exc:  # a truncated or foreign pickle fails with any of a dozen exception types
        raise ValueError(
            f"{str(path)!r} cannot be read ({type(exc).__name__}: {_one_line(exc)}): must be "
            "VecNormalize statistics saved with the model"
        ) from exc
    if not isinstance(stats, VecNormalize):
        raise ValueError(f"{str(path)!r} holds a {type(stats).__name__}: must be VecNormalize statistics")
    _check_statistics(path, stats)
    return stats


def _check_statistics(path: Path, stats: Any) -> None:
    """Refuse statistics that would normalise to NaN or inf (a variance below 0, a NaN mean), naming the
    file and the field: they would load and fail only as a controller's non-finite action."""
    rms = vars(stats).get("obs_rms")
    fields = rms.items() if isinstance(rms, dict) else [("", rms)] if rms is not None else []
    for key, stat in fields:
        name = f"obs_rms[{key!r}]" if key else "obs_rms"
        mean, var = np.asarray(stat.mean, dtype=float), np.asarray(stat.var, dtype=float)
        if not np.all(np.isfinite(mean)):
            raise ValueError(f"{str(path)!r}: {name}.mean={mean.tolist()} is invalid: must be finite")
        if not (np.all(np.isfinite(var)) and np.all(var >= 0.0)):
            raise ValueError(f"{str(path)!r}: {name}.var={var.tolist()} is invalid: must be finite and >= 0")
    for field in ("clip_obs", "epsilon"):
        value = vars(stats).get(field)
        if value is not None and not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{str(path)!r}: {field}={value!r} is invalid: must be finite and > 0")


def mark_run(model: Any, venv: Any) -> str:
    """Give ``model`` and its ``VecNormalize`` ``venv`` a new run id, saved with each (SB3 saves a model's
    attributes, pickle the statistics'), so that :func:`load_agent` refuses another run's statistics.

    Every model and statistics file a run writes (final, checkpoints, ``best_model.zip``, ``selected/``)
    then carries it. Returns the id.
    """
    run_id = uuid.uuid4().hex
    setattr(model, RUN_ID_ATTRIBUTE, run_id)
    setattr(venv, RUN_ID_ATTRIBUTE, run_id)
    return run_id


def _check_same_run(model: Any, model_file: Path, stats: Any, stats_file: Path) -> None:
    # vars(): an unpickled VecNormalize has no wrapped env, and its __getattr__ would look there.
    ours, theirs = vars(model).get(RUN_ID_ATTRIBUTE), vars(stats).get(RUN_ID_ATTRIBUTE)
    if ours is None or theirs is None:
        warnings.warn(
            f"{str(model_file)!r} or its statistics {str(stats_file)!r} were saved without a run id "
            "(by an older version): that they belong together cannot be checked",
            UserWarning,
            stacklevel=3,
        )
    elif ours != theirs:
        raise ValueError(
            f"{str(stats_file)!r} holds the statistics of run {theirs}: must be those of the run of "
            f"{str(model_file)!r} ({ours}); a model needs the statistics it was trained with"
        )


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


def model_folder(model_file: Path) -> Path:
    """The folder with ``model_file``'s ``config.yml`` (and its statistics, but for a checkpoint's): the
    file's own folder (a run, its ``selected/`` folder, a shipped model), or the one above it for a
    checkpoint in ``<run>/checkpoints/``."""
    folder = Path(model_file).parent
    if not (folder / CONFIG_FILE).is_file() and (folder.parent / CONFIG_FILE).is_file():
        return folder.parent
    return folder


def training_run(path: str | Path) -> Path:
    """The run folder that trained the model at ``path`` (a run folder, its ``selected/`` folder, a model
    file or a checkpoint): where its ``train.json`` and curriculum state are."""
    path = Path(path)
    folder = path.parent if path.suffix == ".zip" else path
    return folder.parent if folder.name in (CHECKPOINT_DIR, SELECTED_DIR) else folder


def statistics_file(model_file: Path, run_dir: Path) -> Path:
    """Where the VecNormalize statistics of ``model_file`` are: beside a checkpoint
    ``rl_model_<N>_steps.zip``, its ``rl_model_vecnormalize_<N>_steps.pkl``; else ``run_dir``'s."""
    match = _CHECKPOINT.match(model_file.name)
    if match:
        return model_file.parent / f"{match['prefix']}_vecnormalize_{match['steps']}_steps.pkl"
    return run_dir / VECNORMALIZE_FILE


def save_model(model: Any, path: Path) -> None:
    """``model.save`` completely or not at all (SB3 saves into a buffer, written atomically)."""
    buffer = io.BytesIO()
    model.save(buffer)
    atomic_write_bytes(path, buffer.getvalue())


def save_statistics(venv: Any, path: Path) -> None:
    """``VecNormalize.save`` (a pickle without the wrapped env) completely or not at all."""
    atomic_write_bytes(path, pickle.dumps(venv))


def read_config(path: Path) -> AgentConfig:
    """The :class:`AgentConfig` a run wrote (``config.yml``: ``algo``, ``env_id`` and one entry)."""
    if not path.is_file():
        raise FileNotFoundError(
            f"{str(path)!r} is missing: it says which algorithm and settings the model was trained with"
        )
    document = read_yaml_file(path)
    try:
        algo, env_id = document["algo"], document["env_id"]
    except (TypeError, KeyError):
        raise ValueError(f"{str(path)!r} must have the keys 'algo', 'env_id' and 'hyperparams'") from None
    return load_config(algo, env_id, path, overrides=None, entry_key="hyperparams")
