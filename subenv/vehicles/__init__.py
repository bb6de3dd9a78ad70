"""Vehicle data: the frozen :class:`Vehicle` dataclass, its loader and Froude scaling."""

from subenv.vehicles.loader import available_vehicles, load_vehicle, vehicle_from_dict
from subenv.vehicles.scaling import froude_factor, froude_scaled
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
    "froude_factor",
    "froude_scaled",
    "load_vehicle",
    "vehicle_from_dict",
]
