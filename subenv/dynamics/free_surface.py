"""The free surface's pull on a submerged slender hull near it: the steady suction, written once.

A hull moving at speed u below the free surface draws the water over its top faster than under its
keel; the pressure there drops and the hull is pulled up (and pitched) towards the surface. This
module gives that force and moment as a function of depth, pitch and speed, for
:func:`subenv.dynamics.model.rhs_point`, the one right-hand side, and (batched) for the analysis.

The model, and where it comes from
----------------------------------
*Slender body.* A slender hull of revolution with cross-section S(x) = pi b(x)^2 / 4 moving along
its axis at speed u is represented by a line of sources of strength per unit length
m(x) = -u dS/dx (Newman 1977, *Marine Hydrodynamics*, ch. 7, slender-body theory):
sources over the forebody, sinks over the afterbody, sum zero.

*The free surface as a rigid lid.* At small depth Froude number F_h = u / sqrt(g h) the free surface
is a rigid plane: the Kelvin-Havelock source below a free surface, whose wave terms scale with
exp(-2 g h / u^2), tends to a source plus its mirror image *of the same sign* above the surface
(Havelock 1931, "The wave resistance of a spheroid", Proc. R. Soc. A 131, the zero-speed
limit of his image system; McCreight 1970, MIT SM thesis "Force and moment on a slender body of
revolution moving in water of finite depth", supervised by J. N. Newman, derives the consistent
first-order slender-body heave force and pitch moment for the same image system at a rigid plane
boundary, the sea floor). This is the model here.

*The force: Lagally's theorem.* A source of strength m in an outer flow of velocity V feels the
force -rho m V (Lagally's theorem; Newman 1977 ch. 4; Milne-Thomson 1968, *Theoretical
Hydrodynamics*). The outer flow at the hull's sources is the image line's, so the upward force per
unit length at station x is

    f(x) = rho m(x) int m(xi) (h(x) + h(xi)) / (4 pi r^3) dxi,
    r^2 = (x - xi)^2 cos^2(theta) + (h(x) + h(xi))^2,

with h(x) = Z - x sin(theta) the depth of station x (x forward, pitch nose-up). The heave force is
Z_fs = -cos(theta) int f dx (down positive) and the pitch moment M_fs = cos(theta) int x f dx
(nose-up positive, M = -x Z_F): :func:`suction_point`. Pairs of sources near each other dominate
and pull the hull up (a source is attracted by its image); far from the surface the hull's sources
act as one dipole of moment u V (V the volume) and the suction falls as

    Z_fs -> -3 rho u^2 V^2 / (64 pi h^4)        (h >> L),

the attraction of a dipole by its image, the same law as a sphere's 3 pi rho u^2 a^6 / (16 h^4)
(a sphere has dipole moment 2 pi u a^3 = 1.5 u V; ``tests/dynamics/test_free_surface.py`` checks
the limit).

Range of validity, and the constant left unknown
------------------------------------------------
- Slender hull (b << L), depth larger than the hull radius (h > b / 2: the top of the hull below
  the surface; a station above it is taken at its own radius, where broaching ends an episode).
- Small depth Froude number, F_h^2 = u^2 / (g h) << 1: the rigid-lid limit. The finite-Froude
  corrections (O(F_h^2) in the local flow, exponentially small wave lift; at F_h of order one
  Havelock's wave terms reverse the force) are not modelled. At periscope depth (h = 0.8-1.2 m) and
  0.4-1.2 m/s, F_h^2 = 0.01-0.18.
- Inviscid flow over the bare hull of revolution: the sail, the planes and the boundary layer are
  not represented. How much they change the suction is not published for SUBOFF; it is exposed as
  :attr:`FreeSurface.suction_factor` (1: the potential-flow hull alone).

With ``suction_factor`` 0 (the default of every vehicle's :func:`subenv.dynamics.model_params`)
the free surface is absent: deep water, the model of Riedel (1993) exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np

from subenv import _validation as check
from subenv._typing import ArrayLike, FloatArray
from subenv.dynamics._jit import inline_kernel, kernel, maximum, rows
from subenv.dynamics.hull import SOURCE_ROW, HullTable

__all__ = [
    "NO_FREE_SURFACE",
    "FreeSurface",
    "dipole_suction_N",
    "self_pair",
    "source_pair",
    "station_depth",
    "suction",
    "suction_from_sums",
    "suction_point",
]

_FOUR_PI: Final = 4.0 * math.pi


@dataclass(frozen=True)
class FreeSurface:
    """The free surface's suction on the hull (see the module's docstring for the model).

    Attributes
    ----------
    suction_factor : float
        Multiplies the rigid-lid, bare-hull suction [-]. 1 is the potential-flow hull of
        revolution alone (Havelock 1931's image system at zero Froude number; McCreight 1970); what
        the sail, appendages and viscous wake add is not published for SUBOFF, so it is a parameter.
        0 turns the free surface off (deep water).
    """

    suction_factor: float = 1.0

    def __post_init__(self) -> None:
        check.number("suction_factor", self.suction_factor, 0.0, 10.0)


NO_FREE_SURFACE: Final = FreeSurface(suction_factor=0.0)
"""Deep water: the model of Riedel (1993), with no free-surface force."""


@inline_kernel
def suction_point(
    theta: float, depth: float, u: float, rho_suction: float, hull: FloatArray, first_row: int
) -> tuple[float, float]:
    """Free-surface heave force Z_fs [N, down positive] and pitch moment M_fs [N m, nose-up positive]
    on the hull at pitch ``theta`` [rad], depth ``depth`` [m] and speed ``u`` [m/s].

    ``rho_suction`` is the water density times :attr:`FreeSurface.suction_factor` [kg/m^3] (0: no
    free surface, and the force is exactly 0.0); ``hull`` holds the sources
    (:func:`subenv.dynamics.hull.source_rows`) in rows ``first_row`` .. ``first_row + 2``. The Lagally
    force of the hull's sources in the flow of their rigid-lid images (module docstring), summed over
    pairs of segments.
    """
    if rho_suction == 0.0:  # (deep water: the sum below would be zero, and is not computed)
        return 0.0, 0.0
    n_seg = hull.shape[1] - 1
    xs, strength, radius = hull[first_row], hull[first_row + 1], hull[first_row + 2]
    s, c = math.sin(theta), math.cos(theta)
    force = 0.0  # sum over pairs of s_k s_l (h_k + h_l) / r^3, up positive
    moment = 0.0  # the same with x_k weights
    for k in range(n_seg):
        xk = xs[k]
        hk = station_depth(depth, xk, s, radius[k])
        sk = strength[k]
        # The self pair (image 2 h_k above), then each pair once, both ends weighted.
        self_term = self_pair(sk, hk)
        force += self_term
        moment += xk * self_term
        for m in range(k + 1, n_seg):
            xm = xs[m]
            pair = source_pair(xk, hk, sk, xm, station_depth(depth, xm, s, radius[m]), strength[m], c)
            force += 2.0 * pair
            moment += (xk + xm) * pair
    return suction_from_sums(force, moment, u, rho_suction, c)


# The terms of suction_point's sum, one function each, so that the JAX twin (subenv.jax) sums the
# same terms over arrays of segments.
@inline_kernel
def station_depth(depth: float, x: float, sin_theta: float, radius: float) -> float:
    """Depth [m] of the hull's sources at station ``x`` [m] (a station above the surface is taken at its
    radius)."""
    return maximum(depth - x * sin_theta, radius)


@inline_kernel
def self_pair(strength: float, h: float) -> float:
    """A segment's sources with their own image, ``2 h`` above them: s_k^2 / (4 h_k^2)."""
    return strength * strength / (4.0 * h * h)


