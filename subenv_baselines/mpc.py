"""Model-predictive depth control: linear MPC of both planes, re-linearised every period, solved with DAQP.

The reference a control engineer reaches for with saturated actuators: at every control period, plan the
plane angles over a horizon against the model, with the limits as constraints, apply the first, repeat.
See :class:`DepthMPC` for the formulation, why, and what it measured.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numba
import numpy as np

from subenv.dynamics import CONTROL_PERIOD_S, SUBSTEPS, ModelParams, derivatives, model_params, rk4
from subenv.envs.config import DEFAULT_ARGUMENTS, DEPTH_BAND_M, NOISE_STD, OBSERVATION_NAMES
from subenv.evaluation import SingleRowMixin, check_batch
from subenv.extras import require
from subenv.thesis import reference_length_ratio
from subenv.vehicles import Vehicle
from subenv_baselines._common import DEPTH_ERROR, HEAVE, PITCH, PITCH_RATE, SPEED

require("mpc", "the MPC baseline (subenv_baselines.mpc)", "daqp")
import daqp  # noqa: E402 (after require(), which names the extra to install when DAQP is missing)

__all__ = ["BLOCKS", "DepthMPC", "MPCWeights", "control_period", "discrete_jacobians"]

DEPTH, STERN, BOW = (
    OBSERVATION_NAMES.index(name) for name in ("depth_m", "stern_plane_rad", "bow_plane_rad")
)

N_X: Final = 4  # (theta, w, q, Z)
N_U: Final = 2  # (stern, bow) [rad]
N_D: Final = 2  # (heave force [N], pitch moment [N m]), derivatives' force and moment
BLOCKS: Final = (1, 1, 2, 4, 8, 8, 8, 8)
"""The plan's blocks [control periods] (move blocking): 40 periods, 20 s, with the planes held over
each block."""
_EPS: Final = np.array([1e-7, 1e-7, 1e-7, 1e-7, 1e-7, 1e-7, 1e-5, 1e-5])
"""Forward-difference steps of the discrete Jacobians: (theta, w, q, Z) [rad, m/s, rad/s, m], planes [rad],
force [N], moment [N m]. The truncation error is O(eps) against curvatures of order 1, the rounding error
1e-16 / eps: both about 1e-8 relative, far below what a QP's solution notices; central differences would
cost twice the evaluations (the Jacobians are most of a step's model time)."""


def control_period(
    params: ModelParams,
    state: np.ndarray,
    speed_mps: Any,
    planes_rad: np.ndarray,
    disturbance: np.ndarray,
    dt_s: float = CONTROL_PERIOD_S,
    substeps: int = SUBSTEPS,
) -> np.ndarray:
    """The state one control period on, as the environments integrate it: :func:`subenv.dynamics.rk4` of
    :func:`subenv.dynamics.derivatives` with the planes, the heave force and the pitch moment held (zero-order
    hold) and the speed constant.

    Parameters
    ----------
    state : ndarray, shape (..., 4)
        (theta, w, q, Z) [rad, m/s, rad/s, m].
    speed_mps : array_like, broadcast against ``state[..., 0]``
    planes_rad : ndarray, shape (..., 2)
        Applied (stern, bow) angles [rad].
    disturbance : ndarray, shape (..., 2)
        External heave force [N] and pitch moment [N m].
    """
    stern, bow = planes_rad[..., 0], planes_rad[..., 1]
    force, moment = disturbance[..., 0], disturbance[..., 1]

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        return derivatives(x, speed_mps, stern, bow, params, force, moment)

    return rk4(rhs, 0.0, np.asarray(state, dtype=float), dt_s, substeps)


def discrete_jacobians(
    params: ModelParams,
    points: np.ndarray,
    speed_mps: np.ndarray,
    dt_s: float = CONTROL_PERIOD_S,
    substeps: int = SUBSTEPS,
) -> tuple[np.ndarray, np.ndarray]:
    """The discrete map x+ = F(x, u, d) of :func:`control_period` and its Jacobian at every point, by forward
    differences of the one model (no second copy of the equations).

    Parameters
    ----------
    points : ndarray, shape (..., 8)
        (theta, w, q, Z, stern, bow, force, moment) at which to linearise.
    speed_mps : ndarray, broadcast against ``points[..., 0]``

    Returns
    -------
    F : ndarray, shape (..., 4)
        The map at the points.
    J : ndarray, shape (..., 4, 8)
        dF / d(x, u, d): columns 0-3 the state (A), 4-5 the planes (B), 6-7 the disturbance.
    """
    speed = np.asarray(speed_mps, dtype=float)[..., None]
    perturbed = _perturbed(points)
    out = control_period(
        params,
        perturbed[..., :N_X],
        speed,
        perturbed[..., N_X : N_X + N_U],
        perturbed[..., N_X + N_U :],
        dt_s,
        substeps,
    )
    return _differences(out)


def _perturbed(points: np.ndarray) -> np.ndarray:
    """Each point, then the point with each of its 8 coordinates moved by its step: shape (..., 9, 8)."""
    n = points.shape[-1]
    perturbed = np.repeat(points[..., None, :], 1 + n, axis=-2)
    k = np.arange(n)
    perturbed[..., 1 + k, k] += _EPS
    return perturbed


def _differences(out: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """F and its Jacobian (..., 4, 8) from the map at :func:`_perturbed`'s points (..., 9, 4)."""
    J = (out[..., 1:, :] - out[..., :1, :]) / _EPS[:, None]
    return out[..., 0, :], np.swapaxes(J, -1, -2)


@dataclass(frozen=True)
class MPCWeights:
    """Stage cost, in SI units: over the horizon,
    ``depth (Z - Z_cmd)^2 + pitch theta^2 + heave w^2 + pitch_rate q^2`` at the QP's stages, each times the
    periods it stands for, and the last times ``terminal``; ``plane u^2`` every period and
    ``move (u_j - u_{j-1})^2`` at every change of the planes; and ``slack_linear s + slack_quadratic s^2``
    for each family of soft constraints (pitch, depth), s its largest violation (an exact penalty: the
    constraints hold whenever they can)."""

    depth: float = 1.0
    pitch: float = 20.0
    heave: float = 20.0
    pitch_rate: float = 200.0
    plane: float = 1.0
    move: float = 20.0
    terminal: float = 10.0
    slack_linear: float = 1e3
    slack_quadratic: float = 1e4


@dataclass(frozen=True)
class ObserverNoise:
    """Standard deviations of the disturbance observer's Kalman filter (per control period)."""

    disturbance: tuple[float, float] = (0.3, 0.3)  # [N], [N m]: a random walk
    measurement: tuple[float, float] = (NOISE_STD["heave_mps"], NOISE_STD["pitch_rate_radps"])  # the sensors'
    initial_disturbance: tuple[float, float] = (20.0, 30.0)


class DepthMPC(SingleRowMixin):
    """Linear MPC of both planes, re-linearised at the measured state every period.

    **Model.** The one right-hand side, :func:`subenv.dynamics.derivatives` (Riedel 1993 eqs 2.38-2.43, hull
    cross-flow drag included), integrated over a control period exactly as the environments do
    (:func:`control_period`: :func:`subenv.dynamics.rk4`, the planes and the external heave force and pitch
    moment held, 2 RK4 steps of 0.25 s): at a constant speed its one-period prediction is the environment's
    step bit for bit (``tests/baselines/test_mpc.py``). The speed is taken as constant over the horizon at its
    measured value (a deceleration is not known in advance; the next period's measurement corrects it).

    **Linearisation, every period.** The map F(x, u, d) one period on and its Jacobian (A, B, B_d) at the
    measured state, the planes held and the disturbance estimate, by forward differences of that one model
    (:func:`discrete_jacobians`: no second copy of the equations, no continuous model discretised a second
    way), in the same batched evaluation as the observer's prediction. The plan then predicts with
    x+ = A x + B u + c, c = F - A x - B u: exact over the first period at the held planes, first order in the
    planes' change, and re-linearised at the next measured state every period.

    **QP** (condensed, move-blocked; DAQP, a dual active-set solver for small dense QPs). The plan holds the
    planes over blocks of :data:`BLOCKS` = 1, 1, 2, 4, 8, 8, 8, 8 periods (N = 40 periods, 20 s): 16 plane
    angles and two slacks are the variables, the states are eliminated through the linear model
    (:class:`_CondensedQP`, compiled). Hard: |u| <= plane limit, and with a rate limit the first block within
    rate * dt of the applied planes and each later block within rate * dt * (the block before's length) of it.
    Soft, with an exact penalty (linear + quadratic slack, one slack each over the horizon):
    |theta| <= half the environment's pitch limit, the ordered depth +- the depth band less 5 m, and depth >=
    the hull's half breadth (where it broaches) + 0.25 m. Cost (:class:`MPCWeights`): depth error, pitch,
    heave, pitch rate and plane angle measured from a steady-state target, plus the plane moves; the last
    stage's state terms weighted 10x. The states' cost and the soft constraints are taken at 14 of the 40
    stages, each weighted by the periods it stands for (:class:`_CondensedQP`).

    **Offset-free.** A disturbance d = (heave force [N], pitch moment [N m]) enters the model where
    ``derivatives`` takes external loads; it is estimated by a Kalman filter from what the last period's
    prediction missed in heave and pitch rate (:meth:`_observe`): excess buoyancy (surface suction) is a
    heave force (W - B) cos(theta), a ballast offset a pitch moment -x_GB W cos(theta) (eq. 2.39), and both
    are estimated to 0.1% (tests). The target (:meth:`_target`) is the steady state at the ordered depth of
    the model with d, restricted to the plane limits and the pitch bound: on it the linearisation is exact,
    so the closed loop settles at the ordered depth (the depth error goes to < 1 mm under a ballast offset,
    and stays off depth without the estimate: tests).

    **Both planes.** ``control="independent"``: the bow/stern allocation is the optimiser's, every period.
    With one command the depth mode is uncontrollable at u_cr(alpha) (eq. 3.9, Fig. 3-14); with two
    independent planes it is controllable at every speed, so a linear model exists through the critical
    speed and below it the plan carries the reversed plane effect without any scheduling.

    **Why this formulation** (measured on this 2-core machine). The first version was linear time-varying MPC
    by real-time iteration: re-linearised at all 40 stages of the shifted last plan (2,880 right-hand sides
    per period), a sparse QP of 320 variables and 558 rows in OSQP, set up and refactored each period. It
    took 1.0-1.6 ms per episode-step (QP median 0.5 ms) and the default suite 614 s. This one linearises
    once per period (72 right-hand sides), condenses onto 18 variables and 56 rows, and DAQP solves that in
    0.02 ms (median; 0.08 ms at the 99th percentile, Python's call included): 0.07 ms per episode-step in all,
    the default suite's 700 episodes in 47-57 s (two runs). It won and lost the same episodes on the default
    suite at 100 episodes per scenario, and in one run of ``benchmarks/mpc.py --scenarios
    PeriscopeDepthWaves,BallastOffset --episodes 20 --controllers mpc`` the old one took 63.1 s and this one
    6.1 s, with the same successes and plane RMS within 0.002 rad. So ``./dev run``, with the MPC in its
    comparison, took 93 s against 55 s without (1.69x; ``farm-bench``, two pairs).
    The dynamics are mildly nonlinear at the pitches the soft bound allows (sin, cos, w|w| drag) and slow
    (time constants of 10 s and more): one linearisation per period, renewed at every measurement, tracks
    them as well as 40 did. A CasADi/IPOPT NMPC would need the equations again in CasADi's symbols (a second
    copy of the physics) or a callback around ``derivatives`` without exact derivatives; it was not built,
    so not measured: with this MPC losing only one episode that has a trim (below), there is little for it
    to win.

    **Measured** (``benchmarks/mpc.py --episodes 100``: default suite, seeds 10000-10099, against
    ``reversal_aware`` on the same episodes; 95% Wilson intervals): 100% [96, 100] on Nominal, LowSpeed,
    NearCritical, SpeedTransient, PeriscopeDepth and PeriscopeDepthWaves, as ``reversal_aware``;
    BallastOffset 89% [81, 94] against 87% [79, 92] (89/90 winnable against 87/90; the ten others have no
    depth-holding trim within the plane limits, :func:`subenv.analysis.winnable`; the winnable loss, seed
    10021, ends 0.52 m off depth with the planes at their limit, still closing). Plane RMS: less than
    ``reversal_aware`` below and near the critical speed (0.081 against 0.119 rad LowSpeed, 0.071 against
    0.095 NearCritical) and in the head sea (0.062 against 0.162: it plans through the waves' forcing
    instead of answering it), more at design speed (0.044 against 0.035) and in the transient (0.060
    against 0.054), the same at periscope depth in calm water (0.030 against 0.029) and with a ballast
    offset (0.262 both).

    On the Randomized suite (sensor noise, a 2 N heave-force disturbance, z_GB and C_D drawn; 40 episodes,
    ``benchmarks/mpc.py --suite randomized --episodes 40``) 90% [77, 96] against 82% [68, 91] for
    ``reversal_aware``.

    It knows what the other controllers know: the observation (its measured state; the planes it applied),
    the design vehicle at reset, and the environment's limits as constructor arguments (defaults: the
    environment's). The planes' rate limit is not in the reset ``info``: the harness tells it the
    environment's settings before each scenario (:meth:`inform`; ``mpc:uninformed`` runs it untold, on its
    constructor's values), and a caller running it elsewhere passes ``plane_rate_limit_radps``.
    """

    name = "mpc"
    control = "independent"
    alpha = 0.0

    def __init__(
        self,
        blocks: Sequence[int] = BLOCKS,
        weights: MPCWeights = MPCWeights(),
        noise: ObserverNoise = ObserverNoise(),
        dt_s: float = CONTROL_PERIOD_S,
        substeps: int = SUBSTEPS,
        plane_rate_limit_radps: float | None = DEFAULT_ARGUMENTS["plane_rate_limit_radps"],
        max_pitch_rad: float = DEFAULT_ARGUMENTS["max_pitch_rad"],
        max_depth_error_m: float | None = DEFAULT_ARGUMENTS["max_depth_error_m"],
        pitch_fraction: float = 0.5,
        depth_band_margin_m: float = 5.0,
        surface_margin_m: float = 0.25,
    ) -> None:
        blocks = tuple(blocks)
        if not (
            blocks
            and all(isinstance(b, int) and not isinstance(b, bool) and b >= 1 for b in blocks)
            and blocks[0] == 1
            and sum(blocks) >= 2
        ):
            raise ValueError(
                f"blocks={blocks!r} is invalid: must be integers >= 1 (control periods), the first 1, "
                "at least 2 periods in all"
            )
        if plane_rate_limit_radps is not None and not plane_rate_limit_radps > 0:
            raise ValueError(
                f"plane_rate_limit_radps={plane_rate_limit_radps!r} is invalid: must be None or > 0"
            )
        self.blocks = blocks
        self.weights, self.noise = weights, noise
        self.dt_s, self.substeps = dt_s, substeps
        self.plane_rate_limit_radps = plane_rate_limit_radps
        self.pitch_fraction = pitch_fraction
        self.pitch_bound_rad = pitch_fraction * max_pitch_rad
        self.max_depth_error_m, self.depth_band_margin_m = max_depth_error_m, depth_band_margin_m
        self.band_m = math.nan  # (the environment's depth band less the margin: set with the vehicle)
        self.surface_margin_m = surface_margin_m
        self._qp = _CondensedQP(blocks, weights)
        self._vehicle: Vehicle | None = None
        self._params: ModelParams | None = None
        self.solve_times_s: list[float] = []
        """Wall time of every QP solve (DAQP) [s], one per episode per control period."""

    @property
    def horizon(self) -> int:
        """The plan's length [control periods]: the sum of :attr:`blocks`."""
        return sum(self.blocks)

    # --- the model ------------------------------------------------------------------------------
    def predict(
        self, state: np.ndarray, planes_rad: np.ndarray, speed_mps: Any, disturbance: np.ndarray | None = None
    ) -> np.ndarray:
        """The state one control period on, as the controller predicts it (:func:`control_period` of the
        design vehicle)."""
        if self._params is None:
            raise RuntimeError("call reset() or reset_batch() first")
        d = np.zeros(np.shape(planes_rad)) if disturbance is None else np.asarray(disturbance, dtype=float)
        return control_period(
            self._params, state, speed_mps, np.asarray(planes_rad, dtype=float), d, self.dt_s, self.substeps
        )

    @property
    def disturbance(self) -> np.ndarray:
        """The disturbance estimate of every episode, (heave force [N], pitch moment [N m]): shape (N, 2)."""
        return self._d.copy()

    # --- the protocol -------------------------------------------------------------------------------
    def inform(self, settings: Mapping[str, Any]) -> None:
        """Take the environment's limits and period (the harness's
        :class:`~subenv.evaluation.controller.InformedController` hook): ``plane_rate_limit_radps``,
        ``max_pitch_rad``, ``max_depth_error_m``, ``dt`` and ``substeps``, as the constructor takes them."""
        self.dt_s, self.substeps = float(settings["dt"]), int(settings["substeps"])
        self.plane_rate_limit_radps = settings["plane_rate_limit_radps"]
        self.pitch_bound_rad = self.pitch_fraction * float(settings["max_pitch_rad"])
        self.max_depth_error_m = settings["max_depth_error_m"]
        self._vehicle = None  # (the depth band is set again with the vehicle at the next reset)

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Take the design model and limits of ``vehicle`` (once per vehicle), and start one observer per
        episode of ``infos``: no disturbance estimated yet, no planes applied yet."""
        if vehicle is not self._vehicle:
            self._params = model_params(vehicle)
            self._limit = vehicle.planes.limit_rad
            self._surface_m = 0.5 * max(vehicle.hull.breadth_m) + self.surface_margin_m
            # None: the environments' default band, Froude-scaled to the vehicle as theirs is.
            band = (
                DEPTH_BAND_M * reference_length_ratio(vehicle)
                if self.max_depth_error_m is None
                else self.max_depth_error_m
            )
            self.band_m = band - self.depth_band_margin_m
            self._vehicle = vehicle
        n = self._n = len(infos)
        self._y = np.zeros((n, N_X))  # the last measured state
        self._d = np.zeros((n, N_D))  # the disturbance estimate
        self._P = np.repeat(np.diag(np.square(self.noise.initial_disturbance))[None], n, axis=0)
        self._planes = np.full((n, N_U), np.nan)  # applied (our last command); nan: none yet
        self._sensitivity = np.zeros((n, N_X, N_D))  # dF/dd at the last linearisation, for the observer

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The normalised (stern, bow) commands of every episode, shape (N, 2): the first move of its plan.

        Each row updates its disturbance estimate from what the last period's prediction missed,
        re-linearises at its measured state and solves its QP; a row whose QP has no usable solution
        holds its planes.
        """
        if self._params is None:
            raise RuntimeError("call reset() or reset_batch() first")
        obs = check_batch(observations, self._n).astype(float)
        y = np.stack([obs[:, PITCH], obs[:, HEAVE], obs[:, PITCH_RATE], obs[:, DEPTH]], axis=1)
        speed = obs[:, SPEED]
        command = obs[:, DEPTH] - obs[:, DEPTH_ERROR]
        first = np.isnan(self._planes[:, 0])
        planes = np.where(first[:, None], obs[:, [STERN, BOW]], self._planes)
        # One evaluation of the model (the rk4 of derivatives over a period, batched) for the observer and the
        # linearisation: the last period's prediction (y, planes and estimate of then), and the map one period
        # on from the measured state with the planes held and the estimate, and its slopes.
        last = np.flatnonzero(~first)
        points = _perturbed(np.concatenate([y, planes, self._d], axis=1)).reshape(-1, N_X + N_U + N_D)
        points = np.concatenate(
            [points, np.concatenate([self._y[last], self._planes[last], self._d[last]], axis=1)]
        )
        out = control_period(
            self._params,
            points[:, :N_X],
            np.r_[np.repeat(speed, 1 + N_X + N_U + N_D), speed[last]],
            points[:, N_X : N_X + N_U],
            points[:, N_X + N_U :],
            self.dt_s,
            self.substeps,
        )
        F, J = _differences(out[: len(out) - len(last)].reshape(self._n, 1 + N_X + N_U + N_D, N_X))
        change = self._observe(y, out[len(out) - len(last) :], last)
        A, B, Bd = J[:, :, :N_X], J[:, :, N_X : N_X + N_U], J[:, :, N_X + N_U :]
        self._sensitivity = Bd
        # x+ = A x + B u + c: exact at (y, planes) with the estimate before this period's update, which moves
        # the map by Bd times its change.
        c = F + _apply(Bd, change) - _apply(A, y) - _apply(B, planes)
        x_s, u_s = self._target(A, B, c, command)
        move = np.inf if self.plane_rate_limit_radps is None else self.plane_rate_limit_radps * self.dt_s
        margin = 1e-7  # inside the limits by more than the float32 action's rounding
        lim = self._limit - margin
        first_low = np.maximum(-lim, planes - move + margin)
        first_high = np.minimum(lim, planes + move - margin)
        low_depth = np.maximum(command - self.band_m, self._surface_m)
        qp = self._qp.build(
            A,
            B,
            c,
            y,
            x_s,
            u_s,
            planes,
            lim,
            first_low,
            first_high,
            move - margin,
            self.pitch_bound_rad,
            command + self.band_m,
            low_depth,
        )
        u0, solved = np.empty((self._n, N_U)), np.empty(self._n, dtype=bool)
        times = self.solve_times_s
        for i in range(self._n):
            start = time.perf_counter()
            x, _, exitflag, _ = daqp.solve(qp.H[i], qp.f[i], qp.C[i], qp.upper[i], qp.lower[i])
            times.append(time.perf_counter() - start)
            u0[i], solved[i] = x[:N_U], exitflag >= 1
        # A solve without a usable solution (DAQP's exit flag < 1: infeasible, cycling, iteration limit) holds
        # the planes.
        u0 = np.where((solved & np.all(np.isfinite(u0), axis=1))[:, None], u0, planes)
        u0 = np.clip(u0, first_low, first_high)
        self._planes = u0
        return np.clip(u0 / self._limit, -1.0, 1.0).astype(np.float32)

    # --- the observer -----------------------------------------------------------------------------
    def _observe(self, y: np.ndarray, predicted: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Estimate the disturbance (heave force, pitch moment) from what the last period's prediction
        missed, in ``rows`` (those with a last period; ``predicted`` their states); the change of the
        estimate, every row.

        A Kalman filter on d alone, a random walk, measured through the heave and pitch-rate residuals
        e = y_k - F(y_{k-1}, u_{k-1}, d_hat) ~ B_d (d - d_hat) + noise (B_d the (w, q) rows of dF/dd). In a
        steady state its gain (2 x 2, invertible) makes those residuals 0, so the model with d_hat holds the
        measured state still with the planes that hold the plant there: the MPC then has no reason to stop
        short of the ordered depth (offset-free; theta and Z follow from the exact kinematics). Each row's
        arithmetic on its own (the same bits for any batch).
        """
        noise = self.noise
        change = np.zeros_like(self._d)
        if rows.size:
            H = self._sensitivity[rows, 1:3]
            P = self._P[rows] + np.diag(np.square(noise.disturbance))
            S = H @ P @ np.swapaxes(H, 1, 2) + np.diag(np.square(noise.measurement))
            K = np.swapaxes(np.linalg.solve(S, H @ P), 1, 2)
            change[rows] = _apply(K, y[rows, 1:3] - predicted[:, 1:3])
            self._d[rows] += change[rows]
            self._P[rows] = P - K @ H @ P
        self._y = y.copy()
        return change

    # --- the steady-state target --------------------------------------------------------------------
    def _target(
        self, A: np.ndarray, B: np.ndarray, c: np.ndarray, command: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each row's steady state at the ordered depth, which the cost's state and plane terms measure from.

        The linearised map x+ = A x + B u + c (at the measured state) held still, x = x+, with Z at the
        ordered depth: 4 equations in v = (theta, w, q, stern, bow), a line of steady states (the bow/stern
        allocation is free). On it, the point of least weighted size with the planes within their limit and
        the pitch within the soft bound (where the line crosses that box; else the point nearest to it in
        plane angle). At a steady state the linearisation is exact, so the cost's minimum is the plant's
        steady state at the ordered depth: the state and plane weights leave no offset (measured from 0, a
        finite horizon trades depth error for plane angle), and the target is one the planes can hold (an
        unconstrained one can lie beyond the limit, where the planes then stay pinned while the boat drifts).
        """
        w = self.weights
        scale = 1.0 / np.sqrt([w.pitch, w.heave, w.pitch_rate, w.plane, w.plane])
        I_A = np.eye(N_X) - A
        # One SVD of the scaled system: its least-norm solution, and the line's direction (its null vector).
        U, S, Vt = np.linalg.svd(np.concatenate([I_A[:, :, :3], -B], axis=2) * scale)
        S = np.where(S > 1e-12 * S[:, :1], S, np.inf)  # (a rank-deficient direction contributes nothing)
        rhs = c - I_A[:, :, 3] * command[:, None]
        v0 = scale * _apply(np.swapaxes(Vt[:, :N_X], 1, 2), _apply(np.swapaxes(U, 1, 2), rhs) / S)
        n = scale * Vt[:, -1]  # v0 + t n
        bound = np.array([self.pitch_bound_rad, self._limit, self._limit])
        at, dn = v0[:, [0, 3, 4]], n[:, [0, 3, 4]]
        free = dn == 0
        with np.errstate(divide="ignore", invalid="ignore"):
            ends = np.sort(np.stack([(-bound - at) / dn, (bound - at) / dn]), axis=0)
            low = np.max(np.where(free, -np.inf, ends[0]), axis=1)
            high = np.min(np.where(free, np.inf, ends[1]), axis=1)
            inside = (low <= high) & np.all(~free | (np.abs(at) <= bound), axis=1)
            # No steady state inside the box on this line: the one needing the least plane angle, of t = 0 and
            # the two where the planes' angles are equal in size.
            candidates = np.stack(
                [np.zeros(len(v0))]
                + [-(v0[:, 3] - sign * v0[:, 4]) / (n[:, 3] - sign * n[:, 4]) for sign in (1.0, -1.0)],
                axis=1,
            )
        candidates = np.where(np.isfinite(candidates), candidates, 0.0)
        angle = np.max(np.abs(v0[:, None, 3:] + candidates[:, :, None] * n[:, None, 3:]), axis=2)
        nearest = candidates[np.arange(len(v0)), np.argmin(angle, axis=1)]
        t = np.where(inside, np.minimum(np.maximum(0.0, low), high), nearest)
        v = v0 + t[:, None] * n
        return np.concatenate([v[:, :3], command[:, None]], axis=1), v[:, 3:]


def _apply(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    """M x, row by row: (n, a, b) times (n, b) -> (n, a)."""
    return (M @ x[:, :, None])[:, :, 0]


@dataclass(frozen=True)
class _Rows:
    """The condensed QPs of a batch, one row each, in DAQP's form: min 1/2 v' H v + f' v subject to
    lower <= (v, C v) <= upper (the first entries bound v itself)."""

    H: np.ndarray
    f: np.ndarray
    C: np.ndarray
    upper: np.ndarray
    lower: np.ndarray


class _CondensedQP:
    """The QP over the plan's blocks: variables v = (U_0 .. U_{M-1}, s_pitch, s_depth), U_j the (stern, bow)
    angles [rad] held over block j, s the soft constraints' slacks (one each over the horizon); the states
    eliminated (condensed) through the linear model, x_k = f_k + S_k v.

    The states' cost and the soft constraints are taken at :attr:`stages`: every period of the first blocks,
    then every half block, each weighted by the periods it stands for (a quadrature of the cost over the 40
    periods). The state moves smoothly (its time constants are 10 s and more, the period 0.5 s), and every
    stage costs the condensing and the solver's set-up (DAQP's grows with the constraint rows): with 14
    stages instead of 40 the default suite's MPC took 68 s instead of 85 s (before the condensing was
    compiled), with the same episodes won.
    """

    def __init__(self, blocks: tuple[int, ...], weights: MPCWeights) -> None:
        self.weights = weights
        M = self.M = len(blocks)
        self.nv = N_U * M + 2
        # The stages: within block j (length L) every max(1, L // 2) periods, so each lies in one block.
        self.steps: list[tuple[int, int]] = []  # (block, periods since the stage before)
        for j, length in enumerate(blocks):
            step = max(1, length // 2)
            self.steps += [(j, step)] * (length // step) + ([(j, length % step)] if length % step else [])
        self.stages = np.cumsum([step for _, step in self.steps])
        self.step_blocks = np.array([j for j, _ in self.steps], dtype=np.int64)
        self.step_lengths = np.array([step for _, step in self.steps], dtype=np.int64)
        w = weights
        stage_w = np.outer([step for _, step in self.steps], [w.pitch, w.heave, w.pitch_rate, w.depth])
        stage_w[-1] *= w.terminal
        self.sqrt_state_weights = np.sqrt(stage_w)  # (stages, 4)
        # The plane and move terms and the slacks' quadratic term, constant: 2 x their Hessian.
        R = np.zeros((self.nv, self.nv))
        for j, length in enumerate(blocks):
            for a in range(N_U):
                R[N_U * j + a, N_U * j + a] += 2.0 * w.plane * length + 2.0 * w.move
                if j > 0:  # (U_j - U_{j-1})^2; for j = 0 (U_0 - applied)^2, whose cross term is in f
                    R[N_U * (j - 1) + a, N_U * (j - 1) + a] += 2.0 * w.move
                    R[N_U * j + a, N_U * (j - 1) + a] -= 2.0 * w.move
                    R[N_U * (j - 1) + a, N_U * j + a] -= 2.0 * w.move
        R[-2, -2] = R[-1, -1] = 2.0 * w.slack_quadratic
        self.R = R
        self.lengths = np.asarray(blocks, dtype=float)

    def build(
        self,
        A: np.ndarray,
        B: np.ndarray,
        c: np.ndarray,
        y: np.ndarray,
        x_s: np.ndarray,
        u_s: np.ndarray,
        planes: np.ndarray,
        limit: float,
        first_low: np.ndarray,
        first_high: np.ndarray,
        move: float,
        pitch_bound: float,
        depth_high: np.ndarray,
        depth_low: np.ndarray,
    ) -> _Rows:
        n, M, nv, K = len(y), self.M, self.nv, len(self.stages)
        w = self.weights
        moves = np.isfinite(move) and M > 1
        rows = nv + 4 * K + (N_U * (M - 1) if moves else 0)
        H, g = np.empty((n, nv, nv)), np.empty((n, nv))
        C, upper, lower = np.zeros((n, rows - nv, nv)), np.empty((n, rows)), np.empty((n, rows))
        _condense(
            A,
            B,
            c,
            y,
            x_s,
            u_s,
            planes,
            self.step_blocks,
            self.step_lengths,
            self.sqrt_state_weights,
            self.lengths,
            self.R,
            w.plane,
            w.move,
            w.slack_linear,
            limit,
            first_low,
            first_high,
            move if moves else -1.0,
            pitch_bound,
            depth_high,
            depth_low,
            H,
            g,
            C,
            upper,
            lower,
        )
        return _Rows(H, g, C, upper, lower)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _condense(
    A: np.ndarray,
    B: np.ndarray,
    c: np.ndarray,
    y: np.ndarray,
    x_s: np.ndarray,
    u_s: np.ndarray,
    planes: np.ndarray,
    step_blocks: np.ndarray,
    step_lengths: np.ndarray,
    sqrt_w: np.ndarray,
    lengths: np.ndarray,
    R: np.ndarray,
    w_plane: float,
    w_move: float,
    slack_linear: float,
    limit: float,
    first_low: np.ndarray,
    first_high: np.ndarray,
    move: float,
    pitch_bound: float,
    depth_high: np.ndarray,
    depth_low: np.ndarray,
    H: np.ndarray,
    g: np.ndarray,
    C: np.ndarray,
    upper: np.ndarray,
    lower: np.ndarray,
) -> None:  # pragma: no cover (compiled)
    """Each row's condensed QP (:class:`_CondensedQP`) into H, g, C, upper, lower: the states at the stages
    x = f + S v from x_0 = y through x -> A^L x + (sum_{i<L} A^i)(B U_j + c) over a stage of L periods in
    block j, the state cost sum (x - x_s)' W (x - x_s) over them, and the rows. A loop per row, so a row's
    arithmetic is its own (the same bits in any batch)."""
    n, K, nv = y.shape[0], step_lengths.shape[0], H.shape[1]
    M = lengths.shape[0]
    max_step = np.max(step_lengths)
    P = np.empty((max_step + 1, N_X, N_X))  # A^L
    T = np.empty((max_step + 1, N_X, N_X))  # sum_{i<L} A^i
    S = np.empty((N_X, nv))
    S_next = np.empty((N_X, nv))
    f = np.empty(N_X)
    f_next = np.empty(N_X)
    for i in range(n):
        P[0], T[0] = np.eye(N_X), 0.0
        for L in range(1, max_step + 1):
            for r in range(N_X):
                for k in range(N_X):
                    P[L, r, k] = (
                        A[i, r, 0] * P[L - 1, 0, k]
                        + A[i, r, 1] * P[L - 1, 1, k]
                        + A[i, r, 2] * P[L - 1, 2, k]
                        + A[i, r, 3] * P[L - 1, 3, k]
                    )
                    T[L, r, k] = T[L - 1, r, k] + P[L - 1, r, k]
        H[i] = R
        g[i] = 0.0
        S[:] = 0.0
        f[:] = y[i]
        for s in range(K):
            L, j = step_lengths[s], step_blocks[s]
            for r in range(N_X):
                for a in range(nv):
                    S_next[r, a] = (
                        P[L, r, 0] * S[0, a]
                        + P[L, r, 1] * S[1, a]
                        + P[L, r, 2] * S[2, a]
                        + P[L, r, 3] * S[3, a]
                    )
                for a in range(N_U):
                    S_next[r, N_U * j + a] += (
                        T[L, r, 0] * B[i, 0, a]
                        + T[L, r, 1] * B[i, 1, a]
                        + T[L, r, 2] * B[i, 2, a]
                        + T[L, r, 3] * B[i, 3, a]
                    )
                f_next[r] = (
                    P[L, r, 0] * f[0]
                    + P[L, r, 1] * f[1]
                    + P[L, r, 2] * f[2]
                    + P[L, r, 3] * f[3]
                    + T[L, r, 0] * c[i, 0]
                    + T[L, r, 1] * c[i, 1]
                    + T[L, r, 2] * c[i, 2]
                    + T[L, r, 3] * c[i, 3]
                )
            S[:], f[:] = S_next, f_next
            for r in range(N_X):  # the state cost: H += 2 S' W S, g += 2 S' W (f - x_s)
                wr = sqrt_w[s, r] * sqrt_w[s, r]
                e = 2.0 * wr * (f[r] - x_s[i, r])
                for a in range(nv):
                    sa = S[r, a]
                    if sa != 0.0:
                        g[i, a] += e * sa
                        H[i, a, a] += 2.0 * wr * sa * sa
                        for b in range(a + 1, nv):  # (symmetric to the last bit)
                            h = 2.0 * wr * sa * S[r, b]
                            H[i, a, b] += h
                            H[i, b, a] += h
            # Soft rows: pitch - s_p <= bound, pitch + s_p >= -bound, depth - s_d <= high, depth + s_d >= low.
            for q, (state, slack, high, low) in enumerate(
                ((0, nv - 2, pitch_bound, -pitch_bound), (3, nv - 1, depth_high[i], depth_low[i]))
            ):
                for side in range(2):
                    row = (2 * q + side) * K + s
                    C[i, row, :] = S[state]
                    C[i, row, slack] = 1.0 if side else -1.0
                    upper[i, nv + row] = np.inf if side else high - f[state]
                    lower[i, nv + row] = low - f[state] if side else -np.inf
        # The plane and move terms: w_plane L_j |U_j - u_s|^2 and w_move |U_0 - applied|^2 (the rest is in R).
        for j in range(M):
            for a in range(N_U):
                g[i, N_U * j + a] -= 2.0 * w_plane * lengths[j] * u_s[i, a]
        for a in range(N_U):
            g[i, a] -= 2.0 * w_move * planes[i, a]
        g[i, nv - 2] += slack_linear
        g[i, nv - 1] += slack_linear
        # Simple bounds: the planes within the limit, the first block within the rate limit of the applied
        # planes, the slacks >= 0; then the moves between blocks within the rate times the block before.
        for a in range(N_U * M):
            upper[i, a], lower[i, a] = limit, -limit
        for a in range(N_U):
            upper[i, a], lower[i, a] = first_high[i, a], first_low[i, a]
        upper[i, nv - 2] = upper[i, nv - 1] = np.inf
        lower[i, nv - 2] = lower[i, nv - 1] = 0.0
        if move >= 0.0:
            for j in range(1, M):
                for a in range(N_U):
                    row = 4 * K + N_U * (j - 1) + a
                    C[i, row, N_U * j + a], C[i, row, N_U * (j - 1) + a] = 1.0, -1.0
                    upper[i, nv + row], lower[i, nv + row] = move * lengths[j - 1], -move * lengths[j - 1]
