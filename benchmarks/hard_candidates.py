"""Candidate settings of a Hard track, measured: the shipped controllers' success over the winnable episodes.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/hard_candidates.py --episodes 20
    PYTHONPATH=$PWD .venv/bin/python benchmarks/hard_candidates.py --episodes 50 \
        --candidates HardRateTransient,HardGusts --out /tmp/hard.json --oracle /tmp/oracle.json

Each candidate is an existing scenario changed with :meth:`Scenario.replace
<subenv.scenarios.Scenario.replace>`, registered under a temporary name, and environment settings
(``plane_rate_limit_radps``, ``max_pitch_rad``) passed to every environment the harness makes. The
harness cannot take environment settings yet (issue 37), so this script wraps its private
``_env_args`` for the length of a candidate; that is the one patch, and what the Hard track's
``evaluate(..., env_kwargs=...)`` will replace.

Depth changes ordered during the episode are emulated outside the environment (which holds one
ordered depth per episode): the environment's ordered depth is the final one, the scenario draws the
initial depth about the first ordered depth, and every controller is wrapped
(:class:`OrderedDepthStep`) to see the depth error from the ordered depth of the moment. Success is
judged by the harness over the last 60 s, against the final ordered depth, as for every scenario.

``mpc`` is told nothing (the environments' defaults); ``mpc_informed`` is the same MPC told the
environment's plane rate limit and pitch limit. With ``--oracle`` (the JSON that ``hard_oracle.py``
writes) the table also gives success over the achievable episodes (those whose full-information plan
won on replay, :mod:`subenv_baselines.oracle`).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

import subenv
from subenv.atomic import atomic_write_text
from subenv.evaluation import (
    DEFAULT_SEED,
    BatchController,
    EpisodeResult,
    make_controller,
    rollout,
    run_episodes,
)
from subenv.evaluation.achievable import PlanReplay
from subenv.scenarios import get_scenario, register_scenario
from subenv.scenarios.scenario import Scenario
from subenv.vehicles import Vehicle

DT_S = 0.5  # the environments' control period (every candidate keeps the default)


@dataclass(frozen=True)
class DepthStep:
    """An ordered depth that changes during the episode, in steps: from ``at_s[i]`` on it is
    ``offsets_m[i + 1]`` from the final one (positive: deeper), before ``at_s[0]`` ``offsets_m[0]``,
    and after the last change the final ordered depth, the environment's (``offsets_m`` has one entry
    per change). ``DepthStep.single(3, 150)``: 3 m shallower than the final depth until 150 s, then
    the final depth (an order 3 m deeper)."""

    offsets_m: tuple[float, ...]
    at_s: tuple[float, ...]

    @classmethod
    def single(cls, step_m: float, at_s: float) -> DepthStep:
        """One order, ``step_m`` deeper (negative: shallower), at ``at_s``."""
        return cls((-step_m,), (at_s,))

    @property
    def first_offset_m(self) -> float:
        """The first ordered depth less the final one [m]."""
        return self.offsets_m[0]

    def offset_m(self, time_s: Any) -> Any:
        """The ordered depth at ``time_s`` less the final one [m]."""
        levels = np.array([*self.offsets_m, 0.0])
        return levels[np.searchsorted(np.array(self.at_s), np.asarray(time_s), side="right")]


@dataclass(frozen=True)
class Candidate:
    """A candidate Hard setting: a scenario (registered under ``scenario.name``), environment settings,
    and an ordered depth step emulated by wrapping the controllers."""

    scenario: Scenario
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)
    depth_step: DepthStep | None = None
    note: str = ""

    @property
    def name(self) -> str:
        return self.scenario.name


def _stepped(base: Scenario, name: str, step: DepthStep, **changes: Any) -> Scenario:
    """``base`` with the initial depth drawn about the first ordered depth (``step.first_offset_m`` from the
    environment's, the final one), and the first ordered depth drawn as the base draws it."""
    low, high = base.depth_command_m
    off_low, off_high = base.initial_depth_offset_m
    first = step.first_offset_m
    return base.replace(
        name=name,
        depth_command_m=(low - first, high - first),
        initial_depth_offset_m=(off_low + first, off_high + first),
        **changes,
    )


def candidates() -> dict[str, Candidate]:
    """Every candidate, by name."""
    transient, ballast = get_scenario("SpeedTransient"), get_scenario("BallastOffset")
    near, low_speed = get_scenario("NearCritical"), get_scenario("LowSpeed")
    waves = get_scenario("PeriscopeDepthWaves")
    step_down = DepthStep.single(3.0, 150.0)
    found = [
        Candidate(
            transient.replace(name="HardRateTransient"),
            {"plane_rate_limit_radps": 0.05},
            note="SpeedTransient, planes rate-limited to 0.05 rad/s",
        ),
        Candidate(
            ballast.replace(name="HardBallastLimits", sensor_noise=True, disturbance_std_N=1.0),
            {"plane_rate_limit_radps": 0.03, "max_pitch_rad": 0.3},
            note="BallastOffset, noise, 1 N disturbance, 0.03 rad/s, pitch limit 0.3 rad",
        ),
        Candidate(
            waves.replace(
                name="HardWaves18", sea_state=dataclasses.replace(waves.sea_state, significant_height_m=0.18)
            ),
            note="PeriscopeDepthWaves at H_s 18 cm",
        ),
        Candidate(
            ballast.replace(name="HardBallastSlow", speed_ratio=(0.6, 1.0)),
            note="BallastOffset at 0.6-1.0 u_cr",
        ),
        Candidate(
            near.replace(name="HardGusts", sensor_noise=True, disturbance_std_N=6.0),
            note="NearCritical, noise, 6 N gusts",
        ),
        Candidate(
            _stepped(low_speed, "HardStepLow", step_down),
            depth_step=step_down,
            note="LowSpeed, ordered 3 m deeper at 150 s",
        ),
        Candidate(
            _stepped(near, "HardStepNear", step_down),
            depth_step=step_down,
            note="NearCritical, ordered 3 m deeper at 150 s",
        ),
        Candidate(
            _stepped(transient, "HardStepTransient", step_down),
            depth_step=step_down,
            note="SpeedTransient, ordered 3 m deeper at 150 s (mid-deceleration)",
        ),
        Candidate(
            _stepped(transient, "HardStepTransientRate", step_down),
            {"plane_rate_limit_radps": 0.05},
            depth_step=step_down,
            note="SpeedTransient, ordered 3 m deeper at 150 s, planes rate-limited to 0.05 rad/s",
        ),
        Candidate(
            _stepped(
                ballast,
                "HardStepBallast",
                step_down,
                speed_ratio=(0.6, 1.2),
                sensor_noise=True,
                disturbance_std_N=1.0,
            ),
            depth_step=step_down,
            note="BallastOffset at 0.6-1.2 u_cr, noise, 1 N disturbance, ordered 3 m deeper at 150 s",
        ),
        Candidate(
            _stepped(low_speed, "HardStepLowLate", late := DepthStep.single(4.0, 300.0)),
            depth_step=late,
            note="LowSpeed, ordered 4 m deeper at 300 s",
        ),
        Candidate(
            _stepped(near, "HardStepNearLate", late),
            depth_step=late,
            note="NearCritical, ordered 4 m deeper at 300 s",
        ),
        Candidate(
            _stepped(low_speed, "HardStepUpLow", up := DepthStep.single(-3.0, 250.0)),
            depth_step=up,
            note="LowSpeed, ordered 3 m shallower at 250 s",
        ),
        Candidate(
            _stepped(transient, "HardStepTransientLate", late),
            depth_step=late,
            note="SpeedTransient, ordered 4 m deeper at 300 s (at or after the deceleration's end)",
        ),
        Candidate(
            _stepped(
                near,
                "HardStepLimits",
                mid := DepthStep.single(3.0, 250.0),
                sensor_noise=True,
                disturbance_std_N=1.0,
            ),
            {"plane_rate_limit_radps": 0.05, "max_pitch_rad": 0.3},
            depth_step=mid,
            note=(
                "NearCritical, noise, 1 N disturbance, 0.05 rad/s, pitch limit 0.3 rad, ordered 3 m deeper "
                "at 250 s"
            ),
        ),
        Candidate(
            _stepped(low_speed, "HardStepLowBig", big := DepthStep.single(8.0, 300.0)),
            depth_step=big,
            note="LowSpeed, ordered 8 m deeper at 300 s",
        ),
        Candidate(
            _stepped(low_speed, "HardStepLowBig48", big, speed_ratio=(0.4, 0.8)),
            depth_step=big,
            note="LowSpeed at 0.4-0.8 u_cr, ordered 8 m deeper at 300 s",
        ),
        Candidate(
            _stepped(near, "HardStepNearBig", big),
            depth_step=big,
            note="NearCritical, ordered 8 m deeper at 300 s",
        ),
        Candidate(
            _stepped(
                low_speed, "HardZigzagLow", zigzag := DepthStep((-4.0, 0.0, -4.0), (120.0, 240.0, 360.0))
            ),
            depth_step=zigzag,
            note="LowSpeed, ordered 4 m deeper, shallower, deeper at 120, 240, 360 s",
        ),
        Candidate(
            _stepped(near, "HardZigzagNear", zigzag),
            depth_step=zigzag,
            note="NearCritical, ordered 4 m deeper, shallower, deeper at 120, 240, 360 s",
        ),
        Candidate(
            _stepped(transient, "HardZigzagTransient", zigzag),
            depth_step=zigzag,
            note="SpeedTransient, ordered 4 m deeper, shallower, deeper at 120, 240, 360 s",
        ),
    ]
    return {c.name: c for c in found}


def register(candidate: Candidate) -> None:
    """Register the candidate's scenario and its Gymnasium id (replacing an earlier registration)."""
    register_scenario(candidate.scenario, overwrite=True)
    subenv.register_envs()


@contextlib.contextmanager
def env_kwargs(settings: Mapping[str, Any]) -> Iterator[None]:
    """Every environment the harness makes within gets ``settings`` too (see the module docstring)."""
    original = rollout._env_args

    def with_settings(*args: Any, **kwargs: Any) -> tuple[str, dict[str, Any]]:
        env_id, made = original(*args, **kwargs)
        return env_id, {**made, **settings}

    rollout._env_args = with_settings
    try:
        yield
    finally:
        rollout._env_args = original


class OrderedDepthStep:
    """A batch controller that sees the depth error from the ordered depth of the moment
    (:class:`DepthStep`): every other input as the environment gives it."""

    def __init__(self, inner: BatchController, step: DepthStep, dt_s: float = DT_S) -> None:
        self.inner, self.step, self.dt_s = inner, step, dt_s
        self.name, self.control, self.alpha = inner.name, inner.control, inner.alpha
        self._steps = 0

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        self._steps = 0
        offset = float(self.step.offset_m(0.0))
        shifted = [
            {
                **info,
                "depth_command_m": info["depth_command_m"] + offset,
                "depth_error_m": info["depth_error_m"] - offset,
            }
            for info in infos
        ]
        self.inner.reset_batch(shifted, vehicle)

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        obs = np.array(observations, dtype=np.float32)
        obs[:, 0] -= np.float32(self.step.offset_m(self._steps * self.dt_s))
        self._steps += 1
        return self.inner.act_batch(obs)

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        self.reset_batch([info], vehicle)

    def act(self, observation: np.ndarray) -> np.ndarray:
        action: np.ndarray = self.act_batch(np.asarray(observation)[None])[0]
        return action


def check_plans(candidate: Candidate, folder: str) -> list[dict[str, Any]]:
    """Replay the oracle's plans of ``candidate`` (``<folder>/<candidate>.npz``, ``hard_oracle.py --plans``)
    through the evaluation harness (the vector environment, the candidate's settings): one row per seed,
    whether the plan won."""
    register(candidate)
    with np.load(f"{folder}/{candidate.name}.npz") as stored:
        plans = {int(key.removeprefix("seed_")): stored[key] for key in stored.files}
    seeds = sorted(plans)
    with env_kwargs(candidate.env_kwargs):
        results = run_episodes(PlanReplay([plans[s] for s in seeds]), candidate.name, seeds)
    return [
        {"candidate": candidate.name, "seed": r.seed, "achievable": bool(r.metrics.success)} for r in results
    ]


def controller(name: str, candidate: Candidate) -> BatchController:
    """The controller ``name`` for ``candidate``: ``mpc_informed`` is told its limits."""
    if name == "mpc_informed":
        from subenv_baselines.mpc import DepthMPC

        kwargs = {
            k: v for k, v in candidate.env_kwargs.items() if k in ("plane_rate_limit_radps", "max_pitch_rad")
        }
        made: Any = DepthMPC(**kwargs)
        made.name = "mpc_informed"
    else:
        made = make_controller(name)
    if candidate.depth_step is not None:
        return OrderedDepthStep(made, candidate.depth_step)
    return made


def run(candidate: Candidate, names: Sequence[str], seeds: Sequence[int]) -> list[dict[str, Any]]:
    """One row per controller and episode: success, winnable, outcome, final speed ratio."""
    register(candidate)
    rows = []
    with env_kwargs(candidate.env_kwargs):
        for name in names:
            start = time.perf_counter()
            results: list[EpisodeResult] = run_episodes(controller(name, candidate), candidate.name, seeds)
            elapsed = time.perf_counter() - start
            for r in results:
                rows.append(
                    {
                        "candidate": candidate.name,
                        "controller": name,
                        "seed": r.seed,
                        "success": bool(r.metrics.success),
                        "winnable": bool(r.winnable),
                        "outcome": r.metrics.outcome,
                        "final_speed_ratio": r.final_speed_mps / r.critical_speed_mps,
                        "hold_max_abs_error_m": r.metrics.hold_max_abs_error_m,
                        "seconds": elapsed / len(results),
                    }
                )
    return rows


def summary(rows: Sequence[Mapping[str, Any]], achievable: Mapping[str, Mapping[int, bool]]) -> str:
    """Success over winnable (and achievable) episodes, per candidate and controller, then over all the
    candidates per controller (``mpc_informed`` counted as ``mpc`` where there was no limit to tell), and
    the episodes a controller won that the oracle did not certify (its plan lost): Markdown."""
    lines = [
        "| candidate | controller | episodes | winnable | won / winnable | achievable | won / achievable |",
        "|---|---|---|---|---|---|---|",
    ]
    groups: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["candidate"], row["controller"]), []).append(row)
    candidates_run = list(dict.fromkeys(cand for cand, _ in groups))
    names = list(dict.fromkeys(name for _, name in groups))
    for cand, name in groups:
        lines.append(_line(cand, name, groups[cand, name], achievable.get(cand, {})))
    for name in names:
        # Every candidate's episodes of this controller, numbered afresh (seeds repeat across candidates).
        pairs = [
            (cand, row)
            for cand in candidates_run
            for row in groups.get(
                (cand, name), groups.get((cand, "mpc"), []) if name == "mpc_informed" else []
            )
        ]
        pooled = [dict(row, seed=k) for k, (_, row) in enumerate(pairs)]
        certified = {
            k: achievable[cand][row["seed"]]
            for k, (cand, row) in enumerate(pairs)
            if row["seed"] in achievable.get(cand, {})
        }
        lines.append(_line("all", name, pooled, certified))
    unmatched = [
        f"{r['candidate']} {r['seed']} {r['controller']}"
        for r in rows
        if r["success"] and achievable.get(r["candidate"], {}).get(r["seed"]) is False
    ]
    if achievable:
        lines.append("")
        lines.append(f"won by a controller, not certified by the oracle: {unmatched or 'none'}")
    return "\n".join(lines)


