"""Can depth be held at all? The depth-holding trims of a loading with every plane pair free.

A controller can only hold depth where the boat has a steady state that holds it: q = 0, no depth rate
(w = u tan(theta), Riedel 1993 eq. 4.4), and the heave and pitch balances (eqs 2.38-2.39 with the
accelerations zero) met by plane angles within their limit. With the stern and bow planes driven
independently every bow/stern allocation alpha (eq. 2.58) is one line through the plane square, so a trim
for some allocation is a trim here; where none exists within the limits (a large ballast offset or excess
buoyancy at low speed, Ch. IV-V) no controller can win the episode, and its loss says nothing about the
controller.

At each pitch the balances are linear in the plane angles (the planes enter as u^2 (Z_ds delta_s +
Z_db delta_b) and u^2 (M_ds delta_s + M_db delta_b)): two equations, two unknowns, solved exactly. The
residual forces come from the one right-hand side, :func:`subenv.dynamics.derivatives` (with the hull's
cross-flow drag and the loading's W - B, x_GB, z_GB), so this agrees with the environments by construction.

A vehicle without bow planes (the REMUS 100) has one plane for the two balances: its trims are the pitches at
which the stern angle that zeroes the pitch acceleration zeroes the heave acceleration too (below the critical
speed more than one: the pitchfork's branches), the one that needs the least plane angle counts.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Final

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from subenv import _validation as check
from subenv.analysis.free_surface import sea_mean_suction
from subenv.dynamics.free_surface import NO_FREE_SURFACE, FreeSurface
from subenv.dynamics.model import derivatives, model_params
from subenv.dynamics.waves import SeaState
from subenv.vehicles.vehicle import Vehicle

__all__ = ["DepthHoldingTrim", "depth_holding_trim", "winnable"]

_Surface = tuple[float, FreeSurface, "SeaState | None"]  # depth [m], the suction, a sea

_PITCH_POINTS: Final = 2001
"""Pitch grid over (-max_pitch, max_pitch) on which the least plane angle is looked for, then refined: the
plane needed is smooth in pitch, so a grid of 0.03 deg (for 0.6 rad) brackets its minimum."""


@dataclass(frozen=True)
class DepthHoldingTrim:
    """The depth-holding steady state that needs the least plane angle, at one speed (SI units).

    Attributes
    ----------
    speed_mps : float
    exists : bool
        Whether it is within the plane limit: ``plane_margin_rad >= 0``.
    pitch_rad, heave_mps : float
        Its pitch and heave velocity (w = u tan(theta); q = 0).
    stern_rad, bow_rad : float
        The plane angles that hold it (possibly beyond the limit when it does not exist).
    plane_margin_rad : float
        Plane limit minus max(|stern|, |bow|): how far inside the limits (negative: outside).
    """

    speed_mps: float
    exists: bool
    pitch_rad: float
    heave_mps: float
    stern_rad: float
    bow_rad: float
    plane_margin_rad: float


def _planes(vehicle: Vehicle, speed_mps: float, pitch_rad: np.ndarray, surface: _Surface) -> np.ndarray:
    """(stern, bow) that zero w_dot and q_dot at (theta, u tan(theta), 0, depth): shape (..., 2)."""
    depth, free_surface, sea_state = surface
    params = model_params(vehicle, free_surface)
    force, moment = sea_mean_suction(vehicle, sea_state, depth)  # (the waves' first order averages out)
    theta = np.asarray(pitch_rad, dtype=float)
    state = np.stack(
        [theta, speed_mps * np.tan(theta), np.zeros_like(theta), np.full_like(theta, depth)], axis=-1
    )
    # The balances are affine in the planes: the accelerations at zero planes and per unit of each.
    f0, fs, fb = (
        derivatives(state, speed_mps, s, b, params, force, moment)[..., 1:3]
        for s, b in ((0, 0), (1, 0), (0, 1))
    )
    if not vehicle.planes.has_bow_planes:
        # One plane, two balances: the stern angle that best meets both (least squares), which meets both
        # exactly only at the pitches where _stern_only_mismatch is zero.
        gs = fs - f0
        stern = -np.sum(f0 * gs, axis=-1) / np.sum(gs * gs, axis=-1)
        return np.stack([stern, np.zeros_like(stern)], axis=-1)
    G = np.stack([fs - f0, fb - f0], axis=-1)  # (..., 2, 2): d(w_dot, q_dot) / d(stern, bow)
    return np.linalg.solve(G, -f0[..., None])[..., 0]


def _stern_only_mismatch(
    vehicle: Vehicle, speed_mps: float, pitch_rad: np.ndarray, surface: _Surface
) -> np.ndarray:
    """Without bow planes: the heave acceleration left at the stern angle that zeroes the pitch acceleration,
    at (theta, u tan(theta), 0, depth). A trim exists at the pitches where it is zero."""
    depth, free_surface, sea_state = surface
    params = model_params(vehicle, free_surface)
    force, moment = sea_mean_suction(vehicle, sea_state, depth)
    theta = np.asarray(pitch_rad, dtype=float)
    state = np.stack(
        [theta, speed_mps * np.tan(theta), np.zeros_like(theta), np.full_like(theta, depth)], axis=-1
    )
    f0, fs = (derivatives(state, speed_mps, s, 0.0, params, force, moment)[..., 1:3] for s in (0.0, 1.0))
    gs = fs - f0
    # (w_dot, q_dot) = f0 + stern gs is affine in the stern angle: zero q_dot, and w_dot is what is left.
    return f0[..., 0] - gs[..., 0] * f0[..., 1] / gs[..., 1]


def depth_holding_trim(
    vehicle: Vehicle,
    speed_mps: float,
    max_pitch_rad: float,
    depth_m: float = 0.0,
    free_surface: FreeSurface = NO_FREE_SURFACE,
    sea_state: SeaState | None = None,
) -> DepthHoldingTrim:
    """The depth-holding trim of ``vehicle`` (its loading) at ``speed_mps`` that needs the least plane angle,
    with every plane pair free (the stern planes alone on a vehicle without bow planes) and the pitch inside
    ``max_pitch_rad``: in deep water, or at ``depth_m`` below the free surface (its suction,
    :mod:`subenv.dynamics.free_surface`, and a sea's mean suction).

    Parameters
    ----------
    vehicle : Vehicle
        The loading (W - B, x_GB, z_GB, C_D): an episode's ``env.unwrapped.vehicle``.
    speed_mps : float
        Forward speed [m/s], > 0.
    max_pitch_rad : float
        Pitch limit [rad] in (0, pi/2): the environment's ``max_pitch_rad`` (a trim beyond it ends the
        episode).
    depth_m : float
        Depth [m] of the trim; it matters only with ``free_surface`` or ``sea_state``.
    free_surface : FreeSurface
        The surface's suction (default: deep water).
    sea_state : SeaState, optional
        A sea whose mean suction is added.
    """
    check.require(
        "speed_mps",
        speed_mps,
        check.is_number(speed_mps) and math.isfinite(speed_mps) and speed_mps > 0,
        "a finite number > 0",
    )
    check.require(
        "max_pitch_rad",
        max_pitch_rad,
        check.is_number(max_pitch_rad) and 0 < max_pitch_rad < math.pi / 2,
        "a number in (0, pi/2)",
    )
    u, limit = float(speed_mps), vehicle.planes.limit_rad
    grid = np.linspace(-max_pitch_rad, max_pitch_rad, _PITCH_POINTS)[1:-1]

    surface = (float(depth_m), free_surface, sea_state)
    if not vehicle.planes.has_bow_planes:
        return _stern_only_trim(vehicle, u, limit, grid, surface)

    def need(theta: float | np.ndarray) -> np.ndarray:
        return np.max(np.abs(_planes(vehicle, u, np.asarray(theta), surface)), axis=-1)

    needs = need(grid)
    i = int(np.argmin(needs))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    best = minimize_scalar(
        lambda t: float(need(t)), bounds=(lo, hi), method="bounded", options={"xatol": 1e-12}
    )
    theta = float(best.x) if best.fun <= needs[i] else float(grid[i])
    stern, bow = (float(v) for v in _planes(vehicle, u, np.asarray(theta), surface))
    margin = limit - max(abs(stern), abs(bow))
    return DepthHoldingTrim(u, margin >= 0, theta, u * math.tan(theta), stern, bow, margin)


def _stern_only_trim(
    vehicle: Vehicle, u: float, limit: float, grid: np.ndarray, surface: _Surface
) -> DepthHoldingTrim:
    """:func:`depth_holding_trim` for a vehicle without bow planes: the stern planes alone must meet both
    balances, so the trims are the roots in pitch of :func:`_stern_only_mismatch` (more than one below the
    critical speed, the pitchfork's branches); the one that needs the least plane angle. Where there is none
    within the pitch limit, no plane angle holds depth: the pitch of the least mismatch, its least-squares
    stern angle, and the margin -pi (outside any limit)."""
    mismatch = _stern_only_mismatch(vehicle, u, grid, surface)
    crossings = np.flatnonzero(np.sign(mismatch[:-1]) * np.sign(mismatch[1:]) <= 0)
    best: tuple[float, float] | None = None
    for i in crossings:
        a, b = float(grid[i]), float(grid[i + 1])
        if mismatch[i] == 0.0:
            theta = a
        elif mismatch[i + 1] == 0.0:
            theta = b
        else:
            theta = brentq(
                lambda t: float(_stern_only_mismatch(vehicle, u, np.asarray(t), surface)), a, b, xtol=1e-14
            )
        stern = float(_planes(vehicle, u, np.asarray(theta), surface)[0])
        if best is None or abs(stern) < abs(best[1]):
            best = (theta, stern)
    if best is None:  # (no level-depth steady state within the pitch limit at any plane angle)
        theta = float(grid[int(np.argmin(np.abs(mismatch)))])
        stern = float(_planes(vehicle, u, np.asarray(theta), surface)[0])
        return DepthHoldingTrim(u, False, theta, u * math.tan(theta), stern, 0.0, -math.pi)
    theta, stern = best
    margin = limit - abs(stern)
    return DepthHoldingTrim(u, margin >= 0, theta, u * math.tan(theta), stern, 0.0, margin)


def winnable(
    vehicle: Vehicle,
    speeds_mps: Iterable[float],
    max_pitch_rad: float,
    depth_m: float = 0.0,
    free_surface: FreeSurface = NO_FREE_SURFACE,
    sea_state: SeaState | None = None,
) -> bool:
    """Whether a depth-holding trim within the plane limits exists at every speed of ``speeds_mps`` (for an
    episode: the speed it holds at the end, the last knot of its profile, at its ordered depth; see
    :func:`depth_holding_trim`)."""
    return all(
        depth_holding_trim(vehicle, u, max_pitch_rad, depth_m, free_surface, sea_state).exists
        for u in speeds_mps
    )
