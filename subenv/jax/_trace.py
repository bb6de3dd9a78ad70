"""The JAX twin of a compiled scalar function of :mod:`subenv.dynamics` (:func:`traced`), and its contract.

A kernel that :func:`traced` hands to JAX is written for it (``tests/jax/test_contract.py`` checks
every kernel :mod:`subenv.jax` traces, from the source):

- the globals it names are other kernels, the helpers of :mod:`subenv.dynamics._jit` (``select``,
  ``minimum``, ``maximum``, ``clip``: kernels themselves, with one defined result on both backends,
  NaN included), the functions of :mod:`math` in :data:`MATH` and of NumPy in :data:`NUMPY`,
  ``range`` and ``len``, and module constants (numbers, booleans, strings and tuples of them);
- ``if``, conditional expressions, ``and``, ``or``, ``not``, chained comparisons, ``while`` and the
  bounds of ``range`` (its only loops) depend on static values only: literals, module constants,
  the kernel's parameters annotated :data:`~subenv.dynamics._jit.Static` (which its JAX callers pass as
  Python values: the configuration record, a count of columns), array shapes, and local names given
  only such values. Everything else is a traced array, so a condition on it is written as a
  ``select``.
"""

from __future__ import annotations

import math
import types
from collections.abc import Callable
from typing import Any, Final

import jax.numpy as jnp
import numpy as np

from subenv import _validation as check
from subenv.dynamics import free_surface as surface
from subenv.dynamics import hull as hull_table
from subenv.dynamics import waves as sea
from subenv.dynamics._jit import select

__all__ = ["MATH", "NUMPY", "replacement", "traced"]

MATH: Final = types.SimpleNamespace(
    sin=jnp.sin,
    cos=jnp.cos,
    exp=jnp.exp,
    sqrt=jnp.sqrt,
    fabs=jnp.fabs,
    isfinite=jnp.isfinite,
    isnan=jnp.isnan,
    floor=jnp.floor,
    nan=math.nan,
    inf=math.inf,
    pi=math.pi,
)
"""What a traced kernel may take from :mod:`math`, on JAX (IEEE functions: the same results for NaN,
infinities and signed zeros as numba's)."""
NUMPY: Final = types.SimpleNamespace(rint=jnp.rint, floor=jnp.floor)
"""What a traced kernel may take from NumPy (``np``), on JAX."""
_twins: dict[tuple[Callable[..., Any], bool], Callable[..., Any]] = {}


def _suction_point(
    theta: Any,
    w: Any,
    q: Any,
    depth: Any,
    u: Any,
    rho_suction: Any,
    suction_model: Any,
    hull: Any,
    first_row: int,
) -> tuple[Any, Any]:
    """:func:`subenv.dynamics.free_surface.suction_point` for JAX: both theories' twins, the loading's
    picked (a branch on a number in the compiled code), and exactly 0 in deep water (``rho_suction`` 0)
    as the compiled code's shortcut gives: the sums times 0 would be NaN where a sum is not finite (the
    slender-body sums of a tumbling boat)."""
    sources = _sources_suction(theta, depth, u, rho_suction, hull, first_row)
    slender = _slender_suction(theta, w, q, depth, u, rho_suction, hull, first_row + surface.SLENDER_ROW)
    pick = suction_model == surface.SOURCES_ONLY
    deep = rho_suction == 0.0
    return (
        jnp.where(deep, 0.0, jnp.where(pick, sources[0], slender[0])),
        jnp.where(deep, 0.0, jnp.where(pick, sources[1], slender[1])),
    )


def _sources_suction(
    theta: Any, depth: Any, u: Any, rho_suction: Any, hull: Any, first_row: int
) -> tuple[Any, Any]:
    """:func:`subenv.dynamics.free_surface.sources_suction` for JAX: the same terms (its twins), summed
    over arrays of segments and pairs, not in loops (unrolled by the trace, the loops over the 276
    pairs of SUBOFF's segments took 7 s to compile per right-hand side)."""
    n_seg = hull.shape[1] - 1
    xs, strength, radius = hull[first_row, :n_seg], hull[first_row + 1, :n_seg], hull[first_row + 2, :n_seg]
    s, c = jnp.sin(theta), jnp.cos(theta)
    h = traced(surface.station_depth)(depth, xs, s, radius)
    self_terms = traced(surface.self_pair)(strength, h)
    k, m = np.triu_indices(n_seg, 1)
    pairs = traced(surface.source_pair)(xs[k], h[k], strength[k], xs[m], h[m], strength[m], c)
    force = jnp.sum(self_terms) + jnp.sum(2.0 * pairs)
    moment = jnp.sum(xs * self_terms) + jnp.sum((xs[k] + xs[m]) * pairs)
    return traced(surface.suction_from_sums)(force, moment, u, rho_suction, c)


def _slender_suction(
    theta: Any, w: Any, q: Any, depth: Any, u: Any, rho_suction: Any, hull: Any, first_row: int
) -> tuple[Any, Any]:
    """:func:`subenv.dynamics.free_surface.slender_suction` for JAX: the images' flow at every point from
    every point (the twin of :func:`~subenv.dynamics.free_surface.image_flow` over the square of points),
    then the sections' loads (:func:`~subenv.dynamics.free_surface.section_load`), summed."""
    n = hull.shape[1] - 1
    xs, strength = hull[first_row, :n], hull[first_row + 1, :n]
    weight, radius = hull[first_row + 2, :n], hull[first_row + 3, :n]
    s, c = jnp.sin(theta), jnp.cos(theta)
    h = traced(surface.station_depth)(depth, xs, s, radius)
    cross = w - xs * q
    D, H = xs[:, None] - xs[None, :], h[:, None] + h[None, :]
    A, B = traced(surface.image_distance)(D, H, c)
    normal, axial, slope = traced(surface.image_flow)(D, H, A, B, strength, weight, cross, u, s, c)
    force, moment = traced(surface.section_load)(
        xs, strength, weight, cross, u, normal.sum(1), axial.sum(1), slope.sum(1)
    )
    return -rho_suction * jnp.sum(force), rho_suction * jnp.sum(moment)


