"""Files and folders written completely or not at all, even when the writer is killed.

A file is written to a temporary sibling (:func:`tempfile.mkstemp`), flushed to disk and renamed
over the target with :func:`os.replace`: at every instant the path holds the old file (or nothing)
or the new one, complete.

A folder is assembled in a temporary sibling (:func:`tempfile.mkdtemp`) and renamed into place
when the block that writes it succeeds:

- at a free path, or over an empty folder (replacing one loses nothing; POSIX ``rename`` does it
  in one step), the path holds what it held before, or the new folder, complete;
- over an earlier folder (``overwrite``, ``--force``), the old folder is renamed aside, the new one
  renamed in, and the old one deleted. The path holds the old folder or the new one, complete,
  except between the two renames, when it holds nothing and the old folder, complete, is beside it
  under a hidden name ending in ``.old``. If the second rename fails, the old folder is put back.
  (The standard library has no atomic exchange of two folders; Linux's
  ``renameat2(RENAME_EXCHANGE)`` would close that window, at the price of ctypes and a fallback
  wherever it is missing.)

Leftovers of killed writers. Every temporary sibling is named
``.<name>.<host>-<pid>.<random>.tmp`` (``.old`` for an old folder moved aside), after the machine
and the process that wrote it. Before a path is written or checked (:func:`atomic_write_bytes`,
:func:`check_output_dir`, :func:`atomic_output_dir`), the siblings that writers of that path on
this machine left when they died (their process no longer exists) are put right: an old folder
moved aside goes back if the path is empty or absent, everything else is deleted. A live writer's
siblings are never touched. A dead writer's sibling stays if its process id has meanwhile been
reused (until that process ends), or if it was written on another machine (a shared file system),
or on a system without POSIX processes (Windows): a hidden name beside the output, which may be
deleted by hand, or, for an old folder whose path is empty, renamed back.

``--force`` must not delete what a command did not write: a folder made by
:func:`atomic_output_dir` with a ``kind`` holds a marker file (:data:`MARKER_FILE`) naming the kind,
and only such a folder is replaced.
"""

from __future__ import annotations

import contextlib
import glob
import os
import shutil
import socket
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Final

__all__ = [
    "MARKER_FILE",
    "OutputDirError",
    "atomic_output_dir",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_output_dir",
]

MARKER_FILE: Final = ".subenv-output"
"""A file in an output folder naming the kind of result it holds (e.g. ``subenv evaluate``)."""


class OutputDirError(ValueError):
    """The output folder cannot be created where it was asked for (the message says why)."""


def _writers(target: Path) -> str:
    """The start of the temporary siblings' names of ``target`` written on this machine."""
    return f".{target.name}.{socket.gethostname()}-"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)  # (signal 0: the existence check, nothing is sent)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):  # another user's process; not a process id of ours
        pass
    return True


def _empty_or_absent(path: Path) -> bool:
    try:
        return not os.path.lexists(path) or (path.is_dir() and not path.is_symlink() and not os.listdir(path))
    except OSError:  # unreadable: it may hold something
        return False


def _clean_up(target: Path) -> None:
    """Put right what writers of ``target`` on this machine left when they died (module docstring)."""
    if os.name != "posix":  # (Windows' os.kill(pid, 0) sends a Ctrl-C instead of checking)
        return
    start = _writers(target)
    for leftover in sorted(target.parent.glob(glob.escape(start) + "*")):  # (none if no parent folder)
        pid, _, rest = leftover.name[len(start) :].partition(".")
        if not (pid.isdigit() and rest.endswith((".tmp", ".old"))) or _alive(int(pid)):
            continue
        with contextlib.suppress(FileNotFoundError):  # (another writer put it right meanwhile)
            if rest.endswith(".old") and _empty_or_absent(target):
                os.rename(leftover, target)  # killed between the two renames of a replacement
            elif leftover.is_dir():
                shutil.rmtree(leftover, ignore_errors=True)
            else:
                leftover.unlink()


