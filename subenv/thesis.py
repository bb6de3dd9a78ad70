"""The thesis's design point: the speed its controller is designed at, and the vehicle it is for.

It lives here, below both :mod:`subenv.scenarios` (the default and nominal speed) and
:mod:`subenv.analysis` (the thesis gain), so that each imports the one definition.
"""

from __future__ import annotations

from typing import Final

from subenv.units import fps_to_mps
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.scaling import froude_factor
from subenv.vehicles.vehicle import Vehicle

__all__ = ["REFERENCE_LENGTH_M", "THESIS_DESIGN_SPEED_MPS", "froude_speed_factor", "reference_length_ratio"]

THESIS_DESIGN_SPEED_MPS: Final = fps_to_mps(5.0)
"""The thesis controller's design speed, 5 fps = 1.524 m/s exactly (Riedel 1993 Ch. II.B)."""

REFERENCE_LENGTH_M: Final = load_vehicle("suboff").length_m
"""The length of the thesis's vehicle, SUBOFF [m]. The thesis's design and the shipped scenarios are
SUBOFF's; on a vehicle of another length they are Froude-scaled (:func:`froude_speed_factor`)."""


def reference_length_ratio(vehicle: Vehicle) -> float:
    """Lambda = L / L_SUBOFF: lengths chosen for SUBOFF scale by it on ``vehicle`` (exactly 1.0 on SUBOFF)."""
    return vehicle.length_m / REFERENCE_LENGTH_M


def froude_speed_factor(vehicle: Vehicle) -> float:
    """sqrt(L / L_SUBOFF): speeds and times chosen for SUBOFF scale by it on ``vehicle``, rates by its
    inverse (Froude similarity, :func:`subenv.vehicles.froude_factor`); exactly 1.0 on SUBOFF."""
    return froude_factor("speed", reference_length_ratio(vehicle))
