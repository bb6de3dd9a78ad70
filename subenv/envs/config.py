"""DivePlaneConfig: the one validated configuration of the dive-plane environments.

:class:`~subenv.envs.DivePlaneEnv` and :class:`~subenv.envs.DivePlaneVectorEnv` take the same
keyword arguments and turn them into a :class:`DivePlaneConfig`, which checks every value before
an environment is built; the transition reads its numbers as one record
(:meth:`DivePlaneConfig.constants`).
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType
from typing import Any, Final, Literal

import numpy as np
from gymnasium import spaces

from subenv import _validation as check
from subenv.analysis.linear import check_alpha
from subenv.dynamics._jit import read_only
from subenv.dynamics.integrate import CONTROL_PERIOD_S, SUBSTEPS
from subenv.dynamics.model import model_params
from subenv.envs import transition as tr
from subenv.scenarios.registry import get_scenario
from subenv.scenarios.scenario import Scenario
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.vehicle import Vehicle

__all__ = ["DEFAULT_ARGUMENTS", "OBSERVATION_NAMES", "ControlMode", "DivePlaneConfig"]

ControlMode = Literal["dual", "independent"]

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
NOISE_STD: Final = {
    "depth_m": 0.05,
    "pitch_rad": 0.002,
    "heave_mps": 0.005,
    "pitch_rate_radps": 0.001,
    "speed_mps": 0.02,
}
DISTURBANCE_TIME_CONSTANT_S: Final = 30.0
"""Correlation time of the heave-force disturbance [s]."""
# A state beyond these rates has left the model's validity (and float range soon after).
MAX_HEAVE_MPS: Final = 20.0
MAX_PITCH_RATE_RADPS: Final = 10.0
MAX_SPEED_MPS: Final = 10.0
MAX_DEPTH_COMMAND_M: Final = 1000.0
OBS_MARGIN_M: Final = 10.0
"""Room beyond the depth band for the terminal observation and noise [m]."""
MIN_PITCH_LIMIT_RAD: Final = 0.01
"""The smallest ``max_pitch_rad`` (0.57 deg): the pitch term divides by it, and any terminal pitch
over it stays a finite reward with the largest weight."""
MAX_WEIGHT: Final = 1e6
"""The largest reward weight and termination penalty: every reward term stays finite (the pitch term
is at most ``MAX_WEIGHT * (pi / MIN_PITCH_LIMIT_RAD)^2`` in size, and more only at a terminal pitch
beyond pi)."""
MAX_PLANE_RATE_RADPS: Final = 1000.0
MAX_DEPTH_BAND_M: Final = 1e5
"""The largest ``max_depth_error_m`` and ``depth_scale_m`` [m]: nine times the deepest ocean, so a
study may let the boat sink for hours (``tests/physics``), and the observation bounds stay finite
in float32."""


DEPTH_BAND_M: Final = 25.0
"""``max_depth_error_m`` by default on the scenario's reference vehicle (SUBOFF, 4.26 m long: about
six hull lengths); Froude-scaled on another."""
DEPTH_SCALE_M: Final = 2.0
"""``depth_scale_m`` by default on the scenario's reference vehicle; Froude-scaled on another."""


