"""Vehicle data: the shipped SUBOFF file, the unit conversion, derived quantities, variants, bad data."""

from __future__ import annotations

import dataclasses
import math
import os
import re
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from subenv import load_vehicle
from subenv.units import FOOT_M, POUND_FORCE_N, SLUG_KG
from subenv.vehicles import Vehicle, available_vehicles, vehicle_from_dict


def _suboff_file() -> dict:
    return tomllib.loads(resources.files("subenv.vehicles.data").joinpath("suboff.toml").read_text())


def test_unit_constants_are_the_exact_definitions():
    # 1 slug accelerates at 1 ft/s^2 under 1 lbf.
    assert SLUG_KG * FOOT_M == pytest.approx(POUND_FORCE_N, rel=1e-15)
    assert SLUG_KG == pytest.approx(14.5939029372, rel=1e-10)  # NIST SP 811


def test_suboff_is_shipped_and_frozen(suboff):
    assert "suboff" in available_vehicles()
    with pytest.raises(dataclasses.FrozenInstanceError):
        suboff.length_m = 1.0  # type: ignore[misc]


def test_suboff_conversion_to_si(suboff):
    raw = _suboff_file()
    body = raw["rigid_body"]
    assert suboff.length_m == pytest.approx(body["length"] * 0.3048, rel=1e-15)
    assert suboff.weight_N == pytest.approx(body["weight"] * 4.4482216152605, rel=1e-15)
    assert suboff.inertia_y_kg_m2 == pytest.approx(body["inertia_y"] * 14.593902937206 * 0.3048**2, rel=1e-12)
    assert suboff.z_GB_m == pytest.approx(0.1 * 0.3048, rel=1e-12)
    assert suboff.water_density_kg_m3 == pytest.approx(1.94 * 14.593902937206 / 0.3048**3, rel=1e-12)
    assert suboff.gravity_m_s2 == pytest.approx(32.2 * 0.3048, rel=1e-15)
    # m = W / g in either unit system: 48.330 slug (reference sheet).
    assert suboff.mass_kg / SLUG_KG == pytest.approx(1556.2363 / 32.2, rel=1e-12)
    assert suboff.mass_kg / SLUG_KG == pytest.approx(48.330, abs=5e-4)
    assert suboff.planes.limit_rad == 0.4


def test_dimensional_coefficients_follow_rho_half_L_power(suboff):
    """nd1..nd4 = rho/2 L^2..L^5 (Appendix A); compare in thesis units, then in SI."""
    rho, L = 1.94, 13.9792
    nd = {k: 0.5 * rho * L**k for k in (2, 3, 4, 5)}
    c = suboff.coefficients
    # Z_w is nd1 Z'_w, in lbf s/ft^2 -> kg/m: lbf s^2/ft^2 / s = slug/ft.
    assert c.Z_w == pytest.approx(nd[2] * -1.391e-2 * SLUG_KG / FOOT_M, rel=1e-12)
    assert c.M_qdot == pytest.approx(nd[5] * -8.8e-4 * SLUG_KG * FOOT_M**2, rel=1e-12)
    assert c.M_delta_s == pytest.approx(nd[3] * -2.409e-3 * SLUG_KG, rel=1e-12)
    assert c.Z_delta_b == pytest.approx(0.5 * c.Z_delta_s, rel=1e-12)
    assert c.M_delta_b == pytest.approx(-0.5 * c.M_delta_s, rel=1e-12)


def test_hull_area_and_centroid_are_computed_from_offsets(suboff):
    # Reference sheet: full hull A = 20.215 ft^2; the centroid 0.320 ft is the trapezoid-rule
    # value, the exact piecewise-linear centroid is 0.3163 ft.
    assert suboff.hull_area_m2 / FOOT_M**2 == pytest.approx(20.215, abs=1e-3)
    x = np.asarray(suboff.hull.x_m)
    b = np.asarray(suboff.hull.breadth_m)
    fine = np.linspace(x.min(), x.max(), 400001)
    bf = np.interp(fine, x[::-1], b[::-1])
    centroid = np.trapezoid(fine * bf, fine) / np.trapezoid(bf, fine)
    assert suboff.hull_centroid_x_m == pytest.approx(centroid, abs=1e-7)
    assert suboff.hull_centroid_x_m / FOOT_M == pytest.approx(0.3163, abs=1e-4)
    assert max(suboff.hull.breadth_m) == pytest.approx(1.6667 * FOOT_M, rel=1e-12)


