"""DivePlaneConfig holds what the environments' arguments resolve to, and gives the transition its
constants as one record filled field by field, by name."""

from __future__ import annotations

import inspect
import math
import typing
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import subenv
from subenv.envs import transition as tr
from subenv.envs.config import DEFAULT_ARGUMENTS, NOISE_STD, OBSERVATION_NAMES, DivePlaneConfig, _record
from subenv.scenarios import Scenario, get_scenario
from subenv.vehicles import Vehicle, load_vehicle


def test_the_fields_hold_the_resolved_objects_and_numbers() -> None:
    hints = typing.get_type_hints(DivePlaneConfig)
    assert (hints["scenario"], hints["vehicle"]) == (Scenario, Vehicle)
    assert hints["max_depth_error_m"] is float and hints["depth_scale_m"] is float
    path = Path(str(resources.files("subenv.vehicles.data").joinpath("suboff.toml")))
    for scenario, vehicle in (("LowSpeed", "suboff"), (get_scenario("LowSpeed"), path)):
        config = DivePlaneConfig(scenario=scenario, vehicle=vehicle)
        assert config.scenario == get_scenario("LowSpeed") and config.vehicle == load_vehicle("suboff")
        assert config.base_scenario is config.scenario and config.base_vehicle is config.vehicle
        assert isinstance(config.max_depth_error_m, float) and isinstance(config.depth_scale_m, float)
    changed = config.replace(scenario="Nominal", dt=0.25)
    assert changed.scenario.name == "Nominal" and changed.vehicle is config.vehicle and changed.dt == 0.25
    with pytest.raises(ValueError, match=r"scenario=3 is invalid: must be a scenario name or a Scenario"):
        DivePlaneConfig(scenario=3)  # type: ignore[arg-type]  # (the refusal is the test)


def test_the_environments_take_the_configuration_s_arguments_and_defaults() -> None:
    arguments = {
        name: parameter.default
        for name, parameter in inspect.signature(subenv.DivePlaneEnv).parameters.items()
        if name not in ("render_mode", "config")
    }
    assert arguments == dict(DEFAULT_ARGUMENTS)
    assert DEFAULT_ARGUMENTS["scenario"] == "Randomized" and DEFAULT_ARGUMENTS["max_depth_error_m"] is None


def test_the_constants_record_holds_each_value_under_its_name() -> None:
    config = DivePlaneConfig(
        scenario="LowSpeed",
        alpha=0.5,
        dt=0.25,
        substeps=3,
        plane_rate_limit_radps=0.2,
        max_pitch_rad=0.5,
        max_depth_error_m=20.0,
        depth_scale_m=3.0,
        pitch_weight=0.2,
        effort_weight=0.07,
        termination_penalty=50.0,
    )
    record = config.constants(max_episode_steps=123)
    assert record.shape == (1,) and record.dtype == tr.CONFIG_DTYPE and not record.flags.writeable
    c = record[0]
    decay = math.exp(-0.25 / 30.0)
    expected = {
        "dt_s": 0.25,
        "substeps": 3,
        "dual": True,
        "alpha": 0.5,
        "plane_limit_rad": config.plane_limit_rad,
        "rate_limited": True,
        "max_move_rad": 0.2 * 0.25,
        "max_pitch_rad": 0.5,
        "max_depth_error_m": 20.0,
        "broach_depth_m": config.broach_depth_m,
        "depth_scale_m": 3.0,
        "pitch_weight": 0.2,
        "effort_weight": 0.07,
        "termination_penalty": 50.0,
        "disturbance_decay": decay,
        "disturbance_gain": math.sqrt(1 - decay * decay),
        "max_steps": 123.0,
        "max_heave_mps": 20.0,
        "max_pitch_rate_radps": 10.0,
    }
    assert set(expected) | {"obs_low", "obs_high", "noise_std"} == set(tr.CONFIG_DTYPE.names or ())
    assert {name: c[name].item() for name in expected} == expected
    np.testing.assert_array_equal(c["obs_low"], config.observation_bounds[0])
    np.testing.assert_array_equal(c["obs_high"], config.observation_bounds[1])
    assert c["noise_std"].tolist() == [NOISE_STD.get(name, 0.0) for name in OBSERVATION_NAMES]
    unlimited = DivePlaneConfig().constants()[0]
    assert not unlimited["rate_limited"] and unlimited["max_move_rad"] == 0.0
    assert unlimited["max_steps"] == math.inf


def test_a_record_is_filled_with_every_field_and_no_other() -> None:
    dtype = np.dtype([("a", np.float64), ("b", np.int64)])
    assert _record(dtype, b=2, a=1.5).tolist() == [(1.5, 2)]
    with pytest.raises(ValueError, match=r"missing \['b'\], unknown \[\]"):
        _record(dtype, a=1.5)
    with pytest.raises(ValueError, match=r"missing \[\], unknown \['c'\]"):
        _record(dtype, a=1.5, b=2, c=3)


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_a_copied_configuration_is_equal_and_its_hull_read_only_as_made(how: str) -> None:
    """The kernels take the hull table read-only; pickle and deepcopy give writable arrays, for which an
    environment made from the copy would compile its step again."""
    import copy
    import pickle

    config = DivePlaneConfig(scenario="Nominal")
    assert not config.hull.flags.writeable
    twin = pickle.loads(pickle.dumps(config)) if how == "pickle" else copy.deepcopy(config)
    assert twin == config and not twin.hull.flags.writeable
    np.testing.assert_array_equal(twin.hull, config.hull)
