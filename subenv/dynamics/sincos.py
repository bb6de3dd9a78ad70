"""Sine and cosine of the pitch, written without branches or library calls, so that they vectorize.

The right-hand side takes the sine and the cosine of the pitch on every call. ``math.sin`` and
``math.cos`` are calls into the C library, one value at a time (about 9 ns of a 20 ns right-hand
side); a loop over many states that calls them cannot become SIMD code. :func:`sincos_point` is the
same pair computed with arithmetic and selects only, so the compiled integrator over a block of
sub-environments (:func:`subenv.dynamics.integrate.control_period_lanes`) vectorizes, and it gives
the same bits one state at a time as eight at a time.

The method is FreeBSD msun's (also in musl): reduce ``x`` by multiples of pi/2 with pi/2 split in
three parts (``__rem_pio2.c``, the medium-size path), then the minimax polynomials of
``__kernel_sin`` and ``__kernel_cos`` on [-pi/4, pi/4] with the reduced argument's tail. Within
``|x| <`` :data:`MAX_ARGUMENT` the result is within 1 ulp of the correctly rounded value
(``tests/dynamics/test_sincos.py``); beyond it (more than 260,000 turns), and for infinities and
NaN, both are NaN. The model is a vertical-plane model of a boat near level flight, so a pitch that
large only comes from a diverged state, which the environments end.

References
----------
FreeBSD ``lib/msun/src/k_sin.c``, ``k_cos.c`` and ``e_rem_pio2.c`` (Sun Microsystems, 1993).
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np

from subenv.dynamics._jit import inline_kernel, select

__all__ = ["MAX_ARGUMENT", "sincos_point"]

MAX_ARGUMENT: Final = 2.0**20 * (math.pi / 2)
"""Largest |x| [rad] reduced exactly by the three-part pi/2 (msun's medium-size path)."""

# k_sin.c: sin(x) ~ x + S1 x^3 + ... + S6 x^13 on [-pi/4, pi/4].
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
# k_cos.c: cos(x) ~ 1 - x^2/2 + C1 x^4 + ... + C6 x^14 on [-pi/4, pi/4].
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11
# e_rem_pio2.c: 2/pi, and pi/2 = PIO2_1 + PIO2_2 + PIO2_3 (33 bits each), with the tails PIO2_kT.
_INV_PIO2 = 6.36619772367581382433e-01
_PIO2_1, _PIO2_1T = 1.57079632673412561417e00, 6.07710050650619224932e-11
_PIO2_2, _PIO2_2T = 6.07710050630396597660e-11, 2.02226624879595063154e-21
_PIO2_3, _PIO2_3T = 2.02226624871116645580e-21, 8.47842766036889956997e-32


@inline_kernel
def sincos_point(x: float) -> tuple[float, float]:
    """``(sin(x), cos(x))`` within 1 ulp for ``|x| <`` :data:`MAX_ARGUMENT`, else ``(nan, nan)``."""
    # x = n pi/2 + (y0 + y1), |y0 + y1| <= pi/4 (e_rem_pio2.c, all three refinements always).
    # To the nearest integer, ties to even; + 0.0 makes a zero +0.0, so that sin(-0.0) is -0.0. (As a
    # rounding call, not msun's (y + 1.5 2^52) - 1.5 2^52, which JAX's compiler folds to y.)
    n = np.rint(x * _INV_PIO2) + 0.0
    r = x - n * _PIO2_1
    w = n * _PIO2_1T
    t = r
    w = n * _PIO2_2
    r = t - w
    w = n * _PIO2_2T - ((t - r) - w)
    t = r
    w = n * _PIO2_3
    r = t - w
    w = n * _PIO2_3T - ((t - r) - w)
    y0 = r - w
    y1 = (r - y0) - w
    z = y0 * y0
    zz = z * z
    # k_sin.c with iy = 1.
    v = z * y0
    rs = _S2 + z * (_S3 + z * _S4) + z * zz * (_S5 + z * _S6)
    s = y0 - ((z * (0.5 * y1 - v * rs) - y1) - v * _S1)
    # k_cos.c.
    rc = z * (_C1 + z * (_C2 + z * _C3)) + zz * zz * (_C4 + z * (_C5 + z * _C6))
    hz = 0.5 * z
    one_minus_hz = 1.0 - hz
    c = one_minus_hz + (((1.0 - one_minus_hz) - hz) + (z * rc - y0 * y1))
    # (Selects, not branches: the vectorizer needs straight-line code.)
    quadrant = n - 4.0 * np.floor(0.25 * n)  # n mod 4 (a float: no integer conversion of a nan)
    sin_x = select(quadrant == 0.0, s, select(quadrant == 1.0, c, select(quadrant == 2.0, -s, -c)))
    cos_x = select(quadrant == 0.0, c, select(quadrant == 1.0, -s, select(quadrant == 2.0, -c, s)))
    in_range = math.fabs(x) < MAX_ARGUMENT  # false for inf and nan
    return select(in_range, sin_x, math.nan), select(in_range, cos_x, math.nan)
