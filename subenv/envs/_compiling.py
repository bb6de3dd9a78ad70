"""A one-line notice while the first environment calls of a process compile the physics.

The environments' transition is compiled by numba and cached on disk: loaded from the cache, an
environment's first reset and step take well under a second; with a cold cache (the first run after
installing, or after editing the kernels' sources) they compile for about 30 s, during which nothing
else would be printed. Each environment wraps its first reset and its first step in
:func:`compile_notice`, which prints :data:`COMPILE_NOTICE` on stderr, once per process, when numba
starts compiling within such a call. The decision is numba's own: its ``"numba:compile"`` event
(:mod:`numba.core.event`) starts only when a dispatcher compiles a signature, never when it loads one
from its cache, so that a first call that is merely slow (a loaded machine) says nothing. Later calls
pass by it at the cost of one attribute test.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from types import TracebackType
from typing import Any, Final

from numba.core import event

__all__ = ["COMPILE_NOTICE", "compile_notice", "first_call"]

COMPILE_NOTICE: Final = "subenv: compiling the dynamics (first run only, about 30 s)..."
"""On the development machine's two cores, quiet, with an empty cache: 25 s for ``gym.make``, ``reset`` and
``step`` of ``subenv/DivePlane-v0``; 37 s of compiling in ``subenv evaluate --suite tiny`` (48 s in all,
against 11 s with the cache filled). A loaded machine takes longer."""


class _CompileNotice(event.Listener):
    """Listens to numba's compilations within a block; the first one of the process prints the notice."""

    def __init__(self) -> None:
        self.said = False
        """The notice has been printed (it is printed once per process)."""

    def __enter__(self) -> None:
        # Registered on each entry and unregistered on each exit, even once said: nested or concurrent
        # first calls stay balanced, and there are two per environment.
        event.register("numba:compile", self)

    def __exit__(
        self, kind: type[BaseException] | None, value: BaseException | None, traceback: TracebackType | None
    ) -> None:
        event.unregister("numba:compile", self)

    def on_start(self, compilation: event.Event) -> None:
        """Numba starts compiling a signature: say so, once per process, unless it is one of numba's own
        functions (its typed list's, which an environment's reset builds: numba compiles them in every
        process, in half a second; they are not the physics, which its cache keeps)."""
        dispatcher = (compilation.data or {}).get("dispatcher")
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", None) or ""
        if module.split(".")[0] == "numba":
            return
        if not self.said:
            self.said = True
            print(COMPILE_NOTICE, file=sys.stderr, flush=True)

    def on_end(self, compilation: event.Event) -> None:
        """Nothing to do when a compilation ends."""


_NOTICE = _CompileNotice()


def compile_notice() -> _CompileNotice:
    """The process's notice: ``with compile_notice(): <a first environment call>`` prints
    :data:`COMPILE_NOTICE` on stderr if numba compiles within the block (once per process). The
    environments do this themselves on their first reset and first step."""
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
