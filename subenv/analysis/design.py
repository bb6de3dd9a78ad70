"""Linear design quantities: pole placement, closed-loop eigenvalues, controllability, gain scheduling.

The thesis's controller (Riedel 1993 Ch. II.B) is full-state feedback delta = -K x placed at 5 fps
with poles (-0.3, -0.31, -0.32, -0.33) and alpha = 0; :func:`place_gain` reproduces it (eq. 2.98)
from the linear model of :mod:`subenv.analysis.linear`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

import numpy as np
from scipy.signal import place_poles

from subenv._typing import FloatArray
from subenv.analysis.linear import linear_model
from subenv.thesis import THESIS_DESIGN_SPEED_MPS, froude_speed_factor
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "THESIS_POLES",
    "closed_loop_eigenvalues",
    "controllability_determinant",
    "controllability_losses",
    "depth_gain_denominator",
    "place_gain",
    "scheduled_depth_gain",
    "thesis_gain",
    "thesis_poles",
]

THESIS_POLES: Final = (-0.3, -0.31, -0.32, -0.33)
"""Closed-loop poles of the thesis controller [1/s] (Riedel 1993 Ch. II.B)."""


def place_gain(
    vehicle: Vehicle, speed_mps: float, poles: Sequence[float] = THESIS_POLES, alpha: float = 0.0
) -> FloatArray:
    """Full-state gain K (delta = -K x, x = (theta, w, q, Z) in SI) placing the closed-loop poles.

    Uses ``scipy.signal.place_poles`` on the linear model about level flight (eqs 2.59-2.68);
    the thesis does the same with MATLAB's ``place`` (eqs 2.72-2.97).

    Raises
    ------
    ValueError
        At a speed where the pair (A, B) is uncontrollable (the critical speed, Fig. 3-14).
    """
    lm = linear_model(vehicle, speed_mps, alpha)
    try:
        result = place_poles(lm.A, lm.B[:, None], np.asarray(poles, dtype=float))
    except ValueError as exc:
        raise ValueError(f"speed_mps={speed_mps!r}: cannot place poles {tuple(poles)}: {exc}") from exc
    return np.asarray(result.gain_matrix[0], dtype=float)


def thesis_poles(vehicle: Vehicle) -> tuple[float, ...]:
    """:data:`THESIS_POLES` for ``vehicle``: SUBOFF's, Froude-scaled (rates x sqrt(L_SUBOFF / L); the
    same numbers on SUBOFF), so that a boat of another size gets the same design relative to its own
    dynamics."""
    factor = froude_speed_factor(vehicle)
    return tuple(p / factor for p in THESIS_POLES)


def thesis_gain(vehicle: Vehicle, alpha: float = 0.0) -> FloatArray:
    """The thesis controller's gain: poles (-0.3, -0.31, -0.32, -0.33) placed at 5 fps (eq. 2.98); on a
    vehicle of another length both Froude-scaled (:func:`thesis_poles`, ``froude_speed_factor``)."""
    return place_gain(
        vehicle, THESIS_DESIGN_SPEED_MPS * froude_speed_factor(vehicle), thesis_poles(vehicle), alpha
    )


def closed_loop_eigenvalues(
    vehicle: Vehicle, speeds_mps: Sequence[float] | FloatArray, gain: FloatArray, alpha: float = 0.0
) -> np.ndarray:
    """Eigenvalues of A(u) - B(u) K at each speed, shape (n_speeds, 4), sorted by real part (Fig. 3-4)."""
    out = np.empty((len(speeds_mps), 4), dtype=complex)
    for i, u in enumerate(speeds_mps):
        lm = linear_model(vehicle, float(u), alpha)
        eig = np.linalg.eigvals(lm.A - np.outer(lm.B, gain))
        out[i] = eig[np.argsort(eig.real)]
    return out


def controllability_determinant(vehicle: Vehicle, speed_mps: float, alpha: float = 0.0) -> float:
    """Det [B, AB, A^2 B, A^3 B] of the linear model (Riedel 1993 eqs 3.28-3.46, Fig. 3-14).

    It vanishes at the critical speed: there the single plane command cannot move the boat's
    depth and pitch independently.
    """
    lm = linear_model(vehicle, speed_mps, alpha)
    columns = [lm.B]
    for _ in range(3):
        columns.append(lm.A @ columns[-1])
    return float(np.linalg.det(np.column_stack(columns)))


def controllability_losses(
    vehicle: Vehicle, speeds_mps: Sequence[float] | FloatArray, alpha: float = 0.0
) -> list[tuple[float, complex]]:
    """Speeds where det(controllability matrix) changes sign, with the mode that loses control.

    Each sign change on the grid is refined with ``brentq``; the uncontrollable mode is the
    eigenvalue of A for which [A - lambda I, B] loses rank (PBH test). For SUBOFF two speeds come
    out: u_cr, where the depth (zero-eigenvalue) mode is lost (Fig. 3-14), and about 1.03 u_cr,
    where a stable real pitch-heave mode cancels against a zero of the plane-to-state response
    (harmless: the loop stays stabilisable).
    """
    from scipy.optimize import brentq

    speeds = np.asarray(speeds_mps, dtype=float)
    det = np.array([controllability_determinant(vehicle, float(u), alpha) for u in speeds])
    roots = [float(u) for u in speeds[det == 0]]
    for i in np.flatnonzero(np.sign(det[:-1]) * np.sign(det[1:]) < 0):
        roots.append(
            brentq(
                lambda s: controllability_determinant(vehicle, s, alpha), speeds[i], speeds[i + 1], xtol=1e-14
            )
        )
    out = []
    for u in sorted(roots):
        lm = linear_model(vehicle, u, alpha)
        eig = np.linalg.eigvals(lm.A)
        rank_gap = [
            np.linalg.svd(np.column_stack([lm.A - lam * np.eye(4), lm.B]), compute_uv=False)[-1]
            for lam in eig
        ]
        out.append((float(u), complex(eig[int(np.argmin(rank_gap))])))
    return out


def depth_gain_denominator(vehicle: Vehicle, speed_mps: float, alpha: float = 0.0) -> float:
    """D(u) = -det [A_theta, A_w, A_q, B]: the closed-loop constant coefficient per unit k4.

    det(sI - (A - B K)) has constant term k4 D(u), whatever k1..k3 (eq. 2.97, (D1 + D2) k4 =
    alpha_4). D vanishes at the critical speed (eq. 3.7), so one closed-loop eigenvalue crosses
    zero there for every gain.
    """
    lm = linear_model(vehicle, speed_mps, alpha)
    return float(-np.linalg.det(np.column_stack([lm.A[:, :3], lm.B])))


def scheduled_depth_gain(
    vehicle: Vehicle,
    speeds_mps: Sequence[float] | FloatArray,
    poles: Sequence[float] = THESIS_POLES,
    alpha: float = 0.0,
) -> FloatArray:
    """Depth gain k4(u) of a pole-placement design repeated at each speed [rad/m] (Fig. 5-3).

    From eq. 2.97, k4 = alpha_4 / D(u) with alpha_4 the product of the poles: it grows without
    bound as u -> u_cr and changes sign below it (stern-plane reversal).
    """
    alpha_4 = float(np.prod(poles))
    return np.array([alpha_4 / depth_gain_denominator(vehicle, float(u), alpha) for u in speeds_mps])
