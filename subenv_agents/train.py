"""Train a Stable-Baselines3 agent on a subenv environment (rl-baselines3-zoo's ``train.py``, for subenv).

::

    python -m subenv_agents.train --algo ppo --env subenv/DivePlane-v0 --seed 0
    subenv train --algo sac --env subenv/LowSpeed-v0 -n 200000          # the same command

Hyperparameters come from ``subenv_agents/hyperparams/<algo>.yml`` (:mod:`subenv_agents.config`).
Training runs on the native vector environment (:func:`subenv.envs.sb3.make_sb3_vec_env`) wrapped in
``VecMonitor`` and ``VecNormalize``. A run folder ``<log-folder>/<algo>/<env>_<k>/`` receives::

    model.zip, vecnormalize.pkl   the final model and its normalisation statistics (load both with
                                  subenv_agents.load_agent(folder))
    config.yml                    the resolved hyperparameters (algo, env_id, hyperparams)
    train.json                    seed, steps, wall time, threads, versions, curriculum advances
    progress.csv                  SB3's training log
    tensorboard/                  the same log as TensorBoard's event files, when TensorBoard is installed
    best_model.zip, evaluations.npz   from the evaluation callback (a separately seeded env)
    checkpoints/rl_model_<N>_steps.zip and rl_model_vecnormalize_<N>_steps.pkl
    curriculum.json               the curriculum's stage, the stage it started at and its advances
    selected/, selection.json     with --select-freq: the policy that did best on validation episodes
                                  (subenv_agents.selection), loadable on its own, and the record of
                                  every check

``--trained-agent`` continues a run from its model, a checkpoint or its selected policy into a new
folder, with that model's statistics and the curriculum stage training was at when it was saved.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from importlib import metadata
from importlib.util import find_spec
from pathlib import Path
from typing import Any, Final

import yaml

from subenv.evaluation.results import atomic_write_text
from subenv_agents.config import (
    ALGORITHMS,
    DEFAULT_LOG_FOLDER,
    AgentConfig,
    algorithm_class,
    load_config,
    model_kwargs,
    next_run_dir,
    parse_overrides,
)
from subenv_agents.policy import (
    CHECKPOINT_DIR,
    CONFIG_FILE,
    MODEL_FILE,
    VECNORMALIZE_FILE,
    load_agent,
    mark_run,
    model_folder,
    save_model,
    save_statistics,
    statistics_file,
    training_run,
)

__all__ = ["DEFAULT_ENV_ID", "EVAL_SEED_OFFSET", "TrainResult", "main", "make_vec_env", "train"]

DEFAULT_ENV_ID: Final = "subenv/DivePlane-v0"
TENSORBOARD_DIR: Final = "tensorboard"
"""The run folder's subfolder of TensorBoard's event files (when TensorBoard is installed), so that
``tensorboard --logdir results/agents`` lists each run under its folder's name."""
EVAL_SEED_OFFSET: Final = 1_000_000
"""The evaluation env of a run with seed s is seeded with s + this: never the training episodes,
nor those of the evaluation suites (``subenv.evaluation.DEFAULT_SEED`` = 10000 + i)."""
_INFO_KEYS_CURRICULUM: Final = ("time_s", "depth_error_m", "termination_reason")


@dataclass(frozen=True)
class TrainResult:
    """What :func:`train` did: where it wrote, how many steps, how long."""

    run_dir: Path
    timesteps: int
    wall_time_s: float
    curriculum_advances: tuple[tuple[int, int], ...]
    final_stage: int | None


