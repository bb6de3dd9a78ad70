"""The free surface's pull on a submerged slender hull near it: the steady suction, written once.

A hull moving at speed u below the free surface draws the water over its top faster than under its
keel; the pressure there drops and the hull is pulled up (and pitched) towards the surface. This
module gives that force and moment as a function of depth, pitch, heave velocity, pitch rate and speed,
for :func:`subenv.dynamics.model.rhs_point`, the one right-hand side, and (batched) for the analysis.
The derivation, its sources and the checks of it are in ``docs/free_surface.md``.

The model, and where it comes from
----------------------------------
*Slender body.* A slender hull of revolution with cross-section S(x) = pi b(x)^2 / 4 moving along
its axis at speed u is represented by a line of sources of strength per unit length
m(x) = -u dS/dx (Newman 1977, *Marine Hydrodynamics*, ch. 7, slender-body theory):
sources over the forebody, sinks over the afterbody, sum zero. Its cross-flow, the relative normal
velocity W(x) (w - x q from the hull's own heave and pitch rate, body axes; in level flight
w = u tan(theta), the hull's incidence), raises a line of dipoles normal to the axis of moment
(S + a_33 / rho) W per unit length, 2 S W for circular sections (a_33 = rho S).

*The free surface as a rigid lid.* At small depth Froude number F_h = u / sqrt(g h) the free surface
is a rigid plane: the Kelvin-Havelock source below a free surface, whose wave terms scale with
exp(-2 g h / u^2), tends to a source plus its mirror image *of the same sign* above the surface
(Havelock 1931, "The wave resistance of a spheroid", Proc. R. Soc. A 131, the zero-speed
limit of his image system). A dipole's image is its mirror image. McCreight 1970 (MIT SM thesis
"Force and moment on a slender body of revolution moving in water of finite depth", supervised by
J. N. Newman) derives a consistent first-order slender-body heave force and pitch moment for the same
image system at a rigid plane boundary, the sea floor (its abstract; its text could not be read here).

*The loads: Lagally's theorem with dipoles* (:func:`section_load`). A source of flux Q in an outer flow
of velocity V feels -rho Q V; a dipole p feels the force -rho (p . grad) V and the couple -rho p x V
(Landweber and Yih 1956). The outer flow at the axis is the images' (:func:`image_flow`). To first
order in the images and in W the hull feels

1. its sources in the images' flow: the heave force, and its moment about midship (what the
   sources-only theory of ``PeriscopeDepth-v1`` computes, :func:`sources_suction`);
2. the dipoles that the images' normal velocity w_i raises, in the stream u: the couple
   u int (rho S + a_33) w_i dx, the steady form of strip theory's sectional force
   rho S Dw/Dt + D/Dt (a_33 w), D/Dt = -u d/dx; with a uniform w_i it makes the moment Munk's,
   u w_i (m_33 - m_11) (``tests/dynamics/test_free_surface.py``);
3. the cross-flow dipoles of the hull's own W in the source images' flow, the sources in the dipole
   images' flow, and the dipoles the dipole images raise, in the stream: a heave force and a moment
   linear in w and q, the free surface's share of Z_w, M_w, Z_q, M_q.

Terms 2 and 3 leave the level-flight heave force as it is but not the moment: at 1 m below the surface
SUBOFF's level-flight pitch stiffness is 1.6 times the sources-only theory's, and within 2% of an exact
potential-flow (panel) computation (docs/free_surface.md). The axis points are two per panel of equal
length (:func:`~subenv.dynamics.hull.slender_points`). Far from the surface the hull acts as one dipole
of moment u V (V the volume) and the force falls as

    Z_fs -> -3 rho u^2 V^2 / (64 pi h^4)        (h >> L),

the attraction of a dipole by its image, the same law as a sphere's 3 pi rho u^2 a^6 / (16 h^4)
(a sphere has dipole moment 2 pi u a^3 = 1.5 u V; ``tests/dynamics/test_free_surface.py`` checks
the limit).

Range of validity, and the constant left unknown
------------------------------------------------
- Slender hull (b << L); depth at least :data:`VALIDITY_DEPTH_RADII` hull radii (the line images'
  error grows as (r / 2h)^2: 6% there, 18% at 1.18 r, SUBOFF at 0.3 m). Shallower the model is
  extrapolated down to the hull radius (a station above the surface is taken at its own radius,
  where broaching ends an episode). :func:`within_validity` says where it holds; the environments warn
  once when an episode leaves that range, and the analysis marks its results outside it.
- Small depth Froude number, F_h^2 = u^2 / (g h) at most :data:`VALIDITY_FROUDE_SQUARED`: the rigid-lid
  limit. The finite-Froude corrections (O(F_h^2) in the local flow, exponentially small wave lift; at
  F_h of order one Havelock's wave terms reverse the force) are not modelled. At periscope depth
  (h = 0.8-1.2 m) and 0.4-1.2 m/s, F_h^2 = 0.01-0.18.
- Linear in the cross-flow W (small incidence and pitch rate), first order in the images.
- Inviscid flow over the bare hull of revolution: the sail, the planes and the boundary layer are
  not represented. How much they change the suction is not published for SUBOFF; it is exposed as
  :attr:`FreeSurface.suction_factor` (1: the potential-flow hull alone).

With ``suction_factor`` 0 (the default of every vehicle's :func:`subenv.dynamics.model_params`)
the free surface is absent: deep water, the model of Riedel (1993) exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from subenv import _validation as check
from subenv._typing import ArrayLike, FloatArray
from subenv.dynamics._jit import inline_kernel, kernel, maximum, rows
from subenv.dynamics.hull import SLENDER_ROW, SOURCE_ROW, HullTable

__all__ = [
    "NO_FREE_SURFACE",
    "SLENDER_BODY",
    "SOURCES_ONLY",
    "THEORIES",
    "VALIDITY_DEPTH_RADII",
    "VALIDITY_FROUDE_SQUARED",
    "FreeSurface",
    "dipole_suction_N",
    "image_distance",
    "image_flow",
    "section_load",
    "self_pair",
    "slender_suction",
    "source_pair",
    "sources_suction",
    "station_depth",
    "suction",
    "suction_from_sums",
    "suction_point",
    "validity_depth_m",
    "within_validity",
]

SLENDER_BODY: Final = 0.0
"""``ModelParams.suction_model`` of the consistent first-order slender-body theory
(:func:`slender_suction`)."""
SOURCES_ONLY: Final = 1.0
"""``ModelParams.suction_model`` of the sources-only theory (:func:`sources_suction`: ``PeriscopeDepth-v1``,
``PeriscopeDepthWaves-v0``)."""
THEORIES: Final = {"slender-body": SLENDER_BODY, "sources-only": SOURCES_ONLY}
""":attr:`FreeSurface.theory` -> ``ModelParams.suction_model``."""

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
    theory : str
        ``"slender-body"``: the consistent first-order slender-body theory (:func:`slender_suction`);
        ``"sources-only"``: the Lagally force of the hull's sources alone, one per segment
        (:func:`sources_suction`), the model of ``PeriscopeDepth-v1`` and ``PeriscopeDepthWaves-v0``,
        kept so that their seeded episodes stay as released. It lacks the moment of the hull's
        cross-flow dipoles, which is as large as the rest (docs/free_surface.md).
    """

    suction_factor: float = 1.0
    theory: str = "slender-body"

    def __post_init__(self) -> None:
        check.number("suction_factor", self.suction_factor, 0.0, 10.0)
        check.require("theory", self.theory, self.theory in THEORIES, f"one of {sorted(THEORIES)}")

    @property
    def suction_model(self) -> float:
        """The theory as ``ModelParams.suction_model`` (:data:`SLENDER_BODY` or :data:`SOURCES_ONLY`)."""
        return THEORIES[self.theory]


