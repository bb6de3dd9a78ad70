"""Hull cross-flow drag, integrated exactly over a piecewise-linear hull.

The local heave velocity along the hull, w_loc(x) = w - x q, is linear in x, so w_loc |w_loc| changes
sign at most once, at x* = w / q. With b(x) linear between stations, every piece of the integrand
is a polynomial, and the integrals reduce to the cumulative moments

    C_k(s) = int_{x_tail}^{s} x^k b(x) dx,   k = 0 .. 3,

evaluated at s = x*: one binary search over the stations and a few multiplications per state,
instead of a quadrature over the stations.

The integral is written once, for one state, in four steps compiled with numba (see
:mod:`subenv.dynamics._jit`): the root (:func:`crossflow_root`), its segment (:func:`hull_segment`),
the moments there (:func:`moments_on_segment`) and the integrals from them
(:func:`crossflow_from_moments`). :func:`crossflow_point` chains them, and the right-hand side
(:func:`subenv.dynamics.model.rhs_point`) calls it; the block integrator
(:func:`subenv.dynamics.integrate.control_period_lanes`) runs the same steps over a block of
states, each as one loop. :func:`crossflow_integrals` is the batched form for NumPy callers.

The hull's table (:attr:`HullTable.packed`) also holds its sources and axis points for the free surface's
suction (:func:`source_rows`, :func:`slender_points`; :mod:`subenv.dynamics.free_surface` reads them there).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Final

import numpy as np

from subenv._typing import FloatArray
from subenv.dynamics._jit import clip, inline_kernel, kernel, read_only, rows, select

__all__ = [
    "SLENDER_ROW",
    "SOURCE_ROW",
    "SOURCE_ROWS",
    "HullTable",
    "crossflow_from_moments",
    "crossflow_integrals",
    "crossflow_point",
    "crossflow_root",
    "cumulative_moments_point",
    "hull_segment",
    "moments_on_segment",
    "slender_points",
    "source_rows",
]


SOURCE_ROW: Final = 7
"""First row of the hull's sources in :attr:`HullTable.packed` (:func:`source_rows`)."""
SOURCE_ROWS: Final = 7
"""Rows the hull table (:attr:`HullTable.packed`) gives the free surface, one column per hull segment:
rows 0-2 the sources of the sources-only theory (:func:`subenv.dynamics.free_surface.sources_suction`),
where each segment's sources are lumped, x [m], its change of cross-section S(x_aft) - S(x_fore) [m^2]
(the segment's source strength per unit speed) and its mean radius [m]; rows 3-6 (:data:`SLENDER_ROW` on)
the slender-body theory's axis points (:func:`slender_points`)."""
SLENDER_ROW: Final = 3
"""The slender-body points' first row (:func:`slender_points`), relative to the sources' first row."""


def source_rows(x_m: FloatArray, breadth_m: FloatArray) -> FloatArray:
    """The hull's sources (:data:`SOURCE_ROWS` rows, one column per segment) from ascending stations
    ``x_m`` and breadths ``breadth_m`` (circular sections of diameter b), for the free surface's suction
    (:func:`subenv.dynamics.free_surface.suction_point`, which reads them from :attr:`HullTable.packed`).

    Each segment's sources are lumped into one of strength u (S(x_aft) - S(x_fore)), the flux the
    segment's growth of cross-section pushes out (Newman 1977 ch. 7: m = -u dS/dx), at the centroid
    of m over the segment: with b linear, dS/dx is proportional to b, so the centroid is that of b,
    x_aft + dx (b_aft + 2 b_fore) / (3 (b_aft + b_fore)). The lumped sources then have the hull's
    exact total (zero, for a closed hull) and dipole moment (-u V).
    """
    x = np.asarray(x_m, dtype=float)
    b = np.asarray(breadth_m, dtype=float)
    area = 0.25 * math.pi * b * b
    sources = np.zeros((SOURCE_ROWS, x.size))
    b0, b1, dx = b[:-1], b[1:], np.diff(x)
    total = b0 + b1
    share = np.divide(b0 + 2.0 * b1, 3.0 * total, out=np.full_like(total, 0.5), where=total > 0)
    sources[0, :-1] = x[:-1] + dx * share
    sources[1, :-1] = area[:-1] - area[1:]  # x ascending: segment i runs aft (x[i]) to fore (x[i+1])
    sources[2, :-1] = 0.25 * (b[:-1] + b[1:])
    sources[SLENDER_ROW:, :-1] = slender_points(x, b)
    return sources


