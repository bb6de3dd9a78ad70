"""DivePlaneVectorEnv against SyncVectorEnv over the single environment, and its contract."""

from __future__ import annotations

import math
import re

import gymnasium as gym
import numba
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import subenv
from subenv.dynamics.integrate import LANES
from subenv.envs import DivePlaneVectorEnv
from subenv.envs import transition as tr
from subenv.envs.episodes import Loadings, draw_episode, write_episode
from subenv.scenarios import Scenario, SpeedRamp, get_scenario, scenario_names

ENV_IDS = subenv.env_ids()
MODES = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP)


def assert_same(native, reference, where: str = "") -> None:
    """Equal structure, dtypes and shapes; numbers equal to floating-point tolerance."""
    if isinstance(reference, dict):
        assert isinstance(native, dict) and native.keys() == reference.keys(), (
            where,
            native.keys() ^ reference.keys(),
        )
        for key in reference:
            assert_same(native[key], reference[key], f"{where}/{key}")
        return
    if isinstance(reference, tuple):
        assert isinstance(native, tuple) and len(native) == len(reference), where
        for k, (a, b) in enumerate(zip(native, reference, strict=True)):
            assert_same(a, b, f"{where}[{k}]")
        return
    native, reference = np.asarray(native), np.asarray(reference)
    assert (native.dtype, native.shape) == (reference.dtype, reference.shape), where
    if reference.dtype == object:
        for a, b in zip(native, reference, strict=True):
            if isinstance(b, np.ndarray):
                np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12, err_msg=where)
            else:
                assert a == b, (where, a, b)
    elif reference.dtype == bool:
        np.testing.assert_array_equal(native, reference, err_msg=where)
    else:
        np.testing.assert_allclose(native, reference, rtol=1e-12, atol=1e-12, err_msg=where)


def run_both(env_id: str, mode: AutoresetMode, steps: int, num_envs: int = 4, seed: int = 3, **kwargs):
    """Step the native env and SyncVectorEnv over gym.make(env_id) with the same seeds and actions."""
    sync = gym.make_vec(
        env_id, num_envs=num_envs, vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode}, **kwargs
    )
    native = gym.make_vec(env_id, num_envs=num_envs, autoreset_mode=mode, **kwargs)
    assert isinstance(native, DivePlaneVectorEnv) and isinstance(sync, SyncVectorEnv)
    assert_same(native.reset(seed=seed), sync.reset(seed=seed), "reset")
    rng = np.random.default_rng(seed)
    ends = 0
    for t in range(steps):
        # Mostly small actions, with bursts of full planes that end episodes (pitch limit, broaching).
        scale = 1.0 if (t // 25) % 3 == 0 else 0.2
        actions = (scale * rng.uniform(-1, 1, size=native.action_space.shape)).astype(np.float32)
        result, expected = native.step(actions), sync.step(actions)
        assert_same(result, expected, f"{env_id} {mode.value} step {t}")
        ends += int(np.sum(expected[2] | expected[3]))
    return ends


@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.value)
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_reproduces_sync_vector_env_step_for_step(env_id, mode):
    ends = run_both(env_id, mode, steps=250)
    # Over 250 steps at most envs, episodes end in the short and the violent scenarios.
    if env_id in ("subenv/Nominal-v0", "subenv/SpeedTransient-v0"):
        assert ends > 0


@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.value)
def test_reproduces_sync_vector_env_through_time_limits_and_other_configurations(mode):
    # TimeLimit truncation (max_episode_steps passed through make_vec), both controls, rate limit.
    assert run_both("subenv/DivePlane-v0", mode, steps=120, max_episode_steps=30) >= 4 * 3
    run_both("subenv/PeriscopeDepth-v0", mode, steps=150, control="independent", plane_rate_limit_radps=0.05)
    run_both("subenv/LowSpeed-v0", mode, steps=150, alpha=0.5, dt=0.25, substeps=1, max_pitch_rad=0.3)
    # 10 s steps at 2-2.6 u_cr leave RK4's stability region: "diverged" ends, last valid observation kept.
    assert (
        run_both(
            "subenv/SpeedTransient-v0",
            mode,
            steps=60,
            dt=10.0,
            substeps=1,
            max_pitch_rad=math.pi / 2,
            max_depth_error_m=1000.0,
        )
        > 10
    )