@dataclass(frozen=True, init=False)
class DivePlaneConfig:
    """Everything an environment is made with but its render mode, checked on construction.

    It is made from the environments' keyword arguments (``DivePlaneEnv``'s Arguments section:
    :data:`DEFAULT_ARGUMENTS`), and holds what they resolve to: ``scenario`` and ``vehicle`` given by
    name or path are stored loaded, ``max_depth_error_m`` and ``depth_scale_m`` given as None are
    stored as the values they stand for. :meth:`replace` gives a checked copy (``set_scenario`` uses
    it).
    """

    scenario: Scenario
    """The scenario the episodes are drawn from."""
    vehicle: Vehicle
    """The vehicle as loaded (each episode's loading is a variant of it)."""
    control: ControlMode
    alpha: float
    dt: float
    substeps: int
    plane_rate_limit_radps: float | None
    max_pitch_rad: float
    max_depth_error_m: float
    depth_scale_m: float
    pitch_weight: float
    effort_weight: float
    termination_penalty: float

    def __init__(
        self,
        *,
        scenario: Scenario | str = "Randomized",
        vehicle: Vehicle | str | os.PathLike[str] = "suboff",
        control: ControlMode = "dual",
        alpha: float = 0.0,
        dt: float = CONTROL_PERIOD_S,
        substeps: int = SUBSTEPS,
        plane_rate_limit_radps: float | None = None,
        max_pitch_rad: float = 0.6,
        max_depth_error_m: float | None = None,
        depth_scale_m: float | None = None,
        pitch_weight: float = 0.1,
        effort_weight: float = 0.05,
        termination_penalty: float = 100.0,
    ) -> None:
        put = object.__setattr__
        if isinstance(scenario, str):
            scenario = get_scenario(scenario)
        elif not isinstance(scenario, Scenario):
            raise ValueError(f"scenario={scenario!r} is invalid: must be a scenario name or a Scenario")
        put(self, "scenario", scenario)
        put(self, "vehicle", vehicle if isinstance(vehicle, Vehicle) else load_vehicle(vehicle))
        check.require(
            "control", control, control in ("dual", "independent"), "one of ['dual', 'independent']"
        )
        put(self, "control", control)
        put(self, "alpha", check_alpha(alpha))
        if self.control == "independent" and self.alpha != 0.0:
            raise ValueError(
                f"alpha={self.alpha!r} is invalid with control='independent': must be 0 "
                "(the bow planes have their own action)"
            )
        if not self.vehicle.planes.has_bow_planes and (self.control == "independent" or self.alpha != 0.0):
            name, value = (
                ("control", self.control) if self.control == "independent" else ("alpha", self.alpha)
            )
            raise ValueError(
                f"{name}={value!r} is invalid for vehicle {self.vehicle.name!r}, which has no bow "
                "planes: must be control='dual' with alpha=0 (the stern planes alone)"
            )
        put(self, "dt", check.positive("dt", dt, upper=10.0))
        put(self, "substeps", check.integer("substeps", substeps, 1, 1000))
        if plane_rate_limit_radps is not None:
            plane_rate_limit_radps = check.positive(
                "plane_rate_limit_radps", plane_rate_limit_radps, upper=MAX_PLANE_RATE_RADPS
            )
        put(self, "plane_rate_limit_radps", plane_rate_limit_radps)
        put(
            self,
            "max_pitch_rad",
            check.number("max_pitch_rad", max_pitch_rad, MIN_PITCH_LIMIT_RAD, math.pi / 2),
        )
        # None: the reference vehicle's value (SUBOFF's, for the shipped scenarios), Froude-scaled to
        # this vehicle's length as the scenario's episodes are (Scenario.reference_length_m).
        ratio = self.length_ratio
        for name, given, reference in (
            ("max_depth_error_m", max_depth_error_m, DEPTH_BAND_M),
            ("depth_scale_m", depth_scale_m, DEPTH_SCALE_M),
        ):
            put(
                self,
                name,
                check.positive(name, reference * ratio if given is None else given, upper=MAX_DEPTH_BAND_M),
            )
        for name, weight in (
            ("pitch_weight", pitch_weight),
            ("effort_weight", effort_weight),
            ("termination_penalty", termination_penalty),
        ):
            put(self, name, check.number(name, weight, 0.0, MAX_WEIGHT))

    def replace(self, **changes: Any) -> DivePlaneConfig:
        """A copy with some fields changed, checked again."""
        return dataclasses.replace(self, **changes)

    # --- derived -------------------------------------------------------------------------------
    @property
    def base_vehicle(self) -> Vehicle:
        """:attr:`vehicle` (the name its callers knew it by when ``vehicle`` held the argument as given)."""
        return self.vehicle

    @property
    def base_scenario(self) -> Scenario:
        """:attr:`scenario` (the name its callers knew it by when ``scenario`` held the argument as given)."""
        return self.scenario

    @property
    def length_ratio(self) -> float:
        """Lambda by which the scenario's episodes are Froude-scaled on this vehicle
        (:attr:`Scenario.reference_length_m <subenv.scenarios.Scenario.reference_length_m>`; 1.0 on the
        scenario's reference vehicle, or without one)."""
        return self.scenario.length_ratio(self.vehicle.length_m)

    @property
    def plane_limit_rad(self) -> float:
        """The planes' saturation [rad], the vehicle's."""
        return self.vehicle.planes.limit_rad

    @property
    def broach_depth_m(self) -> float:
        """The depth at which the hull breaks the surface: half the hull's largest breadth [m]."""
        return 0.5 * max(self.vehicle.hull.breadth_m)

    @property
    def n_actions(self) -> int:
        """1 with ``control="dual"``, 2 with ``"independent"``."""
        return 1 if self.control == "dual" else 2

    @cached_property
    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) of the observation (float64, :data:`OBSERVATION_NAMES` order)."""
        depth_error_bound = self.max_depth_error_m + OBS_MARGIN_M
        limit = self.plane_limit_rad
        low = np.array(
            [
                -depth_error_bound,
                -math.pi,
                -MAX_HEAVE_MPS,
                -MAX_PITCH_RATE_RADPS,
                0.0,
                -limit,
                -limit,
                -OBS_MARGIN_M,
            ]
        )
        high = np.array(
            [
                depth_error_bound,
                math.pi,
                MAX_HEAVE_MPS,
                MAX_PITCH_RATE_RADPS,
                MAX_SPEED_MPS,
                limit,
                limit,
                MAX_DEPTH_COMMAND_M + self.max_depth_error_m + OBS_MARGIN_M,
            ]
        )
        return low, high

    def action_space(self) -> spaces.Box:
        """``Box(-1, 1, (n_actions,), float32)``."""
        return spaces.Box(-1.0, 1.0, shape=(self.n_actions,), dtype=np.float32)

    def observation_space(self) -> spaces.Box:
        """``Box(low, high, (8,), float32)`` (:attr:`observation_bounds`)."""
        low, high = self.observation_bounds
        return spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)

    @cached_property
    def hull(self) -> np.ndarray:
        """The vehicle's hull table as the kernels take it (:attr:`subenv.dynamics.HullTable.packed`),
        read-only."""
        return model_params(self.vehicle).hull.packed

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)  # (what pickle and deepcopy do without this method)
        if "hull" in state:  # (computed before the copy: read-only again, as the kernels were compiled)
            read_only(state["hull"])

    def constants(self, max_episode_steps: int | None = None) -> np.ndarray:
        """The transition's constants: one read-only record of
        :data:`~subenv.envs.transition.CONFIG_DTYPE` (shape (1,)); ``max_episode_steps`` truncates
        episodes as ``gymnasium.wrappers.TimeLimit`` does (None: the scenario's duration only)."""
        decay = math.exp(-self.dt / DISTURBANCE_TIME_CONSTANT_S)
        low, high = self.observation_bounds
        record = _record(
            tr.CONFIG_DTYPE,
            dt_s=self.dt,
            substeps=self.substeps,
            dual=self.control == "dual",
            alpha=self.alpha,
            plane_limit_rad=self.plane_limit_rad,
            rate_limited=self.plane_rate_limit_radps is not None,
            max_move_rad=(self.plane_rate_limit_radps or 0.0) * self.dt,
            max_pitch_rad=self.max_pitch_rad,
            max_depth_error_m=self.max_depth_error_m,
            broach_depth_m=self.broach_depth_m,
            depth_scale_m=self.depth_scale_m,
            pitch_weight=self.pitch_weight,
            effort_weight=self.effort_weight,
            termination_penalty=self.termination_penalty,
            disturbance_decay=decay,
            disturbance_gain=math.sqrt(1 - decay * decay),
            max_steps=math.inf if max_episode_steps is None else float(max_episode_steps),
            max_heave_mps=MAX_HEAVE_MPS,
            max_pitch_rate_radps=MAX_PITCH_RATE_RADPS,
            obs_low=low,
            obs_high=high,
            noise_std=[NOISE_STD.get(name, 0.0) for name in OBSERVATION_NAMES],
        )
        read_only(record)
        return record


def _record(dtype: np.dtype, **fields: Any) -> np.ndarray:
    """One record of ``dtype`` (shape (1,)), each field set by its name: all of them, and no other."""
    names = dtype.names or ()
    if set(fields) != set(names):
        raise ValueError(
            f"a record of {sorted(names)} was given {sorted(fields)}: "
            f"missing {sorted(set(names) - set(fields))}, unknown {sorted(set(fields) - set(names))}"
        )
    record = np.zeros(1, dtype=dtype)
    for name, value in fields.items():
        record[name] = value
    return record


DEFAULT_ARGUMENTS: Final[Mapping[str, Any]] = MappingProxyType(
    {name: parameter.default for name, parameter in inspect.signature(DivePlaneConfig).parameters.items()}
)
"""The environments' keyword arguments and their defaults (:class:`DivePlaneConfig`'s)."""
