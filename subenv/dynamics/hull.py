"""Hull cross-flow drag, integrated exactly over a piecewise-linear hull.

The local heave velocity along the hull, w_loc(x) = w - x q, is linear in x, so w_loc |w_loc| changes
sign at most once, at x* = w / q. With b(x) linear between stations, every piece of the integrand
is a polynomial, and the integrals reduce to the cumulative moments

    C_k(s) = int_{x_tail}^{s} x^k b(x) dx,   k = 0 .. 3,

evaluated at s = x*: one ``searchsorted`` and a few multiplications per state, instead of a
quadrature over the stations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from subenv._typing import FloatArray

__all__ = ["HullTable", "crossflow_integrals"]


@dataclass(frozen=True, eq=False)
class HullTable:
    """Precomputed moments of a piecewise-linear hull breadth b(x), for :func:`crossflow_integrals`.

    Built once per hull by :meth:`from_offsets`; ``x`` is ascending (tail to nose).
    """

    x: FloatArray          # breakpoints, ascending [m]
    c0: FloatArray         # b(x) = c0[i] + c1[i] x on segment i [m]
    c1: FloatArray         # [-]
    offset: FloatArray     # shape (4, n_segments): C_k(s) = offset[k, i] + P_k,i(s)
    total: FloatArray      # shape (4,): C_k at the nose, i.e. int x^k b dx over the hull

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
        return cls(x=x, c0=c0, c1=c1, offset=prefix[:, :-1] - p_lo, total=prefix[:, -1].copy())

    def cumulative_moments(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """C_0..C_3 at positions ``s`` (clipped to the hull), each shaped like ``s``."""
        s = np.clip(s, self.x[0], self.x[-1])
        i = np.clip(np.searchsorted(self.x, s, side="right") - 1, 0, self.c0.size - 1)
        c0, c1 = self.c0[i], self.c1[i]
        s2 = s * s
        s3 = s2 * s
        s4 = s3 * s
        s5 = s4 * s
        return (
            self.offset[0, i] + c0 * s + c1 * s2 / 2,
            self.offset[1, i] + c0 * s2 / 2 + c1 * s3 / 3,
            self.offset[2, i] + c0 * s3 / 3 + c1 * s4 / 4,
            self.offset[3, i] + c0 * s4 / 4 + c1 * s5 / 5,
        )


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
        [m^3/s^2]; the hull's drag force is Z = -(rho/2) C_D I0 (Riedel 1993 eq. 2.42).
    I1 : ndarray
        [m^4/s^2]; the drag moment is M = +(rho/2) C_D I1 (from M = -x Z_F with x forward; the
        thesis prints the opposite sign in eqs 2.43 and 4.2).
    """
    w = np.asarray(w, dtype=float)
    q = np.asarray(q, dtype=float)
    lo, hi = table.x[0], table.x[-1]
    # Root of w_loc; for q == 0 w_loc has the sign of w everywhere, which the ends reproduce.
    q_nonzero = q != 0
    root = np.where(q_nonzero, w / np.where(q_nonzero, q, 1.0), np.where(w >= 0, hi, lo))
    C0, C1, C2, C3 = table.cumulative_moments(root)
    T0, T1, T2, T3 = table.total
    ww, wq2, qq = w * w, 2.0 * w * q, q * q
    # With F_k(s) = int_{tail}^{s} x^k b w_loc^2 dx: w_loc > 0 aft of the root when q > 0.
    sigma = np.where(q >= 0, 1.0, -1.0)
    I0 = sigma * (2.0 * (ww * C0 - wq2 * C1 + qq * C2) - (ww * T0 - wq2 * T1 + qq * T2))
    I1 = sigma * (2.0 * (ww * C1 - wq2 * C2 + qq * C3) - (ww * T1 - wq2 * T2 + qq * T3))
    return I0, I1