def test_a_single_env_matches_the_first_row_and_seeds_are_offset_per_env():
    native = gym.make_vec("subenv/DivePlane-v0", num_envs=3)
    obs, info = native.reset(seed=10)
    for i in range(3):
        single = gym.make("subenv/DivePlane-v0")
        single_obs, single_info = single.reset(seed=10 + i)
        np.testing.assert_array_equal(obs[i], single_obs)
        assert info["depth_command_m"][i] == single_info["depth_command_m"]
    assert native.unwrapped.np_random_seed == (10, 11, 12)


def test_seed_lists_none_and_reset_mask_match_sync_vector_env():
    sync = gym.make_vec("subenv/Nominal-v0", num_envs=3, vectorization_mode="sync")
    native = gym.make_vec("subenv/Nominal-v0", num_envs=3)
    assert_same(native.reset(seed=[5, 1, 9]), sync.reset(seed=[5, 1, 9]))
    actions = np.full((3, 1), 0.5, dtype=np.float32)
    assert_same(native.step(actions), sync.step(actions))
    mask = np.array([False, True, False])
    assert_same(
        native.reset(options={"reset_mask": mask.copy()}), sync.reset(options={"reset_mask": mask.copy()})
    )
    assert_same(native.step(actions), sync.step(actions))
    # seed=None keeps each sub-environment's generator: the next draws continue its stream.
    assert_same(native.reset(options={"speed": 1.0}), sync.reset(options={"speed": 1.0}))
    assert native.reset(options={"speed": 1.0})[1]["speed_mps"].tolist() == [1.0, 1.0, 1.0]


@pytest.mark.parametrize("scenario", ["Randomized", "Nominal"])
def test_results_do_not_depend_on_the_number_of_threads(scenario):
    # 600 sub-environments: ten blocks (the last one partial) in three runs of the compiled step, shared
    # among numba's threads (the suite runs with NUMBA_NUM_THREADS >= 2, tests/conftest.py), with resets
    # between the steps.
    n, results, ends = 2 * tr.BLOCKS_PER_RUN * LANES + 88, [], 0
    for threads in (1, 2):
        env = DivePlaneVectorEnv(num_envs=n, threads=threads, scenario=scenario)
        assert env.threads == threads
        env.reset(seed=0)
        rng = np.random.default_rng(0)
        trace = [env.step(rng.uniform(-1, 1, size=(n, 1))) for _ in range(80)]
        ends = sum(int(np.sum(t[2] | t[3])) for t in trace)
        results.append(trace)
    for a, b in zip(*results, strict=True):
        assert_same(a, b)
    if scenario == "Nominal":
        assert ends > 16  # resets ran between the threaded steps


# Every number of an episode drawn, the loading excepted (a batch draws one loading).
_DRAWS_ALL_BUT_THE_LOADING = Scenario(
    name="DrawsAllButTheLoading",
    description="every episode quantity drawn",
    speed_ratio=(0.5, 2.5),
    speed_ramp=SpeedRamp(final_speed_ratio=(0.3, 0.6), start_s=(10.0, 20.0), duration_s=(30.0, 60.0)),
    depth_command_m=(5.0, 20.0),
    initial_depth_offset_m=(-1.0, 1.0),
    initial_pitch_rad=(-0.05, 0.05),
    initial_heave_mps=(-0.02, 0.02),
    initial_pitch_rate_radps=(-0.01, 0.01),
    sensor_noise=True,
    disturbance_std_N=0.7,
    duration_s=100.0,
)
# Every number of an episode drawn, the loading among them (and the sign of x_GB).
_DRAWS_EVERYTHING = _DRAWS_ALL_BUT_THE_LOADING.replace(
    name="DrawsEverything",
    z_GB_m=(0.006, 0.009),
    z_GB_scale=(0.9, 1.1),
    x_GB_m=(0.001, 0.003),
    x_GB_sign_random=True,
    excess_buoyancy_fraction=(-1e-3, 1e-3),
    crossflow_drag=(0.2, 0.5),
)
# A mixture of one component picks without drawing a number (rng.integers(1) draws none).
_ONE_COMPONENT = Scenario(
    name="OneComponent",
    description="BallastOffset, mixed",
    components=("BallastOffset",),
    z_GB_scale=(0.9, 1.1),
)
# A loading per episode in every component, whose free surfaces (and seas) differ: a batch computes the
# loadings of each free surface together.
_TWO_SURFACES = Scenario(
    name="TwoSurfaces",
    description="near the surface in a sea, or deep",
    components=("PeriscopeDepthWaves", "BallastOffset", "Nominal", "PeriscopeDepth-v1"),
    z_GB_scale=(0.9, 1.1),
)
_BATCHES = (
    *scenario_names(),
    _DRAWS_ALL_BUT_THE_LOADING,
    _DRAWS_EVERYTHING,
    _ONE_COMPONENT,
    _TWO_SURFACES,
)