def test_variants_change_only_what_they_name(suboff):
    v = suboff.variant(z_GB_m=0.05, x_GB_m=-0.002, excess_buoyancy_N=3.0, crossflow_drag=0.0)
    assert v.z_GB_m == pytest.approx(0.05)
    assert v.x_GB_m == pytest.approx(-0.002)
    assert v.excess_buoyancy_N == pytest.approx(3.0)
    assert v.crossflow_drag == 0.0
    assert v.mass_kg == suboff.mass_kg  # W unchanged: excess buoyancy changes B
    assert v.coefficients == suboff.coefficients
    assert suboff.z_GB_m == pytest.approx(0.03048)  # the original is untouched
    assert suboff.variant() is suboff
    assert "z_GB=0.05m" in v.name


def test_user_vehicle_file_by_path(tmp_path: Path, suboff):
    text = resources.files("subenv.vehicles.data").joinpath("suboff.toml").read_text()
    path = tmp_path / "mysub.toml"
    path.write_text(
        text.replace('name = "suboff"', 'name = "mysub"').replace("inertia_y = 561.32", "inertia_y = 600.0")
    )
    v = load_vehicle(path)
    assert v.name == "mysub"
    assert v.inertia_y_kg_m2 == pytest.approx(600.0 * SLUG_KG * FOOT_M**2)
    assert v.length_m == suboff.length_m


def test_si_vehicle_file_round_trips(suboff):
    raw = _suboff_file()
    si = dict(raw, units="si")
    si["rigid_body"] = {
        k: v * (FOOT_M if k in ("length", "x_G", "z_G", "x_B", "z_B") else 1.0)
        for k, v in raw["rigid_body"].items()
    }
    si["rigid_body"]["weight"] = suboff.weight_N
    si["rigid_body"]["buoyancy"] = suboff.buoyancy_N
    si["rigid_body"]["inertia_y"] = suboff.inertia_y_kg_m2
    si["environment"] = {"water_density": suboff.water_density_kg_m3, "gravity": suboff.gravity_m_s2}
    si["hull"] = dict(raw["hull"], max_diameter=raw["hull"]["max_diameter"] * FOOT_M)
    v = vehicle_from_dict(si)
    assert v.coefficients.M_q == pytest.approx(suboff.coefficients.M_q, rel=1e-12)
    assert v.hull_area_m2 == pytest.approx(suboff.hull_area_m2, rel=1e-12)


def _broken(section: str | None, key: str, value: object) -> dict:
    raw = _suboff_file()
    target = raw if section is None else raw[section]
    if value is _DELETE:
        del target[key]
    else:
        target[key] = value
    return raw


_DELETE = object()


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("rigid_body", "length", 0.0, r"rigid_body\.length=0\.0 is invalid: must be > 0"),
        ("rigid_body", "length", -13.9, r"rigid_body\.length=-13\.9 is invalid: must be > 0"),
        ("rigid_body", "weight", -1.0, r"rigid_body\.weight=-1\.0 is invalid: must be > 0"),
        ("rigid_body", "inertia_y", 0, r"rigid_body\.inertia_y=0 is invalid: must be > 0"),
        ("rigid_body", "inertia_y", "big", r"rigid_body\.inertia_y='big' is invalid: must be a number"),
        ("hydrodynamics", "M_w", _DELETE, r"missing key hydrodynamics\.M_w"),
        ("hydrodynamics", "K_p", 0.1, r"unknown key\(s\) \['K_p'\] in \[hydrodynamics\]; allowed keys are"),
        (None, "colour", "grey", r"unknown key\(s\) \['colour'\]; allowed top-level keys are"),
        (None, "units", "imperial", r"units='imperial' is invalid: must be one of \['si', 'us_customary'\]"),
        (None, "planes", _DELETE, r"missing section \[planes\]"),
        ("planes", "limit", 2.0, r"planes\.limit_rad=2\.0 is invalid: must be in \(0, pi/2\] rad"),
        (
            "hydrodynamics",
            "crossflow_drag",
            -0.1,
            r"crossflow_drag=-0\.1 is invalid: must be a finite number >= 0",
        ),
        ("hull", "radius_ratio", [0.0, 1.0], r"stations but 2 breadths"),
    ],
)
def test_invalid_vehicle_data_names_field_value_and_allowed(section, key, value, message):
    with pytest.raises(ValueError, match=message):
        vehicle_from_dict(_broken(section, key, value))


