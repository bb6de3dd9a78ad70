"""Linear models of the vertical-plane dynamics about level flight (Riedel 1993 eqs 2.59-2.68)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final, Literal, TypeAlias

import numpy as np

from subenv import _validation as check
from subenv._typing import FloatArray
from subenv.dynamics.free_surface import NO_FREE_SURFACE, FreeSurface
from subenv.dynamics.model import derivatives, model_params
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "BOW_PLANES_ONLY",
    "Allocation",
    "LinearModel",
    "check_alpha",
    "linear_model",
    "numerical_jacobian",
    "plane_derivatives",
]


def check_alpha(alpha: float) -> float:
    """Validate the bow/stern allocation alpha of dual control (eq. 2.58)."""
    check.require("alpha", alpha, check.is_number(alpha) and -1.0 <= alpha <= 1.0, "a number in [-1, 1]")
    return float(alpha)


BOW_PLANES_ONLY: Final = "bow"
"""Pass as ``alpha`` for bow-plane control only, the limit alpha -> infinity (Riedel 1993 Ch. V.B)."""

Allocation: TypeAlias = float | Literal["bow"]
"""A dual-control allocation alpha in [-1, 1], or ``"bow"`` for the bow planes alone."""


def plane_derivatives(vehicle: Vehicle, alpha: Allocation) -> tuple[float, float]:
    """Dimensional Z_delta, M_delta of dual control, Z_ds + alpha Z_db (Riedel 1993 eq. 2.58).

    ``alpha="bow"`` gives the bow planes alone (Z_db, M_db), with delta_b as the command.
    """
    c = vehicle.coefficients
    if alpha == BOW_PLANES_ONLY:
        check.require(
            "alpha",
            alpha,
            vehicle.planes.has_bow_planes,
            f"a number in [-1, 1]: vehicle {vehicle.name!r} has no bow planes",
        )
        return c.Z_delta_b, c.M_delta_b
    alpha = check_alpha(alpha)
    return c.Z_delta_s + alpha * c.Z_delta_b, c.M_delta_s + alpha * c.M_delta_b


@dataclass(frozen=True)
class LinearModel:
    """x_dot = A x + B delta about level flight, x = (theta, w, q, Z) in SI, delta [rad]."""

    A: FloatArray
    B: FloatArray
    speed_mps: float
    alpha: Allocation


def linear_model(vehicle: Vehicle, speed_mps: float, alpha: Allocation = 0.0) -> LinearModel:
    """Closed-form linearisation about level flight (Riedel 1993 eqs 2.59-2.68).

    Parameters
    ----------
    vehicle : Vehicle
        Any loading; the restoring term uses z_G W - z_B B (= W z_GB when W = B). Drag does not
        enter: it is quadratic in (w, q).
    speed_mps : float
        Forward speed u [m/s], >= 0.
    alpha : float or "bow"
        Bow/stern allocation of dual control, in [-1, 1] (eq. 2.58), or "bow" for bow planes only.
    """
    if not (np.isfinite(speed_mps) and speed_mps >= 0):
        raise ValueError(f"speed_mps={speed_mps!r} is invalid: must be a finite number >= 0")
    c = vehicle.coefficients
    m, xG, Iy = vehicle.mass_kg, vehicle.x_G_m, vehicle.inertia_y_kg_m2
    Z_delta, M_delta = plane_derivatives(vehicle, alpha)
    restoring = vehicle.z_G_m * vehicle.weight_N - vehicle.z_B_m * vehicle.buoyancy_N
    # Riedel (1993) eqs 2.61-2.68 (reference sheet: "Linear model").
    Dv = (m - c.Z_wdot) * (Iy - c.M_qdot) - (m * xG + c.Z_qdot) * (m * xG + c.M_wdot)
    a11 = ((Iy - c.M_qdot) * c.Z_w + (m * xG + c.Z_qdot) * c.M_w) / Dv
    a12 = ((Iy - c.M_qdot) * (m + c.Z_q) + (m * xG + c.Z_qdot) * (c.M_q - m * xG)) / Dv
    a13 = -(m * xG + c.Z_qdot) / Dv
    a21 = ((m - c.Z_wdot) * c.M_w + (m * xG + c.M_wdot) * c.Z_w) / Dv
    a22 = ((m - c.Z_wdot) * (c.M_q - m * xG) + (m * xG + c.M_wdot) * (m + c.Z_q)) / Dv
    a23 = -(m - c.Z_wdot) / Dv
    b1 = ((Iy - c.M_qdot) * Z_delta + (m * xG + c.Z_qdot) * M_delta) / Dv
    b2 = ((m - c.Z_wdot) * M_delta + (m * xG + c.M_wdot) * Z_delta) / Dv
    u = float(speed_mps)
    A = np.array(
        [
            [0.0, 0.0, 1.0, 0.0],
            [a13 * restoring, a11 * u, a12 * u, 0.0],
            [a23 * restoring, a21 * u, a22 * u, 0.0],
            [-u, 1.0, 0.0, 0.0],
        ]
    )
    B = np.array([0.0, b1 * u * u, b2 * u * u, 0.0])
    return LinearModel(A=A, B=B, speed_mps=u, alpha=alpha)


def numerical_jacobian(
    vehicle: Vehicle,
    speed_mps: float,
    state: FloatArray,
    stern_rad: float,
    bow_rad: float,
    eps: float = 1e-6,
    free_surface: FreeSurface = NO_FREE_SURFACE,
) -> tuple[FloatArray, FloatArray]:
    """Central-difference Jacobians of :func:`~subenv.dynamics.derivatives` about any point (deep
    water, or near the surface with ``free_surface``: :mod:`subenv.dynamics.free_surface`).

    Returns
    -------
    A : ndarray, shape (4, 4)
        d f / d x.
    B : ndarray, shape (4, 2)
        d f / d (delta_s, delta_b).
    """
    params = model_params(vehicle, free_surface)
    x0 = np.asarray(state, dtype=float)
    steps = eps * np.eye(4)
    f_plus = derivatives(x0 + steps, speed_mps, stern_rad, bow_rad, params)
    f_minus = derivatives(x0 - steps, speed_mps, stern_rad, bow_rad, params)
    A = ((f_plus - f_minus) / (2 * eps)).T
    planes = np.array(
        [
            [stern_rad + eps, bow_rad],
            [stern_rad - eps, bow_rad],
            [stern_rad, bow_rad + eps],
            [stern_rad, bow_rad - eps],
        ]
    )
    f = derivatives(np.broadcast_to(x0, (4, 4)), speed_mps, planes[:, 0], planes[:, 1], params)
    B = np.stack([(f[0] - f[1]) / (2 * eps), (f[2] - f[3]) / (2 * eps)], axis=1)
    return A, B
