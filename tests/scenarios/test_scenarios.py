"""Scenarios as data: the registry, what each shipped scenario draws, bad definitions."""

from __future__ import annotations

import collections

import numpy as np
import pytest

import subenv
from subenv.dynamics.free_surface import FreeSurface
from subenv.dynamics.model import PARAM_FIELDS
from subenv.scenarios import Scenario, SpeedRamp, get_scenario, register_scenario, scenario_names
from subenv.scenarios.presets import BASE_SCENARIOS


def _episodes(name: str, n: int = 40, **env_kwargs):
    env = subenv.DivePlaneEnv(scenario=name, **env_kwargs)
    out = []
    for seed in range(n):
        _, info = env.reset(seed=seed)
        out.append((env.episode, env.vehicle, info, env))
    return out


def test_registry_lists_and_rejects():
    assert scenario_names()[:7] == [
        "Nominal",
        "LowSpeed",
        "NearCritical",
        "SpeedTransient",
        "PeriscopeDepth",
        "BallastOffset",
        "Randomized",
    ]
    assert scenario_names()[-8:] == [
        "PeriscopeDepth-v1",
        "PeriscopeDepthWaves",
        "PeriscopeDepth-v2",
        "PeriscopeDepthWaves-v1",
        "HardRateTransient",
        "HardBallastLimits",
        "HardWaves18",
        "HardGusts",
    ]
    with pytest.raises(ValueError, match=r"scenario='Slow' is unknown: must be one of \['Nominal'"):
        get_scenario("Slow")
    with pytest.raises(ValueError, match="already registered"):
        register_scenario(get_scenario("Nominal"))
    with pytest.raises(ValueError, match=r"component 'Nope' is unknown"):
        register_scenario(Scenario(name="Mix", description="", components=("Nope",)))


def test_nominal_is_the_thesis_design_speed():
    for _, _, info, _ in _episodes("Nominal", 5):
        assert info["speed_mps"] == pytest.approx(5 * 0.3048)


@pytest.mark.parametrize(("name", "low", "high"), [("LowSpeed", 0.3, 0.8), ("NearCritical", 0.85, 1.15)])
def test_speeds_are_placed_relative_to_the_critical_speed(name, low, high):
    ratios = [info["speed_mps"] / info["critical_speed_mps"] for *_, info, _ in _episodes(name)]
    assert low <= min(ratios) and max(ratios) <= high
    assert max(ratios) - min(ratios) > 0.5 * (high - low)  # actually spread over the interval


def test_relative_speeds_follow_the_plane_allocation():
    """With alpha = -1 the critical speed is lower (Fig. 3-9); LowSpeed stays below it."""
    for _, vehicle, info, _env in _episodes("LowSpeed", 5, alpha=-1.0):
        assert info["critical_speed_mps"] == pytest.approx(subenv.analysis.critical_speed(vehicle, -1.0))
        assert info["speed_mps"] < info["critical_speed_mps"] < 0.5


def test_periscope_depth_is_near_the_surface_and_light():
    for _episode, vehicle, info, _ in _episodes("PeriscopeDepth", 10):
        assert 1.0 <= info["depth_command_m"] <= 1.2
        assert 2e-4 <= vehicle.excess_buoyancy_N / vehicle.weight_N <= 1e-3


def test_periscope_depth_v1_is_neutral_with_the_free_surface_and_the_waves_draw_a_sea_per_seed():
    for episode, vehicle, info, env in _episodes("PeriscopeDepth-v1", 10):
        assert 1.0 <= info["depth_command_m"] <= 1.2 and vehicle.excess_buoyancy_N == 0.0
        assert episode.free_surface is not None and episode.sea_state is None
        assert env._episode["params"][0][PARAM_FIELDS.index("rho_suction")] == vehicle.water_density_kg_m3
    seas = [episode.wave_uniforms for episode, _, _, _ in _episodes("PeriscopeDepthWaves", 3)]
    again = [episode.wave_uniforms for episode, _, _, _ in _episodes("PeriscopeDepthWaves", 3)]
    assert seas == again and len(set(seas)) == 3  # a seed gives its sea, another seed another
    assert len(seas[0]) == 2 * get_scenario("PeriscopeDepthWaves").sea_state.waves
    # Version 0 keeps its name, a later version is registered beside it.
    assert get_scenario("PeriscopeDepth").excess_buoyancy_fraction == (2e-4, 1e-3)
    assert get_scenario("PeriscopeDepth-v1").env_id == "subenv/PeriscopeDepth-v1"


