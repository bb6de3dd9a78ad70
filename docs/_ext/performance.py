"""The performance pages' figures and tables, drawn from the benchmarks' JSON records.

A record (``benchmarks/_record.py``) holds what a benchmark printed, its Markdown tables as cells, with
the machine, the date and the command. This module writes, for each record in ``benchmarks/records/``,
a page ``<benchmark>.md``: where and when it ran, its figures, and its tables as recorded.
No measured number is typed into the documentation.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

RESULTS = Path(__file__).resolve().parents[2] / "benchmarks" / "records"
FORMAT = 1


def number(cell: str) -> float:
    """A printed cell as a number (``1,395,734`` -> 1395734.0; ``23.3`` -> 23.3); NaN if it is none."""
    text = cell.replace(",", "").replace("**", "").removesuffix("x").strip()
    for unit in (" MiB", " s", " ns"):
        text = text.removesuffix(unit)
    try:
        return float(text)
    except ValueError:
        return math.nan


def _table_markdown(table: dict[str, Any]) -> str:
    columns = table["columns"]
    lines = ["| " + " | ".join(columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in table["rows"]]
    return "\n".join(lines)


def _section(record: dict[str, Any], title: str) -> list[dict[str, Any]]:
    return next((s["tables"] for s in record["sections"] if s["title"].startswith(title)), [])


def _vector_figure(tables: list[dict[str, Any]], path: Path) -> bool:
    """Env-steps/s against the number of sub-environments, log-log: the native vector env on its
    threads and on one, SyncVectorEnv, and Gymnasium's CartPoleVectorEnv."""
    if not tables:
        return False
    table = tables[0]
    col = {name: k for k, name in enumerate(table["columns"])}
    ids = list(dict.fromkeys(row[col["environment"]] for row in table["rows"]))
    fig, axes = plt.subplots(1, len(ids), figsize=(5.2 * len(ids), 4.2), sharey=True, layout="constrained")
    for ax, env_id in zip(list(axes) if len(ids) > 1 else [axes], ids, strict=True):
        rows = [r for r in table["rows"] if r[col["environment"]] == env_id]
        n = [number(r[col["N"]]) for r in rows]
        for name, style in (
            ("native env-steps/s", "o-"),
            ("native, 1 thread", "s--"),
            ("SyncVectorEnv", "^-"),
            ("CartPoleVectorEnv", "x:"),
        ):
            if name not in col:
                continue
            label = name.removesuffix(" env-steps/s")
            ax.loglog(n, [number(r[col[name]]) for r in rows], style, label=label)
        ax.set(title=env_id, xlabel="sub-environments N")
        ax.grid(alpha=0.3, which="both")
    (axes[0] if len(ids) > 1 else axes).set_ylabel("env-steps per second")
    (axes[-1] if len(ids) > 1 else axes).legend(fontsize="small")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return True


def _single_figure(tables: list[dict[str, Any]], path: Path) -> bool:
    """Steps/s of one environment, raw and through gym.make, next to Gymnasium's."""
    if not tables:
        return False
    table = tables[0]
    col = {name: k for k, name in enumerate(table["columns"])}
    names = [r[col["environment"]] for r in table["rows"]]
    fig, ax = plt.subplots(figsize=(8.5, 3.6), layout="constrained")
    y = range(len(names))
    for offset, name in ((-0.2, "raw steps/s"), (0.2, "gym.make steps/s")):
        if name not in col:
            continue
        ax.barh(
            [k + offset for k in y], [number(r[col[name]]) for r in table["rows"]], height=0.4, label=name
        )
    ax.set_yticks(list(y), names)
    ax.invert_yaxis()
    ax.set(xlabel="steps per second, one environment")
    ax.legend(fontsize="small", loc="lower right")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return True


def record_page(record: dict[str, Any], figures: Path, prefix: str) -> str:
    """A record's page (MyST): its provenance, its figures (written into ``figures``), its tables."""
    if record.get("format") != FORMAT:
        raise ValueError(
            f"benchmark record of format {record.get('format')!r}: this page reads format {FORMAT}"
        )
    lines = [
        f"# Measured: `benchmarks/{record['benchmark']}.py`",
        "",
        f"Measured on {record['date'][:10]} ({record['date']}), on: {record['machine']}.",
        "",
        f"Command: `{record['command']}`.",
        "",
    ]
    if "probe_before" in record:
        lines += [
            f"Free cores, a compiled loop on one thread then two: before the run {record['probe_before']}; "
            f"after it {record['probe_after']}.",
            "",
        ]
    drawn = (
        ("vector", "Vector environment", _vector_figure, "Env-steps per second against N"),
        ("single", "Single environment", _single_figure, "One environment's steps per second"),
    )
    for name, section, draw, caption in drawn:
        file = f"{prefix}-{name}.png"
        if draw(_section(record, section), figures / file):
            lines += [f":::{{figure}} {file}", "", f"{caption} (from the tables below).", ":::", ""]
    for section in record["sections"]:
        lines += [f"## {section['title']}", ""]
        for table in section["tables"]:
            lines += [_table_markdown(table), ""]
    return "\n".join(lines)


def write_pages(folder: Path) -> None:
    """Write one page per record of :data:`RESULTS` into ``folder`` (``speed.md``, ...)."""
    for path in sorted(RESULTS.glob("*.json")):
        record = json.loads(path.read_text("utf-8"))
        (folder / f"{path.stem}.md").write_text(record_page(record, folder, path.stem), "utf-8")
