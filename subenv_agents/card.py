"""Ship a trained run as a model in ``subenv_agents/models/<name>/``, with its model card and evaluation.

::

    python -m subenv_agents.card results/agents/ppo/subenv-DivePlane-v0_1 --name ppo

Copies the run's ``model.zip``, ``vecnormalize.pkl``, ``config.yml`` and ``train.json``, evaluates
the agent next to the ``reversal_aware`` baseline with the harness of ``subenv evaluate`` (the
default suite, 100 episodes per scenario, seeds 10000 + i) and on the held-out scenarios of
:mod:`subenv_agents.generalisation` (50 episodes each), and writes ``evaluation.json`` (the numbers) and
``MODEL_CARD.md`` (how the model was trained, on what, and the tables). The folder appears
complete or not at all. ``tests/agents/test_shipped.py`` re-runs the reversal suite and checks
that it reproduces ``evaluation.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Final

import yaml

from subenv.evaluation.results import atomic_output_dir, atomic_write_bytes, atomic_write_text
from subenv_agents import MODELS_DIR
from subenv_agents.controller import AgentController
from subenv_agents.generalisation import HELD_OUT, evaluate_held_out
from subenv_agents.policy import CONFIG_FILE, MODEL_FILE, VECNORMALIZE_FILE, training_run
from subenv_agents.records import BASELINE, REVERSAL_SCENARIOS, evaluation_record, table, target_met
from subenv_agents.selection import SELECTED_DIR

__all__ = [
    "BASELINE",
    "REVERSAL_SCENARIOS",
    "evaluation_record",
    "lineage",
    "main",
    "ship",
    "total_training_time_s",
]

_MODEL_FILES: Final = (MODEL_FILE, VECNORMALIZE_FILE, CONFIG_FILE)


def lineage(run_dir: Path) -> list[dict[str, Any]]:
    """The ``train.json`` records of the runs ``run_dir`` continued from (``--trained-agent``), earliest
    first.

    A run that continued another one took that one's training too: a model's training time is the
    sum over its lineage. A parent is found from the path it was continued from (a run folder, its
    ``selected/`` folder, its model or a checkpoint); a parent without a ``train.json`` is an error.
    """
    records: list[dict[str, Any]] = []
    record = json.loads((run_dir / "train.json").read_text())
    while record.get("trained_agent"):
        parent = training_run(record["trained_agent"])
        if not (parent / "train.json").is_file():
            raise FileNotFoundError(
                f"{run_dir} continued from {record['trained_agent']!r}, whose run folder "
                f"{str(parent)!r} has no train.json: its training time is unknown"
            )
        record = json.loads((parent / "train.json").read_text())
        records.insert(0, record)
    return records


def total_training_time_s(train_record: dict[str, Any]) -> float:
    """Wall time of a shipped ``train.json``: its own run and every run it continued (``continued_from``)."""
    return float(
        train_record["wall_time_s"] + sum(r["wall_time_s"] for r in train_record.get("continued_from", []))
    )


def ship(
    run_dir: Path,
    name: str,
    episodes: int = 100,
    held_out_episodes: int = 50,
    force: bool = False,
    selected: bool = True,
) -> Path:
    """Copy, evaluate and document ``run_dir`` as ``subenv_agents/models/<name>``; returns the folder.

    With ``selected`` (and a ``selected/`` folder in the run: ``--select-freq``) the policy that
    did best on the validation episodes is shipped (:mod:`subenv_agents.selection`), else the final one.
    """
    from subenv.evaluation import DEFAULT_SEED, evaluate, make_controller

    target = MODELS_DIR / name
    train_record = json.loads((run_dir / "train.json").read_text())
    MODELS_DIR.mkdir(exist_ok=True)
    with atomic_output_dir(target, overwrite=force) as tmp:
        source = run_dir / SELECTED_DIR if selected and (run_dir / SELECTED_DIR).is_dir() else run_dir
        for file in _MODEL_FILES:
            atomic_write_bytes(tmp / file, (source / file).read_bytes())
        parents = lineage(run_dir)
        if parents:
            train_record["continued_from"] = parents
        atomic_write_text(tmp / "train.json", json.dumps(train_record, indent=2) + "\n")
        agent = AgentController(tmp, name=name)
        baseline = make_controller(BASELINE)
        scenarios = (
            "Nominal",
            "LowSpeed",
            "NearCritical",
            "SpeedTransient",
            "PeriscopeDepth",
            "BallastOffset",
        )
        suite = evaluation_record(
            evaluate([agent, baseline], list(scenarios), episodes=episodes, progress=False)
        )
        held = evaluation_record(evaluate_held_out([agent, baseline], episodes=held_out_episodes))
        met, detail = target_met(suite, name)
        record = {
            "suite": suite,
            "held_out": held,
            "episodes": episodes,
            "held_out_episodes": held_out_episodes,
            "seed": DEFAULT_SEED,
            "target_met": met,
        }
        atomic_write_text(tmp / "evaluation.json", json.dumps(record, indent=2) + "\n")
        config = yaml.safe_load((tmp / CONFIG_FILE).read_text())["hyperparams"]
        chosen = train_record.get("selection") if source != run_dir else None
        atomic_write_text(
            tmp / "MODEL_CARD.md",
            _card(name, train_record, config, suite, held, met, detail, episodes, held_out_episodes, chosen),
        )
    return target


def _integral(config: dict[str, Any]) -> str:
    integral = config.get("depth_integral")
    if not integral:
        return ""
    return (
        f"; it also observes the leaky integral of the depth error (time constant "
        f"{integral['time_constant_s']:g} s, `subenv_agents/features.py`), which "
        "`load_agent`/`AgentController` append"
    )


def _policy(train: dict[str, Any], selection: dict[str, Any] | None) -> str:
    if selection is None:
        return f"- Policy: the final one, after {train['timesteps']:,} steps."
    best = selection["best"]
    return (
        f"- Policy: the best of {selection['evaluations']} validations, one every {selection['freq']:,} "
        f"steps and one at the end (`subenv_agents/selection.py`): at step {best['timestep']:,}, "
        f"{100 * best['success_rate']:.1f}% success and {best['plane_rms_rad']:.4f} rad plane RMS on "
        f"{selection['episodes']} episodes each of {', '.join(selection['scenarios'])} with the seeds "
        f"{selection['validation_seed']} + i (not the evaluation's below); the validations are part of "
        "the training time."
    )


def _steps(train: dict[str, Any], parents: list[dict[str, Any]]) -> str:
    """The card's count of environment steps (for a continued run, where the model's counter ended)."""
    if not parents:
        return f"{train['timesteps']:,} environment steps"
    return (
        f"the run ended at step {train['timesteps']:,} of the model's step counter (it goes on from the "
        "policy each run started from)"
    )


def _shaping(config: dict[str, Any], continued: bool) -> str:
    """The card's line on the training-only reward terms (:mod:`subenv_agents.shaping`), if the config has
    any."""
    terms = []
    if config.get("plane_effort_l1"):
        speed = config.get("plane_effort_reference_speed_mps")
        terms.append(
            f"an L1 plane penalty of weight {config['plane_effort_l1']:g}"
            + (f" x u / {speed:g} m/s" if speed else "")
        )
    band = config.get("depth_band_bonus")
    if band:
        terms.append(
            f"a bonus of {band['bonus']:g} per step that ends within {band['half_width_m']:g} m of the "
            "ordered depth"
        )
    if not terms:
        return ""
    where = " of the last run (`config.yml`)" if continued else ""
    return f"- Reward shaping, training only (`subenv_agents/shaping.py`){where}: {' and '.join(terms)}.\n"


def _card(
    name: str,
    train: dict[str, Any],
    config: dict[str, Any],
    suite: dict[str, Any],
    held: dict[str, Any],
    met: bool,
    detail: str,
    episodes: int,
    held_out_episodes: int,
    selection: dict[str, Any] | None = None,
) -> str:
    total_s = total_training_time_s(train)
    parents = train.get("continued_from", [])
    if parents:
        # A continued run's step counter goes on from the policy it started from (the model's own counter).
        earlier = "".join(
            f"\n  - before it, to step {r['timesteps']:,}, in {r['wall_time_s']:.0f} s: `{r['command']}`"
            for r in parents
        )
        command = (
            f"`{train['command']}`, continuing {len(parents)} earlier run{'s' if len(parents) > 1 else ''} "
            f"(all of whose time counts below):{earlier}"
        )
    else:
        command = f"`{train['command']}`"
    envs = ", then ".join(f"`{e}`" for e in dict.fromkeys([r["env_id"] for r in parents] + [train["env_id"]]))
    return f"""# Model card: `{name}` ({train["algo"].upper()} on {envs})

