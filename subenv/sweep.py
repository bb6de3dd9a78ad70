"""Evaluation sweeps over the physics' parameters on Ray: controllers x scenarios x a grid x seeds.

A sweep pins some of a scenario's drawn quantities to each point of a grid (speed as u / u_cr,
ballast offset x_GB, excess buoyancy, metacentric height z_GB, cross-flow drag, disturbance) and
runs every controller on the same seeded episodes at every point, with the batched harness
(:func:`subenv.evaluation.run_episodes`). The work is cut into chunks (one controller, one grid
point, a range of seeds), run as Ray tasks: on a local Ray instance by default, on a cluster with
``address``. Per-episode results are those of the serial harness for the same seeds.

The results folder ``out_dir``::

    sweep.json          the sweep (controllers, scenarios, grid, episodes, seed, vehicle)
    chunks/<id>.parquet each finished chunk's rows, written whole (a temporary name, then a rename)
    manifest.json       the finished chunks, rewritten (atomically) after each one
    results.parquet     every row, in grid order; written last, when every chunk is done

A sweep that is interrupted (Ctrl-C, a lost driver) is resumed by running it again with the same
arguments: finished chunks are read back, not run again; a chunk whose worker died is retried by
Ray (``max_retries``), so no row is lost or duplicated. Needs the ``ray`` extra (Ray and pyarrow).
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from subenv.atomic import atomic_write_bytes, atomic_write_text
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
_SPEC_FILE, _MANIFEST_FILE, _RESULTS_FILE, _CHUNKS_DIR = "sweep.json", "manifest.json", "results.parquet", "chunks"


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
                raise ValueError(f"grid[{name!r}]={list(values)!r} is invalid: must be one or more finite numbers")
        for name, value, low in (("episodes", self.episodes, 1), ("seed", self.seed, 0),
                                 ("chunk_episodes", self.chunk_episodes, 1)):
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= low):
                raise ValueError(f"{name}={value!r} is invalid: must be an integer >= {low}")

    @property
    def points(self) -> list[dict[str, float]]:
        """The grid's points, each parameter -> value (one empty point without a grid)."""
        names = [name for name, _ in self.grid]
        return [dict(zip(names, values)) for values in itertools.product(*(v for _, v in self.grid))]

    def chunks(self) -> list[Chunk]:
        """Every chunk of the sweep, in the order of the results table."""
        return [Chunk(controller, scenario, tuple(point.items()), first, min(self.chunk_episodes, self.episodes - first))
                for controller in self.controllers for scenario in self.scenarios for point in self.points
                for first in range(0, self.episodes, self.chunk_episodes)]

    def as_dict(self) -> dict[str, Any]:
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
    results = run_episodes(controller, chunk.scenario_at_point(), range(seed + chunk.first, seed + chunk.first
                                                                         + chunk.count),
                           first_episode=chunk.first, vehicle=vehicle)
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

    return pq.read_table(path).to_pylist()  # type: ignore[no-any-return]


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
    num_cpus : int, optional
        CPUs of the local instance (Ray's default: all).
    progress : bool
        Chunks done, and the time left, on stderr.

    Returns the path of ``results.parquet``. Raises ``FileExistsError`` if ``out_dir`` holds another
    sweep (its ``sweep.json`` differs).
    """
    require("ray", "subenv sweep", "ray", "pyarrow")
    import ray

    from subenv.evaluation.progress import Progress

    out = Path(out_dir)
    stored = out / _SPEC_FILE
    wanted = json.dumps(spec.as_dict(), indent=2, sort_keys=True) + "\n"
    if stored.exists() and stored.read_text() != wanted:
        raise FileExistsError(f"{str(out)!r} holds another sweep (its {_SPEC_FILE} differs): choose another folder")
    (out / _CHUNKS_DIR).mkdir(parents=True, exist_ok=True)
    if not stored.exists():
        atomic_write_text(stored, wanted)
    chunks = spec.chunks()
    finished = {p.stem for p in (out / _CHUNKS_DIR).glob("*.parquet")}  # (each written whole)
    todo = [c for c in chunks if c.id not in finished]

    def record() -> None:
        atomic_write_text(out / _MANIFEST_FILE, json.dumps(
            {"chunks": len(chunks), "finished": sorted(finished)}, indent=2) + "\n")

    if todo:
        started_here = not ray.is_initialized()
        if started_here:
            ray.init(address=address, num_cpus=num_cpus, include_dashboard=False, log_to_driver=False,
                     configure_logging=False)
        bar = Progress(len(todo), enabled=progress, label="sweep", unit="chunk")
        try:
            task = ray.remote(max_retries=TASK_RETRIES)(run_chunk)
            pending = {task.remote(c, spec.seed, spec.vehicle): c for c in todo}
            while pending:
                (done,), _ = ray.wait(list(pending), num_returns=1)
                chunk = pending.pop(done)
                _write_table(out / _CHUNKS_DIR / f"{chunk.id}.parquet", ray.get(done))
                finished.add(chunk.id)
                record()
                bar.describe(f"{chunk.controller} on {chunk.scenario}")
                bar.update(1)
        finally:
            bar.close()
            if started_here:
                ray.shutdown()
    record()
    rows = [row for c in chunks for row in _read_rows(out / _CHUNKS_DIR / f"{c.id}.parquet")]
    _write_table(out / _RESULTS_FILE, rows)
    return out / _RESULTS_FILE


def plot_performance_maps(results: str | os.PathLike[str], out: str | os.PathLike[str],
                          vehicle: str = "suboff") -> Path:
    """Success rate over a sweep's two grid axes, one panel per controller, with the physics overlaid.

    The x axis is u / u_cr (``grid_speed_ratio``), the y axis the sweep's other parameter (x_GB as
    x_GB / L). Overlaid: the critical speed (u / u_cr = 1, Riedel 1993 eq. 3.9); with x_GB on the y axis,
    the saturation cusp for one plane command (alpha = 0: beyond it the depth-holding state of dual
    control needs more than the plane limit, eqs 4.43-4.45, :func:`subenv.analysis.saturation_cusp`);
    and, hatched, the grid points whose episodes have no depth-holding trim within the limits for any
    allocation (the ``winnable`` column: no controller can win there). Needs the ``plot`` extra.
    """
    require("plot", "the performance maps", "matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from subenv.analysis import critical_speed, saturation_cusp
    from subenv.vehicles import load_vehicle

    rows = _read_rows(Path(results))
    axes_names = [k for k in rows[0] if k.startswith("grid_")]
    if "grid_speed_ratio" not in axes_names or len(axes_names) != 2:
        raise ValueError(f"a performance map needs grid_speed_ratio and one other grid axis; the sweep has {axes_names}")
    other = next(a for a in axes_names if a != "grid_speed_ratio")
    boat = load_vehicle(vehicle)
    scale = 1.0 / boat.length_m if other == "grid_x_GB_m" else 1.0
    label = {"grid_x_GB_m": "x_GB / L", "grid_excess_buoyancy_fraction": "(B - W) / W"}.get(other, other[5:])
    xs = sorted({r["grid_speed_ratio"] for r in rows})
    ys = sorted({r[other] for r in rows})
    controllers = list(dict.fromkeys(r["controller"] for r in rows))
    fig, panels = plt.subplots(1, len(controllers), figsize=(3.6 * len(controllers) + 1.2, 3.8), sharey=True,
                               layout="constrained", squeeze=False)
    image = None
    for ax, controller in zip(panels[0], controllers):
        success = np.full((len(ys), len(xs)), np.nan)
        blocked = np.zeros((len(ys), len(xs)), dtype=bool)
        for j, y in enumerate(ys):
            for i, x in enumerate(xs):
                cell = [r for r in rows if r["controller"] == controller and r["grid_speed_ratio"] == x and r[other] == y]
                if cell:
                    success[j, i] = float(np.mean([r["success"] for r in cell]))
                    blocked[j, i] = not all(r["winnable"] for r in cell)
        image = ax.pcolormesh(_edges(xs), _edges([y * scale for y in ys]), success, vmin=0.0, vmax=1.0,
                              cmap="viridis", shading="flat")
        ax.contourf(xs, [y * scale for y in ys], blocked.astype(float), levels=[0.5, 1.5], colors="none",
                    hatches=["xx"])
        ax.axvline(1.0, color="w", ls="--", lw=1.2)
        if other == "grid_x_GB_m":
            ucr = critical_speed(boat)
            ratios = np.linspace(min(xs), max(xs), 200)
            x_plus, x_minus = saturation_cusp(boat, ratios * ucr)
            ax.plot(ratios, x_plus * scale, color="tab:red", lw=1.2)
            ax.plot(ratios, x_minus * scale, color="tab:red", lw=1.2)
            ax.set_ylim(min(ys) * scale, max(ys) * scale) if min(ys) != max(ys) else None
        ax.set(title=controller, xlabel="u / u_cr")
    panels[0][0].set_ylabel(label)
    fig.colorbar(image, ax=panels[0].tolist(), label="success rate")
    fig.suptitle("Success over the sweep's grid. Dashed: the critical speed; red: the saturation cusp "
                 "(alpha = 0);\nhatched: no depth-holding trim within the limits (no controller can win)",
                 fontsize="medium")
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def _edges(centres: Sequence[float]) -> list[float]:
    """Cell edges around sorted centres (half-way between neighbours)."""
    c = list(centres)
    if len(c) == 1:
        return [c[0] - 0.5, c[0] + 0.5]
    mids = [(a + b) / 2 for a, b in itertools.pairwise(c)]
    return [c[0] - (mids[0] - c[0]), *mids, c[-1] + (c[-1] - mids[-1])]
