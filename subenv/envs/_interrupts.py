"""Ctrl-C held back while numba boxes a typed list of generators.

numba's typed lists run Python code when they are built or changed (each ``numpy.random.Generator``
is unboxed through its bit generator's ``ctypes`` interface, one dispatcher call per item). A
``KeyboardInterrupt`` raised in there is reported as ``SystemError: ... returned a result with an
exception set`` and can leave an item counted twice, which the C heap later reports as a double
free (issue 18's probe: ``_thread.interrupt_main()`` every 1.3 ms during seeded resets). The
environments build these lists only when generators change (a seeded reset, unpickling), so they do
it with SIGINT held here and delivered as soon as the list is complete. (A step only passes the list
to a compiled function: an interrupt there is raised before the compiled code runs, as numba's
``TypeError: can't unbox``, and changes nothing.)

No maintained library defers a signal around a block of code; this is the usual idiom of Python's
``signal`` module, written once.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

__all__ = ["interrupts_deferred"]


@contextmanager
def interrupts_deferred() -> Iterator[None]:
    """Run the block with SIGINT held: a Ctrl-C (or ``_thread.interrupt_main()``) that arrives inside
    is handed to the previous handler when the block ends. Outside the main thread (where Python never
    raises ``KeyboardInterrupt``) the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[tuple[int, FrameType | None]] = []

    def hold(signum: int, frame: FrameType | None) -> None:
        received.append((signum, frame))

    previous = signal.getsignal(signal.SIGINT)
    if previous is None:  # (a handler installed from C: it could not be put back)
        yield
        return
    signal.signal(signal.SIGINT, hold)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if received:
            if callable(previous):
                previous(*received[0])
            elif previous == signal.SIG_DFL:
                signal.raise_signal(signal.SIGINT)
