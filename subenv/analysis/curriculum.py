"""Curriculum helpers: how hard an episode is, from the physics.

- :func:`episode_difficulty`: an episode's distance to the critical speed and the trim margin its loading
  leaves (:class:`EpisodeDifficulty`), what ``subenv_agents.difficulty`` samples training episodes by;
- :func:`speed_curriculum`: speed stages placed relative to the critical speed (the Stable-Baselines3
  agents' ``--curriculum``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from subenv import _validation as check
from subenv.analysis.critical import critical_speed, froude_number
from subenv.analysis.winnable import depth_holding_trim
from subenv.dynamics.free_surface import NO_FREE_SURFACE, FreeSurface
from subenv.dynamics.waves import SeaState
from subenv.vehicles.vehicle import Vehicle

__all__ = ["DEFAULT_STAGES", "EpisodeDifficulty", "SpeedStage", "episode_difficulty", "speed_curriculum"]

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


@dataclass(frozen=True)
class EpisodeDifficulty:
    """How hard an episode is, from what was drawn for it (never from how it was flown).

    Attributes
    ----------
    speed_ratio : float
        u / u_cr at the speed the episode holds at its end (Riedel 1993 eq. 3.9's u_cr of its loading and
        allocation): below 1 the planes act reversed, near 1 they hardly move depth at all (Ch. III).
    trim_margin_rad : float
        The plane limit minus the largest plane angle of the depth-holding trim that needs the least
        (:func:`subenv.analysis.depth_holding_trim`, every plane pair free): how much plane is left
        over once the loading (a ballast offset, excess buoyancy, the surface's suction) is trimmed
        out. Negative: no trim within the limits.
    plane_limit_rad : float
        The vehicle's plane limit.
    """

    speed_ratio: float
    trim_margin_rad: float
    plane_limit_rad: float

    @property
    def winnable(self) -> bool:
        """Whether a depth-holding trim exists within the plane limits (:func:`subenv.analysis.winnable`)."""
        return self.trim_margin_rad >= 0.0

    @property
    def critical_distance(self) -> float:
        """|u / u_cr - 1|: how far from the speed at which the planes lose depth control."""
        return abs(self.speed_ratio - 1.0)

    @property
    def trim_load(self) -> float:
        """The fraction of the plane limit the trim needs: 0 for a neutral loading, 1 at the limit (above
        1: beyond it)."""
        return 1.0 - self.trim_margin_rad / self.plane_limit_rad


def episode_difficulty(
    vehicle: Vehicle,
    speed_mps: float,
    critical_speed_mps: float,
    max_pitch_rad: float,
    depth_m: float = 0.0,
    free_surface: FreeSurface = NO_FREE_SURFACE,
    sea_state: SeaState | None = None,
) -> EpisodeDifficulty:
    """The :class:`EpisodeDifficulty` of an episode of loading ``vehicle`` that is to hold depth at
    ``speed_mps`` (its final speed), ``critical_speed_mps`` being its u_cr; near the surface at ``depth_m``
    with ``free_surface`` and ``sea_state`` (their suction is part of the trim), as
    :func:`subenv.analysis.depth_holding_trim` takes them."""
    check.require(
        "critical_speed_mps",
        critical_speed_mps,
        check.is_finite(critical_speed_mps) and critical_speed_mps > 0,
        "a finite number > 0",
    )
    trim = depth_holding_trim(vehicle, speed_mps, max_pitch_rad, depth_m, free_surface, sea_state)
    return EpisodeDifficulty(
        speed_ratio=float(speed_mps) / float(critical_speed_mps),
        trim_margin_rad=trim.plane_margin_rad,
        plane_limit_rad=vehicle.planes.limit_rad,
    )
