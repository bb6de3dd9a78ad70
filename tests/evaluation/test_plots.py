"""The figures are written (completely, as PNG) for fixed and for randomised critical speeds."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from subenv.evaluation.plots import plot_metrics_vs_speed, plot_trajectories
from subenv.evaluation.rollout import TrajectoryRecorder

pytest.importorskip("matplotlib")


@pytest.fixture
def at_speed(make_result):
    def _at_speed(controller: str, speed: float, ucr: float, success: bool):
        r = make_result(controller, "S", 0, success)
        return dataclasses.replace(r, final_speed_mps=speed, initial_speed_mps=speed, critical_speed_mps=ucr)

    return _at_speed


@pytest.mark.parametrize("randomised", [False, True])
def test_metrics_vs_speed_is_written(tmp_path: Path, randomised: bool, at_speed):
    rng = np.random.default_rng(0)
    results = [
        at_speed(c, float(u), 0.5785 * (rng.uniform(0.8, 1.25) if randomised else 1.0), u > 0.6)
        for c in ("a", "b") for u in np.linspace(0.2, 1.5, 12)
    ]
    path = plot_metrics_vs_speed(results, tmp_path / "plots" / "m.png")
    assert path.read_bytes().startswith(b"\x89PNG")
    assert [p.name for p in path.parent.iterdir()] == ["m.png"]


def test_trajectories_need_one_episode_with_trajectories(tmp_path: Path, at_speed):
    info = {"time_s": 0.0, "depth_error_m": 1.0, "pitch_rad": 0.0, "heave_mps": 0.0, "pitch_rate_radps": 0.0,
            "speed_mps": 0.4, "stern_plane_rad": 0.0, "bow_plane_rad": 0.0, "depth_m": 11.0,
            "depth_command_m": 10.0, "critical_speed_mps": 0.5785}
    recorder = TrajectoryRecorder(info)
    for k in range(1, 5):
        recorder.record(np.zeros(1), info | {"time_s": 0.5 * k, "stern_plane_rad": 0.1})
    trajectory = recorder.finish("", 0.4, 2.0)
    one = dataclasses.replace(at_speed("a", 0.4, 0.5785, False), trajectory=trajectory)
    two = dataclasses.replace(one, controller="b")
    assert plot_trajectories([one, two], tmp_path / "t.png").read_bytes().startswith(b"\x89PNG")
    with pytest.raises(ValueError, match="several episodes"):
        plot_trajectories([one, dataclasses.replace(two, seed=999)], tmp_path / "u.png")
    with pytest.raises(ValueError, match="no result carries a trajectory"):
        plot_trajectories([at_speed("a", 0.4, 0.5785, False)], tmp_path / "v.png")