NO_FREE_SURFACE: Final = FreeSurface(suction_factor=0.0)
"""Deep water: the model of Riedel (1993), with no free-surface force."""


@inline_kernel
def suction_point(
    theta: float,
    w: float,
    q: float,
    depth: float,
    u: float,
    rho_suction: float,
    suction_model: float,
    hull: FloatArray,
    first_row: int,
) -> tuple[float, float]:
    """Free-surface heave force Z_fs [N, down positive] and pitch moment M_fs [N m, nose-up positive]
    on the hull at pitch ``theta`` [rad], heave velocity ``w`` [m/s], pitch rate ``q`` [rad/s], depth
    ``depth`` [m] and speed ``u`` [m/s].

    ``rho_suction`` is the water density times :attr:`FreeSurface.suction_factor` [kg/m^3] (0: no free
    surface, and the force is exactly 0.0); ``suction_model`` the theory (:data:`SLENDER_BODY`, or
    :data:`SOURCES_ONLY`, which ignores ``w`` and ``q``); ``hull`` holds the hull's rows
    (:func:`subenv.dynamics.hull.source_rows`) from row ``first_row`` on.
    """
    if rho_suction == 0.0:  # (deep water: the sums would be zero, and are not computed)
        return 0.0, 0.0
    if suction_model == SOURCES_ONLY:
        return sources_suction(theta, depth, u, rho_suction, hull, first_row)
    return slender_suction(theta, w, q, depth, u, rho_suction, hull, first_row + SLENDER_ROW)


