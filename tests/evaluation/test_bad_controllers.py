"""Bad controllers: each failure is one line naming the controller, scenario and seed, and costs no other
controller its results; a controller cannot publish under another one's name.

The controllers are defined here and declared as an installed package declares its controllers (entry
points of the ``subenv.controllers`` group, as ``tests/conftest.py`` declares the shipped ones), in a
registry of the test's own. Each bad one breaks one call (``reset``, ``act``, or the batch versions)
of a good one, in both of the harness's paths: one episode at a time, and batched in the vector env.
"""

from __future__ import annotations

import csv
import json
import pickle
from collections.abc import Mapping, Sequence
from importlib.metadata import EntryPoint
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from subenv.cli import main
from subenv.evaluation import (
    ENTRY_POINT_GROUP,
    ControllerError,
    ControllerFailure,
    controller,
    discover_controllers,
    evaluate,
    make_controller,
    run_comparison,
    run_episodes,
)
from subenv.vehicles import Vehicle


class GoodP:
    """Planes proportional to the depth error, one episode at a time: runs every episode to its end."""

    name = "good_p"
    control = "dual"
    alpha = 0.0

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        self.steps = 0

    def act(self, observation: np.ndarray) -> np.ndarray:
        self.steps += 1
        return np.clip([0.3 * float(observation[0])], -1.0, 1.0).astype(np.float32)


class GoodBatchP(GoodP):
    """:class:`GoodP` on a batch of episodes (the harness runs it in the vector environment)."""

    name = "good_batch_p"

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        self.steps = 0

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        self.steps += 1
        return np.clip(0.3 * observations[:, :1], -1.0, 1.0).astype(np.float32)


class BadNaN(GoodP):
    name = "bad_nan"

    def act(self, observation: np.ndarray) -> np.ndarray:
        action = super().act(observation)
        return np.full_like(action, np.nan) if self.steps >= 3 else action


class BadNone(GoodP):
    name = "bad_none"

    def act(self, observation: np.ndarray) -> Any:
        return None


class BadShape(GoodP):
    name = "bad_shape"

    def act(self, observation: np.ndarray) -> np.ndarray:
        return np.zeros(3, dtype=np.float32)


class BadRaise(GoodP):
    name = "bad_raise"

    def act(self, observation: np.ndarray) -> np.ndarray:
        raise RuntimeError("matrix is singular\n(in the plugin's own words)")


class BadReset(GoodP):
    name = "bad_reset"

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        raise KeyError("gain")


class BadSlow(GoodP):
    """Fails below the critical speed only (LowSpeed), and completes Nominal."""

    name = "bad_slow"

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        if info["speed_mps"] < info["critical_speed_mps"]:
            raise RuntimeError("no design below the critical speed")
        super().reset(info, vehicle)


class BadNaNBatch(GoodBatchP):
    """NaN in the batch's second row (the episode of the second seed) from the third step on."""

    name = "bad_nan_batch"

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        actions = super().act_batch(observations)
        if self.steps >= 3:
            actions[1] = np.nan
        return actions


class BadNoneBatch(GoodBatchP):
    name = "bad_none_batch"

    def act_batch(self, observations: np.ndarray) -> Any:
        return None


class BadShapeBatch(GoodBatchP):
    name = "bad_shape_batch"

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        return np.zeros((len(observations), 3), dtype=np.float32)


class BadRaiseBatch(GoodBatchP):
    name = "bad_raise_batch"

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        raise RuntimeError("matrix is singular")


class BadResetBatch(GoodBatchP):
    name = "bad_reset_batch"

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        raise ValueError("infos[0] has no 'speed_mps'")


class Liar(GoodP):
    """Declared as ``liar``, it calls itself ``lqr``: its rows would be another controller's."""

    name = "lqr"


DECLARED = {
    "good_p": GoodP,
    "good_batch_p": GoodBatchP,
    "bad_nan": BadNaN,
    "bad_none": BadNone,
    "bad_shape": BadShape,
    "bad_raise": BadRaise,
    "bad_reset": BadReset,
    "bad_slow": BadSlow,
    "bad_nan_batch": BadNaNBatch,
    "bad_none_batch": BadNoneBatch,
    "bad_shape_batch": BadShapeBatch,
    "bad_raise_batch": BadRaiseBatch,
    "bad_reset_batch": BadResetBatch,
    "liar": Liar,
}


@pytest.fixture
def declared(monkeypatch: pytest.MonkeyPatch) -> None:
    """The controllers above declared as entry points, beside the shipped ones, for this test only."""
    monkeypatch.setattr(controller, "_REGISTRY", dict(controller._REGISTRY))
    monkeypatch.setattr(controller, "_UNAVAILABLE", dict(controller._UNAVAILABLE or {}))
    discover_controllers(
        EntryPoint(name, f"{__name__}:{cls.__name__}", ENTRY_POINT_GROUP) for name, cls in DECLARED.items()
    )


LIAR = (
    "controller 'liar' is invalid: its name attribute is 'lqr', and must be 'liar', the name it is "
    "registered under (results are published by name)"
)


