"""The REMUS 100 AUV: a second, different vehicle, made from its own published data (Prestero 2001).

``subenv/vehicles/data/remus100.toml`` is written by this module, never by hand::

    python -m subenv.vehicles.remus          # rewrite the file
    python -m subenv.vehicles.remus --check  # exit 1 if the shipped file is not what it writes

and ``tests/vehicles/test_remus.py`` checks that the shipped file is exactly its output.

Source: T. Prestero, *Verification of a Six-Degree of Freedom Simulation Model for the REMUS Autonomous
Underwater Vehicle*, MS thesis, MIT/WHOI Joint Program, 2001: the hull profile (Myring's equations and their
parameters), the mass properties and the combined vertical-plane coefficients. :data:`PRESTERO_2001` holds
them as he tabulates them, dimensional, about his body origin at the centre of buoyancy; they were read from
two independent public transcriptions of his tables, which agree (the thesis PDF could not be fetched from
the machine this was built on).

How they map onto this package's model (Riedel 1993 eqs 2.38-2.43, the same vertical-plane form as
Prestero's): the origin is his, the centre of buoyancy (so x_B = x_G = 0); his ``Z_uw u w``,
``(Z_uq + m) u q``, ``M_uw u w``, ``(M_uq - m x_G) u q``, ``Z_uuds u^2 delta_s``, ``M_uuds u^2 delta_s`` are
the model's Z_w, Z_q, M_w, M_q and stern-plane derivatives, made non-dimensional here with rho/2 L^n; the
added masses likewise.
His cross-flow drag terms (Z_ww, Z_qq, M_ww, M_qq) are not coefficients in this model: it integrates the
quadratic cross-flow drag over the hull (:class:`~subenv.vehicles.HullOffsets`), here his Myring hull with his
cross-flow drag coefficient c_dc = 1.1. That integral plus his fins' term gives Z_ww = -132.1 kg/m against
his -131 (:func:`crossflow_check`), an independent check of the hull. It gives M_qq = -7.4 kg m^2 where he
tabulates -188, which no quadratic cross-flow integral over this hull can give; the model's value is the
integral's. The fins' own cross-flow drag (3% of Z_ww) is not in the model.

The REMUS 100 has no bow planes: it pitches with its stern planes alone (``Z_delta_b = M_delta_b = 0``).
It is shipped neutrally buoyant, like ``suboff``: the scenarios set each episode's excess buoyancy; Prestero
measured B - W = 7 N (``remus100().variant(excess_buoyancy_N=...)``).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Final

import numpy as np

from subenv.vehicles.loader import vehicle_to_toml, write_shipped_file
from subenv.vehicles.vehicle import HullOffsets, HydroCoefficients, PlaneCoefficients, Vehicle

__all__ = [
    "PRESTERO_2001",
    "REMUS100_NAME",
    "PresteroRemus100",
    "crossflow_check",
    "myring_radius",
    "remus100",
    "remus100_toml",
]

REMUS100_NAME: Final = "remus100"


@dataclass(frozen=True)
class PresteroRemus100:
    """The REMUS 100's published data, as Prestero (2001) tabulates them.

    SI units, about the centre of buoyancy.
    """

    # Hull profile: Myring's equations and their parameters [m, -, rad].
    nose_length_m: float  # a
    nose_offset_m: float  # a_offset
    midbody_length_m: float  # b
    tail_length_m: float  # c
    tail_offset_m: float  # c_offset
    nose_exponent: float  # n
    tail_angle_rad: float  # theta, the included tail angle
    diameter_m: float  # d
    # Mass properties and the water.
    weight_N: float  # W
    buoyancy_N: float  # B, as measured (light)
    inertia_y_kg_m2: float  # I_yy
    z_G_m: float  # z_g, below the centre of buoyancy
    x_B_from_nose_m: float  # the centre of buoyancy (the body origin) behind the nose
    water_density_kg_m3: float  # rho
    gravity_m_s2: float  # g
    # Combined vertical-plane coefficients.
    Z_wdot: float  # [kg]
    Z_qdot: float  # [kg m]
    M_wdot: float  # [kg m]
    M_qdot: float  # [kg m^2]
    Z_uw: float  # [kg/m]   body lift and fin lift
    Z_uq: float  # [kg]     added-mass cross term and fin lift
    M_uw: float  # [kg]     body and fin lift, Munk moment
    M_uq: float  # [kg m]   added-mass cross term and fin lift
    Z_uuds: float  # [kg/m/rad] stern-plane lift
    M_uuds: float  # [kg/rad]   stern-plane moment
    # Cross-flow drag: the coefficients of the cylinder and the fins, the fins, and his Z_ww (for the check).
    crossflow_drag: float  # c_dc (Hoerner's cylinder)
    fin_crossflow_drag: float  # c_df
    fin_area_m2: float  # S_fin, one fin's planform
    fin_x_m: float  # x_fin, the fins' position (behind the centre of buoyancy: negative)
    Z_ww: float  # [kg/m]

    @property
    def forward_length_m(self) -> float:
        """l_f = a + b - a_offset: nose to the start of the tail [m]."""
        return self.nose_length_m + self.midbody_length_m - self.nose_offset_m

    @property
    def length_m(self) -> float:
        """L = l_f + c - c_offset: the hull's length [m] (his 1.33 m, rounded)."""
        return self.forward_length_m + self.tail_length_m - self.tail_offset_m