@numba.njit
def _draws_of_numba_s_generators(rngs, highs, out):
    for j in range(len(rngs)):
        for k in range(highs.shape[0]):
            out[j, 3 * k] = rngs[j].integers(0, highs[k])
            out[j, 3 * k + 1] = rngs[j].random()
            out[j, 3 * k + 2] = rngs[j].normal(0.0, 2.0)


def test_numba_s_generator_integers_draws_numpy_s_numbers_for_ranges_below_2_to_the_32():
    # A batch of resets picks a mixture's component with numba's Generator.integers (transition's
    # draw_reset_numbers): the same numbers as NumPy's Generator.integers, each generator left in the same
    # state (its buffered half of a 64-bit draw included), for any seed and range size below 2**32 (beyond,
    # numba's differs: 2**62 + 3 gives other numbers).
    highs = np.array([1, 2, 3, 5, 6, 7, 9, 100, 1000, 2**16 + 1, 2**31 - 1, 2**32 - 1, 2**32], dtype=np.int64)
    seeds = range(1000)
    rngs = numba.typed.List([np.random.default_rng(seed) for seed in seeds])
    out = np.empty((len(seeds), 3 * len(highs)))
    _draws_of_numba_s_generators(rngs, highs, out)
    for j, seed in enumerate(seeds):
        g = np.random.default_rng(seed)
        expected = [x for high in highs.tolist() for x in (g.integers(high), g.random(), g.normal(0.0, 2.0))]
        assert out[j].tolist() == expected, seed
        assert rngs[j].bit_generator.state == g.bit_generator.state, seed


def test_which_scenarios_draw_their_resets_in_batches():
    assert all(get_scenario(name).samples_in_batches for name in scenario_names())
    nested = Scenario(
        name="Nested", description="a mixture of a mixture", components=("Randomized", "Nominal")
    )
    assert not nested.samples_in_batches
    with pytest.raises(
        ValueError, match=r"scenario 'Nested' cannot draw in batches: a component of the mixture"
    ):
        nested.sample_batch(np.zeros((3, 5)), 1.0)
    randomized = get_scenario("Randomized")
    counts = [get_scenario(name).uniforms_per_episode + 2 for name in randomized.components]
    assert randomized.uniforms_per_pick == tuple(counts)
    uniforms = np.zeros((3, get_scenario("Nominal").uniforms_per_episode))
    with pytest.raises(ValueError, match=r"uniforms has shape \(3, 2\): must be \(n, 3\)"):
        get_scenario("Nominal").sample_batch(uniforms[:, :2], 1.0)
    with pytest.raises(ValueError, match=r"pick=6 is invalid: must be an integer in \[0, 5\]"):
        randomized.sample_batch(uniforms, 1.0, pick=6)


@pytest.mark.parametrize("scenario", _BATCHES, ids=lambda s: s if isinstance(s, str) else s.name)
def test_batch_resets_draw_exactly_what_one_reset_at_a_time_draws(scenario):
    # A batch of resets (a vector env's) takes each sub-environment's numbers in a compiled loop (a
    # mixture's pick among them) and turns them into records over arrays, a loading per episode where
    # the scenario draws one: the same records, bit for bit, the same episodes and vehicles (made when
    # asked for), and every generator left where one reset at a time leaves it.
    n = 64
    batch = DivePlaneVectorEnv(num_envs=n, scenario=scenario)
    batch.reset(seed=5)
    config = batch.config
    loadings = Loadings(config)
    generators = [np.random.default_rng(s) for s in range(100, 100 + n)]
    for i in range(n):
        batch._generators[i] = batch._rngs[i] = np.random.default_rng(100 + i)
    batch._draw_batch(np.arange(n))
    drawn, vehicles = [], []
    for i, g in enumerate(generators):
        draw, loading, episode, state = draw_episode(config, g, loadings)
        drawn.append(draw)
        vehicles.append(loading.vehicle)
        episodes, states = np.zeros(1, tr.EPISODE_DTYPE), np.zeros(1, tr.STATE_DTYPE)
        write_episode(episodes, 0, episode)
        write_episode(states, 0, state)
        assert batch._episode[i].tobytes() == episodes[0].tobytes(), i
        assert batch._state[i].tobytes() == states[0].tobytes(), i
        if episode["n_waves"] > 0:  # and the sea, where the episode has one
            assert batch._seas[i].tobytes() == episode["waves"].tobytes(), i
        assert batch._generators[i].bit_generator.state == g.bit_generator.state
    assert batch.episodes == drawn and batch.vehicles == vehicles
    assert all(type(v) is float for draw in drawn for v in (*draw.initial_state, draw.depth_command_m))
    values = np.stack(
        [batch._state["depth_m"], batch._episode["depth_command_m"], batch._state["disturbance_N"]]
    )
    assert np.unique(values, axis=1).shape[1] == n  # drawn, not shared
    components = config.scenario.components
    if len(components) > 1:  # (64 resets pick every one of a few components)
        assert len(np.unique(batch._unbuilt_pick)) == len(components)


