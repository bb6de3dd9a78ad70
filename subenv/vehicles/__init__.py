"""Vehicle data: the frozen :class:`Vehicle` dataclass and its loader."""

from subenv.vehicles.loader import available_vehicles, load_vehicle, vehicle_from_dict
from subenv.vehicles.vehicle import (
    DimensionalCoefficients,
    HullOffsets,
    HydroCoefficients,
    PlaneCoefficients,
    Vehicle,
)

__all__ = [
    "DimensionalCoefficients",
    "HullOffsets",
    "HydroCoefficients",
    "PlaneCoefficients",
    "Vehicle",
    "available_vehicles",
    "load_vehicle",
    "vehicle_from_dict",
]