PRESTERO_2001: Final = PresteroRemus100(
    nose_length_m=0.191,
    nose_offset_m=0.0165,
    midbody_length_m=0.654,
    tail_length_m=0.541,
    tail_offset_m=0.0368,
    nose_exponent=2.0,
    tail_angle_rad=0.436,
    diameter_m=0.191,
    weight_N=299.0,
    buoyancy_N=306.0,
    inertia_y_kg_m2=3.45,
    z_G_m=0.0196,
    x_B_from_nose_m=0.611,
    water_density_kg_m3=1030.0,
    gravity_m_s2=9.81,
    Z_wdot=-35.5,
    Z_qdot=-1.93,
    M_wdot=-1.93,
    M_qdot=-4.88,
    Z_uw=-28.6,
    Z_uq=-5.22,
    M_uw=24.0,
    M_uq=-2.0,
    Z_uuds=-9.64,
    M_uuds=-6.15,
    crossflow_drag=1.1,
    fin_crossflow_drag=0.56,
    fin_area_m2=6.65e-3,
    fin_x_m=-0.638,
    Z_ww=-131.0,
)
"""Prestero (2001)'s REMUS 100, as he tabulates it."""

PLANE_LIMIT_RAD: Final = math.radians(20.0)
"""The stern planes' travel, +-20 deg.

Prestero gives none; this is the limit of the REMUS 100 model in Fossen's Marine Systems Simulator
(``VESSELS/remus100.m``).
"""

_NOSE_POINTS: Final = 9
_TAIL_POINTS: Final = 15
"""Stations on the curved nose and tail (the midbody is straight): with the blunt nose's end these give a
piecewise-linear hull whose planform area is within 0.3% of the curve's."""


def myring_radius(data: PresteroRemus100, s_m: np.ndarray) -> np.ndarray:
    """The hull radius [m] at ``s_m`` behind the nose.

    Myring's nose, midbody and tail, as Prestero (2001) writes them, with the nose and tail truncated by
    their offsets (a blunt nose; a tail cone ending at the propeller).
    """
    s = np.asarray(s_m, dtype=float)
    a, a0, c, d, n = (
        data.nose_length_m,
        data.nose_offset_m,
        data.tail_length_m,
        data.diameter_m,
        data.nose_exponent,
    )
    lf, tan = data.forward_length_m, math.tan(data.tail_angle_rad)
    nose = 0.5 * d * np.clip(1.0 - ((s + a0 - a) / a) ** 2, 0.0, None) ** (1.0 / n)
    t = s - lf
    tail = 0.5 * d - (3.0 * d / (2.0 * c * c) - tan / c) * t * t + (d / c**3 - tan / (c * c)) * t**3
    return np.where(s < a - a0, nose, np.where(s <= lf, 0.5 * d, tail))


def _hull(data: PresteroRemus100) -> HullOffsets:
    nose_end, lf, length = data.nose_length_m - data.nose_offset_m, data.forward_length_m, data.length_m
    # Denser where the curves bend most: toward the nose's tip, evenly along the tail.
    nose = nose_end * np.sin(0.5 * np.pi * np.linspace(0.0, 1.0, _NOSE_POINTS))
    tail = np.linspace(lf, length, _TAIL_POINTS)
    s = np.concatenate([nose, tail])
    return HullOffsets(
        x_m=tuple(float(v) for v in data.x_B_from_nose_m - s),
        breadth_m=tuple(float(v) for v in 2.0 * myring_radius(data, s)),
    )