def test_a_controller_that_calls_itself_by_another_name_is_refused(declared, tmp_path: Path) -> None:
    with pytest.raises(ValueError) as error:
        make_controller("liar")
    assert str(error.value) == LIAR
    with pytest.raises(ValueError) as error:
        evaluate(["good_p", "liar"], ["Nominal"], episodes=1, progress=False)
    assert str(error.value) == LIAR
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exit_:
        main(
            [
                "evaluate",
                "--controllers",
                "good_p,liar",
                "--suite",
                "Nominal",
                "--no-plots",
                "--out",
                str(out),
            ]
        )
    assert exit_.value.code == f"subenv evaluate: {LIAR}"
    assert not out.exists()
    assert make_controller("lqr").name == "lqr"  # the real one is untouched


FINITE = "is invalid: must be finite (no NaN or inf)"
REAL = "is invalid: must hold real numbers (it holds object)"
BATCH = "seeds 10000-10002"  # (every episode of the batch: the failure is the batch's)
FAILURES = {
    "bad_nan": f"seed 10000, in act at step 3: action=[nan] {FINITE}",
    "bad_none": f"seed 10000, in act at step 1: action=None {REAL}",
    "bad_shape": "seed 10000, in act at step 1: action has shape (3,): must have shape (1,) (control='dual')",
    "bad_raise": "seed 10000, in act at step 1: RuntimeError: matrix is singular (in the plugin's own words)",
    "bad_reset": "seed 10000, in reset: KeyError: 'gain'",
    "bad_nan_batch": f"seed 10001, in act_batch at step 3: actions[1]=[nan] {FINITE}",
    "bad_none_batch": f"{BATCH}, in act_batch at step 1: actions=None {REAL}",
    "bad_shape_batch": (
        f"{BATCH}, in act_batch at step 1: actions has shape (3, 3): must have shape (3, 1) "
        "(num_envs=3, control='dual')"
    ),
    "bad_raise_batch": f"{BATCH}, in act_batch at step 1: RuntimeError: matrix is singular",
    "bad_reset_batch": f"{BATCH}, in reset_batch: ValueError: infos[0] has no 'speed_mps'",
}
"""What follows ``controller '<name>' failed on Nominal, `` in the one line of each failure."""


@pytest.mark.parametrize("name", list(FAILURES))
def test_a_failure_is_one_line_naming_the_controller_the_scenario_and_the_seed(declared, name: str) -> None:
    with pytest.raises(ControllerError) as error:
        run_episodes(make_controller(name), "Nominal", [10000, 10001, 10002])
    expected = f"controller {name!r} failed on Nominal, {FAILURES[name]}"
    assert str(error.value) == expected
    failure = error.value.failure
    assert (failure.controller, failure.scenario, failure.message) == (name, "Nominal", expected)
    # The controller's own exception is the cause (a traceback for whoever debugs it through the API);
    # of an action the environment refused, the environment's ValueError.
    raised = {"bad_raise": RuntimeError, "bad_reset": KeyError, "bad_raise_batch": RuntimeError}
    assert type(error.value.__cause__) is raised.get(name, ValueError)
    again = pickle.loads(pickle.dumps(error.value))  # (as a Ray worker sends it back)
    assert str(again) == expected and again.failure == failure


def test_evaluate_raises_the_first_failure_or_reports_each_and_keeps_the_others(declared) -> None:
    controllers = ["good_p", "bad_slow", "bad_raise_batch", "good_batch_p"]
    scenarios = ["Nominal", "LowSpeed"]
    with pytest.raises(
        ControllerError, match=r"^controller 'bad_slow' failed on LowSpeed, seed 10000, in reset"
    ):
        evaluate(controllers, scenarios, episodes=2, progress=False)
    failures: list[ControllerFailure] = []
    seen: list[tuple[str, str]] = []
    results = evaluate(
        controllers,
        scenarios,
        episodes=2,
        progress=False,
        keep_trajectories=0,
        on_failure=failures.append,
        on_episode=lambda r: seen.append((r.controller, r.scenario)),
    )
    assert [f.message for f in failures] == [
        "controller 'bad_slow' failed on LowSpeed, seed 10000, in reset: RuntimeError: no design below the "
        "critical speed",
        "controller 'bad_raise_batch' failed on Nominal, seeds 10000-10001, in act_batch at step 1: "
        "RuntimeError: matrix is singular",
        "controller 'bad_raise_batch' failed on LowSpeed, seeds 10000-10001, in act_batch at step 1: "
        "RuntimeError: matrix is singular",
    ]
    # The failed controller keeps the scenario it completed, nothing of the one it failed on.
    assert [(r.controller, r.scenario, r.seed) for r in results] == [
        (c, s, seed)
        for c, s in [
            ("good_p", "Nominal"),
            ("good_p", "LowSpeed"),
            ("bad_slow", "Nominal"),
            ("good_batch_p", "Nominal"),
            ("good_batch_p", "LowSpeed"),
        ]
        for seed in (10000, 10001)
    ]
    assert seen == [(r.controller, r.scenario) for r in results]
    # The others' results are those of a run without the bad controllers.
    alone = evaluate(["good_p", "good_batch_p"], scenarios, episodes=2, progress=False, keep_trajectories=0)
    assert [r for r in results if r.controller.startswith("good")] == alone