def test_unknown_vehicle_name_lists_the_shipped_ones():
    with pytest.raises(
        ValueError,
        match=r"vehicle='seawolf' is unknown: must be one of \['remus100', 'suboff', 'suboff_fullscale'\]",
    ):
        load_vehicle("seawolf")
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_vehicle("/nonexistent/sub.toml")


def test_direct_construction_validates(suboff):
    with pytest.raises(ValueError, match=r"inertia_y_kg_m2=-5\.0 is invalid: must be a finite number > 0"):
        dataclasses.replace(suboff, inertia_y_kg_m2=-5.0)
    with pytest.raises(ValueError, match=r"z_GB_m=nan is invalid"):
        suboff.variant(z_GB_m=math.nan)


def test_variant_is_the_vehicle_built_from_scratch(suboff):
    # variant() copies and checks only the changed fields; the result must be the vehicle that
    # construction (which checks everything and derives from nothing cached) gives.
    _ = suboff.coefficients  # cached on the original, carried over by the copy
    v = suboff.variant(z_GB_m=0.02, x_GB_m=0.003, excess_buoyancy_N=-1.5, crossflow_drag=0.45)
    fresh = Vehicle(**{f.name: getattr(v, f.name) for f in dataclasses.fields(v)})
    assert v == fresh
    assert v.coefficients == fresh.coefficients
    assert (v.z_G_m, v.x_G_m, v.buoyancy_N) == (
        suboff.z_B_m + 0.02,
        suboff.x_B_m + 0.003,
        suboff.weight_N - 1.5,
    )


def test_variant_checks_what_it_changes(suboff):
    with pytest.raises(ValueError, match=r"buoyancy_N=.* is invalid: must be a finite number > 0"):
        suboff.variant(excess_buoyancy_N=-2 * suboff.weight_N)
    with pytest.raises(ValueError, match=r"crossflow_drag=-0\.1 is invalid: must be a finite number >= 0"):
        suboff.variant(crossflow_drag=-0.1)


def test_loading_fields_are_the_variants_fields_element_for_element(suboff):
    rng = np.random.default_rng(4)
    z_GB, x_GB, excess, C_D = (
        rng.uniform(-0.01, 0.02, 50),
        rng.normal(0, 2e-3, 50),
        rng.normal(0, 3, 50),
        rng.uniform(0, 0.6, 50),
    )
    fields = suboff.loading_fields(z_GB_m=z_GB, x_GB_m=x_GB, excess_buoyancy_N=excess, crossflow_drag=C_D)
    for i in range(50):
        v = suboff.variant(z_GB_m=z_GB[i], x_GB_m=x_GB[i], excess_buoyancy_N=excess[i], crossflow_drag=C_D[i])
        assert {name: value[i] for name, value in fields.items()} == {
            name: getattr(v, name) for name in fields
        }
    assert suboff.loading_fields(x_GB_m=0.001).keys() == {"x_G_m"}


