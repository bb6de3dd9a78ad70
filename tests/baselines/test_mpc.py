"""The MPC baseline: its one model, its hard constraints, and offset-free depth keeping."""

from __future__ import annotations

import importlib
import sys

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("daqp", reason="the 'mpc' extra is not installed")

from subenv.dynamics import model_params
from subenv.evaluation import run_episodes
from subenv.extras import MissingExtra
from subenv_baselines.mpc import DepthMPC, ObserverNoise, discrete_jacobians

STATE_KEYS = ("pitch_rad", "heave_mps", "pitch_rate_radps", "depth_m")


def _state(info: dict) -> np.ndarray:
    return np.array([info[key] for key in STATE_KEYS])


def _run(controller: DepthMPC, scenario: str, options: dict, seed: int = 0, **env_kwargs):
    """One episode: the env, the commanded planes [rad] and the infos after every step."""
    env = gym.make(f"subenv/{scenario}-v0", control=controller.control, alpha=controller.alpha, **env_kwargs)
    obs, info = env.reset(seed=seed, options=options)
    controller.reset(info, env.unwrapped.base_vehicle)
    limit = env.unwrapped.plane_limit_rad
    commands, infos = [], []
    while True:
        action = controller.act(obs)
        assert action.shape == (2,) and action.dtype == np.float32
        commands.append(action.astype(float) * limit)
        obs, _, terminated, truncated, info = env.step(action)
        infos.append(info)
        if terminated or truncated:
            return env, np.array(commands), infos


def test_the_prediction_is_the_environments_step():
    """The one-model check: the controller's prediction of a control period is the environment's step,
    from the same state with the same planes at a constant speed, bit for bit."""
    controller = DepthMPC()
    env = gym.make("subenv/LowSpeed-v0", control="independent")
    _, info = env.reset(seed=3, options={"speed": 0.45, "initial_state": (0.05, 0.01, -0.002, 12.0)})
    controller.reset(info, env.unwrapped.base_vehicle)
    rng = np.random.default_rng(0)
    limit = env.unwrapped.plane_limit_rad
    for _ in range(50):
        action = rng.uniform(-1, 1, size=2).astype(np.float32)
        before = _state(info)
        _obs, _, terminated, _, info = env.step(action)
        planes = np.array([info["stern_plane_rad"], info["bow_plane_rad"]])
        np.testing.assert_allclose(planes, action.astype(float) * limit)
        predicted = controller.predict(before, planes, info["speed_mps"])
        np.testing.assert_array_equal(predicted, _state(info))  # bit for bit: the same operations
        assert not terminated


