"""The oracle prototype (issue 37): its copy of an episode is the environment's, its plans replay, and its
certificate says what the replay says."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("daqp", reason="the 'mpc' extra is not installed")

from subenv.envs import DivePlaneEnv
from subenv.envs.config import DivePlaneConfig
from subenv.scenarios import get_scenario
from subenv_baselines.oracle import ExactEpisode, OracleSettings, certify, replay

STATE_KEYS = ("depth_m", "pitch_rad", "heave_mps", "pitch_rate_radps", "stern_plane_rad", "bow_plane_rad")


def _noisy_config(**kwargs: object) -> DivePlaneConfig:
    """NearCritical with sensor noise and a 3 N heave-force disturbance: every random draw a step makes."""
    scenario = get_scenario("NearCritical").replace(
        name="NoisyNearCritical", sensor_noise=True, disturbance_std_N=3.0
    )
    return DivePlaneConfig(scenario=scenario, control="independent", **kwargs)


def _plan(steps: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-0.2, 0.2, (steps, 2)).astype(np.float32)


@pytest.mark.parametrize("rate_limit", [None, 0.05])
def test_episode_copy_steps_as_the_environment(rate_limit: float | None) -> None:
    """The oracle's episode and the environment reset with one seed and given one plan go through the
    same states and heave forces, bit for bit, and the heave force drawn ahead is the one they meet."""
    config = _noisy_config(plane_rate_limit_radps=rate_limit)
    episode = ExactEpisode(config, 123)
    env = DivePlaneEnv(config=config)
    _, info = env.reset(seed=123)
    assert episode.info == info
    for k, action in enumerate(_plan(60)):
        _, _, terminated, truncated, info = env.step(action)
        episode.step(action)
        assert episode.info == info
        assert info["disturbance_N"] == episode.disturbances[k + 1]
        assert not (terminated or truncated)


def test_rollouts_predict_the_episode() -> None:
    """A batch of copies rolled out from the present state with the episode's future heave force reaches
    the states the episode itself reaches with the same plan, bit for bit; each copy its own plan."""
    config = _noisy_config()
    episode = ExactEpisode(config, 7)
    for action in _plan(10, seed=1):
        episode.step(action)
    plans = np.stack([_plan(30, seed=2), _plan(30, seed=3)])
    reports = episode.rollout(plans)
    for k, plan in enumerate(plans):
        run = episode.copy()
        for h, action in enumerate(plan):
            run.step(action)
            for key in STATE_KEYS:
                assert reports[h, _row(key), k] == run.info[key], (k, h, key)
    assert episode.steps == 10  # the copies left the episode where it was


def test_certificate_is_its_replay() -> None:
    """On an easy episode the first stage's plan wins, and replaying the stored plan wins again; a plan
    that loses is not a certificate (held planes at design speed: the pitch limit within a minute)."""
    config = DivePlaneConfig(scenario="Nominal", control="independent")
    cert = certify(config, 3, settings=OracleSettings(sampling=False))
    assert cert.success and cert.stage == "mpc"
    assert cert.actions.dtype == np.float32 and cert.actions.shape[1] == 2
    again = replay(config, 3, cert.actions)
    assert again.success and again.hold_max_abs_error_m == cert.hold_max_abs_error_m
    held = replay(config, 3, np.zeros((400, 2), dtype=np.float32))
    assert not held.success and held.outcome == "pitch_limit"


def test_depth_programme_is_judged_at_its_end() -> None:
    """An ordered depth 3 m shallower until 100 s: the first stage follows it (the error it sees is from
    the ordered depth of the moment) and the replay judges the final ordered depth."""
    config = DivePlaneConfig(scenario="Nominal", control="independent")
    cert = certify(
        config, 5, lambda t: np.where(np.asarray(t) < 100.0, -3.0, 0.0), OracleSettings(sampling=False)
    )
    assert cert.success
    episode = ExactEpisode(config, 5, lambda t: np.where(np.asarray(t) < 100.0, -3.0, 0.0))
    for action in cert.actions[:180]:  # to 90 s: held about 3 m above the final ordered depth
        episode.step(action)
    assert abs(episode.info["depth_error_m"] + 3.0) < 0.5


def test_oracle_needs_independent_planes() -> None:
    with pytest.raises(ValueError, match="control='dual' is invalid for the oracle"):
        certify(DivePlaneConfig(scenario="Nominal"), 0)


def _row(key: str) -> int:
    from subenv.envs.transition import REPORT_KEYS

    return REPORT_KEYS.index(key)
