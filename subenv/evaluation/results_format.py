"""The format of what ``subenv evaluate`` writes: ``results.csv`` (one row per episode) and ``run.json``
(what was run, and the scores).

This module is the format's one definition: :data:`RESULTS_COLUMNS` (every column of ``results.csv``,
its type, unit and meaning) and :data:`RUN_SCHEMA` (a JSON Schema, draft 2020-12, of ``run.json``, its
fields described with their units). ``tests/evaluation/test_results_format.py`` validates a written run
against both, and ``docs/results-format.md`` is :func:`markdown` of them (a test keeps it current:
``python -c "from subenv.evaluation.results_format import markdown; print(markdown(), end='')" >
docs/results-format.md``).

A reader needs no subenv to use the files: ``results.csv`` is plain CSV (floats as Python writes
them, exactly: ``inf`` for a settling time never reached, an empty cell for "not determined"; booleans
``True``/``False``), and :func:`subenv.evaluation.results.read_results` reads it back into results whose
tables are the run's. The format's version is :data:`FORMAT_VERSION`, in ``run.json``.
"""

from __future__ import annotations

import csv
import os
from typing import Any, Final

from subenv.evaluation.metrics import OUTCOMES

__all__ = ["FORMAT_VERSION", "RESULTS_COLUMNS", "RUN_SCHEMA", "check_results_csv", "markdown"]

FORMAT_VERSION: Final = "subenv-evaluate/1"
"""The version of the format, ``run.json``'s ``format``: a change that a reader of the files must know of
(a column or field renamed, removed, or its meaning changed) makes a new one."""

RESULTS_COLUMNS: Final[dict[str, tuple[str, str, str]]] = {
    "controller": (
        "str",
        "",
        "The controller's registered name; `<name>:uninformed` when run without being "
        "told the environment's settings.",
    ),
    "scenario": ("str", "", "The scenario's registered name."),
    "episode": ("int", "", "The episode's index within the scenario, from 0."),
    "seed": ("int", "", "The reset seed: the base seed + episode, the same for every controller."),
    "control": ("str", "", "The action space the controller drives: `dual` or `independent`."),
    "alpha": ("float", "1", "The bow/stern allocation of `dual` control (0 with `independent`)."),
    "initial_speed_mps": ("float", "m/s", "Speed at the reset."),
    "final_speed_mps": ("float", "m/s", "Speed at the end: over the hold window, on which success depends."),
    "critical_speed_mps": ("float", "m/s", "u_cr of the episode's loading and the controller's alpha."),
    "final_speed_ratio": ("float", "1", "final_speed_mps / critical_speed_mps."),
    "depth_command_m": ("float", "m", "The ordered depth."),
    "initial_depth_error_m": ("float", "m", "Depth minus ordered depth at the reset (positive: too deep)."),
    "episode_duration_s": (
        "float",
        "s",
        "The scheduled length of the episode (its scenario's, or the suite's cap).",
    ),
    "steps": ("int", "", "Control periods run."),
    "winnable": (
        "bool?",
        "",
        "The loading has a depth-holding trim within the plane and pitch limits at the "
        "final speed (subenv.analysis.winnable); empty: not determined.",
    ),
    "outcome": ("str", "", "The first that applies of: " + ", ".join(OUTCOMES) + "."),
    "success": ("bool", "", "Not terminated, and |depth error| <= 0.5 m over the final 60 s."),
    "terminated": ("bool", "", "The environment ended the episode."),
    "termination_reason": ("str", "", "The environment's reason (empty: ran to its time limit)."),
    "broached": ("bool", "", "Terminated by broaching."),
    "wrong_branch": (
        "bool",
        "",
        "Ended on the thesis's failure mode (steady pitch, a plane pinned, off depth).",
    ),
    "steady_offset": ("bool", "", "Ran to its limit settled off depth with the planes free."),
    "iae_m_s": (
        "float",
        "m s",
        "Integral of |depth error| (a terminated episode charged its final error to the scheduled end).",
    ),
    "settling_time_s": ("float", "s", "Time after which |depth error| stays within 0.5 m; inf if never."),
    "overshoot_m": ("float", "m", "Largest excursion past the ordered depth, on the far side."),
    "peak_pitch_deg": ("float", "deg", "Largest |pitch|."),
    "plane_rms_rad": ("float", "rad", "RMS of the applied plane angles, stern and bow together."),
    "saturated_fraction": ("float", "1", "Time fraction with a plane at its limit."),
    "hold_max_abs_error_m": ("float", "m", "Largest |depth error| over the final 60 s."),
    "final_abs_error_m": ("float", "m", "|depth error| at the end."),
    "duration_s": ("float", "s", "Recorded length of the episode."),
    "regulation_accuracy": (
        "float",
        "1",
        "a: time fraction within 0.1 m of the ordered depth, from 60 s after the order to the scheduled end.",
    ),
    "plane_effort": ("float", "1", "e: RMS plane angle per plane of the vehicle over the plane limit."),
    "pitch_limit": ("bool", "", "Terminated by the pitch limit."),
    "safety_event": ("bool", "", "Terminated by a safety event: broached or the pitch limit."),
    "quality": ("float", "1", "q = 0.8 a + 0.2 (1 - e^2), in [0, 1]; the score reads it on won episodes."),
    "scored": (
        "bool?",
        "",
        "The score counts the episode (its suite's classifier, run.json's `scored_by`); "
        "empty: not determined (then `winnable` decides).",
    ),
    "informed": ("bool", "", "The controller was told the environment's settings."),
}
"""The columns of ``results.csv``, in order: name -> (type, unit, meaning). Types: ``str``, ``int``,
``float`` (``inf`` and ``nan`` as such), ``bool`` (``True``/``False``), ``bool?`` (also empty: not
determined); unit "1": a dimensionless fraction or ratio."""

