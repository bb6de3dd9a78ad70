"""DivePlaneEnv against the Gymnasium and SB3 contracts, over every registered id."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

import subenv
from subenv.dynamics import derivatives, model_params, rk4
from subenv.envs import OBSERVATION_NAMES

ENV_IDS = subenv.env_ids()
REWARD_TERMS = ("reward_depth", "reward_pitch", "reward_effort", "reward_termination")
INFO_KEYS = (
    "time_s",
    "depth_m",
    "depth_command_m",
    "depth_error_m",
    "pitch_rad",
    "heave_mps",
    "pitch_rate_radps",
    "stern_plane_rad",
    "bow_plane_rad",
    "speed_mps",
    "froude_number",
    "critical_speed_mps",
    "critical_froude",
    "termination_reason",
    *REWARD_TERMS,
)


def test_every_scenario_has_an_id_and_the_headline_id_is_randomized():
    expected = {
        "subenv/DivePlane-v0",
        "subenv/Nominal-v0",
        "subenv/LowSpeed-v0",
        "subenv/NearCritical-v0",
        "subenv/SpeedTransient-v0",
        "subenv/PeriscopeDepth-v0",
        "subenv/BallastOffset-v0",
        "subenv/Randomized-v0",
        "subenv/Mixed-v0",
        "subenv/PeriscopeDepth-v1",
        "subenv/PeriscopeDepthWaves-v0",
        "subenv/PeriscopeDepth-v2",
        "subenv/PeriscopeDepthWaves-v1",
        "subenv/HardRateTransient-v0",
        "subenv/HardBallastLimits-v0",
        "subenv/HardWaves18-v0",
        "subenv/HardGusts-v0",
    }
    assert set(ENV_IDS) == expected
    assert all(env_id in gym.registry for env_id in ENV_IDS)
    assert gym.spec("subenv/DivePlane-v0").kwargs["scenario"] == "Randomized"
    # A later version is its own registry entry; version 0 keeps its name (and its seeded episodes).
    assert gym.spec("subenv/PeriscopeDepth-v1").kwargs["scenario"] == "PeriscopeDepth-v1"
    assert gym.spec("subenv/PeriscopeDepth-v0").kwargs["scenario"] == "PeriscopeDepth"


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_check_env(env_id):
    env = gym.make(env_id, disable_env_checker=True)
    gym_check_env(env.unwrapped, skip_render_check=True)


def _sb3_check_env():
    """SB3's env checker, or a skip where SB3 is not installed (the other tests here need no extra)."""
    checker = pytest.importorskip(
        "stable_baselines3.common.env_checker", reason="the 'rl' extra is not installed"
    )
    return checker.check_env


@pytest.mark.parametrize("vehicle", subenv.available_vehicles())
def test_every_shipped_vehicle_passes_gymnasiums_checker(vehicle):
    """Each vehicle file (the Froude-scaled full-scale SUBOFF too) makes a valid env."""
    env = gym.make("subenv/DivePlane-v0", vehicle=vehicle, disable_env_checker=True)
    assert env.unwrapped.base_vehicle.name == vehicle
    gym_check_env(env.unwrapped, skip_render_check=True)


@pytest.mark.parametrize("vehicle", subenv.available_vehicles())
def test_every_shipped_vehicle_passes_sb3s_checker(vehicle):
    sb3_check_env = _sb3_check_env()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_check_env(gym.make("subenv/DivePlane-v0", vehicle=vehicle), warn=True)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env_passes_without_warnings(env_id):
    sb3_check_env = _sb3_check_env()
    env = gym.make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_check_env(env, warn=True)


def _rollout(env_id: str, seed: int, steps: int = 150, **kwargs):
    env = gym.make(env_id, **kwargs)
    env.action_space.seed(seed)
    obs, info = env.reset(seed=seed)
    trace = [(obs, info)]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        trace.append((obs, reward, terminated, truncated, info))
        if terminated or truncated:
            obs, info = env.reset()
            trace.append((obs, info))
    return trace