def test_a_batch_of_resets_refuses_the_loadings_one_reset_at_a_time_refuses():
    # Some loadings of this scenario, on a vehicle already heavy (B / W = 0.7), are beyond what a submerged
    # vehicle may have (B < W / 2): a batch, which checks its loadings as a box, refuses them as one reset
    # at a time does, naming B / W. (On a neutral vehicle no scenario can draw them: the scenario's bound.)
    suboff = subenv.load_vehicle("suboff")
    heavy = suboff.variant(excess_buoyancy_N=-0.3 * suboff.weight_N)
    sinking = Scenario(name="Sinking", description="too heavy", excess_buoyancy_fraction=(-0.4, -0.25))
    for n in (2, 64):  # one at a time, and a batch
        env = DivePlaneVectorEnv(num_envs=n, scenario=sinking, vehicle=heavy)
        with pytest.raises(
            ValueError, match=r"buoyancy_N=.* are invalid: B / W = 0\.[34].* must be in \[0\.5, 2"
        ):
            env.reset(seed=0)
    # A loading without a critical speed, for speeds relative to it: named, in a batch as one at a time.
    unstable = subenv.load_vehicle("suboff").variant(z_GB_m=-0.01)
    for n in (2, 64):
        env = DivePlaneVectorEnv(num_envs=n, scenario="LowSpeed", vehicle=unstable)
        with pytest.raises(
            ValueError,
            match=r"'LowSpeed' gives speeds relative .* has none with this episode's loading: z_GB=-0\.01 m "
            r"gives restoring moment .* exists only for a positive restoring moment",
        ):
            env.reset(seed=0)


@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.value)
def test_many_simultaneous_resets_reproduce_sync_vector_env(mode):
    # Full planes end most episodes of Nominal within a few steps of each other: autoresets come in
    # batches (drawn as arrays), and each is still the sub-environment's own next episode.
    sync = gym.make_vec(
        "subenv/Nominal-v0", num_envs=32, vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode}
    )
    native = gym.make_vec("subenv/Nominal-v0", num_envs=32, autoreset_mode=mode)
    assert_same(native.reset(seed=8), sync.reset(seed=8))
    biggest = 0
    for t in range(120):
        actions = np.full((32, 1), 1.0 if t % 40 < 30 else -1.0, dtype=np.float32)
        result, expected = native.step(actions), sync.step(actions)
        assert_same(result, expected, f"step {t}")
        biggest = max(biggest, int(np.sum(expected[2] | expected[3])))
    assert biggest >= 8
    assert native.unwrapped.episodes == [env.unwrapped.episode for env in sync.envs]


def test_episodes_of_batches_from_different_scenarios_are_each_their_own():
    # A batch keeps its episodes as their scenario and numbers until `episodes` is read. A switch to a
    # scenario that draws more numbers, back again, and resets one at a time in between must leave
    # every sub-environment with its own episode, as SyncVectorEnv's.
    sync = gym.make_vec("subenv/Nominal-v0", num_envs=32, vectorization_mode="sync")
    native = gym.make_vec("subenv/Nominal-v0", num_envs=32)
    native.reset(seed=4)
    sync.reset(seed=4)
    widths = []
    for t in range(150):
        if t in (40, 100):
            scenario = "SpeedTransient" if t == 40 else "Nominal"
            native.unwrapped.set_scenario(scenario)
            sync.call("set_scenario", scenario)
        if t in (70, 149):
            assert native.unwrapped.episodes == [env.unwrapped.episode for env in sync.envs], t
        actions = np.full((32, 1), 1.0 if t % 40 < 30 else -1.0, dtype=np.float32)
        assert_same(native.step(actions), sync.step(actions), f"step {t}")
        widths.append(native.unwrapped._unbuilt_uniforms.shape[1])
    assert (
        widths[0] == get_scenario("Nominal").uniforms_per_episode < widths[-1]
    )  # SpeedTransient drew in a batch


