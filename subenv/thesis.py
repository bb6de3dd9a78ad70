"""The thesis's design point: the speed its controller is designed at.

It lives here, below both :mod:`subenv.scenarios` (the default and nominal speed) and
:mod:`subenv.analysis` (the thesis gain), so that each imports the one definition.
"""

from __future__ import annotations

from typing import Final

from subenv.units import fps_to_mps

__all__ = ["THESIS_DESIGN_SPEED_MPS"]

THESIS_DESIGN_SPEED_MPS: Final = fps_to_mps(5.0)
"""The thesis controller's design speed, 5 fps = 1.524 m/s exactly (Riedel 1993 Ch. II.B)."""