def _same(a, b) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    if isinstance(a, float) and math.isnan(a):
        return isinstance(b, float) and math.isnan(b)
    return a == b


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_same_seed_gives_identical_rollout(env_id):
    assert _same(_rollout(env_id, 3), _rollout(env_id, 3))


def test_different_seeds_draw_different_episodes():
    firsts = {tuple(_rollout("subenv/DivePlane-v0", s, steps=0)[0][0].tolist()) for s in range(5)}
    assert len(firsts) == 5


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_info_reports_the_required_quantities(env_id):
    env = gym.make(env_id)
    _, info = env.reset(seed=0)
    assert set(INFO_KEYS) <= set(info)
    _obs, reward, *_, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    assert set(INFO_KEYS) <= set(info)
    assert reward == pytest.approx(sum(info[k] for k in REWARD_TERMS))
    assert info["critical_speed_mps"] > 0
    assert info["froude_number"] == pytest.approx(
        info["speed_mps"] / math.sqrt(env.unwrapped.vehicle.gravity_m_s2 * env.unwrapped.vehicle.z_GB_m)
    )
    assert info["critical_froude"] == pytest.approx(
        info["froude_number"] * info["critical_speed_mps"] / info["speed_mps"]
    )


def test_depth_reward_is_one_minus_tanh_of_the_scaled_error():
    env = gym.make("subenv/Nominal-v0")
    scale = env.unwrapped.config.depth_scale_m
    errors = []
    for offset in (0.0, 1e-9, 0.3, 2.0, 7.5, 20.0):  # from on depth to the edge of the depth band
        _, info = env.reset(
            seed=0, options={"depth_command": 40.0, "initial_state": {"depth": 40.0 + offset}}
        )
        *_, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
        error = abs(info["depth_error_m"])
        errors.append(error)
        assert info["reward_depth"] == pytest.approx(1.0 - math.tanh(error / scale), rel=1e-14, abs=1e-16)
    assert min(errors) < 0.1 and max(errors) > 15.0


def test_observation_matches_info_without_noise():
    env = gym.make("subenv/Nominal-v0")
    env.reset(seed=1)
    obs, *_, info = env.step(np.array([0.3], dtype=np.float32))
    expected = [
        info["depth_error_m"],
        info["pitch_rad"],
        info["heave_mps"],
        info["pitch_rate_radps"],
        info["speed_mps"],
        info["stern_plane_rad"],
        info["bow_plane_rad"],
        info["depth_m"],
    ]
    assert len(OBSERVATION_NAMES) == obs.shape[0] == 8
    np.testing.assert_allclose(obs, np.array(expected, dtype=np.float32))
    assert info["stern_plane_rad"] == pytest.approx(0.3 * 0.4)


def test_randomized_observations_are_noisy_around_the_truth():
    env = gym.make("subenv/DivePlane-v0")
    env.reset(seed=4)
    diffs = []
    for _ in range(200):
        obs, _, terminated, truncated, info = env.step(np.zeros(1, dtype=np.float32))
        diffs.append(obs[7] - info["depth_m"])
        assert obs[0] - info["depth_error_m"] == pytest.approx(obs[7] - info["depth_m"], abs=1e-5)
        if terminated or truncated:
            env.reset()
    assert 0.03 < np.std(diffs) < 0.07  # depth sensor noise 0.05 m


def test_step_is_one_rk4_call_of_the_shared_dynamics():
    env = subenv.DivePlaneEnv(scenario="Nominal")
    env.reset(seed=0, options={"initial_state": (0.02, 0.01, -0.003, 11.0)})
    x0 = env.state.copy()
    env.step(np.array([0.5], dtype=np.float32))
    params = model_params(env.vehicle)
    expected = rk4(lambda t, x: derivatives(x, 1.524, 0.2, 0.0, params), 0.0, x0, 0.5, 2)
    np.testing.assert_array_equal(env.state, expected)