def _line(cand: str, name: str, group: Sequence[Mapping[str, Any]], certified: Mapping[int, bool]) -> str:
    winnable = [r for r in group if r["winnable"]]
    won_w = sum(r["success"] for r in winnable)
    cells = [cand, name, str(len(group)), str(len(winnable)), _pct(won_w, len(winnable))]
    known = [r for r in group if r["seed"] in certified]
    if known:
        ach = [r for r in known if certified[r["seed"]]]
        cells += [_pct(len(ach), len(known)), _pct(sum(r["success"] for r in ach), len(ach))]
    else:
        cells += ["", ""]
    return "| " + " | ".join(cells) + " |"


def _pct(k: int, n: int) -> str:
    return f"{k}/{n} ({100.0 * k / n:.0f}%)" if n else "0/0"


def read_achievable(paths: str | None) -> dict[str, dict[int, bool]]:
    """Per candidate, per seed: whether the oracle's plan won on replay (``hard_oracle.py``'s JSON files,
    comma-separated; a later file's row for an episode replaces an earlier one's)."""
    found: dict[str, dict[int, bool]] = {}
    for path in paths.split(",") if paths else []:
        with open(path) as f:
            data = json.load(f)
        for row in data["episodes"]:
            found.setdefault(row["candidate"], {})[int(row["seed"])] = bool(row["achievable"])
    return found


