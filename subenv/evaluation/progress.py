"""What a long evaluation tells the person waiting for it: progress, and the first run's compilation.

- :class:`Progress`: episodes done out of the total, on stderr. On a terminal, tqdm's bar; otherwise
  (output going to a log file, CI) :data:`LOG_LINES` lines over the run, with the time
  elapsed and an estimate of the time left, so that a log shows the run is alive.
- :func:`compile_notice` (:mod:`subenv.envs._compiling`, re-exported): the first environment calls
  of a process load the compiled physics from numba's cache, or compile it when the cache is cold (the
  first run after installing or editing the kernels' sources); when numba compiles, the environments
  print a one-line notice saying why nothing moves.
"""

from __future__ import annotations

import math
import sys
import time
from typing import Any, Final, TextIO

from subenv.envs._compiling import COMPILE_NOTICE, compile_notice

__all__ = ["COMPILE_NOTICE", "LOG_LINES", "Progress", "compile_notice"]

LOG_LINES: Final = 20
"""Without a terminal, a progress line each time another 1/20 (5%) of the episodes is done."""


class Progress:
    """Work done out of ``total`` (episodes, or another ``unit``), on ``stream`` (default stderr);
    nothing when not ``enabled``.

    :meth:`describe` names what runs now, :meth:`update` counts, :meth:`close` ends the bar.
    """

    def __init__(
        self,
        total: int,
        *,
        enabled: bool = True,
        stream: TextIO | None = None,
        label: str = "evaluate",
        unit: str = "episode",
    ) -> None:
        self.total, self.label, self.unit, self.done = total, label, unit, 0
        self.stream = sys.stderr if stream is None else stream
        self._what = ""
        self._start = time.perf_counter()
        self._logged = 0  # twentieths of the total reported so far
        self._bar: Any = None
        self._log = False
        if enabled:
            if _is_terminal(self.stream):
                from tqdm.auto import tqdm

                self._bar = tqdm(total=total, desc=label, unit=unit, dynamic_ncols=True, file=self.stream)
            else:
                self._log = True

    def describe(self, what: str) -> None:
        """What runs now (e.g. ``"lqr on LowSpeed"``): the bar's description, and the log lines'."""
        self._what = what
        if self._bar is not None:
            self._bar.set_description(what)

    def update(self, episodes: int = 1) -> None:
        """Count ``episodes`` more done: the bar advances, or a log line is printed each time another
        1/:data:`LOG_LINES` of the total is reached."""
        self.done += episodes
        if self._bar is not None:
            self._bar.update(episodes)
        elif self._log:
            reached = self.done * LOG_LINES // max(self.total, 1)
            if reached > self._logged:
                self._logged = reached
                print(self.line(time.perf_counter() - self._start), file=self.stream, flush=True)

    def line(self, elapsed_s: float) -> str:
        """The log line after ``elapsed_s`` seconds: work done, percent, elapsed and time left."""
        fraction = self.done / self.total if self.total else 1.0
        left = elapsed_s * (1.0 - fraction) / fraction if fraction > 0 else math.nan
        what = f" ({self._what})" if self._what else ""
        return (
            f"{self.label}: {self.done}/{self.total} {self.unit}s, {fraction:.0%}{what}; "
            f"{_clock(elapsed_s)} elapsed, ETA {_clock(left)}"
        )

    def close(self) -> None:
        """End the bar (a no-op without one); safe to call more than once."""
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
