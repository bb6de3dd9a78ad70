"""Atomic files and folders: complete or absent, even when the writer is killed (subenv.atomic)."""

from __future__ import annotations

import errno
import os
import signal
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from subenv import atomic
from subenv.atomic import MARKER_FILE, OutputDirError, atomic_output_dir, atomic_write_text

PARTS = ("a.txt", "b.txt", "c.txt")

# A writer that replaces OUT and kills itself with SIGKILL at its KILL_AT-th step (a rename, a replace,
# an exchange, a deletion), or finishes if it has fewer. The module is loaded from its file alone, so
# the child starts in milliseconds. FALLBACK=1 makes the exchange unavailable.
CHILD = r"""
import importlib.util, os, shutil, signal, sys
from pathlib import Path

out, kill_at, fallback = Path(sys.argv[1]), int(sys.argv[2]), sys.argv[3] == "1"
spec = importlib.util.spec_from_file_location("atomic", sys.argv[4])
atomic = importlib.util.module_from_spec(spec)
spec.loader.exec_module(atomic)
steps = 0

def counted(function):
    def step(*args, **kwargs):
        global steps
        steps += 1
        if steps == kill_at:
            os.kill(os.getpid(), signal.SIGKILL)
        return function(*args, **kwargs)
    return step

os.rename, os.replace, shutil.rmtree = counted(os.rename), counted(os.replace), counted(shutil.rmtree)
atomic._exchange = counted((lambda a, b: False) if fallback else atomic._exchange)
with atomic.atomic_output_dir(out, overwrite=True) as tmp:
    for name in ("a.txt", "b.txt", "c.txt"):
        (tmp / name).write_text("new")
"""


def _write(out: Path, version: str, overwrite: bool = False) -> None:
    with atomic_output_dir(out, overwrite=overwrite) as tmp:
        for name in PARTS:
            (tmp / name).write_text(version)


def _state(out: Path) -> str:
    """'old' or 'new' for a complete folder of one version; anything else names what is wrong."""
    if not out.is_dir():
        return "missing"
    versions = {(out / name).read_text() if (out / name).is_file() else "partial" for name in PARTS}
    return (
        versions.pop()
        if len(versions) == 1 and sorted(p.name for p in out.iterdir()) == list(PARTS)
        else "mixed"
    )


def _exchange_works(tmp_path: Path) -> bool:
    (tmp_path / "x").mkdir()
    (tmp_path / "y").mkdir()
    try:
        return atomic._exchange(tmp_path / "x", tmp_path / "y")
    finally:
        (tmp_path / "x").rmdir()
        (tmp_path / "y").rmdir()


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL and flock are POSIX")
@pytest.mark.parametrize("fallback", [False, True], ids=["exchange", "rename-fallback"])
def test_a_writer_killed_at_any_step_leaves_a_complete_folder(tmp_path: Path, fallback: bool):
    if not fallback and not _exchange_works(tmp_path):
        pytest.skip("this system or file system has no renameat2(RENAME_EXCHANGE)")
    kill_at = 1
    while True:
        parent = tmp_path / f"kill{kill_at}"
        out = parent / "results"
        _write(out, "old")
        child = subprocess.run(
            [sys.executable, "-c", CHILD, str(out), str(kill_at), str(int(fallback)), atomic.__file__],
            check=False,
            capture_output=True,
            text=True,
        )
        if child.returncode == 0:
            assert _state(out) == "new" and os.listdir(parent) == ["results"]
            break
        assert child.returncode == -signal.SIGKILL, child.stderr
        if not fallback:  # the exchange: never a moment without a complete folder at the path
            assert _state(out) in ("old", "new"), f"killed at step {kill_at}"
        # The next writer beside it puts things right before anything else, even one that then refuses.
        with pytest.raises(FileExistsError), atomic_output_dir(out):
            pytest.fail("the folder exists: the block must not run")
        assert _state(out) in ("old", "new"), f"killed at step {kill_at}"
        assert os.listdir(parent) == ["results"], f"killed at step {kill_at}: leftovers"
        kill_at += 1
    assert kill_at >= (5 if fallback else 2)  # every step was a kill point


def test_a_live_writers_temporary_folder_is_not_swept(tmp_path: Path):
    with atomic_output_dir(tmp_path / "first") as first:
        (first / "a.txt").write_text("first")
        _write(tmp_path / "second", "second")  # sweeps the parent on entry
        assert (first / "a.txt").read_text() == "first"
    assert (tmp_path / "first" / "a.txt").read_text() == "first" and _state(tmp_path / "second") == "second"


def test_overwrite_replaces_only_an_earlier_result_of_the_same_kind(tmp_path: Path):
    project = tmp_path / "project"
    (project / ".git").mkdir(parents=True)
    (project / "src").mkdir()
    with (
        pytest.raises(
            FileExistsError,
            match=r"'.*project' exists and is not an earlier result of my tool \(it has "
            r"no \.subenv-output file",
        ),
        atomic_output_dir(project, overwrite=True, kind="my tool"),
    ):
        pytest.fail("the block must not run")
    assert sorted(p.name for p in project.iterdir()) == [".git", "src"]

    out = tmp_path / "out"
    with atomic_output_dir(out, kind="my tool") as tmp:
        (tmp / "one.txt").write_text("1")
    assert (out / MARKER_FILE).read_text() == "my tool\n"
    with (
        pytest.raises(FileExistsError, match="not an earlier result of other tool"),
        atomic_output_dir(out, overwrite=True, kind="other tool"),
    ):
        pytest.fail("the block must not run")
    with atomic_output_dir(out, overwrite=True, kind="my tool") as tmp:
        (tmp / "two.txt").write_text("2")
    assert sorted(p.name for p in out.iterdir()) == [MARKER_FILE, "two.txt"]


def test_a_folder_that_cannot_be_created_is_reported_before_the_block(tmp_path: Path, monkeypatch):
    (tmp_path / "afile").write_text("x")
    with (
        pytest.raises(
            OutputDirError,
            match=r"output folder '.*afile/sub' cannot be created: '.*afile' is a "
            r"file, not a folder",
        ),
        atomic_output_dir(tmp_path / "afile" / "sub"),
    ):
        pytest.fail("the block must not run")

    locked = tmp_path / "locked"
    locked.mkdir()
    real_mkdir = os.mkdir

    def refuse(path, *args, **kwargs):  # what a read-only parent does (root may write anywhere)
        if Path(path).parent == locked:
            raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return real_mkdir(path, *args, **kwargs)

    monkeypatch.setattr(os, "mkdir", refuse)
    with (
        pytest.raises(OutputDirError, match=r"'.*locked/out' cannot be created: Permission denied"),
        atomic_output_dir(locked / "out"),
    ):
        pytest.fail("the block must not run")
    assert list(locked.iterdir()) == []


def test_folders_and_files_get_the_usual_modes(tmp_path: Path):
    mask = os.umask(0o022)
    try:
        with atomic_output_dir(tmp_path / "out") as tmp:
            atomic_write_text(tmp / "a.txt", "a")
    finally:
        os.umask(mask)
    assert stat.S_IMODE((tmp_path / "out").stat().st_mode) == 0o755  # not mkdtemp's 0o700
    assert stat.S_IMODE((tmp_path / "out" / "a.txt").stat().st_mode) == 0o644  # not mkstemp's 0o600