def main() -> None:
    known = candidates()
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--candidates", default=",".join(known), help="comma-separated (default: all)")
    parser.add_argument("--controllers", default="mpc,mpc_informed,reversal_aware,ppo_jax")
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED)
    parser.add_argument("--out", help="write the per-episode rows here (JSON)")
    parser.add_argument(
        "--oracle", help="hard_oracle.py's JSON files, comma-separated: success over achievable episodes too"
    )
    parser.add_argument(
        "--check-plans",
        metavar="FOLDER",
        help="replay hard_oracle.py's plans (--plans FOLDER) through the harness and compare with --oracle",
    )
    args = parser.parse_args()
    if args.check_plans:
        certified = read_achievable(args.oracle)
        for cand in args.candidates.split(","):
            replayed = check_plans(known[cand], args.check_plans)
            agree = sum(r["achievable"] == certified.get(cand, {}).get(r["seed"]) for r in replayed)
            won = sum(r["achievable"] for r in replayed)
            print(f"{cand}: {won}/{len(replayed)} plans win in the harness; {agree} agree with --oracle")
        return
    names = args.controllers.split(",")
    seeds = range(args.seed, args.seed + args.episodes)
    rows: list[dict[str, Any]] = []
    for cand in args.candidates.split(","):
        candidate = known[cand]
        start = time.perf_counter()
        # mpc_informed is mpc where the environment has no limit to tell
        told = [n for n in names if n != "mpc_informed" or candidate.env_kwargs]
        rows += run(candidate, told, seeds)
        print(f"{cand}: {time.perf_counter() - start:.0f} s", flush=True)
        if args.out:
            atomic_write_text(args.out, json.dumps({"seeds": list(seeds), "episodes": rows}, indent=1))
    print(summary(rows, read_achievable(args.oracle)))


if __name__ == "__main__":
    main()
