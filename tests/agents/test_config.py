"""The hyperparameter files and their loader: typed configs, every unknown key rejected."""

from __future__ import annotations

import pytest

pytest.importorskip("yaml", reason="the 'rl' extra is not installed")
pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")

from subenv_agents.config import (
    ALGORITHMS,
    HYPERPARAMS_DIR,
    AgentConfig,
    load_config,
    model_kwargs,
    parse_overrides,
)


@pytest.mark.parametrize("algo", ALGORITHMS)
def test_shipped_file_loads_for_every_registered_id(algo: str) -> None:
    import gymnasium as gym

    assert (HYPERPARAMS_DIR / f"{algo}.yml").is_file()
    for env_id in (k for k in gym.registry if k.startswith("subenv/")):
        config = load_config(algo, env_id)
        assert isinstance(config, AgentConfig)
        assert config.algo == algo and config.env_id == env_id
        assert config.n_timesteps >= 1 and config.n_envs >= 1
        assert 0 < config.gamma() < 1


@pytest.mark.parametrize(
    ("override", "named"),
    [
        ({"n_step": 128}, "n_step"),  # a typo of an algorithm argument
        ({"env_kwargs": {"controll": "dual"}}, "controll"),  # an unknown environment argument
        ({"normalize": {"norm_obss": True}}, "norm_obss"),
        ({"curriculum": {"treshold": 0.5}}, "treshold"),
        ({"depth_integral": {"time_constant": 5.0}}, "time_constant"),
        ({"depth_integral": {"limit_ms": -1.0}}, "limit_ms"),
        ({"plane_effort_l1": -0.5}, "plane_effort_l1"),
        ({"plane_effort_l1": "0.5"}, "plane_effort_l1"),
        ({"plane_effort_reference_speed_mps": 0.0}, "plane_effort_reference_speed_mps"),
        ({"depth_band_bonus": {"width_m": 0.3}}, "width_m"),
        ({"depth_band_bonus": {"half_width_m": 0.0}}, "half_width_m"),
        ({"depth_band_bonus": {"bonus": float("nan")}}, "bonus"),
        ({"depth_band_bonus": 0.5}, "depth_band_bonus"),
        ({"policy_kwargs": {"activation_fn": "nn.Tanh"}}, "activation_fn"),  # no eval of strings
        ({"learning_rate": "lin3e-4"}, "learning_rate"),
        ({"n_timesteps": -5}, "n_timesteps"),
        ({"policy": "CnnPolicy"}, "policy"),
    ],
)
def test_unknown_or_invalid_key_is_an_error_naming_it(override: dict, named: str) -> None:
    with pytest.raises(ValueError, match=named):
        load_config("ppo", "subenv/LowSpeed-v0", overrides=override)


def test_unknown_key_error_lists_the_known_ones() -> None:
    with pytest.raises(ValueError) as info:
        load_config("ppo", "subenv/LowSpeed-v0", overrides={"n_step": 128})
    assert "n_steps" in str(info.value) and "n_timesteps" in str(info.value)


def test_unknown_algorithm_and_env_id_name_the_known_ones() -> None:
    with pytest.raises(ValueError, match=r"algo='dqn' is unknown.*'ppo', 'sac', 'td3'"):
        load_config("dqn", "subenv/LowSpeed-v0")
    with pytest.raises(ValueError, match=r"env_id='subenv/Nope-v0' is not registered.*subenv/LowSpeed-v0"):
        load_config("ppo", "subenv/Nope-v0")


def test_rl_zoo_layout_entry_by_id_then_default(tmp_path) -> None:
    path = tmp_path / "ppo.yml"
    path.write_text(
        "default:\n  n_timesteps: 1000\n  n_steps: 64\n"
        "subenv/LowSpeed-v0:\n  n_timesteps: 2000\n  n_envs: 2\n  normalize: false\n"
        "  learning_rate: lin_1.0e-3\n  policy_kwargs: {net_arch: [16], activation_fn: relu}\n"
    )
    own = load_config("ppo", "subenv/LowSpeed-v0", path)
    assert (own.n_timesteps, own.n_envs, own.normalize) == (2000, 2, None)
    kwargs = model_kwargs(own)
    assert kwargs["learning_rate"](1.0) == pytest.approx(1e-3)  # SB3 progress_remaining 1 -> 0
    assert kwargs["learning_rate"](0.0) == pytest.approx(0.0)
    assert kwargs["policy_kwargs"]["activation_fn"].__name__ == "ReLU"
    other = load_config("ppo", "subenv/NearCritical-v0", path)
    assert (other.n_timesteps, other.algo_kwargs) == (1000, {"n_steps": 64})
    (tmp_path / "bad.yml").write_text("subenv/LowSpeed-v0:\n  n_timesteps: 10\n")
    with pytest.raises(ValueError, match="no entry for 'subenv/Nominal-v0' and no 'default'"):
        load_config("ppo", "subenv/Nominal-v0", tmp_path / "bad.yml")


def test_yaml_is_not_evaluated(tmp_path) -> None:
    path = tmp_path / "ppo.yml"
    path.write_text("default:\n  n_timesteps: !!python/object/apply:os.system ['echo hacked']\n")
    with pytest.raises(Exception, match="python/object/apply"):
        load_config("ppo", "subenv/LowSpeed-v0", path)


def test_config_round_trips_through_its_yaml_entry(tmp_path) -> None:
    import yaml

    config = load_config("sac", "subenv/LowSpeed-v0", overrides={"curriculum": {"threshold": 0.7}})
    path = tmp_path / "sac.yml"
    path.write_text(yaml.safe_dump({"subenv/LowSpeed-v0": config.to_yaml_dict()}))
    assert load_config("sac", "subenv/LowSpeed-v0", path) == config


def test_overrides_are_parsed_as_yaml() -> None:
    assert parse_overrides(
        ["learning_rate:1.0e-4", "policy_kwargs:{net_arch: [32, 32]}", "curriculum:false"]
    ) == {"learning_rate": 1e-4, "policy_kwargs": {"net_arch": [32, 32]}, "curriculum": False}
    with pytest.raises(ValueError, match="key:value"):
        parse_overrides(["learning_rate"])


def test_depth_band_bonus_round_trips_through_yaml() -> None:
    config = load_config("ppo", "subenv/LowSpeed-v0", overrides={"depth_band_bonus": {"half_width_m": 0.25}})
    assert config.depth_band_bonus is not None
    assert (config.depth_band_bonus.half_width_m, config.depth_band_bonus.bonus) == (0.25, 0.5)
    entry = config.to_yaml_dict()
    assert entry["depth_band_bonus"] == {"half_width_m": 0.25, "bonus": 0.5}
    assert load_config("ppo", "subenv/LowSpeed-v0", overrides=entry) == config
    off = load_config("ppo", "subenv/LowSpeed-v0", overrides={"depth_band_bonus": False})
    assert off.depth_band_bonus is None and off.to_yaml_dict()["depth_band_bonus"] is False