def test_the_linearisation_is_the_derivative_of_the_prediction(suboff):
    """The QP's A, B and disturbance columns: the prediction's slopes (checked against a larger step)."""
    params = model_params(suboff)
    point = np.array([0.1, 0.03, -0.01, 5.0, 0.2, -0.3, 4.0, -7.0])
    F, J = discrete_jacobians(params, point, np.array(0.5))
    controller = DepthMPC()
    controller.reset({}, suboff)
    np.testing.assert_allclose(F, controller.predict(point[:4], point[4:6], 0.5, point[6:]), rtol=1e-14)
    for k, h in enumerate([1e-4] * 6 + [1e-2] * 2):
        step = np.zeros(8)
        step[k] = h
        plus = controller.predict((point + step)[:4], (point + step)[4:6], 0.5, (point + step)[6:])
        minus = controller.predict((point - step)[:4], (point - step)[4:6], 0.5, (point - step)[6:])
        np.testing.assert_allclose(J[:, k], (plus - minus) / (2 * h), rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(J[:, 3], [0, 0, 0, 1], rtol=1e-7, atol=0)  # depth enters nothing: Z+ = Z + ...


def test_commands_stay_within_the_plane_limit_and_the_rate_limit():
    """A 4 m depth change at low speed with rate-limited planes: the limits bind, and no command breaks them
    (so the environment's rate limiter never has to cut one)."""
    rate = 0.01  # rad/s: 0.005 rad per control period
    controller = DepthMPC(plane_rate_limit_radps=rate)
    env, commands, infos = _run(
        controller,
        "LowSpeed",
        {"speed": 0.4, "depth_command": 10.0, "initial_state": (0.0, 0.0, 0.0, 14.0)},
        plane_rate_limit_radps=rate,
    )
    limit, move = env.unwrapped.plane_limit_rad, rate * env.unwrapped.dt
    assert np.all(np.abs(commands) <= limit)
    moves = np.abs(np.diff(np.vstack([np.zeros(2), commands]), axis=0))
    assert np.all(moves <= move * (1 + 1e-6))
    assert np.max(moves) > 0.99 * move  # the rate limit was active
    applied = np.array([[i["stern_plane_rad"], i["bow_plane_rad"]] for i in infos])
    np.testing.assert_allclose(applied, commands, atol=1e-7)  # commanded = applied
    assert infos[-1]["termination_reason"] == "" and abs(infos[-1]["depth_error_m"]) < 0.01


def test_commands_stay_within_the_plane_limit_when_saturated():
    controller = DepthMPC()
    env, commands, _infos = _run(
        controller,
        "NearCritical",
        {"speed": 0.6, "depth_command": 10.0, "initial_state": (0.0, 0.0, 0.0, 12.0)},
    )
    limit = env.unwrapped.plane_limit_rad
    assert np.all(np.abs(commands) <= limit)
    assert np.max(np.abs(commands)) > 0.99 * limit  # the limit was active


@pytest.mark.parametrize("estimate", [True, False], ids=["estimated", "not_estimated"])
def test_a_ballast_offset_is_trimmed_out(estimate: bool):
    """A centre of gravity 2 mm aft of the centre of buoyancy (a constant pitch moment, Riedel 1993
    Ch. IV) that the design model does not have: with the disturbance estimated the depth error goes to 0
    and the estimate is the moment -x_GB W cos(theta) (eq. 2.39); without it the boat settles off depth."""
    noise = (
        ObserverNoise() if estimate else ObserverNoise(disturbance=(0.0, 0.0), initial_disturbance=(0.0, 0.0))
    )
    controller = DepthMPC(noise=noise)
    env, _, infos = _run(
        controller,
        "BallastOffset",
        {"speed": 0.9, "depth_command": 10.0, "initial_state": (0.0, 0.0, 0.0, 11.0)},
        seed=1,
    )
    vehicle = env.unwrapped.vehicle
    x_GB = vehicle.x_G_m - vehicle.x_B_m
    assert abs(x_GB) >= 0.5e-3
    last = infos[-60:]
    errors = np.array([i["depth_error_m"] for i in last])
    assert infos[-1]["termination_reason"] == ""
    if estimate:
        assert np.max(np.abs(errors)) < 1e-3
        moment = -x_GB * vehicle.weight_N * np.cos(last[-1]["pitch_rad"])
        np.testing.assert_allclose(controller.disturbance[0], [0.0, moment], rtol=1e-3, atol=1e-3)
    else:
        assert np.min(np.abs(errors)) > 0.01


def test_surface_suction_is_trimmed_out():
    """Excess buoyancy B - W near the surface (Riedel 1993 Ch. V.C): estimated as the heave force W - B, and
    held at periscope depth without broaching."""
    controller = DepthMPC()
    env, _, infos = _run(
        controller,
        "PeriscopeDepth",
        {"speed": 0.7, "depth_command": 1.0, "initial_state": (0.0, 0.0, 0.0, 1.4)},
        seed=2,
    )
    vehicle = env.unwrapped.vehicle
    assert vehicle.buoyancy_N > vehicle.weight_N
    assert infos[-1]["termination_reason"] == ""
    assert np.max(np.abs([i["depth_error_m"] for i in infos[-60:]])) < 1e-3
    force = (vehicle.weight_N - vehicle.buoyancy_N) * np.cos(infos[-1]["pitch_rad"])
    np.testing.assert_allclose(controller.disturbance[0], [force, 0.0], rtol=1e-3, atol=1e-3)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (
            {"blocks": (1,)},
            r"blocks=\(1,\) is invalid: must be integers >= 1 \(control periods\), the first 1, at least 2",
        ),
        ({"blocks": (2, 4)}, r"blocks=\(2, 4\) is invalid"),
        ({"blocks": (1, 0)}, r"blocks=\(1, 0\) is invalid"),
        ({"plane_rate_limit_radps": 0.0}, r"plane_rate_limit_radps=0.0 is invalid: must be None or > 0"),
    ],
)
def test_invalid_settings_name_the_parameter(kwargs, match):
    with pytest.raises(ValueError, match=match):
        DepthMPC(**kwargs)


def test_without_daqp_the_module_names_the_extra(monkeypatch):
    """The entry point's import fails with the one-line advice, so the harness skips ``mpc`` with a note."""
    monkeypatch.setitem(sys.modules, "daqp", None)  # as if not installed
    monkeypatch.delitem(sys.modules, "subenv_baselines.mpc")
    with pytest.raises(
        MissingExtra, match=r"^the 'mpc' extra is needed for the MPC baseline .*subenv\[mpc\]"
    ):
        importlib.import_module("subenv_baselines.mpc")