_GAUSS_NODE: Final = 1.0 / math.sqrt(3.0)  # two-point Gauss-Legendre nodes, +-1/sqrt(3) of the half-width


def slender_points(x_m: FloatArray, breadth_m: FloatArray) -> FloatArray:
    """The axis points of the slender-body theory (:func:`subenv.dynamics.free_surface.slender_suction`),
    shape (4, n_segments): x [m], source strength per unit speed [m^2], cross-flow dipole weight [m^3] and
    radius [m], from ascending stations ``x_m`` and breadths ``breadth_m`` (b linear between stations;
    circular sections).

    The hull is cut into n_segments // 2 panels of equal length (a last column of zeros when n_segments is
    odd), each carried by two points at its Gauss-Legendre nodes whose strengths have the panel's exact
    zeroth and first moments: of the source density m(x) = -dS/dx (per unit speed; Newman 1977 ch. 7) and
    of the dipole weight (S + a_33 / rho) = 2 S (a circle's added mass a_33 = rho S, Newman 1977 ch. 4).
    The panels' points have the hull's exact total source (zero), dipole moment (-u V) and volume, and
    resolve the long parallel midbody that one point per segment lumps (docs/free_surface.md measures
    the convergence); as many points as segments, so the table keeps its shape.
    """
    x = np.asarray(x_m, dtype=float)
    b = np.asarray(breadth_m, dtype=float)
    n_seg = x.size - 1
    panels = n_seg // 2
    out = np.zeros((4, n_seg))
    edges = np.linspace(x[0], x[-1], panels + 1)
    nodes, weights = np.polynomial.legendre.leggauss(3)  # exact for S x (cubic) on each linear piece

    def area(at: FloatArray) -> FloatArray:
        return 0.25 * math.pi * np.interp(at, x, b) ** 2

    for i, (lo, hi) in enumerate(itertools.pairwise(edges)):
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        cuts = np.concatenate([[lo], x[(x > lo) & (x < hi)], [hi]])
        a0, a1 = cuts[:-1, None], cuts[1:, None]
        at = 0.5 * (a0 + a1) + 0.5 * (a1 - a0) * nodes
        volume = float(np.sum(0.5 * (a1 - a0) * weights * area(at)))  # int S dx
        volume_moment = float(np.sum(0.5 * (a1 - a0) * weights * area(at) * (at - mid)))  # int S (x - mid) dx
        s_lo, s_hi = area(np.array([lo, hi]))
        source = s_lo - s_hi  # int -S' dx
        source_moment = s_lo * (lo - mid) - s_hi * (hi - mid) + volume  # int -S' (x - mid) dx, by parts
        gap = _GAUSS_NODE * half
        for total, first, row in ((source, source_moment, 1), (2.0 * volume, 2.0 * volume_moment, 2)):
            out[row, 2 * i] = 0.5 * (total - first / gap)
            out[row, 2 * i + 1] = 0.5 * (total + first / gap)
        out[0, 2 * i : 2 * i + 2] = (mid - gap, mid + gap)
        out[3, 2 * i : 2 * i + 2] = 0.5 * np.interp([mid - gap, mid + gap], x, b)
    return out