def _no_suction(
    theta: Any,
    w: Any,
    q: Any,
    depth: Any,
    u: Any,
    rho_suction: Any,
    suction_model: Any,
    hull: Any,
    first_row: int,
) -> tuple[Any, Any]:
    """:func:`subenv.dynamics.free_surface.suction_point` in deep water: 0 where ``rho_suction`` is 0,
    NaN where it is not (a loading with a free surface traced without it: never a wrong number)."""
    value = jnp.where(rho_suction == 0.0, 0.0, math.nan)
    return value, value


def _wave_force_point(t: Any, distance: Any, depth: Any, u: Any, waves: Any, n: int) -> tuple[Any, Any]:
    """:func:`subenv.dynamics.waves.wave_force_point` for JAX: every wave's term at once (the twin of
    :func:`~subenv.dynamics.waves.wave_term` on the array of the columns' indices), then summed in the
    compiled loop's order. (The loop over 24 waves, unrolled by the trace in each stage of a control period's
    steps (eight stages then), made a sea's jit and 300 steps take 8.6-9.9 s instead of 3.8-4.5 s; the terms'
    rounding differs from the unrolled trace's, within the JAX environment's agreement with numba.)"""
    if n == 0:
        return 0.0, 0.0
    up, nose_up = traced(sea.wave_term)(t, distance, depth, u, waves, np.arange(n))
    total_up, total_nose_up = 0.0, 0.0
    for i in range(n):
        total_up, total_nose_up = total_up + up[i], total_nose_up + nose_up[i]
    return -total_up, total_nose_up


def _hull_segment(s: Any, hull: Any) -> Any:
    """:func:`subenv.dynamics.hull.hull_segment` for JAX: the same count of the inner stations at or aft of
    ``s``, as one comparison of the row of stations, summed. (The loop over the stations, unrolled by the
    trace at each stage of a control period (eight then), was 920 of the 5,210 operations of Nominal-v0's
    step.) An integer: the same number as the compiled loop's, NaN and infinities included, but for a
    subnormal ``s`` or station, which XLA compares as zero on a CPU (as for
    :func:`~subenv.dynamics._jit.maximum`)."""
    return jnp.sum(hull[0, 1 : hull.shape[1] - 1] <= s)


_SAME_AS: Final[dict[bool, dict[Any, Any]]] = {
    free_surface: {
        select: jnp.where,
        hull_table.hull_segment: _hull_segment,
        surface.suction_point: _suction_point if free_surface else _no_suction,
        sea.wave_force_point: _wave_force_point,
    }
    for free_surface in (True, False)
}


def replacement(kernel: Callable[..., Any], free_surface: bool = True) -> Callable[..., Any] | None:
    """The JAX function :func:`traced` puts in place of ``kernel`` instead of tracing its code (``select``:
    ``jax.numpy.where``; the hull's segment search, the free surface's suction and a sea's force: the same
    numbers computed on arrays, not in unrolled loops), or None: its code is traced."""
    return _SAME_AS[_static_bool("free_surface", free_surface)].get(kernel)


def traced(kernel: Callable[..., Any], free_surface: bool = True) -> Callable[..., Any]:
    """The function compiled as ``kernel`` (a numba kernel of :mod:`subenv.dynamics`), for JAX.

    It is the kernel's own Python code (``kernel.py_func.__code__``), run with its module's globals
    but for these names: ``math`` and ``np`` stand for :data:`MATH` and :data:`NUMPY`, every kernel it
    calls for that kernel's twin, and :func:`~subenv.dynamics._jit.select` for ``jax.numpy.where``
    (:func:`replacement`). So the equations exist once; what runs under JAX is the same source,
    traced. The function takes and returns scalars (JAX arrays of shape ()), its static parameters
    (the module's docstring) Python values: batch it with ``jax.vmap`` or ``jax.numpy.vectorize``.

    ``free_surface`` (a bool, static): False gives the twin for deep water only, the free surface's
    suction left out, not computed (the compiled code skips it where ``rho_suction`` is 0, a branch
    on a number; JAX would compute it for every state: in deep water that made a control period seven
    times slower, ``benchmarks/jax_dynamics.py``); a loading with a free surface then gets NaN.
    """
    free_surface = _static_bool("free_surface", free_surface)
    target = replacement(kernel, free_surface) or kernel
    if not hasattr(target, "py_func"):  # (already a JAX function)
        return target
    function = target.py_func
    key = (function, free_surface)
    if key not in _twins:
        namespace = dict(function.__globals__)
        twin = types.FunctionType(
            function.__code__, namespace, function.__name__, function.__defaults__, function.__closure__
        )
        twin.__doc__, twin.__qualname__ = function.__doc__, function.__qualname__
        _twins[key] = twin  # (before its callees: a kernel may be reached twice)
        namespace.update(math=MATH, np=NUMPY)
        for name in function.__code__.co_names:
            value = namespace.get(name)
            if value is not None and hasattr(value, "py_func"):  # a kernel
                namespace[name] = traced(value, free_surface)
    return _twins[key]


def _static_bool(name: str, value: Any) -> bool:
    """``value``, a Python or NumPy bool (a static argument: part of the traced program), as Python's."""
    check.require(name, value, isinstance(value, bool | np.bool_), "True or False")
    return bool(value)
