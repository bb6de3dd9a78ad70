"""Steady states of the closed loop: the pitchfork, its asymmetric and saturated branches.

Under depth feedback delta = -K (theta, w, q, Z), a steady state with unsaturated planes holds a
constant depth (q = 0, w = u tan(theta), eq. 4.4) with the depth error Z absorbing whatever plane
angle the balance needs. With the planes saturated the command no longer balances anything: the
boat settles at a constant pitch and heave while sinking or rising steadily (eqs 4.40-4.42), the
failure the thesis's simulations show (Ch. III.A).

Closed forms (symmetric pitchfork eqs 3.17-3.23; exact steady-state equation 4.3-4.4; saturated
branches 4.40-4.42, 5.1-5.2) are solved here; stability always comes from the one dynamics
function (:func:`subenv.dynamics.derivatives`) through its numerical Jacobian.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final, Literal

import numpy as np
from scipy.optimize import brentq

from subenv._typing import FloatArray
from subenv.analysis.design import thesis_gain
from subenv.analysis.linear import check_alpha, plane_derivatives
from subenv.dynamics.model import derivatives, model_params
from subenv.units import FOOT_M
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "THESIS_HULL_AREA_M2",
    "THESIS_HULL_CENTROID_M",
    "Equilibrium",
    "closed_loop_jacobian",
    "equilibria",
    "steady_state_residual",
    "symmetric_pitchfork",
]

THESIS_HULL_AREA_M2: Final = 19.8473 * FOOT_M**2
"""Planform area the thesis's programs use (BIFSU.M: A = 19.8473 ft^2, from a truncated hull
integral; the full SUBOFF hull gives 20.215 ft^2). An input of the thesis's drag figures."""

THESIS_HULL_CENTROID_M: Final = 0.20126 * FOOT_M
"""Planform centroid the thesis's programs use (BIFSU.M: x_A = 0.20126 ft)."""

DragMoment = Literal["consistent", "thesis"]
HullIntegral = Literal["full", "thesis"]
_PITCH_GRID: Final = np.linspace(-1.5, 1.5, 3001)  # rad, root bracketing for theta in (-86, 86) deg


@dataclass(frozen=True)
class Equilibrium:
    """One steady state of the closed loop at a given speed (SI units).

    Attributes
    ----------
    speed_mps : float
    pitch_rad, heave_mps : float
        Steady pitch and heave velocity (q = 0).
    plane_rad : float
        Dual-control plane command delta (stern planes; bow planes alpha * delta).
    saturated : bool
        Planes at their limit; then the depth drifts at ``depth_rate_mps``.
    depth_rate_mps : float
        Z_dot = -u sin(theta) + w cos(theta); 0 for an unsaturated (depth-holding) steady state.
    depth_offset_m : float or None
        Steady depth error Z_ss that makes the feedback command equal ``plane_rad`` (eq. 3.23);
        None when saturated.
    eigenvalues : ndarray
        Of the closed-loop Jacobian (4x4, theta-w-q-Z with delta = -K x) when unsaturated; of the
        pitch-heave Jacobian (3x3, theta-w-q, planes fixed) when saturated.
    stable : bool
        All eigenvalues in the open left half-plane.
    """

    speed_mps: float
    pitch_rad: float
    heave_mps: float
    plane_rad: float
    saturated: bool
    depth_rate_mps: float
    depth_offset_m: float | None
    eigenvalues: np.ndarray = field(repr=False)
    stable: bool


def _drag_terms(vehicle: Vehicle, drag_moment: DragMoment, hull: HullIntegral) -> tuple[float, float]:
    """(rho/2) C_D A and the signed moment factor m_A with M_drag = m_A w|w| (q = 0)."""
    if drag_moment not in ("consistent", "thesis"):
        raise ValueError(f"drag_moment={drag_moment!r} is invalid: must be one of ['consistent', 'thesis']")
    if hull not in ("full", "thesis"):
        raise ValueError(f"hull={hull!r} is invalid: must be one of ['full', 'thesis']")
    area = vehicle.hull_area_m2 if hull == "full" else THESIS_HULL_AREA_M2
    centroid = vehicle.hull_centroid_x_m if hull == "full" else THESIS_HULL_CENTROID_M
    drag = 0.5 * vehicle.water_density_kg_m3 * vehicle.crossflow_drag * area
    # M = -x Z with Z = -drag w|w| gives +drag x_A w|w|; the thesis prints -drag x_A w|w| (eq. 4.2).
    return drag, (drag * centroid if drag_moment == "consistent" else -drag * centroid)


