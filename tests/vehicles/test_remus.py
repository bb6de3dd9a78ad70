"""The REMUS 100 (Prestero 2001): the shipped file, its published numbers, checks of them, and a vehicle
without bow planes in the environments, the analysis and the evaluation."""

from __future__ import annotations

import dataclasses
import math
from importlib import resources

import gymnasium as gym
import numpy as np
import pytest

import subenv.envs  # noqa: F401  (registers the ids)
from subenv.analysis import critical_speed, depth_holding_trim
from subenv.analysis.linear import BOW_PLANES_ONLY, plane_derivatives
from subenv.analysis.report import critical_speed_three_ways, has_suboff_shape, vehicle_numbers
from subenv.dynamics import derivatives
from subenv.dynamics.model import model_params
from subenv.evaluation.controller import Controller
from subenv.evaluation.rollout import needs_bow_planes, resolve_controllers
from subenv.vehicles import PlaneCoefficients, available_vehicles, load_vehicle
from subenv.vehicles.remus import (
    PRESTERO_2001,
    REMUS100_NAME,
    crossflow_check,
    myring_radius,
    remus100,
    remus100_toml,
)

P = PRESTERO_2001


@pytest.fixture(scope="module")
def remus():
    return load_vehicle(REMUS100_NAME)


def test_the_shipped_file_is_what_the_module_writes_and_loads_to_the_same_vehicle(remus):
    assert REMUS100_NAME in available_vehicles()
    shipped = resources.files("subenv.vehicles.data").joinpath(f"{REMUS100_NAME}.toml").read_text("utf-8")
    assert shipped == remus100_toml()
    made = remus100()
    # (the file rounds the hull's stations and radius ratios to 12 digits, vehicle_to_toml)
    assert dataclasses.replace(remus, hull=made.hull) == made
    np.testing.assert_allclose(remus.hull.x_m, made.hull.x_m, rtol=0, atol=1e-11)
    np.testing.assert_allclose(remus.hull.breadth_m, made.hull.breadth_m, rtol=0, atol=1e-12)


def test_the_dimensional_coefficients_are_prestero_s_table(remus):
    # The file holds primes made with rho/2 L^n; the vehicle's dimensional derivatives are his numbers again.
    c = remus.coefficients
    published = {
        "Z_wdot": P.Z_wdot,
        "Z_qdot": P.Z_qdot,
        "M_wdot": P.M_wdot,
        "M_qdot": P.M_qdot,
        "Z_w": P.Z_uw,
        "Z_q": P.Z_uq,
        "M_w": P.M_uw,
        "M_q": P.M_uq,
        "Z_delta_s": P.Z_uuds,
        "M_delta_s": P.M_uuds,
    }
    for name, value in published.items():
        assert getattr(c, name) == pytest.approx(value, rel=1e-12), name
    assert (c.Z_delta_b, c.M_delta_b) == (0.0, 0.0)
    assert remus.mass_kg == pytest.approx(299.0 / 9.81, rel=1e-15)
    assert (remus.weight_N, remus.buoyancy_N, remus.z_GB_m, remus.x_GB_m) == (299.0, 299.0, 0.0196, 0.0)
    assert remus.length_m == pytest.approx(1.3327, abs=1e-12)  # Myring's l_f + c - c_offset (his 1.33 m)


def test_the_hull_is_checked_by_prestero_s_own_cross_flow_drag_and_centre_of_buoyancy(remus):
    # His Z_ww (-131 kg/m) is the cylinder's cross-flow drag over his hull plus his fins' term: the shipped
    # hull gives it to 1%, which checks the Myring parameters (the tail angle among them) independently.
    computed, published = crossflow_check()
    assert computed == pytest.approx(published, rel=0.01)
    # The hull's volume centroid lies within 1 cm of his centre of buoyancy (the origin, x = 0).
    x, b = np.array(remus.hull.x_m), np.array(remus.hull.breadth_m)
    s = np.linspace(0.0, P.length_m, 20001)
    r = myring_radius(P, s)
    volume_centroid = np.trapezoid(np.pi * r * r * s, s) / np.trapezoid(np.pi * r * r, s)
    assert abs(volume_centroid - P.x_B_from_nose_m) < 0.01
    # The piecewise-linear stations follow the curve: planform area within 0.3% of the profile's.
    assert remus.hull.area_m2 == pytest.approx(np.trapezoid(2 * r, s), rel=3e-3)
    assert x[0] == pytest.approx(P.x_B_from_nose_m) and x[-1] == pytest.approx(P.x_B_from_nose_m - P.length_m)
    assert b.max() == pytest.approx(P.diameter_m, rel=1e-12)


