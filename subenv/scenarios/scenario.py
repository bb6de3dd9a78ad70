"""Scenarios as data: named distributions over episodes, and the concrete draw of one episode.

A :class:`Scenario` says how an episode is drawn (speed profile, loading, depth command, initial
state, noise, disturbance); :meth:`Scenario.sample` turns it into an :class:`EpisodeConfig` with
numbers only. Environments consume the config; they never branch on a scenario's name.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from subenv import _validation as check
from subenv.dynamics.free_surface import FreeSurface
from subenv.dynamics.waves import SeaState
from subenv.scenarios.registry import get_scenario
from subenv.thesis import THESIS_DESIGN_SPEED_MPS
from subenv.vehicles.scaling import froude_factor
from subenv.vehicles.vehicle import BUOYANCY_RATIO_RANGE

__all__ = ["EpisodeConfig", "Interval", "Scenario", "SpeedRamp"]

Interval = tuple[float, float]
"""A closed interval (low, high) drawn uniformly; low == high is a fixed value."""


_TINY = 1e-9  # lower bound for quantities that must be strictly positive


_UNIT: Interval = (0.0, 1.0)
"""The interval whose draw is the uniform number itself (0 + 1 u == u): for a coin flip among the draws."""


@dataclass(frozen=True)
class _Draws:
    """How a scenario turns uniform numbers into its draw: one number in each of some intervals.

    A scenario's draw takes ``k`` numbers uniform in [0, 1) with one ``rng.random(k)`` call, one per
    interval that is not fixed, and maps number ``u`` onto its interval as ``low + (high - low) u``.
    That is the definition: :meth:`Scenario.sample` and :meth:`Scenario.sample_batch` both apply
    :meth:`values` to such numbers, so a batch equals one draw at a time by construction.
    """

    fixed: tuple[float, ...]  # every interval's value, the low end for those drawn
    drawn: tuple[tuple[int, float, float], ...]  # (position, low, high - low) of each interval drawn

    @classmethod
    def of(cls, intervals: Sequence[Interval]) -> _Draws:
        fixed = tuple(float(low) for low, _ in intervals)
        drawn = tuple(
            (j, float(low), float(high - low)) for j, (low, high) in enumerate(intervals) if low != high
        )
        return cls(fixed, drawn)

    def draw(self, rng: np.random.Generator) -> list[float]:
        """One number per interval, in order."""
        return self.values(rng.random(len(self.drawn)).tolist()) if self.drawn else list(self.fixed)

    @cached_property
    def _ends(self) -> np.ndarray:
        """The low ends and the spans of the intervals drawn, shape (2, intervals drawn, 1)."""
        return np.array([[low for _, low, _ in self.drawn], [span for _, _, span in self.drawn]]).reshape(
            2, -1, 1
        )

    def values(self, units: Sequence[Any]) -> list[Any]:
        """The numbers for the ``units`` uniform in [0, 1), one per interval drawn, in order.

        ``units`` may be an array of shape (intervals drawn, n), a row per interval (one number per
        episode of a batch): each interval's value is then an array too, computed element for element
        as for one episode (in one operation over the rows).
        """
        values: list[Any] = list(self.fixed)
        if isinstance(units, np.ndarray) and units.ndim == 2:
            if units.shape[0] != len(self.drawn):
                raise ValueError(f"units has {units.shape[0]} rows: must have {len(self.drawn)}")
            lows, spans = self._ends
            units = lows + spans * units
            for (j, _, _), unit in zip(self.drawn, units, strict=True):
                values[j] = unit
            return values
        for (j, low, span), unit in zip(self.drawn, units, strict=True):
            values[j] = low + span * unit
        return values


@dataclass(frozen=True)
class SpeedRamp:
    """A linear change of speed within an episode, from the initial speed to a final one: in m/s
    (``final_speed_mps``) or as u / u_cr (``final_speed_ratio``), whichever the scenario uses.

    The ramp starts at ``start_s`` and lasts ``duration_s``; the speed is held before and after.
    """

    start_s: Interval
    duration_s: Interval
    final_speed_mps: Interval | None = None
    final_speed_ratio: Interval | None = None

    def __post_init__(self) -> None:
        if (self.final_speed_mps is None) == (self.final_speed_ratio is None):
            raise ValueError(
                f"final_speed_mps={self.final_speed_mps!r}, final_speed_ratio={self.final_speed_ratio!r} are "
                "invalid: give exactly one of them"
            )
        check.interval(
            "final_speed_mps" if self.final_speed_mps is not None else "final_speed_ratio",
            self.final_speed,
            0.0,
        )
        check.interval("start_s", self.start_s, 0.0)
        check.interval("duration_s", self.duration_s, 0.0)

    @property
    def final_speed(self) -> Interval:
        """The final speed's interval, in the unit given (m/s, or u / u_cr)."""
        return self.final_speed_mps if self.final_speed_mps is not None else self.final_speed_ratio  # type: ignore[return-value]