def test_actions_outside_the_box_are_clipped():
    results = []
    for a in (1.0, 7.5):
        env = gym.make("subenv/Nominal-v0")
        env.reset(seed=0)
        obs, reward, *_ = env.step(np.array([a], dtype=np.float32))
        results.append((obs, reward))
    assert np.array_equal(results[0][0], results[1][0]) and results[0][1] == results[1][1]


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_actions_raise(bad):
    env = gym.make("subenv/Nominal-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="must be finite"):
        env.step(np.array([bad], dtype=np.float32))


def test_wrong_action_shape_and_step_before_reset_raise():
    env = subenv.DivePlaneEnv(scenario="Nominal")
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(1, dtype=np.float32))
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"must have shape \(1,\)"):
        env.step(np.zeros(2, dtype=np.float32))


def test_independent_planes_and_alpha_allocation():
    env = subenv.DivePlaneEnv(scenario="Nominal", control="independent")
    assert env.action_space.shape == (2,)
    env.reset(seed=0)
    *_, info = env.step(np.array([0.5, -0.25], dtype=np.float32))
    assert (info["stern_plane_rad"], info["bow_plane_rad"]) == pytest.approx((0.2, -0.1))
    env = subenv.DivePlaneEnv(scenario="Nominal", alpha=0.5)
    env.reset(seed=0)
    *_, info = env.step(np.array([1.0], dtype=np.float32))
    assert (info["stern_plane_rad"], info["bow_plane_rad"]) == pytest.approx((0.4, 0.2))
    assert info["critical_speed_mps"] == pytest.approx(subenv.analysis.critical_speed(env.vehicle, 0.5))


def test_plane_rate_limit():
    env = subenv.DivePlaneEnv(scenario="Nominal", plane_rate_limit_radps=0.04)
    env.reset(seed=0)
    angles = []
    for _ in range(12):
        *_, info = env.step(np.array([1.0], dtype=np.float32))
        angles.append(info["stern_plane_rad"])
    np.testing.assert_allclose(np.diff([0.0, *angles])[:10], 0.02)  # 0.04 rad/s * 0.5 s
    assert angles[-1] == pytest.approx(0.24)


def test_reset_options_place_the_episode_exactly():
    env = gym.make("subenv/LowSpeed-v0")
    obs, info = env.reset(
        seed=0, options={"speed": 0.3, "depth_command": 12.0, "initial_state": (0.05, 0.01, -0.002, 13.5)}
    )
    assert info["speed_mps"] == 0.3 and info["depth_command_m"] == 12.0
    assert (info["pitch_rad"], info["heave_mps"], info["pitch_rate_radps"], info["depth_m"]) == (
        0.05,
        0.01,
        -0.002,
        13.5,
    )
    assert obs[0] == pytest.approx(1.5)
    _, info = env.reset(seed=0, options={"initial_state": {"pitch": 0.1}})
    assert info["pitch_rad"] == 0.1 and info["heave_mps"] == 0.0


def test_speed_transient_decelerates_through_critical():
    env = gym.make("subenv/SpeedTransient-v0")
    _, info = env.reset(seed=0)
    ucr = info["critical_speed_mps"]
    times = np.arange(0.0, 600.5, 0.5)
    speeds = np.array([env.unwrapped.speed_at(t) for t in times])
    assert speeds[0] == info["speed_mps"] > 1.9 * ucr and speeds[-1] < 0.75 * ucr
    assert np.all(np.diff(speeds) <= 1e-12)  # monotone deceleration
    *_, info = env.step(np.zeros(1, dtype=np.float32))
    assert info["speed_mps"] == env.unwrapped.speed_at(0.5)


