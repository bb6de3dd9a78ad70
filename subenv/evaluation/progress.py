"""What a long evaluation tells the person waiting for it: progress, and the first run's compilation.

- :class:`Progress`: episodes done out of the total, on stderr. On a terminal, tqdm's bar; otherwise
  (output going to a log file, CI) :data:`LOG_LINES` lines over the run, with the time
  elapsed and an estimate of the time left, so that a log shows the run is alive.
- :func:`compile_notice`: the first environment calls of a process load the compiled physics from
  numba's cache, or compile it when the cache is cold (the first run after installing or editing
  the kernels' sources); a one-line notice then says why nothing moves.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from types import TracebackType
from typing import Any, Final, TextIO

__all__ = ["COMPILE_NOTICE", "LOG_LINES", "NOTICE_DELAY_S", "Progress", "compile_notice"]

LOG_LINES: Final = 20
"""Without a terminal, a progress line each time another 1/20 (5%) of the episodes is done."""

NOTICE_DELAY_S: Final = 2.0
"""The first environment calls of a process are said to compile when they take longer than this: loaded
from numba's cache they take well under a second (README, "numba compile time": 0.6 s)."""

COMPILE_NOTICE: Final = "subenv: compiling the dynamics (first run only, about 20 s)..."
"""16 s on the development machine's two cores, ``subenv evaluate --suite tiny`` with an empty cache
(README, "numba compile time": 13 s for the kernels the harness calls); a loaded machine takes longer."""


class Progress:
    """Episodes done out of ``total``, on ``stream`` (default stderr); nothing when not ``enabled``.

    :meth:`describe` names what runs now, :meth:`update` counts episodes, :meth:`close` ends the bar.
    """

    def __init__(self, total: int, *, enabled: bool = True, stream: TextIO | None = None,
                 label: str = "evaluate") -> None:
        self.total, self.label, self.done = total, label, 0
        self.stream = sys.stderr if stream is None else stream
        self._what = ""
        self._start = time.perf_counter()
        self._logged = 0  # twentieths of the total reported so far
        self._bar: Any = None
        self._log = False
        if enabled:
            if _is_terminal(self.stream):
                from tqdm.auto import tqdm

                self._bar = tqdm(total=total, desc=label, unit="episode", dynamic_ncols=True, file=self.stream)
            else:
                self._log = True

    def describe(self, what: str) -> None:
        """What runs now (e.g. ``"lqr on LowSpeed"``): the bar's description, and the log lines'."""
        self._what = what
        if self._bar is not None:
            self._bar.set_description(what)

    def update(self, episodes: int = 1) -> None:
        self.done += episodes
        if self._bar is not None:
            self._bar.update(episodes)
        elif self._log:
            reached = self.done * LOG_LINES // max(self.total, 1)
            if reached > self._logged:
                self._logged = reached
                print(self.line(time.perf_counter() - self._start), file=self.stream, flush=True)

    def line(self, elapsed_s: float) -> str:
        """The log line after ``elapsed_s`` seconds: episodes done, percent, elapsed and time left."""
        fraction = self.done / self.total if self.total else 1.0
        left = elapsed_s * (1.0 - fraction) / fraction if fraction > 0 else math.nan
        what = f" ({self._what})" if self._what else ""
        return (f"{self.label}: {self.done}/{self.total} episodes, {fraction:.0%}{what}; "
                f"{_clock(elapsed_s)} elapsed, ETA {_clock(left)}")

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def _is_terminal(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def _clock(seconds: float) -> str:
    """``m:ss`` (``h:mm:ss`` from an hour; ``?`` when unknown)."""
    if not math.isfinite(seconds):
        return "?"
    s = round(seconds)
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


class _CompileNotice:
    """Arms a timer around a block of environment calls until the process's first rollout is over."""

    def __init__(self) -> None:
        self.pending = True
        """Until :meth:`settled`: the compiled physics may still be loading or compiling."""
        self._timer: threading.Timer | None = None

    def __enter__(self) -> None:
        if self.pending and self._timer is None:
            self._timer = threading.Timer(NOTICE_DELAY_S, self._say)
            self._timer.daemon = True
            self._timer.start()

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 traceback: TracebackType | None) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _say(self) -> None:
        if self.pending:
            self.pending = False  # once
            print(COMPILE_NOTICE, file=sys.stderr, flush=True)

    def settled(self) -> None:
        """The environments have reset and stepped once in this process: their kernels are loaded."""
        self.pending = False


_NOTICE = _CompileNotice()


def compile_notice() -> _CompileNotice:
    """The process's notice: ``with compile_notice(): <environment calls>`` prints
    :data:`COMPILE_NOTICE` on stderr if the block takes longer than :data:`NOTICE_DELAY_S`, until
    ``compile_notice().settled()`` says the kernels are loaded (then the block costs nothing)."""
    return _NOTICE
