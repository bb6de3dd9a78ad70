"""A one-line notice while the first environment calls of a process load or compile the physics.

The environments' transition is compiled by numba and cached on disk: loaded from the cache, an
environment's first reset and step take well under a second; with a cold cache (the first run after
installing, or after editing the kernels' sources) they compile for about 20 s, during which nothing
else would be printed. Each environment wraps its first reset and its first step in
:func:`compile_notice`, which prints :data:`COMPILE_NOTICE` on stderr, once per process, when such a
call outlasts :data:`NOTICE_DELAY_S`. Later calls pass by it at the cost of one attribute test.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable
from types import TracebackType
from typing import Any, Final

__all__ = ["COMPILE_NOTICE", "NOTICE_DELAY_S", "compile_notice", "first_call"]

NOTICE_DELAY_S: Final = 2.0
"""A first call is said to compile when it takes longer than this: loaded from numba's cache the first
reset and step take well under a second (0.6 s: ``benchmarks/speed.py``'s compile table)."""

COMPILE_NOTICE: Final = "subenv: compiling the dynamics (first run only, about 20 s)..."
"""16 s on the development machine's two cores, ``subenv evaluate --suite tiny`` with an empty cache
(13 s for the kernels the harness calls, ``benchmarks/speed.py``'s compile table); a loaded machine
takes longer."""


class _CompileNotice:
    """Arms a timer around a block; the first timer of the process that runs out prints the notice."""

    def __init__(self) -> None:
        self.said = False
        """The notice has been printed (it is printed once per process)."""
        self._timer: threading.Timer | None = None

    def __enter__(self) -> None:
        if not self.said and self._timer is None:
            self._timer = threading.Timer(NOTICE_DELAY_S, self._say)
            self._timer.daemon = True
            self._timer.start()

    def __exit__(
        self, kind: type[BaseException] | None, value: BaseException | None, traceback: TracebackType | None
    ) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _say(self) -> None:
        if not self.said:
            self.said = True
            print(COMPILE_NOTICE, file=sys.stderr, flush=True)


_NOTICE = _CompileNotice()


def compile_notice() -> _CompileNotice:
    """The process's notice: ``with compile_notice(): <a first environment call>`` prints
    :data:`COMPILE_NOTICE` on stderr if the block takes longer than :data:`NOTICE_DELAY_S` (once per
    process). The environments do this themselves on their first reset and first step."""
    return _NOTICE


def first_call(pending: set[str], name: str, method: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """An environment's first call of ``method`` (its ``name`` in ``pending``), under the notice.

    ``name`` leaves ``pending`` first, so that ``method`` (which tests ``name in pending`` before its
    work) runs its body; if it raises, the next call is a first call again.
    """
    pending.discard(name)
    try:
        with compile_notice():
            return method(*args, **kwargs)
    except BaseException:
        pending.add(name)
        raise