@inline_kernel
def sources_suction(
    theta: float, depth: float, u: float, rho_suction: float, hull: FloatArray, first_row: int
) -> tuple[float, float]:
    """The sources-only theory's (Z_fs [N], M_fs [N m]) (:data:`SOURCES_ONLY`; ``PeriscopeDepth-v1``): the
    Lagally force of the hull's sources, one per segment, in the flow of their rigid-lid images, summed
    over pairs of segments, and its moment about midship from the vertical force alone. ``hull`` holds
    the sources (:func:`subenv.dynamics.hull.source_rows`) in rows ``first_row`` .. ``first_row + 2``.
    """
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


# The terms of sources_suction's sum, one function each, so that the JAX twin (subenv.jax) sums the
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


# The consistent first-order slender-body theory (docs/free_surface.md): the loads of a slender section in
# an outer flow (section_load), and the outer flow of the images (image_flow), one function each, so that
# the JAX twin (subenv.jax) sums the same terms over arrays of points.
@inline_kernel
def slender_suction(
    theta: float,
    w: float,
    q: float,
    depth: float,
    u: float,
    rho_suction: float,
    hull: FloatArray,
    first_row: int,
) -> tuple[float, float]:
    """The slender-body theory's (Z_fs [N], M_fs [N m]) (:data:`SLENDER_BODY`; module docstring): at every
    axis point (:func:`subenv.dynamics.hull.slender_points`, rows ``first_row`` .. ``first_row + 3`` of
    ``hull``) the outer flow of all the points' rigid-lid images (:func:`image_flow`) and the section's
    loads in it (:func:`section_load`), summed.

    Each point's images are computed in a loop that only stores (the sums follow in a loop of their
    own): the compiler turns it into vector instructions, four or eight images at once, which made the
    suction three times faster than a loop that summed as it went, though it meets every pair twice.
    """
    n = hull.shape[1] - 1
    xs, strength, weight, radius = (
        hull[first_row],
        hull[first_row + 1],
        hull[first_row + 2],
        hull[first_row + 3],
    )
    s, c = math.sin(theta), math.cos(theta)
    h, cross = np.empty(n), np.empty(n)
    normal, axial, slope = np.empty(n), np.empty(n), np.empty(n)
    for k in range(n):
        h[k] = station_depth(depth, xs[k], s, radius[k])
        cross[k] = w - xs[k] * q
    force = 0.0  # along the hull's upward normal, per unit density
    moment = 0.0
    for k in range(n):
        xk, hk = xs[k], h[k]
        for m in range(n):
            D, H = xk - xs[m], hk + h[m]
            A, B = image_distance(D, H, c)
            normal[m], axial[m], slope[m] = image_flow(D, H, A, B, strength[m], weight[m], cross[m], u, s, c)
        vn = 0.0
        ve = 0.0
        dvn = 0.0
        for m in range(n):
            vn += normal[m]
            ve += axial[m]
            dvn += slope[m]
        f, mk = section_load(xk, strength[k], weight[k], cross[k], u, vn, ve, dvn)
        force += f
        moment += mk
    return -rho_suction * force, rho_suction * moment


