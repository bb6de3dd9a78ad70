"""Evaluation sweeps over the physics' parameters on Ray: controllers x scenarios x a grid x seeds.

A sweep pins some of a scenario's drawn quantities to each point of a grid (speed as u / u_cr,
ballast offset x_GB, excess buoyancy, metacentric height z_GB, cross-flow drag, disturbance) and
runs every controller on the same seeded episodes at every point, with the batched harness
(:func:`subenv.evaluation.run_episodes`). The work is cut into chunks (one controller, one grid
point, a range of seeds), run as Ray tasks: on a local Ray instance by default, on a cluster with
``address``. Per-episode results are those of the serial harness for the same seeds.

The results folder ``out_dir`` (made if missing; one that holds another sweep is refused)::

    sweep.json          the sweep (controllers, scenarios, grid, episodes, seed, vehicle)
    chunks/<id>.parquet each finished chunk's rows, written whole (a temporary name, then a rename)
    manifest.json       the finished chunks, rewritten (atomically) after each one
    results.parquet     every row, in grid order; written as soon as every chunk is done

A sweep that is interrupted (Ctrl-C, a lost driver) is resumed by running it again with the same
arguments: finished chunks are read back, not run again; a chunk file that does not read back whole
(truncated, damaged) is reported on stderr in one line and its chunk run again; a chunk whose worker
died is retried by Ray (``max_retries``), so no row is lost or duplicated. Needs the ``ray`` extra
(Ray and pyarrow).

Ray's processes. A local Ray instance the sweep starts, it stops on every way out of
:func:`run_sweep` (the end, an error, Ctrl-C; a Ctrl-C during the stop is held until Ray has
stopped); a Ray the caller started (``ray.init`` before, or the cluster at ``address``) is left
running. A driver killed with SIGKILL stops nothing itself: on Linux Ray binds its head processes
(GCS server, raylet) to the driver (``PR_SET_PDEATHSIG``), so the kernel ends them with it and the
workers exit within seconds of losing the raylet; its dashboard agent and runtime-env agent notice
later and exit within about a minute (65 s measured here, Ray 2.60). ``ray stop`` ends them at once,
with every other Ray instance of the same user on the machine.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import itertools
import json
import math
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from subenv.atomic import OutputDirError, atomic_write_bytes, atomic_write_text
from subenv.envs._interrupts import interrupts_deferred
from subenv.evaluation.suites import DEFAULT_SEED
from subenv.extras import require
from subenv.scenarios import get_scenario, scenario_names
from subenv.scenarios.scenario import Scenario

__all__ = ["PARAMETERS", "Chunk", "SweepSpec", "plot_performance_maps", "run_chunk", "run_sweep"]

PARAMETERS: Final = {
    "speed_ratio": "initial speed as u / u_cr (a scenario with speeds in m/s gets its speed_mps instead)",
    "x_GB_m": "ballast offset x_GB [m] (Riedel 1993 Ch. IV)",
    "excess_buoyancy_fraction": "(B - W) / W",
    "z_GB_m": "metacentric height z_GB [m]",
    "crossflow_drag": "hull cross-flow drag coefficient C_D",
    "disturbance_std_N": "standard deviation of the heave-force disturbance [N]",
}
"""The scenario quantities a sweep's grid may pin, and what each is."""
CHUNK_EPISODES: Final = 50
"""Episodes per chunk by default: a chunk is a few seconds of work on one core, so the scheduling
overhead of a task (milliseconds) is negligible, and a lost worker costs little."""
TASK_RETRIES: Final = 3
"""Times Ray runs a chunk again whose worker died (Ray's ``max_retries``)."""
_SPEC_FILE, _MANIFEST_FILE, _RESULTS_FILE, _CHUNKS_DIR = (
    "sweep.json",
    "manifest.json",
    "results.parquet",
    "chunks",
)


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep runs: the grid is the product of every parameter's values, in the order given."""

    controllers: tuple[str, ...]
    scenarios: tuple[str, ...]
    grid: tuple[tuple[str, tuple[float, ...]], ...]
    episodes: int
    seed: int = DEFAULT_SEED
    vehicle: str = "suboff"
    chunk_episodes: int = CHUNK_EPISODES

    def __post_init__(self) -> None:
        if not self.controllers or not self.scenarios:
            raise ValueError("controllers and scenarios must each name at least one")
        unknown = [s for s in self.scenarios if s not in scenario_names()]
        if unknown:
            raise ValueError(f"scenarios {unknown} are unknown: must be among {scenario_names()}")
        for name, values in self.grid:
            if name not in PARAMETERS:
                raise ValueError(f"grid parameter {name!r} is unknown: must be one of {sorted(PARAMETERS)}")
            if not values or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
                raise ValueError(
                    f"grid[{name!r}]={list(values)!r} is invalid: must be one or more finite numbers"
                )
        for name, value, low in (
            ("episodes", self.episodes, 1),
            ("seed", self.seed, 0),
            ("chunk_episodes", self.chunk_episodes, 1),
        ):
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= low):
                raise ValueError(f"{name}={value!r} is invalid: must be an integer >= {low}")

    @property
    def points(self) -> list[dict[str, float]]:
        """The grid's points, each parameter -> value (one empty point without a grid)."""
        names = [name for name, _ in self.grid]
        return [
            dict(zip(names, values, strict=True)) for values in itertools.product(*(v for _, v in self.grid))
        ]

    def chunks(self) -> list[Chunk]:
        """Every chunk of the sweep, in the order of the results table."""
        return [
            Chunk(
                controller,
                scenario,
                tuple(point.items()),
                first,
                min(self.chunk_episodes, self.episodes - first),
            )
            for controller in self.controllers
            for scenario in self.scenarios
            for point in self.points
            for first in range(0, self.episodes, self.chunk_episodes)
        ]

    def as_dict(self) -> dict[str, Any]:
        """The sweep as JSON data (what ``sweep.json`` holds; the grid as parameter -> values)."""
        return {**dataclasses.asdict(self), "grid": {name: list(values) for name, values in self.grid}}