def test_bad_versions_and_free_surfaces_name_the_field():
    with pytest.raises(ValueError, match="version"):
        get_scenario("Nominal").replace(version=-1)
    with pytest.raises(ValueError, match="a mixture takes its free surface and sea from its components"):
        Scenario(name="Mix", description="", components=("Nominal",), free_surface=FreeSurface())


def test_ballast_offset_draws_both_signs():
    offsets = [vehicle.x_GB_m for _, vehicle, _, _ in _episodes("BallastOffset")]
    assert min(offsets) <= -0.5e-3 and max(offsets) >= 0.5e-3
    assert all(0.5e-3 <= abs(x) <= 3e-3 for x in offsets)


def test_randomized_draws_from_every_scenario_and_randomises_the_loading():
    episodes = _episodes("Randomized", 120)
    z_GB = np.array([v.z_GB_m for _, v, _, _ in episodes])
    drag = np.array([v.crossflow_drag for _, v, _, _ in episodes])
    assert z_GB.min() < 0.9 * 0.03048 and z_GB.max() > 1.15 * 0.03048
    assert drag.min() < 0.1 and drag.max() > 0.5
    assert all(e.sensor_noise and e.disturbance_std_N > 0 for e, *_ in episodes)
    # Every component scenario shows up: recognise them by their signatures.
    kinds = collections.Counter()
    for episode, vehicle, _info, _ in episodes:
        if len(episode.speed_knots) > 1:
            kinds["SpeedTransient"] += 1
        elif vehicle.excess_buoyancy_N > 0:
            kinds["PeriscopeDepth"] += 1
        elif vehicle.x_GB_m != 0:
            kinds["BallastOffset"] += 1
        elif not episode.speed_relative:
            kinds["Nominal"] += 1
        else:
            kinds["LowSpeed or NearCritical"] += 1
    assert len(kinds) == 5 and min(kinds.values()) >= 5
    assert {s.name for s in BASE_SCENARIOS} == set(get_scenario("Randomized").components)


