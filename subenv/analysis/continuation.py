"""Pseudo-arclength continuation of the full model's depth-holding steady states.

Unknowns y = (theta, w, delta) with q = 0; residual (w_dot, q_dot, Z_dot) from the one dynamics
function (:func:`subenv.dynamics.derivatives`, drag included). The parameter is the speed or the
ballast offset x_GB. Unlike a parameter sweep, arclength continuation goes round folds, so it
traces the S-shaped solution sets whose folds make the hysteresis of Riedel (1993) Fig. 4-13.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from subenv._typing import FloatArray
from subenv.analysis.design import thesis_gain
from subenv.analysis.equilibria import _PITCH_GRID, _roots, closed_loop_jacobian, steady_state_residual
from subenv.analysis.linear import check_alpha, plane_derivatives
from subenv.dynamics.model import ModelParams, derivatives, model_params
from subenv.vehicles.vehicle import Vehicle

__all__ = ["Branch", "ContinuationError", "continue_equilibria"]

Parameter = Literal["speed", "x_GB"]


class ContinuationError(RuntimeError):
    """The corrector did not converge even at the smallest step."""


@dataclass(frozen=True)
class Branch:
    """A branch of steady states traced by :func:`continue_equilibria`.

    Attributes
    ----------
    parameter : {"speed", "x_GB"}
    values : ndarray, shape (n,)
        The parameter along the branch [m/s or m].
    states : ndarray, shape (n, 3)
        (theta [rad], w [m/s], delta [rad]) along the branch.
    eigenvalues : ndarray, shape (n, 4)
        Of the closed-loop Jacobian (delta = -K x), per point.
    stable : ndarray of bool, shape (n,)
    folds : ndarray of int
        Indices where the branch turns back in the parameter (limit points).
    residual_max : float
        Largest residual norm of an accepted point [m/s^2 or rad/s^2 scale].
    """

    parameter: str
    values: FloatArray
    states: FloatArray
    eigenvalues: np.ndarray
    stable: np.ndarray
    folds: np.ndarray
    residual_max: float


def continue_equilibria(
    vehicle: Vehicle,
    parameter: Parameter,
    start: float,
    stop: float,
    *,
    speed_mps: float | None = None,
    alpha: float = 0.0,
    gain: FloatArray | None = None,
    initial_pitch_rad: float = 0.0,
    step: float = 0.02,
    max_points: int = 5000,
    tol: float = 1e-10,
) -> Branch:
    """Trace depth-holding steady states from ``parameter = start`` until it reaches ``stop``.

    Parameters
    ----------
    vehicle : Vehicle
        Any loading. With ``parameter="x_GB"``, its x_GB is replaced along the branch.
    parameter : {"speed", "x_GB"}
        The continuation parameter: forward speed [m/s] or ballast offset x_G - x_B [m].
    start, stop : float
        Parameter range; the branch may fold back inside it and is followed round the folds.
    speed_mps : float
        The fixed speed when ``parameter="x_GB"``.
    alpha : float
        Bow/stern allocation (eq. 2.58).
    gain : ndarray, optional
        Feedback gain for the stability of each point (thesis gain by default).
    initial_pitch_rad : float
        Selects the branch when several exist: the start is the root of eq. 4.3 nearest to it.
    step : float
        Initial arclength step in scaled units (pitch in rad, parameter / its scale).
    max_points, tol : int, float
        Safety limit on the number of points; Newton tolerance on the residual.

    Raises
    ------
    ValueError
        Bad arguments.
    ContinuationError
        The corrector fails to converge at the smallest step (reported, never silently truncated).
    """
    if parameter not in ("speed", "x_GB"):
        raise ValueError(f"parameter={parameter!r} is invalid: must be one of ['speed', 'x_GB']")
    if parameter == "x_GB" and not (speed_mps is not None and math.isfinite(speed_mps) and speed_mps > 0):
        raise ValueError(f"speed_mps={speed_mps!r} is invalid: continuation over x_GB needs a speed > 0")
    if parameter == "speed" and not (start > 0 and stop > 0):
        raise ValueError(f"start={start!r}, stop={stop!r}: speeds must be > 0")
    alpha = check_alpha(alpha)
    gain = thesis_gain(vehicle, alpha) if gain is None else np.asarray(gain, dtype=float)
    scale = 1.0 if parameter == "speed" else vehicle.z_GB_m  # parameter scale in the arclength
    cache: dict[float, tuple[ModelParams, Vehicle]] = {}
    base_params = model_params(vehicle)

    def setup(p: float) -> tuple[float, ModelParams, Vehicle]:
        """Speed, model parameters and vehicle at parameter value ``p``."""
        if parameter == "speed":
            return p, base_params, vehicle
        if p not in cache:
            if len(cache) > 64:
                cache.clear()
            variant = vehicle.variant(x_GB_m=p)
            cache[p] = (model_params(variant), variant)
        return float(speed_mps), *cache[p]  # type: ignore[arg-type]

    def residual(z: FloatArray) -> FloatArray:
        p = z[3] * scale
        u, params, _ = setup(p)
        theta, w, delta = z[:3]
        f = derivatives(np.array([theta, w, 0.0, 0.0]), u, delta, alpha * delta, params)
        return f[1:4]

    def jacobian(z: FloatArray) -> FloatArray:
        J = np.empty((3, 4))
        for j in range(4):
            h = 1e-7 * max(1.0, abs(z[j]))
            e = np.zeros(4)
            e[j] = h
            J[:, j] = (residual(z + e) - residual(z - e)) / (2 * h)
        return J

    def tangent(J: FloatArray, previous: FloatArray | None) -> FloatArray:
        t = np.linalg.svd(J)[2][-1]
        if previous is None:
            return t if t[3] * (stop - start) >= 0 else -t
        return t if float(t @ previous) >= 0 else -t

    def newton(
        z: FloatArray, t: FloatArray | None, anchor: FloatArray | None
    ) -> tuple[FloatArray, int] | None:
        for it in range(20):
            F = residual(z)
            J = jacobian(z)
            if t is None:  # fixed parameter: solve the 3x3 system in y
                if np.linalg.norm(F) < tol:
                    return z, it
                dz = np.zeros(4)
                dz[:3] = np.linalg.solve(J[:, :3], -F)
            else:
                arc = float(t @ (z - anchor))  # type: ignore[operator]
                if np.linalg.norm(F) < tol and abs(arc) < 1e-12:
                    return z, it
                dz = np.linalg.solve(np.vstack([J, t]), -np.append(F, arc))
            z = z + dz
            if not np.all(np.isfinite(z)):
                return None
        return None

    u0, _, start_vehicle = setup(start)
    # Start from the root of the exact steady-state equation (eq. 4.3) nearest the pitch guess.
    roots = _roots(lambda th: steady_state_residual(start_vehicle, u0, th, alpha), _PITCH_GRID)
    if not roots:
        raise ContinuationError(f"no steady state exists at {parameter}={start!r}")
    theta0 = min(roots, key=lambda r: abs(r - initial_pitch_rad))
    w0 = u0 * math.tan(theta0)
    delta0 = -(
        vehicle.coefficients.Z_w * u0 * w0 + (vehicle.weight_N - vehicle.buoyancy_N) * math.cos(theta0)
    ) / (plane_derivatives(vehicle, alpha)[0] * u0 * u0)
    solved = newton(np.array([theta0, w0, delta0, start / scale]), None, None)
    if solved is None:
        raise ContinuationError(f"no steady state found at {parameter}={start!r} from pitch {theta0!r} rad")
    z = solved[0]
    t = tangent(jacobian(z), None)
    points = [z]
    h, h_min, h_max = step, step / 1024, step * 4
    lo, hi = min(start, stop) / scale, max(start, stop) / scale
    while len(points) < max_points:
        prediction = z + h * t
        corrected = newton(prediction, t, prediction)
        if corrected is None:
            h /= 2
            if h < h_min:
                raise ContinuationError(
                    f"corrector failed at {parameter}={z[3] * scale!r} (pitch {z[0]!r} rad) at the "
                    "smallest step"
                )
            continue
        z_new, iterations = corrected
        if abs(z_new[0]) > 1.4:  # beyond ~80 deg of pitch the branch has left the model's range
            break
        t = tangent(jacobian(z_new), t)
        z = z_new
        points.append(z)
        if not lo - 1e-12 <= z[3] <= hi + 1e-12:
            break
        if iterations <= 3:
            h = min(h * 1.3, h_max)
    pts = np.array(points)
    values = pts[:, 3] * scale
    rows = []
    for (th, w, d), p in zip(pts[:, :3], values, strict=True):
        u, _, v = setup(float(p))
        rows.append(
            np.linalg.eigvals(closed_loop_jacobian(v, u, np.array([th, w, 0.0, 0.0]), d, alpha, gain))
        )
    eig = np.array(rows)
    direction = np.sign(np.diff(values))
    folds = np.flatnonzero(direction[1:] * direction[:-1] < 0) + 1
    residual_max = max(float(np.linalg.norm(residual(p))) for p in pts)
    return Branch(parameter, values, pts[:, :3], eig, np.all(eig.real < 0, axis=1), folds, residual_max)