def test_the_critical_speed_is_eq_3_9_on_prestero_s_dimensional_numbers(remus):
    # Riedel (1993) eq. 3.9 by hand from the table, without the file's primes:
    # u_cr^2 = W z_GB Z_d / (Z_d M_w - Z_w M_d).
    by_hand = math.sqrt(P.weight_N * P.z_G_m * P.Z_uuds / (P.Z_uuds * P.M_uw - P.Z_uw * P.M_uuds))
    assert critical_speed(remus) == pytest.approx(by_hand, rel=1e-12)
    three = critical_speed_three_ways(remus)
    assert three["eigenvalue"] == pytest.approx(by_hand, rel=1e-9)
    assert three["controllability"] == pytest.approx(by_hand, rel=1e-3)
    rows = {r.quantity: r for r in vehicle_numbers(remus)}
    assert rows["u_cr, eq. 3.9 closed form"].computed == pytest.approx(by_hand, rel=1e-12)
    assert not any("bow" in q for q in rows)  # (no bow planes, no bow rows)
    assert not has_suboff_shape(remus)
    assert has_suboff_shape(load_vehicle("suboff")) and has_suboff_shape(load_vehicle("suboff_fullscale"))


def test_below_the_critical_speed_the_stern_planes_reverse_in_the_environment(remus):
    # A dive command (stern planes trailing edge down, positive) held from level flight: above u_cr the boat
    # goes down, below it up (dive-plane reversal), on REMUS's own coefficients.
    ucr = critical_speed(remus)
    depth_change = {}
    for ratio in (0.6, 1.6):
        env = gym.make("subenv/Nominal-v0", vehicle=REMUS100_NAME)
        _, info = env.reset(
            seed=0,
            options={"speed": ratio * ucr, "depth_command": 5.0, "initial_state": (0.0, 0.0, 0.0, 5.0)},
        )
        start = info["depth_m"]
        for _ in range(80):
            _, _, terminated, truncated, info = env.step(np.array([0.25], dtype=np.float32))
            if terminated or truncated:
                break
        depth_change[ratio] = info["depth_m"] - start
        env.close()
    assert depth_change[1.6] > 0.0 > depth_change[0.6]


def test_a_vehicle_without_bow_planes_refuses_what_would_move_them(remus):
    with pytest.raises(
        ValueError, match=r"control='independent' is invalid for vehicle 'remus100', which has no bow planes"
    ):
        gym.make("subenv/Nominal-v0", vehicle=REMUS100_NAME, control="independent")
    with pytest.raises(
        ValueError, match=r"alpha=0\.5 is invalid for vehicle 'remus100', which has no bow planes"
    ):
        gym.make("subenv/Nominal-v0", vehicle=REMUS100_NAME, alpha=0.5)
    with pytest.raises(ValueError, match=r"alpha='bow' is invalid: must be .*'remus100' has no bow planes"):
        plane_derivatives(remus, BOW_PLANES_ONLY)
    # Bow planes with effect need both derivatives; both zero is a vehicle without them.
    with pytest.raises(
        ValueError, match=r"planes\.Z_delta_b=0\.0 is invalid: must be a non-zero number .* or 0 for both"
    ):
        PlaneCoefficients(Z_delta_s=-0.01, M_delta_s=-0.005, Z_delta_b=0, M_delta_b=0.001)
    assert not PlaneCoefficients(Z_delta_s=-0.01, M_delta_s=-0.005).has_bow_planes


@dataclasses.dataclass
class _Fixed:
    name: str
    control: str
    alpha: float

    def reset(self, env=None, info=None):
        pass

    def act(self, observation, info):
        return np.zeros(1 if self.control == "dual" else 2)


def test_the_evaluation_leaves_bow_plane_controllers_out_on_a_vehicle_without_them(remus):
    stern, both = _Fixed("stern", "dual", 0.0), _Fixed("both", "independent", 0.0)
    assert isinstance(stern, Controller) and needs_bow_planes(both) and not needs_bow_planes(stern)
    assert needs_bow_planes(_Fixed("mixed", "dual", 0.5))
    with pytest.raises(
        ValueError, match=r"controllers \['both'\] move the bow planes .* vehicle 'remus100' has none"
    ):
        resolve_controllers([stern, both], remus)
    assert resolve_controllers([stern, both], load_vehicle("suboff")) == [stern, both]
    names = [c.name for c in resolve_controllers(None, remus)]
    assert (
        names
        and "reversal_aware" not in names
        and "reversal_aware" in [c.name for c in resolve_controllers(None)]
    )


