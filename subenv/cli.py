"""The ``subenv`` command line: the submarine depth-control benchmark's commands.

``subenv evaluate`` (the main job) compares the installed controllers on a suite of scenarios;
``subenv sweep`` runs them over a grid of the physics' parameters on Ray (:mod:`subenv.sweep`);
``subenv analyze`` recomputes Riedel (1993)'s published numbers and the findings beyond them
(:mod:`subenv.analysis.report`);
``subenv demo`` flies the thesis's pole-placement design (Riedel 1993 Ch. II.B, computed here from
the linear model) once above and once below the critical speed, prints a summary and writes a plot.
The command line is the composition root: it finds the controllers through their entry points
(:func:`subenv.evaluation.discover_controllers`) and ``--plugins``, and forwards ``subenv train``
to ``subenv_agents.train`` by name, so that the library imports neither package.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import json
import math
import sys
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import subenv  # noqa: F401  (registers the environments)
from subenv.analysis import THESIS_POLES, critical_speed, thesis_gain
from subenv.atomic import atomic_write_text
from subenv.extras import MissingExtra, require
from subenv.sweep import PARAMETERS
from subenv.thesis import THESIS_DESIGN_SPEED_MPS
from subenv.units import mps_to_fps
from subenv.vehicles import available_vehicles


@dataclass
class Run:
    """One episode of ``subenv demo``: its speed, traces and end."""

    label: str
    speed_mps: float
    times: np.ndarray
    depth_error: np.ndarray
    pitch: np.ndarray
    plane: np.ndarray
    reason: str


def fly(env_id: str, speed_mps: float, seed: int, label: str) -> Run:
    """One episode of the thesis controller at a constant speed, starting 2 m above the ordered depth."""
    env = gym.make(env_id)
    gain = thesis_gain(env.unwrapped.base_vehicle)  # type: ignore[attr-defined]
    limit = env.unwrapped.plane_limit_rad  # type: ignore[attr-defined]
    obs, info = env.reset(
        seed=seed, options={"speed": speed_mps, "depth_command": 10.0, "initial_state": (0.0, 0.0, 0.0, 8.0)}
    )
    times, errors, pitches, planes = [0.0], [info["depth_error_m"]], [info["pitch_rad"]], [0.0]
    reason = "time limit"
    while True:
        x = np.array([obs[1], obs[2], obs[3], obs[0]])  # (theta, w, q, depth error)
        action = np.clip(-(gain @ x) / limit, -1.0, 1.0).astype(np.float32)
        obs, _, terminated, truncated, info = env.step(action)
        times.append(info["time_s"])
        errors.append(info["depth_error_m"])
        pitches.append(info["pitch_rad"])
        planes.append(info["stern_plane_rad"])
        if terminated or truncated:
            reason = info["termination_reason"] or "time limit"
            break
    env.close()
    return Run(
        label, speed_mps, np.array(times), np.array(errors), np.array(pitches), np.array(planes), reason
    )


def _write_plot(runs: Sequence[Run], ucr: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from subenv.evaluation.plots import save_figure

    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for run in runs:
        axes[0].plot(run.times, run.depth_error, label=run.label)
        axes[1].plot(run.times, np.degrees(run.pitch), label=run.label)
        axes[2].plot(run.times, np.degrees(run.plane), label=run.label)
    axes[0].set_ylabel("depth error [m]\n(+ too deep)")
    axes[0].invert_yaxis()
    axes[1].set_ylabel("pitch [deg]")
    axes[2].set_ylabel("stern planes [deg]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best")
    fig.suptitle(f"Thesis pole-placement controller (5 fps design); critical speed {ucr:.3f} m/s")
    fig.tight_layout()
    save_figure(fig, path, image_format=path.suffix[1:] or "png")  # the format the file name says
    plt.close(fig)


def demo(args: argparse.Namespace) -> int:
    """``subenv demo``: the thesis controller above and below the critical speed."""
    env = gym.make(args.env)
    ucr = critical_speed(env.unwrapped.base_vehicle)  # type: ignore[attr-defined]
    env.close()
    if not (args.low_speed > 0 and math.isfinite(args.low_speed)):
        raise SystemExit(f"--low-speed={args.low_speed!r} is invalid: must be a number > 0 (m/s)")
    if not args.no_plot:
        require("plot", "the plot (or pass --no-plot)", "matplotlib")
    runs = [
        fly(
            args.env, THESIS_DESIGN_SPEED_MPS, args.seed, f"{THESIS_DESIGN_SPEED_MPS:.3f} m/s (design speed)"
        ),
        fly(args.low_env, args.low_speed, args.seed, f"{args.low_speed:.3f} m/s"),
    ]
    print(
        f"subenv demo on {args.env} and {args.low_env}: thesis pole placement at 5 fps (poles {THESIS_POLES})"
    )
    print(f"critical speed u_cr = {ucr:.4f} m/s = {mps_to_fps(ucr):.4f} fps (Riedel 1993 eq. 3.9)")
    print(
        f"{'speed [m/s]':>12} {'u/u_cr':>7} {'final depth err [m]':>20} {'final pitch [deg]':>18} "
        f"{'final plane [deg]':>18}  end"
    )
    for run in runs:
        print(
            f"{run.speed_mps:12.3f} {run.speed_mps / ucr:7.2f} {run.depth_error[-1]:20.3f} "
            f"{math.degrees(run.pitch[-1]):18.2f} {math.degrees(run.plane[-1]):18.2f}  {run.reason}"
        )
    if not args.no_plot:
        _write_plot(runs, ucr, Path(args.out))
        print(f"plot written to {args.out}")
    return 0


def analyze(args: argparse.Namespace) -> int:
    """``subenv analyze``: :func:`subenv.analysis.report.write_findings`, and its tables printed."""
    from subenv.analysis import report
    from subenv.atomic import OutputDirError
    from subenv.vehicles import load_vehicle

    try:
        vehicle = load_vehicle(args.vehicle)
    except (ValueError, OSError) as exc:
        raise SystemExit(f"subenv analyze: --vehicle {args.vehicle!r}: {exc}") from None
    try:
        found = report.write_findings(args.out, vehicle, overwrite=args.force)
    except (FileExistsError, OutputDirError) as exc:
        raise SystemExit(f"subenv analyze: --out: {exc}") from None
    header: tuple[str, ...]
    cells: list[tuple[str, ...]]
    if found.suboff_shape:
        print(f"Riedel (1993)'s published numbers, recomputed for {found.vehicle}:\n")
        header = ("quantity", "thesis value", "computed value", "difference", "unit", "note")
        cells = [
            (r.quantity, f"{r.thesis:.5g}", f"{r.computed:.5g}", f"{r.difference:+.3g}", r.unit, r.note)
            for r in found.published
        ]
    else:
        print(f"The critical speed and saturation of {found.vehicle} (the thesis studied SUBOFF):\n")
        header = ("quantity", "value", "unit", "note")
        cells = [(r.quantity, f"{r.computed:.5g}", r.unit, r.note) for r in found.numbers]
    for row in (header, ("---",) * len(header), *cells):
        print("| " + " | ".join(row) + " |")
    hopf = found.hopf.point
    print(
        f"\nPlanes held at zero, level flight loses stability at u_H = {hopf.speed_mps:.4f} m/s "
        f"({hopf.speed_mps / critical_speed(vehicle):.3f} u_cr; period {hopf.period_s:.1f} s, "
        f"{hopf.criticality})"
    )
    near = found.surface.critical[0]
    print(
        f"Near the free surface the critical speed falls: {100 * near.shift:+.1f} % at {near.depth_m:.3g} m"
    )
    print(
        f"\nfindings written to {Path(args.out) / report.REPORT_FILE}; the report with its figures is the "
        "documentation's Reproduction page"
    )
    return 0


def _load_plugins(names: Sequence[str]) -> None:
    """Import each plugin: a Python file (``depth_p.py``) or a module importable from the current
    directory or the path (``my_package.controllers``); it registers its controllers with
    :func:`subenv.evaluation.register_controller` when imported."""
    if "" not in sys.path and str(Path.cwd()) not in sys.path:
        sys.path.insert(0, str(Path.cwd()))  # (as `python -m` does: a module beside the user is found)
    for name in names:
        if name.endswith(".py"):
            path = Path(name)
            if not path.is_file():
                raise SystemExit(f"subenv evaluate: --plugins: no Python file {name!r} here")
            module_name = path.stem
            spec = importlib.util.spec_from_file_location(module_name, path)
            if spec is None or spec.loader is None or not module_name.isidentifier():
                raise SystemExit(
                    f"subenv evaluate: --plugins: {name!r} cannot be imported: its name must be a "
                    "Python identifier ending in .py"
                )
            module = importlib.util.module_from_spec(spec)
            sys.modules[module_name] = module  # (the importlib recipe: dataclasses and pickling find it)
            try:
                spec.loader.exec_module(module)
            except BaseException:
                del sys.modules[module_name]
                raise
            continue
        try:
            importlib.import_module(name)
        except ModuleNotFoundError as exc:
            raise SystemExit(f"subenv evaluate: cannot import controller package {name!r}: {exc}") from None


def _installed_controllers(requested: Sequence[str] | None) -> None:
    """Register the installed controllers; a requested one that cannot load is an error, the others a note.

    A declared controller whose optional dependencies are missing (the shipped agents without the
    ``rl`` extra) is skipped with one line on stderr per reason when every controller runs.
    """
    from subenv.evaluation import discover_controllers

    unavailable = discover_controllers()
    for name in requested or ():
        if name in unavailable:
            raise SystemExit(f"subenv evaluate: controller {name!r} cannot load: {unavailable[name]}")
    if requested is None:
        by_reason: dict[str, list[str]] = {}
        for name, reason in unavailable.items():
            by_reason.setdefault(reason, []).append(name)
        for reason, names in by_reason.items():
            print(f"(skipped {', '.join(names)}: {reason})", file=sys.stderr)


def _note_other_vehicle(vehicle_name: str, controllers: Sequence[str] | None) -> None:
    """On a vehicle of another length the comparison is Froude-scaled, but the agents are not; on one
    without bow planes the controllers that move them are left out of the default comparison."""
    from subenv.evaluation.rollout import needs_bow_planes, resolve_controllers
    from subenv.thesis import reference_length_ratio
    from subenv.vehicles import load_vehicle

    try:
        vehicle = load_vehicle(vehicle_name)
    except ValueError as exc:
        raise SystemExit(f"subenv evaluate: {exc}") from None
    if controllers is None and not vehicle.planes.has_bow_planes:
        bow = [c.name for c in resolve_controllers(None) if needs_bow_planes(c)]
        if bow:
            print(
                f"(skipped {', '.join(bow)}: they move the bow planes, and {vehicle_name} has none)",
                file=sys.stderr,
            )
    ratio = reference_length_ratio(vehicle)
    if ratio != 1.0:
        print(
            f"(--vehicle {vehicle_name}: the scenarios, the success criterion and the classical baselines' "
            f"designs are Froude-scaled to its {vehicle.length_m:.4g} m (x{ratio:.4g}); the trained agents "
            "are SUBOFF's and only run there as they were trained)",
            file=sys.stderr,
        )


def evaluate(args: argparse.Namespace) -> int:
    """``subenv evaluate``: 0 when every controller ran every episode; 1 when one failed (the others'
    results are written, and each failure is a line on stderr)."""
    from subenv.atomic import OutputDirError
    from subenv.dynamics.free_surface import VALIDITY_DEPTH_RADII, VALIDITY_FROUDE_SQUARED
    from subenv.envs import FreeSurfaceRangeWarning
    from subenv.evaluation import (
        BENCHMARK_SUITES,
        DEFAULT_SEED,
        ENTRY_POINT_GROUP,
        controller_names,
        run_benchmark,
        run_comparison,
        suite_names,
    )

    _load_plugins(args.plugins or ())
    _installed_controllers(None if args.list else args.controllers)
    if args.list:
        print("controllers:", ", ".join(controller_names()) or "(none registered)")
        print("suites:", ", ".join(suite_names()))
        return 0
    if not controller_names():
        raise SystemExit(
            f"subenv evaluate: no controllers are registered: install a package that declares some "
            f"in the {ENTRY_POINT_GROUP!r} entry-point group, or see --plugins"
        )
    _note_other_vehicle(args.vehicle, args.controllers)
    # The plots are a by-product: without matplotlib (a bare install) the run goes on without them, with a
    # note, as a controller that cannot load is skipped.
    plots = not args.no_plots
    if plots:
        try:
            require("plot", "the plots", "matplotlib")
        except MissingExtra as exc:
            print(f"(skipped the plots: {exc})", file=sys.stderr)
            plots = False
    out = args.out or f"results/evaluation/{time.strftime('%Y%m%d-%H%M%S')}"
    # No --suite: the benchmark's tracks (the default and the Hard one), each its own leaderboard; so too
    # with several suite names. Otherwise one suite (a name, or scenarios).
    suites = list(BENCHMARK_SUITES) if args.suite is None else args.suite
    several = len(suites) > 1 and all(name in suite_names() for name in suites)
    common = {
        "overwrite": args.force,
        "seed": DEFAULT_SEED if args.seed is None else args.seed,
        "progress": not args.no_progress,
        "plots": plots,
        "vehicle": args.vehicle,
        "env_kwargs": args.env_kwargs,
    }
    # Each environment warns once when an episode leaves the free-surface model's range (broaching
    # episodes pass through it): one line for the run instead of one per environment.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", FreeSurfaceRangeWarning)
        try:
            if several:
                comparisons = run_benchmark(args.controllers, suites, args.episodes, out, **common)
            else:
                comparisons = [run_comparison(args.controllers, suites, args.episodes, out, **common)]
        except (FileExistsError, OutputDirError) as exc:
            raise SystemExit(f"subenv evaluate: --out: {exc}") from None
        except ValueError as exc:
            raise SystemExit(f"subenv evaluate: {exc}") from None
    outside = [w for w in caught if issubclass(w.category, FreeSurfaceRangeWarning)]
    for w in caught:
        if not issubclass(w.category, FreeSurfaceRangeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    if outside:
        print(
            f"(in {len(outside)} of the environments an episode left the free-surface model's range, where "
            f"its suction is extrapolated: shallower than {VALIDITY_DEPTH_RADII:g} hull radii or u^2 / (g h) "
            f"above {VALIDITY_FROUDE_SQUARED:g}, as a broaching boat passes; subenv.dynamics.free_surface)",
            file=sys.stderr,
        )
    print("\n".join(c.leaderboard for c in comparisons))
    episodes = sum(len(c.results) for c in comparisons)
    seconds = sum(c.elapsed_s for c in comparisons)
    print(f"\n{episodes} episodes in {seconds:.1f} s; results in {out}/")
    # A failed controller cost the others nothing (their results are written); the run still did not do
    # what was asked: each failure on one line, and a non-zero status.
    failures = [failure for c in comparisons for failure in c.failures]
    for failure in failures:
        print(f"subenv evaluate: {failure.message}", file=sys.stderr)
    return 1 if failures else 0


def train(argv: Sequence[str]) -> int:
    """``subenv train ...`` is ``python -m subenv_agents.train ...`` (imported by name: the composition
    root)."""
    require("rl", "subenv train", "stable_baselines3", "yaml")
    module = importlib.import_module("subenv_agents.train")
    return int(module.main(list(argv)))


def list_environments(args: argparse.Namespace) -> int:
    """``subenv list``: every registered id and its scenario."""
    from subenv.scenarios import get_scenario, scenario_names

    for name in scenario_names():
        print(f"{get_scenario(name).env_id}: {get_scenario(name).description}")
    print("subenv/DivePlane-v0: the Randomized scenario")
    return 0


def _path(text: str) -> str:
    """An ``--out`` value: any path but the empty one (which would mean the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: must be a path, not empty")
    return text


def _grid_axis(text: str) -> tuple[str, tuple[float, ...]]:
    """``name=v1,v2,...`` or ``name=start:stop:count`` (count points from start to stop)."""
    name, sep, values = text.partition("=")
    try:
        if not sep or not name.strip():
            raise ValueError
        if ":" in values:
            start, stop, count = values.split(":")
            n = int(count)
            if n < 1:
                raise ValueError
            points = tuple(float(v) for v in np.linspace(float(start), float(stop), n))
        else:
            points = tuple(float(v) for v in values.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"invalid value {text!r}: must be name=v1,v2,... or name=start:stop:count"
        ) from None
    return name.strip(), points


_PRINTED_POINTS = 60
"""A sweep with more grid points x controllers than this prints one line per controller (the table is
in success.md)."""

DEFAULT_MAPS: dict[str, list[tuple[str, tuple[float, ...]]]] = {
    "x_GB": [
        ("speed_ratio", tuple(np.round(np.linspace(0.3, 2.0, 10), 6).tolist())),
        ("x_GB_m", tuple(np.round(np.linspace(0.0, 0.003, 7), 6).tolist())),
    ],
    "excess_buoyancy": [
        ("speed_ratio", tuple(np.round(np.linspace(0.3, 2.0, 10), 6).tolist())),
        ("excess_buoyancy_fraction", tuple(np.round(np.linspace(-0.001, 0.001, 9), 6).tolist())),
    ],
}
"""What ``subenv sweep`` without ``--grid`` runs: the two performance maps, over (u/u_cr, x_GB) and over
(u/u_cr, (B - W)/W), each into its own subfolder of ``--out``."""


def sweep(args: argparse.Namespace) -> int:
    """``subenv sweep``: run (or resume) the sweep, or the default maps' two; 130 when interrupted."""
    from subenv.evaluation.rollout import resolve_controllers
    from subenv.sweep import SweepSpec
    from subenv.vehicles import load_vehicle

    require("ray", "subenv sweep", "ray", "pyarrow")  # (before anything is printed or made)
    _installed_controllers(args.controllers)
    try:
        # (on a vehicle without bow planes the default leaves out, and a name is refused, what moves them)
        controllers = [c.name for c in resolve_controllers(args.controllers, load_vehicle(args.vehicle))]
    except ValueError as exc:
        raise SystemExit(f"subenv sweep: {exc}") from None
    grids = {"": args.grid} if args.grid is not None else DEFAULT_MAPS
    try:
        specs = {
            name: SweepSpec(
                controllers=tuple(controllers),
                scenarios=tuple(args.scenarios),
                grid=tuple(grid),
                episodes=args.episodes,
                seed=args.seed,
                vehicle=args.vehicle,
                chunk_episodes=args.chunk_episodes,
            )
            for name, grid in grids.items()
        }
    except ValueError as exc:
        raise SystemExit(f"subenv sweep: {exc}") from None
    out = Path(args.out or f"results/sweep/{time.strftime('%Y%m%d-%H%M%S')}")
    try:
        for name, spec in specs.items():
            if len(specs) > 1:
                print(
                    f"## {name}: " + " x ".join(f"{axis} ({len(values)})" for axis, values in spec.grid),
                    flush=True,
                )
            _sweep_one(spec, out / name if name else out, args)
    except KeyboardInterrupt:  # (Ray is stopped by then; the finished chunks are on disk)
        print(
            f"subenv sweep: interrupted; the same command resumes it from the finished chunks in {out}",
            file=sys.stderr,
        )
        return 130  # (128 + SIGINT, as a shell reports a command ended by Ctrl-C)
    return 0


def _sweep_one(spec: Any, out: Path, args: argparse.Namespace) -> None:
    """Run (or resume) one sweep, print its success per grid point, draw its maps."""
    from subenv.atomic import OutputDirError
    from subenv.sweep import run_sweep

    try:
        path = run_sweep(
            spec, out, address=args.address, num_cpus=args.num_cpus, progress=not args.no_progress
        )
    except (FileExistsError, OutputDirError) as exc:
        raise SystemExit(f"subenv sweep: --out: {exc}") from None
    import pyarrow.parquet as pq

    rows = pq.read_table(path).to_pylist()
    axes = [f"grid_{name}" for name, _ in spec.grid]
    cells: dict[tuple[Any, ...], list[bool]] = {}
    for row in rows:
        cells.setdefault((row["controller"], row["scenario"], *(row[a] for a in axes)), []).append(
            row["success"]
        )
    table = [
        "| controller | scenario | "
        + " | ".join(name for name, _ in spec.grid)
        + (" | " if axes else "")
        + "success |",
        "|---" * (3 + len(axes)) + "|",
    ]
    for key, successes in cells.items():
        values = " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in key)
        table.append(f"| {values} | {sum(successes) / len(successes):.0%} |")
    atomic_write_text(path.parent / "success.md", "\n".join(table) + "\n")
    if len(cells) <= _PRINTED_POINTS:
        print("\n".join(table))
    else:  # (a map's hundreds of points: one line per controller here, every point in success.md)
        for controller in spec.controllers:
            mine = [r["success"] for r in rows if r["controller"] == controller]
            print(f"{controller}: {sum(mine) / len(mine):.0%} success over {len(mine)} episodes")
    print(
        f"\n{len(rows)} episodes; results in {path}, success per grid point in {path.parent / 'success.md'}"
    )
    names = [name for name, _ in spec.grid]
    if not args.no_plots and "speed_ratio" in names and len(names) == 2:
        from subenv.sweep import plot_performance_maps

        try:
            maps = plot_performance_maps(path, path.parent / "maps.png", vehicle=spec.vehicle)
        except MissingExtra as exc:
            print(f"(no performance maps: {exc})", file=sys.stderr)
        else:
            print(f"performance maps in {maps}")


def _names(text: str) -> list[str]:
    """A comma-separated list of names; an empty one (``""``, ``"a,"``, ``"a,,b"``) is refused."""
    names = [name.strip() for name in text.split(",")]
    if not all(names):
        raise argparse.ArgumentTypeError(
            f"invalid value {text!r}: must be comma-separated names, none of them empty"
        )
    return names


def _json_object(text: str) -> dict[str, Any]:
    """A JSON object (``--env-kwargs``); argparse reports a ValueError's type as the usage error."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: not JSON ({exc.msg})") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError(
            f"invalid value {text!r}: must be a JSON object of the environment's arguments, e.g. "
            "'{\"plane_rate_limit_radps\": 0.05}'"
        )
    return value


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="subenv",
        description="Submarine depth control at low speed: a Gymnasium benchmark.",
        epilog="'subenv <command> --help' gives a command's options.",
    )
    sub = parser.add_subparsers(dest="command", title="commands", metavar="<command>")
    p_eval = sub.add_parser("evaluate", help="compare the controllers on a suite of scenarios (the main job)")
    p_eval.add_argument(
        "--controllers", type=_names, help="comma-separated controller names (default: all registered)"
    )
    p_eval.add_argument(
        "--suite",
        type=_names,
        help="a suite name, comma-separated suite names (one leaderboard each, in one results folder), or "
        "comma-separated scenario names (default: 'default,hard', the default and the Hard track)",
    )
    p_eval.add_argument(
        "--episodes", type=int, help="episodes per scenario and controller (default: the suite's)"
    )
    p_eval.add_argument(
        "--seed", type=int, help="base seed; episode i uses seed + i (default: the suite's, 10000)"
    )
    p_eval.add_argument(
        "--out",
        type=_path,
        help="results folder, must not exist unless --force (default: results/evaluation/<date-time>)",
    )
    p_eval.add_argument(
        "--force",
        action="store_true",
        help="replace the results folder if it holds earlier results (it has the marker file)",
    )
    p_eval.add_argument("--no-plots", action="store_true", help="write tables only")
    p_eval.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress on stderr (a bar on a terminal, otherwise a line every 5%%)",
    )
    p_eval.add_argument(
        "--plugins",
        type=_names,
        help="comma-separated Python files (depth_p.py) or modules (here or on the path) that "
        "register controllers when imported; installed packages declare theirs as entry "
        "points and need none",
    )
    p_eval.add_argument(
        "--vehicle",
        default="suboff",
        help="vehicle name or file (default: %(default)s); the scenarios are Froude-scaled to "
        "its length (shipped: " + ", ".join(available_vehicles()) + ")",
    )
    p_eval.add_argument(
        "--env-kwargs",
        type=_json_object,
        metavar="JSON",
        help="the environments' other arguments, a JSON object, e.g. '{\"plane_rate_limit_radps\": 0.05}' "
        "(checked by the environment before anything runs; recorded in run.json; a controller that takes "
        "them, such as mpc, is told them: name it <name>:uninformed to run it untold)",
    )
    p_eval.add_argument("--list", action="store_true", help="list the controllers and suites, and exit")
    p_demo = sub.add_parser("demo", help="fly the thesis controller above and below the critical speed")
    p_demo.add_argument("--env", default="subenv/Nominal-v0", help="environment id (default: %(default)s)")
    p_demo.add_argument(
        "--low-env",
        default="subenv/LowSpeed-v0",
        help="environment id for the low-speed run (default: %(default)s)",
    )
    p_demo.add_argument(
        "--low-speed",
        type=float,
        default=0.45,
        help="the speed below critical to fly, m/s (default: %(default)s)",
    )
    p_demo.add_argument("--seed", type=int, default=0, help="reset seed (default: %(default)s)")
    p_demo.add_argument(
        "--out", type=_path, default="results/demo.png", help="plot file (default: %(default)s)"
    )
    p_demo.add_argument("--no-plot", action="store_true", help="print the summary only")
    p_analyze = sub.add_parser("analyze", help="recompute the numbers of Riedel (1993), into report.json")
    p_analyze.add_argument(
        "--out", type=_path, default="results/analysis", help="output folder (default: %(default)s)"
    )
    p_analyze.add_argument("--vehicle", default="suboff", help="vehicle name or file (default: %(default)s)")
    p_analyze.add_argument(
        "--force",
        action="store_true",
        help="replace the folder if it holds an earlier report (it has the marker file)",
    )
    p_sweep = sub.add_parser("sweep", help="run controllers over a grid of physics parameters, on Ray")
    p_sweep.add_argument(
        "--controllers", type=_names, help="comma-separated controller names (default: all registered)"
    )
    p_sweep.add_argument(
        "--scenarios",
        type=_names,
        default=["LowSpeed"],
        help="comma-separated scenario names (default: LowSpeed)",
    )
    p_sweep.add_argument(
        "--grid",
        type=_grid_axis,
        action="append",
        help="a grid axis, name=v1,v2,... or name=start:stop:count, repeatable; names: "
        + ", ".join(sorted(PARAMETERS))
        + " (default: the two performance maps, speed_ratio=0.3:2:10 with "
        "x_GB_m=0:0.003:7, and with excess_buoyancy_fraction=-0.001:0.001:9)",
    )
    p_sweep.add_argument(
        "--episodes", type=int, default=20, help="episodes per grid point (default: %(default)s)"
    )
    p_sweep.add_argument("--seed", type=int, default=10000, help="base seed (default: %(default)s)")
    p_sweep.add_argument("--vehicle", default="suboff", help="vehicle name or file (default: %(default)s)")
    p_sweep.add_argument(
        "--chunk-episodes", type=int, default=50, help="episodes per Ray task (default: %(default)s)"
    )
    p_sweep.add_argument(
        "--out",
        type=_path,
        help="results folder; the same arguments again resume it (default: results/sweep/<date-time>)",
    )
    p_sweep.add_argument(
        "--address", help="a Ray cluster's address (e.g. auto); default: a local Ray instance"
    )
    p_sweep.add_argument("--num-cpus", type=int, help="CPUs of the local Ray instance (default: all)")
    p_sweep.add_argument("--no-progress", action="store_true", help="no progress on stderr")
    p_sweep.add_argument(
        "--no-plots",
        action="store_true",
        help="no performance maps (drawn when the grid is speed_ratio and one other axis)",
    )
    sub.add_parser("list", help="list the environment ids and their scenarios")
    sub.add_parser("train", add_help=False, help="train a Stable-Baselines3 agent (needs the 'rl' extra)")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run a command; without one, print the help on stderr and return 2 (argparse's usage-error status)."""
    parser = _parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if argv[:1] == ["train"]:
            return train(argv[1:])
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help(sys.stderr)
            return 2
        commands = {
            "evaluate": evaluate,
            "demo": demo,
            "analyze": analyze,
            "list": list_environments,
            "sweep": sweep,
        }
        return commands[args.command](args)
    except MissingExtra as exc:
        raise SystemExit(f"subenv {argv[0]}: {exc}") from None


if __name__ == "__main__":
    sys.exit(main())