_NUMBER = {"type": "number"}
_INTERVAL = {"type": ["number", "null"]}
_COUNT = {"type": "integer", "minimum": 0}


def _scored_object(description: str, fields: dict[str, Any]) -> dict[str, Any]:
    return {
        "type": "object",
        "description": description,
        "required": list(fields),
        "additionalProperties": False,
        "properties": fields,
    }


RUN_SCHEMA: Final[dict[str, Any]] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://github.com/subenv/subenv/results-format/run.json",
    "title": "run.json of subenv evaluate",
    "type": "object",
    "additionalProperties": False,
    "required": [
        "format",
        "subenv_version",
        "suite",
        "scenarios",
        "max_duration_s",
        "vehicle",
        "episodes",
        "seeds",
        "env_kwargs",
        "scored_by",
        "controllers",
        "failures",
        "depth_tolerance_m",
        "hold_window_s",
        "saturation_level",
        "pinned_fraction",
        "non_level_pitch_deg",
        "steady_pitch_rate_degps",
        "steady_depth_change_m",
        "regulation_band_m",
        "approach_s",
        "confidence_level",
        "score",
        "scores",
        "paired",
        "rollout_seconds",
        "report_seconds",
    ],
    "properties": {
        "format": {"const": FORMAT_VERSION, "description": "The format's version."},
        "subenv_version": {"type": "string", "description": "The installed subenv's version."},
        "suite": {"type": "string", "description": "The suite's name (`custom` for scenarios named)."},
        "scenarios": {
            "type": "array",
            "items": {"type": "string"},
            "description": "Its scenarios, in order.",
        },
        "max_duration_s": {
            "type": ["number", "null"],
            "description": "The suite's cap on an episode [s]; null: none.",
        },
        "vehicle": {"type": "string", "description": "The vehicle, as named (a shipped name or a file)."},
        "episodes": {"type": "integer", "minimum": 1, "description": "Episodes per scenario and controller."},
        "seeds": {
            "type": "array",
            "items": {"type": "integer"},
            "minItems": 2,
            "maxItems": 2,
            "description": "The first and last reset seed of every scenario's episodes.",
        },
        "env_kwargs": {
            "type": "object",
            "description": "The environment's settings given (subenv evaluate --env-kwargs); {}: none.",
        },
        "scored_by": {
            "type": "string",
            "description": "The classifier whose episodes the score counts (`winnable`, ...).",
        },
        "controllers": {
            "type": "array",
            "description": "The controllers, in the order run.",
            "items": {
                "type": "object",
                "required": ["name", "informed", "complete"],
                "additionalProperties": False,
                "properties": {
                    "name": {"type": "string"},
                    "control": {"enum": ["dual", "independent"]},
                    "alpha": _NUMBER,
                    "informed": {"type": "boolean", "description": "Told the environment's settings."},
                    "complete": {"type": "boolean", "description": "Ran every episode (no failure)."},
                },
            },
        },
        "failures": {
            "type": "array",
            "description": "Controllers' failures (subenv.evaluation.failures.ControllerFailure).",
            "items": {
                "type": "object",
                "required": ["controller", "scenario", "seeds", "call", "step", "error", "message"],
                "additionalProperties": False,
                "properties": {
                    "controller": {"type": "string"},
                    "scenario": {"type": "string"},
                    "seeds": {"type": "array", "items": {"type": "integer"}},
                    "call": {"type": "string"},
                    "step": {"type": ["integer", "null"]},
                    "error": {"type": "string"},
                    "message": {"type": "string"},
                },
            },
        },
        "depth_tolerance_m": {**_NUMBER, "description": "Success: |depth error| within this [m]..."},
        "hold_window_s": {**_NUMBER, "description": "...over the final this-many seconds [s]."},
        "saturation_level": {**_NUMBER, "description": "A plane at this fraction of its limit is saturated."},
        "pinned_fraction": {
            **_NUMBER,
            "description": "Wrong branch: a plane pinned more than this fraction.",
        },
        "non_level_pitch_deg": {**_NUMBER, "description": "Wrong branch: |pitch| above this [deg]."},
        "steady_pitch_rate_degps": {**_NUMBER, "description": "Steady: |pitch rate| at most this [deg/s]."},
        "steady_depth_change_m": {
            **_NUMBER,
            "description": "Steady offset: depth error drifting at most this over the window [m].",
        },
        "regulation_band_m": {
            **_NUMBER,
            "description": "Regulation accuracy: within this of the ordered depth [m].",
        },
        "approach_s": {
            **_NUMBER,
            "description": "The regulation window starts this long after the order [s].",
        },
        "confidence_level": {**_NUMBER, "description": "Level of every interval (two-sided)."},
        "score": _scored_object(
            "How the scores are computed.",
            {
                "formula": {"type": "string"},
                "quality": {"type": "string"},
                "quality_accuracy_weight": _NUMBER,
                "quality_effort_weight": _NUMBER,
                "bootstrap_resamples": _COUNT,
                "bootstrap_seed": _COUNT,
            },
        ),
        "scores": {
            "type": "array",
            "description": "Per controller that completed: its score on each scenario and pooled over "
            "the suite (scenario `all`): subenv.evaluation.score.Score. Intervals null where there is "
            "nothing to resample.",
            "items": _scored_object(
                "A score.",
                {
                    "controller": {"type": "string"},
                    "scenario": {"type": "string"},
                    "episodes": _COUNT,
                    "scored": {**_COUNT, "description": "N: the episodes the score counts."},
                    "wins": {**_COUNT, "description": "W: of those, won."},
                    "quality": {"type": ["number", "null"], "description": "1000 Q, 0-1000; null: none won."},
                    "score": {"type": ["number", "null"], "description": "S, 0-1000; null: nothing scored."},
                    "success_rate": {"type": ["number", "null"], "description": "W / N."},
                    "success_ci_low": _INTERVAL,
                    "success_ci_high": _INTERVAL,
                    "quality_ci_low": _INTERVAL,
                    "quality_ci_high": _INTERVAL,
                    "score_ci_low": _INTERVAL,
                    "score_ci_high": _INTERVAL,
                },
            ),
        },
        "paired": {
            "type": "array",
            "description": "Every pair of those controllers, pooled (scenario `all`) and per scenario: "
            "subenv.evaluation.score.PairedComparison.",
            "items": _scored_object(
                "A paired comparison on the episodes both ran that count.",
                {
                    "first": {"type": "string"},
                    "second": {"type": "string"},
                    "scenario": {"type": "string"},
                    "episodes": _COUNT,
                    "first_only": {**_COUNT, "description": "Won by the first, lost by the second."},
                    "second_only": {**_COUNT, "description": "Won by the second, lost by the first."},
                    "mcnemar_p": {**_NUMBER, "description": "Exact McNemar test of equal success."},
                    "both_won": _COUNT,
                    "first_better": {**_COUNT, "description": "Both won, the first's quality higher."},
                    "second_better": _COUNT,
                    "quality_difference": {
                        "type": ["number", "null"],
                        "description": "Median of 1000 (q_first - q_second) over the episodes both won.",
                    },
                    "wilcoxon_p": {
                        "type": ["number", "null"],
                        "description": "Wilcoxon signed-rank test of equal quality over those; null: none.",
                    },
                },
            ),
        },
        "rollout_seconds": {**_NUMBER, "description": "Wall-clock time of the rollouts [s]."},
        "report_seconds": {**_NUMBER, "description": "Wall-clock time of the scores and tables [s]."},
    },
}
"""The JSON Schema (draft 2020-12) of ``run.json``. Floats that are not finite are written as null."""