@pytest.mark.parametrize("ratio", [0.6, 1.5, 3.0])
def test_the_stern_only_trim_holds_depth_with_the_one_plane(remus, ratio):
    # With a ballast offset the trim needs pitch and plane; at it both accelerations and the depth rate
    # vanish.
    boat = remus.variant(x_GB_m=0.0005)
    u = ratio * critical_speed(remus)
    trim = depth_holding_trim(boat, u, 0.6)
    assert trim.exists and trim.bow_rad == 0.0 and abs(trim.stern_rad) > 1e-4
    state = np.array([trim.pitch_rad, trim.heave_mps, 0.0, 5.0])
    rates = derivatives(state, u, trim.stern_rad, 0.0, model_params(boat))
    assert np.max(np.abs(rates[1:])) < 1e-10


def test_a_stern_only_loading_with_no_trim_is_not_winnable(remus):
    # Far more excess buoyancy than the stern planes can hold down at a low speed: no trim within the limits.
    light = remus.variant(excess_buoyancy_N=0.05 * remus.weight_N)
    trim = depth_holding_trim(light, 0.5 * critical_speed(remus), 0.6)
    assert not trim.exists and trim.plane_margin_rad < 0
    assert all(math.isfinite(v) for v in dataclasses.astuple(trim)[2:])


def test_the_shallowest_depth_held_is_froude_scaled_on_every_shipped_vehicle():
    # The search starts at SUBOFF's deepest depth Froude-scaled to the vehicle (it used to start at 5 m,
    # inside the full-scale hull): at full scale the shallowest depth is the model's x 24, within the search's
    # tolerance.
    from subenv.analysis.free_surface import min_level_flight_depth

    model, full = load_vehicle("suboff"), load_vehicle("suboff_fullscale")
    ratio = full.length_m / model.length_m
    held = {
        v.name: min_level_flight_depth(v, 0.9 * critical_speed(v))
        for v in (model, full, load_vehicle("remus100"))
    }
    assert held["suboff_fullscale"].min_depth_m == pytest.approx(
        ratio * held["suboff"].min_depth_m, abs=2e-3 * ratio
    )
    assert held["suboff_fullscale"].limited_by == held["suboff"].limited_by == "no trim"
    assert held["remus100"].min_depth_m > 0.5 * P.diameter_m


def test_the_shipped_report_is_this_code_s(remus):
    # docs/remus100/ is `subenv analyze --vehicle remus100`: its key numbers are what the analysis computes
    # now.
    from pathlib import Path

    from subenv.analysis.hopf import hopf_points

    text = (Path(__file__).resolve().parents[2] / "docs" / "remus100" / "report.md").read_text("utf-8")
    assert f"| u_cr, eq. 3.9 closed form | {critical_speed(remus):.5g} | m/s |" in text
    (hopf,) = hopf_points(remus)
    assert (
        f"| Hopf speed u_H, eigenvalues of level flight (planes held) | {hopf.speed_mps:.4f} | m/s |" in text
    )


def test_the_command_line_runs_the_comparison_on_remus_without_the_bow_plane_controllers(tmp_path, capsys):
    pytest.importorskip("ray", reason="the 'ray' extra is not installed")  # (subenv sweep)
    import json

    from subenv.cli import main

    out = tmp_path / "remus"
    main(
        [
            "evaluate",
            "--vehicle",
            REMUS100_NAME,
            "--controllers",
            "thesis,lqr",
            "--suite",
            "tiny",
            "--episodes",
            "1",
            "--no-plots",
            "--no-progress",
            "--out",
            str(out),
        ]
    )
    run = json.loads((out / "run.json").read_text())
    assert run["vehicle"] == REMUS100_NAME and [c["name"] for c in run["controllers"]] == ["thesis", "lqr"]
    with pytest.raises(
        SystemExit, match=r"subenv evaluate: controllers \['reversal_aware'\] move the bow planes"
    ):
        main(
            [
                "evaluate",
                "--vehicle",
                REMUS100_NAME,
                "--controllers",
                "reversal_aware",
                "--suite",
                "tiny",
                "--episodes",
                "1",
                "--no-plots",
                "--out",
                str(tmp_path / "refused"),
            ]
        )
    assert not (tmp_path / "refused").exists()
    with pytest.raises(
        SystemExit, match=r"subenv sweep: controllers \['reversal_aware'\] move the bow planes"
    ):
        main(
            [
                "sweep",
                "--vehicle",
                REMUS100_NAME,
                "--controllers",
                "reversal_aware",
                "--out",
                str(tmp_path / "s"),
            ]
        )
    assert not (tmp_path / "s").exists()