@inline_kernel
def image_distance(D: float, H: float, cos_theta: float) -> tuple[float, float]:
    """1 / (4 pi r^3) and 3 / (4 pi r^5) [m^-3, m^-5] for an image H [m] above a point and D cos(theta) [m]
    along the surface from it (:func:`image_flow`)."""
    r2 = D * D * cos_theta * cos_theta + H * H
    A = 1.0 / (_FOUR_PI * r2 * math.sqrt(r2))
    return A, 3.0 * A / r2


@inline_kernel
def image_flow(
    D: float,
    H: float,
    A: float,
    B: float,
    sm: float,
    vm: float,
    Wm: float,
    u: float,
    sin_theta: float,
    cos_theta: float,
) -> tuple[float, float, float]:
    """The outer flow at an axis point k of the rigid-lid image of point m (source u ``sm`` [m^3/s],
    cross-flow dipole ``vm`` ``Wm`` [m^4/s]), ``D`` = x_k - x_m [m] behind it along the axis and
    ``H`` = h_k + h_m [m] below it (``A``, ``B`` from :func:`image_distance`): the velocity along the
    hull's upward normal n [m/s], along its axis [m/s] and the normal velocity's derivative along n [1/s].

    In a rigid plane the image of a source is a source of the same sign, that of a dipole its mirror image
    (the method of images). The dipole image's axial velocity and slope act only on the hull's own dipoles,
    a load quadratic in the cross-flow, and are left out (the theory is linear in w and q).
    """
    s, c = sin_theta, cos_theta
    along_n = -c * (s * D + H)  # n . (point - image)
    source = u * sm
    # A point dipole p' at distance d: v = -(p' / r^3 - 3 (p' . d) d / r^5) / (4 pi); here p' = -vm Wm n',
    # n' the mirror of n, n . n' = s^2 - c^2 and (n' . d)(n . d) = -c^2 (H^2 - s^2 D^2).
    dipole = vm * Wm * ((s * s - c * c) * A + B * c * c * (H * H - s * s * D * D))
    return (
        source * A * along_n + dipole,
        source * A * (D * c * c - s * H),
        source * (A - B * along_n * along_n),
    )


@inline_kernel
def section_load(
    xk: float, sk: float, vk: float, Wk: float, u: float, normal: float, axial: float, normal_slope: float
) -> tuple[float, float]:
    """The loads per unit density on the slender section at station ``xk`` [m] (source u ``sk``, cross-flow
    dipole weight ``vk`` [m^3], relative cross-flow ``Wk`` = w - x q [m/s]) in an outer flow of normal
    velocity ``normal``, axial velocity ``axial`` and normal slope ``normal_slope`` (:func:`image_flow`):
    its force along the hull's upward normal [m^4/s^2] and its nose-up moment about midship [m^5/s^2].

    Lagally's theorem with dipoles (Landweber and Yih 1956, J. Fluid Mech. 1, 319-336): the source feels
    -rho Q V, the dipole p = -vk Wk n the force -rho (p . grad) V and the couple -rho p x V; the dipoles
    that the outer flow's cross-flow raises, vk ``normal``, feel the couple of the stream u, the term
    U int (rho S + a_33) w dx (docs/free_surface.md: in a uniform cross-flow it is what makes the moment
    Munk's).
    """
    force = -u * sk * normal + vk * Wk * normal_slope
    return force, xk * force - vk * Wk * axial + u * vk * normal


@kernel
def _suction_rows(
    theta: FloatArray,
    w: FloatArray,
    q: FloatArray,
    depth: FloatArray,
    u: FloatArray,
    rho_suction: FloatArray,
    suction_model: FloatArray,
    hull: FloatArray,
    first_row: int,
    Z: FloatArray,
    M: FloatArray,
) -> None:
    # A loop over rows, not a generalized ufunc (see subenv.dynamics._jit).
    for i in range(theta.shape[0]):
        Z[i], M[i] = suction_point(
            theta[i], w[i], q[i], depth[i], u[i], rho_suction[i], suction_model[i], hull, first_row
        )


