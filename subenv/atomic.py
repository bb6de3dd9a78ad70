"""Files and folders written completely or not at all, even when the writer is killed.

A file is written to a temporary sibling, flushed and renamed over the target (``os.replace``).
A folder is assembled in a temporary sibling and then put in place with one atomic step: on Linux
``renameat2(RENAME_EXCHANGE)`` swaps the new folder and the old one, so at every instant the path
holds the old complete folder or the new complete one; the old one, now at the temporary name, is
then deleted. ``os.rename`` cannot do this (it refuses to replace a non-empty folder) and Python has
no binding for the exchange; the small PyPI wrappers (``renameat2``, ``atomicswap``) have had no
release since 2022-23, so the call is made through ctypes, in a few lines (glibc >= 2.28; ext4, xfs,
btrfs and tmpfs support it).

Where the exchange is missing (another OS, an old C library, a file system without it) the old
folder is renamed to a hidden sibling and the new one renamed in. A writer killed between those two
renames leaves the path empty for a moment; the next writer of a folder in that parent puts the old
folder back (see below) before doing anything else.

Temporary siblings are named ``.<name>.subenv-<8 hex>.tmp`` (``.old`` for a folder moved aside) and
locked with ``flock`` by the process writing them. The lock goes when that process dies, however it
dies, so :func:`atomic_output_dir` deletes every unlocked one it finds beside the folder it writes:
whatever a killed run left behind goes on the next run. (Without ``fcntl``, e.g. on Windows, nothing
can tell a dead writer's temporary from a live one's, and leftovers stay.)

``--force`` must not delete what a command did not write: a folder made by :func:`atomic_output_dir`
with a ``kind`` holds a marker file (:data:`MARKER_FILE`) naming the kind, and only such a folder is
replaced.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import functools
import os
import re
import secrets
import shutil
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Final

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

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

_TEMPORARY = re.compile(r"\.(?P<name>.+)\.subenv-[0-9a-f]{8}\.(?P<role>tmp|old)")
_RENAME_EXCHANGE: Final = 2  # linux/fs.h: RENAME_EXCHANGE = (1 << 1)
_AT_FDCWD: Final = -100  # linux/fcntl.h
_NO_EXCHANGE: Final = (errno.ENOSYS, errno.EINVAL, errno.EOPNOTSUPP)  # kernel or file system lacks it


class OutputDirError(ValueError):
    """The output folder cannot be created where it was asked for (the message says why)."""


def _temporary_sibling(target: Path, role: str) -> Path:
    return target.with_name(f".{target.name}.subenv-{secrets.token_hex(4)}.{role}")


def _lock(fd: int) -> bool | None:
    """Take ``fd``'s exclusive lock without waiting: False if another open file holds it, None where
    the system or file system has no locks."""
    if fcntl is None:  # pragma: no cover - Windows
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    except OSError:  # e.g. ENOLCK on a file system without locks
        return None
    return True


def _create_locked(target: Path, make: Callable[[Path], int]) -> tuple[Path, int]:
    """A new temporary sibling of ``target`` made by ``make`` (returns an open fd), locked."""
    while True:
        path = _temporary_sibling(target, "tmp")
        try:
            fd = make(path)
        except FileExistsError:
            continue
        # A sweep by another writer may have deleted the new, still unlocked, entry: check it is ours.
        if _lock(fd) is not False and os.path.lexists(path) and os.stat(path).st_ino == os.fstat(fd).st_ino:
            return path, fd
        os.close(fd)


def _new_file(path: Path) -> int:
    return os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies


def _new_dir(path: Path) -> int:
    os.mkdir(path, 0o777)  # the umask applies (tempfile.mkdtemp would make it 0700)
    return os.open(path, os.O_RDONLY)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` completely or not at all (temporary file, then ``os.replace``)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp, fd = _create_locked(target, _new_file)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
            os.replace(tmp, target)  # before closing: the lock keeps sweeps off the temporary file
    except BaseException:
        tmp.unlink(missing_ok=True)
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
    """Raise FileExistsError unless ``path`` is free, or replaceable with ``overwrite``.

    A folder is replaceable if ``overwrite`` is true and, when ``kind`` is given, it holds an
    earlier result of that kind (its :data:`MARKER_FILE` says ``kind``). A file or link never is.
    """
    out = Path(path)
    if not os.path.lexists(out):
        return out
    if out.is_symlink() or not out.is_dir():
        raise FileExistsError(
            f"output folder {str(out)!r} exists and is not a folder: choose another output folder"
        )
    if not overwrite:
        raise FileExistsError(
            f"output folder {str(out)!r} exists: choose another output folder or pass overwrite=True (--force)"
        )
    if kind is not None and _marker(out) != kind:
        raise FileExistsError(
            f"output folder {str(out)!r} exists and is not an earlier result of {kind} (it has no {MARKER_FILE} "
            "file saying so): refusing to replace it; choose another output folder or delete this one yourself"
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


def _sweep(parent: Path) -> None:
    """Delete the temporary siblings dead writers left in ``parent``; put back a folder moved aside."""
    if fcntl is None or not parent.is_dir():  # pragma: no cover - Windows
        return
    for path in [p for p in parent.iterdir() if _TEMPORARY.fullmatch(p.name)]:
        try:  # a link or a FIFO with such a name is not ours: refuse to follow or wait on it
            fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
        except OSError:
            continue  # gone meanwhile, or not ours
        try:
            if not _lock(fd):
                continue  # its writer is alive, or nothing can tell (no locks here)
            match = _TEMPORARY.fullmatch(path.name)
            assert match is not None
            original = parent / match["name"]
            if match["role"] == "old" and not os.path.lexists(original):
                os.rename(path, original)  # killed between the two renames of the fallback
            elif path.is_dir():
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)
        finally:
            os.close(fd)


@functools.cache
def _renameat2() -> Callable[..., int] | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        function = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):  # glibc < 2.28, or another C library without it
        return None
    function.argtypes = (ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint)
    function.restype = ctypes.c_int
    return function  # type: ignore[no-any-return]


def _exchange(a: Path, b: Path) -> bool:
    """Swap the entries ``a`` and ``b`` in one atomic step; False where the system cannot."""
    function = _renameat2()
    if function is None:
        return False
    if function(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in _NO_EXCHANGE:
        return False
    raise OSError(code, os.strerror(code), str(b))


def _put_in_place(new: Path, out: Path) -> None:
    """Make the folder ``new`` appear at ``out``; the old folder, if any, ends up at ``new``."""
    if not os.path.lexists(out):
        os.rename(new, out)
    elif not _exchange(new, out):
        old = _temporary_sibling(out, "old")
        fd = os.open(out, os.O_RDONLY)  # locked, so that no sweep puts it back while we swap
        try:
            _lock(fd)
            os.rename(out, old)
            try:
                os.rename(new, out)
            except BaseException:
                os.rename(old, out)
                raise
            os.rename(old, new)
        finally:
            os.close(fd)


@contextlib.contextmanager
def atomic_output_dir(
    path: str | os.PathLike[str], overwrite: bool = False, *, kind: str | None = None
) -> Iterator[Path]:
    """Assemble a folder in a temporary sibling and put it at ``path`` when the block succeeds.

    On entry, before the block runs: leftovers of killed writers beside ``path`` are deleted (see
    the module docstring), ``path`` is checked with :func:`check_output_dir`, and the temporary
    folder is created, which proves the parent writable. Nothing is visible at ``path`` until the
    block succeeds; with ``overwrite`` the old folder is swapped out atomically and deleted. If the
    block raises, nothing changes.

    Parameters
    ----------
    path : path-like
        The folder to write.
    overwrite : bool
        Replace ``path`` if it is a folder (and, with ``kind``, an earlier result of that kind).
    kind : str, optional
        What writes the folder (e.g. ``"subenv evaluate"``): recorded in :data:`MARKER_FILE`, and
        required there of a folder that ``overwrite`` replaces.

    Raises
    ------
    FileExistsError
        ``path`` exists and may not be replaced (checked on entry and again before the swap).
    OutputDirError
        The folder cannot be created there (a file in the way, no permission, ...).

    Examples
    --------
    >>> with atomic_output_dir("results/eval", kind="my script") as tmp:  # doctest: +SKIP
    ...     write_csv(tmp / "results.csv", rows)
    """
    out = Path(path)
    with contextlib.suppress(OSError):  # an unusable parent is reported just below
        _sweep(out.parent)
    check_output_dir(out, overwrite, kind)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp, fd = _create_locked(out, _new_dir)
    except OSError as exc:
        raise OutputDirError(f"output folder {str(out)!r} cannot be created: {_why_not(out, exc)}") from exc
    try:
        if kind is not None:
            atomic_write_text(tmp / MARKER_FILE, kind + "\n")
        yield tmp
        check_output_dir(out, overwrite, kind)
        _put_in_place(tmp, out)
    finally:
        os.close(fd)
        shutil.rmtree(tmp, ignore_errors=True)  # the unfinished folder, or the old one swapped out