def test_check_loadings_refuses_a_box_of_loadings_exactly_when_variant_refuses_one_of_them(suboff):
    # A batch of resets checks its loadings by the corners of their box (every check of variant() is
    # monotone in each field, or worst at an end of x_G's range): the box must be refused when, and only
    # when, one of the loadings in it is. Near the bounds: G beyond the hull, B / W beyond [0.5, 2], the
    # mass matrix indefinite (|x_G| about a radius of gyration), C_D < 0.
    rng = np.random.default_rng(0)
    W, L = suboff.weight_N, suboff.length_m
    outcomes = set()
    for _ in range(60):
        scale = rng.choice([0.05, 0.5, 1.0])
        loading = {
            "z_GB_m": rng.uniform(-1.2, 1.2, 4) * L * scale,
            "x_GB_m": rng.uniform(-0.6, 0.6, 4) * L * scale,
            "excess_buoyancy_N": rng.uniform(-0.7, 1.2, 4) * W * scale,
            "crossflow_drag": rng.uniform(-0.1, 1.0, 4) if scale < 1.0 else None,
        }
        refused = []
        for i in range(4):
            one = {name: None if value is None else float(value[i]) for name, value in loading.items()}
            try:
                suboff.variant(**one)
            except ValueError as exc:
                refused.append(str(exc))
        try:
            suboff.check_loadings(**loading)
        except ValueError as exc:
            assert refused, exc
            outcomes.add("refused")
        else:
            assert not refused, refused
            outcomes.add("passed")
    assert outcomes == {"refused", "passed"}
    with pytest.raises(ValueError, match=r"x_GB_m=nan is invalid: must be a finite number"):
        suboff.check_loadings(x_GB_m=np.array([0.001, math.nan]))


# --- physical admissibility and hostile files (issue 18, finding 6) ---------------------------------


def _nd2(raw: dict) -> float:
    """rho/2 L^3 in the file's units: the factor that makes Z_wdot an added mass."""
    return 0.5 * raw["environment"]["water_density"] * raw["rigid_body"]["length"] ** 3


def _mass_slug(raw: dict) -> float:
    return raw["rigid_body"]["weight"] / raw["environment"]["gravity"]


@pytest.mark.parametrize("Z_wdot", ["singular", 3.0])
def test_mass_matrix_must_be_positive_definite(Z_wdot):
    # Z_wdot = m / (rho/2 L^3) makes m - Z_wdot zero (a singular matrix); 3.0 makes it negative.
    raw = _suboff_file()
    value = _mass_slug(raw) / _nd2(raw) if Z_wdot == "singular" else Z_wdot
    with pytest.raises(
        ValueError,
        match=r"vehicle file <dict>: .*hydrodynamics\.Z_wdot=.*mass matrix.*"
        r"must be positive definite",
    ):
        vehicle_from_dict(_broken("hydrodynamics", "Z_wdot", value))


def test_suboff_mass_matrix_is_rigid_body_plus_added_mass(suboff):
    c = suboff.coefficients
    (m11, m12), (m21, m22) = suboff.mass_matrix
    assert m11 == pytest.approx(suboff.mass_kg - c.Z_wdot, rel=1e-15)
    assert m22 == pytest.approx(suboff.inertia_y_kg_m2 - c.M_qdot, rel=1e-15)
    assert (m12, m21) == (-c.Z_qdot, -c.M_wdot)  # x_G = 0
    assert m11 > suboff.mass_kg and m22 > suboff.inertia_y_kg_m2  # added mass adds to the body's