def test_disturbance_force_varies_within_an_episode():
    env = subenv.DivePlaneEnv(scenario="Randomized")
    env.reset(seed=0, options={"speed": 1.0})
    forces = [env.step(np.zeros(1, dtype=np.float32))[-1]["disturbance_N"] for _ in range(50)]
    assert np.std(forces) > 0.01 and max(map(abs, forces)) < 10.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"speed_mps": (1.0, 0.5)}, r"speed_mps=\(1\.0, 0\.5\) is invalid: must be a \(low, high\) pair"),
        ({"speed_mps": (-1.0, 0.5)}, r"speed_mps=\(-1\.0, 0\.5\) is invalid"),
        ({"speed_ratio": (0.5, 0.4)}, r"speed_ratio=\(0\.5, 0\.4\) is invalid"),
        (
            {"speed_mps": (1.0, 1.0), "speed_ratio": (0.5, 0.5)},
            r"speed_mps=\(1\.0, 1\.0\), speed_ratio=\(0\.5, 0\.5\) are invalid: give one of them",
        ),
        (
            {
                "speed_ratio": (0.5, 0.5),
                "speed_ramp": SpeedRamp(
                    start_s=(1.0, 1.0), duration_s=(1.0, 1.0), final_speed_mps=(0.2, 0.2)
                ),
            },
            r"its final speed must be given as the initial speed is, final_speed_ratio",
        ),
        ({"duration_s": 0.0}, r"duration_s=0\.0 is invalid: must be a finite number > 0"),
        ({"z_GB_scale": (0.0, 1.0)}, r"z_GB_scale=\(0\.0, 1\.0\) is invalid"),
        ({"disturbance_std_N": -1.0}, r"disturbance_std_N=-1\.0 is invalid"),
        (  # (B - W) / W below -0.5: B / W below the vehicles' 0.5 (subenv.vehicles.BUOYANCY_RATIO_RANGE)
            {"excess_buoyancy_fraction": (-0.7, -0.3)},
            r"excess_buoyancy_fraction=\(-0\.7, -0\.3\) is invalid: .* with -0\.5 <= low <= high <= 1\.0",
        ),
        ({"name": "lowercase"}, r"name='lowercase' is invalid: must be a CamelCase identifier"),
    ],
)
def test_bad_scenario_definitions(kwargs, message):
    fields = {"name": "Custom", "description": "test"} | kwargs
    with pytest.raises(ValueError, match=message):
        Scenario(**fields)
    with pytest.raises(ValueError, match="duration_s"):
        SpeedRamp(final_speed_mps=(0.1, 0.2), start_s=(0.0, 1.0), duration_s=(-1.0, 1.0))
    with pytest.raises(ValueError, match="give exactly one of them"):
        SpeedRamp(
            final_speed_mps=(0.1, 0.2),
            final_speed_ratio=(0.1, 0.2),
            start_s=(0.0, 1.0),
            duration_s=(1.0, 1.0),
        )


def test_a_custom_scenario_object_runs_without_registration():
    custom = get_scenario("LowSpeed").replace(name="VeryLow", speed_ratio=(0.2, 0.2), duration_s=10.0)
    env = subenv.DivePlaneEnv(scenario=custom)
    _, info = env.reset(seed=0)
    assert info["speed_mps"] == pytest.approx(0.2 * info["critical_speed_mps"])


def test_a_draw_is_its_uniform_numbers_mapped_onto_the_intervals() -> None:
    # The definition of a plain scenario's draw: rng.random(k), one number per interval that is not
    # fixed, mapped as low + (high - low) u. sample() and sample_batch() both apply it.
    scenario = _ALL_RANDOM
    k = scenario.uniforms_per_episode
    for seed in range(20):
        rng, twin = np.random.default_rng(seed), np.random.default_rng(seed)
        uniforms = twin.random(k)
        assert scenario.sample(rng, 1000.0) == scenario.episode_from_uniforms(uniforms, 1000.0)
        assert rng.random() == twin.random()  # both generators are left in the same state
    rows = np.random.default_rng(0).random((5, k))
    batch = scenario.replace(
        x_GB_sign_random=False,
        z_GB_m=(0.007, 0.007),
        z_GB_scale=(1.0, 1.0),
        x_GB_m=(0.003, 0.003),
        excess_buoyancy_fraction=(0.012, 0.012),
        crossflow_drag=(0.5, 0.5),
    )
    drawn = batch.sample_batch(rows[:, : batch.uniforms_per_episode], 1000.0)
    for i in range(5):
        one = batch.episode_from_uniforms(rows[i, : batch.uniforms_per_episode], 1000.0)
        assert one.depth_command_m == drawn.depth_command_m[i]
        assert one.initial_state == tuple(
            float(v[i]) if isinstance(v, np.ndarray) else v for v in drawn.initial_state
        )
    with pytest.raises(ValueError, match=r"uniforms has 2 numbers: must have 15"):
        scenario.episode_from_uniforms([0.5, 0.5], 1000.0)