@dataclass(frozen=True)
class EpisodeConfig:
    """One concrete episode: every number an environment needs to run it (SI units).

    ``speed_knots`` is a piecewise-linear speed profile, held constant after the last knot (a single
    knot is a constant speed): (t [s], u [m/s]) pairs, or with ``speed_relative`` (t [s], u / u_cr)
    pairs, multiples of the episode's critical speed, which the environment resolves. The metacentric
    height is ``z_GB_m`` (None: the vehicle's) times ``z_GB_scale``; ``crossflow_drag`` None keeps the
    vehicle's C_D.
    """

    speed_knots: tuple[tuple[float, float], ...]
    speed_relative: bool
    depth_command_m: float
    initial_state: tuple[float, float, float, float]
    z_GB_m: float | None
    z_GB_scale: float
    x_GB_m: float
    excess_buoyancy_N: float
    crossflow_drag: float | None
    sensor_noise: bool
    disturbance_std_N: float
    duration_s: float
    free_surface: FreeSurface | None = None
    sea_state: SeaState | None = None
    wave_uniforms: tuple[Any, ...] = ()

    def froude_scaled(self, length_ratio: float) -> EpisodeConfig:
        """The same episode for a vehicle ``length_ratio`` times longer, at equal Froude number
        (:func:`subenv.vehicles.froude_scaled`): lengths x lambda, speeds and times x sqrt(lambda),
        rates x 1/sqrt(lambda), forces x lambda^3; angles, ratios (u / u_cr, ``z_GB_scale``, C_D)
        and ``excess_buoyancy_N`` (drawn as a fraction of the scaled vehicle's weight) stay.
        Works on a batch's draw too (arrays). A ratio of exactly 1 returns this episode itself."""
        ratio = check.positive("length_ratio", length_ratio)
        if ratio == 1.0:
            return self
        length, time, rate, force = (froude_factor(q, ratio) for q in ("length", "time", "rate", "force"))
        speed = froude_factor("speed", ratio)
        speed_knot = 1.0 if self.speed_relative else speed
        pitch, heave, pitch_rate, depth = self.initial_state
        return dataclasses.replace(
            self,
            speed_knots=tuple((t * time, u * speed_knot) for t, u in self.speed_knots),
            depth_command_m=self.depth_command_m * length,
            initial_state=(pitch, heave * speed, pitch_rate * rate, depth * length),
            z_GB_m=None if self.z_GB_m is None else self.z_GB_m * length,
            x_GB_m=self.x_GB_m * length,
            disturbance_std_N=self.disturbance_std_N * force,
            duration_s=self.duration_s * time,
            sea_state=None
            if self.sea_state is None
            else dataclasses.replace(
                self.sea_state,
                significant_height_m=self.sea_state.significant_height_m * length,
                peak_period_s=self.sea_state.peak_period_s * time,
            ),
        )


