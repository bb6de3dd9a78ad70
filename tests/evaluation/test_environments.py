"""The environment's settings in the harness: checked before anything runs, passed to every environment,
told to the controllers that take them (and not to those run uninformed), recorded with the results."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from subenv.evaluation import (
    BatchController,
    InformedController,
    Suite,
    evaluate,
    make_controller,
    run_comparison,
    uninformed,
)
from subenv.evaluation.environments import check_env_kwargs, env_settings, setting_names
from subenv.evaluation.plan import resolve_controllers
from subenv.evaluation.plots import replay_trajectory
from subenv.vehicles import Vehicle, load_vehicle

SHORT = Suite(
    name="short", description="10 s of Nominal", scenarios=("Nominal",), episodes=2, max_duration_s=10.0
)


class BangBang:
    """Full plane one way, then the other, every step; records what it is told."""

    name = "bang_bang"
    control = "dual"
    alpha = 0.0

    def __init__(self) -> None:
        self.told: list[dict[str, Any]] = []
        self.sign = 1.0

    def inform(self, settings: Mapping[str, Any]) -> None:
        self.told.append(dict(settings))

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        self.sign = 1.0

    def act(self, observation: np.ndarray) -> np.ndarray:
        self.sign = -self.sign
        return np.array([self.sign], dtype=np.float32)


@pytest.mark.parametrize(
    ("env_kwargs", "match"),
    [
        ({"plane_rate_limit": 0.05}, r"env_kwargs: 'plane_rate_limit' is unknown: must be one of \['dt', "),
        ({"control": "independent"}, "env_kwargs: 'control' cannot be set there: each controller declares"),
        ({"vehicle": "remus100"}, "env_kwargs: 'vehicle' cannot be set there: the comparison's vehicle"),
        ({"plane_rate_limit_radps": -1.0}, "env_kwargs: plane_rate_limit_radps=-1.0 is invalid"),
        ({"max_pitch_rad": float("nan")}, "env_kwargs: max_pitch_rad=nan is invalid"),
        ({"dt": "fast"}, "env_kwargs: dt='fast' is invalid"),
        ([("dt", 0.5)], "env_kwargs=.* is invalid: must be a mapping"),
    ],
)
def test_bad_settings_are_refused_in_one_line_naming_the_key_before_any_episode(env_kwargs, match) -> None:
    controller = BangBang()
    with pytest.raises(ValueError, match=match) as error:
        evaluate([controller], SHORT, progress=False, env_kwargs=env_kwargs)
    assert "\n" not in str(error.value)
    assert controller.told == []  # nothing ran


def test_the_settings_reach_every_environment_and_the_controllers_that_take_them() -> None:
    """With a rate limit of 0.05 rad/s the bang-bang planes move 0.025 rad per 0.5 s step instead of
    swinging from limit to limit; the controller is told the limit, and the same one run uninformed is
    not, under a name that says so."""
    told, untold = BangBang(), BangBang()
    untold_wrapped = uninformed(untold)
    assert untold_wrapped.name == "bang_bang:uninformed" and not isinstance(
        untold_wrapped, InformedController
    )
    settings = {"plane_rate_limit_radps": 0.05}
    results = evaluate(
        [told, untold_wrapped], SHORT, progress=False, keep_trajectories=2, env_kwargs=settings
    )
    free = evaluate([BangBang()], SHORT, progress=False, keep_trajectories=2)

    def largest_move(r):  # type: ignore[no-untyped-def]
        return float(np.max(np.abs(np.diff(r.trajectory.stern_plane_rad[1:]))))

    assert [largest_move(r) for r in results] == pytest.approx([0.025] * 4)
    assert [largest_move(r) for r in free] == pytest.approx([0.8] * 2)  # limit to limit without the setting
    assert told.told == [env_settings("Nominal", settings)] and untold.told == []
    assert list(told.told[0]) == setting_names()
    assert told.told[0]["plane_rate_limit_radps"] == 0.05 and told.told[0]["max_pitch_rad"] == 0.6
    assert [(r.controller, r.informed) for r in results] == [("bang_bang", True)] * 2 + [
        ("bang_bang:uninformed", False)
    ] * 2


def test_the_mpc_is_told_the_limits_and_runs_untold_by_name() -> None:
    pytest.importorskip("daqp", reason="the 'mpc' extra is not installed")
    mpc = make_controller("mpc")
    evaluate([mpc], SHORT, episodes=1, progress=False, env_kwargs={"plane_rate_limit_radps": 0.05})
    assert mpc.plane_rate_limit_radps == 0.05  # type: ignore[attr-defined]
    evaluate([mpc], SHORT, episodes=1, progress=False)  # the environment's default again: no limit
    assert mpc.plane_rate_limit_radps is None  # type: ignore[attr-defined]
    (untold,) = resolve_controllers(["mpc:uninformed"])
    assert untold.name == "mpc:uninformed" and isinstance(untold, BatchController)
    assert not isinstance(untold, InformedController)


def test_check_env_kwargs_uses_the_environments_own_checks_for_every_scenario() -> None:
    suboff = load_vehicle("suboff")
    assert check_env_kwargs(None, ["Nominal"], suboff) == {}
    given = {"plane_rate_limit_radps": 0.05, "max_pitch_rad": 0.3}
    assert check_env_kwargs(given, ["Nominal", "LowSpeed"], suboff) == given
    assert env_settings("Nominal")["max_depth_error_m"] is None  # (the environment's default for the vehicle)


def test_the_settings_and_who_was_told_are_in_run_json(tmp_path: Path) -> None:
    out = tmp_path / "run"
    settings = {"plane_rate_limit_radps": 0.1}
    run_comparison(
        [BangBang(), "thesis"], SHORT, out_dir=out, progress=False, plots=False, env_kwargs=settings
    )
    record = json.loads((out / "run.json").read_text())
    assert record["env_kwargs"] == settings
    assert [(c["name"], c["informed"]) for c in record["controllers"]] == [
        ("bang_bang", True),
        ("thesis", False),
    ]
    board = (out / "leaderboard.md").read_text()
    rows = {
        line.split("|")[2].strip(): line.split("|")[3].strip()
        for line in board.split("\n\n")[1].splitlines()[2:]
    }
    assert rows == {"bang_bang": "yes", "thesis": "no"}


def test_the_figures_replay_their_episodes_in_the_run_settings(tmp_path: Path) -> None:
    """The outcome figures replay an episode that was not kept (here episodes 1 and 2) in the settings
    of the run: in the default settings the replay would be another episode, and refused."""
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")  # (the figures)
    settings = {"plane_rate_limit_radps": 0.05}
    comparison = run_comparison(
        [BangBang()], SHORT, episodes=3, out_dir=tmp_path / "run", progress=False, env_kwargs=settings
    )
    assert (tmp_path / "run" / "plots" / "trajectories_Nominal.png").is_file()
    unkept = next(r for r in comparison.results if r.trajectory is None)
    replay_trajectory(unkept, BangBang(), max_duration_s=SHORT.max_duration_s, env_kwargs=settings)
    with pytest.raises(ValueError, match="replaying bang_bang on Nominal seed"):
        replay_trajectory(unkept, BangBang(), max_duration_s=SHORT.max_duration_s)