def _cell_ok(kind: str, text: str) -> bool:
    """Whether ``text`` is a cell of a column of type ``kind``."""
    if kind == "str":
        return True
    if kind == "int":
        return text.lstrip("-").isdigit()
    if kind == "float":
        try:
            float(text)
        except ValueError:
            return False
        return True
    return text in ("True", "False") or (kind == "bool?" and text == "")


def check_results_csv(path: str | os.PathLike[str]) -> int:
    """Check a ``results.csv`` against :data:`RESULTS_COLUMNS` (its header, in order, and every cell's
    type); returns its number of rows. Raises ValueError naming the first column or cell that is not."""
    with open(path, newline="") as file:
        reader = csv.reader(file)
        header = next(reader, [])
        if header != list(RESULTS_COLUMNS):
            raise ValueError(f"{os.fspath(path)!r}: columns {header} are not {list(RESULTS_COLUMNS)}")
        rows = 0
        for line, row in enumerate(reader, start=2):
            if len(row) != len(header):
                raise ValueError(f"{os.fspath(path)!r}, line {line}: {len(row)} cells, not {len(header)}")
            for name, text in zip(header, row, strict=True):
                kind = RESULTS_COLUMNS[name][0]
                if not _cell_ok(kind, text):
                    raise ValueError(f"{os.fspath(path)!r}, line {line}: {name}={text!r} is not a {kind}")
            rows += 1
    return rows


