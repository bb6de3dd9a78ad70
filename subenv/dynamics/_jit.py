"""How the physics is compiled: one numba configuration for every kernel.

The right-hand side, the hull integral and the environment transition are written once as
scalar functions and compiled with numba. There is no interpreted copy beside them: the batched
NumPy-facing functions (:func:`subenv.dynamics.derivatives`,
:func:`subenv.dynamics.crossflow_integrals`) are generalized ufuncs over the same compiled scalar
functions that the environments call.

- ``nogil=True``: the kernels release the GIL, so the vector environment steps slices of its
  sub-environments on Python threads (no OpenMP runtime, which does not survive ``fork``).
- ``cache=True``: compiled code is stored next to the sources (or in ``NUMBA_CACHE_DIR``), so
  only the first process on a machine pays the compile time (``benchmarks/speed.py`` reports it).
- ``error_model="numpy"``: division by zero gives inf/nan as in NumPy instead of raising, and
  saves the checks.
- No ``fastmath``: results stay IEEE, so the compiled integrator reproduces
  :func:`subenv.dynamics.rk4` over :func:`subenv.dynamics.derivatives` bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Final, TypeVar, cast

import numba

__all__ = ["KERNEL_OPTIONS", "gufunc", "inline_kernel", "kernel"]

KERNEL_OPTIONS: Final[dict[str, Any]] = {"cache": True, "nogil": True, "error_model": "numpy"}

FunctionT = TypeVar("FunctionT", bound=Callable[..., Any])


def kernel(fn: FunctionT) -> FunctionT:
    """``numba.njit`` with the package's options, compiled lazily on the first call."""
    return cast(FunctionT, numba.njit(**KERNEL_OPTIONS)(fn))


def inline_kernel(fn: FunctionT) -> FunctionT:
    """As :func:`kernel`, and inlined into the compiled callers (no call overhead, no reference counting
    of the array arguments): for the small functions called per state."""
    return cast(FunctionT, numba.njit(inline="always", **KERNEL_OPTIONS)(fn))


def gufunc(fn: Any, signature: str, layout: str) -> Any:
    """Compile ``fn`` as a generalized ufunc (NumPy broadcasting over the loop dimensions)."""
    return numba.guvectorize([signature], layout, cache=True)(fn)
