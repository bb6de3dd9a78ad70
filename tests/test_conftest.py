"""The suite's own set-up: how its tests are imported and grouped over pytest-xdist's workers."""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent


@pytest.mark.parametrize(
    "folder", sorted(p.name for p in TESTS.iterdir() if p.is_dir() and p.name.isidentifier())
)
def test_no_test_folder_is_found_for_a_module_of_its_name(folder: str) -> None:
    # Under pytest's default import mode tests/ was on sys.path, and tests/jax (no __init__.py) was the
    # package `jax` where JAX is not installed: importorskip("jax") passed, then the tests failed to import.
    spec = importlib.util.find_spec(folder)
    found = [*(spec.submodule_search_locations or ()), spec.origin or ""] if spec else []
    assert not any(Path(place).resolve().is_relative_to(TESTS) for place in found if place), found


def _suite(tmp_path: Path, files: dict[str, str]) -> Path:
    """A project of this repository's pytest configuration and tests/conftest.py, with these test files."""
    shutil.copy2(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    (tmp_path / "tests").mkdir()
    shutil.copy2(TESTS / "conftest.py", tmp_path / "tests" / "conftest.py")
    for name, text in files.items():
        (tmp_path / "tests" / name).write_text(text)
    return tmp_path


def _pytest(project: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", *args],
        cwd=project,
        capture_output=True,
        text=True,
        timeout=600,
    )


# The session fixture of tests/conftest.py, replaced by one that costs nothing (a module's fixture wins).
_USER = """
import pytest

@pytest.fixture(scope="session")
def analysis_report():
    return None

def test_uses_it(analysis_report):
    pass

def test_does_not(tmp_path):
    pass
"""


def test_the_users_of_a_shared_session_fixture_run_in_one_worker_and_every_file_in_one(
    tmp_path: Path,
) -> None:
    pytest.importorskip("xdist", reason="the 'test' extra is not installed")
    plain = "def test_one():\n    pass\n\ndef test_two():\n    pass\n"
    project = _suite(
        tmp_path, {"test_a.py": _USER, "test_b.py": _USER, "test_c.py": plain, "test_d.py": plain}
    )
    run = _pytest(project, "-n", "2", "--dist", "loadgroup", "-v")
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    ran = {test: worker for worker, test in re.findall(r"\[(gw\d+)\] .*PASSED (\S+)", run.stdout)}
    groups: dict[str, set[str]] = {}
    for test, worker in ran.items():
        groups.setdefault(test.rpartition("@")[2], set()).add(worker)
    # Every test of the files that use the fixture (those that do not use it too), in one group on one worker.
    assert groups.keys() == {"analysis_report", "tests/test_c.py", "tests/test_d.py"}, ran
    assert all(len(workers) == 1 for workers in groups.values()), ran
    assert len(ran) == 8, ran


def test_a_file_whose_tests_use_two_shared_session_fixtures_is_refused(tmp_path: Path) -> None:
    both = _USER + "\n@pytest.fixture(scope='session')\ndef small_run():\n    return None\n\n"
    both += "def test_uses_the_other(small_run):\n    pass\n"
    run = _pytest(_suite(tmp_path, {"test_both.py": both}), "--collect-only", "-q")
    assert run.returncode == pytest.ExitCode.USAGE_ERROR, run.stdout[-3000:] + run.stderr[-3000:]
    assert (
        "tests/test_both.py uses the session fixtures ['analysis_report', 'small_run'], each computed in its "
        "own group of files" in run.stderr
    )


def test_the_groups_started_first_are_groups_of_the_suite() -> None:
    # (a file renamed or a fixture gone would leave its group to be scheduled by chance, without a word)
    spec = importlib.util.spec_from_file_location("suite_conftest", TESTS / "conftest.py")
    assert spec and spec.loader
    conftest = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(conftest)
    for group in conftest.LONGEST_FIRST:
        assert group in conftest.SHARED_SESSION_FIXTURES or (ROOT / group).is_file(), group
    assert len(set(conftest.LONGEST_FIRST)) == len(conftest.LONGEST_FIRST)