def steady_state_residual(
    vehicle: Vehicle,
    speed_mps: float,
    pitch_rad: FloatArray | float,
    alpha: float = 0.0,
    drag_moment: DragMoment = "consistent",
    hull: HullIntegral = "full",
) -> FloatArray:
    """Left-hand side of the exact steady-state equation, Riedel (1993) eq. 4.3 with w = u tan(theta).

    (Z_w M_d - M_w Z_d) u w - C (M_d - x_A Z_d) w|w| + ((W - B) M_d + (x_G W - x_B B) Z_d) cos(theta)
    + Z_d (z_G W - z_B B) sin(theta), where C = (rho/2) C_D A and the drag moment's sign is the
    physically consistent one unless ``drag_moment="thesis"``. Its roots are the depth-holding
    steady states.
    """
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    c = vehicle.coefficients
    W, B = vehicle.weight_N, vehicle.buoyancy_N
    drag, drag_moment_factor = _drag_terms(vehicle, drag_moment, hull)
    theta = np.asarray(pitch_rad, dtype=float)
    u = speed_mps
    w = u * np.tan(theta)  # Riedel (1993) eq. 4.4
    # Riedel (1993) eq. 4.3: M_d * (4.1) - Z_d * (4.2), with the drag moment M_drag = m_A w|w|.
    return (
        (c.Z_w * M_d - c.M_w * Z_d) * u * w
        - (drag * M_d + drag_moment_factor * Z_d) * w * np.abs(w)
        + ((W - B) * M_d + (vehicle.x_G_m * W - vehicle.x_B_m * B) * Z_d) * np.cos(theta)
        + Z_d * (vehicle.z_G_m * W - vehicle.z_B_m * B) * np.sin(theta)
    )


def _plane_for_heave_balance(
    vehicle: Vehicle, u: float, theta: float, w: float, alpha: float, drag: float
) -> float:
    """Delta from the heave balance, eq. 4.1: Z_w u w - C w|w| + (W - B) cos(theta) + Z_d u^2 delta = 0."""
    Z_d, _ = plane_derivatives(vehicle, alpha)
    W, B = vehicle.weight_N, vehicle.buoyancy_N
    return -(vehicle.coefficients.Z_w * u * w - drag * w * abs(w) + (W - B) * math.cos(theta)) / (Z_d * u * u)


def closed_loop_jacobian(
    vehicle: Vehicle,
    speed_mps: float,
    state: FloatArray,
    plane_rad: float,
    alpha: float,
    gain: FloatArray | None,
    eps: float = 1e-7,
) -> FloatArray:
    """Jacobian of the full model about ``state`` with planes ``plane_rad`` (central differences).

    With a gain, the command delta = -K x is part of the loop (4x4); with ``gain=None`` the planes
    are held (the 3x3 pitch-heave block, depth being a drifting coordinate).
    """
    params = model_params(vehicle)
    x0 = np.asarray(state, dtype=float)
    n = 4 if gain is not None else 3
    J = np.empty((n, n))
    for j in range(n):
        step = np.zeros(4)
        step[j] = eps
        cols = []
        for sign in (1.0, -1.0):
            x = x0 + sign * step
            delta = plane_rad if gain is None else plane_rad - float(np.dot(gain, sign * step))
            cols.append(derivatives(x, speed_mps, delta, alpha * delta, params))
        J[:, j] = ((cols[0] - cols[1]) / (2 * eps))[:n]
    return J


def _stability(eigenvalues: np.ndarray) -> bool:
    return bool(np.all(eigenvalues.real < 0))


def _roots(fun: Callable[[Any], Any], grid: FloatArray) -> list[float]:
    """The sorted roots of ``fun`` on ``grid``: its sign changes between grid points, refined by brentq.

    ``fun`` takes the whole grid (an array) and, in brentq, single floats.
    """
    values = fun(grid)
    roots = []
    for i in np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) <= 0):
        a, b = grid[i], grid[i + 1]
        if values[i] == 0:
            roots.append(float(a))
        elif values[i + 1] != 0:
            roots.append(float(brentq(fun, a, b, xtol=1e-14, rtol=1e-13)))
    return sorted(set(roots))


