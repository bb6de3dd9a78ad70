"""Hopf bifurcations of level flight at speed, and the pitch oscillations they start.

Riedel (1993) Ch. VI recommends "a Hopf bifurcation analysis to identify the critical parameters
that lead to vehicle instability at high speeds"; this module does it on the package's one
right-hand side (:func:`subenv.dynamics.derivatives`).

- :func:`hopf_points`: the speeds at which a complex pair of eigenvalues of level flight crosses the
  imaginary axis, with the planes held at zero (open loop: the (theta, w, q) subsystem; depth does
  not feed back) or under a linear gain on (theta, w, q, Z) (closed loop), and the frequency there.
  For SUBOFF the open loop has one, at 0.836 m/s, 0.157 rad/s (a 40 s period): the pitch/heave
  oscillation of the statically stable hull grows above it, because the destabilising Munk moment
  (M_w u w) grows with u while the restoring moment W z_GB does not.
- :class:`HopfPoint.amplitude_coefficient`: criticality. The hull's cross-flow drag is quadratic,
  ``v |v|``, which is not twice differentiable at level flight, so the first Lyapunov coefficient of
  smooth Hopf theory (cubic order) does not decide it: the drag enters the amplitude equation one
  order earlier. Averaging the field over a cycle of the critical mode (Krylov-Bogoliubov) gives
  ``dr/dt = Re(lambda(u)) r + c2 r^2 + O(r^3)``, r the pitch amplitude [rad]; smooth quadratic
  terms average to zero, the drag does not. ``c2 < 0``: supercritical, a stable cycle is born on the
  unstable side, its amplitude ``r = -Re(lambda(u)) / c2`` growing linearly (not as a square root)
  with ``u - u_H``.
- :func:`periodic_orbit` / :func:`continue_periodic_orbits`: the cycles themselves, by shooting on the
  section theta = 0 (scipy's ``root`` and ``solve_ivp``), with their period, pitch amplitude and
  Floquet multipliers (stability).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final, Literal

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, root

from subenv import _validation as check
from subenv._typing import FloatArray
from subenv.analysis.linear import check_alpha, linear_model
from subenv.dynamics.model import derivatives_with, model_params
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "HopfPoint",
    "PeriodicOrbit",
    "continue_periodic_orbits",
    "hopf_points",
    "level_flight_eigenvalues",
    "oscillatory_growth_rate",
    "periodic_orbit",
]

DEFAULT_FROUDE_GRID: Final = np.linspace(0.008, 0.464, 457)
"""Where :func:`hopf_points` looks for crossings by default: these length Froude numbers u / sqrt(g L),
0.001 apart (for SUBOFF, 0.05 to 3.0 m/s), so that a vehicle of any size is searched over the same
physics (Froude similarity); each crossing is then refined by ``brentq``."""
_COMPLEX: Final = 1e-9
"""An eigenvalue with |imaginary part| above this [rad/s] is one of a complex pair."""
_AVERAGING_AMPLITUDES: Final = (1e-4, 2e-4)
"""Pitch amplitudes [rad] at which the cycle average is taken: small enough that the O(r^3) terms are
below 1e-6 of the drag's, large enough for double precision."""
_PHASES: Final = 512
_GUESS_PERIODS: Final = 30
"""Periods flown from a neighbouring orbit before shooting (a stable orbit is then near)."""

Loop = Literal["open", "closed"]


