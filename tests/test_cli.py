"""The ``subenv`` command: its commands, their help, and their one-line errors."""

from __future__ import annotations

import csv
import errno
import json
import os
import shutil
import stat
import sys
import warnings
from importlib import resources
from importlib.metadata import EntryPoint
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import subenv.analysis.report
import subenv.cli
import subenv.evaluation.comparison
from subenv.analysis.free_surface import SurfaceCriticalSpeed
from subenv.atomic import MARKER_FILE
from subenv.cli import main
from subenv.envs import FreeSurfaceRangeWarning
from subenv.evaluation import controller


def test_demo_prints_the_summary_and_writes_the_plot(tmp_path: Path, capsys):
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")
    out = tmp_path / "figs" / "demo.png"
    assert main(["demo", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "u_cr = 0.5785 m/s = 1.8979 fps" in text
    rows = [line.split() for line in text.splitlines() if line.strip().startswith(("1.524", "0.450"))]
    assert len(rows) == 2
    design, low = rows
    assert abs(float(design[2])) < 0.01  # holds the ordered depth at 5 fps
    assert abs(float(low[2])) > 1.0  # loses it below the critical speed
    assert out.read_bytes().startswith(b"\x89PNG")
    assert [p.name for p in out.parent.iterdir()] == ["demo.png"]  # no temporary file left


def test_bad_option_is_a_clear_error(capsys):
    with pytest.raises(SystemExit, match=r"--low-speed=-1\.0 is invalid"):
        main(["demo", "--low-speed", "-1", "--no-plot"])


def test_list_names_every_id(capsys):
    assert main(["list"]) == 0
    text = capsys.readouterr().out
    assert "subenv/LowSpeed-v0" in text and "subenv/DivePlane-v0" in text


def _stand_in_findings(monkeypatch, hopf) -> list[str]:  # type: ignore[no-untyped-def]
    """Make ``reproduction(vehicle)`` return at once: the session's Hopf findings and a stand-in for the
    rest. Returns the list of the vehicles it was called for."""
    from subenv.analysis import report as report_module

    surface = report_module.SurfaceFindings(
        critical=(SurfaceCriticalSpeed(1.0, 0.57, 0.57, 0.58, 0.0, 0.0),),
        held={},
        suction_N=(),
        growth_per_s=(),
    )
    calls = []

    def quick(vehicle):  # type: ignore[no-untyped-def]
        calls.append(vehicle.name)
        return report_module.Reproduction(vehicle.name, True, (), (), hopf, surface)

    monkeypatch.setattr(report_module, "reproduction", quick)
    return calls


def test_analyze_needs_no_matplotlib(tmp_path: Path, analysis_report, monkeypatch, capsys):
    # Its findings are numbers (report.json); the figures are the documentation's.
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if not installed: `import matplotlib` fails
    calls = _stand_in_findings(monkeypatch, analysis_report.hopf)
    assert main(["analyze", "--out", str(tmp_path / "out")]) == 0
    assert calls == ["suboff"] and (tmp_path / "out" / "report.json").is_file()
    assert "findings written to" in capsys.readouterr().out


def test_analyze_writes_the_report_and_refuses_to_overwrite(tmp_path: Path, analysis_report, monkeypatch):
    # `subenv analyze --out <folder>` into a folder that did not exist, once per session (tests/conftest.py).
    from subenv.analysis import report as report_module

    out = analysis_report.folder
    assert analysis_report.exit_code == 0
    text = analysis_report.printed
    assert "| quantity | thesis value | computed value | difference | unit | note |" in text
    assert "| u_cr, eq. 3.9 closed form | 1.8979 | 1.8979 |" in text
    assert f"level flight loses stability at u_H = {analysis_report.hopf.point.speed_mps:.4f} m/s" in text
    assert sorted(p.name for p in out.iterdir()) == sorted([report_module.REPORT_FILE, MARKER_FILE])
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(out.stat().st_mode) == 0o777 & ~mask  # the usual mode, not mkdtemp's 0o700
    with pytest.raises(SystemExit, match="exists: choose another output folder or pass overwrite=True"):
        main(["analyze", "--out", str(out)])
    existing = tmp_path / "analysis"  # the shared report stays as it is: --force replaces a copy of it
    shutil.copytree(out, existing)
    (existing / "notes.txt").write_text("a file the earlier report did not have")
    # --force replaces an earlier report (its marker file says so) through the same atomic replacement,
    # without computing the findings a second time (tens of seconds).
    calls = _stand_in_findings(monkeypatch, analysis_report.hopf)
    assert main(["analyze", "--out", str(existing), "--force"]) == 0
    assert (
        calls == ["suboff"]
        and json.loads((existing / report_module.REPORT_FILE).read_text())["published"] == []
    )
    assert not (existing / "notes.txt").exists()  # the earlier report was replaced, not written into


def test_evaluate_end_to_end_on_the_tiny_suite(tmp_path: Path, capsys):
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")
    out = tmp_path / "eval"
    assert (
        main(
            [
                "evaluate",
                "--suite",
                "tiny",
                "--episodes",
                "1",
                "--controllers",
                "thesis,reversal_aware",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    printed = capsys.readouterr()
    text = printed.out
    assert "| controller |" in text and "reversal_aware" in text and "thesis" in text
    # stderr is not a terminal here (a log file, CI): progress comes as lines, the last at 100%
    progress = [line for line in printed.err.splitlines() if line.startswith("evaluate: ")]
    assert progress[-1].startswith("evaluate: 4/4 episodes, 100% (reversal_aware on LowSpeed); ")
    # and then what the seconds after 100% are spent on
    lines = printed.err.splitlines()
    assert lines[lines.index(progress[-1]) + 1] == "(scoring the 4 episodes and writing the tables and plots)"
    assert (out / "results.csv").is_file() and (out / "leaderboard.md").is_file()
    with pytest.raises(SystemExit, match="exists"):
        main(["evaluate", "--suite", "tiny", "--episodes", "1", "--out", str(out), "--no-progress"])


def test_evaluate_rejects_unknown_names(tmp_path: Path):
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")
    with pytest.raises(SystemExit, match=r"controller='pid' is unknown: must be one of \[") as error:
        main(["evaluate", "--controllers", "pid", "--out", str(tmp_path / "x"), "--no-progress"])
    assert all(f"'{name}'" in str(error.value) for name in ("thesis", "scheduled", "lqr", "reversal_aware"))
    with pytest.raises(SystemExit, match=r"suite|scenario"):
        main(["evaluate", "--suite", "Fastest", "--out", str(tmp_path / "y"), "--no-progress"])
    with pytest.raises(SystemExit, match="cannot import controller package 'nopkg'"):
        main(["evaluate", "--plugins", "nopkg", "--out", str(tmp_path / "z")])


_SCENARIO_PLUGIN = """
from subenv.scenarios import get_scenario, register_scenario

register_scenario(get_scenario("LowSpeed").replace(name="MyScenario", duration_s=20.0))
"""


def test_a_plugins_scenario_is_evaluated_by_name(tmp_path: Path, monkeypatch, capsys):
    """A plugin that registers a scenario, and nothing else, makes it a suite of ``subenv evaluate``."""
    import gymnasium as gym

    from subenv.scenarios import registry

    monkeypatch.setattr(registry, "_REGISTRY", dict(registry._REGISTRY))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_scenario.py").write_text(_SCENARIO_PLUGIN)
    out = tmp_path / "eval"
    argv = ["evaluate", "--plugins", "my_scenario.py", "--suite", "MyScenario", "--controllers", "thesis"]
    try:
        main([*argv, "--episodes", "1", "--no-plots", "--no-progress", "--out", str(out)])
    finally:
        sys.modules.pop("my_scenario", None)
        gym.registry.pop("subenv/MyScenario-v0", None)
    assert "| controller |" in capsys.readouterr().out
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [(row["controller"], row["scenario"]) for row in rows] == [("thesis", "MyScenario")]


@pytest.fixture
def no_work(monkeypatch):
    """Make the commands' real work (rollouts, the report's numbers) fail the test if it starts."""

    def refuse(*args, **kwargs):
        pytest.fail("the command started its work before checking its arguments")

    monkeypatch.setattr(subenv.evaluation.comparison, "roll_out", refuse)
    monkeypatch.setattr(subenv.analysis.report, "reproduce_numbers", refuse)


def _refuse_mkdir_in(monkeypatch, folder: Path) -> None:
    """Make ``folder`` unwritable, as chmod would for a user other than root (who may write anywhere)."""
    real_mkdir = os.mkdir

    def mkdir(path, *args, **kwargs):
        if Path(path).parent == folder:
            raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return real_mkdir(path, *args, **kwargs)

    monkeypatch.setattr(os, "mkdir", mkdir)


EVALUATE = ["evaluate", "--suite", "tiny", "--episodes", "1", "--controllers", "thesis", "--no-progress"]


@pytest.mark.parametrize("command", [EVALUATE, ["analyze"]], ids=["evaluate", "analyze"])
def test_an_output_folder_that_cannot_be_written_is_refused_before_any_work(
    tmp_path: Path, monkeypatch, no_work, command
):
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")
    (tmp_path / "afile").write_text("x")
    with pytest.raises(
        SystemExit,
        match=r"--out: output folder '.*afile/sub' cannot be created: '.*afile' is a "
        r"file, not a folder",
    ):
        main([*command, "--out", str(tmp_path / "afile" / "sub")])
    locked = tmp_path / "locked"
    locked.mkdir()
    _refuse_mkdir_in(monkeypatch, locked)
    with pytest.raises(
        SystemExit,
        match=r"--out: output folder '.*locked/results' cannot be created: Permission "
        r"denied",
    ):
        main([*command, "--out", str(locked / "results")])


@pytest.mark.parametrize("command", [EVALUATE, ["analyze"]], ids=["evaluate", "analyze"])
def test_force_replaces_only_an_earlier_result_of_the_command(tmp_path: Path, no_work, command):
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")
    project = tmp_path / "project"
    (project / ".git").mkdir(parents=True)
    (project / "src").mkdir()
    with pytest.raises(
        SystemExit,
        match=rf"--out: output folder '.*project' exists and is not an earlier result of "
        rf"subenv {command[0]}",
    ):
        main([*command, "--out", str(project), "--force"])
    assert sorted(p.name for p in project.iterdir()) == [".git", "src"]
    (tmp_path / "afile").write_text("x")
    with pytest.raises(SystemExit, match=r"--out: output folder '.*afile' exists and is not a folder"):
        main([*command, "--out", str(tmp_path / "afile"), "--force"])


class _WorkStarted(Exception):
    pass


@pytest.mark.parametrize("force", [[], ["--force"]], ids=["", "force"])
@pytest.mark.parametrize("command", [EVALUATE, ["analyze"]], ids=["evaluate", "analyze"])
def test_an_empty_out_folder_is_accepted(tmp_path: Path, monkeypatch, command, force):
    def started(*args, **kwargs):  # the command got past its checks of --out
        raise _WorkStarted

    monkeypatch.setattr(subenv.evaluation.comparison, "roll_out", started)
    monkeypatch.setattr(subenv.analysis.report, "reproduce_numbers", started)
    (tmp_path / "empty").mkdir()
    with pytest.raises(_WorkStarted):
        main(
            [
                *command,
                "--out",
                str(tmp_path / "empty"),
                *force,
                *(["--no-plots"] if command == EVALUATE else []),
            ]
        )
    assert [p.name for p in tmp_path.iterdir()] == ["empty"] and not any((tmp_path / "empty").iterdir())


@pytest.mark.parametrize(
    ("vehicle", "reason"),
    [
        ("nope", r"vehicle='nope' is unknown: must be one of \['remus100', 'suboff', 'suboff_fullscale'\]"),
        ("missing.toml", r"vehicle file 'missing.toml' does not exist"),
    ],
)
def test_analyze_with_a_bad_vehicle_is_a_one_line_error(tmp_path: Path, no_work, vehicle, reason):
    with pytest.raises(SystemExit, match=rf"^subenv analyze: --vehicle '{vehicle}': {reason}"):
        main(["analyze", "--vehicle", vehicle, "--out", str(tmp_path / "report")])
    assert list(tmp_path.iterdir()) == []


def test_analyze_with_a_singular_vehicle_is_a_one_line_error(tmp_path: Path, no_work):
    text = resources.files("subenv.vehicles.data").joinpath("suboff.toml").read_text("utf-8")
    # With M_qdot' = I_y' and Z_qdot' = 0 the mass matrix
    # [[m' - Z_wdot', -Z_qdot'], [-M_wdot', I_y' - M_qdot']] is singular.
    inertia_nd = 561.32 / (0.97 * 13.9792**5)  # I_y / (rho/2 L^5), in the file's US customary units
    singular = text.replace("M_qdot = -8.8e-4", f"M_qdot = {inertia_nd!r}").replace(
        "Z_qdot = -6.33e-4", "Z_qdot = 0.0"
    )
    path = tmp_path / "singular.toml"
    path.write_text(singular)
    with pytest.raises(SystemExit, match=r"^subenv analyze: --vehicle '.*singular.toml': "):
        main(["analyze", "--vehicle", str(path), "--out", str(tmp_path / "report")])


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--suite", "Nominal,"),
        ("--suite", ",Nominal"),
        ("--suite", "Nominal,,LowSpeed"),
        ("--suite", ""),
        ("--controllers", ""),
        ("--controllers", "thesis,"),
        ("--plugins", ""),
        ("--out", ""),
        ("--out", " "),
    ],
)
def test_evaluate_refuses_empty_names_and_an_empty_out(
    tmp_path: Path, monkeypatch, capsys, no_work, option, value
):
    monkeypatch.chdir(tmp_path)  # where the default --out would be written
    arguments = {"--suite": "tiny", "--controllers": "thesis", "--out": str(tmp_path / "eval"), option: value}
    with pytest.raises(SystemExit) as error:
        main(
            ["evaluate", "--episodes", "1", "--no-progress", *(x for pair in arguments.items() for x in pair)]
        )
    assert error.value.code == 2
    assert f"argument {option}: invalid value {value!r}: must be" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", [["demo", "--no-plot"], ["analyze"]], ids=["demo", "analyze"])
def test_an_empty_out_is_refused_by_every_command(capsys, no_work, command):
    with pytest.raises(SystemExit):
        main([*command, "--out", ""])
    assert "argument --out: invalid value '': must be a path, not empty" in capsys.readouterr().err


def test_evaluate_takes_scenario_names_for_the_suite(tmp_path: Path, capsys):
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")
    out = tmp_path / "eval"
    assert (
        main(
            [
                "evaluate",
                "--suite",
                "Nominal",
                "--episodes",
                "1",
                "--controllers",
                "thesis",
                "--no-plots",
                "--out",
                str(out),
                "--no-progress",
            ]
        )
        == 0
    )
    assert {row["scenario"] for row in csv.DictReader((out / "results.csv").open())} == {"Nominal"}
    with pytest.raises(
        SystemExit,
        match=r"suite='Fastest' is unknown: must be a suite name \(one of \['default'.*"
        r"or a scenario name \(one of \['Nominal'",
    ):
        main(["evaluate", "--suite", "Fastest", "--out", str(tmp_path / "y"), "--no-progress"])


class _Reached(Exception):
    """The command got past its checks to its work."""


_WORDS = st.sampled_from(
    [
        "tiny",
        "Nominal",
        "LowSpeed",
        "nope",
        "",
        ",",
        "thesis",
        "lqr",
        "-1",
        "0",
        "3",
        "1e9",
        "Nominal,",
        "subenv/Nominal-v0",
        "x/y",
        "\x00",
        " ",
        "é",
    ]
)


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    options=st.lists(
        st.tuples(
            st.sampled_from(["--suite", "--controllers", "--episodes", "--seed", "--plugins", "--out"]),
            _WORDS,
        ),
        max_size=4,
    )
)
def test_evaluate_arguments_are_refused_in_one_line_or_reach_the_work(options, tmp_path_factory, monkeypatch):
    """Fuzzing ``subenv evaluate``'s arguments: each is refused by a usage error or a one-line
    message (no traceback), or the command reaches its rollouts."""

    def reached(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise _Reached

    monkeypatch.setattr(subenv.evaluation.comparison, "roll_out", reached)
    argv = ["evaluate", "--no-progress", "--out", str(tmp_path_factory.mktemp("fuzz") / "out")]
    for flag, word in options:
        argv += [flag, word]
    try:
        main(argv)
    except _Reached:
        return
    except SystemExit as exit_:
        assert exit_.code == 2 or (isinstance(exit_.code, str) and "\n" not in exit_.code.strip()), exit_.code
        return
    pytest.fail(f"{argv} neither ran nor was refused")


COMMANDS = ("evaluate", "demo", "analyze", "sweep", "list", "train")


def test_help_lists_every_command_in_one_line(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--help"])
    assert exit_.value.code == 0
    lines = capsys.readouterr().out.splitlines()
    section = lines[lines.index("commands:") + 2 :]  # after the "<command>" line
    section = section[: section.index("")]
    assert [line.split()[0] for line in section] == list(COMMANDS)  # no help wraps onto a second line


def test_no_command_prints_the_help_as_a_usage_error(capsys):
    assert main([]) == 2  # argparse's status for a usage error
    printed = capsys.readouterr()
    assert printed.out == "" and "commands:" in printed.err
    assert all(f"    {command} " in printed.err for command in COMMANDS)


@pytest.mark.parametrize("command", [["demo"]], ids=["demo"])
def test_a_missing_matplotlib_is_one_line_naming_the_extra(tmp_path: Path, monkeypatch, no_work, command):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if not installed: `import matplotlib` fails
    monkeypatch.setattr(
        subenv.cli, "fly", lambda *args: pytest.fail("demo flew before checking for matplotlib")
    )
    with pytest.raises(SystemExit) as exit_:
        main([*command, "--out", str(tmp_path / "out")])
    message = str(exit_.value.code)
    assert message.startswith(f"subenv {command[0]}: ") and "\n" not in message
    assert "the 'plot' extra is needed for " in message and 'pip install "subenv[plot]"' in message
    assert "./dev installs every extra" in message
    assert not (tmp_path / "out").exists()


def test_evaluate_without_matplotlib_skips_the_plots_with_a_note(tmp_path: Path, monkeypatch, capsys):
    """A bare install's main job: the comparison runs, its tables are written, and one line says that
    the plots were skipped and how to get them."""
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if not installed: `import matplotlib` fails
    out = tmp_path / "out"
    args = ["evaluate", "--suite", "tiny", "--episodes", "1", "--controllers", "thesis", "--no-progress"]
    assert main([*args, "--out", str(out)]) == 0
    (note,) = [line for line in capsys.readouterr().err.splitlines() if "plot" in line]
    assert note.startswith("(skipped the plots: the 'plot' extra is needed for the plots: ")
    assert 'pip install "subenv[plot]"' in note
    assert (out / "results.csv").is_file() and not list(out.rglob("*.png"))


def test_controllers_that_cannot_load_are_skipped_with_a_note(tmp_path: Path, monkeypatch, capsys):
    """The shipped agents without the rl extra: a one-line note when every controller runs, an error
    when one is asked for by name."""
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)
    monkeypatch.delitem(sys.modules, "subenv_agents.shipped", raising=False)
    monkeypatch.setattr(controller, "_REGISTRY", {"thesis": controller._REGISTRY["thesis"]})
    monkeypatch.setattr(controller, "_UNAVAILABLE", {})
    monkeypatch.setattr(controller, "entry_points", lambda group: [])  # only the declarations below
    group = controller.ENTRY_POINT_GROUP
    declared = [EntryPoint(name, f"subenv_agents.shipped:{name}", group) for name in ("ppo", "sac")]
    unavailable = controller.discover_controllers(declared)
    assert sorted(unavailable) == ["ppo", "sac"] and controller.controller_names() == ["thesis"]
    assert unavailable["ppo"].startswith(
        "the 'rl' extra is needed for the shipped agents: pip install \"subenv[rl]\""
    )

    monkeypatch.setattr(
        subenv.evaluation.comparison, "roll_out", lambda *a, **k: pytest.fail("reached the work")
    )
    assert main(["evaluate", "--list"]) == 0
    printed = capsys.readouterr()
    assert "controllers: thesis\n" in printed.out
    assert printed.err == f"(skipped ppo, sac: {unavailable['ppo']})\n"
    with pytest.raises(
        SystemExit, match=r"^subenv evaluate: controller 'sac' cannot load: the 'rl' extra is needed"
    ):
        main(["evaluate", "--controllers", "thesis,sac", "--out", str(tmp_path / "out")])


def test_evaluate_takes_a_vehicle_and_says_what_is_not_scaled(tmp_path: Path, capsys) -> None:
    out = tmp_path / "full"
    main(
        [
            "evaluate",
            "--vehicle",
            "suboff_fullscale",
            "--controllers",
            "thesis",
            "--suite",
            "tiny",
            "--episodes",
            "1",
            "--no-plots",
            "--no-progress",
            "--out",
            str(out),
        ]
    )
    err = capsys.readouterr().err
    assert (
        "--vehicle suboff_fullscale: the scenarios, the success criterion and the classical baselines' "
        "designs are Froude-scaled to its 102.3 m (x24)" in err
    )
    assert json.loads((out / "run.json").read_text())["vehicle"] == "suboff_fullscale"
    with pytest.raises(
        SystemExit,
        match=r"vehicle='boat' is unknown: must be one of \['remus100', 'suboff', 'suboff_fullscale'\]",
    ):
        main(["evaluate", "--vehicle", "boat", "--out", str(tmp_path / "none")])
    assert not (tmp_path / "none").exists()


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (
            '{"plane_rate_limit_radps": -1}',
            "subenv evaluate: env_kwargs: plane_rate_limit_radps=-1 is invalid",
        ),
        ('{"plane_rate": 0.05}', "subenv evaluate: env_kwargs: 'plane_rate' is unknown: must be one of"),
        ('{"control": "independent"}', "subenv evaluate: env_kwargs: 'control' cannot be set there"),
    ],
)
def test_evaluate_refuses_bad_env_kwargs_in_one_line_before_any_work(tmp_path: Path, no_work, value, message):
    with pytest.raises(SystemExit) as exit_:
        main([*EVALUATE, "--no-plots", "--env-kwargs", value, "--out", str(tmp_path / "out")])
    assert str(exit_.value.code).startswith(message) and "\n" not in str(exit_.value.code)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("value", "reason"), [("{nope", "not JSON"), ("[0.05]", "must be a JSON object")])
