"""Critical speed and Froude number of dive-plane reversal (Riedel 1993 Ch. III)."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from subenv._typing import ArrayLike, FloatArray
from subenv.analysis.linear import Allocation, plane_derivatives
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "critical_froude",
    "critical_speed",
    "critical_speed_for_planes",
    "critical_speeds",
    "froude_number",
]


def critical_speed(vehicle: Vehicle, alpha: Allocation = 0.0) -> float:
    """Speed below which level flight under dual control loses stability [m/s].

    Riedel (1993) eq. 3.9 (exponent 1/2): u_cr^2 = z_GB Z_delta B / (M_w Z_delta - Z_w M_delta),
    written with the restoring moment z_G W - z_B B (= B z_GB when W = B). At u_cr the constant
    coefficient of the closed-loop characteristic polynomial vanishes for any gain (eq. 3.7).

    Parameters
    ----------
    vehicle : Vehicle
        Needs z_GB > 0 (a statically stable loading).
    alpha : float or "bow"
        Bow/stern allocation of dual control, in [-1, 1] (eq. 2.58), or ``"bow"`` for bow planes
        only (the limit alpha -> infinity, Fig. 5-4: Fn_cr = 2.05 for SUBOFF).

    Raises
    ------
    ValueError
        z_GB <= 0 (no critical speed: level flight has no restoring moment), alpha outside
        [-1, 1], or an allocation whose planes produce no net pitch-heave coupling.
    """
    Z_delta, M_delta = plane_derivatives(vehicle, alpha)
    return critical_speed_for_planes(vehicle, Z_delta, M_delta, label=f"alpha={alpha!r}")


def critical_speed_for_planes(
    vehicle: Vehicle, Z_delta: float, M_delta: float, label: str = "planes"
) -> float:
    """Critical speed [m/s] for any dimensional plane derivatives Z_delta, M_delta (eq. 3.9).

    :func:`critical_speed` calls this with the derivatives of an allocation alpha; Fig. 5-4's
    sweep of alpha beyond [-1, 1] calls it directly.
    """
    restoring, u2 = _speed_squared(vehicle, Z_delta, M_delta, vehicle.z_G_m, vehicle.buoyancy_N)
    if not restoring > 0:
        raise ValueError(
            f"z_GB={vehicle.z_GB_m!r} m gives restoring moment z_G W - z_B B = {restoring!r} N m; "
            "a critical speed exists only for a positive restoring moment (z_GB > 0)"
        )
    if not (math.isfinite(u2) and u2 > 0):
        raise ValueError(
            f"{label}: this plane allocation has no critical speed "
            f"(z_GB Z_delta B / (M_w Z_delta - Z_w M_delta) = {u2!r} m^2/s^2 is not positive)"
        )
    return math.sqrt(u2)  # Riedel (1993) eq. 3.9


def critical_speeds(vehicle: Vehicle, alpha: Allocation, loading: Mapping[str, ArrayLike]) -> FloatArray:
    """:func:`critical_speed` of many loadings of ``vehicle`` at once, nan for those without one.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle loaded.
    alpha : float or "bow"
        As for :func:`critical_speed`.
    loading : mapping
        Its loadings' ``z_G_m`` and ``buoyancy_N`` (:meth:`Vehicle.loading_fields
        <subenv.vehicles.Vehicle.loading_fields>`; a field not given is the vehicle's), floats or
        arrays of one loading per element.

    Returns
    -------
    ndarray
        Element for element, what :func:`critical_speed` gives for the variant with that loading, bit for
        bit, or nan where it raises for a loading without a critical speed.
    """
    Z_delta, M_delta = plane_derivatives(vehicle, alpha)
    restoring, u2 = _speed_squared(
        vehicle,
        Z_delta,
        M_delta,
        loading.get("z_G_m", vehicle.z_G_m),
        loading.get("buoyancy_N", vehicle.buoyancy_N),
    )
    u2 = np.where((np.asarray(restoring) > 0) & np.isfinite(u2) & (u2 > 0), u2, math.nan)
    return np.sqrt(u2)  # Riedel (1993) eq. 3.9 (correctly rounded, as math.sqrt)


def _speed_squared(
    vehicle: Vehicle, Z_delta: float, M_delta: float, z_G_m: ArrayLike, buoyancy_N: ArrayLike
) -> tuple[ArrayLike, ArrayLike]:
    """The restoring moment z_G W - z_B B [N m] and u_cr^2 of eq. 3.9 [m^2/s^2] for G at depth
    ``z_G_m`` and buoyancy ``buoyancy_N`` (floats or arrays)."""
    restoring = z_G_m * vehicle.weight_N - vehicle.z_B_m * buoyancy_N
    c = vehicle.coefficients
    coupling = c.M_w * Z_delta - c.Z_w * M_delta
    u2 = restoring * Z_delta / coupling if coupling != 0 else math.inf
    return restoring, u2


def froude_number(vehicle: Vehicle, speed_mps: float) -> float:
    """Fn = u / sqrt(g z_GB) (Riedel 1993 eq. 4.25 uses lambda = Fn^2)."""
    if not vehicle.z_GB_m > 0:
        raise ValueError(f"z_GB={vehicle.z_GB_m!r} m: the Froude number needs z_GB > 0")
    return speed_mps / math.sqrt(vehicle.gravity_m_s2 * vehicle.z_GB_m)


def critical_froude(vehicle: Vehicle, alpha: Allocation = 0.0) -> float:
    """Froude number at the critical speed, u_cr / sqrt(g z_GB)."""
    return froude_number(vehicle, critical_speed(vehicle, alpha))
