"""The shipped models: complete, loadable in one call, registered, and as good as their cards say."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")

import subenv_agents
from subenv.evaluation import controller_names, evaluate, make_controller
from subenv_agents import shipped_models
from subenv_agents.card import BASELINE, REVERSAL_SCENARIOS, evaluation_record, total_training_time_s
from subenv_agents.policy import load_agent

SHIPPED = shipped_models()


def test_ppo_and_sac_are_shipped() -> None:
    assert {"ppo", "sac"} <= set(SHIPPED)


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_model_folder_is_complete_and_loads_in_one_call(name: str) -> None:
    folder = SHIPPED[name]
    for file in (
        "model.zip",
        "vecnormalize.pkl",
        "config.yml",
        "train.json",
        "evaluation.json",
        "MODEL_CARD.md",
    ):
        assert (folder / file).is_file(), file
    record = json.loads((folder / "train.json").read_text())
    card = (folder / "MODEL_CARD.md").read_text()
    assert record["command"] in card and f"Seed: {record['seed']}" in card
    assert (
        total_training_time_s(record) <= 30 * 60
    )  # the budget: 30 minutes on 2 cores, earlier runs included
    agent = load_agent(folder)
    assert agent.obs_mean is not None and agent.config.algo == record["algo"]
    observation = np.zeros(agent.observation_space.shape)
    assert subenv_agents.load_agent(folder).predict(observation).shape == agent.action_space.shape


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_shipped_model_is_a_registered_controller(name: str) -> None:
    assert name in controller_names()
    controller = make_controller(name)
    assert controller.name == name and controller.control == "independent"


@pytest.fixture(scope="module")
def reversal_results():  # type: ignore[no-untyped-def]
    """The reversal suite (100 episodes per scenario, seeds 10000 + i) for every shipped model and the
    baseline."""
    controllers = [make_controller(n) for n in sorted(SHIPPED)] + [make_controller(BASELINE)]
    return evaluation_record(evaluate(controllers, list(REVERSAL_SCENARIOS), episodes=100, progress=False))


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_card_numbers_are_reproduced(name: str, reversal_results) -> None:  # type: ignore[no-untyped-def]
    stored = json.loads((SHIPPED[name] / "evaluation.json").read_text())
    assert stored["episodes"] == 100
    for scenario in REVERSAL_SCENARIOS:
        for who in (name, BASELINE):
            ours, theirs = reversal_results[who][scenario], stored["suite"][who][scenario]
            assert ours["success_rate"] == theirs["success_rate"], (who, scenario)
            assert ours["plane_rms_rad"] == pytest.approx(theirs["plane_rms_rad"], rel=1e-9), (who, scenario)


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_card_states_the_target_as_measured(name: str, reversal_results, report) -> None:  # type: ignore[no-untyped-def]
    """The target: at least the reversal-aware baseline's success with less plane effort, below, near and
    through u_cr. The card says "met" exactly when this run measures it met, on every scenario."""
    stored = json.loads((SHIPPED[name] / "evaluation.json").read_text())
    met = []
    for scenario in REVERSAL_SCENARIOS:
        ours, baseline = reversal_results[name][scenario], reversal_results[BASELINE][scenario]
        met.append(
            ours["success_rate"] >= baseline["success_rate"]
            and ours["plane_rms_rad"] < baseline["plane_rms_rad"]
        )
        report(
            f"shipped {name} vs {BASELINE}, {scenario}",
            f"success {100 * ours['success_rate']:.0f}% vs {100 * baseline['success_rate']:.0f}%, plane RMS "
            f"{ours['plane_rms_rad']:.4f} vs {baseline['plane_rms_rad']:.4f} rad",
        )
    assert stored["target_met"] == all(met)
    card = (SHIPPED[name] / "MODEL_CARD.md").read_text()
    assert f"**{'met' if all(met) else 'not met'}**" in card


def test_shipped_ppo_uses_less_plane_effort_than_the_baseline(reversal_results) -> None:  # type: ignore[no-untyped-def]
    """What the README claims for the shipped PPO: lower plane RMS than reversal_aware on every reversal
    scenario."""
    for scenario in REVERSAL_SCENARIOS:
        assert (
            reversal_results["ppo"][scenario]["plane_rms_rad"]
            < reversal_results[BASELINE][scenario]["plane_rms_rad"]
        )


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_a_shipped_agent_makes_its_env_and_acts_on_its_observations_as_the_harness_does(name: str) -> None:
    """The README's episode loop: ``agent.make_env()`` is the env the agent was trained on, its
    observations as the agent takes them, so ``agent.predict(obs)`` acts in one call; the actions are
    the evaluation controller's (which appends the depth-error integral itself) on the plain env."""
    import gymnasium as gym

    from subenv_agents.controller import AgentController

    agent = load_agent(SHIPPED[name])
    env = agent.make_env()
    plain = gym.make(agent.config.env_id, **agent.config.env_kwargs)
    controller = AgentController(agent)
    obs, _ = env.reset(seed=5)
    plain_obs, info = plain.reset(seed=5)
    controller.reset(info, plain.unwrapped.vehicle)
    assert env.observation_space.shape == agent.observation_space.shape
    for _ in range(60):
        action = agent.predict(obs)
        np.testing.assert_array_equal(action, controller.act(plain_obs))
        obs, _, terminated, truncated, _ = env.step(action)
        plain_obs, *_ = plain.step(action)
        if terminated or truncated:
            break