@dataclass(frozen=True)
class HopfPoint:
    """A complex pair of level flight's eigenvalues crossing the imaginary axis at ``speed_mps``."""

    speed_mps: float
    frequency_radps: float
    """The pair's imaginary part at the crossing: the oscillation's angular frequency."""
    growth_slope: float
    """d Re(lambda) / du at the crossing [1/s per m/s]: > 0, level flight loses stability as u rises."""
    amplitude_coefficient: float
    """c2 [1/(s rad)] of ``dr/dt = Re(lambda) r + c2 r^2``, r the pitch amplitude: < 0 supercritical."""
    loop: Loop
    alpha: float

    @property
    def period_s(self) -> float:
        """The period of the oscillation born at the crossing, 2 pi / frequency [s]."""
        return 2.0 * math.pi / self.frequency_radps

    @property
    def criticality(self) -> Literal["supercritical", "subcritical"]:
        """Supercritical: stable cycles of small amplitude where level flight is unstable."""
        return "supercritical" if self.amplitude_coefficient < 0.0 else "subcritical"

    def predicted_amplitude_rad(
        self, vehicle: Vehicle, speed_mps: float, gain: FloatArray | None = None
    ) -> float:
        """The normal form's pitch amplitude of the cycle at ``speed_mps``, ``-Re(lambda) / c2``
        (NaN where it has none); valid while the amplitude is small (a few degrees)."""
        growth = oscillatory_growth_rate(vehicle, speed_mps, gain, self.alpha)
        amplitude = -growth / self.amplitude_coefficient
        return float(amplitude) if amplitude > 0.0 else math.nan


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic solution of the nonlinear equations at ``speed_mps`` (planes held, or the gain's)."""

    speed_mps: float
    period_s: float
    state: FloatArray
    """A point of the orbit, (theta, w, q) (open loop) or (theta, w, q, Z) (closed loop), at theta = 0."""
    pitch_amplitude_rad: float
    """Half the pitch's range over a period."""
    floquet_multipliers: FloatArray
    """Eigenvalues of the monodromy matrix, the trivial one (1, along the orbit) included."""
    solver: Any
    """scipy's ``OptimizeResult`` of the shooting equations."""

    @property
    def stable(self) -> bool:
        """Every multiplier but the trivial one inside the unit circle."""
        nontrivial = np.delete(self.floquet_multipliers, np.argmin(np.abs(self.floquet_multipliers - 1.0)))
        return bool(np.all(np.abs(nontrivial) < 1.0))


def level_flight_eigenvalues(
    vehicle: Vehicle, speed_mps: float, gain: FloatArray | None = None, alpha: float = 0.0
) -> np.ndarray:
    """Eigenvalues of level flight at ``speed_mps``: of the (theta, w, q) subsystem with the planes
    held (``gain=None``; depth is a pure integrator that does not feed back), or of
    ``A - B gain`` on (theta, w, q, Z) with dual control ``alpha`` (Riedel 1993 eqs 2.59-2.68)."""
    model = linear_model(vehicle, speed_mps, alpha)
    if gain is None:
        return np.linalg.eigvals(model.A[:3, :3])
    return np.linalg.eigvals(model.A - np.outer(model.B, gain))


def oscillatory_growth_rate(
    vehicle: Vehicle, speed_mps: float, gain: FloatArray | None = None, alpha: float = 0.0
) -> float:
    """The largest real part [1/s] among the complex pairs of :func:`level_flight_eigenvalues`: the growth
    (> 0) or decay of level flight's oscillation; -inf where no eigenvalue is complex."""
    eigenvalues = level_flight_eigenvalues(vehicle, speed_mps, gain, alpha)
    pairs = eigenvalues[np.abs(eigenvalues.imag) > _COMPLEX]
    return float(pairs.real.max()) if pairs.size else -math.inf


def _check_level_flight(vehicle: Vehicle) -> None:
    if abs(vehicle.excess_buoyancy_N) > 1e-9 * vehicle.weight_N or abs(vehicle.x_GB_m) > 1e-12:
        raise ValueError(
            f"vehicle {vehicle.name!r} has excess buoyancy {vehicle.excess_buoyancy_N:.4g} N and x_GB "
            f"{vehicle.x_GB_m:.4g} m: Hopf points are found about level flight, which needs both 0 "
            "(a neutrally trimmed loading)"
        )


def _check_gain(gain: FloatArray | None) -> FloatArray | None:
    if gain is None:
        return None
    k = np.asarray(gain, dtype=float)
    if k.shape != (4,) or not np.all(np.isfinite(k)):
        raise ValueError(f"gain={gain!r} is invalid: must be 4 finite numbers, on (theta, w, q, Z)")
    return k


def _field(
    vehicle: Vehicle, speed_mps: float, gain: FloatArray | None, alpha: float
) -> Callable[[FloatArray], FloatArray]:
    """The nonlinear right-hand side in the loop's coordinates, for a batch of states (..., n)."""
    derivatives = derivatives_with(model_params(vehicle))
    if gain is None:

        def open_loop(x: FloatArray) -> FloatArray:
            if x.ndim == 1:  # (one state: solve_ivp's calls, a million a report)
                return derivatives((x[0], x[1], x[2], 0.0), speed_mps, 0.0, 0.0)[:3]
            state = np.concatenate([x, np.zeros((*x.shape[:-1], 1))], axis=-1)
            return derivatives(state, speed_mps, 0.0, 0.0)[..., :3]

        return open_loop

    def closed_loop(x: FloatArray) -> FloatArray:
        delta = -(x @ gain)  # unsaturated: the small oscillations about level flight
        return derivatives(x, speed_mps, delta, alpha * delta)

    return closed_loop


def _amplitude_coefficient(
    vehicle: Vehicle, speed_mps: float, gain: FloatArray | None, alpha: float
) -> float:
    """c2 of the averaged amplitude equation at a Hopf point (see the module docstring)."""
    model = linear_model(vehicle, speed_mps, alpha)
    A = model.A[:3, :3] if gain is None else model.A - np.outer(model.B, gain)
    values, vectors = np.linalg.eig(A)
    k = int(np.argmax(values.imag))
    v = vectors[:, k] / (
        2.0 * vectors[0, k]
    )  # pitch component 1/2: x = 2 r Re(v e^{i phi}) has pitch amplitude r
    left_values, left_vectors = np.linalg.eig(A.conj().T)
    w = left_vectors[:, int(np.argmin(np.abs(left_values - values[k].conj())))]
    w = w / np.conj(np.vdot(w, v))  # w^H v = 1: z = w^H x is the critical mode's coordinate
    field = _field(vehicle, speed_mps, gain, alpha)
    phase = np.linspace(0.0, 2.0 * math.pi, _PHASES, endpoint=False)

    def averaged(r: float) -> float:  # <Re(e^{-i phi} w^H g(x))>, g the nonlinear part
        x = 2.0 * r * np.real(np.outer(np.exp(1j * phase), v))
        g = field(x) - x @ A.T
        return float(np.mean(np.real(np.exp(-1j * phase) * (g @ w.conj()))))

    r1, r2 = _AVERAGING_AMPLITUDES
    # averaged(r) = c2 r^2 + c3 r^3: two amplitudes separate the two.
    f1, f2 = averaged(r1) / r1**2, averaged(r2) / r2**2
    return (f1 * r2 - f2 * r1) / (r2 - r1)


def hopf_points(
    vehicle: Vehicle,
    gain: FloatArray | None = None,
    alpha: float = 0.0,
    speeds_mps: FloatArray | None = None,
) -> list[HopfPoint]:
    """The Hopf points of level flight over speed.

    Parameters
    ----------
    vehicle : Vehicle
        A neutrally trimmed loading (W = B, x_GB = 0), whose level flight is a steady state at every speed.
    gain : array of 4, optional
        A linear gain on (theta, w, q, Z) [rad per SI unit], planes ``-gain @ x`` (dual control
        ``alpha``): the closed loop. None: the planes held at zero (open loop).
    alpha : float
        Bow/stern allocation of the closed loop (Riedel 1993 eq. 2.58).
    speeds_mps : array, optional
        The grid searched for sign changes of the complex pairs' real part (default
        :data:`DEFAULT_FROUDE_GRID` times sqrt(g L)); each is refined with ``brentq``.

    Returns
    -------
    list of HopfPoint
        In order of speed; empty if no complex pair crosses on the grid.
    """
    _check_level_flight(vehicle)
    k = _check_gain(gain)
    alpha = check_alpha(alpha)
    froude_speed = math.sqrt(vehicle.gravity_m_s2 * vehicle.length_m)
    grid = DEFAULT_FROUDE_GRID * froude_speed if speeds_mps is None else np.asarray(speeds_mps, dtype=float)
    check.require(
        "speeds_mps",
        speeds_mps,
        grid.ndim == 1
        and grid.size >= 2
        and bool(np.all(np.isfinite(grid)))
        and bool(np.all(grid >= 0.0))
        and bool(np.all(np.diff(grid) > 0.0)),
        "an increasing array of at least 2 finite speeds >= 0",
    )

    def growth(u: float) -> float:
        return oscillatory_growth_rate(vehicle, u, k, alpha)

    values = [growth(u) for u in grid]
    points = []
    for lo, hi, g_lo, g_hi in zip(grid[:-1], grid[1:], values[:-1], values[1:], strict=True):
        if not (math.isfinite(g_lo) and math.isfinite(g_hi)) or (g_lo < 0.0) == (g_hi < 0.0):
            continue  # (no pair at one end: a pair that turns real is not a Hopf crossing)
        speed = brentq(growth, lo, hi, xtol=1e-12)
        eigenvalues = level_flight_eigenvalues(vehicle, speed, k, alpha)
        frequency = float(np.abs(eigenvalues[np.abs(eigenvalues.imag) > _COMPLEX].imag).max())
        h = 1e-6
        slope = (growth(speed + h) - growth(speed - h)) / (2 * h)
        points.append(
            HopfPoint(
                speed_mps=float(speed),
                frequency_radps=frequency,
                growth_slope=float(slope),
                amplitude_coefficient=_amplitude_coefficient(vehicle, speed, k, alpha),
                loop="open" if k is None else "closed",
                alpha=alpha,
            )
        )
    return points


def _flow(field: Callable[[FloatArray], FloatArray], x0: FloatArray, period: float, **kwargs: Any) -> Any:
    return solve_ivp(
        lambda t, x: field(x), (0.0, period), x0, method="DOP853", rtol=1e-10, atol=1e-12, **kwargs
    )


def periodic_orbit(
    vehicle: Vehicle,
    speed_mps: float,
    guess: PeriodicOrbit | None = None,
    gain: FloatArray | None = None,
    alpha: float = 0.0,
    settle_s: float = 4000.0,
) -> PeriodicOrbit:
    """The periodic orbit at ``speed_mps``, by shooting on the section theta = 0 (theta rising).

    Unknowns: (w, q[, Z]) on the section and the period T; equations: the flow over T returns to
    the point. Newton starts from the motion after :data:`_GUESS_PERIODS` periods flown from
    ``guess`` (a neighbouring orbit: continuation), or after ``settle_s`` seconds from a 0.02 rad
    pitch, so it finds stable orbits. Raises ``RuntimeError``
    if the shooting does not converge or converges to level flight.
    """
    _check_level_flight(vehicle)
    k = _check_gain(gain)
    alpha = check_alpha(alpha)
    check.require(
        "speed_mps", speed_mps, check.is_number(speed_mps) and speed_mps > 0.0, "a finite number > 0"
    )
    field = _field(vehicle, float(speed_mps), k, alpha)
    n = 3 if k is None else 4
    if guess is None:
        start = np.zeros(n)
        start[0] = 0.02
    else:
        start, settle_s = guess.state, _GUESS_PERIODS * guess.period_s
    # Newton on the shooting equations also has level flight as a root (any T): it starts from the
    # motion after settling (on the orbit, for a stable one), never from far away.
    settled = _flow(field, start, settle_s, dense_output=True)
    t = np.linspace(0.5 * settle_s, settle_s, 20000)
    theta = settled.sol(t)[0]
    rising = np.flatnonzero((theta[:-1] < 0.0) & (theta[1:] >= 0.0))
    if len(rising) < 2:
        raise RuntimeError(
            f"no oscillation at speed_mps={speed_mps}: level flight is stable there (or the motion diverged)"
        )
    x0, period0 = settled.sol(t[rising[-2]]), float(t[rising[-1]] - t[rising[-2]])

    def residual(z: FloatArray) -> FloatArray:
        start = np.concatenate([[0.0], z[:-1]])
        end = _flow(field, start, z[-1]).y[:, -1]
        return np.concatenate([end - start])

    solution = root(residual, np.concatenate([x0[1:], [period0]]), method="hybr", options={"xtol": 1e-11})
    state = np.concatenate([[0.0], solution.x[:-1]])
    period = float(solution.x[-1])
    if not solution.success or np.max(np.abs(residual(solution.x))) > 1e-7 or np.max(np.abs(state)) < 1e-6:
        raise RuntimeError(f"no periodic orbit found at speed_mps={speed_mps}: {solution.message}")
    orbit = _flow(field, state, period, dense_output=True)
    theta = orbit.sol(np.linspace(0.0, period, 2001))[0]
    # Monodromy by central differences of the flow over one period.
    eps = 1e-7
    columns = []
    for j in range(n):
        step = np.zeros(n)
        step[j] = eps
        columns.append(
            (_flow(field, state + step, period).y[:, -1] - _flow(field, state - step, period).y[:, -1])
            / (2 * eps)
        )
    multipliers = np.linalg.eigvals(np.column_stack(columns))
    return PeriodicOrbit(
        speed_mps=float(speed_mps),
        period_s=period,
        state=state,
        pitch_amplitude_rad=float(0.5 * (theta.max() - theta.min())),
        floquet_multipliers=multipliers,
        solver=solution,
    )


def continue_periodic_orbits(
    vehicle: Vehicle,
    speeds_mps: FloatArray,
    gain: FloatArray | None = None,
    alpha: float = 0.0,
) -> list[PeriodicOrbit]:
    """:func:`periodic_orbit` along ``speeds_mps``, each from the last as its guess (natural-parameter
    continuation); stops at the first speed where none is found."""
    orbits: list[PeriodicOrbit] = []
    for speed in np.asarray(speeds_mps, dtype=float):
        try:
            orbits.append(periodic_orbit(vehicle, float(speed), orbits[-1] if orbits else None, gain, alpha))
        except RuntimeError:
            break
    return orbits