@inline_kernel
def source_pair(xk: float, hk: float, sk: float, xm: float, hm: float, sm: float, cos_theta: float) -> float:
    """Segment k's sources with segment m's image: s_k s_m (h_k + h_m) / r^3."""
    dz = hk + hm
    dx = (xk - xm) * cos_theta
    r2 = dx * dx + dz * dz
    return sk * sm * dz / (r2 * math.sqrt(r2))


@inline_kernel
def suction_from_sums(
    force: float, moment: float, u: float, rho_suction: float, cos_theta: float
) -> tuple[float, float]:
    """(Z_fs [N], M_fs [N m]) from the sums over the pairs (``force``: up positive; ``moment``: with x_k
    weights)."""
    scale = rho_suction * u * u / _FOUR_PI
    return -scale * force * cos_theta, scale * moment * cos_theta


@kernel
def _suction_rows(
    theta: FloatArray,
    depth: FloatArray,
    u: FloatArray,
    rho_suction: FloatArray,
    hull: FloatArray,
    first_row: int,
    Z: FloatArray,
    M: FloatArray,
) -> None:
    # A loop over rows, not a generalized ufunc (see subenv.dynamics._jit).
    for i in range(theta.shape[0]):
        Z[i], M[i] = suction_point(theta[i], depth[i], u[i], rho_suction[i], hull, first_row)


def suction(
    hull: HullTable, pitch_rad: ArrayLike, depth_m: ArrayLike, speed_mps: ArrayLike, rho_suction: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """:func:`suction_point` broadcast over arrays: (Z_fs [N], M_fs [N m]).

    Parameters
    ----------
    hull : subenv.dynamics.HullTable
        The hull (its :attr:`~subenv.dynamics.HullTable.packed` table holds the sources).
    pitch_rad, depth_m, speed_mps : array_like
        Pitch [rad], depth of midship [m, down positive], forward speed [m/s].
    rho_suction : array_like
        Water density times :attr:`FreeSurface.suction_factor` [kg/m^3]
        (:attr:`subenv.dynamics.ModelParams.rho_suction`).
    """
    shape = np.broadcast_shapes(*(np.shape(a) for a in (pitch_rad, depth_m, speed_mps, rho_suction)))
    Z, M = np.empty(math.prod(shape)), np.empty(math.prod(shape))
    theta, depth, u, rho = (rows(a, shape) for a in (pitch_rad, depth_m, speed_mps, rho_suction))
    _suction_rows(theta, depth, u, rho, hull.packed, SOURCE_ROW, Z, M)
    return Z.reshape(shape), M.reshape(shape)


def dipole_suction_N(
    volume_m3: ArrayLike, depth_m: ArrayLike, speed_mps: ArrayLike, density_kg_m3: float
) -> FloatArray:
    """The far-field limit of the suction, 3 rho u^2 V^2 / (64 pi h^4) [N, up positive]: the hull as
    one dipole of moment u V attracted by its image at 2 h (a check of :func:`suction_point`, valid
    for h >> L)."""
    V, h, u = (np.asarray(a, dtype=float) for a in (volume_m3, depth_m, speed_mps))
    return 3.0 * density_kg_m3 * u * u * V * V / (64.0 * math.pi * h**4)