def test_evaluate_env_kwargs_must_be_a_json_object(tmp_path: Path, capsys, no_work, value, reason):
    with pytest.raises(SystemExit) as exit_:
        main([*EVALUATE, "--env-kwargs", value, "--out", str(tmp_path / "out")])
    assert (
        exit_.value.code == 2
        and f"argument --env-kwargs: invalid value {value!r}: {reason}" in capsys.readouterr().err
    )


def test_evaluate_passes_env_kwargs_to_the_environments_and_records_them(tmp_path: Path) -> None:
    pytest.importorskip("daqp", reason="the 'mpc' extra is not installed")
    out = tmp_path / "out"
    settings = '{"plane_rate_limit_radps": 0.05, "max_pitch_rad": 0.4}'
    # One scenario of the tiny suite: what is recorded is the same for each (mpc runs slowly).
    assert (
        main(
            [
                *EVALUATE,
                "--suite",
                "Nominal",
                "--controllers",
                "thesis,mpc,mpc:uninformed",
                "--no-plots",
                "--env-kwargs",
                settings,
                "--out",
                str(out),
            ]
        )
        == 0
    )
    record = json.loads((out / "run.json").read_text())
    assert record["env_kwargs"] == {"plane_rate_limit_radps": 0.05, "max_pitch_rad": 0.4}
    assert [(c["name"], c["informed"]) for c in record["controllers"]] == [
        ("thesis", False),
        ("mpc", True),
        ("mpc:uninformed", False),
    ]
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert {r["controller"]: r["informed"] for r in rows} == {
        "thesis": "False",
        "mpc": "True",
        "mpc:uninformed": "False",
    }


def test_evaluate_says_once_that_episodes_left_the_free_surface_models_range(tmp_path: Path, capsys):
    """The environments' warning (once per environment) is one line for the whole run, not a warning per
    environment among the leaderboard's lines."""
    argv = ["evaluate", "--suite", "PeriscopeDepth-v2", "--episodes", "8", "--controllers", "thesis"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", FreeSurfaceRangeWarning)  # (one that escaped would fail the run)
        assert main([*argv, "--no-plots", "--no-progress", "--out", str(tmp_path / "e")]) == 0
    err = capsys.readouterr().err
    said = [line for line in err.splitlines() if "free-surface model's range" in line]
    assert len(said) == 1 and said[0].startswith("(in 1 of the environments an episode left"), err
    assert "Warning" not in err