def test_a_batch_gets_the_one_at_a_time_results_bit_for_bit():
    """Each episode's controller state is its own row (the harness's contract for batch controllers)."""
    seeds = [10_005, 10_010, 10_000]
    one = run_episodes(
        DepthMPC(), "BallastOffset", seeds, batched=False, max_duration_s=60.0, keep_trajectories=3
    )
    batch = run_episodes(DepthMPC(), "BallastOffset", seeds, max_duration_s=60.0, keep_trajectories=3)
    for a, b in zip(one, batch, strict=True):
        assert a.trajectory is not None and b.trajectory is not None
        np.testing.assert_array_equal(a.trajectory.actions, b.trajectory.actions)
        np.testing.assert_array_equal(a.trajectory.depth_error_m, b.trajectory.depth_error_m)


@pytest.mark.parametrize(
    "scenario", ["Nominal", "LowSpeed", "NearCritical", "SpeedTransient", "PeriscopeDepth", "BallastOffset"]
)
def test_it_wins_exactly_the_winnable_episodes(scenario):
    """Every scenario class: each episode with a depth-holding trim inside the plane limits is won, and the
    one without (BallastOffset seed 2: x_GB = 2.0 mm at 0.56 m/s) is lost, as it must be by any
    controller."""
    results = run_episodes(DepthMPC(), scenario, [0, 1, 2])
    for result in results:  # (the harness records subenv.analysis.winnable for every episode)
        assert (result.metrics.outcome == "success") == result.winnable, (result.seed, result.metrics.outcome)
    assert scenario != "BallastOffset" or [r.metrics.outcome == "success" for r in results] == [
        True,
        True,
        False,
    ]


def test_the_condensed_qp_is_the_linear_model_stepped_and_its_cost():
    """The compiled condensing: the pitch and depth its rows predict at the stages are x+ = A x + B u + c
    stepped period by period with the planes held over each block, and 1/2 v' H v + f' v differs between two
    plans by what the cost, summed stage by stage, does."""
    from subenv_baselines.mpc import BLOCKS, MPCWeights, _CondensedQP

    rng = np.random.default_rng(5)
    n, weights = 3, MPCWeights()
    qp = _CondensedQP(BLOCKS, weights)
    A = np.eye(4) + 0.05 * rng.normal(size=(n, 4, 4))
    B, c = 0.05 * rng.normal(size=(n, 4, 2)), 0.05 * rng.normal(size=(n, 4))
    y, x_s, u_s = rng.normal(size=(n, 4)), rng.normal(size=(n, 4)), 0.1 * rng.normal(size=(n, 2))
    planes = 0.1 * rng.normal(size=(n, 2))
    high, low, pitch_bound, move = np.full(n, 30.0), np.full(n, 2.0), 0.1, 0.01
    rows = qp.build(
        A, B, c, y, x_s, u_s, planes, 0.4, planes - move, planes + move, move, pitch_bound, high, low
    )
    K, nv, M = len(qp.stages), qp.nv, len(BLOCKS)
    assert rows.H.shape == (n, nv, nv) and rows.C.shape == (n, 4 * K + 2 * (M - 1), nv)
    np.testing.assert_array_equal(rows.H, np.swapaxes(rows.H, 1, 2))

    def stepped(i, U):  # the states after each period, and the planes of each period
        u = np.repeat(U.reshape(M, 2), BLOCKS, axis=0)
        x, xs = y[i], []
        for k in range(sum(BLOCKS)):
            x = A[i] @ x + B[i] @ u[k] + c[i]
            xs.append(x)
        return np.array(xs), u

    def cost(i, U):  # summed stage by stage, the slacks 0
        xs, u = stepped(i, U)
        e = xs[qp.stages - 1] - x_s[i]
        moves = np.diff(np.vstack([planes[i], U.reshape(M, 2)]), axis=0)
        return (
            np.sum(qp.sqrt_state_weights**2 * e**2)
            + weights.plane * np.sum((u - u_s[i]) ** 2)
            + weights.move * np.sum(moves**2)
        )

    def quadratic(i, U):  # the QP's objective, the slacks 0
        v = np.r_[U, 0.0, 0.0]
        return 0.5 * v @ rows.H[i] @ v + rows.f[i] @ v

    for i in range(n):
        U0, U1 = 0.2 * rng.normal(size=2 * M), 0.2 * rng.normal(size=2 * M)
        xs, _ = stepped(i, U1)
        v = np.r_[U1, 0.0, 0.0]
        pitch = rows.C[i, :K] @ v + (pitch_bound - rows.upper[i, nv : nv + K])
        depth = rows.C[i, 2 * K : 3 * K] @ v + (high[i] - rows.upper[i, nv + 2 * K : nv + 3 * K])
        np.testing.assert_allclose(pitch, xs[qp.stages - 1, 0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(depth, xs[qp.stages - 1, 3], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(quadratic(i, U1) - quadratic(i, U0), cost(i, U1) - cost(i, U0), rtol=1e-10)
