"""Bifurcation sets of the asymmetric pitchfork in the (lambda, beta) plane (Riedel 1993 Ch. IV-V).

lambda = u^2 / (g z_GB) = Fn^2 (eq. 4.25) and beta = -x_GB g / u^2 (eq. 4.27). Inside a cusp the
boat has several steady states for the same speed and loading; crossing its edge makes the
steady pitch jump (Fig. 4-13).

A note on eq. 4.37 as printed, 27 beta^2 lambda^2 = 8 u^2 (1 + zeta lambda)^3: its u^2 is not
dimensionless (the thesis's eq. 4.26 drops a factor u from two terms when it divides eq. 4.7 by
Z_delta z_GB W). Redoing the division gives w^3 - 2u^2 (1 + zeta lambda) w + 2 u^3 beta lambda + ...
= 0 and the dimensionless cusp 27 beta^2 lambda^2 = 8 (1 + zeta lambda)^3, which matches the folds
of the exact equation (tests/analysis). Both forms are here; ``form="thesis"`` evaluates the
printed one with u in ft/s, as the thesis's Fig. 4-2 did.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Literal

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from subenv._typing import FloatArray
from subenv.analysis.equilibria import DragMoment, HullIntegral, _drag_terms, steady_state_residual
from subenv.analysis.linear import plane_derivatives
from subenv.units import mps_to_fps
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "approximate_cusp",
    "buoyancy_bifurcation_set",
    "exact_bifurcation_set",
    "exact_cusp",
    "offset_from_beta",
    "saturation_cusp",
    "saturation_cusp_closed_form",
    "speed_from_lambda",
    "zeta",
]

CuspForm = Literal["consistent", "thesis"]


def speed_from_lambda(vehicle: Vehicle, lam: FloatArray | float) -> FloatArray:
    """U = sqrt(lambda g z_GB) [m/s], lambda as in eq. 4.25."""
    return np.sqrt(np.asarray(lam, dtype=float) * vehicle.gravity_m_s2 * vehicle.z_GB_m)


def offset_from_beta(vehicle: Vehicle, beta: FloatArray | float, speed_mps: FloatArray | float) -> FloatArray:
    """x_GB = -beta u^2 / g [m], beta as in eq. 4.27."""
    return -np.asarray(beta, dtype=float) * np.asarray(speed_mps, dtype=float) ** 2 / vehicle.gravity_m_s2


def zeta(vehicle: Vehicle, alpha: float = 0.0) -> float:
    """Zeta = g (Z_w M_d - M_w Z_d) / (Z_d W) (eq. 4.28); 1 + zeta lambda = 0 at the critical speed."""
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    c = vehicle.coefficients
    return vehicle.gravity_m_s2 * (c.Z_w * M_d - c.M_w * Z_d) / (Z_d * vehicle.weight_N)


def exact_cusp(
    vehicle: Vehicle, lam: FloatArray, alpha: float = 0.0, form: CuspForm = "consistent"
) -> FloatArray:
    """|beta| on the cusp of the simplified pitchfork (eq. 4.37) for each lambda below critical.

    ``form="consistent"``: 27 beta^2 lambda^2 = 8 (1 + zeta lambda)^3 (dimensionless);
    ``form="thesis"``: 27 beta^2 lambda^2 = 8 u^2 (1 + zeta lambda)^3 with u in ft/s, as printed.
    NaN where 1 + zeta lambda < 0 (above the critical speed there is no cusp).
    """
    lam = np.asarray(lam, dtype=float)
    growth = 1.0 + zeta(vehicle, alpha) * lam
    factor = 1.0 if form == "consistent" else mps_to_fps(speed_from_lambda(vehicle, lam)) ** 2
    with np.errstate(invalid="ignore"):
        return np.where(growth >= 0, np.sqrt(8.0 * factor * growth**3 / (27.0 * lam**2)), np.nan)


def approximate_cusp(
    vehicle: Vehicle, beta: FloatArray, alpha: float = 0.0, form: CuspForm = "consistent"
) -> FloatArray:
    """Lambda on the cusp near its point, the small-beta expansion of eq. 4.37 (eq. 4.39).

    lambda = lambda_0 (1 - 3/2 (|beta| lambda_0)^(2/3) c), lambda_0 = -1/zeta, c = 1 (consistent)
    or u_cr^(-2/3) with u_cr in ft/s (the printed form).
    """
    lam0 = -1.0 / zeta(vehicle, alpha)
    c = 1.0 if form == "consistent" else float(mps_to_fps(speed_from_lambda(vehicle, lam0))) ** (-2.0 / 3.0)
    return lam0 * (1.0 - 1.5 * (np.abs(np.asarray(beta, dtype=float)) * lam0) ** (2.0 / 3.0) * c)


def exact_bifurcation_set(
    vehicle: Vehicle,
    speeds_mps: FloatArray,
    alpha: float = 0.0,
    drag_moment: DragMoment = "consistent",
    hull: HullIntegral = "full",
) -> tuple[FloatArray, FloatArray]:
    """Ballast offsets x_GB [m] at which the exact steady-state equation folds, per speed.

    Eq. 4.3 is affine in x_GB (through x_G W - x_B B with x_B kept): x_GB(theta) = -g0(theta) /
    (W Z_d cos(theta)), and a fold (two steady states merging) is an extremum of x_GB(theta). Below
    the critical speed there are two, x_low < 0 < x_high for the neutral boat; NaN above it.
    Uses the vehicle's own W, B, z_GB and C_D (the thesis's Figs 4-2, 4-3 are its C_D cases).

    Returns
    -------
    x_low, x_high : ndarray
        The two edges of the bifurcation set [m], NaN where there is none.
    """
    Z_d, _ = plane_derivatives(vehicle, alpha)
    W = vehicle.weight_N
    base = vehicle.variant(x_GB_m=0.0)

    def offset(theta: float, u: float) -> float:
        g0 = float(steady_state_residual(base, u, theta, alpha, drag_moment, hull))
        return -g0 / (W * Z_d * math.cos(theta))

    return _fold_edges(offset, speeds_mps)


def buoyancy_bifurcation_set(
    vehicle: Vehicle,
    speeds_mps: FloatArray,
    alpha: float = 0.0,
    drag_moment: DragMoment = "consistent",
    hull: HullIntegral = "full",
) -> tuple[FloatArray, FloatArray]:
    """Excess buoyancy fractions (B - W) / W at which the exact steady-state equation folds, per speed.

    The counterpart of :func:`exact_bifurcation_set` for the other imperfection of the pitchfork (Riedel 1993
    Ch. V.C): eq. 4.3 is affine in B (through (W - B) M_d, x_B B and z_B B, W kept), so each pitch theta is a
    steady state for one B(theta), and a fold is an extremum of B(theta). Below the critical speed there
    are two, one on each side of the neutral boat's; NaN above it. Uses the vehicle's own x_GB, z_GB and C_D.

    Returns
    -------
    low, high : ndarray
        The two edges of the bifurcation set as (B - W) / W, NaN where there is none.
    """
    W = vehicle.weight_N
    neutral, heavier = vehicle.variant(excess_buoyancy_N=0.0), vehicle.variant(excess_buoyancy_N=W)

    def excess(theta: float, u: float) -> float:
        r0 = float(steady_state_residual(neutral, u, theta, alpha, drag_moment, hull))
        r1 = float(steady_state_residual(heavier, u, theta, alpha, drag_moment, hull)) - r0  # per W of excess
        return -r0 / r1

    return _fold_edges(excess, speeds_mps)


def _fold_edges(
    parameter: Callable[[float, float], float], speeds_mps: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The two extrema of ``parameter(theta, u)`` nearest zero over theta, per speed: the folds of the
    steady states (two merge where the parameter that puts theta at a steady state turns back)."""
    lows, highs = [], []
    for u in np.asarray(speeds_mps, dtype=float):
        grid = np.linspace(-1.2, 1.2, 481)
        values = np.array([parameter(t, u) for t in grid])
        slope = np.diff(values)
        turns = np.flatnonzero(np.sign(slope[:-1]) * np.sign(slope[1:]) < 0) + 1
        extrema = []
        for i in turns:
            sign = -1.0 if slope[i - 1] > 0 else 1.0  # (a maximum, or a minimum)
            res = minimize_scalar(
                lambda t, u=u, sign=sign: sign * parameter(t, u),
                bounds=(grid[i - 1], grid[i + 1]),
                method="bounded",
                options={"xatol": 1e-10},
            )
            extrema.append(parameter(float(res.x), u))
        inner = sorted(extrema, key=abs)[:2]
        if len(inner) == 2:
            lows.append(min(inner))
            highs.append(max(inner))
        else:
            lows.append(math.nan)
            highs.append(math.nan)
    return np.array(lows), np.array(highs)