def test_episodes_of_a_batch_keep_the_length_scaling_of_the_scenario_they_were_drawn_from():
    # A batch's episodes are made when asked for: Froude-scaled to the vehicle by the reference length of
    # their own scenario, also after a switch to a scenario with another (here none: episodes as drawn).
    as_drawn = get_scenario("Nominal").replace(name="NominalAsDrawn", reference_length_m=None)
    sync = gym.make_vec("subenv/Nominal-v0", num_envs=8, vectorization_mode="sync", vehicle="remus100")
    native = gym.make_vec("subenv/Nominal-v0", num_envs=8, vehicle="remus100")
    native.reset(seed=4)
    sync.reset(seed=4)
    native.unwrapped.set_scenario(as_drawn)
    sync.call("set_scenario", as_drawn)
    assert native.unwrapped.episodes == [env.unwrapped.episode for env in sync.envs]


_TWO_RUNS = 2 * tr.BLOCKS_PER_RUN * LANES  # sub-environments that two threads share


def _step_threaded_in_child(queue, inherited) -> None:  # runs in a forked process
    env = DivePlaneVectorEnv(num_envs=_TWO_RUNS, threads=2)
    env.reset(seed=0)
    queue.put(env.step(np.zeros((_TWO_RUNS, 1)))[0].shape)
    queue.put([inherited.step(np.zeros((_TWO_RUNS, 1)))[0] for _ in range(3)])  # the parent's env, forked


def test_threaded_stepping_survives_fork():
    import multiprocessing

    # numba's TBB layer, after the parent has stepped on two threads: the forked child steps on two
    # threads too, its own env and its copy of the parent's, with the parent's results.
    env = DivePlaneVectorEnv(num_envs=_TWO_RUNS, threads=2)
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros((_TWO_RUNS, 1)))
    assert numba.threading_layer() == "tbb"
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_step_threaded_in_child, args=(queue, env))
    child.start()
    shape, child_obs = queue.get(timeout=60), queue.get(timeout=60)
    child.join(60)
    assert child.exitcode == 0 and shape == (_TWO_RUNS, 8)
    for obs in child_obs:  # the child stepped its copy as the parent steps the original
        np.testing.assert_array_equal(obs, env.step(np.zeros((_TWO_RUNS, 1)))[0])


def test_autoreset_modes_are_declared_and_same_step_keeps_the_final_observation():
    env = gym.make_vec("subenv/Nominal-v0", num_envs=2, autoreset_mode="SameStep")
    assert env.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP
    assert gym.make_vec("subenv/Nominal-v0", num_envs=2).metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    env.reset(seed=0)
    while True:  # full planes pitch the boat past the limit
        obs, _, terminated, _, info = env.step(np.ones((2, 1), dtype=np.float32))
        if terminated.any():
            break
    i = int(np.flatnonzero(terminated)[0])
    assert info["_final_obs"][i] and info["final_info"]["termination_reason"][i] == "pitch_limit"
    assert abs(info["final_obs"][i][1]) > 0.6  # the terminal pitch, in the final observation
    assert info["time_s"][i] == 0.0 and obs[i][1] == np.float32(info["pitch_rad"][i])  # the new episode