def make_vec_env(config: AgentConfig, n_envs: int, seed: int, curriculum: bool = False) -> Any:
    """The native vector env of ``config`` for SB3, with (if configured) the depth-band bonus, the L1
    plane-effort penalty and the depth-error integral observation, ``VecMonitor`` and (if configured)
    ``VecNormalize``."""
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from subenv.envs.sb3 import make_sb3_vec_env
    from subenv_agents.shaping import DEPTH_ERROR_KEY, DepthBandBonusVecEnv, PlaneEffortL1VecEnv

    info_keys: tuple[str, ...] = _INFO_KEYS_CURRICULUM if curriculum else ()
    if config.depth_band_bonus is not None and DEPTH_ERROR_KEY not in info_keys:
        info_keys += (DEPTH_ERROR_KEY,)
    venv = make_sb3_vec_env(config.env_id, n_envs=n_envs, seed=seed, info_keys=info_keys, **config.env_kwargs)
    if config.depth_band_bonus is not None:
        venv = DepthBandBonusVecEnv(venv, config.depth_band_bonus.half_width_m, config.depth_band_bonus.bonus)
    if config.plane_effort_l1 > 0:
        venv = PlaneEffortL1VecEnv(venv, config.plane_effort_l1, config.plane_effort_reference_speed_mps)
    if config.depth_integral is not None:
        from subenv_agents.features import DepthIntegralVecEnv

        venv = DepthIntegralVecEnv(venv, config.depth_integral, venv.get_attr("config")[0].dt)
    venv = VecMonitor(venv)
    if config.normalize is not None:
        norm = config.normalize
        venv = VecNormalize(
            venv,
            norm_obs=norm.norm_obs,
            norm_reward=norm.norm_reward,
            clip_obs=norm.clip_obs,
            clip_reward=norm.clip_reward,
            gamma=norm.gamma if norm.gamma is not None else config.gamma(),
        )
    return venv


def steps_per_iteration(model: Any) -> int:
    """The environment steps ``model.learn`` takes between two checks of its step count: it stops at
    the end of the iteration that reaches the total, so a run trains a whole number of these.

    On-policy (PPO): a rollout, ``n_envs * n_steps``; off-policy (SAC, TD3): ``n_envs * train_freq``
    (with ``train_freq`` in episodes, a vector step, ``n_envs``: such a run may take more).
    """
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
    from stable_baselines3.common.type_aliases import TrainFrequencyUnit

    if isinstance(model, OnPolicyAlgorithm):
        return int(model.n_steps * model.n_envs)
    freq = model.train_freq
    return int(model.n_envs * (freq.frequency if freq.unit == TrainFrequencyUnit.STEP else 1))


