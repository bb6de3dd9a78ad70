"""The shipped models' evaluation records and target, shared by the model cards of
:mod:`subenv_agents.card` (Stable-Baselines3) and :mod:`subenv_agents.jax_ppo` (JAX): plain Python over
the harness's results, no training stack needed."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Final

__all__ = [
    "BASELINE",
    "DYNAMICS_KWARGS",
    "REVERSAL_SCENARIOS",
    "check_harness_kwargs",
    "evaluation_record",
    "score_record",
    "score_table",
    "table",
    "target_met",
]

BASELINE: Final = "reversal_aware"
DYNAMICS_KWARGS: Final = (
    "vehicle",
    "dt",
    "substeps",
    "plane_rate_limit_radps",
    "max_pitch_rad",
    "max_depth_error_m",
)
"""Environment arguments that change what an agent sees or commands. The evaluation harness makes its
environments with ``control`` and ``alpha`` only, the rest at their defaults (reward weights do not
matter to it), so a model trained with any of these changed is refused as a controller."""
REVERSAL_SCENARIOS: Final = ("LowSpeed", "NearCritical", "SpeedTransient")
"""Where the target is measured: at least the baseline's success rate with less plane effort (and so
where the shipped agents are selected, :mod:`subenv_agents.selection`)."""


def check_harness_kwargs(env_kwargs: Mapping[str, Any], model: str) -> None:
    """Raise ``ValueError`` if ``model`` (its name in the message) was trained with any of
    :data:`DYNAMICS_KWARGS` in its ``env_kwargs``."""
    changed = [k for k in DYNAMICS_KWARGS if k in env_kwargs]
    if changed:
        raise ValueError(
            f"the {model} was trained with env_kwargs {changed} changed from the defaults the "
            "evaluation harness uses; evaluate it on its own environment instead"
        )


def evaluation_record(results: Sequence[Any]) -> dict[str, dict[str, dict[str, float]]]:
    """``{controller: {scenario: {success_rate, ci_low, ci_high, plane_rms_rad, episodes}}}``."""
    from subenv.evaluation.results import summarize

    out: dict[str, dict[str, dict[str, float]]] = {}
    for row in summarize(results):
        out.setdefault(row["controller"], {})[row["scenario"]] = {
            "success_rate": row["success_rate"],
            "ci_low": row["success_ci_low"],
            "ci_high": row["success_ci_high"],
            "plane_rms_rad": row["plane_rms_rad_mean"],
            "episodes": row["episodes"],
        }
    return out


def score_record(results: Sequence[Any]) -> dict[str, dict[str, dict[str, Any]]]:
    """The benchmark-v1 score of each controller on each scenario and pooled (``"all"``,
    :mod:`subenv.evaluation.score`): ``{controller: {scenario: {episodes, scored, wins, success_rate,
    quality, score, score_ci_low, score_ci_high, outcomes}}}``, ``success_rate`` over the scored (winnable)
    episodes and ``outcomes`` the count of each failure outcome among them."""
    from subenv.evaluation.results import outcome_counts
    from subenv.evaluation.score import POOLED, scores

    out: dict[str, dict[str, dict[str, Any]]] = {}
    for s in scores(results):
        counted = [
            r.metrics
            for r in results
            if r.controller == s.controller and r.counts and s.scenario in (POOLED, r.scenario)
        ]
        failures = {o: n for o, n in outcome_counts(counted).items() if n and o != "success"}
        out.setdefault(s.controller, {})[s.scenario] = {
            "episodes": s.episodes,
            "scored": s.scored,
            "wins": s.wins,
            "success_rate": s.success_rate,
            "quality": s.quality,
            "score": s.score,
            "score_ci_low": s.score_ci[0],
            "score_ci_high": s.score_ci[1],
            "outcomes": failures,
        }
    return out


def score_table(record: Mapping[str, Mapping[str, Mapping[str, Any]]]) -> str:
    """A Markdown table of :func:`score_record`'s wins over the scored episodes and the score [95%
    interval], per scenario (then pooled) and controller."""
    controllers = list(record)
    scenarios = list(next(iter(record.values())))
    lines = [
        "| scenario | " + " | ".join(f"{c}: wins / scored | {c}: score [95% CI]" for c in controllers) + " |",
        "|---|" + "---:|---:|" * len(controllers),
    ]
    for s in scenarios:
        cells = []
        for c in controllers:
            r = record[c][s]
            interval = f"[{r['score_ci_low']:.0f}, {r['score_ci_high']:.0f}]"
            cells.append(f"{r['wins']}/{r['scored']} | {r['score']:.0f} {interval}")
        lines.append(f"| {'all (pooled)' if s == 'all' else s} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table(record: dict[str, dict[str, dict[str, float]]], scenarios: Sequence[str]) -> str:
    """A Markdown table of ``record``'s success (95% Wilson interval) and plane RMS per scenario and
    controller."""
    lines = [
        "| scenario | " + " | ".join(f"{c} success | {c} plane RMS [rad]" for c in record) + " |",
        "|---|" + "---:|---:|" * len(record),
    ]
    for s in scenarios:
        cells = []
        for rows in record.values():
            r = rows[s]
            cells.append(
                f"{100 * r['success_rate']:.0f}% [{100 * r['ci_low']:.0f}, {100 * r['ci_high']:.0f}] | "
                f"{r['plane_rms_rad']:.4f}"
            )
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def target_met(record: dict[str, dict[str, dict[str, float]]], name: str) -> tuple[bool, str]:
    """Whether ``name`` met the target on every scenario of :data:`REVERSAL_SCENARIOS`, and the sentence
    saying so."""
    ok, parts = True, []
    for s in REVERSAL_SCENARIOS:
        a, b = record[name][s], record[BASELINE][s]
        meets = a["success_rate"] >= b["success_rate"] and a["plane_rms_rad"] < b["plane_rms_rad"]
        ok &= meets
        parts.append(
            f"{s}: {100 * a['success_rate']:.0f}% vs {100 * b['success_rate']:.0f}%, plane RMS "
            f"{a['plane_rms_rad']:.4f} vs {b['plane_rms_rad']:.4f} rad ({'met' if meets else 'not met'})"
        )
    return ok, "; ".join(parts)