def _run_lines(schema: dict[str, Any], prefix: str = "") -> list[str]:
    lines = []
    for name, field in schema.get("properties", {}).items():
        kind = field.get("type", "const" if "const" in field else "enum")
        kind = " or ".join(kind) if isinstance(kind, list) else kind
        lines.append(f"| `{prefix}{name}` | {kind} | {field.get('description', '')} |")
        items = field.get("items")
        if isinstance(items, dict) and "properties" in items:
            lines += _run_lines(items, f"{prefix}{name}[].")
        elif "properties" in field:
            lines += _run_lines(field, f"{prefix}{name}.")
    return lines


def markdown() -> str:
    """``docs/results-format.md``: the two files' fields, types, units and meanings."""
    from subenv.evaluation.results import SCORE_NOTE

    columns = "\n".join(
        f"| `{name}` | {kind} | {unit or '-'} | {meaning} |"
        for name, (kind, unit, meaning) in RESULTS_COLUMNS.items()
    )
    run = "\n".join(_run_lines(RUN_SCHEMA))
    return f"""# The results of `subenv evaluate`

<!-- Generated by subenv.evaluation.results_format.markdown(); edit subenv/evaluation/results_format.py. -->

`subenv evaluate --out DIR` writes `DIR/results.csv` (one row per controller, scenario and episode) and
`DIR/run.json` (what was run, the scores with their intervals, and paired comparisons), besides the
tables made from them (`leaderboard.md`, `summary.md`, `summary.csv`) and the figures. Format version:
`{FORMAT_VERSION}` (`run.json`'s `format`). `tests/evaluation/test_results_format.py` checks a written run
against this page's definitions (`subenv.evaluation.results_format`: a JSON Schema of `run.json`).

## The score

{SCORE_NOTE}

Per controller and scenario, and pooled over the suite (scenario `all` in `run.json`): intervals of the
score and the quality from a bootstrap stratified by scenario (`scipy.stats.bootstrap`, percentile, the
resamples and seed in `run.json`'s `score`), of the success rate Wilson's. Controllers that ran the same
seeds are compared in pairs: an exact McNemar test on success, a Wilcoxon signed-rank test on the quality
of the episodes both won (`run.json`'s `paired`).

## results.csv

Plain CSV, one row per episode, these columns in this order. Floats are written exactly (Python's
`repr`: `inf` for a settling time never reached); booleans `True`/`False`; an empty `bool?` cell: not
determined. Unit "1": a dimensionless fraction or ratio.

| column | type | unit | meaning |
|---|---|---|---|
{columns}

## run.json

JSON (non-finite numbers written as `null`); `subenv.evaluation.results_format.RUN_SCHEMA` is its JSON
Schema (draft 2020-12).

| field | type | meaning |
|---|---|---|
{run}
"""
