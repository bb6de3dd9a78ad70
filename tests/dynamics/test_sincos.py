"""The right-hand side's own sine and cosine.

Within 1 ulp, NaN where it gives up, the same bits in SIMD code.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from subenv.dynamics.sincos import MAX_ARGUMENT, sincos_point


@numba.njit(error_model="numpy")
def _sincos_loop(x: np.ndarray, s: np.ndarray, c: np.ndarray) -> None:
    for i in range(x.shape[0]):  # a plain loop: compiled to SIMD code
        s[i], c[i] = sincos_point(x[i])


def _sincos(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    s, c = np.empty_like(x), np.empty_like(x)
    _sincos_loop(x, s, c)
    return s, c


def _ulps(value: np.ndarray, exact: np.ndarray) -> np.ndarray:
    return np.abs(value - exact) / np.spacing(np.abs(exact))


def _near_multiples_of_half_pi(k_max: int) -> np.ndarray:
    """The doubles next to k pi/2 (where the reduction cancels most bits), for k up to ``k_max``."""
    k = np.unique(np.geomspace(1, k_max, 300).round())
    x = k * (np.pi / 2)
    return np.concatenate([x, np.nextafter(x, 0), np.nextafter(x, np.inf), -x])


@pytest.mark.parametrize("half_width", [0.8, 10.0, 1e3, 1e6])
def test_within_one_ulp_of_the_correctly_rounded_value(half_width):
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.uniform(-half_width, half_width, 200_000), _near_multiples_of_half_pi(2**20 - 1)])
    x = x[np.abs(x) < MAX_ARGUMENT]
    s, c = _sincos(x)
    # Reference: the long double functions, rounded once to double.
    exact_s = np.sin(x.astype(np.longdouble)).astype(float)
    exact_c = np.cos(x.astype(np.longdouble)).astype(float)
    assert _ulps(s, exact_s).max() <= 1.0
    assert _ulps(c, exact_c).max() <= 1.0
    # Most values are the correctly rounded ones, as the C library's.
    assert np.mean(s == exact_s) > 0.8 and np.mean(c == exact_c) > 0.8


def test_special_values():
    s, c = _sincos(np.array([0.0, -0.0, np.inf, -np.inf, np.nan, MAX_ARGUMENT, -MAX_ARGUMENT, 1e300]))
    assert s[0] == 0.0 and c[0] == 1.0
    assert s[1] == 0.0 and math.copysign(1.0, s[1]) == -1.0 and c[1] == 1.0  # sin(-0) = -0
    assert np.isnan(s[2:]).all() and np.isnan(c[2:]).all()  # beyond the exact reduction: NaN, not garbage


def test_odd_and_even_and_the_same_one_at_a_time():
    x = np.random.default_rng(1).uniform(0.0, 50.0, 10_000)
    s, c = _sincos(x)
    s_neg, c_neg = _sincos(-x)
    np.testing.assert_array_equal(s_neg, -s)
    np.testing.assert_array_equal(c_neg, c)
    # The SIMD loop gives the bits of scalar calls (sincos_point called from Python runs scalar code).
    for i in range(0, x.size, 997):
        assert sincos_point(x[i]) == (s[i], c[i])
