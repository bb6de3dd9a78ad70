"""How the physics is compiled: one numba configuration for every kernel.

The right-hand side, the hull integral and the environment transition are written once as
scalar functions and compiled with numba. There is no interpreted copy beside them: the batched
NumPy-facing functions (:func:`subenv.dynamics.derivatives`,
:func:`subenv.dynamics.crossflow_integrals`) broadcast their arguments (:func:`rows`) and call a kernel
that loops over the same compiled scalar functions that the environments call. (Not numba's
generalized ufuncs: a cached gufunc can segfault when two processes compile it at once with a cold
cache, numba#10128, which two Ray workers here did.)

- ``nogil=True``: the kernels release the GIL, so other Python threads run meanwhile.
- :func:`parallel_kernel` compiles a kernel with ``parallel=True`` as well: its ``numba.prange``
  loop is shared among numba's threads. numba's TBB threading layer is the one that is safe both
  when several threads launch kernels and after ``fork`` (numba's "safe" layer); the ``tbb``
  package is a dependency, and :func:`threading_layer_available` makes its library loadable
  where pip installed it (a virtual environment's ``lib/``, which the loader does not search).
- ``cache=True``: compiled code is stored next to the sources (or in ``NUMBA_CACHE_DIR``), so
  only the first process on a machine pays the compile time (``benchmarks/speed.py`` reports it).
  numba checks a cached kernel against its own source file only, not against the files of the
  functions it inlines: after an edit of ``hull.py`` the environments' kernel in
  ``transition.py`` would load the old physics from the cache. So each package that compiles
  kernels declares its kernel sources (:func:`declare_kernel_sources`: its files with kernels, and
  the packages whose kernels they inline; this package's are :data:`KERNEL_SOURCES`), every cache
  directory (one per package folder) carries a stamp of all the files its kernels may inline, and a
  changed stamp drops the directory's cached kernels before any is loaded. A kernel in a file its
  package has not declared is refused when it is defined.
- ``error_model="numpy"``: division by zero gives inf/nan as in NumPy instead of raising, and
  saves the checks.
- No ``fastmath``: results stay IEEE, so the compiled integrator reproduces
  :func:`subenv.dynamics.rk4` over :func:`subenv.dynamics.derivatives` bit for bit.
"""

from __future__ import annotations

import hashlib
import os
import types
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache, cached_property
from pathlib import Path
from typing import Annotated, Any, Final, TypeVar, cast

import numba
import numpy as np

__all__ = [
    "KERNEL_OPTIONS",
    "KERNEL_SOURCES",
    "STATIC",
    "KernelSources",
    "Static",
    "clip",
    "declare_kernel_sources",
    "inline_kernel",
    "kernel",
    "kernel_sources",
    "maximum",
    "minimum",
    "parallel_kernel",
    "rows",
    "select",
    "threading_layer_available",
]

KERNEL_OPTIONS: Final[dict[str, Any]] = {"cache": True, "nogil": True, "error_model": "numpy"}

_STAMP_PREFIX: Final = "subenv-kernels."


@dataclass(frozen=True)
class KernelSources:
    """The files a package's compiled kernels are written in: its own, and (through the declarations in
    ``inlines``) those of the packages whose kernels they inline. Declared with
    :func:`declare_kernel_sources`.

    Attributes
    ----------
    folder : Path
        The package's folder (numba keeps one cache directory per folder of kernel sources).
    files : tuple of str
        The package's files that define kernels, in ``folder``.
    inlines : tuple of KernelSources
        The packages whose kernels this package's kernels call (numba inlines them).
    """

    folder: Path
    files: tuple[str, ...]
    inlines: tuple[KernelSources, ...] = ()

    def paths(self) -> tuple[Path, ...]:
        """Every file this package's kernels may inline: its own, then those of ``inlines`` (each once)."""
        own = tuple(self.folder / name for name in self.files)
        return tuple(dict.fromkeys([*own, *(path for sources in self.inlines for path in sources.paths())]))

    @cached_property
    def stamp(self) -> str:
        """A digest of the files of :meth:`paths` (read once per process)."""
        digest = hashlib.sha256()
        for path in self.paths():
            digest.update(f"{path.parent.name}/{path.name}".encode())
            digest.update(path.read_bytes())
        return digest.hexdigest()[:16]


_DECLARED: dict[Path, KernelSources] = {}


def declare_kernel_sources(
    module_file: str, files: tuple[str, ...], inlines: tuple[KernelSources, ...] = ()
) -> KernelSources:
    """Declare the kernel sources of the package of ``module_file`` (a module's ``__file__``): its
    ``files`` that define kernels, and the declarations of the packages whose kernels they call.

    Call it in the package's first module to define kernels, before the first of them (the
    decorators look the declaration up: :func:`kernel_sources`). An edit of any of these files then
    drops the package's cached kernels.
    """
    sources = KernelSources(Path(module_file).resolve().parent, tuple(files), tuple(inlines))
    _DECLARED[sources.folder] = sources
    return sources


