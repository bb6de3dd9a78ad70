"""Resets of the dive-plane environments: an episode's draw turned into the transition's records.

A reset draws an :class:`~subenv.scenarios.EpisodeConfig` from the scenario with the
sub-environment's generator (:func:`draw_episode`), then the heave force's first value, and writes
the episode's records (:data:`~subenv.envs.transition.EPISODE_DTYPE`,
:data:`~subenv.envs.transition.STATE_DTYPE`): :func:`write_episode`, and its sea, if it has one
(:func:`write_sea`). A vector environment draws a batch of resets as arrays
(:func:`draw_episode_batch`): the same numbers from the same generators, turned into episodes and
loadings by the same functions over arrays, and into records by the same :func:`write_episode`.

The environments' ``reset(options=...)`` are checked here (:func:`check_options`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Final, NamedTuple

import numpy as np
from gymnasium.utils import seeding

from subenv import _validation as check
from subenv.analysis.critical import critical_speed, critical_speeds
from subenv.dynamics._jit import read_only
from subenv.dynamics.free_surface import NO_FREE_SURFACE, FreeSurface
from subenv.dynamics.model import model_params, pack_params
from subenv.dynamics.waves import MAX_WAVES, WAVE_FIELDS
from subenv.envs import transition as tr
from subenv.envs.config import (
    MAX_DEPTH_COMMAND_M,
    MAX_HEAVE_MPS,
    MAX_PITCH_RATE_RADPS,
    MAX_SPEED_MPS,
    DivePlaneConfig,
)
from subenv.scenarios.scenario import EpisodeConfig
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "OPTIONS",
    "EpisodeBatch",
    "EpisodeGroup",
    "Loading",
    "LoadingKey",
    "Loadings",
    "check_options",
    "draw_episode",
    "draw_episode_batch",
    "episode_table",
    "for_vehicle",
    "new_seas",
    "write_episode",
    "write_sea",
]

OPTIONS: Final = ("speed", "depth_command", "initial_state")
"""The keys of ``reset(options=...)``."""
STATE_KEYS: Final = ("pitch", "heave", "pitch_rate", "depth")
"""The keys of ``options["initial_state"]`` as a mapping."""
_LOADING_CACHE_SIZE: Final = 1024  # loadings kept per environment


class LoadingKey(NamedTuple):
    """What an episode's draw loads the vehicle with: :meth:`Vehicle.variant
    <subenv.vehicles.Vehicle.variant>`'s arguments and the free surface's suction; floats, or arrays of
    one value per episode of a batch (where the draw's are)."""

    z_GB_m: Any
    x_GB_m: Any
    excess_buoyancy_N: Any
    crossflow_drag: Any  # None: the vehicle's
    suction_factor: float

    def loading(self) -> dict[str, Any]:
        """The arguments of :meth:`Vehicle.variant <subenv.vehicles.Vehicle.variant>` (and of
        :meth:`~subenv.vehicles.Vehicle.loading_fields`)."""
        return {
            "z_GB_m": self.z_GB_m,
            "x_GB_m": self.x_GB_m,
            "excess_buoyancy_N": self.excess_buoyancy_N,
            "crossflow_drag": self.crossflow_drag,
        }


_LOADING_NAMES: Final = LoadingKey._fields[:4]
"""The fields of a :class:`LoadingKey` that are :meth:`Vehicle.variant
<subenv.vehicles.Vehicle.variant>`'s arguments."""


class Loading(NamedTuple):
    """An episode's loading and what the transition needs of it; a batch's holds arrays, one value (or
    row) per episode."""

    key: LoadingKey
    vehicle: Vehicle | None  # the episode's (a variant of the configured one); None for a batch's
    params: np.ndarray  # ModelParams, packed (PARAM_FIELDS order), read-only; (n, P) for a batch
    critical_speed_mps: Any  # nan: none (z_GB <= 0)
    froude_scale_mps: Any  # sqrt(g z_GB); nan for z_GB <= 0


class Loadings:
    """The loadings of an environment's episodes: one episode's memoised (a new draw of the same loading
    costs nothing), a batch's computed as arrays."""

    def __init__(self, config: DivePlaneConfig) -> None:
        self.base = config.vehicle
        self.alpha = config.alpha
        self._found: dict[LoadingKey, Loading] = {}
        # The box of a batch's loadings checked so far (_check): the least and largest of each field.
        self._checked: np.ndarray | None = None

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        read_only(*(loading.params for loading in self._found.values()))  # (as made: see _loading)

    def of(self, draw: EpisodeConfig) -> Loading:
        """The loading of an episode's draw, or of a batch's (:meth:`Scenario.sample_batch
        <subenv.scenarios.Scenario.sample_batch>`): then arrays, each element what one episode's draw
        with that element's numbers gives, bit for bit (:meth:`of_batch`)."""
        key = self._key(draw)
        sizes = [np.size(value) for value in key if isinstance(value, np.ndarray)]
        return self.of_batch([draw], [max(sizes)])[0] if sizes else self._memoised(key, draw)

    def of_batch(self, draws: Sequence[EpisodeConfig], sizes: Sequence[int]) -> list[Loading]:
        """The loadings of a batch's draws (:meth:`Scenario.sample_batch
        <subenv.scenarios.Scenario.sample_batch>`, draw ``k`` of ``sizes[k]`` episodes), each as
        :meth:`of` gives it; the vehicles of those with a loading per episode are made on demand
        (:meth:`vehicle`).

        The draws with a loading per episode (of the mixture's components that a batch's resets picked)
        are checked and reduced to parameters and critical speeds together, as one array of loadings
        (one per free surface among them): a batch's Python work does not grow with its picks.
        """
        keys = [self._key(draw) for draw in draws]
        found: list[Loading | None] = [None] * len(draws)
        varied = []  # (the draws with a loading per episode)
        for k, key in enumerate(keys):
            if any(isinstance(value, np.ndarray) for value in key):
                varied.append(k)
            else:
                found[k] = self._memoised(key, draws[k])
        surfaces = {k: draws[k].free_surface or NO_FREE_SURFACE for k in varied}
        unset = (None, None, None, self.base.crossflow_drag)  # (only C_D may be left as the vehicle's)
        for surface in dict.fromkeys(surfaces.values()):  # (one, unless a mixture's components differ)
            mine = [k for k in varied if surfaces[k] == surface]
            bounds = np.cumsum([0, *(sizes[k] for k in mine)]).tolist()
            columns = np.empty((len(_LOADING_NAMES), bounds[-1]))  # their loadings, draw after draw
            for at, k in enumerate(mine):
                for j, value in enumerate(keys[k][: len(_LOADING_NAMES)]):
                    columns[j, bounds[at] : bounds[at + 1]] = value if value is not None else unset[j]
            self._check(columns)
            z_GB, x_GB, excess, drag = columns
            whole = self._loading(LoadingKey(z_GB, x_GB, excess, drag, surface.suction_factor), None, surface)
            for at, k in enumerate(mine):
                part = slice(bounds[at], bounds[at + 1])
                found[k] = Loading(
                    keys[k],
                    None,
                    whole.params[part],
                    whole.critical_speed_mps[part],
                    whole.froude_scale_mps[part],
                )
        return [loading for loading in found if loading is not None]

    def vehicle(self, key: LoadingKey) -> Vehicle:
        """The vehicle of one episode's loading (checked: ``ValueError`` for an invalid one)."""
        return self.base.variant(**key.loading())

    def _key(self, draw: EpisodeConfig) -> LoadingKey:
        """The loading of ``draw`` (floats, or arrays over a batch's episodes)."""
        base = self.base
        z_GB = draw.z_GB_m if draw.z_GB_m is not None else base.z_GB_m
        return LoadingKey(
            z_GB * draw.z_GB_scale,
            base.x_GB_m + draw.x_GB_m,
            base.excess_buoyancy_N + draw.excess_buoyancy_N,
            draw.crossflow_drag,
            (draw.free_surface or NO_FREE_SURFACE).suction_factor,
        )

    def _memoised(self, key: LoadingKey, draw: EpisodeConfig) -> Loading:
        """The loading of one episode's ``key`` (floats), its vehicle made and checked once."""
        found = self._found.get(key)
        if found is None:
            if len(self._found) >= _LOADING_CACHE_SIZE:
                self._found.clear()
            free_surface = draw.free_surface or NO_FREE_SURFACE
            found = self._found[key] = self._loading(key, self.vehicle(key), free_surface)
        return found

    def _loading(self, key: LoadingKey, vehicle: Vehicle | None, free_surface: FreeSurface) -> Loading:
        """The numbers of ``key``'s loading (floats where ``vehicle`` is given, else arrays): each
        computed once, by the functions that compute one vehicle's, from the loading's fields."""
        base = self.base
        fields = base.loading_fields(**key.loading())
        params = pack_params(model_params(base, free_surface, fields))
        read_only(params)
        ucr = critical_speeds(base, self.alpha, fields)
        z_GB = fields["z_G_m"] - base.z_B_m  # (Vehicle.z_GB_m of each loading)
        froude = np.sqrt(np.where(z_GB > 0, base.gravity_m_s2 * z_GB, math.nan))
        if vehicle is not None:
            return Loading(key, vehicle, params, float(ucr), float(froude))
        return Loading(key, None, params, ucr, froude)

    def _check(self, columns: np.ndarray) -> None:
        """Check a batch's loadings (``columns``: a row per field of :data:`_LOADING_NAMES`) as
        :meth:`vehicle` checks one: the box of the loadings checked so far grows to hold them, and is
        checked again where it grows (:meth:`Vehicle.check_loadings
        <subenv.vehicles.Vehicle.check_loadings>`); within it, nothing is left to check."""
        box = np.stack([columns.min(axis=1), columns.max(axis=1)], axis=1)  # (nan: outside any box)
        checked = self._checked
        if checked is not None:
            if np.all(box[:, 0] >= checked[:, 0]) and np.all(box[:, 1] <= checked[:, 1]):
                return
            box = np.stack(
                [np.minimum(box[:, 0], checked[:, 0]), np.maximum(box[:, 1], checked[:, 1])], axis=1
            )
        self.base.check_loadings(**dict(zip(_LOADING_NAMES, box, strict=True)))
        self._checked = box


def for_vehicle(config: DivePlaneConfig, draw: EpisodeConfig) -> EpisodeConfig:
    """The scenario's draw Froude-scaled to the vehicle's length (:attr:`DivePlaneConfig.length_ratio
    <subenv.envs.config.DivePlaneConfig.length_ratio>`; the draw itself on the reference length)."""
    return draw.froude_scaled(config.length_ratio)


def draw_episode(
    config: DivePlaneConfig,
    rng: np.random.Generator,
    loadings: Loadings,
    options: Mapping[str, Any] | None = None,
) -> tuple[EpisodeConfig, Loading, dict[str, Any], dict[str, Any]]:
    """One reset from ``rng``: the scenario's draw, then the initial heave force
    (``rng.normal(0, disturbance_std_N)`` where the draw has a disturbance).

    Returns the draw, its loading, and the episode's and the state's fields (:func:`episode_fields`).
    ``options`` must have passed :func:`check_options`.
    """
    draw = for_vehicle(config, config.scenario.sample(rng, config.vehicle.weight_N))
    std = draw.disturbance_std_N
    disturbance = float(rng.normal(0.0, std)) if std > 0 else 0.0
    loading = loadings.of(draw)
    return (draw, loading, *episode_fields(config, draw, loading, disturbance, options))


def episode_table(config: DivePlaneConfig, seeds: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The episodes of resets seeded with ``seeds``, drawn ahead: row ``k`` is the episode that
    ``DivePlaneEnv(config=config).reset(seed=seeds[k])`` draws (:func:`draw_episode`, from the
    generator that seed gives the environment), for an environment that cannot draw its own
    (:mod:`subenv.jax` resets from such a table).

    Returns the episodes' records (:data:`~subenv.envs.transition.EPISODE_DTYPE`), their states at the
    reset (:data:`~subenv.envs.transition.STATE_DTYPE`, speed not yet set: nan) and their seas
    (:func:`new_seas`), one row per seed.
    """
    values = [check.integer(f"seeds[{k}]", seed, 0) for k, seed in enumerate(seeds)]
    check.require("seeds", seeds, len(values) > 0, "at least one seed")
    episodes, states = (
        np.zeros(len(values), dtype=tr.EPISODE_DTYPE),
        np.zeros(len(values), dtype=tr.STATE_DTYPE),
    )
    seas = new_seas(len(values))
    loadings = Loadings(config)
    for k, seed in enumerate(values):
        rng, _ = seeding.np_random(seed)
        _, _, episode, state = draw_episode(config, rng, loadings)
        write_episode(episodes, k, episode)
        write_episode(states, k, state)
        write_sea(seas, k, episode)
    return episodes, states, seas


class EpisodeGroup(NamedTuple):
    """The episodes of a batch of resets that picked one component of a mixture (all of a plain
    scenario's): their draw and loading, arrays over them, and their records' fields."""

    rows: np.ndarray  # their positions in the batch
    draw: EpisodeConfig
    loading: Loading
    episode: dict[str, Any]
    state: dict[str, Any]


class EpisodeBatch(NamedTuple):
    """A batch of resets (:func:`draw_episode_batch`): each one's pick and uniform numbers (row ``j``'s
    first ``uniforms_per_pick[picks[j]]``), from which :meth:`Scenario.episode_from_uniforms
    <subenv.scenarios.Scenario.episode_from_uniforms>` makes its draw again, and its episodes by pick."""

    picks: np.ndarray
    uniforms: np.ndarray
    groups: list[EpisodeGroup]


def draw_episode_batch(
    config: DivePlaneConfig, rngs: Any, indices: np.ndarray, loadings: Loadings
) -> EpisodeBatch:
    """The resets of the sub-environments ``indices``, each from its own generator ``rngs[i]`` (a numba
    typed list), drawn as arrays: for a scenario that :attr:`~subenv.scenarios.Scenario.samples_in_batches`.

    Each generator gives what :func:`draw_episode` takes from it (without options), in its order: a
    mixture's pick and the uniform numbers of the draw
    (:func:`~subenv.envs.transition.draw_reset_numbers`), then the initial heave force
    (:func:`~subenv.envs.transition.draw_initial_disturbances`) with the standard deviation of the
    episode drawn. The episodes of one pick are made together (:meth:`Scenario.sample_batch
    <subenv.scenarios.Scenario.sample_batch>`, :meth:`Loadings.of`, :func:`episode_fields`): the same
    functions as one reset's, over arrays, and so the same numbers.
    """
    scenario, weight_N = config.scenario, config.vehicle.weight_N
    counts = np.array(scenario.uniforms_per_pick, dtype=np.int64)
    n = len(indices)
    picks, uniforms = np.empty(n, dtype=np.int64), np.empty((n, int(counts.max())))
    tr.draw_reset_numbers(rngs, indices, counts, picks, uniforms)
    if len(counts) > 1:  # a mixture: the resets of each pick together
        order = np.argsort(picks, kind="stable")
        starts = [0, *(np.flatnonzero(np.diff(picks[order])) + 1).tolist()]
        every_pick = [
            (order[a:b], int(picks[order[a]])) for a, b in zip(starts, [*starts[1:], n], strict=True)
        ]
    else:
        every_pick = [(np.arange(n), 0)]
    draws, stds = [], np.empty(n)
    for rows, pick in every_pick:
        draw = for_vehicle(config, scenario.sample_batch(uniforms[rows, : counts[pick]], weight_N, pick))
        stds[rows] = draw.disturbance_std_N
        draws.append(draw)
    disturbances = np.empty(n)
    tr.draw_initial_disturbances(rngs, indices, stds, disturbances)
    groups = []
    loadings_drawn = loadings.of_batch(draws, [len(rows) for rows, _ in every_pick])
    for (rows, _), draw, loading in zip(every_pick, draws, loadings_drawn, strict=True):
        episode, state = episode_fields(config, draw, loading, disturbances[rows], None)
        groups.append(EpisodeGroup(rows, draw, loading, episode, state))
    return EpisodeBatch(picks, uniforms, groups)


def episode_fields(
    config: DivePlaneConfig,
    draw: EpisodeConfig,
    loading: Loading,
    disturbance: Any,
    options: Mapping[str, Any] | None,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The fields of the episode's and the state's records at a reset (the state's speed is set when
    it is observed: :func:`subenv.envs.transition.observe`).

    A value is an array over the episodes where a batch's draw (or ``disturbance``) has one. The
    episode's ``"waves"`` are its sea (None: calm), for :func:`write_sea`, not a field of its record.
    """
    ucr = loading.critical_speed_mps
    if draw.speed_relative and not np.all(np.isfinite(ucr)):
        raise ValueError(
            f"scenario {config.scenario.name!r} gives speeds relative to the critical speed, but "
            f"vehicle {config.vehicle.name!r} has none with {_without_critical_speed(config, loading)}"
        )
    scale = ucr if draw.speed_relative else 1.0
    knots = [(t, u * scale) for t, u in draw.speed_knots]
    command = draw.depth_command_m
    pitch, heave, rate, depth = draw.initial_state
    if options:
        if "speed" in options:
            knots = [(0.0, options["speed"])]
        if "depth_command" in options:
            # Keep the drawn initial offset from the ordered depth, unless it would broach.
            offset = depth - command
            command = float(options["depth_command"])
            depth = command + offset
            if not depth > config.broach_depth_m:
                depth = command
        if "initial_state" in options:
            pitch, heave, rate, depth = _initial_state(
                config, options["initial_state"], (pitch, heave, rate, depth), command
            )
    if len(knots) > tr.MAX_KNOTS:
        raise ValueError(
            f"the speed profile has {len(knots)} knots; the environment takes at most {tr.MAX_KNOTS}"
        )
    # One row of knots, or one per episode of a batch.
    shape = (len(disturbance), tr.MAX_KNOTS) if isinstance(disturbance, np.ndarray) else tr.MAX_KNOTS
    knot_time, knot_speed = np.zeros(shape), np.zeros(shape)
    for k, (t, u) in enumerate(knots):
        knot_time[..., k], knot_speed[..., k] = t, u
    n_waves, waves = _sea(draw, config.vehicle, shape)
    episode = {
        "params": loading.params,
        "n_knots": len(knots),
        "knot_time_s": knot_time,
        "knot_speed_mps": knot_speed,
        "depth_command_m": command,
        "disturbance_std_N": draw.disturbance_std_N,
        "sensor_noise": draw.sensor_noise,
        "duration_s": draw.duration_s,
        "critical_speed_mps": ucr,
        "froude_scale_mps": loading.froude_scale_mps,
        "n_waves": n_waves,
        "waves": waves,
    }
    state = {
        "pitch_rad": pitch,
        "heave_mps": heave,
        "pitch_rate_radps": rate,
        "depth_m": depth,
        "stern_plane_rad": 0.0,
        "bow_plane_rad": 0.0,
        "time_s": 0.0,
        "steps": 0,
        "disturbance_N": disturbance,
        "speed_mps": math.nan,
        "distance_m": 0.0,
    }
    return episode, state


def _without_critical_speed(config: DivePlaneConfig, loading: Loading) -> str:
    """The first of ``loading``'s episodes without a critical speed, and why (what
    :func:`~subenv.analysis.critical.critical_speed` says of its vehicle)."""
    first = int(np.argmin(np.isfinite(loading.critical_speed_mps)))
    one = {name: np.asarray(v).flat[first] if np.ndim(v) else v for name, v in loading.key.loading().items()}
    variant = config.vehicle.variant(**one)
    try:
        critical_speed(variant, config.alpha)
    except ValueError as error:  # (it names the loading's z_GB and restoring moment, or the allocation)
        return f"this episode's loading: {error}"
    return f"this episode's loading (z_GB={variant.z_GB_m!r} m, alpha={config.alpha!r})"


def _sea(draw: EpisodeConfig, vehicle: Vehicle, knot_shape: Any) -> tuple[int, np.ndarray | None]:
    """The episode's sea as the transition reads it (:meth:`subenv.dynamics.waves.SeaState.components`,
    shape (WAVE_FIELDS, MAX_WAVES)), one per episode of a batch: its number of waves and their numbers
    (0 and None: calm). ``vehicle``'s hull, water and gravity: those of every loading of it."""
    sea = draw.sea_state
    batch = knot_shape[0] if isinstance(knot_shape, tuple) else None
    if sea is None:
        return 0, None
    units = np.asarray(draw.wave_uniforms, dtype=float)  # (2 n,) or (2 n, batch)
    jitter, phase = units[: sea.waves], 2.0 * math.pi * units[sea.waves :]
    x, breadth = np.asarray(vehicle.hull.x_m), np.asarray(vehicle.hull.breadth_m)
    rho, g = vehicle.water_density_kg_m3, vehicle.gravity_m_s2
    if batch is None:
        return sea.waves, sea.components(jitter, phase, x, breadth, rho, g)
    waves = np.stack([sea.components(jitter[:, i], phase[:, i], x, breadth, rho, g) for i in range(batch)])
    return sea.waves, waves


def write_episode(records: np.ndarray, index: int | np.ndarray, fields: Mapping[str, Any]) -> None:
    """Write ``fields`` (:func:`episode_fields`) into ``records[index]``; ``index`` an int, or an array of
    indices with a field's value one per index or shared. Each field of the records is set by its name."""
    names = records.dtype.names or ()
    if isinstance(index, (int, np.integer)):
        records[index] = tuple([fields[name] for name in names])  # (one assignment: a reset's Python cost)
        return
    for name in names:
        records[name][index] = fields[name]


def write_sea(seas: np.ndarray, index: int | np.ndarray, fields: Mapping[str, Any]) -> None:
    """Write the sea of ``fields`` (:func:`episode_fields`) into ``seas[index]``
    (:func:`subenv.envs.transition.step`'s ``seas``); nothing for a calm episode, whose row is not read."""
    if fields["n_waves"] > 0:
        seas[index] = fields["waves"]


def new_seas(n: int) -> np.ndarray:
    """The seas of ``n`` sub-environments (:func:`subenv.envs.transition.step`'s ``seas``), all calm.
    (Zeros from the allocator: memory the calm ones never touch costs nothing.)"""
    return np.zeros((n, WAVE_FIELDS, MAX_WAVES))


def check_options(config: DivePlaneConfig, options: Mapping[str, Any] | None) -> dict[str, Any]:
    """``reset(options=...)`` checked before anything is drawn (only ``initial_state``'s depth is
    checked against the ordered depth once that is known)."""
    if not options:
        return {}
    unknown = set(options) - set(OPTIONS)
    if unknown:
        raise ValueError(f"reset options {sorted(unknown)} are unknown: allowed options are {list(OPTIONS)}")
    checked = dict(options)
    if "speed" in options:
        checked["speed"] = check.positive("options['speed']", options["speed"], upper=MAX_SPEED_MPS)
    if "depth_command" in options:
        value = options["depth_command"]
        check.require(
            "options['depth_command']",
            value,
            check.is_finite(value) and config.broach_depth_m < value <= MAX_DEPTH_COMMAND_M,
            f"a number in ({config.broach_depth_m:.4g}, {MAX_DEPTH_COMMAND_M:g}] m (below the hull radius)",
        )
    if "initial_state" in options:
        _initial_state(config, options["initial_state"], (0.0, 0.0, 0.0, math.nan), math.nan)
    return checked


def _initial_state(
    config: DivePlaneConfig, value: Any, drawn: tuple[float, float, float, float], command: float
) -> tuple[float, float, float, float]:
    """``options["initial_state"]`` over the drawn state; the depth is checked where ``command`` is known."""
    if isinstance(value, Mapping):
        unknown = set(value) - set(STATE_KEYS)
        if unknown:
            raise ValueError(
                f"options['initial_state'] has unknown keys {sorted(unknown)}: allowed keys are "
                f"{list(STATE_KEYS)}"
            )
        state = [value.get(k, d) for k, d in zip(STATE_KEYS, drawn, strict=True)]
    elif isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, str) and len(value) == 4:
        state = list(value)
    else:
        raise ValueError(
            f"options['initial_state']={value!r} is invalid: must be (pitch, heave, pitch_rate, depth) "
            f"or a mapping with keys {list(STATE_KEYS)}"
        )
    for key, v in zip(STATE_KEYS, state, strict=True):
        if not check.is_number(v):
            raise ValueError(f"options['initial_state']={value!r} is invalid: must hold real numbers")
        unknown_depth = key == "depth" and math.isnan(command) and isinstance(v, float) and math.isnan(v)
        check.require(f"options['initial_state'][{key!r}]", v, check.is_finite(v) or unknown_depth, "finite")
    state = [float(v) for v in state]
    pitch, heave, rate, depth = state
    limit = config.max_pitch_rad
    check.require(
        "options['initial_state']['pitch']",
        pitch,
        abs(pitch) < limit,
        f"in (-{limit}, {limit}) rad (max_pitch_rad)",
    )
    check.require(
        "options['initial_state']['heave']",
        heave,
        abs(heave) <= MAX_HEAVE_MPS,
        f"in [-{MAX_HEAVE_MPS}, {MAX_HEAVE_MPS}] m/s",
    )
    check.require(
        "options['initial_state']['pitch_rate']",
        rate,
        abs(rate) <= MAX_PITCH_RATE_RADPS,
        f"in [-{MAX_PITCH_RATE_RADPS}, {MAX_PITCH_RATE_RADPS}] rad/s",
    )
    low = config.broach_depth_m
    if math.isnan(command):
        if not math.isnan(depth):
            check.require(
                "options['initial_state']['depth']",
                depth,
                low < depth,
                f"in ({low:.4g}, ...] m (below the hull radius)",
            )
        return pitch, heave, rate, depth
    high = command + config.max_depth_error_m
    check.require(
        "options['initial_state']['depth']",
        depth,
        low < depth <= high,
        f"in ({low:.4g}, {high:.4g}] m (below the hull radius, within max_depth_error_m of the ordered "
        "depth)",
    )
    return pitch, heave, rate, depth
