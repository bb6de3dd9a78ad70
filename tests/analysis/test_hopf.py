"""The Hopf bifurcation of level flight at speed (Riedel 1993 Ch. VI's recommendation), checked by
independent means: the environment's own integration, the shooting of the nonlinear equations."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from subenv.analysis import thesis_gain
from subenv.analysis.hopf import hopf_points, level_flight_eigenvalues, periodic_orbit
from subenv.analysis.report import env_growth_rate
from subenv.envs import DivePlaneEnv
from subenv.vehicles import load_vehicle

SUBOFF = load_vehicle("suboff")


@pytest.fixture(scope="module")
def hopf():  # type: ignore[no-untyped-def]
    (point,) = hopf_points(SUBOFF)
    return point


def test_the_open_loop_pair_crosses_the_imaginary_axis_at_the_hopf_speed(hopf) -> None:  # type: ignore[no-untyped-def]
    at = level_flight_eigenvalues(SUBOFF, hopf.speed_mps)
    pair = at[np.abs(at.imag) > 1e-9]
    assert np.max(np.abs(pair.real)) < 1e-9 and np.isclose(np.abs(pair.imag).max(), hopf.frequency_radps)
    below, above = (level_flight_eigenvalues(SUBOFF, hopf.speed_mps * f) for f in (0.98, 1.02))
    assert np.all(below.real < 0.0) and np.max(above.real) > 0.0 and hopf.growth_slope > 0.0
    assert (
        0.0 < hopf.frequency_radps and hopf.speed_mps > 1.4 * 0.5785
    )  # well above u_cr: another instability


def test_the_environment_grows_and_decays_at_the_eigenvalues_rate_and_crosses_at_the_hopf_speed(hopf) -> None:  # type: ignore[no-untyped-def]
    """The env integrates the nonlinear equations (drag included) with its own integrator; from a
    1e-3 rad pitch its oscillation's growth is Re(lambda), and changes sign at u_H."""
    below, above = 0.82, 0.85
    rates = [env_growth_rate(u) for u in (below, above)]
    for u, rate in zip((below, above), rates, strict=True):
        expected = max(e.real for e in level_flight_eigenvalues(SUBOFF, u) if abs(e.imag) > 1e-9)
        assert rate == pytest.approx(expected, abs=1e-3)
    assert rates[0] < 0.0 < rates[1]
    crossing = below - rates[0] * (above - below) / (rates[1] - rates[0])
    assert crossing == pytest.approx(hopf.speed_mps, rel=5e-3)


def test_the_environment_growth_rate_refuses_an_id_that_is_not_a_subenv_environment() -> None:
    with pytest.raises(
        ValueError, match=r"^env_id='CartPole-v1' is invalid: must be a subenv environment id$"
    ):
        env_growth_rate(0.8, env_id="CartPole-v1")


def test_the_bifurcation_is_supercritical_with_amplitude_linear_in_the_speed_excess(hopf) -> None:  # type: ignore[no-untyped-def]
    """c2 < 0: stable cycles above u_H; their amplitude follows -Re(lambda)/c2, linear in u - u_H (the
    quadratic drag's law; a smooth Hopf's amplitude grows as the square root)."""
    assert hopf.criticality == "supercritical"
    speeds = (hopf.speed_mps + 0.002, hopf.speed_mps + 0.004)
    orbits = [periodic_orbit(SUBOFF, u) for u in speeds]
    for orbit in orbits:
        assert orbit.stable and orbit.period_s == pytest.approx(hopf.period_s, rel=0.03)
        assert orbit.pitch_amplitude_rad == pytest.approx(
            hopf.predicted_amplitude_rad(SUBOFF, orbit.speed_mps), rel=0.05
        )
    ratio = orbits[1].pitch_amplitude_rad / orbits[0].pitch_amplitude_rad
    assert ratio == pytest.approx(2.0, rel=0.05)  # (a square-root law would give 1.41)


def test_a_closed_loop_with_a_zero_gain_has_the_open_loops_hopf_point_and_the_thesis_gain_none(hopf) -> None:  # type: ignore[no-untyped-def]
    (closed,) = hopf_points(SUBOFF, gain=np.zeros(4))
    assert closed.loop == "closed" and closed.speed_mps == pytest.approx(hopf.speed_mps, rel=1e-9)
    assert closed.amplitude_coefficient == pytest.approx(hopf.amplitude_coefficient, rel=1e-4)
    assert hopf_points(SUBOFF, gain=thesis_gain(SUBOFF)) == []  # the design damps the mode up to 3 m/s


def test_the_env_docstring_states_what_the_analysis_computes(analysis_report) -> None:  # type: ignore[no-untyped-def]
    doc = " ".join((DivePlaneEnv.__doc__ or "").split())
    found = (
        analysis_report.hopf
    )  # hopf_findings(SUBOFF), as the session's report computed it (tens of seconds)
    stated = re.search(r"Below u_H = ([\d.]+) m/s \(([\d.]+) u_cr\)", doc)
    assert stated is not None
    assert float(stated.group(1)) == round(found.point.speed_mps, 3)
    assert float(re.search(r"pitch limit at ([\d.]+) m/s", doc).group(1)) == round(
        found.pitch_limit_speed_mps, 2
    )  # type: ignore[union-attr]
    assert float(re.search(r"above ([\d.]+) m/s the motion diverges", doc).group(1)) == round(
        found.splitting_speed_mps, 2
    )  # type: ignore[union-attr]
    assert math.isclose(found.env_hopf_speed_mps, found.point.speed_mps, rel_tol=5e-3) and found.orbits_stable


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"gain": [1.0, 2.0]}, r"gain=.* must be 4 finite numbers"),
        ({"gain": [1.0, 2.0, math.nan, 0.0]}, r"gain=.* must be 4 finite numbers"),
        ({"alpha": 2.0}, r"alpha=2.0 is invalid: must be a number in \[-1, 1\]"),
        ({"speeds_mps": [1.0, 0.5]}, r"speeds_mps=.* must be an increasing array"),
    ],
)
def test_bad_arguments_are_refused(kwargs, match) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=match):
        hopf_points(SUBOFF, **kwargs)


def test_a_loading_without_level_flight_is_refused() -> None:
    heavy = SUBOFF.variant(excess_buoyancy_N=-0.01 * SUBOFF.weight_N)
    with pytest.raises(ValueError, match="level flight"):
        hopf_points(heavy)


def test_the_hopf_point_of_the_full_scale_boat_is_the_models_froude_scaled(hopf) -> None:  # type: ignore[no-untyped-def]
    """Froude similarity (subenv.vehicles.froude_scaled): speeds x sqrt(lambda), rates x 1/sqrt(lambda);
    the pitch amplitude, an angle, and so the criticality stay."""
    full = load_vehicle("suboff_fullscale")
    ratio = full.length_m / SUBOFF.length_m
    (point,) = hopf_points(full)
    assert point.speed_mps == pytest.approx(hopf.speed_mps * math.sqrt(ratio), rel=1e-9)
    assert point.frequency_radps == pytest.approx(hopf.frequency_radps / math.sqrt(ratio), rel=1e-9)
    assert point.amplitude_coefficient == pytest.approx(
        hopf.amplitude_coefficient / math.sqrt(ratio), rel=1e-6
    )