def saturation_cusp(
    vehicle: Vehicle,
    speeds_mps: FloatArray,
    alpha: float = 0.0,
    drag_moment: DragMoment = "consistent",
    hull: HullIntegral = "full",
) -> tuple[FloatArray, FloatArray]:
    """Ballast offsets at which a depth-holding steady state reaches the plane limit, per speed.

    For delta = +-limit and w = u tan(theta), solve the heave balance (eq. 4.44; 5.1 with excess
    buoyancy and drag) for theta, then the pitch balance (eq. 4.45; 5.2) for x_GB. With C_D = 0 and
    W = B this is eq. 4.43 (see :func:`saturation_cusp_closed_form`).

    Returns
    -------
    x_plus, x_minus : ndarray
        x_GB [m] for delta = +limit and -limit (NaN where the heave balance has no root).
    """
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    c = vehicle.coefficients
    W, B = vehicle.weight_N, vehicle.buoyancy_N
    drag, drag_moment_factor = _drag_terms(vehicle, drag_moment, hull)
    out: dict[float, list[float]] = {1.0: [], -1.0: []}
    for u in np.asarray(speeds_mps, dtype=float):
        for sign in (1.0, -1.0):
            delta = sign * vehicle.planes.limit_rad

            def heave(theta: float, u: float = u, delta: float = delta) -> float:
                w = u * math.tan(theta)
                return c.Z_w * u * w - drag * w * abs(w) + (W - B) * math.cos(theta) + Z_d * u * u * delta

            lo, hi = -1.45, 1.45
            if heave(lo) * heave(hi) > 0:
                out[sign].append(math.nan)
                continue
            theta = brentq(heave, lo, hi, xtol=1e-14)
            w = u * math.tan(theta)
            # Eq. 4.45 / 5.2 solved for x_G W - x_B B, then x_GB with x_B kept.
            xGW_xBB = (
                c.M_w * u * w
                + drag_moment_factor * w * abs(w)
                - (vehicle.z_G_m * W - vehicle.z_B_m * B) * math.sin(theta)
                + M_d * u * u * delta
            ) / math.cos(theta)
            out[sign].append((xGW_xBB + vehicle.x_B_m * B) / W - vehicle.x_B_m)
    return np.array(out[1.0]), np.array(out[-1.0])


def saturation_cusp_closed_form(
    vehicle: Vehicle, x_GB_m: FloatArray, sign: float, alpha: float = 0.0
) -> FloatArray:
    """Eq. 4.43 (C_D = 0, W = B): the speed^2 at which the planes saturate, for each x_GB.

    u^2 = (-x_GB Z_w W + z_GB W Z_d delta) / ((Z_d M_w - M_d Z_w) delta (1 + (Z_d/Z_w)^2 delta^2)^(1/2)).
    """
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    c = vehicle.coefficients
    W = vehicle.weight_N
    delta = sign * vehicle.planes.limit_rad
    x = np.asarray(x_GB_m, dtype=float)
    return (-x * c.Z_w * W + vehicle.z_GB_m * W * Z_d * delta) / (
        (Z_d * c.M_w - M_d * c.Z_w) * delta * math.sqrt(1.0 + (Z_d / c.Z_w) ** 2 * delta**2)
    )
