"""DivePlaneEnv: depth control of a submarine with saturated dive planes at low speed."""

from __future__ import annotations

import math
import os
from typing import Any, Final, SupportsFloat

import gymnasium as gym
import numpy as np
from numba import typed

from subenv import _validation as check
from subenv.dynamics._jit import read_only
from subenv.envs import transition as tr
from subenv.envs._compiling import first_call
from subenv.envs._interrupts import interrupts_deferred
from subenv.envs.config import DEFAULT_ARGUMENTS, OBSERVATION_NAMES, ControlMode, DivePlaneConfig
from subenv.envs.episodes import Loadings, check_options, draw_episode, new_seas, write_episode, write_sea
from subenv.envs.info import step_info
from subenv.envs.validity import SurfaceValidityWatch
from subenv.scenarios.scenario import EpisodeConfig, Scenario
from subenv.vehicles.vehicle import Vehicle

__all__ = ["OBSERVATION_NAMES", "DivePlaneEnv"]


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

    What zero action (planes held at zero) does depends on the speed, for SUBOFF
    (:func:`subenv.analysis.hopf.hopf_points`, the report of ``subenv analyze``): the hull is
    statically stable in pitch (z_GB > 0) but its Munk moment (M_w u w) destabilises it as u grows.
    Below u_H = 0.836 m/s (1.45 u_cr) a pitch/heave disturbance dies out in a ~40 s oscillation;
    above it the oscillation grows (a supercritical Hopf bifurcation) into a stable cycle whose
    pitch amplitude grows linearly with u - u_H (the quadratic cross-flow drag limits it) and
    reaches the 0.6 rad pitch limit at 0.93 m/s; above 1.64 m/s the motion diverges without
    oscillating. So at the Nominal design speed (1.524 m/s) zero action ends on ``"pitch_limit"``
    within a minute: the planes must act.

    Near the surface (``PeriscopeDepth-v2``, ``PeriscopeDepthWaves-v1``) the free surface pulls the
    hull up and pitches it (the rigid-lid suction of a slender hull, proportional to u^2, falling as
    h^-4 far from the surface, and its share of the heave and pitch derivatives:
    :mod:`subenv.dynamics.free_surface`; outside the model's range, shallower than two hull radii, the
    environment warns once), and in ``PeriscopeDepthWaves`` a seeded JONSWAP head sea adds an
    oscillating heave force and pitch moment and a mean suction (:mod:`subenv.dynamics.waves`). With
    the planes held, level flight there is unstable in depth (the suction weakens with depth); just
    below u_cr the trim of level flight is lost near the surface
    (:func:`subenv.analysis.free_surface.min_level_flight_depth`).

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
             max_depth_error_m=None, depth_scale_m=None, pitch_weight=0.1, effort_weight=0.05,
             termination_penalty=100.0, render_mode=None)
    ```

    - ``scenario``: a registered name (``subenv.scenarios.scenario_names()``) or a
      :class:`~subenv.scenarios.Scenario`. Each registered scenario also has its own id,
      ``subenv/<Name>-v0``; ``subenv/DivePlane-v0`` is ``Randomized``. The Hard ids register some of
      the arguments below too (their limits: :data:`subenv.envs.registration.ID_ARGUMENTS`).
    - ``vehicle``: a shipped name, a vehicle file path, or a :class:`~subenv.vehicles.Vehicle`.
      The shipped scenarios are SUBOFF's: on a vehicle of another length L every episode is
      Froude-scaled by lambda = L / 4.26 m (depths, ``max_depth_error_m`` and ``depth_scale_m``
      x lambda; speeds, times and durations x sqrt(lambda); :meth:`EpisodeConfig.froude_scaled
      <subenv.scenarios.EpisodeConfig.froude_scaled>`), so ``suboff_fullscale`` flies the same
      episodes at full scale. ``dt``, the sensor noise and the disturbance's 30 s time constant are
      not scaled; the registered ids' ``max_episode_steps`` are SUBOFF's (the evaluation harness
      scales them; with ``gym.make`` pass ``max_episode_steps`` for longer episodes).
    - ``control``: ``"dual"`` (one command, eq. 2.58) or ``"independent"`` (two).
    - ``alpha``: bow/stern allocation in [-1, 1] for ``"dual"``; must be 0 with
      ``"independent"``, whose reported critical speed is that of the stern planes.
    - ``dt``: control period [s], in (0, 10]; each step integrates ``substeps`` (1 to 1000) RK4
      steps with the planes held. The default 0.5 s with 2 substeps keeps the integration error
      below 1 mm and 1e-5 rad over 600 s against ``solve_ivp`` at rtol 1e-10
      (``tests/dynamics/test_integrator.py``).
    - ``plane_rate_limit_radps``: None (planes move at once) or the planes' largest rate, in
      (0, 1000] rad/s.
    - ``max_pitch_rad`` in [0.01, pi/2], ``max_depth_error_m`` in (0, 1e5] m (None: 25 m on
      SUBOFF, see below): the Episode End limits. ``depth_scale_m`` in (0, 1e5] m (None: 2 m),
      ``pitch_weight``, ``effort_weight`` and ``termination_penalty`` in [0, 1e6]: the Rewards'
      terms. Within these bounds every reward and observation is finite; a value outside them
      raises ``ValueError``.
    - ``config``: instead of the arguments above, a :class:`~subenv.envs.DivePlaneConfig` (the
      object they are checked into; ``env.config``).

    ## Vectorized environment

    ``gym.make_vec(id, num_envs=N)`` returns :class:`~subenv.envs.DivePlaneVectorEnv`, which steps
    all N sub-environments as arrays through the same compiled transition
    (:mod:`subenv.envs.transition`). Sub-environment ``i`` of ``reset(seed=s)`` is this environment
    reset with ``seed=s + i`` (``SyncVectorEnv``'s rule), step for step and bit for bit, for any N
    and any number of threads; ``vectorization_mode="sync"`` gives ``SyncVectorEnv`` itself. For
    Stable-Baselines3 use :func:`subenv.envs.sb3.make_sb3_vec_env`.

    ## Version History

    - v0: initial version. (The transition's rewrite over named records, with one block integrator
      for every step, kept every seeded rollout bit for bit. The shipped scenarios are Froude-scaled
      on vehicles of another length than SUBOFF's since 2026-12; on SUBOFF, and so for every id's
      defaults, the seeded rollouts are unchanged.)
    - ``PeriscopeDepth-v1`` (2026-12): the surface's suction is the free-surface model
      (:mod:`subenv.dynamics.free_surface`), a force and moment that depend on depth, pitch and
      speed, instead of v0's constant excess buoyancy (0.02-0.1 % of the weight); the boat is
      neutrally buoyant. Same draws otherwise (speeds 0.7-2 u_cr, ordered depth 1.0-1.2 m).
      ``PeriscopeDepth-v0`` stays registered with its seeded episodes (the shipped agents' model
      cards report it); ``Randomized`` and ``Mixed`` draw from it, unchanged.
    - ``PeriscopeDepthWaves-v0`` (2026-12): new, ``PeriscopeDepth-v1`` in a seeded head sea.
      Every other id's seeded rollouts are unchanged, bit for bit.
    - The Hard track's ids (2026-12), new: ``HardRateTransient-v0`` (``SpeedTransient`` with the
      planes rate-limited to 0.05 rad/s, the id's ``plane_rate_limit_radps``), ``HardBallastLimits-v0``
      (``BallastOffset`` with sensor noise, a 1 N heave-force disturbance, 0.03 rad/s and a 0.3 rad
      pitch limit), ``HardWaves18-v0`` (``PeriscopeDepthWaves`` at H_s 18 cm) and ``HardGusts-v0``
      (``NearCritical`` with sensor noise and a 6 N heave-force disturbance); the suite ``hard`` of
      ``subenv evaluate`` scores them over the episodes a stored full-information plan won
      (:mod:`subenv.evaluation.achievable`). Every other id's seeded rollouts are unchanged.
    - ``PeriscopeDepth-v2`` (2026-12): the free surface's consistent first-order slender-body theory
      (``FreeSurface()``, issue 38): besides v1's Lagally force of the hull's sources it has the
      moment of the cross-flow dipoles that the images raise (u int (rho S + a_33) w dx) and the
      images of the hull's own cross-flow (a heave force and moment linear in w and q), on axis
      points converged where v1 lumped one source per segment. At 1 m the level-flight pitch
      stiffness of the suction is about 1.6 times v1's, within 5% of an exact potential-flow
      computation (docs/free_surface.md). Same draws otherwise. ``PeriscopeDepth-v1`` stays registered
      with its seeded episodes (``FreeSurface(theory="sources-only")``).
    - ``PeriscopeDepthWaves-v1`` (2026-12): ``PeriscopeDepth-v2`` in the same seeded head sea, its
      first-order force at the boat's speed (encounter frequency and the u int a_33 w dx moment,
      :mod:`subenv.dynamics.waves`; v0's zero-speed form is ``SeaState(encounter_frequency=False)``).
      ``PeriscopeDepthWaves-v0`` stays registered with its seeded episodes. Every other id's seeded
      rollouts are unchanged, bit for bit.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012 - Gymnasium's convention
        "render_modes": ["human", "rgb_array"],
        "render_fps": 30,
    }

    def __init__(
        self,
        scenario: str | Scenario = DEFAULT_ARGUMENTS["scenario"],
        vehicle: str | os.PathLike[str] | Vehicle = DEFAULT_ARGUMENTS["vehicle"],
        control: ControlMode = DEFAULT_ARGUMENTS["control"],
        alpha: float = DEFAULT_ARGUMENTS["alpha"],
        dt: float = DEFAULT_ARGUMENTS["dt"],
        substeps: int = DEFAULT_ARGUMENTS["substeps"],
        plane_rate_limit_radps: float | None = DEFAULT_ARGUMENTS["plane_rate_limit_radps"],
        max_pitch_rad: float = DEFAULT_ARGUMENTS["max_pitch_rad"],
        max_depth_error_m: float | None = DEFAULT_ARGUMENTS["max_depth_error_m"],
        depth_scale_m: float | None = DEFAULT_ARGUMENTS["depth_scale_m"],
        pitch_weight: float = DEFAULT_ARGUMENTS["pitch_weight"],
        effort_weight: float = DEFAULT_ARGUMENTS["effort_weight"],
        termination_penalty: float = DEFAULT_ARGUMENTS["termination_penalty"],
        render_mode: str | None = None,
        *,
        config: DivePlaneConfig | None = None,
    ) -> None:
        given: dict[str, Any] = {
            "scenario": scenario,
            "vehicle": vehicle,
            "control": control,
            "alpha": alpha,
            "dt": dt,
            "substeps": substeps,
            "plane_rate_limit_radps": plane_rate_limit_radps,
            "max_pitch_rad": max_pitch_rad,
            "max_depth_error_m": max_depth_error_m,
            "depth_scale_m": depth_scale_m,
            "pitch_weight": pitch_weight,
            "effort_weight": effort_weight,
            "termination_penalty": termination_penalty,
        }
        if config is None:
            config = DivePlaneConfig(**given)
        elif not isinstance(config, DivePlaneConfig):
            raise ValueError(f"config={config!r} is invalid: must be a DivePlaneConfig")
        else:
            changed = sorted(name for name, value in given.items() if value != DEFAULT_ARGUMENTS[name])
            if changed:
                raise ValueError(f"config and keyword arguments {changed} were given: give one or the other")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            allowed = self.metadata["render_modes"]
            raise ValueError(f"render_mode={render_mode!r} is invalid: must be None or one of {allowed}")
        self.config = config
        """The environment's configuration (checked); ``set_scenario`` replaces its scenario."""
        self.render_mode = render_mode
        self.action_space = config.action_space()
        self.observation_space = config.observation_space()
        self._constants = config.constants()
        self._hull = config.hull
        self._action_shape = self.action_space.shape
        self._loadings = Loadings(config)

        # The episode, set by reset(): a batch of one for the transition.
        self.vehicle: Vehicle = config.base_vehicle
        """The episode's vehicle (its loading)."""
        self.episode: EpisodeConfig | None = None
        """The episode's draw (None before the first reset)."""
        self._state = np.zeros(1, dtype=tr.STATE_DTYPE)
        self._episode = np.zeros(1, dtype=tr.EPISODE_DTYPE)
        self._episode["critical_speed_mps"] = math.nan
        self._seas = new_seas(1)
        self._obs = np.zeros((1, tr.N_OBS), dtype=np.float32)
        self._obs_row = self._obs[0]
        self._report = np.zeros((len(tr.REPORT_KEYS), 1))
        self._validity = SurfaceValidityWatch(config)
        self._active = np.ones(1, dtype=bool)
        self._rngs: Any = None  # a numba typed list holding self.np_random, for the transition
        self._rngs_source: np.random.Generator | None = None
        self._history: list[tuple[float, float, float]] = []
        self._window: Any = None
        # The first reset and step may load (or, with a cold cache, compile) the transition's kernels:
        # they run under the compile notice (subenv.envs._compiling), the later ones without a test more.
        self._first_calls = {"reset", "step"}

    # --- Gymnasium API ----------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Draw an episode from the scenario (Starting State) and return its first observation and info.

        Parameters
        ----------
        seed : int, optional
            Seeds the environment's generator (Gymnasium's ``np_random``): None, or an integer >= 0, a
            NumPy integer too (``np.int64(3)`` draws what ``3`` draws). Anything else raises ``ValueError``.
        options : dict, optional
            ``"speed"``, ``"depth_command"``, ``"initial_state"`` (see Starting State). Not a dict, or an
            unknown key or value, raises ``ValueError`` and changes nothing.
        """
        if "reset" in self._first_calls:
            return first_call(self._first_calls, "reset", self.reset, seed=seed, options=options)
        # One rule for seeds and options in every environment (the vector env's and subenv.jax's too).
        seed = check.seed("seed", seed)
        checked = check_options(self.config, check.mapping("options", options))
        previous = (self._np_random, self._np_random_seed)
        super().reset(seed=seed)
        rng = self.np_random
        # An option can still prove out of range once the episode is drawn (an initial depth beyond the
        # band of the ordered depth drawn): then the generator is put back as it was.
        saved = rng.bit_generator.state if checked else None
        try:
            draw, loading, episode, state = draw_episode(self.config, rng, self._loadings, checked)
        except ValueError:
            if saved is not None:
                rng.bit_generator.state = saved
            self._np_random, self._np_random_seed = previous
            raise
        assert loading.vehicle is not None  # (one episode's loading has its vehicle)
        self.vehicle, self.episode = loading.vehicle, draw
        write_episode(self._episode, 0, episode)
        write_episode(self._state, 0, state)
        write_sea(self._seas, 0, episode)
        tr.observe(
            self._state, self._episode, _FIRST, self._obs, self._bound_rngs(), self._constants, self._report
        )
        self._history = [(0.0, state["depth_m"], episode["depth_command_m"])]
        self._validity.check(float(self._report[_DEPTH, 0]), float(self._report[_SPEED, 0]))
        if self.render_mode == "human":
            self.render()
        return self._obs_row.copy(), step_info(self._report.ravel().tolist())

    def step(self, action: np.ndarray) -> tuple[np.ndarray, SupportsFloat, bool, bool, dict[str, Any]]:
        """Advance one control period with the planes commanded by ``action`` (clipped to the Action Space).

        A NaN or infinite action raises ``ValueError`` and changes nothing.
        """
        if "step" in self._first_calls:
            return first_call(self._first_calls, "step", self.step, action)
        if self.episode is None:
            raise gym.error.ResetNeeded("Cannot call step() before reset()")
        a = np.ascontiguousarray(check.real_array("action", action)).reshape(1, -1)
        if a.shape[1:] != self._action_shape:
            raise ValueError(
                f"action has shape {np.shape(action)}: must have shape {self._action_shape} "
                f"(control={self.config.control!r})"
            )
        rngs = self._rngs if self._rngs_source is self._np_random else self._bound_rngs()
        if (
            tr.step(
                self._state,
                self._episode,
                self._seas,
                a,
                self._active,
                self._obs,
                rngs,
                self._constants,
                self._hull,
                self._report,
            )
            >= 0
        ):
            raise ValueError(
                f"action={np.asarray(action).tolist()!r} is invalid: must be finite (no NaN or inf)"
            )
        r = self._report.ravel().tolist()  # (its one column)
        self._validity.check(r[_DEPTH], r[_SPEED])
        if self.render_mode is not None:
            self._history.append((r[_TIME], r[_DEPTH], r[_COMMAND]))
            if self.render_mode == "human":
                self.render()
        return self._obs_row.copy(), r[_REWARD], r[_TERMINATED] > 0.0, r[_TRUNCATED] > 0.0, step_info(r)

    def render(self) -> np.ndarray | None:
        """The boat, its planes and its depth history: an RGB frame (``"rgb_array"``) or a window."""
        if self.render_mode is None:
            gym.logger.warn(
                "You are calling render method without specifying any render mode. Set render_mode at "
                'initialization, e.g. gym.make("subenv/DivePlane-v0", render_mode="rgb_array")'
            )
            return None
        from subenv.envs.rendering import Frame, HumanWindow, render_rgb

        frame = Frame.of(self.config.base_vehicle, self._state[0], self._episode[0], self._history)
        if self.render_mode == "rgb_array":
            return render_rgb(frame)
        if self._window is None:
            self._window = HumanWindow(fps=self.metadata["render_fps"])
        self._window.show(frame)
        return None

    def close(self) -> None:
        """Close the render window, if one is open."""
        if self._window is not None:
            self._window.close()
            self._window = None

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_rngs"] = state["_rngs_source"] = None  # a numba typed list does not pickle; rebuilt on use
        state["_window"] = None
        del state["_obs_row"]  # (a view of _obs: made again from the copy)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._obs_row = self._obs[0]
        read_only(self._constants)  # (as the original's: the same compiled step; the hull is the config's)

    # --- the configuration and the episode ------------------------------------------------------
    @property
    def scenario(self) -> Scenario:
        """The scenario the episodes are drawn from."""
        return self.config.base_scenario

    @property
    def base_vehicle(self) -> Vehicle:
        """The vehicle as configured (each episode's loading is a variant of it)."""
        return self.config.base_vehicle

    @property
    def control(self) -> ControlMode:
        """``"dual"`` or ``"independent"``."""
        return self.config.control

    @property
    def alpha(self) -> float:
        """The bow/stern allocation of dual control (eq. 2.58)."""
        return self.config.alpha

    @property
    def dt(self) -> float:
        """The control period [s]."""
        return self.config.dt

    @property
    def plane_limit_rad(self) -> float:
        """The planes' saturation [rad]."""
        return self.config.plane_limit_rad

    @property
    def state(self) -> np.ndarray:
        """(pitch [rad], heave [m/s], pitch rate [rad/s], depth [m]), a copy."""
        s = self._state[0]
        return np.array([s["pitch_rad"], s["heave_mps"], s["pitch_rate_radps"], s["depth_m"]])

    @property
    def time_s(self) -> float:
        """Time since the reset [s]."""
        return float(self._state[0]["time_s"])

    @property
    def depth_command_m(self) -> float:
        """The ordered depth of the episode [m]."""
        return float(self._episode[0]["depth_command_m"])

    @property
    def planes_rad(self) -> np.ndarray:
        """Applied (stern, bow) plane angles [rad], a copy."""
        s = self._state[0]
        return np.array([s["stern_plane_rad"], s["bow_plane_rad"]])

    @property
    def critical_speed_mps(self) -> float:
        """Critical speed of the episode's loading [m/s] (nan: none, z_GB <= 0)."""
        return float(self._episode[0]["critical_speed_mps"])

    def set_scenario(self, scenario: str | Scenario) -> None:
        """Draw the following episodes from ``scenario`` (a registered name or a Scenario).

        The episode under way is not changed; the next ``reset`` draws from the new scenario. This
        is how a training curriculum moves the distribution of speeds and loadings
        (``subenv_agents.curriculum``); everything else of the environment (spaces, reward, limits)
        stays as it was made.
        """
        self.config = self.config.replace(scenario=scenario)
        self._validity = SurfaceValidityWatch(self.config, self._validity.warned)

    def speed_at(self, t: float) -> float:
        """Forward speed [m/s] of the current episode at time ``t`` [s]."""
        e = self._episode[0]
        return float(tr.speed_at(float(t), e["n_knots"], e["knot_time_s"], e["knot_speed_mps"]))

    def _bound_rngs(self) -> Any:
        """A numba typed list holding ``self.np_random`` (rebuilt when the generator changes)."""
        rng = self.np_random
        if self._rngs_source is not rng:
            with interrupts_deferred():
                self._rngs = typed.List([rng])
            self._rngs_source = rng
        return self._rngs


_FIRST: Final = np.zeros(1, dtype=np.intp)  # the index of a single environment
_TIME, _DEPTH, _COMMAND, _SPEED, _REWARD, _TERMINATED, _TRUNCATED = (
    tr.REPORT_KEYS.index(key)
    for key in ("time_s", "depth_m", "depth_command_m", "speed_mps", "reward", "terminated", "truncated")
)