def test_disabled_autoreset_needs_an_explicit_masked_reset():
    env = DivePlaneVectorEnv(num_envs=2, scenario="Nominal", autoreset_mode="Disabled")
    env.reset(seed=0)
    while not env.step(np.ones((2, 1)))[2].any():
        pass
    with pytest.raises(RuntimeError, match="reset_mask"):
        env.step(np.zeros((2, 1)))
    env.reset(options={"reset_mask": np.array([True, True])})
    env.step(np.zeros((2, 1)))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"num_envs": 0}, r"num_envs=0 is invalid: must be an integer >= 1"),
        ({"num_envs": -3}, r"num_envs=-3 is invalid"),
        ({"num_envs": 2.5}, r"num_envs=2\.5 is invalid"),
        ({"num_envs": True}, r"num_envs=True is invalid"),
        ({"num_envs": 2, "max_episode_steps": 0}, r"max_episode_steps=0 is invalid"),
        (
            {"num_envs": 2, "autoreset_mode": "Sometimes"},
            r"autoreset_mode='Sometimes' is invalid: must be one of",
        ),
        ({"num_envs": 2, "render_mode": "human"}, r"render_mode='human' is invalid"),
        ({"num_envs": 2, "threads": 0}, r"threads=0 is invalid: must be None or an integer >= 1"),
        ({"num_envs": 2, "scenario": "Fast"}, r"scenario='Fast' is unknown"),  # the single env's checks
    ],
)
def test_bad_constructor_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        DivePlaneVectorEnv(**kwargs)
    with pytest.raises(ValueError, match=message):
        gym.make_vec("subenv/DivePlane-v0", **kwargs)


def test_bad_actions_raise_before_any_sub_environment_steps():
    env = gym.make_vec("subenv/Nominal-v0", num_envs=3)
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros((3, 1)))
    env.reset(seed=0)
    state = env.unwrapped.state
    for shape in [(3, 2), (2, 1), (3, 1, 1), (1,), ()]:
        with pytest.raises(ValueError, match=r"actions has shape .*: must have shape \(3, 1\) \(num_envs=3"):
            env.step(np.zeros(shape))
    for bad in (np.nan, np.inf):
        actions = np.zeros((3, 1))
        actions[2, 0] = bad
        with pytest.raises(ValueError, match=rf"actions\[2\]=\[{bad}\] is invalid: must be finite"):
            env.step(actions)
    np.testing.assert_array_equal(env.unwrapped.state, state)  # nothing moved
    env.step(np.zeros(3))  # (num_envs,) is accepted for a one-dimensional action
    independent = gym.make_vec("subenv/Nominal-v0", num_envs=2, control="independent")
    independent.reset(seed=0)
    with pytest.raises(ValueError, match=r"must have shape \(2, 2\) \(num_envs=2, control='independent'\)"):
        independent.step(np.zeros(2))


def test_render_rgb_array_shows_every_sub_environment():
    pytest.importorskip("pygame", reason="the 'render' extra is not installed")
    native = gym.make_vec("subenv/PeriscopeDepth-v0", num_envs=3, render_mode="rgb_array")
    single = gym.make("subenv/PeriscopeDepth-v0", render_mode="rgb_array")
    native.reset(seed=4)
    single.reset(seed=4)
    for _ in range(15):
        native.step(np.full((3, 1), 0.5, dtype=np.float32))
        single.step(np.array([0.5], dtype=np.float32))
    frames = native.render()
    assert len(frames) == 3 and all(f.shape == (480, 720, 3) and f.dtype == np.uint8 for f in frames)
    np.testing.assert_array_equal(frames[0], single.render())
    with pytest.warns(UserWarning, match="without specifying any render mode"):
        assert gym.make_vec("subenv/Nominal-v0", num_envs=2).render() is None


@pytest.mark.parametrize("scenario", ["Randomized", "Nominal"])  # episodes drawn one at a time, in a batch
def test_vector_env_pickles_and_continues_identically(scenario, compiled_signatures):
    import pickle

    env = DivePlaneVectorEnv(num_envs=4, scenario=scenario)
    env.reset(seed=1)
    env.step(np.zeros((4, 1)))
    compiled = compiled_signatures()
    copy = pickle.loads(pickle.dumps(env))
    assert not copy._constants.flags.writeable and not copy.config.hull.flags.writeable  # (as the original's)
    actions = np.random.default_rng(0).uniform(-1, 1, size=(4, 1))
    assert_same(copy.step(actions), env.step(actions))
    assert copy.episodes == env.episodes and None not in env.episodes
    assert compiled_signatures() == compiled  # (the copy ran the original's compiled step)


def test_every_id_registers_the_vector_entry_point():
    for env_id in ENV_IDS:
        assert gym.spec(env_id).vector_entry_point == "subenv.envs.vector:DivePlaneVectorEnv"
    env = gym.make_vec("subenv/LowSpeed-v0", num_envs=2)
    assert env.unwrapped.max_episode_steps == gym.spec("subenv/LowSpeed-v0").max_episode_steps
    assert env.unwrapped.config == gym.make("subenv/LowSpeed-v0").unwrapped.config
    assert env.single_action_space == gym.make("subenv/LowSpeed-v0").action_space
    assert math.isfinite(env.reset(seed=0)[1]["critical_speed_mps"][0])