@pytest.mark.parametrize("name", ["Randomized", "Mixed"])
def test_a_mixture_s_draw_is_its_pick_and_then_uniform_numbers(name) -> None:
    # A mixture's draw: rng.integers(len(components)), then its component's numbers and its own, all
    # uniform (rng.random(k)), which episode_from_uniforms and sample_batch (a vector env's resets) map
    # as sample() does: the episode of a pick and numbers, element for element in a batch.
    scenario = get_scenario(name)
    counts = scenario.uniforms_per_pick
    rows = collections.defaultdict(list)
    for seed in range(60):
        rng, twin = np.random.default_rng(seed), np.random.default_rng(seed)
        pick = int(twin.integers(len(counts)))
        uniforms = twin.random(counts[pick])
        one = scenario.sample(rng, 1000.0)
        assert one == scenario.episode_from_uniforms(uniforms, 1000.0, pick)
        assert rng.bit_generator.state == twin.bit_generator.state
        rows[pick].append((uniforms, one))
    assert len(rows) == len(counts)  # every component picked
    for pick, drawn in rows.items():
        batch = scenario.sample_batch(np.array([u for u, _ in drawn]), 1000.0, pick)
        for i, (_, one) in enumerate(drawn):
            assert batch.z_GB_scale[i] == one.z_GB_scale and batch.crossflow_drag[i] == one.crossflow_drag
            assert np.broadcast_to(batch.x_GB_m, len(drawn))[i] == one.x_GB_m
            assert batch.depth_command_m[i] == one.depth_command_m
        assert (batch.sensor_noise, batch.disturbance_std_N) == (one.sensor_noise, one.disturbance_std_N)


_ALL_RANDOM = Scenario(
    # Every quantity drawn, from pairwise disjoint intervals: a value landing in another's field shows.
    name="AllRandom",
    description="every quantity drawn",
    speed_mps=(1.2, 1.4),
    speed_ramp=SpeedRamp(final_speed_mps=(0.2, 0.4), start_s=(10.0, 20.0), duration_s=(30.0, 60.0)),
    depth_command_m=(8.0, 9.5),
    initial_depth_offset_m=(-2.0, -1.0),
    initial_pitch_rad=(0.02, 0.05),
    initial_heave_mps=(0.1, 0.15),
    initial_pitch_rate_radps=(0.001, 0.002),
    z_GB_m=(0.006, 0.009),
    z_GB_scale=(0.9, 1.1),
    x_GB_m=(0.003, 0.004),
    x_GB_sign_random=True,
    excess_buoyancy_fraction=(0.011, 0.013),
    crossflow_drag=(0.45, 0.6),
)


def test_sample_puts_every_draw_in_its_place() -> None:
    rng = np.random.default_rng(2)
    signs = set()
    for _ in range(50):
        c = _ALL_RANDOM.sample(rng, 1000.0)
        (t0, u0), (t1, u1), (t2, u2) = c.speed_knots
        assert t0 == 0.0 and u0 == u1 and 1.2 <= u0 <= 1.4
        assert 10.0 <= t1 <= 20.0 and 30.0 <= t2 - t1 <= 60.0 and 0.2 <= u2 <= 0.4
        assert 8.0 <= c.depth_command_m <= 9.5 and -2.0 <= c.initial_state[3] - c.depth_command_m <= -1.0
        pitch, heave, rate, _ = c.initial_state
        assert 0.02 <= pitch <= 0.05 and 0.1 <= heave <= 0.15 and 0.001 <= rate <= 0.002
        assert 0.006 <= c.z_GB_m <= 0.009 and 0.9 <= c.z_GB_scale <= 1.1 and 0.003 <= abs(c.x_GB_m) <= 0.004
        assert 11.0 <= c.excess_buoyancy_N <= 13.0 and 0.45 <= c.crossflow_drag <= 0.6
        signs.add(c.x_GB_m > 0)
    assert signs == {True, False}


def test_sample_draws_one_number_per_random_quantity() -> None:
    # The 15 random quantities of AllRandom (the sign of x_GB is one), and Nominal's 3 (command, offset,
    # pitch).
    for scenario, expected in ((_ALL_RANDOM, 15), (get_scenario("Nominal"), 3)):
        rng, twin = np.random.default_rng(5), np.random.default_rng(5)
        for _ in range(20):
            scenario.sample(rng, 1000.0)
            twin.random(expected)
            assert rng.bit_generator.state == twin.bit_generator.state
