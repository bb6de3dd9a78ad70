"""The Hard suite's achievability certificates: stored plans that win on replay, and the classifier reading
their flags (subenv.evaluation.achievable; written by benchmarks/hard_certificates.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from subenv.evaluation import DEFAULT_SEED, evaluate, get_suite, run_episodes
from subenv.evaluation.achievable import (
    CERTIFIED_SETTINGS,
    PlanReplay,
    certified_ids,
    plan_sha256,
    read_certificates,
)
from subenv.scenarios.registry import get_scenario

PLANS = Path(__file__).parent.parent / "data" / "certificates"
HARD = get_suite("hard")


def _stored(scenario: str) -> dict[int, np.ndarray]:
    with np.load(PLANS / f"{scenario}.npz") as stored:
        return {int(key.removeprefix("seed_")): stored[key] for key in stored.files}


@pytest.mark.parametrize("scenario", HARD.scenarios)
def test_the_stored_plans_replay_to_their_certificates(scenario: str) -> None:
    """The certificate is the plan: replayed in the id's own environment, through the harness, it wins
    exactly the episodes the flags call achievable (a sample per scenario, with one not certified)."""
    env_id = get_scenario(scenario).env_id
    flags = certified_ids()[env_id].episodes
    plans = _stored(scenario)
    seeds = sorted(plans)
    assert len(seeds) >= 2
    results = run_episodes(PlanReplay([plans[s] for s in seeds]), env_id, seeds)
    for r in results:
        flag = flags[r.seed]
        assert plan_sha256(plans[r.seed]) == flag.plan_sha256
        assert (r.metrics.success, r.metrics.outcome) == (flag.achievable, flag.outcome), (scenario, r.seed)
        assert r.metrics.hold_max_abs_error_m == pytest.approx(flag.hold_max_abs_error_m, abs=1e-6)


def test_every_hard_scenario_is_certified_for_the_suites_seeds_and_mostly_achievable() -> None:
    """Every episode of the Hard suite has a flag, with the settings of its id, and at least 80% of each
    scenario's episodes are achievable (issue 37's rule for a Hard scenario)."""
    seeds = range(DEFAULT_SEED, DEFAULT_SEED + HARD.episodes)
    for scenario in HARD.scenarios:
        certified = certified_ids()[get_scenario(scenario).env_id]
        assert certified.scenario == scenario and set(certified.settings) == set(CERTIFIED_SETTINGS)
        assert set(seeds) <= set(certified.episodes)
        achievable = sum(certified.episodes[s].achievable for s in seeds)
        assert achievable >= 0.8 * HARD.episodes, scenario


def test_the_hard_suite_is_scored_over_the_achievable_episodes() -> None:
    """The harness classifies a Hard episode by its flag: the episode HardGusts 10000 + k not certified is
    not counted even where it is winnable; with settings other than those certified (or another seed) the
    classifier cannot say, and winnable decides."""
    flags = certified_ids()[get_scenario("HardGusts").env_id].episodes
    lost = min(s for s, f in flags.items() if not f.achievable)
    seeds = [DEFAULT_SEED, lost]
    for batched in (True, False):  # (the vector environment's path, and one episode at a time)
        (won, not_certified) = run_episodes(
            PlanReplay([_stored("HardGusts")[s] for s in seeds]),
            "HardGusts",
            seeds,
            scored_by="achievable",
            batched=batched,
        )
        assert (won.scored, not_certified.scored) == (True, False)
        assert not not_certified.counts and won.counts
    other = run_episodes(
        PlanReplay([np.zeros((1, 2))]),
        "HardGusts",
        [DEFAULT_SEED],
        scored_by="achievable",
        env_kwargs={"max_pitch_rad": 0.5},
    )
    assert other[0].scored is None and other[0].counts == other[0].winnable
    unstored = run_episodes(PlanReplay([np.zeros((1, 2))]), "HardGusts", [1], scored_by="achievable")
    assert unstored[0].scored is None


def test_the_hard_ids_make_their_settings_and_the_informed_mpc_is_told_them() -> None:
    """gym.make(id) has the limits the certificates hold for, and evaluate tells an informed controller."""
    pytest.importorskip("daqp", reason="the 'mpc' extra is not installed")
    import gymnasium as gym

    env = gym.make("subenv/HardBallastLimits-v0")
    config = env.unwrapped.config
    assert (config.plane_rate_limit_radps, config.max_pitch_rad) == (0.03, 0.3)
    env.close()
    (result,) = evaluate(["mpc"], ["HardBallastLimits"], episodes=1, progress=False)
    assert result.informed


def test_a_certificate_file_of_another_format_is_refused() -> None:
    with pytest.raises(ValueError, match="format 1"):
        read_certificates('{"format": 2, "ids": {}}')
    with pytest.raises(ValueError, match="plan"):
        PlanReplay([np.full((3, 2), np.nan)])


def test_evaluate_runs_each_suite_named_into_its_own_leaderboard(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    """``subenv evaluate --suite tiny,hard`` (without --suite: default,hard, what ./dev run runs): one
    results folder per suite and both leaderboards, the Hard one counting the achievable episodes."""
    import json

    from subenv.cli import main

    out = tmp_path / "both"
    argv = ["evaluate", "--suite", "tiny,hard", "--episodes", "1", "--controllers", "thesis"]
    assert main([*argv, "--no-plots", "--no-progress", "--out", str(out)]) == 0
    board = (out / "leaderboard.md").read_text("utf-8")
    assert "## Leaderboard: suite 'tiny'" in board and "## Leaderboard: suite 'hard'" in board
    assert "achievable: a full-information plan" in board
    assert board in capsys.readouterr().out
    runs = {name: json.loads((out / name / "run.json").read_text("utf-8")) for name in ("tiny", "hard")}
    assert runs["hard"]["scored_by"] == "achievable" and runs["tiny"]["scored_by"] == "winnable"


def test_the_hard_suite_runs_each_informed_controller_told_and_untold(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """With no controllers named, the Hard suite runs ``mpc`` told its limits and ``mpc:uninformed``; the
    default suite does not twin; ``subenv evaluate`` with no --suite runs both tracks."""
    pytest.importorskip("daqp", reason="the 'mpc' extra is not installed")
    import subenv.evaluation
    from subenv.cli import main
    from subenv.evaluation.plan import resolve

    names = [c.name for c in resolve(None, "hard").controllers]
    assert names.index("mpc:uninformed") == names.index("mpc") + 1
    assert not any(n.endswith(":uninformed") for n in (c.name for c in resolve(None, "default").controllers))
    asked = []
    monkeypatch.setattr(
        subenv.evaluation, "run_benchmark", lambda c, suites, *a, **k: asked.append(suites) or []
    )
    main(["evaluate", "--no-progress", "--out", str(tmp_path / "x")])
    assert asked == [["default", "hard"]]
