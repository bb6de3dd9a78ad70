"""Hyperparameter search on Ray Tune with Optuna's sampler: each trial trains an agent and is scored on
validation episodes.

::

    python -m subenv_agents.tune --algo ppo --env subenv/LowSpeed-v0 --samples 8 -n 200000

A trial is :func:`subenv_agents.train.train` with the config's hyperparameters and the trial's values
(``-params`` style keys), then :func:`subenv_agents.selection.validation_score` of its final policy on
validation seeds (never the evaluation's): Tune maximises the success rate, Optuna's TPE proposes the
values (``OptunaSearch``), at most ``max_concurrent`` trials run at once. Every trial keeps its run folder
under ``<out>/trials/``; ``<out>/best.json`` records the best trial's values, score and folder. The
search space is a mapping of hyperparameter -> ``("log", low, high)``, ``("uniform", low, high)`` or
``("choice", [values])``. Needs the ``ray`` and ``rl`` extras.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import threading
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Final

from subenv.atomic import atomic_write_text
from subenv.extras import MissingExtra, require

__all__ = ["DEFAULT_SPACE", "SELECTION_SCENARIOS", "fit", "main", "search", "tune_space"]

DEFAULT_SPACE: Final[dict[str, tuple[Any, ...]]] = {
    "learning_rate": ("log", 1e-4, 1e-3),
    "gamma": ("choice", [0.99, 0.995, 0.999]),
}
"""What ``--samples`` explores by default: the two the shipped configs found the most sensitive."""
SELECTION_SCENARIOS: Final = ("LowSpeed", "NearCritical")
"""The validation scenarios a trial is scored on (below and near the critical speed: where it is hard)."""
_KINDS: Final = ("log", "uniform", "choice")


def tune_space(space: Mapping[str, Sequence[Any]]) -> dict[str, Any]:
    """The search space in Tune's terms (``tune.loguniform``, ``tune.uniform``, ``tune.choice``)."""
    from ray import tune

    out: dict[str, Any] = {}
    for key, spec in space.items():
        kind = spec[0] if spec else None
        if kind not in _KINDS:
            raise ValueError(f"space[{key!r}]={spec!r} is invalid: must start with one of {list(_KINDS)}")
        if kind == "choice":
            if len(spec) != 2 or not list(spec[1]):
                raise ValueError(f"space[{key!r}]={spec!r} is invalid: must be ('choice', [values])")
            out[key] = tune.choice(list(spec[1]))
            continue
        if (
            len(spec) != 3
            or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in spec[1:])
            or not spec[1] < spec[2]
            or (kind == "log" and spec[1] <= 0)
        ):
            raise ValueError(
                f"space[{key!r}]={spec!r} is invalid: must be ({kind!r}, low, high) with "
                f"{'0 < ' if kind == 'log' else ''}low < high"
            )
        out[key] = tune.loguniform(spec[1], spec[2]) if kind == "log" else tune.uniform(spec[1], spec[2])
    return out


def _trial(
    values: dict[str, Any],
    *,
    algo: str,
    env_id: str,
    timesteps: int,
    seed: int,
    episodes: int,
    trials_dir: str,
    overrides: dict[str, Any],
) -> None:
    """One trial (the function Tune runs in a worker): train, score, report."""
    from ray import tune

    from subenv_agents.config import load_config
    from subenv_agents.policy import load_agent
    from subenv_agents.selection import validation_score
    from subenv_agents.train import train

    config = load_config(algo, env_id, overrides={**overrides, **values, "n_timesteps": timesteps})
    name = "-".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in sorted(values.items()))
    run_dir = Path(trials_dir) / f"{tune.get_context().get_trial_id()}_{name}"
    result = train(config, seed=seed, run_dir=run_dir, eval_freq=0, save_freq=0, verbose=0, progress=False)
    score = validation_score(load_agent(result.run_dir), SELECTION_SCENARIOS, episodes)
    tune.report({**score, "run_dir": str(result.run_dir), "timesteps": result.timesteps})


