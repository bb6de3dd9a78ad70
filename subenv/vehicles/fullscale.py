"""The full-scale SUBOFF-shaped vehicle file, made from the model by Froude scaling.

``subenv/vehicles/data/suboff_fullscale.toml`` is written by this module, never by hand::

    python -m subenv.vehicles.fullscale          # rewrite the file
    python -m subenv.vehicles.fullscale --check  # exit 1 if the shipped file is not what it writes

and ``tests/vehicles/test_scaling.py`` checks that the shipped file is exactly its output.
"""

from __future__ import annotations

import dataclasses
import sys
from typing import Final

from subenv.vehicles.loader import load_vehicle, vehicle_to_toml, write_shipped_file
from subenv.vehicles.scaling import froude_scaled
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "SUBOFF_FULLSCALE_LENGTH_RATIO",
    "SUBOFF_FULLSCALE_NAME",
    "suboff_fullscale",
    "suboff_fullscale_toml",
]

SUBOFF_FULLSCALE_LENGTH_RATIO: Final = 24.0
"""Full-scale length over model length: a choice. SUBOFF is a generic hull, not the model of one boat,
and the sources used here give no full-scale length; 1:24 makes the 4.26 m model a 102.3 m boat, the
size of a large modern submarine."""

SUBOFF_FULLSCALE_NAME: Final = "suboff_fullscale"

_HEADER = """\
A SUBOFF-shaped submarine at full scale: the DARPA SUBOFF model of suboff.toml, Froude-scaled by
the length ratio {ratio:g} (L = {length:.2f} m).

GENERATED FILE, do not edit: written by `python -m subenv.vehicles.fullscale`, which loads
suboff.toml and applies subenv.vehicles.froude_scaled (tests/vehicles/test_scaling.py checks that
this file is exactly its output). Edit suboff.toml or the scaling, then regenerate.

Scaling (Riedel 1993 Ch. VI recommends Froude scaling to full-scale vessels): lengths x {ratio:g},
weight and buoyancy x {ratio:g}^3, I_y x {ratio:g}^5; the same water and gravity; the non-dimensional
coefficients, plane limit and C_D unchanged. Speeds of equal Froude number are sqrt({ratio:g}) =
{speed:.4f} times the model's, times too. The Reynolds number is not kept ({ratio:g}^1.5 = {reynolds:.0f}
times the model's at equal Froude number): the coefficients are taken as Reynolds-independent, as the
thesis does. The ratio is a choice: SUBOFF is a generic hull, and its sources give no full-scale length.

Sources of the model's numbers: Riedel (1993), NPS thesis, Appendix A (THESIS1.M) and Appendix B;
see suboff.toml. Units here are SI."""


def suboff_fullscale() -> Vehicle:
    """The SUBOFF model Froude-scaled to full size (:data:`SUBOFF_FULLSCALE_LENGTH_RATIO`)."""
    ratio = SUBOFF_FULLSCALE_LENGTH_RATIO
    vehicle = froude_scaled(load_vehicle("suboff"), ratio, name=SUBOFF_FULLSCALE_NAME)
    return dataclasses.replace(
        vehicle,
        description=f"DARPA SUBOFF shape at full scale: the model Froude-scaled by {ratio:g} "
        f"(L = {vehicle.length_m:.2f} m)",
        source="Riedel (1993), NPS thesis, Appendices A and B (the model), Froude-scaled by "
        "subenv.vehicles.froude_scaled (Ch. VI)",
    )


def suboff_fullscale_toml() -> str:
    """The text of ``suboff_fullscale.toml``."""
    ratio = SUBOFF_FULLSCALE_LENGTH_RATIO
    vehicle = suboff_fullscale()
    header = _HEADER.format(ratio=ratio, length=vehicle.length_m, speed=ratio**0.5, reynolds=ratio**1.5)
    return vehicle_to_toml(vehicle, header)


def main(argv: list[str] | None = None) -> int:
    return write_shipped_file(
        SUBOFF_FULLSCALE_NAME, suboff_fullscale_toml(), "subenv.vehicles.fullscale", argv
    )


if __name__ == "__main__":
    sys.exit(main())
