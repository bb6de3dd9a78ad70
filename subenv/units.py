"""Unit conversions between the thesis's US customary units and SI.

Riedel (1993) works in ft, slug, lbf and s. The package's public API is SI (m, kg, N, s, rad);
vehicle files may be written in either system and are converted once, in the loader.
"""

from __future__ import annotations

from typing import Final, TypeVar

from subenv._typing import FloatArray

_Speed = TypeVar("_Speed", float, FloatArray)

FOOT_M: Final = 0.3048
"""One international foot in metres (exact)."""

POUND_FORCE_N: Final = 4.4482216152605
"""One pound-force in newtons (exact, with standard gravity)."""

SLUG_KG: Final = POUND_FORCE_N / FOOT_M
"""One slug (lbf s^2 / ft) in kilograms."""

FPS_MPS: Final = FOOT_M
"""One foot per second in metres per second."""

SLUG_FT2_KG_M2: Final = SLUG_KG * FOOT_M**2
"""One slug ft^2 (moment of inertia) in kg m^2."""

SLUG_PER_FT3_KG_PER_M3: Final = SLUG_KG / FOOT_M**3
"""One slug/ft^3 (density) in kg/m^3."""


def fps_to_mps(speed_fps: _Speed) -> _Speed:
    """Convert a speed from ft/s to m/s."""
    return speed_fps * FPS_MPS


def mps_to_fps(speed_mps: _Speed) -> _Speed:
    """Convert a speed from m/s to ft/s."""
    return speed_mps / FPS_MPS
