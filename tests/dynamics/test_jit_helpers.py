"""The kernels' comparisons (subenv.dynamics._jit: minimum, maximum, clip; and math.fabs): one defined
result, NaN, infinities and signed zeros included, compiled by numba and traced by JAX. (Subnormal
numbers are numba's alone: XLA compares them as zeros on a CPU.)"""

import functools
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from subenv.dynamics._jit import KERNEL_SOURCES, clip, declare_kernel_sources, inline_kernel, maximum, minimum

SPECIAL = (
    math.nan,
    -math.inf,
    math.inf,
    -0.0,
    0.0,
    -1.5,
    1.0,
    2.2250738585072014e-308,
    -1.7976931348623157e308,
)
"""NaN, the infinities, the zeros, the smallest normal number and the largest in size."""
SUBNORMAL = 5e-324
PAIRS = list(itertools.product(SPECIAL, SPECIAL))


declare_kernel_sources(__file__, ("test_jit_helpers.py",), inlines=(KERNEL_SOURCES,))


@inline_kernel
def _fabs(x):
    return math.fabs(x)


def _bits(x):
    """A float's bits, every NaN as one (no NaN's payload is specified)."""
    return "nan" if math.isnan(x) else np.float64(x).view(np.int64).item()


def _expected(builtin, a, b):
    """The definition: NaN where either is NaN, else Python's ``max``/``min`` (``a`` where the two are
    equal: the sign of a zero is the first's)."""
    return math.nan if math.isnan(a) or math.isnan(b) else builtin(a, b)


def _expected_clip(x, lo, hi):
    return _expected(min, _expected(max, x, lo), hi)


@pytest.mark.parametrize("helper, builtin", [(maximum, max), (minimum, min)])
def test_minimum_and_maximum_compiled_by_numba(helper, builtin):
    for a, b in PAIRS:
        assert _bits(helper(a, b)) == _bits(_expected(builtin, a, b)), (a, b)
    assert _bits(maximum(-0.0, 0.0)) == _bits(-0.0) and _bits(maximum(0.0, -0.0)) == _bits(0.0)
    for x in (-0.0, 0.0, 1.0):  # (numba compares subnormal numbers as numbers)
        assert _bits(helper(x, SUBNORMAL)) == _bits(builtin(x, SUBNORMAL)), x
    assert math.isnan(helper(1.0, math.nan)) and math.isnan(helper(math.nan, 1.0))  # (either position)
    assert helper(3, 7) == builtin(3, 7) and isinstance(helper(3, 7), int)  # (integers stay integers)


def test_clip_and_fabs_compiled_by_numba():
    for x, lo in PAIRS:
        for hi in (math.nan, -1.0, 0.0, 2.0, math.inf):
            assert _bits(clip(x, lo, hi)) == _bits(_expected_clip(x, lo, hi)), (x, lo, hi)
        assert _bits(_fabs(x)) == _bits(abs(x)), x
    assert clip(5.0, 1.0, -1.0) == -1.0  # (lo > hi: hi)
    assert _bits(_fabs(-0.0)) == _bits(0.0)


@functools.cache  # (one jitted twin each for the whole file: the property test calls it per example)
def _jax_twins():
    jax = pytest.importorskip("jax")  # the jax extra
    import subenv.jax as sj

    return {name: jax.jit(jax.numpy.vectorize(sj.traced(f))) for name, f in _KERNELS.items()}


_KERNELS = {"maximum": maximum, "minimum": minimum, "clip": clip, "fabs": _fabs}


def test_the_same_bits_traced_by_jax():
    """The JAX twins (the same code, traced) give numba's result for every pair of special values, in
    either position, and so do the JAX programs whose twins call them (jit and vectorized)."""
    twins = _jax_twins()
    a = np.array([p[0] for p in PAIRS])
    b = np.array([p[1] for p in PAIRS])
    for name, builtin in (("maximum", max), ("minimum", min)):
        got = np.asarray(twins[name](a, b))
        assert [_bits(x) for x in got] == [_bits(_expected(builtin, x, y)) for x, y in PAIRS], name
    for hi in (math.nan, -1.0, 0.0, 2.0, math.inf):
        got = np.asarray(twins["clip"](a, b, hi))
        assert [_bits(x) for x in got] == [_bits(_expected_clip(x, y, hi)) for x, y in PAIRS], hi
    assert [_bits(x) for x in np.asarray(twins["fabs"](a))] == [_bits(abs(x)) for x in a]
    ints = np.asarray(twins["minimum"](np.array([3, 9]), np.array([7, 2])))
    assert ints.tolist() == [3, 2] and np.issubdtype(ints.dtype, np.integer)


@settings(max_examples=50)
@given(
    hnp.arrays(np.float64, 16, elements=st.floats(allow_subnormal=False)),
    hnp.arrays(np.float64, 16, elements=st.floats(allow_subnormal=False)),
    st.floats(allow_subnormal=False),
)
def test_numba_and_jax_agree_on_any_floats(a, b, hi):
    twins = _jax_twins()
    for name, helper in (("maximum", maximum), ("minimum", minimum)):
        compiled = [_bits(helper(x, y)) for x, y in zip(a, b, strict=True)]
        assert [_bits(x) for x in np.asarray(twins[name](a, b))] == compiled, name
    compiled = [_bits(clip(x, y, hi)) for x, y in zip(a, b, strict=True)]
    assert [_bits(x) for x in np.asarray(twins["clip"](a, b, hi))] == compiled