# --- misuse refused as SyncVectorEnv refuses it (issue 34, finding 11) ------------------------------
_N = 3
_ACTIONS = np.zeros((_N, 1), dtype=np.float32)


def _reset_then(call):  # type: ignore[no-untyped-def]
    """A misuse after a seeded reset."""

    def misuse(env):  # type: ignore[no-untyped-def]
        env.reset(seed=0)
        return call(env)

    return misuse


def _step_after_an_episode_ended(env):  # type: ignore[no-untyped-def]
    env.reset(seed=0)
    for _ in range(10_000):  # full planes pitch the boat past the limit within a minute
        if np.any(np.logical_or(*env.step(np.ones((_N, 1), dtype=np.float32))[2:4])):
            return env.step(_ACTIONS)
    raise AssertionError("no episode ended")


def _outcome(vectorization_mode: str, misuse, kwargs: dict) -> Exception | None:  # type: ignore[no-untyped-def]
    """What making a vector env of ``subenv/Nominal-v0`` with ``kwargs`` and ``misuse`` of it raised (None:
    nothing)."""
    try:
        if vectorization_mode == "sync":
            env = SyncVectorEnv([lambda: gym.make("subenv/Nominal-v0") for _ in range(_N)], **kwargs)
        else:
            env = gym.make_vec("subenv/Nominal-v0", num_envs=_N, **kwargs)
        misuse(env)
    except Exception as error:  # (any exception: it is what is compared)
        return error
    assert isinstance(env, (SyncVectorEnv, DivePlaneVectorEnv))
    return None


# SyncVectorEnv's own checks and those it leaves to the sub-environments (ours): the native env raises the
# same type with the same message, compared at run time. The type is the one Gymnasium 1.4 raises: before
# 1.4, SyncVectorEnv checks the seed list and the reset mask with assert statements.
_SAME_AS_SYNC = {
    "step before reset": (lambda env: env.step(_ACTIONS), gym.error.ResetNeeded),
    "a seed list too short": (lambda env: env.reset(seed=[0] * (_N - 1)), ValueError),
    "a seed list too long": (lambda env: env.reset(seed=list(range(_N + 1))), ValueError),
    "a seed tuple too short": (lambda env: env.reset(seed=(0,) * (_N - 1)), ValueError),
    "a negative seed": (lambda env: env.reset(seed=-1), ValueError),
    "reset_mask a list": (_reset_then(lambda env: env.reset(options={"reset_mask": [True] * _N})), TypeError),
    "reset_mask too long": (
        _reset_then(lambda env: env.reset(options={"reset_mask": np.ones(_N + 1, dtype=bool)})),
        ValueError,
    ),
    "reset_mask 2-d": (
        _reset_then(lambda env: env.reset(options={"reset_mask": np.ones((_N, 1), dtype=bool)})),
        ValueError,
    ),
    "reset_mask of integers": (
        _reset_then(lambda env: env.reset(options={"reset_mask": np.ones(_N, dtype=int)})),
        TypeError,
    ),
    "reset_mask all False": (
        _reset_then(lambda env: env.reset(options={"reset_mask": np.zeros(_N, dtype=bool)})),
        ValueError,
    ),
    "options a list": (lambda env: env.reset(options=[("speed", 1.0)]), ValueError),
    "an unknown option": (lambda env: env.reset(options={"sped": 1.0}), ValueError),
    "an option out of range": (lambda env: env.reset(options={"speed": -1.0}), ValueError),
    # Not misuse for either: both go on.
    "step after close": (_reset_then(lambda env: (env.close(), env.step(_ACTIONS))), None),
    "actions of shape (num_envs,)": (_reset_then(lambda env: env.step(np.zeros(_N))), None),
}


@pytest.mark.parametrize("case", list(_SAME_AS_SYNC))
def test_misuse_raises_what_sync_vector_env_raises_with_its_message(case):
    misuse, error = _SAME_AS_SYNC[case]
    theirs, ours = _outcome("sync", misuse, {}), _outcome("vector_entry_point", misuse, {})
    if isinstance(theirs, AssertionError) and error is not AssertionError:  # Gymnasium before 1.4
        assert type(ours) is error, repr(ours)
    else:
        assert (type(ours), str(ours)) == (type(theirs), str(theirs))