def test_truncation_at_the_scenario_duration():
    env = gym.make("subenv/Nominal-v0")
    env.reset(seed=0, options={"initial_state": (0.0, 0.0, 0.0, 10.0), "depth_command": 10.0})
    steps = 0
    while True:
        steps += 1
        _, _, terminated, truncated, info = env.step(np.zeros(1, dtype=np.float32))
        if terminated or truncated:
            break
    assert (terminated, truncated, steps) == (False, True, 400)  # 200 s at 0.5 s
    assert info["time_s"] == pytest.approx(200.0)
    assert abs(info["depth_error_m"]) < 1e-9  # level flight is an equilibrium at speed


def _run_until_done(env, action):
    while True:
        obs, reward, terminated, truncated, info = env.step(action)
        assert np.all(np.isfinite(obs))
        if terminated or truncated:
            return obs, reward, terminated, truncated, info


def test_termination_reasons():
    # Full planes at 5 fps pitch the boat past the limit.
    env = subenv.DivePlaneEnv(scenario="Nominal")
    env.reset(seed=0)
    _, _reward, terminated, _, info = _run_until_done(env, np.array([-1.0], dtype=np.float32))
    assert terminated and info["termination_reason"] == "pitch_limit" and info["reward_termination"] == -100.0
    # Near the surface with planes pitching the bow up, the hull breaks the surface.
    env = subenv.DivePlaneEnv(scenario="PeriscopeDepth", max_pitch_rad=1.5)
    env.reset(seed=0, options={"speed": 1.5})
    *_, info = _run_until_done(env, np.array([-1.0], dtype=np.float32))
    assert info["termination_reason"] == "broached" and info["depth_m"] < 0.26
    # Diving away from a narrow depth band.
    env = subenv.DivePlaneEnv(scenario="Nominal", max_depth_error_m=3.0)
    env.reset(seed=0, options={"initial_state": (0.0, 0.3, 0.0, 12.9), "depth_command": 10.0})
    *_, info = _run_until_done(env, np.array([0.0], dtype=np.float32))
    assert info["termination_reason"] == "left_depth_band" and abs(info["depth_error_m"]) > 3.0