def _csv(path: Path) -> list[dict[str, str]]:
    with path.open() as file:
        return list(csv.DictReader(file))


def _ranked(board: str) -> list[str]:
    table = board.split("\n\n")[1]
    return [line.split("|")[2].strip() for line in table.splitlines()[2:]]


def test_subenv_evaluate_writes_the_others_results_and_reports_each_failure(
    declared, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--controllers good_p,bad_nan,bad_slow,lqr``: the results of good_p and lqr are those of a run
    without the bad ones, bad_slow's Nominal episodes are kept but not ranked, and the status is 1."""
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")  # (the plots are checked)
    common = ["evaluate", "--suite", "Nominal,LowSpeed", "--episodes", "2"]
    out = tmp_path / "with_bad"
    assert main([*common, "--controllers", "good_p,bad_nan,bad_slow,lqr", "--out", str(out)]) == 1
    printed = capsys.readouterr()
    lines = [line for line in printed.err.splitlines() if line.startswith("subenv evaluate: ")]
    expected = [
        f"controller 'bad_nan' failed on Nominal, seed 10000, in act at step 3: action=[nan] {FINITE}",
        f"controller 'bad_nan' failed on LowSpeed, seed 10000, in act at step 3: action=[nan] {FINITE}",
        "controller 'bad_slow' failed on LowSpeed, seed 10000, in reset: RuntimeError: no design below the "
        "critical speed",
    ]
    assert lines == [f"subenv evaluate: {line}" for line in expected]
    assert "Traceback" not in printed.err
    # The progress counts the episodes left out of a failed scenario as done, so it ends at 100%.
    progress = [line for line in printed.err.splitlines() if line.startswith("evaluate: ")]
    assert progress[-1].startswith("evaluate: 16/16 episodes, 100% (lqr on LowSpeed)")

    reference = tmp_path / "good_only"
    assert main([*common, "--controllers", "good_p,lqr", "--out", str(reference), "--no-progress"]) == 0
    capsys.readouterr()

    rows, good_rows = _csv(out / "results.csv"), _csv(reference / "results.csv")
    assert [r for r in rows if r["controller"] in ("good_p", "lqr")] == good_rows
    assert [(r["controller"], r["scenario"]) for r in rows if r["controller"] not in ("good_p", "lqr")] == [
        ("bad_slow", "Nominal")
    ] * 2
    summary = _csv(out / "summary.csv")
    assert [r for r in summary if r["controller"] in ("good_p", "lqr")] == _csv(reference / "summary.csv")
    listed = "".join(f"- {line}\n" for line in expected)
    assert (out / "summary.md").read_text().endswith(f"\n\n{listed}")

    board, good_board = (out / "leaderboard.md").read_text(), (reference / "leaderboard.md").read_text()
    assert _ranked(board) == _ranked(good_board) and set(_ranked(board)) == {"good_p", "lqr"}
    assert board == good_board + (
        "\n### Failed: bad_nan, bad_slow\n\nNot ranked: a controller that raised an exception or returned an "
        "action the environment refused has no episodes on that scenario. Its scenarios that completed are "
        f"in results.csv and the summary.\n\n{listed}"
    )
    assert board in printed.out

    record = json.loads((out / "run.json").read_text())
    assert [(c["name"], c["complete"]) for c in record["controllers"]] == [
        ("good_p", True),
        ("bad_nan", False),
        ("bad_slow", False),
        ("lqr", True),
    ]
    assert [f["message"] for f in record["failures"]] == expected
    assert record["failures"][0] | {"message": ""} == {
        "controller": "bad_nan",
        "scenario": "Nominal",
        "seeds": [10000],
        "call": "act",
        "step": 3,
        "error": "action=[nan] is invalid: must be finite (no NaN or inf)",
        "message": "",
    }
    assert sorted(p.name for p in (out / "plots").iterdir()) == [
        "metrics_vs_speed.png",
        "trajectories_LowSpeed.png",
        "trajectories_Nominal.png",
    ]


def test_when_every_controller_fails_the_folder_says_so(declared, tmp_path: Path) -> None:
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")  # (the plots are checked)
    out = tmp_path / "out"
    comparison = run_comparison(
        ["bad_raise", "bad_reset_batch"], "Nominal", episodes=2, out_dir=out, progress=False
    )
    assert comparison.results == [] and comparison.failed == ("bad_raise", "bad_reset_batch")
    board = (out / "leaderboard.md").read_text()
    assert board.startswith(
        "## Leaderboard: suite 'custom'\n\nNo controller completed the suite: none is ranked.\n"
    )
    assert board.endswith(
        "- controller 'bad_raise' failed on Nominal, seed 10000, in act at step 1: RuntimeError: matrix is "
        "singular (in the plugin's own words)\n- controller 'bad_reset_batch' failed on Nominal, seeds "
        "10000-10001, in reset_batch: ValueError: infos[0] has no 'speed_mps'\n"
    )
    assert len(json.loads((out / "run.json").read_text())["failures"]) == 2
    assert not (out / "plots").exists()
