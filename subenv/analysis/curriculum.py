"""Curriculum helpers: speed stages placed relative to the critical speed."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from subenv.analysis.critical import critical_speed, froude_number
from subenv.vehicles.vehicle import Vehicle

__all__ = ["DEFAULT_STAGES", "SpeedStage", "speed_curriculum"]

DEFAULT_STAGES: Final = (
    ("cruise", 1.6, 2.6),
    ("approach", 1.15, 1.6),
    ("near_critical", 0.85, 1.15),
    ("below_critical", 0.3, 0.85),
)
"""(name, low, high) in units of the critical speed, easy (fast) to hard (at and below u_cr)."""


@dataclass(frozen=True)
class SpeedStage:
    """One curriculum stage: a speed interval, in m/s and relative to the critical speed.

    ``ratio_low``/``ratio_high`` are u / u_cr (= Fn / Fn_cr); feed ``speed_mps`` to
    ``reset(options={"speed": ...})`` or a scenario's ``speed_mps``, or the ratios to a scenario's
    ``speed_ratio``.
    """

    name: str
    ratio_low: float
    ratio_high: float
    speed_low_mps: float
    speed_high_mps: float
    froude_low: float
    froude_high: float

    @property
    def speed_mps(self) -> tuple[float, float]:
        """The stage's speed interval (low, high) [m/s]."""
        return (self.speed_low_mps, self.speed_high_mps)


def speed_curriculum(
    vehicle: Vehicle,
    alpha: float = 0.0,
    stages: Sequence[tuple[str, float, float]] = DEFAULT_STAGES,
) -> list[SpeedStage]:
    """Speed stages for ``vehicle`` from stage definitions in units of its critical speed.

    Raises
    ------
    ValueError
        A stage with low > high or a non-positive ratio; a vehicle without a critical speed.
    """
    ucr = critical_speed(vehicle, alpha)
    out = []
    for name, low, high in stages:
        if not (math.isfinite(low) and math.isfinite(high) and 0 < low <= high):
            raise ValueError(f"stage {name!r}: ({low!r}, {high!r}) is invalid: must satisfy 0 < low <= high")
        out.append(
            SpeedStage(
                name,
                low,
                high,
                low * ucr,
                high * ucr,
                froude_number(vehicle, low * ucr),
                froude_number(vehicle, high * ucr),
            )
        )
    return out