def test_a_diverging_integration_ends_the_episode_with_finite_observations():
    # A 10 s step at 8 m/s is far outside RK4's stability region: the state blows up.
    env = subenv.DivePlaneEnv(
        scenario="Nominal", dt=10.0, substeps=1, max_pitch_rad=math.pi / 2, max_depth_error_m=1000.0
    )
    env.reset(seed=0, options={"speed": 8.0, "initial_state": (0.3, 0.5, 0.1, 500.0), "depth_command": 500.0})
    obs, *_, info = _run_until_done(env, np.array([1.0], dtype=np.float32))
    assert info["termination_reason"] == "diverged"
    assert np.all(np.isfinite(obs))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"scenario": "Fast"}, r"scenario='Fast' is unknown: must be one of \['Nominal', 'LowSpeed'"),
        ({"vehicle": "seawolf"}, r"vehicle='seawolf' is unknown"),
        ({"control": "both"}, r"control='both' is invalid: must be one of \['dual', 'independent'\]"),
        ({"alpha": 1.5}, r"alpha=1\.5 is invalid: must be a number in \[-1, 1\]"),
        ({"alpha": 0.5, "control": "independent"}, r"alpha=0\.5 is invalid with control='independent'"),
        ({"dt": 0.0}, r"dt=0\.0 is invalid: must be a finite number in \(0, 10\.0\]"),
        ({"dt": math.nan}, r"dt=nan is invalid"),
        ({"substeps": 0}, r"substeps=0 is invalid: must be an integer in \[1, 1000\]"),
        ({"plane_rate_limit_radps": -1.0}, r"plane_rate_limit_radps=-1\.0 is invalid"),
        ({"max_pitch_rad": 2.0}, r"max_pitch_rad=2\.0 is invalid: must be a finite number in \[0\.01, 1\.57"),
        ({"max_depth_error_m": 0}, r"max_depth_error_m=0 is invalid"),
        (
            {"effort_weight": -1.0},
            r"effort_weight=-1\.0 is invalid: must be a finite number in \[0\.0, 1000000\.0\]",
        ),
        (
            {"render_mode": "ansi"},
            r"render_mode='ansi' is invalid: must be None or one of \['human', 'rgb_array'\]",
        ),
    ],
)
def test_bad_constructor_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        subenv.DivePlaneEnv(**kwargs)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (
            {"sped": 1.0},
            r"reset options \['sped'\] are unknown: allowed options are \['speed', 'depth_command'",
        ),
        ({"speed": -0.5}, r"options\['speed'\]=-0\.5 is invalid: must be a finite number in \(0, 10\.0\]"),
        ({"speed": math.inf}, r"options\['speed'\]=inf is invalid"),
        ({"depth_command": 0.1}, r"options\['depth_command'\]=0\.1 is invalid: must be a number in \(0\.254"),
        ({"initial_state": (0.0, 0.0, 0.0)}, r"must be \(pitch, heave, pitch_rate, depth\)"),
        (
            {"initial_state": (1.0, 0.0, 0.0, 10.0)},
            r"\['pitch'\]=1\.0 is invalid: must be in \(-0\.6, 0\.6\) rad",
        ),
        ({"initial_state": (0.0, math.nan, 0.0, 10.0)}, r"\['heave'\]=nan is invalid: must be finite"),
        ({"initial_state": (0.0, 0.0, 0.0, 0.1)}, r"\['depth'\]=0\.1 is invalid: must be in \(0\.254"),
        ({"initial_state": {"roll": 0.1}}, r"unknown keys \['roll'\]: allowed keys are \['pitch', 'heave'"),
        # (a depth beyond the band of the ordered depth the draw gives: found after the draw)
        (
            {"initial_state": {"depth": 100.0}},
            r"\['depth'\]=100\.0 is invalid: must be in \(0\.254.*max_depth_error_m",
        ),
    ],
)
def test_bad_reset_options(options, message):
    # The error changes nothing: the episode under way and the generator's stream go on as before.
    env, twin = subenv.DivePlaneEnv(scenario="Nominal"), subenv.DivePlaneEnv(scenario="Nominal")
    env.reset(seed=3)
    twin.reset(seed=3)
    for seed in (None, 4):
        with pytest.raises(ValueError, match=message):
            env.reset(seed=seed, options=options)
    action = np.array([0.3], dtype=np.float32)
    np.testing.assert_array_equal(env.step(action)[0], twin.step(action)[0])
    np.testing.assert_array_equal(env.reset()[0], twin.reset()[0])


def test_both_environments_take_one_checked_configuration():
    from subenv.envs import DivePlaneConfig, DivePlaneVectorEnv

    config = DivePlaneConfig(scenario="LowSpeed", alpha=0.5, dt=0.25, pitch_weight=0.2)
    single, vector = subenv.DivePlaneEnv(config=config), DivePlaneVectorEnv(num_envs=3, config=config)
    assert single.config is config and vector.config is config
    assert single.scenario.name == "LowSpeed" and single.alpha == 0.5 and single.dt == 0.25
    assert subenv.DivePlaneEnv(scenario="LowSpeed", alpha=0.5, dt=0.25, pitch_weight=0.2).config == config
    obs, info = vector.reset(seed=7)
    np.testing.assert_array_equal(obs[2], single.reset(seed=9)[0])  # sub-environment i: seed 7 + i
    assert info["time_s"].tolist() == [0.0] * 3
    with pytest.raises(ValueError, match=r"dt=-1\.0 is invalid: must be a finite number in \(0, 10\.0\]"):
        config.replace(dt=-1.0)
    with pytest.raises(ValueError, match=r"config and keyword arguments \['alpha'\] were given"):
        DivePlaneVectorEnv(num_envs=2, config=config, alpha=0.1)
    with pytest.raises(ValueError, match=r"config and keyword arguments \['dt'\] were given"):
        subenv.DivePlaneEnv(config=config, dt=0.3)
    with pytest.raises(ValueError, match=r"config=3 is invalid: must be a DivePlaneConfig"):
        subenv.DivePlaneEnv(config=3)
    # set_scenario replaces the configuration's scenario, checked, and keeps the rest.
    single.set_scenario("Nominal")
    assert single.config == config.replace(scenario="Nominal") and single.config.dt == 0.25
    with pytest.raises(ValueError, match=r"scenario 'Nope' is not registered|unknown scenario|Nope"):
        single.set_scenario("Nope")
    assert single.scenario.name == "Nominal"