def test_variant_moving_G_checks_the_mass_matrix(suboff):
    # m x_G enters the off-diagonal terms: G 0.45 L aft of midship (within the hull) makes the matrix
    # indefinite; beyond a hull length G is refused as outside the vehicle.
    with pytest.raises(ValueError, match=r"x_G_m=.*mass matrix.*must be positive definite"):
        suboff.variant(x_GB_m=-0.45 * suboff.length_m)
    with pytest.raises(ValueError, match=r"x_G_m=42\.6.* is invalid: must be a finite number in \[-4\.26"):
        suboff.variant(x_GB_m=10 * suboff.length_m)


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        (None, "units", ["si"], r"units=\['si'\] is invalid: must be one of \['si', 'us_customary'\]"),
        (
            "rigid_body",
            "length",
            1e308,
            r"length_m=3\.048e\+307 is invalid: must be a finite number in \[0\.01, 1000\.0\]",
        ),
        (
            "environment",
            "water_density",
            1e-300,
            r"water_density_kg_m3=5\.15.*e-298 is invalid: must be a finite number in \[500\.0, 2000\.0\]",
        ),
        ("planes", "Z_delta_s", 0.0, r"planes\.Z_delta_s=0\.0 is invalid: must be a non-zero"),
        ("planes", "M_delta_b", 0, r"planes\.M_delta_b=0\.0 is invalid: must be a non-zero"),
        (
            "hull",
            "radius_ratio",
            [0.0] * 25,
            r"hull offsets: planform area=0\.0 m\^2 is invalid: must be > 0",
        ),
        ("hydrodynamics", "Z_w", True, r"hydrodynamics\.Z_w=True is invalid: must be a number"),
        # TOML's integers have no bound: one beyond the float range is refused by name, not converted.
        (
            "rigid_body",
            "z_G",
            10**400,
            r"rigid_body\.z_G=<an integer of 1329 bits> is invalid: must be a finite",
        ),
        (
            "rigid_body",
            "weight",
            -(10**400),
            r"rigid_body\.weight=<an integer of 1329 bits> is invalid: must be",
        ),
        ("hydrodynamics", "M_w", math.inf, r"hydrodynamics\.M_w=inf is invalid: must be a finite number"),
        ("rigid_body", "x_B", math.nan, r"rigid_body\.x_B=nan is invalid: must be a finite number"),
        (
            "hull",
            "stations",
            [0, 10**400],
            r"hull\.stations=\[0, <an integer of 1329 bits>\] is invalid: must be a list of finite numbers",
        ),
    ],
)
def test_inadmissible_vehicle_data_names_the_parameter(section, key, value, message):
    with pytest.raises(ValueError, match=r"vehicle file <dict>: " + message):
        vehicle_from_dict(_broken(section, key, value))


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\xff\xfe\x00\x01", r"vehicle file '.*bad\.toml' is not UTF-8 text \(byte 0xff at position 0\)"),
        (
            'name = "Sub\u00e9"\n'.encode("latin-1"),
            r"vehicle file '.*bad\.toml' is not UTF-8 text \(byte 0xe9",
        ),
    ],
)
def test_a_file_that_is_not_utf8_is_named(tmp_path: Path, content, message):
    path = tmp_path / "bad.toml"
    path.write_bytes(content)
    with pytest.raises(ValueError, match=message):
        load_vehicle(path)


@pytest.mark.parametrize("kind", ["directory", "device"])
def test_a_path_that_is_not_a_file_is_not_reported_missing(tmp_path: Path, kind):
    path = tmp_path if kind == "directory" else Path(os.devnull)
    with pytest.raises(ValueError, match=rf"vehicle file {re.escape(repr(str(path)))} is not a regular file"):
        load_vehicle(path)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"crossflow_drag": "0.3"}, r"crossflow_drag='0\.3' is invalid: must be a finite number >= 0"),
        ({"z_GB_m": 10**400}, r"z_GB_m=<an integer of 1329 bits> is invalid: must be a finite number"),
        ({"x_GB_m": -(10**400)}, r"x_GB_m=<an integer of 1329 bits> is invalid: must be a finite number"),
        ({"z_GB_m": True}, r"z_GB_m=True is invalid: must be a finite number"),
        ({"excess_buoyancy_N": np.True_}, r"excess_buoyancy_N=np\.True_ is invalid: must be a finite number"),
    ],
)
def test_variant_rejects_non_reals_and_huge_values_with_value_error(suboff, changes, message):
    with pytest.raises(ValueError, match=message):
        suboff.variant(**changes)


def test_variant_accepts_numpy_reals(suboff):
    v = suboff.variant(z_GB_m=np.float32(0.05), crossflow_drag=np.float64(0.2), x_GB_m=np.int64(0))
    assert (v.z_GB_m, v.crossflow_drag, v.x_GB_m) == (pytest.approx(0.05), 0.2, 0.0)
    assert type(v.crossflow_drag) is float and type(v.z_G_m) is float