def _usual_mode(path: str | Path, mode: int) -> None:
    """Give ``path`` the mode ``open`` or ``mkdir`` would have (mkstemp: 0o600, mkdtemp: 0o700)."""
    mask = os.umask(0o077)  # (reading the umask sets it: a strict one meanwhile, for other threads' files)
    os.umask(mask)
    os.chmod(path, mode & ~mask)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` completely or not at all (temporary file, then ``os.replace``)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    _clean_up(target)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f"{_writers(target)}{os.getpid()}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        _usual_mode(tmp, 0o666)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return target


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` completely or not at all."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def _marker(folder: Path) -> str | None:
    try:
        return (folder / MARKER_FILE).read_text("utf-8").strip()
    except (OSError, UnicodeDecodeError):
        return None


def check_output_dir(path: str | os.PathLike[str], overwrite: bool, kind: str | None = None) -> Path:
    """Raise FileExistsError unless ``path`` is free (absent, or an empty folder), or replaceable with
    ``overwrite``.

    A folder is replaceable if ``overwrite`` is true and, when ``kind`` is given, it holds an
    earlier result of that kind (its :data:`MARKER_FILE` says ``kind``). A file or link never is.
    First puts right what killed writers of ``path`` left beside it (see the module docstring).
    """
    out = Path(path)
    _clean_up(out)
    if _empty_or_absent(out):
        return out
    if out.is_symlink() or not out.is_dir():
        raise FileExistsError(
            f"output folder {str(out)!r} exists and is not a folder: choose another output folder"
        )
    if not overwrite:
        raise FileExistsError(
            f"output folder {str(out)!r} exists: choose another output folder or pass overwrite=True "
            "(--force)"
        )
    if kind is not None and _marker(out) != kind:
        raise FileExistsError(
            f"output folder {str(out)!r} exists and is not an earlier result of {kind} (it has no "
            f"{MARKER_FILE} file saying so): refusing to replace it; choose another output folder or "
            "delete this one yourself"
        )
    return out


def _why_not(out: Path, exc: OSError) -> str:
    """Why ``out`` could not be created: a file where a folder should be, or the OS's reason."""
    for ancestor in out.parents:
        if os.path.lexists(ancestor):
            if not ancestor.is_dir():
                return f"{str(ancestor)!r} is a file, not a folder"
            break
    return f"{exc.strerror or exc} ({str(exc.filename or out)!r})"


@contextlib.contextmanager
def atomic_output_dir(
    path: str | os.PathLike[str], overwrite: bool = False, *, kind: str | None = None
) -> Iterator[Path]:
    """Assemble a folder in a temporary sibling and put it at ``path`` when the block succeeds.

    On entry, before the block runs, ``path`` is checked with :func:`check_output_dir` and the
    temporary folder is created, which proves the parent writable. Nothing changes at ``path``
    until the block succeeds; then the folder is renamed into place (the module docstring says
    what the path holds at every instant). If the block raises, nothing changes.

    Parameters
    ----------
    path : path-like
        The folder to write. An empty folder there is replaced, with or without ``overwrite``.
    overwrite : bool
        Replace ``path`` if it is a folder (and, with ``kind``, an earlier result of that kind).
    kind : str, optional
        What writes the folder (e.g. ``"subenv evaluate"``): recorded in :data:`MARKER_FILE`, and
        required there of a folder that ``overwrite`` replaces.

    Raises
    ------
    FileExistsError
        ``path`` exists and may not be replaced (checked on entry and again before the rename).
    OutputDirError
        The folder cannot be created there (a file in the way, no permission, ...).

    Examples
    --------
    >>> with atomic_output_dir("results/eval", kind="my script") as tmp:  # doctest: +SKIP
    ...     write_csv(tmp / "results.csv", rows)
    """
    out = Path(path)
    check_output_dir(out, overwrite, kind)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f"{_writers(out)}{os.getpid()}.", suffix=".tmp"))
    except OSError as exc:
        raise OutputDirError(f"output folder {str(out)!r} cannot be created: {_why_not(out, exc)}") from exc
    try:
        _usual_mode(tmp, 0o777)
        if kind is not None:
            atomic_write_text(tmp / MARKER_FILE, kind + "\n")
        yield tmp
        check_output_dir(out, overwrite, kind)
        if _empty_or_absent(out):
            os.rename(tmp, out)
        else:
            old = tmp.with_suffix(".old")
            os.rename(out, old)
            try:
                os.rename(tmp, out)
            except BaseException:
                os.rename(old, out)
                raise
            shutil.rmtree(old, ignore_errors=True)  # (what resists stays, for the next writer to delete)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)  # the unfinished folder (gone if it was put in place)