A {train["algo"].upper()} agent (Stable-Baselines3 {train["versions"]["stable_baselines3"]}) for depth
keeping, trained on {envs} with the environment arguments
`{config["env_kwargs"]}` (`control: independent`: stern and bow planes driven
separately){_integral(config)}. Registered as the controller `{name}` of `subenv evaluate` (a
`subenv.controllers` entry point); load it with `subenv_agents.load_agent("subenv_agents/models/{name}")`
(the model and its VecNormalize statistics together).

## Training

- Command: {command}
- Seed: {train["seed"]}; {train["n_envs"]} sub-environments of the native vector env;
  {_steps(train, parents)}; hyperparameters in `config.yml` (resolved from
  `subenv_agents/hyperparams/{train["algo"]}.yml`).
- Training time: {total_s:.0f} s ({total_s / 60:.1f} min) of wall-clock time on {train["machine"]}
  ({train["torch_threads"]} torch thread), the learning itself (model set-up and the final save not
  counted); `train.json` has the record.
{_shaping(config, bool(parents))}{_policy(train, selection)}
- Versions: {", ".join(f"{k} {v}" for k, v in train["versions"].items())}.

## Evaluation

The harness of `subenv evaluate`, {episodes} episodes per scenario (seeds 10000 + i, never seen in
training: training episodes use seeds 0 + i, its evaluation callback 1,000,000 + i), next to the
`{BASELINE}` baseline on the same episodes. Success: not terminated and |depth error| <= 0.5 m over the
final 60 s (95% Wilson intervals). Plane RMS: sqrt of the time mean of stern^2 + bow^2.