def test_make_refuses_a_singular_vehicle_file_naming_it(tmp_path: Path):
    import gymnasium as gym

    import subenv  # noqa: F401  (registers the ids)

    raw = _suboff_file()
    text = resources.files("subenv.vehicles.data").joinpath("suboff.toml").read_text()
    path = tmp_path / "singular.toml"
    path.write_text(text.replace("Z_wdot = -1.4529e-2", f"Z_wdot = {_mass_slug(raw) / _nd2(raw)!r}"))
    with pytest.raises(
        ValueError, match=rf"vehicle file {re.escape(str(path))}: hydrodynamics\.Z_wdot=.*positive definite"
    ):
        gym.make("subenv/DivePlane-v0", vehicle=str(path))


_NUMERIC_FIELDS = [
    (section, key)
    for section, values in _suboff_file().items()
    if isinstance(values, dict)
    for key, value in values.items()
    if isinstance(value, (int, float)) and not isinstance(value, bool)
]


# An integer of 1025 bits, just beyond the float range, that this test drew on 2026-12-04: the loader met
# it as an OverflowError in float(value) instead of refusing it by name.
_FOUND_OVERFLOW = int(
    "3313722152495269168099680644867163650344222645704764420399734711842783418174376906866094711128791422"
    "2816819655283251060936221007482107672124635065678700123900814438946589792875403138219616115318983815"
    "3787596163257199035061303283398554748462787108494179883618594503882325694539349169792876899001455035"
    "019811137"
)


# (The suite's derandomized Hypothesis profile draws the examples from a seed made of the test's source: an
# edit of the test draws others, so a failure found that way is kept below as an @example.)
@settings(max_examples=60)
@example(field=("rigid_body", "z_G"), value=_FOUND_OVERFLOW, scale=None)
@given(
    field=st.sampled_from(_NUMERIC_FIELDS),
    value=st.one_of(
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(-(10**400), 10**400),
        st.booleans(),
        st.text(max_size=2),
        st.lists(st.floats(), max_size=2),
    ),
    scale=st.sampled_from([None, -1.0, 0.0, 1e-300, 0.5, 2.0, 1e300]),
)
def test_a_perturbed_vehicle_file_loads_an_admissible_vehicle_or_is_refused_by_name(field, value, scale):
    """Fuzzing the shipped file, one field at a time: the loader gives a vehicle whose environment
    steps with finite outputs, or a ValueError that names the file; never another exception."""
    import gymnasium as gym

    import subenv  # noqa: F401  (registers the ids)

    section, key = field
    raw = _suboff_file()
    raw[section][key] = value if scale is None else raw[section][key] * scale
    try:
        vehicle = vehicle_from_dict(raw, origin="fuzz.toml")
    except ValueError as error:
        assert str(error).startswith("vehicle file fuzz.toml"), error
        return
    try:
        env = gym.make("subenv/Nominal-v0", vehicle=vehicle)
    except (
        ValueError
    ) as error:  # admissible as a vehicle, but not for the environment (e.g. no critical speed)
        assert "is invalid" in str(error) or "has none" in str(error), error
        return
    obs, _ = env.reset(seed=0)
    for _ in range(10):
        obs, reward, *_ = env.step(np.array([1.0], dtype=np.float32))
        assert np.isfinite(obs).all() and np.isfinite(reward)