def remus100(data: PresteroRemus100 = PRESTERO_2001) -> Vehicle:
    """The REMUS 100 as a :class:`Vehicle` (neutrally buoyant; see the module's text)."""
    L, half_rho = data.length_m, 0.5 * data.water_density_kg_m3
    nd1, nd2, nd3, nd4 = (half_rho * L**k for k in (2, 3, 4, 5))  # rho/2 L^n, as Vehicle.coefficients
    return Vehicle(
        name=REMUS100_NAME,
        description=f"REMUS 100 AUV (Prestero 2001), stern planes only, L = {L:.4f} m, neutrally buoyant",
        source="T. Prestero, Verification of a Six-Degree of Freedom Simulation Model for the REMUS "
        "Autonomous Underwater Vehicle, MS thesis, MIT/WHOI, 2001 (subenv.vehicles.remus)",
        length_m=L,
        weight_N=data.weight_N,
        buoyancy_N=data.weight_N,
        inertia_y_kg_m2=data.inertia_y_kg_m2,
        x_G_m=0.0,
        z_G_m=data.z_G_m,
        x_B_m=0.0,
        z_B_m=0.0,
        water_density_kg_m3=data.water_density_kg_m3,
        gravity_m_s2=data.gravity_m_s2,
        hydro=HydroCoefficients(
            Z_wdot=data.Z_wdot / nd2,
            Z_qdot=data.Z_qdot / nd3,
            Z_w=data.Z_uw / nd1,
            Z_q=data.Z_uq / nd2,
            M_wdot=data.M_wdot / nd3,
            M_qdot=data.M_qdot / nd4,
            M_w=data.M_uw / nd2,
            M_q=data.M_uq / nd3,
        ),
        planes=PlaneCoefficients(
            Z_delta_s=data.Z_uuds / nd1, M_delta_s=data.M_uuds / nd2, limit_rad=PLANE_LIMIT_RAD
        ),
        hull=_hull(data),
        crossflow_drag=data.crossflow_drag,
    )


def crossflow_check(data: PresteroRemus100 = PRESTERO_2001) -> tuple[float, float]:
    """(Z_ww from the shipped hull's cross-flow integral plus the fins' term, Prestero's Z_ww) [kg/m]:
    -(rho/2) c_dc int 2R dx - 2 (rho/2) S_fin c_df, his formula, over the hull this module ships."""
    hull = remus100(data).hull
    half_rho = 0.5 * data.water_density_kg_m3
    return (
        -half_rho * data.crossflow_drag * hull.area_m2
        - 2.0 * half_rho * data.fin_area_m2 * data.fin_crossflow_drag,
        data.Z_ww,
    )


_HEADER = """\
The REMUS 100 AUV: a second vehicle, from its own published data.

GENERATED FILE, do not edit: written by `python -m subenv.vehicles.remus` from the numbers in
subenv/vehicles/remus.py (PRESTERO_2001), which says how they map onto this model and what was checked
(tests/vehicles/test_remus.py checks that this file is exactly its output).

Source: T. Prestero, "Verification of a Six-Degree of Freedom Simulation Model for the REMUS Autonomous
Underwater Vehicle", MS thesis, MIT/WHOI, 2001: the Myring hull profile, the mass properties and the
vertical-plane coefficients, dimensional about the centre of buoyancy (the origin here). They are made
non-dimensional with rho/2 L^n, L = {length:.4f} m (l_f + c - c_offset; his 1.33 m), rho = {rho:g} kg/m^3.
The hull's stations sample his profile (origin at the centre of buoyancy, {x_cb:g} m behind the nose;
x = (10 - station) L / 20, so the nose is at station {nose_station:.4f}). Cross-flow drag: his c_dc = {cdc:g}
over the hull. No bow planes. Stern-plane travel +-20 deg (Fossen's MSS remus100.m; Prestero gives none).
Neutrally buoyant: he measured B - W = {excess:g} N; the scenarios set each episode's loading. SI units."""


def remus100_toml() -> str:
    """The text of ``remus100.toml``."""
    data, vehicle = PRESTERO_2001, remus100()
    header = _HEADER.format(
        length=vehicle.length_m,
        rho=data.water_density_kg_m3,
        x_cb=data.x_B_from_nose_m,
        nose_station=10.0 - 20.0 * vehicle.hull.x_m[0] / vehicle.length_m,
        cdc=data.crossflow_drag,
        excess=data.buoyancy_N - data.weight_N,
    )
    return vehicle_to_toml(vehicle, header)


def main(argv: list[str] | None = None) -> int:
    return write_shipped_file(REMUS100_NAME, remus100_toml(), "subenv.vehicles.remus", argv)


if __name__ == "__main__":
    sys.exit(main())