def trained_steps(requested: int, per_iteration: int) -> int:
    """The steps a run of ``requested`` steps trains: rounded up to whole iterations of ``per_iteration``."""
    return -(-requested // per_iteration) * per_iteration


def _iteration(model: Any) -> str:
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

    if isinstance(model, OnPolicyAlgorithm):
        return f"rollouts of {model.n_envs} envs x n_steps {model.n_steps}"
    return f"{model.n_envs} envs x train_freq {model.train_freq.frequency} {model.train_freq.unit.value}"


def train(
    config: AgentConfig,
    seed: int = 0,
    log_folder: str | Path = DEFAULT_LOG_FOLDER,
    run_dir: str | Path | None = None,
    trained_agent: str | Path | None = None,
    eval_freq: int = 100_000,
    eval_episodes: int = 10,
    save_freq: int = 500_000,
    progress: bool = False,
    verbose: int = 1,
    threads: int | None = 1,
    command: str | None = None,
    select_freq: int = 0,
    select_episodes: int = 30,
) -> TrainResult:
    """Train ``config`` with ``seed`` and write the run folder (see the module docstring).

    Parameters
    ----------
    run_dir : path, optional
        The run folder; must not exist. Default: ``<log_folder>/<algo>/<env>_<k>``, k the next free.
    trained_agent : path, optional
        Continue from this model (a run folder, ``model.zip`` or a checkpoint) for
        ``config.n_timesteps`` more steps; its normalisation statistics and curriculum stage too.
    eval_freq, save_freq : int
        Environment steps between evaluations (``eval_episodes`` episodes) and between checkpoints;
        0 disables either.
    progress : bool
        Steps trained on stderr (:class:`subenv_agents.progress.TrainingProgress`): a bar on a
        terminal, otherwise a line every 5%.
    verbose : int
        1: SB3's log tables on stdout (above the bar), and a line when ``config.n_timesteps`` is
        rounded up to whole iterations (:func:`steps_per_iteration`); 0: neither.
    threads : int or None
        ``torch.set_num_threads`` (None leaves torch's default). One thread is fastest for these
        small networks and leaves the other core to a second run.
    command : str, optional
        The command line that started the run, recorded in ``train.json``.
    select_freq, select_episodes : int
        Environment steps between validations of the policy (:mod:`subenv_agents.selection`; 0: none),
        and validation episodes per scenario; the best policy goes to ``<run>/selected/``.
    """
    import torch
    from stable_baselines3.common.callbacks import CallbackList, CheckpointCallback, EvalCallback
    from stable_baselines3.common.logger import Logger, make_output_format
    from stable_baselines3.common.vec_env import VecNormalize

    from subenv_agents.curriculum import CurriculumCallback, read_stage, stage_scenarios, write_state
    from subenv_agents.progress import TrainingProgress

    for name, value in (
        ("seed", seed),
        ("eval_freq", eval_freq),
        ("eval_episodes", eval_episodes),
        ("save_freq", save_freq),
        ("select_freq", select_freq),
        ("select_episodes", select_episodes),
    ):
        if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
            raise ValueError(f"{name}={value!r} is invalid: must be an integer >= 0")
    if threads is not None:
        torch.set_num_threads(threads)
    run_dir = Path(run_dir) if run_dir is not None else next_run_dir(log_folder, config.algo, config.env_id)
    # An empty folder loses nothing: a run may fill it (as every output folder of subenv may).
    existed = run_dir.is_dir() and not run_dir.is_symlink() and not any(run_dir.iterdir())
    if run_dir.exists() and not existed:
        raise FileExistsError(f"run folder {str(run_dir)!r} exists: choose another (or delete it)")
    # The outermost folder this run creates (the run folder, or <log-folder>/<algo>/... if new).
    created = next((p for p in reversed((run_dir, *run_dir.parents)) if not p.exists()), None)
    run_dir.mkdir(parents=True, exist_ok=existed)
    try:
        atomic_write_text(
            run_dir / CONFIG_FILE,
            yaml.safe_dump(
                {"algo": config.algo, "env_id": config.env_id, "hyperparams": config.to_yaml_dict()},
                sort_keys=False,
            ),
        )

        curriculum = config.curriculum
        venv = make_vec_env(config, config.n_envs, seed, curriculum=curriculum is not None)
        eval_env = make_vec_env(config, min(eval_episodes, 10) or 1, seed + EVAL_SEED_OFFSET)
        if isinstance(eval_env, VecNormalize):
            eval_env.training = False
            eval_env.norm_reward = False
        algo_class = algorithm_class(config.algo)
        stage = 0
        if trained_agent is not None:
            previous = load_agent(trained_agent)
            previous.check_spaces(venv, with_features=True)
            # The config's hyperparameters (with any -params overrides) replace the stored ones before
            # the model is set up, so a resumed run trains with what its config.yml says; a "lin_" rate
            # goes on from where the step count stands (SB3: progress = 1 - steps / total steps).
            kwargs = model_kwargs(config)
            policy_kwargs = kwargs.pop("policy_kwargs", {})
            with _hyperparameters_checked(config):
                model = algo_class.load(previous.path, env=venv, device="cpu", seed=seed, **kwargs)
            changed = {k: v for k, v in policy_kwargs.items() if model.policy_kwargs.get(k) != v}
            if changed:
                raise ValueError(
                    f"policy_kwargs {changed} differ from the trained agent's {model.policy_kwargs}: "
                    "a run cannot change the network it continues"
                )
            if isinstance(venv, VecNormalize) and previous.obs_mean is not None:
                stats = statistics_file(previous.path, model_folder(previous.path))
                venv = VecNormalize.load(str(stats), venv.venv)
                model.set_env(venv)
            stage = read_stage(training_run(previous.path), model.num_timesteps)
        else:
            with _hyperparameters_checked(config):
                model = algo_class(
                    config.policy, venv, seed=seed, verbose=0, device="cpu", **model_kwargs(config)
                )
        if isinstance(venv, VecNormalize):
            mark_run(model, venv)  # every model and statistics file of this run carries its id
        outputs = [make_output_format("csv", str(run_dir))] + (
            [make_output_format("stdout", str(run_dir))] if verbose else []
        )
        if find_spec("tensorboard"):
            outputs.append(make_output_format("tensorboard", str(run_dir / TENSORBOARD_DIR)))
        model.set_logger(Logger(str(run_dir), outputs))

        n_envs = venv.num_envs
        chunk = steps_per_iteration(model)
        planned = trained_steps(config.n_timesteps, chunk)
        if planned != config.n_timesteps and verbose:
            print(
                f"training {planned} steps: {config.n_timesteps} rounded up to whole iterations of {chunk} "
                f"steps ({_iteration(model)})",
                file=sys.stderr,
            )
        callbacks: list[Any] = [TrainingProgress(planned, enabled=progress)]
        curriculum_callback = None
        if curriculum is not None:
            vehicle = venv.get_attr("config")[0].base_vehicle
            alpha = float(config.env_kwargs.get("alpha", 0.0))
            scenarios = stage_scenarios(venv.get_attr("scenario")[0], curriculum, vehicle, alpha)
            stage = min(stage, len(scenarios) - 1)
            curriculum_callback = CurriculumCallback(
                scenarios, curriculum, run_dir, stage=stage, verbose=verbose
            )
            write_state(run_dir, stage, [], start_stage=stage)
            callbacks.append(curriculum_callback)
        if eval_freq:
            callbacks.append(
                EvalCallback(
                    eval_env,
                    n_eval_episodes=eval_episodes,
                    eval_freq=max(eval_freq // n_envs, 1),
                    log_path=str(run_dir),
                    best_model_save_path=str(run_dir),
                    deterministic=True,
                    verbose=0,
                )
            )
        selection = None
        if select_freq:
            from subenv_agents.selection import SelectionCallback

            selection = SelectionCallback(config, run_dir, select_freq, select_episodes, verbose=verbose)
            callbacks.append(selection)
        if save_freq:
            callbacks.append(
                CheckpointCallback(
                    max(save_freq // n_envs, 1), str(run_dir / CHECKPOINT_DIR), save_vecnormalize=True
                )
            )
    except BaseException:
        # Nothing trained yet: leave no half-made run folder behind (it would block the same --run-dir),
        # nor the folders made for it (<log-folder>/<algo>/) while they are empty (another run may use one).
        shutil.rmtree(run_dir, ignore_errors=True)
        if existed:  # the empty folder it was given is left as it was
            run_dir.mkdir(exist_ok=True)
        elif created is not None:
            with suppress(OSError):
                for folder in run_dir.parents:
                    if folder == created.parent:
                        break
                    folder.rmdir()
        raise
    start = time.perf_counter()
    model.learn(
        config.n_timesteps, callback=CallbackList(callbacks), reset_num_timesteps=trained_agent is None
    )
    wall = time.perf_counter() - start

    save_model(model, run_dir / MODEL_FILE)
    if isinstance(venv, VecNormalize):
        save_statistics(venv, run_dir / VECNORMALIZE_FILE)
    advances = tuple(curriculum_callback.advances) if curriculum_callback else ()
    final_stage = curriculum_callback.schedule.stage if curriculum_callback else None
    atomic_write_text(
        run_dir / "train.json",
        json.dumps(
            {
                "algo": config.algo,
                "env_id": config.env_id,
                "seed": seed,
                "timesteps": int(model.num_timesteps),
                "wall_time_s": round(wall, 1),
                "torch_threads": torch.get_num_threads(),
                "n_envs": n_envs,
                "trained_agent": str(trained_agent) if trained_agent else None,
                "curriculum_advances": [list(a) for a in advances],
                "final_stage": final_stage,
                "selection": selection.record() if selection else None,
                "command": command,
                "machine": f"{platform.machine()}, {os.cpu_count()} cores",
                "versions": {
                    p: metadata.version(p) for p in ("stable_baselines3", "torch", "gymnasium", "numpy")
                },
            },
            indent=2,
        )
        + "\n",
    )
    venv.close()
    eval_env.close()
    return TrainResult(run_dir, int(model.num_timesteps), wall, advances, final_stage)


@contextmanager
def _hyperparameters_checked(config: AgentConfig) -> Iterator[None]:
    """SB3's checks of its constructor's arguments (mostly ``assert``) as a ValueError naming the
    algorithm."""
    try:
        yield
    except (AssertionError, ValueError, TypeError) as exc:
        raise ValueError(
            f"{config.algo.upper()} refused the hyperparameters {config.algo_kwargs}: "
            f"{' '.join(str(exc).split())}"
        ) from exc


def _quote(arg: str) -> str:
    import shlex

    return shlex.quote(arg)


def main(argv: list[str] | None = None) -> int:
    """``python -m subenv_agents.train`` (and ``subenv train``): train one agent into a run folder and
    say where; exits with a one-line message on a bad configuration or argument."""
    parser = argparse.ArgumentParser(
        prog="python -m subenv_agents.train",
        description="Train a Stable-Baselines3 agent (PPO, SAC, TD3) on a subenv environment.",
    )
    parser.add_argument(
        "--algo", default="ppo", choices=ALGORITHMS, help="the algorithm (default: %(default)s)"
    )
    parser.add_argument("--env", default=DEFAULT_ENV_ID, help="environment id (default: %(default)s)")
    parser.add_argument(
        "-n",
        "--n-timesteps",
        type=int,
        help="environment steps, rounded up to whole iterations (PPO: rollouts of n_envs x n_steps; "
        "SAC, TD3: n_envs x train_freq) (default: the config's)",
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of the model and the environments (default: 0)"
    )
    parser.add_argument("-f", "--log-folder", default=DEFAULT_LOG_FOLDER, help="default: %(default)s")
    parser.add_argument("--run-dir", help="the run folder itself (default: <log-folder>/<algo>/<env>_<k>)")
    parser.add_argument(
        "-conf", "--conf-file", help="hyperparameter YAML (default: subenv_agents/hyperparams/<algo>.yml)"
    )
    parser.add_argument(
        "-params",
        "--hyperparams",
        nargs="+",
        default=[],
        metavar="KEY:VALUE",
        help="override hyperparameters, e.g. learning_rate:1e-4 'policy_kwargs:{net_arch: [32, 32]}'",
    )
    parser.add_argument(
        "--curriculum",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="use (or not) the speed curriculum (default: the config's)",
    )
    parser.add_argument("-i", "--trained-agent", help="continue from this run folder, model or checkpoint")
    parser.add_argument("--eval-freq", type=int, default=100_000, help="steps between evaluations, 0: none")
    parser.add_argument("--eval-episodes", type=int, default=10, help="episodes per evaluation")
    parser.add_argument("--save-freq", type=int, default=500_000, help="steps between checkpoints, 0: none")
    parser.add_argument(
        "--select-freq",
        type=int,
        default=0,
        help="steps between validations that keep the best policy in <run>/selected/ (0: none)",
    )
    parser.add_argument("--select-episodes", type=int, default=30, help="validation episodes per scenario")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (default: 1)")
    parser.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="progress on stderr: a bar on a terminal, otherwise a line every 5%% (default: on)",
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="no training log on stdout")
    argv_list = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv_list)
    try:
        overrides = parse_overrides(args.hyperparams)
        if args.n_timesteps is not None:
            overrides["n_timesteps"] = args.n_timesteps
        if args.curriculum is not None:
            overrides["curriculum"] = args.curriculum
        config = load_config(args.algo, args.env, args.conf_file, overrides)
        result = train(
            config,
            seed=args.seed,
            log_folder=args.log_folder,
            run_dir=args.run_dir,
            trained_agent=args.trained_agent,
            eval_freq=args.eval_freq,
            eval_episodes=args.eval_episodes,
            save_freq=args.save_freq,
            progress=args.progress,
            verbose=0 if args.quiet else 1,
            threads=args.threads,
            select_freq=args.select_freq,
            select_episodes=args.select_episodes,
            command=" ".join(["python -m subenv_agents.train", *map(_quote, argv_list)]),
        )
    except (ValueError, FileExistsError, FileNotFoundError) as exc:
        raise SystemExit(f"subenv_agents.train: {exc}") from None
    print(
        f"trained {config.algo} on {config.env_id} for {result.timesteps} steps in "
        f"{result.wall_time_s:.0f} s (seed {args.seed}); run folder {result.run_dir}/"
    )
    if result.final_stage is not None:
        print(
            f"curriculum: stage {result.final_stage}, advances (step, stage): "
            f"{list(result.curriculum_advances)}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
