"""Hyperparameters: per-algorithm YAML files in the rl-baselines3-zoo layout, loaded into typed configs.

``subenv_agents/hyperparams/<algo>.yml`` maps environment ids to settings, with a ``default`` entry for
any id that has none of its own (rl-zoo's layout, with that one addition)::

    default:
      n_timesteps: 3.0e6          # total environment steps
      policy: MlpPolicy
      n_envs: 16                  # sub-environments of the native vector env
      normalize: {norm_obs: true, norm_reward: true, gamma: 0.995}   # or true / false
      env_kwargs: {control: independent}                           # DivePlaneEnv's arguments
      curriculum: {threshold: 0.8, window: 100}                    # or false (see subenv_agents.curriculum)
      depth_integral: {time_constant_s: 100.0}                     # or false (see subenv_agents.features)
      plane_effort_l1: 0.5                                         # training-only (see subenv_agents.shaping)
      depth_band_bonus: {half_width_m: 0.3, bonus: 0.5}            # or false (see subenv_agents.shaping)
      policy_kwargs: {net_arch: [64, 64], activation_fn: tanh}
      learning_rate: lin_3.0e-4   # "lin_<x>": linear decay from x to 0, as in rl-zoo
      n_steps: 256                # ... any other argument of the algorithm's constructor

Files are read with ``yaml.safe_load`` only; nothing is ``eval``-ed (rl-zoo evaluates strings
such as ``"dict(net_arch=[64, 64])"``; here mappings are written as YAML mappings and activation
functions by name). Every key is checked: an unknown top-level key, algorithm argument,
environment argument, normalisation or curriculum option is a ``ValueError`` naming it and the
known ones.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any, Final

__all__ = [
    "ALGORITHMS",
    "DEFAULT_LOG_FOLDER",
    "HYPERPARAMS_DIR",
    "AgentConfig",
    "CurriculumConfig",
    "DepthBandBonusConfig",
    "DepthIntegralConfig",
    "NormalizeConfig",
    "algorithm_class",
    "load_config",
    "model_kwargs",
    "next_run_dir",
    "parse_overrides",
    "read_yaml_file",
]

HYPERPARAMS_DIR: Final = Path(__file__).parent / "hyperparams"
"""Where ``<algo>.yml`` files are looked up by default."""

ALGORITHMS: Final = ("ppo", "sac", "td3")
"""The Stable-Baselines3 algorithms ``subenv_agents.train`` trains."""

DEFAULT_LOG_FOLDER: Final = "results/agents"
"""Where the training commands put a run folder not named (rl-zoo's ``logs/``)."""


def next_run_dir(log_folder: str | Path, algo: str, env_id: str) -> Path:
    """``<log_folder>/<algo>/<env>_<k>``, k the first number whose folder does not exist (rl-zoo's
    layout; ``env`` the id with ``/`` as ``-``)."""
    folder, name = Path(log_folder) / algo, env_id.replace("/", "-")
    k = 1
    while (folder / f"{name}_{k}").exists():
        k += 1
    return folder / f"{name}_{k}"


DEFAULT_KEY: Final = "default"

_ACTIVATIONS: Final = ("tanh", "relu", "elu", "leaky_relu")
# Constructor arguments the training command sets itself (from its own options), never a config.
_RESERVED: Final = frozenset(
    {"self", "policy", "env", "seed", "verbose", "tensorboard_log", "device", "_init_setup_model"}
)


def algorithm_class(algo: str) -> type[Any]:
    """The Stable-Baselines3 class of ``algo`` (one of :data:`ALGORITHMS`)."""
    _check_algo(algo)
    import stable_baselines3

    return getattr(stable_baselines3, algo.upper())  # type: ignore[no-any-return]


def _check_algo(algo: str) -> None:
    if algo not in ALGORITHMS:
        raise ValueError(f"algo={algo!r} is unknown: must be one of {list(ALGORITHMS)}")


@dataclass(frozen=True)
class NormalizeConfig:
    """Arguments of ``VecNormalize``: observation and reward normalisation, saved with the model."""

    norm_obs: bool = True
    norm_reward: bool = True
    clip_obs: float = 10.0
    clip_reward: float = 10.0
    gamma: float | None = None
    """Discount of the reward normalisation; None takes the algorithm's ``gamma``."""


@dataclass(frozen=True)
class CurriculumConfig:
    """The speed curriculum (:mod:`subenv_agents.curriculum`).

    Stages are ``(name, low, high)`` speed bands in units of the critical speed, easy (fast) to
    hard; stage k draws speeds from its own low end up to the first stage's high end, and the
    loadings (ballast offset, excess buoyancy) grow linearly to their maxima over the stages.
    After the last stage the environment's own scenario takes over.
    """

    stages: tuple[tuple[str, float, float], ...] | None = None
    """None: :data:`subenv.analysis.curriculum.DEFAULT_STAGES`."""
    threshold: float = 0.8
    """Success rate over the last ``window`` episodes of a stage that advances it."""
    window: int = 100
    """Episodes (of the current stage) the success rate is measured over."""
    max_x_GB_m: float = 3e-3
    """Largest ballast offset |x_GB| of the last stage [m] (BallastOffset's range)."""
    max_excess_buoyancy_fraction: float = 1e-3
    """Largest (B - W) / W of the last stage (PeriscopeDepth's range)."""

    def __post_init__(self) -> None:
        if not (0.0 < self.threshold <= 1.0):
            raise ValueError(f"curriculum threshold={self.threshold!r} is invalid: must be in (0, 1]")
        if not (isinstance(self.window, int) and self.window >= 1):
            raise ValueError(f"curriculum window={self.window!r} is invalid: must be an integer >= 1")
        for name in ("max_x_GB_m", "max_excess_buoyancy_fraction"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"curriculum {name}={value!r} is invalid: must be a finite number >= 0")
        if self.stages is not None:
            if not self.stages:
                raise ValueError("curriculum stages=() is invalid: give at least one (name, low, high) stage")
            for stage in self.stages:
                if not (
                    len(stage) == 3
                    and isinstance(stage[0], str)
                    and all(isinstance(v, (int, float)) and math.isfinite(v) for v in stage[1:])
                    and 0 < stage[1] <= stage[2]
                ):
                    raise ValueError(
                        f"curriculum stage {stage!r} is invalid: must be [name, low, high] with "
                        "0 < low <= high (multiples of the critical speed)"
                    )


@dataclass(frozen=True)
class DepthIntegralConfig:
    """The depth-error integral observation (:mod:`subenv_agents.features`): leak time constant [s] and
    clipping [m s]."""

    time_constant_s: float = 100.0
    limit_ms: float = 200.0

    def __post_init__(self) -> None:
        for name in ("time_constant_s", "limit_ms"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"depth_integral {name}={value!r} is invalid: must be a finite number > 0")


@dataclass(frozen=True)
class DepthBandBonusConfig:
    """The training-only depth-band bonus (:mod:`subenv_agents.shaping`): ``bonus`` for every step that ends
    within ``half_width_m`` [m] of the ordered depth."""

    half_width_m: float = 0.3
    bonus: float = 0.5

    def __post_init__(self) -> None:
        for name in ("half_width_m", "bonus"):
            value = getattr(self, name)
            if not (
                isinstance(value, (int, float))
                and not isinstance(value, bool)
                and math.isfinite(value)
                and value > 0
            ):
                raise ValueError(f"depth_band_bonus {name}={value!r} is invalid: must be a finite number > 0")


@dataclass(frozen=True)
class AgentConfig:
    """Everything that defines a training run but the seed, resolved from a hyperparameter file.

    ``algo_kwargs`` are the algorithm's own constructor arguments (checked against its
    signature), ``learning_rate`` may be ``"lin_<x>"``; ``policy_kwargs`` has ``activation_fn``
    by name.
    """

    algo: str
    env_id: str
    n_timesteps: int
    policy: str = "MlpPolicy"
    n_envs: int = 8
    normalize: NormalizeConfig | None = field(default_factory=NormalizeConfig)
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    curriculum: CurriculumConfig | None = None
    depth_integral: DepthIntegralConfig | None = None
    plane_effort_l1: float = 0.0
    """Weight of the training-only L1 penalty on the plane commands (:mod:`subenv_agents.shaping`); 0:
    none."""
    plane_effort_reference_speed_mps: float | None = None
    """With it, the L1 weight scales with the speed u of the step: weight * u / this (None: constant)."""
    depth_band_bonus: DepthBandBonusConfig | None = None
    """The training-only bonus for steps that end near the ordered depth (:mod:`subenv_agents.shaping`);
    None: none."""
    policy_kwargs: dict[str, Any] = field(default_factory=dict)
    algo_kwargs: dict[str, Any] = field(default_factory=dict)

    def to_yaml_dict(self) -> dict[str, Any]:
        """The config as one entry of a hyperparameter file (``load_config`` reads it back)."""
        out: dict[str, Any] = {
            "n_timesteps": self.n_timesteps,
            "policy": self.policy,
            "n_envs": self.n_envs,
            "normalize": asdict(self.normalize) if self.normalize else False,
            "env_kwargs": dict(self.env_kwargs),
        }
        out["depth_integral"] = asdict(self.depth_integral) if self.depth_integral else False
        out["plane_effort_l1"] = self.plane_effort_l1
        out["plane_effort_reference_speed_mps"] = self.plane_effort_reference_speed_mps
        out["depth_band_bonus"] = asdict(self.depth_band_bonus) if self.depth_band_bonus else False
        if self.curriculum is None:
            out["curriculum"] = False
        else:
            curriculum = asdict(self.curriculum)
            if curriculum["stages"] is not None:
                curriculum["stages"] = [list(s) for s in curriculum["stages"]]
            out["curriculum"] = curriculum
        if self.policy_kwargs:
            out["policy_kwargs"] = _plain(self.policy_kwargs)
        out.update(_plain(self.algo_kwargs))
        return out

    def gamma(self) -> float:
        """The discount the algorithm uses (its default if the config does not set it)."""
        if "gamma" in self.algo_kwargs:
            return float(self.algo_kwargs["gamma"])
        default = inspect.signature(algorithm_class(self.algo).__init__).parameters["gamma"].default
        return float(default)


def _plain(value: Any) -> Any:
    """Tuples to lists, recursively (YAML-friendly)."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def load_config(
    algo: str,
    env_id: str,
    path: str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
    entry_key: str | None = None,
) -> AgentConfig:
    """The config of ``algo`` for ``env_id`` from a hyperparameter file.

    Parameters
    ----------
    algo : {"ppo", "sac", "td3"}
    env_id : str
        A registered id (``subenv/LowSpeed-v0``, ...); its entry in the file, else ``default``.
    path : path, optional
        The YAML file; default ``subenv_agents/hyperparams/<algo>.yml``.
    overrides : mapping, optional
        Keys replacing the file's (``--hyperparams`` of the training command), checked alike.
    entry_key : str, optional
        Read this entry instead of looking ``env_id`` up (a run's ``config.yml``: ``hyperparams``).

    Raises
    ------
    ValueError
        Unknown algorithm or environment id; no entry for the id and no ``default``; any unknown
        key (the message names it and the known ones); a value of the wrong kind.
    """
    import gymnasium as gym

    import subenv  # noqa: F401  (registers the ids)

    _check_algo(algo)
    known = sorted(k for k, spec in gym.registry.items() if spec.namespace == "subenv")
    if env_id not in known:  # another library's id (CartPole-v1) would fail deep inside the training stack
        raise ValueError(f"env_id={env_id!r} is not registered by subenv: must be one of {known}")
    path = Path(path) if path is not None else HYPERPARAMS_DIR / f"{algo}.yml"
    try:
        document = read_yaml_file(path)
    except FileNotFoundError:
        raise ValueError(f"hyperparameter file {str(path)!r} does not exist") from None
    if not isinstance(document, dict):
        raise ValueError(f"{path}: must be a mapping of environment ids to hyperparameters")
    key = entry_key or (env_id if env_id in document else DEFAULT_KEY)
    if key not in document:
        raise ValueError(
            f"{path}: has no entry for {env_id!r} and no {DEFAULT_KEY!r} entry (has {sorted(document)})"
        )
    entry = document[key]
    if not isinstance(entry, dict):
        raise ValueError(f"{path}: entry {key!r} must be a mapping, not {entry!r}")
    entry = {**entry, **dict(overrides or {})}
    return _from_entry(algo, env_id, entry, f"{path} [{key}]")


def _from_entry(algo: str, env_id: str, entry: dict[str, Any], where: str) -> AgentConfig:
    entry = dict(entry)
    top = {f.name for f in fields(AgentConfig)} - {"algo", "env_id", "algo_kwargs"}
    algo_params = (
        set(inspect.signature(algorithm_class(algo).__init__).parameters) - _RESERVED - {"policy_kwargs"}
    )
    unknown = set(entry) - top - algo_params
    if unknown:
        raise ValueError(
            f"{where}: unknown hyperparameter(s) {sorted(unknown)} for {algo}: known keys are "
            f"{sorted(top)} and {algo.upper()}'s arguments {sorted(algo_params)}"
        )
    if "n_timesteps" not in entry:
        raise ValueError(f"{where}: n_timesteps is missing (the number of environment steps to train)")
    n_timesteps = _integer(where, "n_timesteps", entry.pop("n_timesteps"))
    n_envs = _integer(where, "n_envs", entry.pop("n_envs", 8))
    policy = entry.pop("policy", "MlpPolicy")
    if policy != "MlpPolicy":
        raise ValueError(
            f"{where}: policy={policy!r} is invalid: must be 'MlpPolicy' (observations are a vector)"
        )
    normalize = _normalize(where, entry.pop("normalize", True))
    env_kwargs = _env_kwargs(where, entry.pop("env_kwargs", {}) or {})
    curriculum = _curriculum(where, entry.pop("curriculum", False))
    integral = _section(where, "depth_integral", entry.pop("depth_integral", False), DepthIntegralConfig)
    l1 = entry.pop("plane_effort_l1", 0.0)
    if not (isinstance(l1, (int, float)) and not isinstance(l1, bool) and math.isfinite(l1) and l1 >= 0):
        raise ValueError(f"{where}: plane_effort_l1={l1!r} is invalid: must be a finite number >= 0")
    l1_speed = entry.pop("plane_effort_reference_speed_mps", None)
    if l1_speed is not None and not (
        isinstance(l1_speed, (int, float))
        and not isinstance(l1_speed, bool)
        and math.isfinite(l1_speed)
        and l1_speed > 0
    ):
        raise ValueError(
            f"{where}: plane_effort_reference_speed_mps={l1_speed!r} is invalid: must be null or a "
            "finite number > 0"
        )
    band = _section(where, "depth_band_bonus", entry.pop("depth_band_bonus", False), DepthBandBonusConfig)
    policy_kwargs = entry.pop("policy_kwargs", {}) or {}
    if not isinstance(policy_kwargs, dict):
        raise ValueError(f"{where}: policy_kwargs={policy_kwargs!r} is invalid: must be a mapping")
    activation = policy_kwargs.get("activation_fn")
    if activation is not None and activation not in _ACTIVATIONS:
        raise ValueError(
            f"{where}: policy_kwargs.activation_fn={activation!r} is invalid: must be one of "
            f"{list(_ACTIVATIONS)}"
        )
    lr = entry.get("learning_rate")
    if isinstance(lr, str):
        _linear_start(where, lr)
    return AgentConfig(
        algo=algo,
        env_id=env_id,
        n_timesteps=n_timesteps,
        policy=policy,
        n_envs=n_envs,
        normalize=normalize,
        env_kwargs=env_kwargs,
        curriculum=curriculum,
        depth_integral=None if integral is None else DepthIntegralConfig(**integral),
        plane_effort_l1=float(l1),
        plane_effort_reference_speed_mps=None if l1_speed is None else float(l1_speed),
        depth_band_bonus=None if band is None else DepthBandBonusConfig(**band),
        policy_kwargs=policy_kwargs,
        algo_kwargs=entry,
    )


def _integer(where: str, name: str, value: Any) -> int:
    if isinstance(value, float) and value.is_integer():
        value = int(value)  # 2.0e6 in YAML is a float
    if not (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
        raise ValueError(f"{where}: {name}={value!r} is invalid: must be an integer >= 1")
    return value


def _section(where: str, name: str, value: Any, cls: type[Any]) -> dict[str, Any] | None:
    """An optional section (``normalize``, ``curriculum``): false/None -> None, true -> defaults,
    a mapping -> its options, checked against the fields of ``cls``."""
    if value is False or value is None:
        return None
    if value is True:
        return {}
    if not isinstance(value, dict):
        raise ValueError(f"{where}: {name}={value!r} is invalid: must be true, false or a mapping")
    known = [f.name for f in fields(cls)]
    unknown = set(value) - set(known)
    if unknown:
        raise ValueError(f"{where}: unknown {name} option(s) {sorted(unknown)}: known options are {known}")
    return dict(value)


def _normalize(where: str, value: Any) -> NormalizeConfig | None:
    options = _section(where, "normalize", value, NormalizeConfig)
    return None if options is None else NormalizeConfig(**options)


def _env_kwargs(where: str, value: Any) -> dict[str, Any]:
    from subenv.envs import DivePlaneEnv

    if not isinstance(value, dict):
        raise ValueError(f"{where}: env_kwargs={value!r} is invalid: must be a mapping")
    known = set(inspect.signature(DivePlaneEnv.__init__).parameters) - {"self", "render_mode"}
    unknown = set(value) - known
    if unknown:
        raise ValueError(
            f"{where}: unknown env_kwargs {sorted(unknown)}: DivePlaneEnv's arguments are {sorted(known)}"
        )
    return dict(value)


def _curriculum(where: str, value: Any) -> CurriculumConfig | None:
    options = _section(where, "curriculum", value, CurriculumConfig)
    if options is None:
        return None
    if options.get("stages") is not None:
        options["stages"] = tuple(tuple(s) if isinstance(s, (list, tuple)) else s for s in options["stages"])
    return CurriculumConfig(**options)


def _linear_start(where: str, value: str) -> float:
    prefix = "lin_"
    try:
        if not value.startswith(prefix):
            raise ValueError
        start = float(value[len(prefix) :])
        if not (math.isfinite(start) and start > 0):
            raise ValueError
    except ValueError:
        raise ValueError(
            f"{where}: learning_rate={value!r} is invalid: must be a number or 'lin_<number > 0>'"
        ) from None
    return start


def parse_overrides(items: list[str]) -> dict[str, Any]:
    """``["key:value", ...]`` (``--hyperparams`` of the training command) to a mapping; values are
    read as YAML (``learning_rate:1e-4``, ``policy_kwargs:{net_arch: [32, 32]}``)."""
    import yaml

    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition(":")
        if not sep or not key:
            raise ValueError(f"--hyperparams {item!r} is invalid: must be key:value")
        try:
            out[key.strip()] = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            problem = _yaml_problem(exc)
            raise ValueError(
                f"--hyperparams {item!r} is invalid: the value must be YAML ({problem})"
            ) from None
    return out


def read_yaml_file(path: Path) -> Any:
    """``yaml.safe_load`` of the file at ``path``; a one-line ValueError naming it if it is not UTF-8 YAML.

    Raises ``FileNotFoundError`` (and the other ``OSError``) as reading does.
    """
    import yaml

    try:
        return yaml.safe_load(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise ValueError(
            f"{str(path)!r} is not UTF-8 text (byte {exc.object[exc.start]:#04x} at position "
            f"{exc.start}): must be a YAML file"
        ) from None
    except yaml.YAMLError as exc:
        raise ValueError(f"{str(path)!r} is not valid YAML: {_yaml_problem(exc)}") from None


def _yaml_problem(exc: Exception) -> str:
    """PyYAML's error in one line: the problem and where (its own message spans several, quoting the text)."""
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or str(exc)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    return " ".join(f"{problem}{where}".split())


def model_kwargs(config: AgentConfig) -> dict[str, Any]:
    """The algorithm's constructor arguments of ``config``: ``lin_<x>`` as SB3's ``LinearSchedule``,
    ``policy_kwargs.activation_fn`` as the torch class it names."""
    kwargs = dict(config.algo_kwargs)
    lr = kwargs.get("learning_rate")
    if isinstance(lr, str):
        from stable_baselines3.common.utils import LinearSchedule

        kwargs["learning_rate"] = LinearSchedule(_linear_start("learning_rate", lr), 0.0, 1.0)
    policy_kwargs = dict(config.policy_kwargs)
    if "activation_fn" in policy_kwargs:
        from torch import nn

        policy_kwargs["activation_fn"] = {
            "tanh": nn.Tanh,
            "relu": nn.ReLU,
            "elu": nn.ELU,
            "leaky_relu": nn.LeakyReLU,
        }[policy_kwargs["activation_fn"]]
    if policy_kwargs:
        kwargs["policy_kwargs"] = policy_kwargs
    return kwargs