def test_gym_make_with_module_prefix_in_a_fresh_process():
    code = (
        "import gymnasium as gym\n"
        "env = gym.make('subenv:subenv/DivePlane-v0')\n"
        "obs, info = env.reset(seed=0)\n"
        "print(obs.shape, type(env.unwrapped).__name__)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "(8,) DivePlaneEnv"


def test_register_envs_called_again_registers_the_same_ids_without_warnings():
    """What a Ray worker's setup hook does after the worker already imported subenv (README: RLlib)."""
    before = {env_id: gym.spec(env_id) for env_id in ENV_IDS}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        subenv.register_envs()
        subenv.register_envs()
    assert {env_id: gym.spec(env_id) for env_id in ENV_IDS} == before
    assert all(
        gym.spec(env_id).vector_entry_point == "subenv.envs.vector:DivePlaneVectorEnv" for env_id in ENV_IDS
    )


def test_render_rgb_array_through_the_env():
    pytest.importorskip("pygame", reason="the 'render' extra is not installed")
    env = gym.make("subenv/PeriscopeDepth-v0", render_mode="rgb_array", disable_env_checker=True)
    gym_check_env(env.unwrapped)  # includes Gymnasium's render checks
    env.reset(seed=0)
    first = env.render()
    for _ in range(20):
        env.step(np.array([0.5], dtype=np.float32))
    frame = env.render()
    assert frame.shape == (480, 720, 3) and frame.dtype == np.uint8
    assert not np.array_equal(first, frame)  # the picture follows the episode
    env.close()


def test_render_human_with_a_dummy_display():
    pytest.importorskip("pygame", reason="the 'render' extra is not installed")
    env = gym.make("subenv/Nominal-v0", render_mode="human")
    env.reset(seed=0)
    env.step(np.zeros(1, dtype=np.float32))
    assert env.unwrapped._window is not None and env.unwrapped._window.is_open
    env.close()
    assert env.unwrapped._window is None


@pytest.mark.parametrize("env_id", ["subenv/Nominal-v0", "subenv/DivePlane-v0"])
@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_a_copy_continues_exactly_and_apart(env_id, how, compiled_signatures):
    import copy
    import pickle

    env = gym.make(env_id).unwrapped
    env.reset(seed=11)
    for _ in range(5):
        env.step(np.array([0.4], dtype=np.float32))
    compiled = compiled_signatures()
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    # The arrays the kernels only read are read-only in the copy too (pickle and deepcopy make writable
    # ones): numba types the two apart, and the copy's first step would compile the kernels again.
    assert not twin._constants.flags.writeable and not twin._hull.flags.writeable
    assert [k for k, loading in twin._loadings._found.items() if loading.params.flags.writeable] == []
    rng = np.random.default_rng(0)
    for _ in range(30):
        action = rng.uniform(-1, 1, size=1).astype(np.float32)
        a, b = env.step(action), twin.step(action)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:4] == b[1:4] and a[4] == b[4]
    twin.reset(seed=12)
    twin.step(np.zeros(1, dtype=np.float32))
    assert compiled_signatures() == compiled  # (the copy ran the original's compiled step and reset)
    # Apart: stepping one leaves the other where it was.
    before = twin.state
    env.step(np.array([1.0], dtype=np.float32))
    np.testing.assert_array_equal(twin.state, before)
