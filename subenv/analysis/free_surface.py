"""Level flight near the free surface: trims, their stability, the shallowest depth a speed can hold,
and how the critical speed moves (the first recommendation of Riedel 1993, Ch. VI).

Every number here comes from the one right-hand side, :func:`subenv.dynamics.derivatives`, with the
free surface's suction in it (:mod:`subenv.dynamics.free_surface`) and, for a seaway, the waves'
mean suction at the trim's depth (:meth:`subenv.dynamics.waves.SeaState.mean_suction`) as an
external force: no equation is written again here, except the critical speed's closed form, which
is the check of the numerical one.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np
from scipy.optimize import brentq, root

from subenv import _validation as check
from subenv._typing import FloatArray
from subenv.analysis.critical import critical_speed
from subenv.analysis.linear import check_alpha, plane_derivatives
from subenv.dynamics.free_surface import FreeSurface, suction, validity_depth_m
from subenv.dynamics.model import derivatives, derivatives_with, model_params
from subenv.dynamics.waves import SeaState
from subenv.thesis import reference_length_ratio
from subenv.vehicles.scaling import froude_factor
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "LevelFlightDepth",
    "SurfaceCriticalSpeed",
    "SurfaceTrim",
    "min_level_flight_depth",
    "surface_critical_speed",
    "surface_trim",
]

_EPS: Final = 1e-6  # central-difference step of the Jacobians (rad, m/s, rad/s, m)
_RESIDUAL: Final = 1e-12  # m/s^2 and rad/s^2: a trim's heave and pitch accelerations, at most
_PITCH_STARTS_RAD: Final = (0.0, 0.1, -0.1, 0.2, -0.2, 0.4, -0.4)  # the trim search's starts
# Depths from the deepest (5 m on SUBOFF) to the hull radius, geometric (steps below 1 % of the depth).
_DEPTH_STEPS: Final = 400
_BRANCH_JUMP_RAD: Final = 0.05  # a trim this far in pitch from the one below is another branch
_DEPTH_TOLERANCE_M: Final = 1e-3  # of the shallowest depth held
_DEEPEST_M: Final = 5.0  # the search's deepest depth on SUBOFF (Froude-scaled on another vehicle, as its
# episodes are): there SUBOFF's suction is below 0.1 % of its plane force


@dataclass(frozen=True)
class SurfaceTrim:
    """Steady level flight (q = 0, w = u tan(theta): constant depth) at one depth and speed.

    Attributes
    ----------
    depth_m, speed_mps : float
        Depth of midship [m] and forward speed [m/s].
    pitch_rad, heave_mps : float
        The trim's pitch [rad] and heave velocity [m/s].
    plane_rad : float
        Dual-control command delta [rad] (stern planes; bow planes alpha delta); may exceed the limit.
    within_limits : bool
        |delta| within the vehicle's plane limit.
    suction_N, suction_moment_Nm : float
        The free surface's heave force [N, down positive] and pitch moment [N m] at the trim
        (suction and a sea's mean suction).
    eigenvalues : ndarray
        Of the 4x4 Jacobian in (theta, w, q, Z) with the planes held at the trim [1/s]: depth
        enters through the suction, so the depth mode is no longer a zero eigenvalue.
    stable : bool
        All eigenvalues in the open left half-plane.
    solver : object
        scipy's result of the trim's root search.
    """

    depth_m: float
    speed_mps: float
    pitch_rad: float
    heave_mps: float
    plane_rad: float
    within_limits: bool
    suction_N: float
    suction_moment_Nm: float
    eigenvalues: np.ndarray = field(repr=False)
    stable: bool
    solver: Any = field(repr=False, compare=False)


@dataclass(frozen=True)
class LevelFlightDepth:
    """The shallowest depth at which a speed can hold level flight within the plane limit.

    Attributes
    ----------
    speed_mps : float
    min_depth_m : float
        Shallowest depth [m] with a trim within the plane limit; the hull radius (broaching) when
        the planes hold it up to the surface.
    limited_by : str
        Why the boat cannot go shallower: ``"planes"`` (the trim needs more than the plane limit),
        ``"no trim"`` (no level-flight equilibrium exists: it has met another in a fold) or
        ``"broaching"`` (the planes hold it up to the hull radius).
    plane_limit_rad : float
    alpha : float
    """

    speed_mps: float
    min_depth_m: float
    limited_by: str
    plane_limit_rad: float
    alpha: float


@dataclass(frozen=True)
class SurfaceCriticalSpeed:
    """The critical speed at one depth below the surface, found two ways.

    At the critical speed a held plane angle no longer changes the steady depth rate (Riedel 1993
    Ch. III; eq. 3.9 in deep water). Near the surface the suction adds a pitch stiffness
    dM_fs/dtheta and a heave force dZ_fs/dtheta, both proportional to u^2 (per u^2:
    ``suction_M_theta``, ``suction_Z_theta``), and, in the slender-body theory, changes the heave
    derivatives Z_w and M_w by dZ_fs/dw and dM_fs/dw, proportional to u (per u: ``suction_Z_w``,
    ``suction_M_w``). In level flight w = u theta to first order, and eq. 3.9 becomes

        u_cr^2 = Z_d (z_G W - z_B B) / ((M_w + m_w) Z_d - (Z_w + z_w) M_d + Z_d m_theta - z_theta M_d).

    Attributes
    ----------
    depth_m : float
    speed_mps : float
        From the closed form above [m/s].
    speed_numerical_mps : float
        Where the steady depth-rate gain of the linearised right-hand side at (0, 0, 0, depth)
        changes sign (root search) [m/s]: the check.
    deep_speed_mps : float
        Eq. 3.9, deep water [m/s].
    suction_Z_theta, suction_M_theta : float
        dZ_fs/dtheta / u^2 [kg/m per rad] and dM_fs/dtheta / u^2 [kg per rad] at level flight.
    suction_Z_w, suction_M_w : float
        dZ_fs/dw / u [kg/m] and dM_fs/dw / u [kg] at level flight (0 in the sources-only theory).
    within_validity : bool
        ``depth_m`` at least :func:`~subenv.dynamics.free_surface.validity_depth_m` (the model's range).
    """

    depth_m: float
    speed_mps: float
    speed_numerical_mps: float
    deep_speed_mps: float
    suction_Z_theta: float
    suction_M_theta: float
    suction_Z_w: float = 0.0
    suction_M_w: float = 0.0
    within_validity: bool = True

    @property
    def shift(self) -> float:
        """u_cr(depth) / u_cr(deep) - 1 [-]."""
        return self.speed_mps / self.deep_speed_mps - 1.0


def sea_mean_suction(vehicle: Vehicle, sea_state: SeaState | None, depth_m: float) -> tuple[float, float]:
    """A sea's mean suction on ``vehicle`` at ``depth_m``: the external (heave force [N], pitch moment
    [N m]) of :func:`subenv.dynamics.derivatives` for a trim there (:meth:`SeaState.mean_suction` over the
    vehicle's hull); (0, 0) in calm water (``sea_state`` None)."""
    if sea_state is None:
        return 0.0, 0.0
    Z, M = sea_state.mean_suction(
        depth_m,
        np.asarray(vehicle.hull.x_m),
        np.asarray(vehicle.hull.breadth_m),
        vehicle.water_density_kg_m3,
        vehicle.gravity_m_s2,
    )
    return float(Z), float(M)


def _field(
    vehicle: Vehicle,
    rhs: Callable[..., FloatArray],
    sea_state: SeaState | None,
    u: float,
    stern: float,
    bow: float,
    x: FloatArray,
) -> FloatArray:
    """``rhs`` (:func:`~subenv.dynamics.derivatives_with` of the loading) at ``x`` with a sea's mean
    suction at its depth."""
    force, moment = sea_mean_suction(vehicle, sea_state, float(x[3]))
    return rhs(np.asarray(x, dtype=float), u, stern, bow, force, moment)


def _plane_limit(vehicle: Vehicle) -> float:
    return vehicle.planes.limit_rad


def _check(vehicle: Vehicle, speed_mps: float, depth_m: float) -> tuple[float, float]:
    u = check.positive("speed_mps", speed_mps, upper=100.0)
    radius = max(vehicle.hull.breadth_m) / 2
    h = check.number("depth_m", depth_m)
    check.require(
        "depth_m",
        depth_m,
        h > radius,
        f"deeper than the hull radius, {radius:.4g} m (above it the hull broaches)",
    )
    return u, h


def surface_trim(
    vehicle: Vehicle,
    speed_mps: float,
    depth_m: float,
    alpha: float = 0.0,
    free_surface: FreeSurface | None = None,
    sea_state: SeaState | None = None,
    start: tuple[float, float] | None = None,
) -> SurfaceTrim:
    """Level flight at ``depth_m`` and ``speed_mps`` with the free surface's suction (and a sea's mean
    suction): the pitch and dual-control plane angle that balance heave and pitch with q = 0 and
    w = u tan(theta), and the stability of that steady state with the planes held.

    Parameters
    ----------
    vehicle : Vehicle
    speed_mps : float
        Forward speed [m/s], > 0.
    depth_m : float
        Depth of midship [m], deeper than the hull radius.
    alpha : float
        Dual-control allocation (Riedel 1993 eq. 2.58), in [-1, 1].
    free_surface : FreeSurface, optional
        The suction model (default :class:`~subenv.dynamics.free_surface.FreeSurface`, factor 1).
    sea_state : SeaState, optional
        Adds the waves' mean suction at the depth.
    start : (float, float), optional
        (pitch [rad], plane [rad]) to start the root search from, and only from there (a branch
        followed in depth: :func:`min_level_flight_depth`); by default from level and pitched starts,
        keeping the trim nearest to level.

    Raises
    ------
    RuntimeError
        No trim found.
    """
    u, h = _check(vehicle, speed_mps, depth_m)
    alpha = check_alpha(alpha)
    params = model_params(vehicle, free_surface or FreeSurface())
    rhs = derivatives_with(params)

    def balance(v: FloatArray) -> FloatArray:
        theta, delta = v
        x = np.array([theta, u * math.tan(theta), 0.0, h])
        return _field(vehicle, rhs, sea_state, u, delta, alpha * delta, x)[1:3]

    # From level (the trim of a neutral boat in deep water), then from pitched starts and by
    # Levenberg-Marquardt where Powell's hybrid method stalls; the nearest trim to level is kept.
    found = []
    starts = [start] if start is not None else [(pitch, 0.0) for pitch in _PITCH_STARTS_RAD]
    for first in starts:
        for method in ("hybr", "lm"):
            result = root(balance, np.array(first, dtype=float), method=method, tol=1e-14)
            if np.max(np.abs(balance(result.x))) <= _RESIDUAL and abs(result.x[0]) < 0.5 * math.pi:
                found.append(result)
                break
        if found and first[0] == 0.0:
            break
    if not found:
        raise RuntimeError(
            f"surface_trim: no level-flight trim at depth {h} m, speed {u} m/s from pitch "
            f"{_PITCH_STARTS_RAD} rad"
        )
    result = min(found, key=lambda r: abs(r.x[0]))
    theta, delta = (float(v) for v in result.x)
    x0 = np.array([theta, u * math.tan(theta), 0.0, h])
    steps = _EPS * np.eye(4)
    jac = np.stack(
        [
            (
                _field(vehicle, rhs, sea_state, u, delta, alpha * delta, x0 + e)
                - _field(vehicle, rhs, sea_state, u, delta, alpha * delta, x0 - e)
            )
            / (2 * _EPS)
            for e in steps
        ],
        axis=1,
    )
    eig = np.linalg.eigvals(jac)
    Zfs, Mfs = (
        float(a)
        for a in suction(params.hull, theta, h, u, params.rho_suction, x0[1], 0.0, params.suction_model)
    )
    Zw, Mw = sea_mean_suction(vehicle, sea_state, h)
    return SurfaceTrim(
        depth_m=h,
        speed_mps=u,
        pitch_rad=theta,
        heave_mps=float(x0[1]),
        plane_rad=delta,
        within_limits=max(abs(delta), abs(alpha * delta)) <= _plane_limit(vehicle),
        suction_N=Zfs + Zw,
        suction_moment_Nm=Mfs + Mw,
        eigenvalues=eig,
        stable=bool(np.all(eig.real < 0)),
        solver=result,
    )


def min_level_flight_depth(
    vehicle: Vehicle,
    speed_mps: float,
    alpha: float = 0.0,
    free_surface: FreeSurface | None = None,
    sea_state: SeaState | None = None,
) -> LevelFlightDepth:
    """The shallowest depth at which ``speed_mps`` holds level flight with the planes within their limit.

    The level-flight trim of deep water (level, planes amidships, for a neutral boat) is followed up
    towards the surface in steps of at most 1 % of the depth, each trim's root search started from
    the one below (:func:`surface_trim`), until the trim needs more than the plane limit or the
    branch is lost: near the surface the suction's nose-up moment grows with pitch, and the trim
    meets another in a fold and disappears (the root search fails, or lands on a distant branch);
    the boundary is then bisected to 1 mm.
    """
    u = check.positive("speed_mps", speed_mps, upper=100.0)
    alpha = check_alpha(alpha)
    limit = _plane_limit(vehicle)
    radius = max(vehicle.hull.breadth_m) / 2

    def follow(h: float, below: SurfaceTrim) -> tuple[SurfaceTrim | None, str]:
        try:
            trim = surface_trim(
                vehicle, u, h, alpha, free_surface, sea_state, start=(below.pitch_rad, below.plane_rad)
            )
        except RuntimeError:
            return None, "no trim"
        if abs(trim.pitch_rad - below.pitch_rad) > _BRANCH_JUMP_RAD:
            return None, "no trim"
        return trim, "" if trim.within_limits else "planes"

    deepest = _DEEPEST_M * froude_factor(
        "length", reference_length_ratio(vehicle)
    )  # (x 1.0 exactly on SUBOFF)
    held = surface_trim(vehicle, u, deepest, alpha, free_surface, sea_state)
    if not held.within_limits:
        raise ValueError(f"speed_mps={u!r}: level flight cannot be held even at {deepest:.6g} m")
    for h in np.geomspace(deepest, radius * (1.0 + 1e-6), _DEPTH_STEPS)[1:]:
        trim, why = follow(float(h), held)
        if why:
            lost = float(h)
            while held.depth_m - lost > _DEPTH_TOLERANCE_M:
                mid = 0.5 * (held.depth_m + lost)
                trim, why_mid = follow(mid, held)
                if why_mid:
                    lost, why = mid, why_mid
                else:
                    held = trim  # type: ignore[assignment]
            return LevelFlightDepth(u, held.depth_m, why, limit, alpha)
        held = trim  # type: ignore[assignment]
    return LevelFlightDepth(u, radius, "broaching", limit, alpha)


def surface_critical_speed(
    vehicle: Vehicle, depth_m: float, alpha: float = 0.0, free_surface: FreeSurface | None = None
) -> SurfaceCriticalSpeed:
    """The critical speed at ``depth_m`` below the surface, by the closed form and by the linearised
    right-hand side (:class:`SurfaceCriticalSpeed`)."""
    _, h = _check(vehicle, 1.0, depth_m)
    alpha = check_alpha(alpha)
    params = model_params(vehicle, free_surface or FreeSurface())
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    c = vehicle.coefficients
    restoring = vehicle.z_G_m * vehicle.weight_N - vehicle.z_B_m * vehicle.buoyancy_N

    # The suction's pitch derivatives per u^2 and heave derivatives per u: central differences at u = 1 m/s.
    def at(pitch: float, heave: float) -> tuple[float, float]:
        Z, M = suction(params.hull, pitch, h, 1.0, params.rho_suction, heave, 0.0, params.suction_model)
        return float(Z), float(M)

    (Zp, Mp), (Zm, Mm) = at(_EPS, 0.0), at(-_EPS, 0.0)
    z_theta, m_theta = (Zp - Zm) / (2 * _EPS), (Mp - Mm) / (2 * _EPS)
    (Zp, Mp), (Zm, Mm) = at(0.0, _EPS), at(0.0, -_EPS)
    z_w, m_w = (Zp - Zm) / (2 * _EPS), (Mp - Mm) / (2 * _EPS)
    denominator = (c.M_w + m_w) * Z_d - (c.Z_w + z_w) * M_d + Z_d * m_theta - z_theta * M_d
    closed = math.sqrt(Z_d * restoring / denominator)  # Riedel (1993) eq. 3.9 with the suction's derivatives

    def depth_rate_gain(u: float) -> float:
        # Held planes delta: the steady (theta, w) of the (w, q) balances with q = 0, and its depth rate.
        x0 = np.array([0.0, 0.0, 0.0, h])
        steps = _EPS * np.eye(4)[:3]
        f = [
            derivatives(x0 + e, u, 0.0, 0.0, params) - derivatives(x0 - e, u, 0.0, 0.0, params) for e in steps
        ]
        A = np.stack(f, axis=1)[:, :3] / (2 * _EPS)  # columns theta, w, q
        B = (
            derivatives(x0, u, _EPS, alpha * _EPS, params) - derivatives(x0, u, -_EPS, -alpha * _EPS, params)
        ) / (2 * _EPS)
        # q = 0 (theta_dot row), w_dot = q_dot = 0: solve rows 1, 2 for (theta, w) per unit delta.
        theta, w = np.linalg.solve(A[1:3, :2], -B[1:3])
        return float(-u * theta + w)

    deep = critical_speed(vehicle, alpha)
    numerical = brentq(depth_rate_gain, 0.5 * deep, 1.5 * deep, xtol=1e-10)
    return SurfaceCriticalSpeed(
        h, closed, float(numerical), deep, z_theta, m_theta, z_w, m_w, h >= validity_depth_m(vehicle)
    )
