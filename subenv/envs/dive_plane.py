"""DivePlaneEnv: depth control of a submarine with saturated dive planes at low speed."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from typing import Any, Final, Literal, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numba import typed

from subenv.analysis.critical import critical_speed
from subenv.analysis.linear import check_alpha
from subenv.dynamics.integrate import CONTROL_PERIOD_S, SUBSTEPS
from subenv.dynamics.model import model_params, pack_params
from subenv.envs import transition as tr
from subenv.scenarios.registry import get_scenario
from subenv.scenarios.scenario import EpisodeConfig, Scenario
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.vehicle import Vehicle

__all__ = ["OBSERVATION_NAMES", "DivePlaneEnv"]

OBSERVATION_NAMES: Final = (
    "depth_error_m",
    "pitch_rad",
    "heave_mps",
    "pitch_rate_radps",
    "speed_mps",
    "stern_plane_rad",
    "bow_plane_rad",
    "depth_m",
)
"""Names (with units) of the observation components, in order."""

# Standard deviations of the sensor noise, per observation component (depth error and depth share
# one depth-sensor draw; the plane angles are not noisy).
_NOISE_STD: Final = {
    "depth_m": 0.05,
    "pitch_rad": 0.002,
    "heave_mps": 0.005,
    "pitch_rate_radps": 0.001,
    "speed_mps": 0.02,
}
_DISTURBANCE_TIME_CONSTANT_S: Final = 30.0  # correlation time of the heave-force disturbance
# A state beyond these rates has left the model's validity (and float range soon after).
_MAX_HEAVE_MPS: Final = 20.0
_MAX_PITCH_RATE_RADPS: Final = 10.0
_MAX_SPEED_MPS: Final = 10.0
_MAX_DEPTH_COMMAND_M: Final = 1000.0
_OBS_MARGIN_M: Final = 10.0  # room beyond the depth band for the terminal observation and noise
_OPTIONS: Final = ("speed", "depth_command", "initial_state")
_STATE_KEYS: Final = ("pitch", "heave", "pitch_rate", "depth")
_LOADING_CACHE_SIZE: Final = 1024  # loadings kept per environment (each one: a Vehicle and its parameters)
ControlMode = Literal["dual", "independent"]


def _positive(name: str, value: Any, upper: float = math.inf) -> float:
    if not (isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value <= upper
            and math.isfinite(value)):
        raise ValueError(f"{name}={value!r} is invalid: must be a finite number in (0, {upper}]")
    return float(value)


def _non_negative(name: str, value: Any) -> float:
    if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            and value >= 0):
        raise ValueError(f"{name}={value!r} is invalid: must be a finite number >= 0")
    return float(value)


class DivePlaneEnv(gym.Env[np.ndarray, np.ndarray]):
    """Depth keeping with dive planes for a submarine whose speed a scenario sets.

    ## Description

    The nonlinear vertical-plane model of the DARPA SUBOFF submarine (Riedel 1993 eqs 2.38-2.43)
    with saturated dive planes and hull cross-flow drag. The agent moves the planes to reach and
    hold an ordered depth. Below a critical speed u_cr (eq. 3.9; 0.5785 m/s for SUBOFF at
    alpha = 0) level flight loses stability in a pitchfork bifurcation and the planes' effect on
    depth reverses (dive-plane reversal): a controller designed at speed drives the boat to a
    pitched equilibrium with the planes pinned at their limit instead of to the ordered depth.
    Speed is not controlled by the agent; the scenario sets it (constant or a deceleration
    through u_cr).

    ## Action Space

    ``Box(-1, 1, (1,), float32)`` with ``control="dual"``: the command delta = a * 0.4 rad drives
    the stern planes, and the bow planes follow as alpha * delta (eq. 2.58).
    ``Box(-1, 1, (2,), float32)`` with ``control="independent"``: (stern, bow) = a * 0.4 rad.
    Signs follow the thesis's coefficients: a positive stern-plane angle lifts the stern and
    pitches the nose down (above the critical speed the boat then dives); a positive bow-plane
    angle lifts the bow. Actions outside [-1, 1] are clipped; NaN or infinite actions
    raise ``ValueError``. With ``plane_rate_limit_radps`` the applied angles move towards the
    command by at most that rate times ``dt`` per step.

    ## Observation Space

    ``Box(low, high, (8,), float32)``, bounds below; observations are clipped to them, which only a
    terminal state can reach (D = ``max_depth_error_m``):

    | Num | Observation       | Unit  | Bounds          | Note                                      |
    |-----|-------------------|-------|-----------------|-------------------------------------------|
    | 0   | depth error       | m     | +-(D + 10)      | depth - ordered depth (positive: too deep)|
    | 1   | pitch theta       | rad   | +-pi            | nose-up positive                          |
    | 2   | heave velocity w  | m/s   | +-20            | body axes, down positive                  |
    | 3   | pitch rate q      | rad/s | +-10            |                                           |
    | 4   | forward speed u   | m/s   | [0, 10]         | set by the scenario                       |
    | 5   | stern plane angle | rad   | +-0.4           | applied (after saturation, rate limit)    |
    | 6   | bow plane angle   | rad   | +-0.4           | applied                                   |
    | 7   | depth             | m     | [-10, 1010 + D] | below the surface, of midship             |

    With sensor noise (scenario ``Randomized``), Gaussian noise of standard deviation 0.05 m
    (depth, one draw shared by 0 and 7), 0.002 rad, 0.005 m/s, 0.001 rad/s and 0.02 m/s is
    added to components 0-4 and 7. The true values are in ``info``.

    ## Rewards

    ``reward = reward_depth + reward_pitch + reward_effort + reward_termination``, each term
    returned in ``info`` under its name:

    - ``reward_depth = 1 - tanh(|depth error| / depth_scale_m)``, in (0, 1];
    - ``reward_pitch = -pitch_weight * (theta / max_pitch_rad)^2``;
    - ``reward_effort = -effort_weight * mean(a^2)`` (a: the clipped action);
    - ``reward_termination = -termination_penalty`` on the step that terminates, else 0.

    ## Starting State

    Drawn from the scenario: speed profile, ordered depth, initial (theta, w, q, depth), loading
    (z_GB, x_GB, excess buoyancy), hull drag coefficient. ``reset(options=...)`` overrides:

    - ``speed`` (m/s): a constant speed for the episode (replaces the scenario's profile);
    - ``depth_command`` (m): the ordered depth;
    - ``initial_state``: (pitch [rad], heave [m/s], pitch_rate [rad/s], depth [m]), or a mapping
      with any of the keys ``pitch``, ``heave``, ``pitch_rate``, ``depth`` (the rest drawn).

    ## Episode End

    Terminated when |theta| > ``max_pitch_rad`` (``"pitch_limit"``), the depth is less than the
    hull radius (the hull breaks the surface: ``"broached"``), |depth error| >
    ``max_depth_error_m`` (``"left_depth_band"``), or the state diverges (``"diverged"``; the
    last valid observation is returned). The reason is ``info["termination_reason"]`` ("" while
    running). Truncated when the scenario's duration is reached (200-600 s).

    ## Arguments

    ```python
    gym.make("subenv/DivePlane-v0", scenario="Randomized", vehicle="suboff", control="dual",
             alpha=0.0, dt=0.5, substeps=2, plane_rate_limit_radps=None, max_pitch_rad=0.6,
             max_depth_error_m=25.0, depth_scale_m=2.0, pitch_weight=0.1, effort_weight=0.05,
             termination_penalty=100.0, render_mode=None)
    ```

    - ``scenario``: a registered name (``subenv.scenarios.scenario_names()``) or a
      :class:`~subenv.scenarios.Scenario`. Each registered scenario also has its own id,
      ``subenv/<Name>-v0``; ``subenv/DivePlane-v0`` is ``Randomized``.
    - ``vehicle``: a shipped name, a vehicle file path, or a :class:`~subenv.vehicles.Vehicle`.
    - ``control``: ``"dual"`` (one command, eq. 2.58) or ``"independent"`` (two).
    - ``alpha``: bow/stern allocation in [-1, 1] for ``"dual"``; must be 0 with
      ``"independent"``, whose reported critical speed is that of the stern planes.
    - ``dt``: control period [s]; each step integrates ``substeps`` RK4 steps with the planes
      held. The default 0.5 s with 2 substeps keeps the integration error below 1 mm and 1e-5 rad
      over 600 s against ``solve_ivp`` at rtol 1e-10 (``tests/dynamics/test_integrator.py``).

    ## Vectorized environment

    ``gym.make_vec(id, num_envs=N)`` returns :class:`~subenv.envs.DivePlaneVectorEnv`, which steps
    all N sub-environments as arrays through the same compiled transition
    (:mod:`subenv.envs.transition`) and reproduces ``SyncVectorEnv`` over this environment step
    for step; ``vectorization_mode="sync"`` gives the latter. For Stable-Baselines3 use
    :func:`subenv.envs.sb3.make_sb3_vec_env`.

    ## Version History

    - v0: initial version.
    """

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array"], "render_fps": 30}

    def __init__(
        self,
        scenario: str | Scenario = "Randomized",
        vehicle: str | os.PathLike[str] | Vehicle = "suboff",
        control: ControlMode = "dual",
        alpha: float = 0.0,
        dt: float = CONTROL_PERIOD_S,
        substeps: int = SUBSTEPS,
        plane_rate_limit_radps: float | None = None,
        max_pitch_rad: float = 0.6,
        max_depth_error_m: float = 25.0,
        depth_scale_m: float = 2.0,
        pitch_weight: float = 0.1,
        effort_weight: float = 0.05,
        termination_penalty: float = 100.0,
        render_mode: str | None = None,
    ) -> None:
        self.scenario: Scenario
        self.set_scenario(scenario)
        self.base_vehicle = vehicle if isinstance(vehicle, Vehicle) else load_vehicle(vehicle)
        if control not in ("dual", "independent"):
            raise ValueError(f"control={control!r} is invalid: must be one of ['dual', 'independent']")
        self.control: ControlMode = control
        self.alpha = check_alpha(alpha)
        if control == "independent" and self.alpha != 0.0:
            raise ValueError(
                f"alpha={alpha!r} is invalid with control='independent': must be 0 "
                "(the bow planes have their own action)"
            )
        self.dt = _positive("dt", dt, upper=10.0)
        if not (isinstance(substeps, int) and not isinstance(substeps, bool) and 1 <= substeps <= 1000):
            raise ValueError(f"substeps={substeps!r} is invalid: must be an integer in [1, 1000]")
        self.substeps = substeps
        self.plane_rate_limit_radps = (
            None if plane_rate_limit_radps is None else _positive("plane_rate_limit_radps", plane_rate_limit_radps)
        )
        self.max_pitch_rad = _positive("max_pitch_rad", max_pitch_rad, upper=math.pi / 2)
        self.max_depth_error_m = _positive("max_depth_error_m", max_depth_error_m)
        self.depth_scale_m = _positive("depth_scale_m", depth_scale_m)
        self.pitch_weight = _non_negative("pitch_weight", pitch_weight)
        self.effort_weight = _non_negative("effort_weight", effort_weight)
        self.termination_penalty = _non_negative("termination_penalty", termination_penalty)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode={render_mode!r} is invalid: must be None or one of {self.metadata['render_modes']}"
            )
        self.render_mode = render_mode

        self.plane_limit_rad = self.base_vehicle.planes.limit_rad
        self.broach_depth_m = 0.5 * max(self.base_vehicle.hull.breadth_m)
        n_actions = 1 if control == "dual" else 2
        self.action_space = spaces.Box(-1.0, 1.0, shape=(n_actions,), dtype=np.float32)
        depth_error_bound = self.max_depth_error_m + _OBS_MARGIN_M
        limit = self.plane_limit_rad
        self._obs_low = np.array([-depth_error_bound, -math.pi, -_MAX_HEAVE_MPS, -_MAX_PITCH_RATE_RADPS,
                                  0.0, -limit, -limit, -_OBS_MARGIN_M])
        self._obs_high = np.array([depth_error_bound, math.pi, _MAX_HEAVE_MPS, _MAX_PITCH_RATE_RADPS,
                                   _MAX_SPEED_MPS, limit, limit,
                                   _MAX_DEPTH_COMMAND_M + self.max_depth_error_m + _OBS_MARGIN_M])
        self.observation_space = spaces.Box(
            self._obs_low.astype(np.float32), self._obs_high.astype(np.float32), dtype=np.float32
        )
        self._noise_std = np.array(
            [_NOISE_STD.get(name, 0.0) for name in OBSERVATION_NAMES], dtype=float
        )
        self._hull = model_params(self.base_vehicle).hull.packed
        self._cfg = self._constants(max_episode_steps=None)
        self._loadings: dict[tuple[float, float, float, float | None], tuple[Vehicle, list[float], float, float]] = {}

        # Episode state, set by reset(): one row of the transition's table (subenv.envs.transition).
        self.vehicle: Vehicle = self.base_vehicle
        self.episode: EpisodeConfig | None = None
        self._rows = np.zeros((1, tr.N_COLUMNS))
        self._rows[0, tr.CRITICAL_SPEED] = math.nan
        self._row = self._rows[0]
        self._obs_rows = np.zeros((1, len(OBSERVATION_NAMES)), dtype=np.float32)
        self._report = np.zeros((tr.N_REPORT, 1))  # (unused here: the info is built from the row)
        self._active = np.ones(1, dtype=bool)
        self._last_obs = self._obs_rows[0]
        self._rngs: Any = None  # numba typed list holding self.np_random, for the transition
        self._rngs_source: np.random.Generator | None = None
        self._history: list[tuple[float, float, float]] = []
        self._window: Any = None

    # --- Gymnasium API ----------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self.vehicle, self.episode, self._row[:] = self._draw_episode(self.np_random, options)
        tr.observe_batch(self._rows, _FIRST, self._obs_rows, self._bound_rngs(), self._cfg, self._report)
        self._history = [(0.0, self._row[tr.DEPTH], self._row[tr.COMMAND])]
        if self.render_mode == "human":
            self.render()
        return self._last_obs.copy(), _info(self._row.tolist())

    def step(self, action: np.ndarray) -> tuple[np.ndarray, SupportsFloat, bool, bool, dict[str, Any]]:
        if self.episode is None:
            raise gym.error.ResetNeeded("Cannot call step() before reset()")
        a = np.ascontiguousarray(action, dtype=np.float64).reshape(1, -1)
        if a.shape[1:] != self.action_space.shape:
            raise ValueError(
                f"action has shape {np.shape(action)}: must have shape {self.action_space.shape} "
                f"(control={self.control!r})"
            )
        rngs = self._rngs if self._rngs_source is self._np_random else self._bound_rngs()
        if tr.step_batch(self._rows, a, self._active, self._obs_rows, rngs, 0, self._cfg, self._hull, self._report) >= 0:
            raise ValueError(f"action={np.asarray(action).tolist()!r} is invalid: must be finite (no NaN or inf)")
        r = self._row.tolist()
        if self.render_mode is not None:
            self._history.append((r[tr.TIME], r[tr.DEPTH], r[tr.COMMAND]))
            if self.render_mode == "human":
                self.render()
        return self._last_obs.copy(), r[tr.REWARD], r[tr.TERMINATED] > 0.0, r[tr.TRUNCATED] > 0.0, _info(r)

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn(
                "You are calling render method without specifying any render mode. "
                'Set render_mode at initialization, e.g. gym.make("subenv/DivePlane-v0", render_mode="rgb_array")'
            )
            return None
        from subenv.envs.rendering import HumanWindow, render_rgb

        frame = self._frame(self._row, self._history)
        if self.render_mode == "rgb_array":
            return render_rgb(frame)
        if self._window is None:
            self._window = HumanWindow(fps=self.metadata["render_fps"])
        self._window.show(frame)
        return None

    def close(self) -> None:
        if self._window is not None:
            self._window.close()
            self._window = None

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_rngs"] = state["_rngs_source"] = None  # a numba typed list does not pickle; rebuilt on use
        state["_window"] = None
        return state

    # --- the episode's state, kept in the transition's row -----------------------------------
    @property
    def state(self) -> np.ndarray:
        """(pitch [rad], heave [m/s], pitch rate [rad/s], depth [m]), a copy."""
        return self._row[tr.PITCH:tr.DEPTH + 1].copy()

    @state.setter
    def state(self, value: np.ndarray) -> None:
        self._row[tr.PITCH:tr.DEPTH + 1] = value

    @property
    def time_s(self) -> float:
        """Time since the reset [s]."""
        return float(self._row[tr.TIME])

    @property
    def depth_command_m(self) -> float:
        """The ordered depth of the episode [m]."""
        return float(self._row[tr.COMMAND])

    @property
    def planes_rad(self) -> np.ndarray:
        """Applied (stern, bow) plane angles [rad], a copy."""
        return self._row[tr.STERN:tr.BOW + 1].copy()

    @property
    def critical_speed_mps(self) -> float:
        """Critical speed of the episode's loading [m/s] (nan: none, z_GB <= 0)."""
        return float(self._row[tr.CRITICAL_SPEED])

    def set_scenario(self, scenario: str | Scenario) -> None:
        """Draw the following episodes from ``scenario`` (a registered name or a Scenario).

        The episode under way is not changed; the next ``reset`` draws from the new scenario. This
        is how a training curriculum moves the distribution of speeds and loadings
        (``agents.curriculum``); everything else of the environment (spaces, reward, limits)
        stays as it was made.
        """
        if isinstance(scenario, Scenario):
            self.scenario = scenario
        elif isinstance(scenario, str):
            self.scenario = get_scenario(scenario)
        else:
            raise ValueError(f"scenario={scenario!r} is invalid: must be a scenario name or a Scenario")

    def speed_at(self, t: float) -> float:
        """Forward speed [m/s] of the current episode at time ``t`` [s]."""
        return float(tr.speed_at_point(float(t), self._row))

    # --- helpers, shared with DivePlaneVectorEnv ----------------------------------------------
    def _constants(self, max_episode_steps: int | None) -> np.ndarray:
        """The transition's constants (``subenv.envs.transition.C_*``) for this configuration."""
        cfg = np.zeros(tr.N_CONFIG)
        decay = math.exp(-self.dt / _DISTURBANCE_TIME_CONSTANT_S)
        cfg[tr.C_DT] = self.dt
        cfg[tr.C_SUBSTEPS] = self.substeps
        cfg[tr.C_DUAL] = 1.0 if self.control == "dual" else 0.0
        cfg[tr.C_ALPHA] = self.alpha
        cfg[tr.C_PLANE_LIMIT] = self.plane_limit_rad
        if self.plane_rate_limit_radps is not None:
            cfg[tr.C_RATE_LIMITED] = 1.0
            cfg[tr.C_MAX_MOVE] = self.plane_rate_limit_radps * self.dt
        cfg[tr.C_MAX_PITCH] = self.max_pitch_rad
        cfg[tr.C_MAX_DEPTH_ERROR] = self.max_depth_error_m
        cfg[tr.C_BROACH_DEPTH] = self.broach_depth_m
        cfg[tr.C_DEPTH_SCALE] = self.depth_scale_m
        cfg[tr.C_PITCH_WEIGHT] = self.pitch_weight
        cfg[tr.C_EFFORT_WEIGHT] = self.effort_weight
        cfg[tr.C_TERMINATION_PENALTY] = self.termination_penalty
        cfg[tr.C_DISTURBANCE_DECAY] = decay
        cfg[tr.C_DISTURBANCE_GAIN] = math.sqrt(1 - decay * decay)
        cfg[tr.C_MAX_STEPS] = tr.episode_time_limit(max_episode_steps)
        cfg[tr.C_MAX_HEAVE] = _MAX_HEAVE_MPS
        cfg[tr.C_MAX_PITCH_RATE] = _MAX_PITCH_RATE_RADPS
        cfg[tr.C_OBS_LOW:tr.C_OBS_LOW + tr.N_OBS] = self._obs_low
        cfg[tr.C_OBS_HIGH:tr.C_OBS_HIGH + tr.N_OBS] = self._obs_high
        cfg[tr.C_NOISE_STD:tr.C_NOISE_STD + tr.N_OBS] = self._noise_std
        cfg.flags.writeable = False
        return cfg

    def _bound_rngs(self) -> Any:
        """A numba typed list holding ``self.np_random`` (rebuilt when the generator changes)."""
        rng = self.np_random
        if self._rngs_source is not rng:
            self._rngs = typed.List([rng])
            self._rngs_source = rng
        return self._rngs

    def _loading(self, config: EpisodeConfig) -> tuple[Vehicle, list[float], float, float]:
        """The episode's vehicle, its model parameters (``PARAM_FIELDS``), critical speed and
        sqrt(g z_GB) (nan for z_GB <= 0), memoised."""
        base = self.base_vehicle
        z_GB = config.z_GB_m if config.z_GB_m is not None else base.z_GB_m
        key = (z_GB * config.z_GB_scale, base.x_GB_m + config.x_GB_m,
               base.excess_buoyancy_N + config.excess_buoyancy_N, config.crossflow_drag)
        found = self._loadings.get(key)
        if found is None:
            vehicle = base.variant(z_GB_m=key[0], x_GB_m=key[1], excess_buoyancy_N=key[2], crossflow_drag=key[3])
            if len(self._loadings) >= _LOADING_CACHE_SIZE:
                self._loadings.clear()
            z_GB = vehicle.z_GB_m
            found = self._loadings[key] = (
                vehicle,
                pack_params(model_params(vehicle)).tolist(),
                self._critical_speed(vehicle),
                math.sqrt(vehicle.gravity_m_s2 * z_GB) if z_GB > 0 else math.nan,
            )
        return found

    def _draw_episode(
        self, rng: np.random.Generator, options: dict[str, Any] | None
    ) -> tuple[Vehicle, EpisodeConfig, list[float]]:
        """Draw an episode from ``rng`` (and ``options``): its vehicle, its draw and its transition row
        (``subenv.envs.transition`` columns); the observation is not drawn yet."""
        options = options or {}
        if options:
            unknown = set(options) - set(_OPTIONS)
            if unknown:
                raise ValueError(
                    f"reset options {sorted(unknown)} are unknown: allowed options are {list(_OPTIONS)}"
                )
        config = self.scenario.sample(rng, self.base_vehicle.weight_N)
        std = config.disturbance_std_N
        disturbance = float(rng.normal(0.0, std)) if std > 0 else 0.0
        vehicle, values = self._episode_row(config, options, disturbance)
        return vehicle, config, values

    def _episode_row(
        self, config: EpisodeConfig, options: dict[str, Any], disturbance: Any
    ) -> tuple[Vehicle, list[Any]]:
        """The episode's vehicle and transition row (``subenv.envs.transition`` columns) from its draw, the
        ``options`` (checked) and the initial heave force [N].

        Also for a batch of episodes with one loading (:meth:`Scenario._sample_batch
        <subenv.scenarios.Scenario._sample_batch>`, no options): a column's value is then an array
        over the episodes where the draw has one.
        """
        vehicle, params, ucr, froude_scale = self._loading(config)
        if config.speed_relative and not math.isfinite(ucr):
            raise ValueError(
                f"scenario {self.scenario.name!r} gives speeds relative to the critical speed, but "
                f"vehicle {vehicle.name!r} (z_GB={vehicle.z_GB_m!r} m) has none"
            )
        scale = ucr if config.speed_relative else 1.0
        knots = [(k[0], k[1] * scale) for k in config.speed_knots]
        command = config.depth_command_m
        state = list(config.initial_state)

        if "speed" in options:
            knots = [(0.0, _positive("options['speed']", options["speed"], upper=_MAX_SPEED_MPS))]
        if "depth_command" in options:
            value = options["depth_command"]
            if not (isinstance(value, (int, float)) and math.isfinite(value)
                    and self.broach_depth_m < value <= _MAX_DEPTH_COMMAND_M):
                raise ValueError(
                    f"options['depth_command']={value!r} is invalid: must be a number in "
                    f"({self.broach_depth_m:.4g}, {_MAX_DEPTH_COMMAND_M:g}] m (below the hull radius)"
                )
            # Keep the drawn initial offset from the ordered depth, unless it would broach.
            offset = state[3] - command
            command = float(value)
            state[3] = command + offset
            if not state[3] > self.broach_depth_m:
                state[3] = command
        if "initial_state" in options:
            state = self._initial_state_option(options["initial_state"], state, command)
        if len(knots) > tr.MAX_KNOTS:
            raise ValueError(f"the speed profile has {len(knots)} knots; the environment takes at most {tr.MAX_KNOTS}")

        values = [0.0] * tr.N_COLUMNS
        values[tr.PITCH:tr.DEPTH + 1] = state
        values[tr.PARAMS:tr.STERN] = params
        values[tr.N_KNOTS] = len(knots)
        for k, (t, u) in enumerate(knots):
            values[tr.KNOT_T + k] = t
            values[tr.KNOT_U + k] = u
        values[tr.COMMAND] = command
        values[tr.DISTURBANCE] = disturbance
        values[tr.DISTURBANCE_STD] = config.disturbance_std_N
        values[tr.NOISE] = 1.0 if config.sensor_noise else 0.0
        values[tr.DURATION] = config.duration_s
        values[tr.CRITICAL_SPEED] = ucr
        values[tr.SQRT_G_ZGB] = froude_scale
        return vehicle, values

    def _frame(self, row: np.ndarray, history: Sequence[tuple[float, float, float]]) -> Any:
        """The rendering :class:`~subenv.envs.rendering.Frame` of a transition row."""
        from subenv.envs.rendering import Frame

        times, depths, commands = zip(*history) if history else ((), (), ())
        return Frame(
            hull_x_m=self.base_vehicle.hull.x_m,
            hull_breadth_m=self.base_vehicle.hull.breadth_m,
            length_m=self.base_vehicle.length_m,
            pitch_rad=float(row[tr.PITCH]),
            depth_m=float(row[tr.DEPTH]),
            depth_command_m=float(row[tr.COMMAND]),
            stern_plane_rad=float(row[tr.STERN]),
            bow_plane_rad=float(row[tr.BOW]),
            speed_mps=float(tr.speed_at_point(float(row[tr.TIME]), row)),
            critical_speed_mps=float(row[tr.CRITICAL_SPEED]),
            time_s=float(row[tr.TIME]),
            times_s=tuple(times),
            depths_m=tuple(depths),
            commands_m=tuple(commands),
        )

    def _critical_speed(self, vehicle: Vehicle) -> float:
        try:
            return critical_speed(vehicle, self.alpha)
        except ValueError:
            return math.nan  # z_GB <= 0: no critical speed exists for this loading

    def _initial_state_option(self, value: Any, drawn: list[float], command: float) -> list[float]:
        if isinstance(value, Mapping):
            unknown = set(value) - set(_STATE_KEYS)
            if unknown:
                raise ValueError(
                    f"options['initial_state'] has unknown keys {sorted(unknown)}: allowed keys are {list(_STATE_KEYS)}"
                )
            state = [value.get(k, d) for k, d in zip(_STATE_KEYS, drawn)]
        elif isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, str) and len(value) == 4:
            state = list(value)
        else:
            raise ValueError(
                f"options['initial_state']={value!r} is invalid: must be (pitch, heave, pitch_rate, depth) "
                f"or a mapping with keys {list(_STATE_KEYS)}"
            )
        try:
            state = [float(v) for v in state]
        except (TypeError, ValueError):
            raise ValueError(f"options['initial_state']={value!r} is invalid: must hold numbers") from None
        for key, v in zip(_STATE_KEYS, state):
            if not math.isfinite(v):
                raise ValueError(f"options['initial_state'][{key!r}]={v!r} is invalid: must be finite")
        pitch, heave, rate, depth = state
        if not abs(pitch) < self.max_pitch_rad:
            raise ValueError(
                f"options['initial_state']['pitch']={pitch!r} is invalid: must be in "
                f"(-{self.max_pitch_rad}, {self.max_pitch_rad}) rad (max_pitch_rad)"
            )
        if not abs(heave) <= _MAX_HEAVE_MPS:
            raise ValueError(
                f"options['initial_state']['heave']={heave!r} is invalid: must be in [-{_MAX_HEAVE_MPS}, {_MAX_HEAVE_MPS}] m/s"
            )
        if not abs(rate) <= _MAX_PITCH_RATE_RADPS:
            raise ValueError(
                f"options['initial_state']['pitch_rate']={rate!r} is invalid: must be in "
                f"[-{_MAX_PITCH_RATE_RADPS}, {_MAX_PITCH_RATE_RADPS}] rad/s"
            )
        low, high = self.broach_depth_m, command + self.max_depth_error_m
        if not low < depth <= high:
            raise ValueError(
                f"options['initial_state']['depth']={depth!r} is invalid: must be in ({low:.4g}, {high:.4g}] m "
                "(below the hull radius, within max_depth_error_m of the ordered depth)"
            )
        return state


