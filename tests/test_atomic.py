"""Atomic files and folders: complete or absent, even when the writer is killed (subenv.atomic)."""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from subenv import atomic
from subenv.atomic import (
    MARKER_FILE,
    OutputDirError,
    atomic_output_dir,
    atomic_write_text,
    check_output_dir,
)

PARTS = ("a.txt", "b.txt", "c.txt")

# A writer that replaces OUT and kills itself with SIGKILL at its KILL_AT-th step (the writing of a
# file, a rename, a replace, a deletion), or finishes if it has fewer; with PAUSE it waits for a line
# on stdin once the folder is written, before putting it in place. The module is loaded from its file
# alone, so the child starts in milliseconds.
CHILD = r"""
import importlib.util, os, shutil, signal, sys
from pathlib import Path

out, kill_at, pause = Path(sys.argv[1]), int(sys.argv[2]), sys.argv[3] == "1"
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
write = counted(lambda path: path.write_text("new"))
with atomic.atomic_output_dir(out, overwrite=True) as tmp:
    for name in ("a.txt", "b.txt", "c.txt"):
        write(tmp / name)
    if pause:
        print("written", flush=True)
        sys.stdin.readline()
"""


def _child(out: Path, kill_at: int = 0, pause: bool = False) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-c", CHILD, str(out), str(kill_at), str(int(pause)), atomic.__file__],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _write(out: Path, version: str, overwrite: bool = False) -> None:
    with atomic_output_dir(out, overwrite=overwrite) as tmp:
        for name in PARTS:
            (tmp / name).write_text(version)


def _state(out: Path) -> str:
    """'old' or 'new' for a complete folder of one version, 'empty' or 'absent'; anything else names
    what is wrong."""
    if not os.path.lexists(out):
        return "absent"
    if not out.is_dir():
        return "not a folder"
    if not any(out.iterdir()):
        return "empty"
    versions = {(out / name).read_text() if (out / name).is_file() else "partial" for name in PARTS}
    return (
        versions.pop()
        if len(versions) == 1 and sorted(p.name for p in out.iterdir()) == list(PARTS)
        else "mixed"
    )


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL, and the leftovers are put right on POSIX only")
@pytest.mark.parametrize("before", ["old", "empty", "absent"])
def test_a_writer_killed_at_any_step_leaves_a_complete_folder(tmp_path: Path, before: str):
    kill_at, states = 1, set()
    while True:
        parent = tmp_path / f"kill{kill_at}"
        out = parent / "results"
        if before == "old":
            _write(out, "old")
        elif before == "empty":
            out.mkdir(parents=True)
        else:
            parent.mkdir()
        child = _child(out, kill_at)
        _, stderr = child.communicate()
        if child.returncode == 0:
            assert _state(out) == "new" and os.listdir(parent) == ["results"]
            break
        assert child.returncode == -signal.SIGKILL, stderr
        state = _state(out)
        states.add(state)
        moved_aside = [parent / n for n in os.listdir(parent) if n.endswith(".old")]
        if state == "absent" and before == "old":  # between the two renames: the old folder is beside it
            assert [_state(p) for p in moved_aside] == ["old"], f"killed at step {kill_at}"
        else:
            assert state in (before, "new"), f"killed at step {kill_at}"
        # The next writer of the path (here one that only checks it) puts right what the dead one left.
        with contextlib.suppress(FileExistsError):
            check_output_dir(out, overwrite=False)
        assert _state(out) in (before, "new"), f"killed at step {kill_at}"
        assert os.listdir(parent) == ([] if _state(out) == "absent" else ["results"]), f"killed at {kill_at}"
        kill_at += 1
    # Every step was a kill point: the writing, (for a replacement) the moment between the two renames,
    # the new folder in place.
    assert {before, "new"} | ({"absent"} if before == "old" else set()) == states


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL, and the leftovers are put right on POSIX only")
def test_a_live_writers_temporary_folder_is_left_and_a_dead_ones_deleted(tmp_path: Path):
    out = tmp_path / "results"
    _write(out, "old")
    live = _child(out, pause=True)
    try:
        assert live.stdout is not None and live.stdout.readline() == "written\n"
        dead = _child(out, kill_at=2)  # killed while writing its folder
        dead.communicate()
        assert dead.returncode == -signal.SIGKILL
        assert len(os.listdir(tmp_path)) == 3  # the folder, and the two writers' temporary folders
        _write(out, "mine", overwrite=True)
        (building,) = [p for p in tmp_path.iterdir() if p.name != "results"]  # the live writer's
        assert _state(building) == "new" and _state(out) == "mine"
    finally:
        _, stderr = live.communicate("\n")  # it puts its folder in place, over this one
    assert live.returncode == 0, stderr
    assert _state(out) == "new" and os.listdir(tmp_path) == ["results"]


def test_an_empty_folder_is_replaced_with_or_without_overwrite(tmp_path: Path):
    for overwrite in (False, True):
        out = tmp_path / f"out-{overwrite}"
        out.mkdir()
        assert check_output_dir(out, overwrite, kind="my tool") == out
        with atomic_output_dir(out, overwrite, kind="my tool") as tmp:
            (tmp / "one.txt").write_text("1")
        assert sorted(p.name for p in out.iterdir()) == [MARKER_FILE, "one.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out-False", "out-True"]  # nothing left beside
    (tmp_path / "target").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "target")  # a link to an empty folder is still a link
    with pytest.raises(FileExistsError, match="is not a folder"), atomic_output_dir(tmp_path / "link"):
        pytest.fail("the block must not run")


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