{table(suite, list(next(iter(suite.values()))))}

**Target** (at least the baseline's success with less plane effort on LowSpeed, NearCritical and
SpeedTransient): **{"met" if met else "not met"}**. {detail}.

## Generalisation (held out of training)

{held_out_episodes} episodes per scenario, noise-free, on speeds and loadings outside the training
ranges (`subenv_agents/generalisation.py`), next to the baseline:

{chr(10).join(f"- `{s.name}`: {s.description}" for s in HELD_OUT)}

{table(held, [s.name for s in HELD_OUT])}

Reproduce: `python -m subenv_agents.card <run folder> --name {name} --force` re-evaluates and rewrites this
card; `python -m subenv_agents.evaluate subenv_agents/models/{name} --suite default` gives the full tables.
"""


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m subenv_agents.card``: evaluate a training run and ship it as
    ``subenv_agents/models/<name>/``, then print its card; exits with a one-line message on a bad run
    folder or an existing model (without ``--force``)."""
    parser = argparse.ArgumentParser(
        prog="python -m subenv_agents.card", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("run", type=Path, help="the run folder (python -m subenv_agents.train's)")
    parser.add_argument(
        "--name", required=True, help="the model's name: subenv_agents/models/<name>, the controller name"
    )
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--held-out-episodes", type=int, default=50)
    parser.add_argument("--force", action="store_true", help="replace an existing model of that name")
    parser.add_argument(
        "--final",
        action="store_true",
        help="ship the final policy even if the run selected one on validation episodes",
    )
    args = parser.parse_args(argv)
    try:
        folder = ship(
            args.run, args.name, args.episodes, args.held_out_episodes, args.force, selected=not args.final
        )
    except (FileExistsError, FileNotFoundError, ValueError) as exc:
        raise SystemExit(f"subenv_agents.card: {exc}") from None
    print((folder / "MODEL_CARD.md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
