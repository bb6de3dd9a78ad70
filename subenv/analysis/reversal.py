"""Dive-plane reversal: what level flight needs as the speed falls through critical (Riedel 1993 Ch. V)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from subenv._typing import FloatArray
from subenv.analysis.linear import plane_derivatives
from subenv.vehicles.vehicle import Vehicle

__all__ = ["LevelFlightTrim", "level_flight_trim"]


@dataclass(frozen=True)
class LevelFlightTrim:
    """Pitch and plane angle for steady level flight (constant depth) per speed (Fig. 5-2).

    Attributes
    ----------
    speeds_mps, pitch_rad, plane_rad : ndarray
        The plane angle is the dual-control command (stern planes; bow planes alpha times it).
    """

    speeds_mps: FloatArray
    pitch_rad: FloatArray
    plane_rad: FloatArray


def level_flight_trim(vehicle: Vehicle, speeds_mps: FloatArray, alpha: float = 0.0) -> LevelFlightTrim:
    """Small-angle trim for straight and level flight with a loading bias (Riedel 1993 Fig. 5-2).

    The steady heave and pitch balances (eqs 4.1, 4.2 linearised about level flight, C_D = 0) with
    q = 0 and w = u theta (no depth change) are linear in (theta, delta):

        Z_w u^2 theta + Z_d u^2 delta = -(W - B)
        (M_w u^2 - (z_G W - z_B B)) theta + M_d u^2 delta = x_G W - x_B B

    Their determinant is Z_d (z_G W - z_B B) (1 - u^2/u_cr^2): the required pitch and plane angle
    grow without bound at the critical speed and change sign below it, the stern-plane reversal.
    A neutral, balanced boat (W = B, x_G W = x_B B) needs no trim at any speed.
    """
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    c = vehicle.coefficients
    W, B = vehicle.weight_N, vehicle.buoyancy_N
    restoring = vehicle.z_G_m * W - vehicle.z_B_m * B
    u2 = np.asarray(speeds_mps, dtype=float) ** 2
    heave_bias = -(W - B)
    pitch_bias = vehicle.x_G_m * W - vehicle.x_B_m * B
    det = c.Z_w * u2 * M_d * u2 - Z_d * u2 * (c.M_w * u2 - restoring)
    with np.errstate(divide="ignore", invalid="ignore"):
        theta = (heave_bias * M_d * u2 - Z_d * u2 * pitch_bias) / det
        delta = (c.Z_w * u2 * pitch_bias - (c.M_w * u2 - restoring) * heave_bias) / det
    return LevelFlightTrim(np.asarray(speeds_mps, dtype=float), theta, delta)