@dataclass(frozen=True)
class Chunk:
    """One controller on one grid point of one scenario, episodes ``first .. first + count - 1``."""

    controller: str
    scenario: str
    point: tuple[tuple[str, float], ...]
    first: int
    count: int

    @property
    def id(self) -> str:
        """A name that identifies the chunk's work (stable across runs: the resume key)."""
        text = json.dumps([self.controller, self.scenario, self.point, self.first, self.count])
        return f"{self.controller}-{self.scenario}-{hashlib.sha256(text.encode()).hexdigest()[:16]}"

    def scenario_at_point(self) -> Scenario:
        """The scenario with the point's quantities pinned (an interval of one value)."""
        base = get_scenario(self.scenario)
        changes: dict[str, Any] = {}
        for name, value in self.point:
            if name == "speed_ratio" and not base.speed_relative:
                changes["speed_mps"] = None
            if name == "disturbance_std_N":
                changes[name] = float(value)
            else:
                changes[name] = (float(value), float(value))
        return base.replace(**changes)


def run_chunk(chunk: Chunk, seed: int, vehicle: str = "suboff") -> list[dict[str, Any]]:
    """The rows of one chunk: :func:`subenv.evaluation.run_episodes` on seeds ``seed + first ..``, each
    row with the grid point's values (the task a Ray worker runs; also callable directly)."""
    from subenv.evaluation import discover_controllers, make_controller, run_episodes

    discover_controllers()  # (a fresh worker process registers the installed controllers)
    controller = make_controller(chunk.controller)
    results = run_episodes(
        controller,
        chunk.scenario_at_point(),
        range(seed + chunk.first, seed + chunk.first + chunk.count),
        first_episode=chunk.first,
        vehicle=vehicle,
    )
    point = {f"grid_{name}": value for name, value in chunk.point}
    return [{**r.row(), **point, "chunk": chunk.id} for r in results]