@dataclass(frozen=True, eq=False)
class HullTable:
    """Precomputed moments of a piecewise-linear hull breadth b(x), for :func:`crossflow_integrals`.

    Built once per hull by :meth:`from_offsets`; ``x`` is ascending (tail to nose).
    """

    x: FloatArray  # breakpoints, ascending [m]
    c0: FloatArray  # b(x) = c0[i] + c1[i] x on segment i [m]
    c1: FloatArray  # [-]
    offset: FloatArray  # shape (4, n_segments): C_k(s) = offset[k, i] + P_k,i(s)
    total: FloatArray  # shape (4,): C_k at the nose, i.e. int x^k b dx over the hull
    breadth: FloatArray  # b at the breakpoints [m]

    @classmethod
    def from_offsets(cls, x_m: tuple[float, ...], breadth_m: tuple[float, ...]) -> HullTable:
        """Build the table from stations (any order along x) and breadths."""
        order = np.argsort(x_m)
        x = np.asarray(x_m, dtype=float)[order]
        b = np.asarray(breadth_m, dtype=float)[order]
        x0, x1, b0, b1 = x[:-1], x[1:], b[:-1], b[1:]
        c1 = (b1 - b0) / (x1 - x0)
        c0 = b0 - c1 * x0
        k = np.arange(4)[:, None]
        # Antiderivative of x^k (c0 + c1 x) on each segment, at both ends of the segment.
        p_lo = c0 * x0 ** (k + 1) / (k + 1) + c1 * x0 ** (k + 2) / (k + 2)
        p_hi = c0 * x1 ** (k + 1) / (k + 1) + c1 * x1 ** (k + 2) / (k + 2)
        prefix = np.concatenate([np.zeros((4, 1)), np.cumsum(p_hi - p_lo, axis=1)], axis=1)
        return cls(x=x, c0=c0, c1=c1, offset=prefix[:, :-1] - p_lo, total=prefix[:, -1].copy(), breadth=b)

    @cached_property
    def packed(self) -> FloatArray:
        """The table as one C-contiguous (14, n_stations) array, the form the kernels take.

        Row 0 is ``x``; rows 1 and 2 are ``c0`` and ``c1``; rows 3-6 are ``offset[k]`` with
        ``total[k]`` in the last column; rows 7-13 (:data:`SOURCE_ROW` on) the hull's sources and axis
        points for the free-surface suction (:func:`source_rows`).
        """
        n = self.x.size
        packed = np.zeros((SOURCE_ROW + SOURCE_ROWS, n))
        packed[0] = self.x
        packed[1, :-1] = self.c0
        packed[2, :-1] = self.c1
        packed[3:SOURCE_ROW, :-1] = self.offset
        packed[3:SOURCE_ROW, -1] = self.total
        packed[SOURCE_ROW:] = source_rows(self.x, self.breadth)
        read_only(packed)
        return packed


@inline_kernel
def hull_segment(s: float, hull: FloatArray) -> int:
    """The segment i of the hull with x[i] <= s < x[i+1] (0 at or aft of the tail, the last at or
    forward of the nose, 0 for nan): ``clip(searchsorted(x, s, side="right") - 1, 0, n_seg - 1)``.

    Found as the number of inner stations x[1] .. x[n_seg - 1] at or aft of ``s``: a branch-free
    count, one vector loop over the stations, whose cost does not depend on where ``s`` lies (a
    binary search's branches went wrong often enough, with states spread over the hull, to cost
    the environments' step a third more). The one search over the stations: the right-hand side
    (:func:`crossflow_point`) and the block integrator
    (:func:`subenv.dynamics.integrate.control_period_lanes`) both call it.
    """
    count = 0
    for k in range(1, hull.shape[1] - 1):
        count += select(hull[0, k] <= s, 1, 0)
    return count


@inline_kernel
def moments_on_segment(
    s: float, c0: float, c1: float, o0: float, o1: float, o2: float, o3: float
) -> tuple[float, float, float, float]:
    """C_0..C_3 at ``s`` on a segment with breadth ``c0 + c1 x`` and offsets ``o0..o3``
    (:attr:`HullTable.packed` rows 1-6 of the segment's column)."""
    s2 = s * s
    s3 = s2 * s
    s4 = s3 * s
    s5 = s4 * s
    return (
        o0 + c0 * s + c1 * s2 / 2,
        o1 + c0 * s2 / 2 + c1 * s3 / 3,
        o2 + c0 * s3 / 3 + c1 * s4 / 4,
        o3 + c0 * s4 / 4 + c1 * s5 / 5,
    )