_FIRST: Final = np.zeros(1, dtype=np.intp)  # the row index of a single environment


def _info(r: list[float]) -> dict[str, Any]:
    """The step's ``info`` from a transition row (as a list of floats)."""
    depth, command, speed = r[tr.DEPTH], r[tr.COMMAND], r[tr.SPEED]
    froude_scale, ucr = r[tr.SQRT_G_ZGB], r[tr.CRITICAL_SPEED]  # nan when z_GB <= 0 (then no Froude numbers)
    return {
        "time_s": r[tr.TIME],
        "depth_m": depth,
        "depth_command_m": command,
        "depth_error_m": depth - command,
        "pitch_rad": r[tr.PITCH],
        "heave_mps": r[tr.HEAVE],
        "pitch_rate_radps": r[tr.PITCH_RATE],
        "stern_plane_rad": r[tr.STERN],
        "bow_plane_rad": r[tr.BOW],
        "speed_mps": speed,
        "froude_number": speed / froude_scale,  # Fn = u / sqrt(g z_GB)
        "critical_speed_mps": ucr,
        "critical_froude": ucr / froude_scale,
        "disturbance_N": r[tr.DISTURBANCE],
        "termination_reason": tr.REASONS[int(r[tr.REASON])],
        "reward_depth": r[tr.REWARD_DEPTH],
        "reward_pitch": r[tr.REWARD_PITCH],
        "reward_effort": r[tr.REWARD_EFFORT],
        "reward_termination": r[tr.REWARD_TERMINATION],
    }