@dataclass(frozen=True)
class Scenario:
    """A named distribution over episodes; registered with :func:`subenv.scenarios.register_scenario`.

    Intervals are drawn uniformly and independently. ``None`` for ``z_GB_m`` or ``crossflow_drag``
    keeps the vehicle's own value. A scenario with ``components`` first picks one of the named
    scenarios uniformly and then applies its own randomisation (``z_GB_scale``,
    ``crossflow_drag``, noise, disturbance) on top: this is how ``Randomized`` draws from all.

    Attributes
    ----------
    name : str
        CamelCase; registered as the Gymnasium id ``subenv/<name>-v0``.
    description : str
        One line on what the scenario tests.
    speed_mps : Interval or None
        Initial forward speed [m/s]; the thesis's design speed, 5 fps, when neither it nor
        ``speed_ratio`` is given.
    speed_ratio : Interval or None
        Initial forward speed as u / u_cr of the episode's own loading and plane allocation (the
        ramp's final speed then too: ``SpeedRamp.final_speed_ratio``), so the scenario stays
        below, near or above critical for any vehicle. Give ``speed_mps`` or ``speed_ratio``.
    speed_ramp : SpeedRamp or None
        A deceleration (or acceleration) within the episode.
    depth_command_m : Interval
        Ordered depth [m, positive down].
    initial_depth_offset_m : Interval
        Initial depth minus the ordered depth [m].
    initial_pitch_rad, initial_heave_mps, initial_pitch_rate_radps : Interval
        Initial state.
    z_GB_m : Interval or None
        Metacentric height [m]; None keeps the vehicle's.
    z_GB_scale : Interval
        Factor applied to the metacentric height after the draw.
    x_GB_m : Interval
        Ballast offset [m] (Riedel 1993 Ch. IV).
    x_GB_sign_random : bool
        Flip the sign of the drawn x_GB with probability 1/2.
    excess_buoyancy_fraction : Interval
        (B - W) / W; near-surface suction modelled as excess buoyancy (Ch. V.C). Within [-0.5, 1]:
        B / W within :data:`~subenv.vehicles.vehicle.BUOYANCY_RATIO_RANGE` for a neutral vehicle.
    crossflow_drag : Interval or None
        Hull cross-flow drag coefficient C_D; None keeps the vehicle's.
    sensor_noise : bool
        Add Gaussian noise to the observed depth, pitch, heave, pitch rate and speed.
    disturbance_std_N : float
        Standard deviation of a Gauss-Markov heave-force disturbance [N]; 0 disables it.
    duration_s : float
        Episode length [s]; the episode is truncated at this time.
    components : tuple of str
        Names of scenarios to draw from (a mixture); empty for a plain scenario.
    free_surface : FreeSurface or None
        The free surface's suction on the hull (:mod:`subenv.dynamics.free_surface`); None: deep
        water (Riedel 1993's model).
    sea_state : SeaState or None
        A seaway from ahead (:mod:`subenv.dynamics.waves`), its phases and frequencies drawn at each
        reset; None: calm water.
    version : int
        The Gymnasium id's version, ``subenv/<name>-v<version>``: a scenario whose seeded episodes
        changed is registered again under the next version, and the old one kept. The registry
        knows a scenario of version 0 by its name, a later one as ``<name>-v<version>``
        (:attr:`key`).
    reference_length_m : float or None
        The hull length [m] the scenario's absolute quantities (depths, m/s speeds, times, loadings,
        disturbance) were chosen for. On a vehicle of another length L an environment Froude-scales
        every episode by L / reference_length_m (:meth:`EpisodeConfig.froude_scaled`), so the
        scenario means the same for a boat of any size; None (the default): the episodes are used as
        drawn. The shipped scenarios give SUBOFF's length.
    """

    name: str
    description: str
    speed_mps: Interval | None = None
    speed_ratio: Interval | None = None
    speed_ramp: SpeedRamp | None = None
    depth_command_m: Interval = (10.0, 10.0)
    initial_depth_offset_m: Interval = (-2.0, 2.0)
    initial_pitch_rad: Interval = (0.0, 0.0)
    initial_heave_mps: Interval = (0.0, 0.0)
    initial_pitch_rate_radps: Interval = (0.0, 0.0)
    z_GB_m: Interval | None = None
    z_GB_scale: Interval = (1.0, 1.0)
    x_GB_m: Interval = (0.0, 0.0)
    x_GB_sign_random: bool = False
    excess_buoyancy_fraction: Interval = (0.0, 0.0)
    crossflow_drag: Interval | None = None
    sensor_noise: bool = False
    disturbance_std_N: float = 0.0
    duration_s: float = 300.0
    components: tuple[str, ...] = ()
    reference_length_m: float | None = None
    free_surface: FreeSurface | None = None
    sea_state: SeaState | None = None
    version: int = 0

    def __post_init__(self) -> None:
        if not (self.name and self.name.isidentifier() and self.name[0].isupper()):
            raise ValueError(f"name={self.name!r} is invalid: must be a CamelCase identifier")
        if self.speed_mps is not None and self.speed_ratio is not None:
            raise ValueError(
                f"speed_mps={self.speed_mps!r}, speed_ratio={self.speed_ratio!r} are invalid: give one of "
                "them (m/s, or u / u_cr)"
            )
        if self.speed_ratio is not None:
            check.interval("speed_ratio", self.speed_ratio, 0.0)
        else:
            if self.speed_mps is None:
                object.__setattr__(self, "speed_mps", (THESIS_DESIGN_SPEED_MPS, THESIS_DESIGN_SPEED_MPS))
            check.interval("speed_mps", self.speed_mps, 0.0)
        ramp = self.speed_ramp
        if ramp is not None and (ramp.final_speed_ratio is not None) != self.speed_relative:
            raise ValueError(
                f"speed_ramp={ramp!r} is invalid: its final speed must be given as the initial speed is, "
                f"{'final_speed_ratio (u / u_cr)' if self.speed_relative else 'final_speed_mps (m/s)'}"
            )
        check.interval("depth_command_m", self.depth_command_m, 0.0)
        check.interval("initial_depth_offset_m", self.initial_depth_offset_m)
        check.interval("initial_pitch_rad", self.initial_pitch_rad, -math.pi / 2, math.pi / 2)
        check.interval("initial_heave_mps", self.initial_heave_mps)
        check.interval("initial_pitch_rate_radps", self.initial_pitch_rate_radps)
        if self.z_GB_m is not None:
            check.interval("z_GB_m", self.z_GB_m, _TINY)
        check.interval("z_GB_scale", self.z_GB_scale, _TINY)
        check.interval("x_GB_m", self.x_GB_m)
        # (B - W) / W within the B / W a vehicle may have, so that a neutrally buoyant one can take any draw
        low, high = BUOYANCY_RATIO_RANGE
        check.interval("excess_buoyancy_fraction", self.excess_buoyancy_fraction, low - 1.0, high - 1.0)
        if self.crossflow_drag is not None:
            check.interval("crossflow_drag", self.crossflow_drag, 0.0)
        if not (math.isfinite(self.disturbance_std_N) and self.disturbance_std_N >= 0):
            raise ValueError(
                f"disturbance_std_N={self.disturbance_std_N!r} is invalid: must be a finite number >= 0"
            )
        if not (math.isfinite(self.duration_s) and self.duration_s > 0):
            raise ValueError(f"duration_s={self.duration_s!r} is invalid: must be a finite number > 0")
        if self.reference_length_m is not None:
            check.positive("reference_length_m", self.reference_length_m)
        check.integer("version", self.version, 0)
        if self.components and (self.free_surface is not None or self.sea_state is not None):
            raise ValueError(
                f"scenario {self.name!r}: a mixture takes its free surface and sea from its components; "
                "give free_surface and sea_state on those"
            )

    @property
    def key(self) -> str:
        """The name the registry knows this scenario by: ``name``, or ``name-v<version>`` after version 0."""
        return self.name if self.version == 0 else f"{self.name}-v{self.version}"

    @property
    def env_id(self) -> str:
        """The Gymnasium id, ``subenv/<name>-v<version>``."""
        return f"subenv/{self.name}-v{self.version}"

    @property
    def speed_relative(self) -> bool:
        """Speeds are u / u_cr (``speed_ratio``), not m/s."""
        return self.speed_ratio is not None

    @property
    def initial_speed(self) -> Interval:
        """The initial speed's interval, in the scenario's unit (m/s, or u / u_cr)."""
        return self.speed_ratio if self.speed_ratio is not None else self.speed_mps  # type: ignore[return-value]

    def length_ratio(self, length_m: float) -> float:
        """Lambda = ``length_m`` / :attr:`reference_length_m`, by which an environment Froude-scales the
        episodes on a vehicle of that length (1.0 without a reference length)."""
        return 1.0 if self.reference_length_m is None else length_m / self.reference_length_m

    def replace(self, **changes: object) -> Scenario:
        """A copy with some fields changed (``dataclasses.replace``), validated again."""
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]

    def sample(
        self, rng: np.random.Generator, weight_N: float, registry: dict[str, Scenario] | None = None
    ) -> EpisodeConfig:
        """Draw one episode.

        Parameters
        ----------
        rng : numpy.random.Generator
            The environment's generator; the draw consumes it deterministically.
        weight_N : float
            The vehicle's weight, to turn ``excess_buoyancy_fraction`` into newtons.
        registry : dict, optional
            Where ``components`` are looked up (the global registry by default).
        """
        if self.components:
            names: Sequence[str] = self.components
            pick = names[int(rng.integers(len(names)))]
            base = registry[pick] if registry is not None else get_scenario(pick)
            return self._mixed(base.sample(rng, weight_N, registry), self._draws.draw(rng))
        return self._episode(self._draws.draw(rng), weight_N)

    def sample_batch(self, uniforms: np.ndarray, weight_N: float, pick: int = 0) -> EpisodeConfig:
        """Many episodes at once, from their uniform numbers (a vector environment's resets).

        Only for a scenario whose draws are uniform numbers after a pick (:attr:`samples_in_batches`).

        Parameters
        ----------
        uniforms : ndarray, shape (n, k)
            Row ``i`` holds the ``k`` = ``uniforms_per_pick[pick]`` (:attr:`uniforms_per_pick`)
            numbers that :meth:`sample` takes from episode ``i``'s generator (``rng.random(k)``,
            after a mixture's pick).
        weight_N : float
            As for :meth:`sample`.
        pick : int
            The component of a mixture every one of these episodes picked (``rng.integers`` in
            :meth:`sample`: an index into :attr:`components`); 0 for a plain scenario.

        Returns
        -------
        EpisodeConfig
            Its drawn fields are arrays of ``n``: row ``i`` is what :meth:`sample` draws with row
            ``i``'s numbers; the others are the scenario's (or the component's) values.
        """
        count = self._uniforms_after(pick)
        uniforms = np.asarray(uniforms, dtype=float)
        if uniforms.ndim != 2 or uniforms.shape[1] != count:
            raise ValueError(f"uniforms has shape {uniforms.shape}: must be (n, {count})")
        return self._from_uniforms(pick, uniforms.T, weight_N)

    def episode_from_uniforms(
        self, uniforms: Sequence[float], weight_N: float, pick: int = 0
    ) -> EpisodeConfig:
        """The episode :meth:`sample` draws with these numbers after ``pick`` (a row of
        :meth:`sample_batch`'s)."""
        count = self._uniforms_after(pick)
        if len(uniforms) != count:
            raise ValueError(f"uniforms has {len(uniforms)} numbers: must have {count}")
        return self._from_uniforms(pick, [float(u) for u in uniforms], weight_N)

    @property
    def uniforms_per_episode(self) -> int:
        """How many uniform numbers a plain scenario's :meth:`sample` takes from the generator (a
        mixture's: those of its own randomisation, after its component's)."""
        return len(self._draws.drawn)

    @property
    def uniforms_per_pick(self) -> tuple[int, ...]:
        """How many uniform numbers :meth:`sample` takes from the generator after its pick, one count per
        component of a mixture (the component's, then the mixture's own), or one for a plain scenario.

        Raises ``ValueError`` for a scenario that does not draw in batches (:attr:`samples_in_batches`).
        """
        return tuple(self._uniforms_after(pick) for pick in range(max(len(self.components), 1)))

    @property
    def samples_in_batches(self) -> bool:
        """Each of its draws is a pick and then uniform numbers (:meth:`sample_batch` applies): a plain
        scenario, or a mixture of plain scenarios (as registered now)."""
        return not any(get_scenario(name).components for name in self.components)

    def _uniforms_after(self, pick: int) -> int:
        """Element ``pick`` of :attr:`uniforms_per_pick`, ``pick`` checked (a batch's resets ask for the
        picks they drew, not for every component's)."""
        choices = max(len(self.components), 1)
        if not (type(pick) is int and 0 <= pick < choices):  # (checked: the message names what is allowed)
            check.integer("pick", pick, 0, choices - 1)
        if not self.components:
            return self.uniforms_per_episode
        component = get_scenario(self.components[pick])
        if component.components:
            raise ValueError(
                f"scenario {self.name!r} cannot draw in batches: a component of the mixture is a mixture "
                f"({list(self.components)})"
            )
        return component.uniforms_per_episode + self.uniforms_per_episode

    def _from_uniforms(self, pick: int, units: Sequence[Any], weight_N: float) -> EpisodeConfig:
        """The episode :meth:`sample` draws with ``pick``, then these uniform numbers (floats or arrays)."""
        if not self.components:
            return self._episode(self._draws.values(units), weight_N)
        component = get_scenario(self.components[pick])
        k = component.uniforms_per_episode
        config = component._episode(component._draws.values(units[:k]), weight_N)
        return self._mixed(config, self._draws.values(units[k:]))

    def _mixed(self, config: EpisodeConfig, values: Sequence[Any]) -> EpisodeConfig:
        """A mixture's episode: its component's draw ``config`` with the mixture's own randomisation on top,
        from its drawn numbers (:attr:`_draws`), floats or arrays."""
        drawn = iter(values)
        return dataclasses.replace(
            config,
            z_GB_scale=config.z_GB_scale * next(drawn),
            crossflow_drag=next(drawn) if self.crossflow_drag is not None else config.crossflow_drag,
            sensor_noise=self.sensor_noise or config.sensor_noise,
            disturbance_std_N=max(self.disturbance_std_N, config.disturbance_std_N),
        )

    def _episode(self, values: Sequence[Any], weight_N: float) -> EpisodeConfig:
        """The episode of a plain scenario from its drawn numbers (:attr:`_draws`), floats or arrays."""
        drawn = iter(values)
        speed0 = next(drawn)
        knots: tuple[tuple[float, float], ...] = ((0.0, speed0),)
        if self.speed_ramp is not None:
            start, length, final = next(drawn), next(drawn), next(drawn)
            knots = ((0.0, speed0), (start, speed0), (start + length, final))
        command = next(drawn)
        depth = command + next(drawn)
        state = (next(drawn), next(drawn), next(drawn), depth)
        z_GB = next(drawn) if self.z_GB_m is not None else None
        x_GB = next(drawn)
        if self.x_GB_sign_random:  # a coin flip: -x_GB for a number below 1/2 (element for element)
            flip = next(drawn) < 0.5
            x_GB = np.where(flip, -x_GB, x_GB) if isinstance(flip, np.ndarray) else -x_GB if flip else x_GB
        return EpisodeConfig(
            speed_knots=knots,
            speed_relative=self.speed_relative,
            depth_command_m=command,
            initial_state=state,
            z_GB_m=z_GB,
            z_GB_scale=next(drawn),
            x_GB_m=x_GB,
            excess_buoyancy_N=next(drawn) * weight_N,
            crossflow_drag=next(drawn) if self.crossflow_drag is not None else None,
            sensor_noise=self.sensor_noise,
            disturbance_std_N=self.disturbance_std_N,
            duration_s=self.duration_s,
            free_surface=self.free_surface,
            sea_state=self.sea_state,
            wave_uniforms=tuple(drawn),  # the sea's: each wave's place in its bin, then its phase / (2 pi)
        )

    @cached_property
    def _draws(self) -> _Draws:
        """The intervals :meth:`sample` draws, in the order it uses them."""
        if self.components:  # then this scenario's own randomisation, on top of the component's draw
            return _Draws.of(
                (self.z_GB_scale,) if self.crossflow_drag is None else (self.z_GB_scale, self.crossflow_drag)
            )
        ramp = self.speed_ramp
        return _Draws.of(
            (
                self.initial_speed,
                *((ramp.start_s, ramp.duration_s, ramp.final_speed) if ramp is not None else ()),
                self.depth_command_m,
                self.initial_depth_offset_m,
                self.initial_pitch_rad,
                self.initial_heave_mps,
                self.initial_pitch_rate_radps,
                *((self.z_GB_m,) if self.z_GB_m is not None else ()),
                self.x_GB_m,
                *((_UNIT,) if self.x_GB_sign_random else ()),
                self.z_GB_scale,
                self.excess_buoyancy_fraction,
                *((self.crossflow_drag,) if self.crossflow_drag is not None else ()),
                *((_UNIT,) * (2 * self.sea_state.waves) if self.sea_state is not None else ()),
            )
        )