def search(
    algo: str,
    env_id: str,
    out_dir: str | os.PathLike[str],
    *,
    space: Mapping[str, Sequence[Any]] = DEFAULT_SPACE,
    samples: int = 8,
    timesteps: int = 200_000,
    seed: int = 0,
    episodes: int = 20,
    max_concurrent: int = 2,
    overrides: Mapping[str, Any] | None = None,
    address: str | None = None,
) -> dict[str, Any]:
    """Run the search and return the best trial's record (also written to ``<out_dir>/best.json``).

    Parameters
    ----------
    space : mapping
        Hyperparameter -> ``("log"|"uniform", low, high)`` or ``("choice", [values])`` (:func:`tune_space`).
    samples : int
        Trials; ``timesteps`` environment steps each (rounded as ``subenv_agents.train`` rounds).
    episodes : int
        Validation episodes per scenario of :data:`SELECTION_SCENARIOS`.
    overrides : mapping, optional
        Fixed hyperparameters for every trial (``-params`` style).
    address : str, optional
        A Ray cluster; None starts a local instance (or uses the one already started).
    """
    require("ray", "the hyperparameter search", "ray", "pandas", "optuna")
    require("rl", "the hyperparameter search", "stable_baselines3")
    from ray import tune
    from ray.tune.search.optuna import OptunaSearch

    from subenv_agents.config import load_config

    for name, value, low in (
        ("samples", samples, 1),
        ("timesteps", timesteps, 1),
        ("episodes", episodes, 1),
        ("max_concurrent", max_concurrent, 1),
        ("seed", seed, 0),
    ):
        if not (isinstance(value, int) and not isinstance(value, bool) and value >= low):
            raise ValueError(f"{name}={value!r} is invalid: must be an integer >= {low}")
    param_space = tune_space(space)
    load_config(algo, env_id, overrides=dict(overrides or {}))  # (unknown algorithm, id or key: refused now)
    out = Path(out_dir).resolve()
    if (out / "best.json").exists():
        raise FileExistsError(f"{str(out)!r} holds a finished search (best.json): choose another folder")
    (out / "trials").mkdir(parents=True, exist_ok=True)
    trainable = tune.with_parameters(
        _trial,
        algo=algo,
        env_id=env_id,
        timesteps=timesteps,
        seed=seed,
        episodes=episodes,
        trials_dir=str(out / "trials"),
        overrides=dict(overrides or {}),
    )
    grid = fit(
        lambda: tune.Tuner(
            trainable,
            param_space=param_space,
            tune_config=tune.TuneConfig(
                search_alg=OptunaSearch(metric="success_rate", mode="max", seed=seed),
                num_samples=samples,
                max_concurrent_trials=max_concurrent,
            ),
            run_config=tune.RunConfig(name="search", storage_path=str(out / "tune"), verbose=0),
        ),
        address,
    )
    trials = [
        {
            "values": {k: r.config[k] for k in space},
            **{k: r.metrics[k] for k in ("success_rate", "plane_rms_rad", "run_dir", "timesteps")},
        }
        for r in grid
    ]
    best = max(trials, key=lambda t: (t["success_rate"], -t["plane_rms_rad"]))
    record = {
        "algo": algo,
        "env_id": env_id,
        "samples": samples,
        "timesteps_per_trial": timesteps,
        "seed": seed,
        "validation": {"scenarios": list(SELECTION_SCENARIOS), "episodes": episodes},
        "best": best,
        "trials": trials,
    }
    atomic_write_text(out / "best.json", json.dumps(record, indent=2) + "\n")
    return best


def fit(make_tuner: Callable[[], Any], address: str | None) -> Any:
    """``make_tuner().fit()`` on the Ray cluster at ``address`` (None: the instance already started, or a
    local one started and shut down here); a RuntimeError names the failed trials and the first error."""
    import ray

    started_here = not ray.is_initialized()
    if started_here:
        ray.init(address=address, include_dashboard=False, log_to_driver=False, configure_logging=False)
    # Ray Tune installs a SIGINT handler of its own for the run and leaves it installed: without putting
    # the caller's back, every later Ctrl-C in this process (a sweep, a notebook cell) would be swallowed.
    previous = signal.getsignal(signal.SIGINT)
    try:
        grid = make_tuner().fit()
    finally:
        if previous is not None and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, previous)
        if started_here:
            ray.shutdown()
    failed = [r.error for r in grid if r.error is not None]
    if failed:
        raise RuntimeError(
            f"{len(failed)} of {len(grid)} trials failed (running the same command again retries "
            f"what a resumable run has not finished); the first: {failed[0]}"
        )
    return grid


def main(argv: list[str] | None = None) -> int:
    """``python -m subenv_agents.tune``: run the search and print the best trial; exits with a one-line
    message on bad arguments or a missing extra."""
    parser = argparse.ArgumentParser(
        prog="python -m subenv_agents.tune", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--algo", required=True, help="ppo, sac or td3")
    parser.add_argument("--env", default="subenv/LowSpeed-v0", help="environment id (default: %(default)s)")
    parser.add_argument("--samples", type=int, default=8, help="trials (default: %(default)s)")
    parser.add_argument(
        "-n", "--n-timesteps", type=int, default=200_000, help="steps per trial (default: %(default)s)"
    )
    parser.add_argument(
        "--episodes", type=int, default=20, help="validation episodes per scenario (default: %(default)s)"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of the trials and of the sampler (default: 0)"
    )
    parser.add_argument("--max-concurrent", type=int, default=2, help="trials at once (default: %(default)s)")
    parser.add_argument(
        "--space",
        help='JSON, e.g. \'{"learning_rate": ["log", 1e-4, 1e-3]}\' (default: learning_rate, gamma)',
    )
    parser.add_argument("--out", default="results/tune", help="results folder (default: %(default)s)")
    parser.add_argument("--address", help="a Ray cluster's address; default: a local Ray instance")
    args = parser.parse_args(argv)
    try:
        space = json.loads(args.space) if args.space else DEFAULT_SPACE
        best = search(
            args.algo,
            args.env,
            args.out,
            space=space,
            samples=args.samples,
            timesteps=args.n_timesteps,
            seed=args.seed,
            episodes=args.episodes,
            max_concurrent=args.max_concurrent,
            address=args.address,
        )
    except (ValueError, FileExistsError, RuntimeError, json.JSONDecodeError, MissingExtra) as exc:
        raise SystemExit(f"subenv_agents.tune: {exc}") from None
    print(
        f"best: {best['values']} success {best['success_rate']:.0%}, plane RMS "
        f"{best['plane_rms_rad']:.4f} rad; run folder {best['run_dir']}; all trials in "
        f"{Path(args.out) / 'best.json'}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
