"""The speed curriculum: stages placed by the critical speed, advancing on measured success."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the 'rl' extra is not installed")

from subenv.analysis import critical_speed
from subenv.analysis.curriculum import DEFAULT_STAGES
from subenv.scenarios import get_scenario
from subenv_agents.config import CurriculumConfig
from subenv_agents.curriculum import (
    STATE_FILE,
    CurriculumCallback,
    CurriculumSchedule,
    read_stage,
    stage_scenarios,
    write_state,
)


def test_schedule_advances_only_on_a_full_window_at_threshold() -> None:
    schedule = CurriculumSchedule(n_stages=3, threshold=0.8, window=10)
    for _ in range(9):
        assert not schedule.record(True)  # window not full yet
    assert schedule.stage == 0
    assert schedule.record(True)  # 10/10
    assert schedule.stage == 1 and math.isnan(schedule.success_rate)  # the new stage starts afresh
    pattern = [True, True, False] * 10  # at most 7 of any 10 in a row: never advances
    assert not any(schedule.record(s) for s in pattern)
    assert schedule.stage == 1 and schedule.success_rate == pytest.approx(0.6)  # the last 10: FTTFTTFTTF
    # The window slides: the fourth success makes it 8 of the last 10.
    assert [schedule.record(True) for _ in range(4)] == [False, False, False, True]
    assert schedule.stage == 2 and schedule.final
    assert not any(schedule.record(True) for _ in range(50))  # the last stage is never left
    assert schedule.stage == 2


def test_schedule_rejects_bad_arguments() -> None:
    with pytest.raises(ValueError, match="n_stages"):
        CurriculumSchedule(0, 0.8, 10)
    with pytest.raises(ValueError, match="stage=3"):
        CurriculumSchedule(3, 0.8, 10, stage=3)
    with pytest.raises(ValueError, match="threshold"):
        CurriculumConfig(threshold=1.5)
    with pytest.raises(ValueError, match="stage"):
        CurriculumConfig(stages=(("x", 1.0, 0.5),))


def test_stages_are_placed_relative_to_the_critical_speed(suboff) -> None:
    base = get_scenario("Randomized")
    config = CurriculumConfig()
    scenarios = stage_scenarios(base, config, suboff)
    assert len(scenarios) == len(DEFAULT_STAGES) + 1 and scenarios[-1] is base
    top = DEFAULT_STAGES[0][2]
    lows = [s.speed_ratio[0] for s in scenarios[:-1]]
    assert lows == [low for _, low, _ in DEFAULT_STAGES]  # easy (fast) to hard
    assert all(s.speed_relative and s.speed_ratio[1] == top for s in scenarios[:-1])
    assert lows[0] > 1.0 and lows[-1] < 1.0  # starts above u_cr, ends below it
    # The loadings grow to the configured maxima; the base's randomisation applies throughout.
    assert scenarios[0].x_GB_m == (0.0, 0.0) and scenarios[-2].x_GB_m == (0.0, config.max_x_GB_m)
    assert scenarios[-2].excess_buoyancy_fraction[1] == config.max_excess_buoyancy_fraction
    assert all(
        s.sensor_noise == base.sensor_noise and s.z_GB_scale == base.z_GB_scale for s in scenarios[:-1]
    )


def test_stage_episodes_fly_at_the_stage_speeds(suboff) -> None:
    import gymnasium as gym

    scenarios = stage_scenarios(get_scenario("Randomized"), CurriculumConfig(), suboff)
    env = gym.make("subenv/DivePlane-v0")
    env.unwrapped.set_scenario(scenarios[0])
    ratios = []
    for seed in range(30):
        _, info = env.reset(seed=seed)
        ratios.append(info["speed_mps"] / info["critical_speed_mps"])
    assert min(ratios) >= DEFAULT_STAGES[0][1] - 1e-9 and max(ratios) <= DEFAULT_STAGES[0][2] + 1e-9
    assert critical_speed(suboff) > 0


class _FakeVecEnv:
    """What the callback needs of a training env: num_envs and env_method('set_scenario')."""

    def __init__(self, n: int) -> None:
        self.num_envs = n
        self.scenarios: list[str] = []

    def env_method(self, name: str, scenario, indices=None):  # type: ignore[no-untyped-def]
        assert name == "set_scenario"
        self.scenarios.append(scenario.name)
        return [None] * self.num_envs


def _run(
    callback: CurriculumCallback,
    env: _FakeVecEnv,
    episodes: list[tuple[int, bool]],
    length: int = 240,
    truncated: bool = True,
) -> None:
    """Feed ``episodes`` (env index, success) one step-stream at a time: ``length`` steps of 0.5 s each."""
    from stable_baselines3.common.logger import Logger

    class Model:
        logger = Logger(folder=None, output_formats=[])
        num_timesteps = 0

        def get_env(self):  # type: ignore[no-untyped-def]
            return env

    callback.init_callback(Model())  # type: ignore[arg-type]
    callback.on_training_start({}, {})
    n = env.num_envs
    for env_index, success in episodes:
        for k in range(1, length + 1):
            t = 0.5 * k
            dones = np.zeros(n, dtype=bool)
            infos = [{"time_s": t, "depth_error_m": 0.0} for _ in range(n)]
            if not success and k > length - 10:
                infos[env_index]["depth_error_m"] = 0.8  # off depth in the final window
            if k == length:
                dones[env_index] = True
                infos[env_index]["TimeLimit.truncated"] = truncated
            callback.update_locals({"infos": infos, "dones": dones})
            Model.num_timesteps += n
            callback.on_step()


def test_callback_advances_on_a_synthetic_success_signal(suboff) -> None:
    scenarios = stage_scenarios(get_scenario("Randomized"), CurriculumConfig(), suboff)
    config = CurriculumConfig(threshold=0.75, window=4)
    env = _FakeVecEnv(1)
    callback = CurriculumCallback(scenarios, config)
    # Episode 1 was under way before the curriculum started: it counts for no stage. Episodes
    # 2-5 fail, 6-8 succeed: 3 of the last 4 advance at the end of episode 8. Episode 9 was drawn
    # (autoreset) before that advance, so it counts for no stage either; 10-12 succeed and 13
    # fails: 3 of 4 again, the second advance.
    episodes = [(0, True)] + [(0, False)] * 4 + [(0, True)] * 3 + [(0, True)] + [(0, True)] * 3 + [(0, False)]
    _run(callback, env, episodes)
    assert callback.schedule.stage == 2
    assert env.scenarios == [scenarios[0].name, scenarios[1].name, scenarios[2].name]
    steps = [step for step, _ in callback.advances]
    assert steps == [8 * 240, 13 * 240]


@pytest.mark.parametrize(("length", "truncated"), [(100, True), (240, False)])
def test_short_or_terminated_episodes_do_not_count_as_success(suboff, length: int, truncated: bool) -> None:
    # 100 steps = 50 s, shorter than the 60 s hold window; or ended by termination, on depth.
    scenarios = stage_scenarios(get_scenario("Randomized"), CurriculumConfig(), suboff)
    callback = CurriculumCallback(scenarios, CurriculumConfig(threshold=0.5, window=2))
    env = _FakeVecEnv(1)
    _run(callback, env, [(0, True)] * 3, length=length, truncated=truncated)
    assert callback.schedule.stage == 0 and callback.schedule.success_rate == 0.0


def test_the_stage_at_a_step_is_the_start_stage_and_the_advances_up_to_it(tmp_path) -> None:
    write_state(tmp_path, 3, [(1000, 2), (5000, 3)], start_stage=1)
    assert read_stage(tmp_path) == 3  # the run's last
    assert [read_stage(tmp_path, t) for t in (0, 999, 1000, 4999, 5000, 10**9)] == [1, 1, 2, 2, 3, 3]
    assert read_stage(tmp_path / "no-curriculum", 100) == 0
    # Files written before the start stage was: a run that advanced started at stage 0.
    (tmp_path / STATE_FILE).write_text(json.dumps({"stage": 2, "advances": [[10, 1], [20, 2]]}))
    assert [read_stage(tmp_path, t) for t in (5, 10, 25)] == [0, 1, 2]
    (tmp_path / STATE_FILE).write_text(json.dumps({"stage": 2, "advances": []}))
    assert read_stage(tmp_path, 5) == 2
