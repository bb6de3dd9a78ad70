"""Shared fixtures, the opt-in ``slow`` marker, and a summary of measured figures."""

from __future__ import annotations

import contextlib
import io
import os
from pathlib import Path
from typing import NamedTuple

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # pygame renders headless in tests
os.environ.setdefault("MPLBACKEND", "Agg")
# One OpenBLAS thread (read when numpy/scipy load, which is after this file). The tests' matrices are
# at most 10 x 10: more threads do not split the work (the results are bitwise the same) but each call
# then waits for the pool; on 2 shared cores one gain-schedule design of the LQR baselines (190 CARE
# solves) took 1.5-3 s instead of 0.12 s.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# At least two numba threads (read once, when numba is first imported), so that the tests that step a
# vector environment on two threads run on a one-core machine too: results never depend on it.
os.environ["NUMBA_NUM_THREADS"] = str(max(2, int(os.environ.get("NUMBA_NUM_THREADS", "0") or 0), os.cpu_count() or 1))

_MEASURED: list[tuple[str, str]] = []


def pytest_configure(config: pytest.Config) -> None:
    """Register the controllers as this checkout's ``pyproject.toml`` declares them.

    The installed metadata, from which :func:`subenv.evaluation.controller_names` would read them,
    may be another checkout's or older than the declarations (an editable install keeps the entry
    points it was installed with; ./dev reinstalls when pyproject.toml changes). The installed path
    itself is tested from a wheel in ``tests/test_packaging.py``.
    """
    from importlib.metadata import EntryPoint

    from subenv.evaluation import ENTRY_POINT_GROUP, discover_controllers

    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib  # type: ignore[no-redef]

    pyproject = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    declared = pyproject["project"]["entry-points"][ENTRY_POINT_GROUP]
    discover_controllers(EntryPoint(name, value, ENTRY_POINT_GROUP) for name, value in declared.items())


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--run-slow", action="store_true", help="also run tests marked slow (minutes)")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if config.getoption("--run-slow"):
        return
    skip = pytest.mark.skip(reason="slow: opt in with --run-slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


@pytest.fixture
def report():
    """Record a measured figure; all of them are printed in the terminal summary."""

    def _report(name: str, value: str) -> None:
        _MEASURED.append((name, value))

    return _report


def pytest_terminal_summary(terminalreporter, exitstatus, config) -> None:  # type: ignore[no-untyped-def]
    if _MEASURED:
        terminalreporter.section("measured")
        for name, value in _MEASURED:
            terminalreporter.write_line(f"{name}: {value}")


@pytest.fixture(scope="session")
def suboff():
    from subenv import load_vehicle

    return load_vehicle("suboff")


class AnalysisReport(NamedTuple):
    folder: Path
    """Where ``subenv analyze --out <folder>`` wrote the report; it did not exist before."""
    exit_code: int
    printed: str
    """What the command printed (stdout)."""


@pytest.fixture(scope="session")
def analysis_report(tmp_path_factory: pytest.TempPathFactory) -> AnalysisReport:
    """The reproduction report of Riedel (1993), written once per session (tens of seconds).

    ``subenv analyze --out <folder>`` writes it: the command calls ``write_report(folder,
    load_vehicle("suboff"))``, so the tests of ``write_report`` (tests/analysis) and of the command
    (tests/test_cli.py) share this one folder. Its parent holds nothing else. Tests read it and must
    not change it; one that needs an existing report to replace works on a copy.
    """
    from subenv.cli import main

    folder = tmp_path_factory.mktemp("analysis") / "report"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exit_code = main(["analyze", "--out", str(folder)])
    return AnalysisReport(folder, exit_code, printed.getvalue())


@pytest.fixture(scope="session")
def local_ray():  # type: ignore[no-untyped-def]
    """One local Ray instance with 2 CPUs for every test that runs Ray tasks or Tune trials (a start costs
    5-10 s); the functions under test use it instead of starting their own."""
    ray = pytest.importorskip("ray", reason="the 'ray' extra is not installed")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield
    ray.shutdown()