def kernel_sources(source_file: str | Path) -> KernelSources:
    """The declared kernel sources of the package of ``source_file``, a file that defines kernels;
    RuntimeError if the file is not among them."""
    path = Path(source_file).resolve()
    sources = _DECLARED.get(path.parent)
    if sources is None or path.name not in sources.files:
        raise RuntimeError(
            f"{path} defines kernels but is not among its package's kernel sources: declare them with "
            "subenv.dynamics._jit.declare_kernel_sources before the package's first kernel"
            + ("" if sources is None else f" (declared: {list(sources.files)})")
        )
    return sources


KERNEL_SOURCES: Final = declare_kernel_sources(
    __file__,
    ("_jit.py", "hull.py", "free_surface.py", "waves.py", "model.py", "integrate.py", "sincos.py"),
)
"""The kernel sources of the dynamics: the files of this package that define kernels (they inline
no other package's)."""

FunctionT = TypeVar("FunctionT", bound=Callable[..., Any])
T = TypeVar("T")
Number = TypeVar("Number", int, float)

STATIC: Final = "static"
"""The mark of :data:`Static`."""
Static = Annotated[T, STATIC]
"""``Static[X]``: a kernel's parameter of type X whose value is fixed when :mod:`subenv.jax` traces the
kernel (a Python value, not a traced array), so that the kernel may branch on it (``if``, a ``range``
bound): the configuration record ``cfg`` of the transition, a count of columns. numba ignores it; the
contract of the traced kernels (``tests/jax/test_contract.py``) reads it."""


def kernel(fn: FunctionT) -> FunctionT:
    """``numba.njit`` with the package's options, compiled lazily on the first call."""
    _drop_stale_cache(fn)
    return cast(FunctionT, numba.njit(**KERNEL_OPTIONS)(fn))


def parallel_kernel(fn: FunctionT) -> FunctionT:
    """As :func:`kernel`, with ``parallel=True``: its ``numba.prange`` loops run on numba's threads.

    ``fn`` may be compiled by :func:`kernel` as well (one source, a serial and a parallel kernel):
    the parallel one is compiled from a twin of ``fn`` named ``<name>_parallel``, because numba
    files a function's cached machine code under its name and signature only, so the two would
    load each other's code from the cache. Call it only where :func:`threading_layer_available`.
    """
    twin = types.FunctionType(
        fn.__code__, fn.__globals__, f"{fn.__name__}_parallel", fn.__defaults__, fn.__closure__
    )
    twin.__qualname__ = f"{fn.__qualname__}_parallel"
    twin.__module__, twin.__doc__ = fn.__module__, fn.__doc__
    _drop_stale_cache(twin)
    return cast(FunctionT, numba.njit(parallel=True, **KERNEL_OPTIONS)(twin))


@cache
def threading_layer_available() -> bool:
    """Whether numba's TBB threading layer can run here (loading pip's ``libtbb`` first if needed).

    numba's ``tbbpool`` extension links ``libtbb.so.12`` by name; pip's ``tbb`` wheel puts that
    library in the environment's ``lib/`` folder, which the dynamic loader does not search
    (numba/numba#6108). Loading it by its installed path first lets the extension find it.
    Without it (no ``tbb`` installed, or a platform without its wheels) the vector environment
    steps on one thread.
    """
    try:
        import numba.np.ufunc.tbbpool
    except ImportError:
        if not _load_pip_tbb():
            return False
        try:
            import numba.np.ufunc.tbbpool  # noqa: F401
        except ImportError:
            return False
    # (False if the user chose another layer for the process)
    return os.environ.get("NUMBA_THREADING_LAYER", "default") in ("default", "safe", "tbb")


def _load_pip_tbb() -> bool:
    import ctypes
    from importlib import metadata

    try:
        files = metadata.distribution("tbb").files or []
    except metadata.PackageNotFoundError:
        return False
    names = ("libtbb.so.12", "libtbb.12.dylib")
    for file in files:
        if file.name in names:
            try:
                ctypes.CDLL(str(file.locate()), mode=ctypes.RTLD_GLOBAL)
            except OSError:
                return False
            return True
    return False


def inline_kernel(fn: FunctionT) -> FunctionT:
    """As :func:`kernel`, and inlined into the compiled callers (no call overhead, no reference counting
    of the array arguments): for the small functions called per state."""
    _drop_stale_cache(fn)
    return cast(FunctionT, numba.njit(inline="always", **KERNEL_OPTIONS)(fn))


def rows(value: Any, shape: tuple[int, ...]) -> Any:
    """``value`` broadcast to ``shape`` as a contiguous float64 array of one row per element
    (``shape + (k,)`` arrays: pass ``shape + (k,)`` and reshape): how the batched NumPy-facing functions
    hand a batch to a kernel that loops over it.

    Always read-only (a view where the copy is the caller's own): numba types a read-only array apart
    from a writable one, and a kernel given both would compile once per combination of its arguments'
    flags (four times, 5 s each, in one ``subenv evaluate``)."""
    array = np.asarray(value, dtype=float)
    if array.shape != shape:  # (broadcast_to costs microseconds: the analysis calls this millions of times)
        array = np.broadcast_to(array, shape)
    out = np.ascontiguousarray(array).reshape(-1)
    if out.flags.writeable:
        out = out.view()
        read_only(out)
    return out