# --- the physical consistency the model needs, checked at load (issue 34, finding 7) -----------------
@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        # weight = 1e30 loaded, then every reset said "buoyancy_N=0.0 is invalid" (B - W rounded to -W).
        (
            "rigid_body",
            "weight",
            1e30,
            r"weight_N=4\.448.*e\+30 and buoyancy_N=6922\.48.* are invalid: B / W = 1\.556.*e-27 must be in "
            r"\[0\.5, 2\.0\]",
        ),
        ("rigid_body", "buoyancy", 2.5 * 1556.2363, r"are invalid: B / W = 2\.5 must be in \[0\.5, 2\.0\]"),
        # M_w = -1e300 loaded, then gym.make said the vehicle had no critical speed.
        (
            "hydrodynamics",
            "M_w",
            -1e300,
            r"hydrodynamics\.M_w=-1e\+300 is invalid: must be .* in \[-10\.0, 10\.0\]",
        ),
        (
            "planes",
            "Z_delta_b",
            50.0,
            r"planes\.Z_delta_b=50\.0 is invalid: must be a finite number in \[-10",
        ),
        # A derivative written in another sign convention: the stern planes would never reverse.
        (
            "hydrodynamics",
            "M_w",
            -1.0324e-2,
            r"hydrodynamics\.Z_w=-0\.01391 and M_w=-0\.010324 with planes\.Z_delta_s",
        ),
        (
            "hydrodynamics",
            "Z_w",
            0.5,
            r"give the stern planes no critical speed: .* must be > 0 \(Riedel 1993 eq\. 3\.9",
        ),
        (
            "rigid_body",
            "inertia_y",
            1e300,
            r"inertia_y_kg_m2=1\.35.*e\+300 is invalid: must be at most mass_kg \* length_m\^2 = 12805\.2 kg",
        ),
        (
            "environment",
            "gravity",
            1e-300,
            r"gravity_m_s2=3\.048.*e-301 is invalid: must be a finite number in \[0\.1",
        ),
        ("rigid_body", "z_G", 1e10, r"z_G_m=3048000000\.0 is invalid: must be a finite number in \[-4\.26"),
        ("rigid_body", "x_B", -20.0, r"x_B_m=-6\.096 is invalid: must be a finite number in \[-4\.26"),
    ],
)
def test_a_vehicle_the_model_cannot_run_is_refused_at_load_naming_the_file_and_field(
    section, key, value, message
):
    with pytest.raises(ValueError, match=r"^vehicle file absurd\.toml: .*" + message):
        vehicle_from_dict(_broken(section, key, value), origin="absurd.toml")


def test_a_derived_quantity_that_overflows_is_refused_by_name():
    # Weight and buoyancy of 1e307 lbf are each finite and in ratio 1, but the mass matrix's determinant
    # m11 m22 - m12 m21, by which the linear model divides, overflows.
    raw = _suboff_file()
    raw["rigid_body"].update(weight=1e307, buoyancy=1e307)
    with pytest.raises(
        ValueError,
        match=r"^vehicle file <dict>: the mass matrix's determinant Dv \(eqs 2\.59-2\.68\) = inf with "
        r"weight_N=4\.448.*e\+307, .* is invalid: must be finite",
    ):
        vehicle_from_dict(raw)


def test_a_variant_keeps_buoyancy_within_a_factor_of_two_of_weight(suboff):
    W = suboff.weight_N
    assert suboff.variant(excess_buoyancy_N=W).buoyancy_N == 2 * W  # (the analysis's heavier boat)
    assert suboff.variant(excess_buoyancy_N=-0.5 * W).buoyancy_N == 0.5 * W
    with pytest.raises(ValueError, match=r"are invalid: B / W = 2\.5 must be in \[0\.5, 2\.0\]"):
        suboff.variant(excess_buoyancy_N=1.5 * W)


@pytest.mark.parametrize(
    ("old", "new", "scenario", "message"),
    [
        (
            "weight = 1556.2363",
            "weight = 1e30",
            "Nominal",
            r"weight_N=.* and buoyancy_N=.* are invalid: B / W",
        ),
        ("M_w = 1.0324e-2", "M_w = -1e300", "LowSpeed", r"hydrodynamics\.M_w=-1e\+300 is invalid"),
    ],
)
def test_make_refuses_an_absurd_vehicle_file_naming_the_file_not_a_later_symptom(
    tmp_path: Path, old, new, scenario, message
):
    import gymnasium as gym

    import subenv  # noqa: F401  (registers the ids)

    text = resources.files("subenv.vehicles.data").joinpath("suboff.toml").read_text()
    assert old in text
    path = tmp_path / "absurd.toml"
    path.write_text(text.replace(old, new))
    with pytest.raises(ValueError, match=rf"^vehicle file {re.escape(str(path))}: {message}"):
        gym.make(f"subenv/{scenario}-v0", vehicle=str(path)).reset(seed=0)
