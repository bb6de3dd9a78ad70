"""Model-predictive depth control: linear time-varying MPC by real-time iteration, solved with OSQP.

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

import numpy as np
import scipy.sparse as sp

from subenv.dynamics import CONTROL_PERIOD_S, SUBSTEPS, ModelParams, derivatives, model_params, rk4
from subenv.envs.config import DEPTH_BAND_M, NOISE_STD, OBSERVATION_NAMES, DivePlaneConfig
from subenv.evaluation import SingleRowMixin, check_batch
from subenv.extras import require
from subenv.thesis import reference_length_ratio
from subenv.vehicles import Vehicle
from subenv_baselines._common import DEPTH_ERROR, HEAVE, PITCH, PITCH_RATE, SPEED

require("mpc", "the MPC baseline (subenv_baselines.mpc)", "osqp")
import osqp

__all__ = ["DepthMPC", "MPCWeights", "control_period", "discrete_jacobians"]

DEPTH, STERN, BOW = (OBSERVATION_NAMES.index(name) for name in ("depth_m", "stern_plane_rad", "bow_plane_rad"))

N_X: Final = 4  # (theta, w, q, Z)
N_U: Final = 2  # (stern, bow) [rad]
N_D: Final = 2  # (heave force [N], pitch moment [N m]), derivatives' force and moment
_EPS: Final = np.array([1e-7, 1e-7, 1e-7, 1e-7, 1e-7, 1e-7, 1e-5, 1e-5])
"""Forward-difference steps of the discrete Jacobians: (theta, w, q, Z) [rad, m/s, rad/s, m], planes [rad],
force [N], moment [N m]. The truncation error is O(eps) against curvatures of order 1, the rounding error
1e-16 / eps: both about 1e-8 relative, far below what a QP's solution notices; central differences would
cost twice the evaluations (the Jacobians are most of a step's model time)."""


def control_period(params: ModelParams, state: np.ndarray, speed_mps: Any, planes_rad: np.ndarray,
                   disturbance: np.ndarray, dt_s: float = CONTROL_PERIOD_S, substeps: int = SUBSTEPS) -> np.ndarray:
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


def discrete_jacobians(params: ModelParams, points: np.ndarray, speed_mps: np.ndarray, dt_s: float = CONTROL_PERIOD_S,
                       substeps: int = SUBSTEPS) -> tuple[np.ndarray, np.ndarray]:
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
    n = points.shape[-1]
    perturbed = np.repeat(points[..., None, :], 1 + n, axis=-2)
    k = np.arange(n)
    perturbed[..., 1 + k, k] += _EPS
    speed = np.asarray(speed_mps, dtype=float)[..., None]
    out = control_period(params, perturbed[..., :N_X], speed, perturbed[..., N_X:N_X + N_U],
                         perturbed[..., N_X + N_U:], dt_s, substeps)
    J = (out[..., 1:, :] - out[..., :1, :]) / _EPS[:, None]
    return out[..., 0, :], np.swapaxes(J, -1, -2)


@dataclass(frozen=True)
class MPCWeights:
    """Stage cost, in SI units: sum over the horizon of
    ``depth (Z - Z_cmd)^2 + pitch theta^2 + heave w^2 + pitch_rate q^2 + plane u^2 + move (u_k - u_{k-1})^2``,
    the terminal stage's state terms times ``terminal``, and ``slack_linear s + slack_quadratic s^2`` per
    violated soft constraint (an exact penalty: the constraint holds whenever it can)."""

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


class _RowQP:
    """The QP of one episode, set up once and updated in place (the sparsity never changes).

    Variables z = (x_1 .. x_N, u_0 .. u_{N-1}, s_pitch_1 .. s_pitch_N, s_depth_1 .. s_depth_N).
    """

    def __init__(self, horizon: int, weights: MPCWeights, settings: Mapping[str, Any]) -> None:
        N = self.N = horizon
        nx, nu, ns = N_X * N, N_U * N, 2 * N
        self.ix, self.iu, self.isp, self.isd = 0, nx, nx + nu, nx + nu + N
        nz = self.nz = nx + nu + ns
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        r = 0

        def add(rr: np.ndarray, cc: np.ndarray, vv: np.ndarray) -> int:
            start = sum(v.size for v in vals)
            rows.append(np.ravel(rr)), cols.append(np.ravel(cc)), vals.append(np.ravel(vv).astype(float))
            return start

        # Dynamics, rows 0 .. 4N-1: x_{k+1} - A_k x_k - B_k u_k = c_k.
        ii, jj = np.meshgrid(np.arange(N_X), np.arange(N_X), indexing="ij")
        iu, ju = np.meshgrid(np.arange(N_X), np.arange(N_U), indexing="ij")
        self.a_pos = np.zeros((N, N_X, N_X), dtype=np.int64)
        self.b_pos = np.zeros((N, N_X, N_U), dtype=np.int64)
        for k in range(N):
            add(r + np.arange(N_X), self.ix + N_X * k + np.arange(N_X), np.ones(N_X))
            if k > 0:
                start = add(r + ii, self.ix + N_X * (k - 1) + jj, np.zeros((N_X, N_X)))
                self.a_pos[k] = start + np.arange(N_X * N_X).reshape(N_X, N_X)
            start = add(r + iu, self.iu + N_U * k + ju, np.zeros((N_X, N_U)))
            self.b_pos[k] = start + np.arange(N_X * N_U).reshape(N_X, N_U)
            r += N_X
        self.r_dyn = 0
        # Planes, 2N rows: their limits (and for k = 0 the rate limit from the applied planes).
        self.r_planes = r
        add(r + np.arange(nu), self.iu + np.arange(nu), np.ones(nu))
        r += nu
        # Moves, 2(N-1) rows: u_k - u_{k-1} within the rate limit.
        self.r_moves = r
        m = N_U * (N - 1)
        add(r + np.arange(m), self.iu + N_U + np.arange(m), np.ones(m))
        add(r + np.arange(m), self.iu + np.arange(m), -np.ones(m))
        r += m
        # Soft pitch and depth, 2N rows each: theta_k -/+ s_k, Z_k -/+ s_k.
        k = np.arange(N)
        self.r_soft = r
        for state, slack in ((0, self.isp), (3, self.isd)):
            add(r + 2 * k, self.ix + N_X * k + state, np.ones(N))
            add(r + 2 * k, slack + k, -np.ones(N))
            add(r + 2 * k + 1, self.ix + N_X * k + state, np.ones(N))
            add(r + 2 * k + 1, slack + k, np.ones(N))
            r += 2 * N
        # Slacks >= 0.
        self.r_slack = r
        add(r + np.arange(ns), self.isp + np.arange(ns), np.ones(ns))
        r += ns
        self.n_rows = r
        rr, cc, self.template = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
        order = sp.csc_matrix((np.arange(1, rr.size + 1, dtype=float), (rr, cc)), shape=(r, nz))
        order.sort_indices()
        self.perm = order.data.astype(np.int64) - 1  # CSC data position -> our value index
        self.A = order.copy()
        self.A.data = self.template[self.perm]

        # Cost (1/2) z' P z + q' z, constant P.
        w = weights
        state_w = np.array([w.pitch, w.heave, w.pitch_rate, w.depth])
        diag = np.zeros(nz)
        stage = np.tile(state_w, N)
        stage[-N_X:] *= w.terminal
        self.state_weights = stage
        diag[:nx] = 2.0 * stage
        diag[self.iu:self.iu + nu] = 2.0 * w.plane + 2.0 * w.move * np.r_[np.full(nu - N_U, 2.0), np.ones(N_U)]
        diag[self.isp:] = 2.0 * w.slack_quadratic
        moves = sp.diags(-2.0 * w.move * np.ones(nu - N_U), N_U, shape=(nu, nu))
        P = sp.diags(diag, format="csc") + sp.block_diag([sp.csc_matrix((nx, nx)), moves + moves.T,
                                                          sp.csc_matrix((ns, ns))], format="csc")
        self.q0 = np.zeros(nz)
        self.q0[self.isp:] = w.slack_linear
        self.move_weight = w.move
        self.solver = osqp.OSQP()
        self.solver.setup(sp.triu(P, format="csc"), self.q0.copy(), self.A, -np.inf * np.ones(r), np.inf * np.ones(r),
                          **settings)
        self.z: np.ndarray | None = None
        self.y: np.ndarray | None = None

    def values(self, A: np.ndarray, B: np.ndarray) -> np.ndarray:
        """The constraint matrix's data (CSC order) with the dynamics' -A_k (k >= 1) and -B_k."""
        v = self.template.copy()
        v[self.a_pos[1:]] = -A[1:]
        v[self.b_pos] = -B
        return v[self.perm]


class DepthMPC(SingleRowMixin):
    """Linear time-varying MPC of both planes, re-linearised along the predicted trajectory every period.

    **Model.** The one right-hand side, :func:`subenv.dynamics.derivatives` (Riedel 1993 eqs 2.38-2.43, hull
    cross-flow drag included), integrated over a control period exactly as the environments do
    (:func:`control_period`: :func:`subenv.dynamics.rk4`, the planes and the external heave force and pitch
    moment held, 2 RK4 steps of 0.25 s): at a constant speed its one-period prediction is the environment's
    step bit for bit (``tests/baselines/test_mpc.py``). The speed is taken as constant over the horizon at its
    measured value (a deceleration is not known in advance; the next period's measurement corrects it).
    The QP's matrices are the Jacobians of that discrete map by forward differences
    (:func:`discrete_jacobians`), so there is no second copy of the equations, and no continuous linear
    model discretised a second way.

    **Real-time iteration (Diehl's RTI, multiple shooting).** Each period the last plan, shifted by one
    period, is the trajectory (x_k, u_k), k = 0 .. N-1, to linearise along, with x_0 the measured state; the
    map F(x, u, d) and its Jacobians at all N points come from one batched evaluation, and
    x_{k+1} = A_k x_k + B_k u_k + c_k (c_k = F - A_k x_k - B_k u_k, the defect) are the QP's equality
    constraints: one QP per period, no sequential roll-out. At an episode's first period, with no plan, the
    measured state is held as the first guess and the QP is solved and re-linearised three times.

    **QP** (OSQP, sparse, set up once per episode and updated in place: only the Jacobian entries, the
    bounds and the linear cost change; warm-started from the shifted solution). Variables: the states
    x_1 .. x_N, the planes u_0 .. u_{N-1} (stern, bow), and slacks. Hard: |u_k| <= plane limit, and with a
    rate limit |u_k - u_{k-1}| <= rate * dt (from the applied planes at k = 0). Soft, with an exact penalty
    (linear + quadratic slack): |theta| <= half the environment's pitch limit, the ordered depth +- the depth
    band less 5 m, and depth >= the hull's half breadth (where it broaches) + 0.25 m. Cost
    (:class:`MPCWeights`): depth error, pitch, heave, pitch rate and plane angle measured from a steady-state
    target, plus the plane moves; the last stage's state terms weighted 10x. N = 40 periods (20 s).

    **Offset-free.** A disturbance d = (heave force [N], pitch moment [N m]) enters the model where
    ``derivatives`` takes external loads; it is estimated by a Kalman filter from what the last period's
    prediction missed in heave and pitch rate (:meth:`_observe`): excess buoyancy (surface suction) is a
    heave force (W - B) cos(theta), a ballast offset a pitch moment -x_GB W cos(theta) (eq. 2.39), and both
    are estimated to 0.1% (tests). The target (:meth:`_target`) is the steady state at the ordered depth of the
    model with d, restricted to the plane limits and the pitch bound: on it the linearisation is exact, so the
    closed loop settles at the ordered depth (the depth error goes to < 1 mm under a ballast offset, and stays
    off depth without the estimate: tests).

    **Both planes.** ``control="independent"``: the bow/stern allocation is the optimiser's, every period.
    With one command the depth mode is uncontrollable at u_cr(alpha) (eq. 3.9, Fig. 3-14); with two
    independent planes it is controllable at every speed, so a linear model exists through the critical
    speed and below it the plan carries the reversed plane effect without any scheduling.

    **Why this formulation** (and not full nonlinear MPC): the dynamics are mildly nonlinear at the pitches
    the soft bound allows (sin, cos, w|w| drag), and RTI along the shifted plan tracks them; one QP of 320
    variables and 558 rows per period solves in 0.47 ms (median; 0.90 ms at the 99th percentile) on this
    2-core machine, the whole step (Jacobians, filter, target, QP) in 1.0 ms per episode (the default suite's
    600 episodes in 614 s, against 1.9 s for ``reversal_aware``).
    A CasADi/IPOPT NMPC would need the equations again in CasADi's symbols (a second copy of the physics) or a
    callback around ``derivatives`` without exact derivatives; it was not built, so not measured: with this
    MPC losing only one episode that has a trim (below), there is little for it to win.

    **Measured** (``benchmarks/mpc.py --episodes 100``: default suite, seeds 10000-10099, against
    ``reversal_aware`` on the same episodes; 95% Wilson intervals): 100% [96, 100] on Nominal, LowSpeed,
    NearCritical and SpeedTransient, as ``reversal_aware``; PeriscopeDepth 94% [88, 97] (94/94 of the
    winnable episodes; the six losses have no depth-holding trim within the plane limits,
    :func:`subenv.analysis.winnable`), as ``reversal_aware``; BallastOffset 89% [81, 94] against 87%
    [79, 92] (89/90 winnable against 87/90; the one winnable loss, seed 10021, has a trim 0.036 rad inside
    the limits and closes its depth error, 1.3 m after 30 s, at 1.3 mm/s with the planes that close to
    their limit). Plane RMS:
    less than ``reversal_aware`` below and near the critical speed (0.070 against 0.119 rad LowSpeed, 0.070
    against 0.095 NearCritical), more at design speed (0.049 against 0.035), in the transient (0.061 against
    0.054) and at periscope depth (0.179 against 0.142), where it drives both planes to trim; the same with
    a ballast offset (0.261 against 0.262).

    On the Randomized suite (sensor noise, a 2 N heave-force disturbance, z_GB and C_D drawn; 40 episodes)
    90% [77, 96] against 82% [68, 91] for ``reversal_aware``.

    It knows what the other controllers know: the observation (its measured state; the planes it applied),
    the design vehicle at reset, and the environment's limits as constructor arguments (defaults: the
    environment's). The planes' rate limit is not in the reset ``info``: pass the environment's
    ``plane_rate_limit_radps``.
    """

    name = "mpc"
    control = "independent"
    alpha = 0.0
    in_default_comparison = False
    """Run when named (``subenv evaluate --controllers ...,mpc``), not in the comparison of every registered
    controller: at 1.0 ms per episode-step it would take the default suite from half a minute to about ten."""

    def __init__(self, horizon: int = 40, weights: MPCWeights = MPCWeights(),
                 noise: ObserverNoise = ObserverNoise(), dt_s: float = CONTROL_PERIOD_S, substeps: int = SUBSTEPS,
                 plane_rate_limit_radps: float | None = DivePlaneConfig.plane_rate_limit_radps,
                 max_pitch_rad: float = DivePlaneConfig.max_pitch_rad,
                 max_depth_error_m: float | None = DivePlaneConfig.max_depth_error_m,
                 pitch_fraction: float = 0.5, depth_band_margin_m: float = 5.0, surface_margin_m: float = 0.25,
                 max_iter: int = 400) -> None:
        if not (isinstance(horizon, int) and horizon >= 2):
            raise ValueError(f"horizon={horizon!r} is invalid: must be an integer >= 2 (control periods)")
        if plane_rate_limit_radps is not None and not plane_rate_limit_radps > 0:
            raise ValueError(f"plane_rate_limit_radps={plane_rate_limit_radps!r} is invalid: must be None or > 0")
        self.horizon, self.weights, self.noise = horizon, weights, noise
        self.dt_s, self.substeps = dt_s, substeps
        self.plane_rate_limit_radps = plane_rate_limit_radps
        self.pitch_bound_rad = pitch_fraction * max_pitch_rad
        self.max_depth_error_m, self.depth_band_margin_m = max_depth_error_m, depth_band_margin_m
        self.band_m = math.nan  # (the environment's depth band less the margin: set with the vehicle)
        self.surface_margin_m = surface_margin_m
        self.settings = {"verbose": False, "warm_starting": True, "polishing": False, "eps_abs": 1e-5,
                         "eps_rel": 1e-5, "max_iter": max_iter, "check_termination": 10}
        self._vehicle: Vehicle | None = None
        self._params: ModelParams | None = None
        self._rows: list[_RowQP] = []
        self.solve_times_s: list[float] = []
        """Wall time of every QP solve (update, solve) [s], one per episode per control period."""

    # --- the model ------------------------------------------------------------------------------
    def predict(self, state: np.ndarray, planes_rad: np.ndarray, speed_mps: Any,
                disturbance: np.ndarray | None = None) -> np.ndarray:
        """The state one control period on, as the controller predicts it (:func:`control_period` of the design
        vehicle)."""
        if self._params is None:
            raise RuntimeError("call reset() or reset_batch() first")
        d = np.zeros(np.shape(planes_rad)) if disturbance is None else np.asarray(disturbance, dtype=float)
        return control_period(self._params, state, speed_mps, np.asarray(planes_rad, dtype=float), d, self.dt_s,
                              self.substeps)

    @property
    def disturbance(self) -> np.ndarray:
        """The disturbance estimate of every episode, (heave force [N], pitch moment [N m]): shape (N, 2)."""
        return self._d.copy()

    # --- the protocol -------------------------------------------------------------------------------
    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        if vehicle is not self._vehicle:
            self._params = model_params(vehicle)
            self._limit = vehicle.planes.limit_rad
            self._surface_m = 0.5 * max(vehicle.hull.breadth_m) + self.surface_margin_m
            # None: the environments' default band, Froude-scaled to the vehicle as theirs is.
            band = (DEPTH_BAND_M * reference_length_ratio(vehicle) if self.max_depth_error_m is None
                    else self.max_depth_error_m)
            self.band_m = band - self.depth_band_margin_m
            self._vehicle = vehicle
        n = len(infos)
        # A fresh solver per episode: OSQP carries its iterates and step size from one solve to the next, so a
        # reused one would make an episode's actions depend on the episodes run before it in that row.
        self._rows = [_RowQP(self.horizon, self.weights, self.settings) for _ in range(n)]
        N = self.horizon
        self._n = n
        self._y = np.zeros((n, N_X))                     # the last measured state
        self._d = np.zeros((n, N_D))                     # the disturbance estimate
        self._P = np.repeat(np.diag(np.square(self.noise.initial_disturbance))[None], n, axis=0)
        self._planes = np.full((n, N_U), np.nan)         # applied (our last command); nan: none yet
        self._plan_x = np.zeros((n, N + 1, N_X))         # the last solution, to linearise along
        self._plan_u = np.zeros((n, N, N_U))
        self._jac0 = np.zeros((n, N_X, N_X + N_U + N_D))  # stage 0's Jacobian, for the observer

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        if self._params is None:
            raise RuntimeError("call reset() or reset_batch() first")
        obs = check_batch(observations, self._n).astype(float)
        y = np.stack([obs[:, PITCH], obs[:, HEAVE], obs[:, PITCH_RATE], obs[:, DEPTH]], axis=1)
        speed = obs[:, SPEED]
        command = obs[:, DEPTH] - obs[:, DEPTH_ERROR]
        first = np.isnan(self._planes[:, 0])
        planes = np.where(first[:, None], obs[:, [STERN, BOW]], self._planes)
        self._observe(y, speed, first)
        # Linearise along the last plan, shifted one period (real-time iteration); at the first period along
        # the estimate held, iterated.
        shift_x = np.concatenate([self._plan_x[:, 2:], self._plan_x[:, -1:]], axis=1)
        shift_u = np.concatenate([self._plan_u[:, 1:], self._plan_u[:, -1:]], axis=1)
        xbar = np.concatenate([y[:, None], shift_x], axis=1)[:, :-1]   # x_0 .. x_{N-1}; x_0 measured
        ubar = shift_u
        xbar[first, 1:] = y[first, None]
        ubar[first] = planes[first, None]
        iterations = 3 if first.any() else 1
        for it in range(iterations):
            rows = np.arange(self._n) if it == 0 else np.flatnonzero(first)
            points = np.concatenate([xbar[rows], ubar[rows], np.repeat(self._d[rows, None], self.horizon, axis=1)],
                                    axis=-1)
            F, J = discrete_jacobians(self._params, points, speed[rows, None], self.dt_s, self.substeps)
            for j, i in enumerate(rows.tolist()):
                self._solve(i, F[j], J[j], xbar[i], ubar[i], planes[i], command[i])
                xbar[i], ubar[i] = self._plan_x[i, :-1], self._plan_u[i]
            if it == 0:
                self._jac0[rows] = J[:, 0]
        u0 = self._plan_u[:, 0]
        self._planes = u0.copy()
        return np.clip(u0 / self._limit, -1.0, 1.0).astype(np.float32)

    # --- the observer -----------------------------------------------------------------------------
    def _observe(self, y: np.ndarray, speed: np.ndarray, first: np.ndarray) -> None:
        """Estimate the disturbance (heave force, pitch moment) from what the last period's prediction missed.

        A Kalman filter on d alone, a random walk, measured through the heave and pitch-rate residuals
        e = y_k - F(y_{k-1}, u_{k-1}, d_hat) ~ B_d (d - d_hat) + noise (B_d the (w, q) rows of dF/dd). In a
        steady state its gain (2 x 2, invertible) makes those residuals 0, so the model with d_hat holds the
        measured state still with the planes that hold the plant there: the MPC then has no reason to stop
        short of the ordered depth (offset-free; theta and Z follow from the exact kinematics). Each row's
        arithmetic on its own (the same bits for any batch).
        """
        noise = self.noise
        Q = np.diag(np.square(noise.disturbance))
        R = np.diag(np.square(noise.measurement))
        rows = np.flatnonzero(~first)
        if rows.size:
            predicted = control_period(self._params, self._y[rows], speed[rows], self._planes[rows], self._d[rows],
                                       self.dt_s, self.substeps)
        for j, i in enumerate(rows.tolist()):
            H = self._jac0[i, 1:3, N_X + N_U:]
            P = self._P[i] + Q
            S = H @ P @ H.T + R
            K = np.linalg.solve(S, H @ P).T
            self._d[i] = self._d[i] + K @ (y[i, 1:3] - predicted[j, 1:3])
            self._P[i] = P - K @ H @ P
        self._y = y.copy()

    # --- the QP -----------------------------------------------------------------------------------
    def _solve(self, i: int, F: np.ndarray, J: np.ndarray, xbar: np.ndarray, ubar: np.ndarray, planes: np.ndarray,
               command: float) -> None:
        row, N, lim = self._rows[i], self.horizon, self._limit
        A, B = J[:, :, :N_X], J[:, :, N_X:N_X + N_U]
        # c_k = F(xbar_k, ubar_k) - A_k xbar_k - B_k ubar_k; stage 0's state is the estimate, not a variable.
        c = F - np.einsum("kij,kj->ki", A, xbar) - np.einsum("kij,kj->ki", B, ubar)
        x_s, u_s = self._target(A[0], B[0], c[0], command)
        c[0] += A[0] @ xbar[0]
        l, u = np.empty(row.n_rows), np.empty(row.n_rows)
        l[:N * N_X] = u[:N * N_X] = c.ravel()
        move = np.inf if self.plane_rate_limit_radps is None else self.plane_rate_limit_radps * self.dt_s
        margin = 1e-7  # inside the limits by more than the float32 action's rounding
        lo, hi = np.full(N * N_U, -lim + margin), np.full(N * N_U, lim - margin)
        lo[:N_U] = np.maximum(lo[:N_U], planes - move + margin)
        hi[:N_U] = np.minimum(hi[:N_U], planes + move - margin)
        r = row.r_planes
        l[r:r + N * N_U], u[r:r + N * N_U] = lo, hi
        r = row.r_moves
        l[r:row.r_soft], u[r:row.r_soft] = -move + margin, move - margin
        r = row.r_soft
        l[r:r + 2 * N:2], u[r:r + 2 * N:2] = -np.inf, self.pitch_bound_rad
        l[r + 1:r + 2 * N:2], u[r + 1:r + 2 * N:2] = -self.pitch_bound_rad, np.inf
        r += 2 * N
        l[r:r + 2 * N:2], u[r:r + 2 * N:2] = -np.inf, command + self.band_m
        l[r + 1:r + 2 * N:2], u[r + 1:r + 2 * N:2] = max(command - self.band_m, self._surface_m), np.inf
        r = row.r_slack
        l[r:], u[r:] = 0.0, np.inf
        q = row.q0.copy()
        q[:N * N_X] = -2.0 * row.state_weights * np.tile(x_s, N)
        q[row.iu:row.iu + N * N_U] = -2.0 * self.weights.plane * np.tile(u_s, N)
        q[row.iu:row.iu + N_U] -= 2.0 * row.move_weight * planes
        start = time.perf_counter()
        row.solver.update(q=q, l=l, u=u, Ax=row.values(A, B))
        if row.z is not None:
            row.solver.warm_start(x=row.z, y=row.y)
        result = row.solver.solve(raise_error=False)
        self.solve_times_s.append(time.perf_counter() - start)
        z = result.x
        if z is None or not np.all(np.isfinite(z)):
            # No usable solution (does not happen in the suite): keep the last plan, shifted, within the limits.
            u_plan = np.clip(ubar, np.maximum(-lim, planes - move), np.minimum(lim, planes + move))
            self._plan_u[i] = u_plan
            self._plan_x[i, 0] = xbar[0]
            self._plan_x[i, 1:] = F
            row.z = row.y = None
            return
        row.z = self._shift(z, row)
        row.y = None if result.y is None else result.y.copy()
        self._plan_x[i, 0] = xbar[0]
        self._plan_x[i, 1:] = z[:N * N_X].reshape(N, N_X)
        self._plan_u[i] = np.clip(z[row.iu:row.iu + N * N_U].reshape(N, N_U), lo.reshape(N, N_U), hi.reshape(N, N_U))

    def _target(self, A: np.ndarray, B: np.ndarray, c: np.ndarray, command: float) -> tuple[np.ndarray, np.ndarray]:
        """The steady state at the ordered depth that the cost's state and plane terms measure from.

        The linearised map x+ = A x + B u + c (at the measured state) held still, x = x+, with Z at the ordered
        depth: 4 equations in v = (theta, w, q, stern, bow), a line of steady states (the bow/stern allocation is
        free). On it, the point of least weighted size with the planes within their limit and the pitch within
        the soft bound (where the line crosses that box; else the point nearest to it in plane angle). At a
        steady state the linearisation is exact, so the cost's minimum is the plant's steady state at the
        ordered depth: the state and plane weights leave no offset (measured from 0, a finite horizon trades
        depth error for plane angle), and the target is one the planes can hold (an unconstrained one can lie
        beyond the limit, where the planes then stay pinned while the boat drifts).
        """
        w = self.weights
        scale = 1.0 / np.sqrt([w.pitch, w.heave, w.pitch_rate, w.plane, w.plane])
        I_A = np.eye(N_X) - A
        # One SVD of the scaled system: its least-norm solution, and the line's direction (its null vector).
        U, S, Vt = np.linalg.svd(np.concatenate([I_A[:, :3], -B], axis=1) * scale)
        S = np.where(S > 1e-12 * S[0], S, np.inf)  # (a rank-deficient direction contributes nothing)
        v0 = scale * (Vt[:N_X].T @ ((U.T @ (c - I_A[:, 3] * command)) / S))
        n = scale * Vt[-1]  # v0 + t n
        bound = np.array([self.pitch_bound_rad, self._limit, self._limit])
        at, dn = v0[[0, 3, 4]], n[[0, 3, 4]]
        with np.errstate(divide="ignore", invalid="ignore"):
            ends = np.sort(np.stack([(-bound - at) / dn, (bound - at) / dn]), axis=0)
        free = dn == 0
        low = np.max(np.where(free, -np.inf, ends[0]))
        high = np.min(np.where(free, np.inf, ends[1]))
        if low <= high and np.all(np.abs(at[free]) <= bound[free]):
            t = min(max(0.0, low), high)
        else:  # no steady state inside the box on this line: the one needing the least plane angle
            candidates = [0.0] + [-(v0[3] - sign * v0[4]) / d for sign in (1.0, -1.0)
                                  if (d := n[3] - sign * n[4]) != 0]
            t = min(candidates, key=lambda t: float(np.max(np.abs(v0[3:] + t * n[3:]))))
        v = v0 + t * n
        return np.append(v[:3], command), v[3:]

    @staticmethod
    def _shift(z: np.ndarray, row: _RowQP) -> np.ndarray:
        """The solution shifted one period, as the next warm start."""
        N = row.N
        x = z[:N * N_X].reshape(N, N_X)
        u = z[row.iu:row.iu + N * N_U].reshape(N, N_U)
        s = z[row.isp:].reshape(2, N)
        return np.concatenate([np.r_[x[1:], x[-1:]].ravel(), np.r_[u[1:], u[-1:]].ravel(),
                               np.c_[s[:, 1:], s[:, -1:]].ravel()])
