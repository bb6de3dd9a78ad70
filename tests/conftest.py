"""Shared fixtures, the opt-in ``slow`` marker, and a summary of measured figures."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # pygame renders headless in tests
os.environ.setdefault("MPLBACKEND", "Agg")

_MEASURED: list[tuple[str, str]] = []


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