def read_only(*arrays: np.ndarray) -> None:
    """Mark ``arrays`` read-only (in place). numba types a read-only array apart from a writable one, so
    the arrays a kernel only reads are read-only wherever they are made; and again where an object that
    holds them is copied: pickle and ``copy.deepcopy`` give writable arrays, with which a copied
    environment's first step would compile every kernel again for the other flag (10-20 s)."""
    for array in arrays:
        array.flags.writeable = False


def _drop_stale_cache(fn: Callable[..., Any]) -> None:
    """Before ``fn``'s kernel can load from numba's cache: if its cache directory's stamp is not that
    of its package's current kernel sources, delete the directory's cached kernels of these sources
    and stamp it."""
    from numba.core.caching import FunctionCache

    sources = kernel_sources(fn.__code__.co_filename)
    try:
        directory = Path(FunctionCache(fn)._cache_path)
    except (AttributeError, RuntimeError, OSError):  # no cache location (numba then compiles every time)
        return
    _check_directory(directory, sources.stamp, tuple(Path(name).stem for name in sources.files))


@cache
def _check_directory(directory: Path, stamp: str, stems: tuple[str, ...]) -> None:
    """Once per process and directory (:func:`_drop_stale_cache`): ``stems`` are the modules whose
    kernels the directory caches."""
    stamp_file = directory / f"{_STAMP_PREFIX}{stamp}"
    if stamp_file.exists():
        return
    try:
        for path in directory.iterdir():
            # numba names its files <module>.<function>-<line>.<python>.nbi/.nbc ("guf-" first for gufuncs).
            module = path.name.removeprefix("guf-").split(".", 1)[0]
            stale_stamp = path.name.startswith(_STAMP_PREFIX)
            if stale_stamp or (path.suffix in (".nbi", ".nbc") and module in stems):
                path.unlink(missing_ok=True)
        stamp_file.touch()
    except OSError:  # a read-only or vanished cache directory: numba copes (it compiles)
        return


@inline_kernel
def select(condition: bool, if_true: Any, if_false: Any) -> Any:
    """``if_true if condition else if_false``, both already computed: the physics' conditional
    expressions are written as this call, so that the same source also traces under JAX (where
    :mod:`subenv.jax` makes it ``jax.numpy.where``), and the compiler makes it a select, not a branch."""
    return if_true if condition else if_false


# The comparisons the physics makes, as calls with one defined result on both backends. (Python's
# ``max(a, b)``, which numba compiles as ``select(b > a, b, a)``, drops a NaN in the second position;
# ``jax.numpy.maximum`` keeps it in either.) Written with ``select`` and comparisons only, so that
# subenv.jax traces this same code.
@inline_kernel
def maximum(a: Number, b: Number) -> Number:
    """The larger of ``a`` and ``b`` (floats or integers), with NaN: a NaN in either position gives NaN
    (that argument), as ``numpy.maximum``.

    Infinities order as numbers (``maximum(x, inf)`` is inf, ``maximum(x, -inf)`` is x). Where ``a``
    and ``b`` compare equal the result is ``a``: ``maximum(-0.0, 0.0)`` is -0.0 and
    ``maximum(0.0, -0.0)`` is 0.0 (as Python's ``max``, which this is wherever no NaN is second).
    The same bits compiled by numba and traced by JAX (``tests/dynamics/test_jit_helpers.py``), but
    for subnormal numbers, which XLA compares as zeros on a CPU (numba as numbers).
    """
    return select(b != b, b, select(b > a, b, a))


@inline_kernel
def minimum(a: Number, b: Number) -> Number:
    """The smaller of ``a`` and ``b`` (floats or integers), with NaN: a NaN in either position gives
    NaN (that argument), as ``numpy.minimum``.

    Infinities order as numbers. Where ``a`` and ``b`` compare equal the result is ``a``:
    ``minimum(0.0, -0.0)`` is 0.0 (as Python's ``min``, which this is wherever no NaN is second).
    The same bits compiled by numba and traced by JAX (``tests/dynamics/test_jit_helpers.py``), but
    for subnormal numbers, which XLA compares as zeros on a CPU (numba as numbers).
    """
    return select(b != b, b, select(b < a, b, a))


@inline_kernel
def clip(x: Number, lo: Number, hi: Number) -> Number:
    """``x`` clipped to [``lo``, ``hi``]: ``minimum(maximum(x, lo), hi)``, so NaN where ``x`` (or a bound)
    is NaN, never a bound in its place; ``hi`` where ``lo > hi``; a zero of either sign inside
    the interval is kept as it is."""
    return minimum(maximum(x, lo), hi)