def _unsaturated(
    vehicle: Vehicle, u: float, theta: float, alpha: float, gain: FloatArray, drag: float
) -> Equilibrium:
    w = u * math.tan(theta)
    delta = _plane_for_heave_balance(vehicle, u, theta, w, alpha, drag)
    # Eq. 3.23: Z_ss such that -(k1 theta + k2 w + k4 Z) = delta.
    depth = -(delta + gain[0] * theta + gain[1] * w) / gain[3]
    eig = np.linalg.eigvals(
        closed_loop_jacobian(vehicle, u, np.array([theta, w, 0.0, depth]), delta, alpha, gain)
    )
    return Equilibrium(u, theta, w, delta, False, 0.0, depth, eig, _stability(eig))


def _saturated_branch(
    vehicle: Vehicle,
    u: float,
    sign: float,
    alpha: float,
    gain: FloatArray,
    drag: float,
    drag_moment_factor: float,
) -> list[Equilibrium]:
    """Steady pitch with the planes at sign * limit (eqs 4.40-4.42; 5.1-5.2 with W != B and drag)."""
    delta = sign * vehicle.planes.limit_rad
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    c = vehicle.coefficients
    W, B = vehicle.weight_N, vehicle.buoyancy_N

    damping = c.Z_w * u
    if not (damping < 0 and drag >= 0):
        raise ValueError(
            f"Z_w={c.Z_w!r} and the cross-flow drag factor {drag!r} are invalid for the saturated branch: "
            "need Z_w < 0 and a drag factor >= 0 (a heave force that falls as w rises)"
        )

    def heave(theta: float) -> float:
        # Eq. 4.40 solved for w: Z_w u w - C w|w| + rest = 0, strictly decreasing in w (Z_w u < 0, C >= 0),
        # so its one root has the sign of rest: the root of C w^2 - Z_w u w - rest = 0 (rest >= 0) or of
        # C w^2 + Z_w u w + rest = 0 (rest < 0), written without cancellation, as for C = 0.
        rest = (W - B) * math.cos(theta) + Z_d * u * u * delta
        return 2.0 * rest / (math.sqrt(damping * damping + 4.0 * drag * abs(rest)) - damping)

    def pitch_balance(theta: FloatArray) -> FloatArray:
        th = np.atleast_1d(theta)
        out = np.empty(th.shape)
        for i, t in enumerate(th):
            w = heave(float(t))
            # Eq. 4.41 (5.2): the pitch-moment balance at the saturated plane angle.
            out[i] = (
                c.M_w * u * w
                + drag_moment_factor * w * abs(w)
                - (vehicle.x_G_m * W - vehicle.x_B_m * B) * math.cos(t)
                - (vehicle.z_G_m * W - vehicle.z_B_m * B) * math.sin(t)
                + M_d * u * u * delta
            )
        return out if np.ndim(theta) else out[0]

    found = []
    for theta in _roots(pitch_balance, _PITCH_GRID[::10]):
        w = heave(theta)
        rate = -u * math.sin(theta) + w * math.cos(theta)
        # The saturation persists only if the depth drift pushes the command further into it:
        # d(delta_cmd)/dt = -k4 Z_dot must have the sign of the saturated plane angle.
        if -gain[3] * rate * sign < 0:
            continue
        eig = np.linalg.eigvals(
            closed_loop_jacobian(vehicle, u, np.array([theta, w, 0.0, 0.0]), delta, alpha, None)
        )
        found.append(Equilibrium(u, theta, w, delta, True, rate, None, eig, _stability(eig)))
    return found