def suction(
    hull: HullTable,
    pitch_rad: ArrayLike,
    depth_m: ArrayLike,
    speed_mps: ArrayLike,
    rho_suction: ArrayLike,
    heave_mps: ArrayLike = 0.0,
    pitch_rate_radps: ArrayLike = 0.0,
    suction_model: ArrayLike = SLENDER_BODY,
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
    heave_mps, pitch_rate_radps : array_like, optional
        Heave velocity w [m/s] and pitch rate q [rad/s] (body axes): the hull's cross-flow w - x q, whose
        dipoles' images the slender-body theory includes. In level flight w = u tan(pitch).
    suction_model : array_like, optional
        :data:`SLENDER_BODY` (default) or :data:`SOURCES_ONLY` (:attr:`FreeSurface.suction_model`,
        ``ModelParams.suction_model``).
    """
    arguments = (pitch_rad, heave_mps, pitch_rate_radps, depth_m, speed_mps, rho_suction, suction_model)
    shape = np.broadcast_shapes(*(np.shape(a) for a in arguments))
    Z, M = np.empty(math.prod(shape)), np.empty(math.prod(shape))
    theta, w, q, depth, u, rho, model = (rows(a, shape) for a in arguments)
    _suction_rows(theta, w, q, depth, u, rho, model, hull.packed, SOURCE_ROW, Z, M)
    return Z.reshape(shape), M.reshape(shape)


def dipole_suction_N(
    volume_m3: ArrayLike, depth_m: ArrayLike, speed_mps: ArrayLike, density_kg_m3: float
) -> FloatArray:
    """The far-field limit of the suction, 3 rho u^2 V^2 / (64 pi h^4) [N, up positive]: the hull as
    one dipole of moment u V attracted by its image at 2 h (a check of :func:`suction_point`, valid
    for h >> L)."""
    V, h, u = (np.asarray(a, dtype=float) for a in (volume_m3, depth_m, speed_mps))
    return 3.0 * density_kg_m3 * u * u * V * V / (64.0 * math.pi * h**4)


VALIDITY_DEPTH_RADII: Final = 2.0
"""The model holds for midship depths h of at least this many hull radii r (the hull's top a radius below
the surface): a line of images stands for the surface's images of the hull's sections with a relative
error of order (r / 2h)^2 (the next multipole of a section at distance 2h), 6% here; the two-point panels
(:func:`~subenv.dynamics.hull.slender_points`) are converged to within 1% there (docs/free_surface.md).
Shallower, the model is extrapolated (18% at h = 1.18 r, SUBOFF at 0.3 m), until the hull broaches at
h = r."""
VALIDITY_FROUDE_SQUARED: Final = 0.25
"""The rigid lid holds for a depth Froude number u^2 / (g h) of at most this (F_h 0.5): the free surface's
corrections are of order F_h^2 (module docstring). On SUBOFF it binds before the depth limit (0.51 m)
only above 1.12 m/s: at 0.55 m at PeriscopeDepth's fastest, 2 u_cr = 1.16 m/s."""


def validity_depth_m(vehicle: Any) -> float:
    """The shallowest midship depth [m] at which the free-surface model holds: :data:`VALIDITY_DEPTH_RADII`
    hull radii (of ``vehicle``, a :class:`~subenv.vehicles.Vehicle`)."""
    return VALIDITY_DEPTH_RADII * 0.5 * max(vehicle.hull.breadth_m)


def within_validity(vehicle: Any, depth_m: ArrayLike, speed_mps: ArrayLike) -> np.ndarray:
    """Whether (``depth_m`` [m], ``speed_mps`` [m/s]) lies where the model holds: deeper than
    :func:`validity_depth_m`, and a depth Froude number u^2 / (g h) of at most
    :data:`VALIDITY_FROUDE_SQUARED`."""
    h, u = np.asarray(depth_m, dtype=float), np.asarray(speed_mps, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        froude_squared = u * u / (vehicle.gravity_m_s2 * h)
    return (h >= validity_depth_m(vehicle)) & (froude_squared <= VALIDITY_FROUDE_SQUARED)
