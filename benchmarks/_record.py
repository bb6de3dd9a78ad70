"""A benchmark's record as JSON: what it printed (its Markdown tables), where, when and how it ran.

The documentation draws its performance figures from these records (``docs/_ext/performance.py``), so
that no measured number is typed by hand. A record is written whole or not at all
(:func:`subenv.atomic.atomic_write_text`).
"""

from __future__ import annotations

import datetime
import json
import shlex
import sys
from pathlib import Path
from typing import Any

from subenv.atomic import atomic_write_text

FORMAT = 1
"""The record's format version (``docs/_ext/performance.py`` reads this one)."""


def markdown_tables(lines: list[str]) -> list[dict[str, Any]]:
    """The Markdown tables among printed ``lines``: each as its columns and rows of cells (strings, as
    printed: ``1,395,734``, ``23.3``), the separator row left out."""
    tables: list[dict[str, Any]] = []
    current: list[list[str]] = []
    for line in [*lines, ""]:
        if line.startswith("|"):
            cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
            if not all(set(cell) <= set("-:") for cell in cells):
                current.append(cells)
        elif current:
            tables.append({"columns": current[0], "rows": current[1:]})
            current = []
    return tables


def write_record(
    path: str | Path, benchmark: str, machine: str, sections: list[tuple[str, list[str]]], **notes: Any
) -> None:
    """Write ``path``: the benchmark's name, the UTC date, the command as typed, the machine, each
    section's title and tables, and ``notes`` (e.g. the free-cores probes before and after)."""
    record = {
        "format": FORMAT,
        "benchmark": benchmark,
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": shlex.join(["python", *sys.argv]),
        "machine": machine,
        **notes,
        "sections": [{"title": title, "tables": markdown_tables(lines)} for title, lines in sections],
    }
    atomic_write_text(path, json.dumps(record, indent=1) + "\n")