def equilibria(
    vehicle: Vehicle,
    speed_mps: float,
    alpha: float = 0.0,
    gain: FloatArray | None = None,
    drag_moment: DragMoment = "consistent",
    hull: HullIntegral = "full",
    saturation: bool = True,
) -> list[Equilibrium]:
    """All steady states of the closed loop at one speed, with saturation (Riedel 1993 Ch. IV).

    Unsaturated, depth-holding states are the roots of the exact steady-state equation (eqs 4.3,
    4.4) whose plane angle (eq. 4.1) is within the limit; saturated states solve eqs 4.40-4.41
    (5.1-5.2 with excess buoyancy and drag) at +-limit and are kept where the depth drift keeps the
    planes saturated. Holds for any loading (W != B, x_GB, z_GB) and drag coefficient.

    Parameters
    ----------
    vehicle : Vehicle
    speed_mps : float
        Forward speed [m/s], > 0.
    alpha : float
        Bow/stern allocation in [-1, 1] (eq. 2.58).
    gain : ndarray, optional
        Feedback gain K (delta = -K x); the thesis controller's (eq. 2.98) by default. It sets the
        steady depth offsets and the closed-loop stability, not the steady pitch.
    drag_moment : {"consistent", "thesis"}
        Sign of the hull drag moment in the closed form; "thesis" reproduces eqs 4.2-4.3 as printed.
        Stability always uses the package's (consistent) dynamics.
    hull : {"full", "thesis"}
        Hull planform area and centroid: the full SUBOFF offsets or the thesis's truncated values.
    saturation : bool
        With False, the planes are unlimited: every root of eq. 4.3 is returned, whatever its
        plane angle, and no saturated state (Fig. 4-1).

    Returns
    -------
    list of Equilibrium
        Sorted by pitch.
    """
    if not (math.isfinite(speed_mps) and speed_mps > 0):
        raise ValueError(f"speed_mps={speed_mps!r} is invalid: must be a finite number > 0")
    alpha = check_alpha(alpha)
    gain = thesis_gain(vehicle, alpha) if gain is None else np.asarray(gain, dtype=float)
    drag, drag_moment_factor = _drag_terms(vehicle, drag_moment, hull)
    limit = vehicle.planes.limit_rad
    found = []
    roots = _roots(
        lambda th: steady_state_residual(vehicle, speed_mps, th, alpha, drag_moment, hull), _PITCH_GRID
    )
    for theta in roots:
        eq = _unsaturated(vehicle, speed_mps, theta, alpha, gain, drag)
        if not saturation or abs(eq.plane_rad) <= limit:
            found.append(eq)
    if saturation:
        for sign in (1.0, -1.0):
            found.extend(_saturated_branch(vehicle, speed_mps, sign, alpha, gain, drag, drag_moment_factor))
    return sorted(found, key=lambda e: e.pitch_rad)


def symmetric_pitchfork(
    vehicle: Vehicle, speed_mps: float, alpha: float = 0.0, gain: FloatArray | None = None
) -> list[Equilibrium]:
    """The symmetric pitchfork in closed form (Riedel 1993 eqs 3.17-3.23, saturated 3.24-3.26/4.42).

    For the thesis's simplified boat (W = B, x_G = x_B, C_D = 0): level flight always, and below the
    critical speed the pair cos(theta_ss) = u^2 (M_w Z_d - Z_w M_d) / (Z_d B z_GB) (eq. 3.17) with
    delta_ss = -(Z_w / Z_d) tan(theta_ss) (eq. 3.21); where |delta_ss| would pass the limit the pair
    is replaced by the saturated states of eq. 4.42.

    Raises
    ------
    ValueError
        If the vehicle is not symmetric in the thesis's sense (use :func:`equilibria`).
    """
    if vehicle.excess_buoyancy_N != 0 or vehicle.x_GB_m != 0 or vehicle.crossflow_drag != 0:
        raise ValueError(
            f"vehicle {vehicle.name!r} has B - W = {vehicle.excess_buoyancy_N!r} N, "
            f"x_GB = {vehicle.x_GB_m!r} m, C_D = {vehicle.crossflow_drag!r}: the symmetric pitchfork needs "
            "all three 0 (use equilibria())"
        )
    if not (math.isfinite(speed_mps) and speed_mps > 0):
        raise ValueError(f"speed_mps={speed_mps!r} is invalid: must be a finite number > 0")
    alpha = check_alpha(alpha)
    gain = thesis_gain(vehicle, alpha) if gain is None else np.asarray(gain, dtype=float)
    Z_d, M_d = plane_derivatives(vehicle, alpha)
    c = vehicle.coefficients
    u = speed_mps
    found = [_unsaturated(vehicle, u, 0.0, alpha, gain, 0.0)]
    cos_ss = u * u * (c.M_w * Z_d - c.Z_w * M_d) / (Z_d * vehicle.buoyancy_N * vehicle.z_GB_m)  # eq. 3.17
    if 0 < cos_ss < 1:
        theta_ss = math.acos(cos_ss)  # eq. 3.18
        delta_ss = -(c.Z_w / Z_d) * math.tan(theta_ss)  # eq. 3.21
        if abs(delta_ss) <= vehicle.planes.limit_rad:
            found += [_unsaturated(vehicle, u, s * theta_ss, alpha, gain, 0.0) for s in (1.0, -1.0)]
    for sign in (1.0, -1.0):
        found.extend(_saturated_branch(vehicle, u, sign, alpha, gain, 0.0, 0.0))
    return sorted(found, key=lambda e: e.pitch_rad)