# SyncVectorEnv passes the batch to its sub-environments, whose message names one action, or zip() finds the
# batch short or long: the same type, and the native env's message names the batch.
_SAME_TYPE_AS_SYNC = {
    "actions for fewer sub-environments": (
        _reset_then(lambda env: env.step(np.zeros((_N - 1, 1)))),
        rf"^actions has shape \({_N - 1}, 1\): must have shape \({_N}, 1\) \(num_envs={_N}",
    ),
    "actions for more sub-environments": (
        _reset_then(lambda env: env.step(np.zeros((_N + 1, 1)))),
        rf"^actions has shape \({_N + 1}, 1\): must have shape \({_N}, 1\)",
    ),
    "actions of two planes in dual control": (
        _reset_then(lambda env: env.step(np.zeros((_N, 2)))),
        rf"^actions has shape \({_N}, 2\): must have shape \({_N}, 1\)",
    ),
    "a NaN action": (
        _reset_then(lambda env: env.step(np.full((_N, 1), np.nan))),
        r"^actions\[0\]=\[nan\] is invalid: must be finite",
    ),
    "a negative seed in a list": (
        lambda env: env.reset(seed=[0, -1, 2]),
        r"^seed\[1\]=-1 is invalid: must be None or an integer >= 0",
    ),
}


@pytest.mark.parametrize("case", list(_SAME_TYPE_AS_SYNC))
def test_misuse_of_a_batch_raises_sync_vector_env_s_type_with_a_message_naming_the_batch(case):
    misuse, message = _SAME_TYPE_AS_SYNC[case]
    theirs, ours = _outcome("sync", misuse, {}), _outcome("vector_entry_point", misuse, {})
    assert type(ours) is type(theirs) is ValueError, (repr(theirs), repr(ours))
    assert re.search(message, str(ours)), str(ours)


def test_an_unknown_autoreset_mode_raises_sync_vector_env_s_type_naming_the_argument():
    theirs = _outcome("sync", lambda env: None, {"autoreset_mode": "Sometimes"})
    ours = _outcome("vector_entry_point", lambda env: None, {"autoreset_mode": "Sometimes"})
    assert type(ours) is type(theirs) is ValueError
    assert str(ours).startswith("autoreset_mode='Sometimes' is invalid: must be one of ['NextStep'")


# Where SyncVectorEnv fails in its own code, on a type it does not check (len() of a float, `in` an int), or
# checks with an assert statement, or takes a bool as an integer, the native env does what the README
# promises (ValueError naming the argument; numpy integer seeds taken as the integer). Recorded here, so
# that a Gymnasium that checks these calls for the native env to match it.
_SYNC_FAILS_IN_ITS_OWN_CODE = {
    "a float seed": (lambda env: env.reset(seed=1.5), {}, TypeError, (ValueError, r"^seed=1\.5 is invalid")),
    "a numpy integer seed": (lambda env: env.reset(seed=np.int64(3)), {}, TypeError, None),
    "a bool seed": (lambda env: env.reset(seed=True), {}, None, (ValueError, r"^seed=True is invalid")),
    "options not a dict": (
        lambda env: env.reset(options=5),
        {},
        TypeError,
        (ValueError, r"^options=5 is invalid: must be None or a dict"),
    ),
    "a step after an episode ended, autoreset disabled": (
        _step_after_an_episode_ended,
        {"autoreset_mode": AutoresetMode.DISABLED},
        AssertionError,
        (RuntimeError, r"have ended their episodes and autoreset_mode is DISABLED: reset them with reset\("),
    ),
}


@pytest.mark.parametrize("case", list(_SYNC_FAILS_IN_ITS_OWN_CODE))
def test_where_sync_vector_env_does_not_check_the_native_env_refuses_by_name(case):
    misuse, kwargs, sync_raises, native_raises = _SYNC_FAILS_IN_ITS_OWN_CODE[case]
    theirs, ours = _outcome("sync", misuse, kwargs), _outcome("vector_entry_point", misuse, kwargs)
    assert type(theirs) is (sync_raises or type(None)), repr(theirs)
    if native_raises is None:
        assert ours is None, repr(ours)
    else:
        assert type(ours) is native_raises[0] and re.search(native_raises[1], str(ours)), repr(ours)