def _write_table(path: Path, rows: Sequence[Mapping[str, Any]]) -> None:
    """A Parquet file of ``rows``, complete or absent (:func:`subenv.atomic.atomic_write_bytes`)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    sink = pa.BufferOutputStream()
    pq.write_table(pa.Table.from_pylist(list(rows)), sink)
    atomic_write_bytes(path, sink.getvalue().to_pybytes())


def _read_rows(path: Path) -> list[dict[str, Any]]:
    import pyarrow.parquet as pq

    return pq.read_table(path).to_pylist()


def _finished_chunks(out: Path, chunks: Sequence[Chunk]) -> dict[str, list[dict[str, Any]]]:
    """The rows of each chunk whose file in ``out`` reads back whole, by chunk id; a file that does
    not (truncated, damaged) is named on stderr in one line, and its chunk left to run again."""
    import pyarrow as pa

    finished = {}
    for chunk in chunks:
        path = out / _CHUNKS_DIR / f"{chunk.id}.parquet"
        if not path.exists():
            continue
        try:
            rows = _read_rows(path)
            if len(rows) != chunk.count or any(row.get("chunk") != chunk.id for row in rows):
                raise ValueError(f"{len(rows)} rows, not the chunk's {chunk.count}")
        except (OSError, ValueError, pa.ArrowException) as exc:
            reason = (str(exc).splitlines() or [type(exc).__name__])[0]
            print(f"(sweep: {path} does not read back: {reason}; running its chunk again)", file=sys.stderr)
            continue
        finished[chunk.id] = rows
    return finished


def _stop_ray(ray: Any) -> None:
    """``ray.shutdown()`` with Ctrl-C held until it is done (interrupted, it would leave Ray's processes
    running)."""
    with interrupts_deferred():
        ray.shutdown()


def run_sweep(
    spec: SweepSpec,
    out_dir: str | os.PathLike[str],
    *,
    address: str | None = None,
    num_cpus: int | None = None,
    progress: bool = True,
) -> Path:
    """Run (or resume) ``spec`` on Ray and write ``out_dir`` (the module docstring lists it).

    Parameters
    ----------
    address : str, optional
        A Ray cluster (``ray.init(address=...)``, e.g. ``"auto"``); None starts a local instance.
        Either is used only where Ray is not initialised already; the sweep stops only a Ray it started.
    num_cpus : int, optional
        CPUs of the local instance (Ray's default: all).
    progress : bool
        Chunks done, and the time left, on stderr.

    Returns
    -------
    Path
        The path of ``results.parquet``.

    Raises
    ------
    FileExistsError
        If ``out_dir`` is a file or holds another sweep (its ``sweep.json`` differs) or files that are
        no sweep's (no ``sweep.json``).
    OutputDirError
        If ``out_dir`` cannot be created.
    """
    require("ray", "subenv sweep", "ray", "pyarrow")
    import ray

    from subenv.evaluation.progress import Progress

    out = Path(out_dir)
    stored = out / _SPEC_FILE
    wanted = json.dumps(spec.as_dict(), indent=2, sort_keys=True) + "\n"
    if os.path.lexists(out) and not out.is_dir():
        raise FileExistsError(f"output folder {str(out)!r} exists and is not a folder: choose another folder")
    if stored.exists() and stored.read_text() != wanted:
        raise FileExistsError(
            f"{str(out)!r} holds another sweep (its {_SPEC_FILE} differs): choose another folder"
        )
    if out.is_dir() and not stored.exists() and any(out.iterdir()):
        # (a sweep writes its sweep.json first: a folder with files and without one is not a sweep's)
        raise FileExistsError(
            f"output folder {str(out)!r} holds files and no {_SPEC_FILE}: it is not a sweep's to resume; "
            "choose an empty or new folder"
        )
    try:
        (out / _CHUNKS_DIR).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputDirError(f"output folder {str(out)!r} cannot be created: {exc.strerror or exc}") from exc
    if not stored.exists():
        atomic_write_text(stored, wanted)
    chunks = spec.chunks()
    finished = _finished_chunks(out, chunks)
    todo = [c for c in chunks if c.id not in finished]

    def record() -> None:
        atomic_write_text(
            out / _MANIFEST_FILE,
            json.dumps({"chunks": len(chunks), "finished": sorted(finished)}, indent=2) + "\n",
        )

    with contextlib.ExitStack() as cleanup:  # (its callbacks run, last first, however the block ends)
        if todo:
            if not ray.is_initialized():  # (registered first: a start that is interrupted is stopped too)
                cleanup.callback(_stop_ray, ray)
                ray.init(
                    address=address,
                    num_cpus=num_cpus,
                    include_dashboard=False,
                    log_to_driver=False,
                    configure_logging=False,
                )
            bar = Progress(len(todo), enabled=progress, label="sweep", unit="chunk")
            cleanup.callback(bar.close)
            task = ray.remote(max_retries=TASK_RETRIES)(run_chunk)
            pending = {task.remote(c, spec.seed, spec.vehicle): c for c in todo}
            while pending:
                (done,), _ = ray.wait(list(pending), num_returns=1)
                chunk = pending.pop(done)
                rows = ray.get(done)
                _write_table(out / _CHUNKS_DIR / f"{chunk.id}.parquet", rows)
                finished[chunk.id] = rows
                record()
                bar.describe(f"{chunk.controller} on {chunk.scenario}")
                bar.update(1)
        # The table is written as soon as every chunk is done, before Ray is stopped.
        record()
        _write_table(out / _RESULTS_FILE, [row for c in chunks for row in finished[c.id]])
    return out / _RESULTS_FILE


def plot_performance_maps(
    results: str | os.PathLike[str], out: str | os.PathLike[str], vehicle: str = "suboff"
) -> Path:
    """Success rate and plane effort over a sweep's two grid axes, one column per controller, with the
    physics overlaid.

    The x axis is u / u_cr (``grid_speed_ratio``), the y axis the sweep's other parameter (x_GB as
    x_GB / L, excess buoyancy as (B - W) / W). Top row: the success rate; bottom row: the mean plane RMS
    [rad] (sqrt of the time mean of stern^2 + bow^2), one colour scale for all controllers. Overlaid: the
    critical speed (u / u_cr = 1, Riedel 1993 eq. 3.9); the fold (hysteresis) set of one plane command
    (alpha = 0), where two steady states merge and the steady pitch jumps (eq. 4.3;
    :func:`subenv.analysis.exact_bifurcation_set` for x_GB, :func:`subenv.analysis.buoyancy_bifurcation_set`
    for the excess buoyancy); with x_GB on the y axis, the saturation cusp for one plane command (beyond it
    the depth-holding state needs more than the plane limit, eqs 4.43-4.45,
    :func:`subenv.analysis.saturation_cusp`); and, hatched, the grid points whose episodes have no
    depth-holding trim within the limits for any allocation (the ``winnable`` column: no controller can win
    there). Written whole or not at all. Needs the ``plot`` extra.
    """
    require("plot", "the performance maps", "matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.patches import Rectangle

    from subenv.analysis import (
        buoyancy_bifurcation_set,
        critical_speed,
        exact_bifurcation_set,
        saturation_cusp,
    )
    from subenv.evaluation.plots import save_figure
    from subenv.vehicles import load_vehicle

    rows = _read_rows(Path(results))
    axes_names = [k for k in rows[0] if k.startswith("grid_")]
    if "grid_speed_ratio" not in axes_names or len(axes_names) != 2:
        raise ValueError(
            f"a performance map needs grid_speed_ratio and one other grid axis; the sweep has {axes_names}"
        )
    other = next(a for a in axes_names if a != "grid_speed_ratio")
    boat = load_vehicle(vehicle)
    scale = 1.0 / boat.length_m if other == "grid_x_GB_m" else 1.0
    label = {"grid_x_GB_m": "x_GB / L", "grid_excess_buoyancy_fraction": "(B - W) / W"}.get(other, other[5:])
    xs = sorted({r["grid_speed_ratio"] for r in rows})
    ys = sorted({r[other] for r in rows})
    controllers = list(dict.fromkeys(r["controller"] for r in rows))
    shape = (len(ys), len(xs))
    success, effort = (
        {c: np.full(shape, np.nan) for c in controllers},
        {c: np.full(shape, np.nan) for c in controllers},
    )
    blocked = np.zeros(shape, dtype=bool)
    for (c, x, y), cell in _cells(rows, other).items():
        j, i = ys.index(y), xs.index(x)
        success[c][j, i] = float(np.mean([r["success"] for r in cell]))
        effort[c][j, i] = float(np.mean([r["plane_rms_rad"] for r in cell]))
        blocked[j, i] |= not all(r["winnable"] for r in cell)
    # The physics, over the plotted speeds (alpha = 0: one plane command, the allocation of lqr and thesis).
    ucr = critical_speed(boat)
    ratios = np.linspace(min(xs), max(xs), 120)
    curves: list[tuple[np.ndarray, str, str]] = []
    if other == "grid_x_GB_m":
        curves += [(c * scale, "tab:red", "-") for c in saturation_cusp(boat, ratios * ucr)]
        curves += [(c * scale, "white", ":") for c in exact_bifurcation_set(boat, ratios * ucr)]
    elif other == "grid_excess_buoyancy_fraction":
        curves += [(c, "white", ":") for c in buoyancy_bifurcation_set(boat, ratios * ucr)]
    x_edges, y_edges = _edges(xs), _edges([y * scale for y in ys])
    effort_max = max(float(np.nanmax(e)) for e in effort.values())
    fig, panels = plt.subplots(
        2,
        len(controllers),
        figsize=(3.4 * len(controllers) + 1.4, 6.6),
        sharex=True,
        sharey=True,
        layout="constrained",
        squeeze=False,
    )
    images = []
    for k, controller in enumerate(controllers):
        for row, (values, cmap, vmax) in enumerate(
            ((success[controller], "viridis", 1.0), (effort[controller], "magma", effort_max))
        ):
            ax = panels[row][k]
            images.append(
                ax.pcolormesh(x_edges, y_edges, values, vmin=0.0, vmax=vmax, cmap=cmap, shading="flat")
            )
            for j, i in zip(*np.nonzero(blocked), strict=True):  # whole cells, hatched
                ax.add_patch(
                    Rectangle(
                        (x_edges[i], y_edges[j]),
                        x_edges[i + 1] - x_edges[i],
                        y_edges[j + 1] - y_edges[j],
                        fill=False,
                        hatch="xx",
                        edgecolor="0.8" if row == 0 else "0.2",
                        lw=0.0,
                    )
                )
            ax.axvline(1.0, color="w", ls="--", lw=1.2)
            for curve, color, style in curves:
                ax.plot(ratios, curve, color=color, ls=style, lw=1.4)
            ax.set_ylim(y_edges[0], y_edges[-1])
            if row == 0:
                ax.set_title(controller)
            else:
                ax.set_xlabel("u / u_cr")
        panels[0][k].set_xlim(x_edges[0], x_edges[-1])
    panels[0][0].set_ylabel(f"{label}\n(success)")
    panels[1][0].set_ylabel(f"{label}\n(plane RMS)")
    fig.colorbar(images[0], ax=panels[0].tolist(), label="success rate")
    fig.colorbar(images[1], ax=panels[1].tolist(), label="plane RMS [rad]")
    cusp = "; red: the saturation cusp" if other == "grid_x_GB_m" else ""
    fig.suptitle(
        "Dashed: the critical speed; dotted: the fold (hysteresis) set of one plane command (alpha = 0)"
        f"{cusp};\nhatched: no depth-holding trim within the limits for any allocation "
        "(no controller can win)",
        fontsize="medium",
    )
    path = save_figure(fig, out)
    plt.close(fig)
    return path


def _cells(rows: Sequence[Mapping[str, Any]], other: str) -> dict[tuple[Any, ...], list[Mapping[str, Any]]]:
    """The rows of each (controller, speed ratio, other axis) grid cell."""
    cells: dict[tuple[Any, ...], list[Mapping[str, Any]]] = {}
    for r in rows:
        cells.setdefault((r["controller"], r["grid_speed_ratio"], r[other]), []).append(r)
    return cells


def _edges(centres: Sequence[float]) -> list[float]:
    """Cell edges around sorted centres (half-way between neighbours)."""
    c = list(centres)
    if len(c) == 1:
        return [c[0] - 0.5, c[0] + 0.5]
    mids = [(a + b) / 2 for a, b in itertools.pairwise(c)]
    return [c[0] - (mids[0] - c[0]), *mids, c[-1] + (c[-1] - mids[-1])]