@inline_kernel
def cumulative_moments_point(s: float, hull: FloatArray) -> tuple[float, float, float, float]:
    """C_0..C_3 at one position ``s`` [m] (clipped to the hull); ``hull`` is :attr:`HullTable.packed`."""
    n_seg = hull.shape[1] - 1
    s = select(s == s, clip(s, hull[0, 0], hull[0, n_seg]), s)
    i = hull_segment(s, hull)
    return moments_on_segment(s, hull[1, i], hull[2, i], hull[3, i], hull[4, i], hull[5, i], hull[6, i])


@inline_kernel
def crossflow_root(w: float, q: float, hull: FloatArray) -> float:
    """The root x* = w / q of w_loc = w - x q, clipped to the hull; for q == 0 (w_loc has the sign of
    w everywhere) the end that reproduces that sign."""
    lo, hi = hull[0, 0], hull[0, hull.shape[1] - 1]
    # (w / 1.0 where q == 0, unused: no division by zero, which raises in a caller compiled with numba's
    # default error model, and whose inf would poison JAX's gradients through the select)
    root = select(q != 0, w / select(q != 0, q, 1.0), select(w >= 0, hi, lo))
    return select(root == root, clip(root, lo, hi), root)


@inline_kernel
def crossflow_from_moments(
    w: float, q: float, C0: float, C1: float, C2: float, C3: float, hull: FloatArray
) -> tuple[float, float]:
    """I_0, I_1 from the cumulative moments C_0..C_3 at the (clipped) root of w_loc."""
    n_seg = hull.shape[1] - 1
    T0, T1, T2, T3 = hull[3, n_seg], hull[4, n_seg], hull[5, n_seg], hull[6, n_seg]
    ww, wq2, qq = w * w, 2.0 * w * q, q * q
    # With F_k(s) = int_{tail}^{s} x^k b w_loc^2 dx: w_loc > 0 aft of the root when q > 0.
    sigma = select(q >= 0, 1.0, -1.0)
    I0 = sigma * (2.0 * (ww * C0 - wq2 * C1 + qq * C2) - (ww * T0 - wq2 * T1 + qq * T2))
    I1 = sigma * (2.0 * (ww * C1 - wq2 * C2 + qq * C3) - (ww * T1 - wq2 * T2 + qq * T3))
    return I0, I1


@inline_kernel
def crossflow_point(w: float, q: float, hull: FloatArray) -> tuple[float, float]:
    """Exact I_0, I_1 (see :func:`crossflow_integrals`) for one (w, q); ``hull`` is
    :attr:`HullTable.packed`."""
    s = crossflow_root(w, q, hull)
    C0, C1, C2, C3 = cumulative_moments_point(s, hull)
    return crossflow_from_moments(w, q, C0, C1, C2, C3, hull)


def crossflow_integrals(table: HullTable, w: FloatArray, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Exact I_0 = int b w_loc|w_loc| dx and I_1 = int x b w_loc|w_loc| dx, w_loc = w - x q.

    Parameters
    ----------
    table : HullTable
        The hull.
    w, q : array_like
        Heave velocity [m/s] and pitch rate [rad/s], broadcast together.

    Returns
    -------
    I0 : ndarray
        [m^4/s^2]: b [m] times w_loc^2 [m^2/s^2] times dx [m]. The hull's drag force is
        Z = -(rho/2) C_D I0 [N] (Riedel 1993 eq. 2.42).
    I1 : ndarray
        [m^5/s^2]: one more factor x [m]. The drag moment is M = +(rho/2) C_D I1 [N m] (from
        M = -x Z_F with x forward; the thesis prints the opposite sign in eqs 2.43 and 4.2).
    """
    shape = np.broadcast_shapes(np.shape(w), np.shape(q))
    w_rows, q_rows = rows(w, shape), rows(q, shape)
    I0, I1 = np.empty(w_rows.shape), np.empty(w_rows.shape)
    _crossflow_rows(w_rows, q_rows, table.packed, I0, I1)
    return I0.reshape(shape), I1.reshape(shape)


@kernel
def _crossflow_rows(w: FloatArray, q: FloatArray, hull: FloatArray, I0: FloatArray, I1: FloatArray) -> None:
    # A loop over rows, not a generalized ufunc (see subenv.dynamics._jit).
    for i in range(w.shape[0]):
        I0[i], I1[i] = crossflow_point(w[i], q[i], hull)
