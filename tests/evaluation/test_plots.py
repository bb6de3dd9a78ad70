"""The figures show what the results hold: a typical episode of every outcome, the speed crossing u_cr,
metrics binned against u / u_cr; and they are written completely, as PNG."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from subenv.evaluation.plots import (
    metrics_vs_speed_figure,
    outcomes_figure,
    plot_metrics_vs_speed,
    plot_outcomes,
    replay_trajectory,
    speed_crossing_s,
)
from subenv.evaluation.results import representative_episodes
from subenv.evaluation.rollout import TrajectoryRecorder

pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")


def _trajectory_of(small_run):
    def get(r):
        return replay_trajectory(r, small_run.controllers[r.controller])

    return get


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
        for c in ("a", "b")
        for u in np.linspace(0.2, 1.5, 12)
    ]
    path = plot_metrics_vs_speed(results, tmp_path / "plots" / "m.png")
    assert path.read_bytes().startswith(b"\x89PNG")
    assert [p.name for p in path.parent.iterdir()] == ["m.png"]


def test_metrics_vs_speed_spans_each_scenario_and_sets_the_controllers_apart(at_speed):
    """Each panel spans its own scenario's speeds (one below u_cr is not stretched to reach it, an
    arrow points there), the controllers stand side by side in each bin in legend order, and the
    title fits the figure with two scenarios."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.text import Text

    ucr = 0.5785
    results = [
        dataclasses.replace(at_speed(c, ucr * ratio, ucr, ratio > 0.5), scenario=scenario)
        for scenario, ratios in (("Slow", np.linspace(0.3, 0.8, 12)), ("Around", np.linspace(0.8, 1.3, 12)))
        for c in ("a", "b", "c")
        for ratio in ratios
    ]
    fig = metrics_vs_speed_figure(results, bins=2)
    FigureCanvasAgg(fig).draw()
    slow_success, around_success, slow_iae = fig.axes[0], fig.axes[1], fig.axes[2]
    low, high = slow_success.get_xlim()
    assert 0.3 - 0.05 <= low < 0.3 and 0.8 < high <= 0.8 + 0.05  # its bins, and no room for u_cr
    assert [t.get_text() for t in slow_success.texts] == ["u_cr \u2192"]
    assert not around_success.texts and 1.0 in [line.get_xdata()[0] for line in around_success.lines]
    for ax in (slow_success, slow_iae):
        markers = [line for line in ax.lines if line.get_marker() == "o"]
        x = np.array([line.get_xdata() for line in markers])  # (controller, bin)
        assert x.shape == (3, 2)
        assert np.all(np.diff(x, axis=0) > 0)  # a, b, c left to right in each bin
        assert np.all((x[:, 0] > 0.3) & (x[:, 0] < 0.55) & (x[:, 1] > 0.55) & (x[:, 1] < 0.8))
    (title,) = [t for t in fig.findobj(Text) if t.get_text() == fig.get_suptitle()]
    box = title.get_window_extent()
    assert 0 <= box.x0 and box.x1 <= fig.bbox.width


@pytest.mark.parametrize("scenario", ["LowSpeed", "PeriscopeDepth", "SpeedTransient"])
def test_outcome_figure_shows_one_chosen_episode_per_outcome(small_run, scenario: str):
    mine = [r for r in small_run.results if r.scenario == scenario]
    fig = outcomes_figure(mine, _trajectory_of(small_run))
    chosen = representative_episodes(mine)[scenario]
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    occurred = {r.metrics.outcome for r in mine}
    assert set(chosen) == occurred  # every outcome that occurred, and only those
    assert len(titles) == len(chosen)
    for title, (outcome, r) in zip(titles, chosen.items(), strict=True):
        count = sum(x.metrics.outcome == outcome for x in mine)
        its = [x for x in mine if x.controller == r.controller]
        its_count = sum(x.metrics.outcome == outcome for x in its)
        assert 1 <= its_count <= count
        assert title.startswith(
            f"{outcome.replace('_', ' ')} (all controllers: {count} of {len(mine)})\n"
            f"{r.controller}: {its_count} of {len(its)}; seed {r.seed}"
        )


def test_speed_transient_shows_the_speed_and_where_it_crosses_u_cr(small_run):
    mine = [r for r in small_run.results if r.scenario == "SpeedTransient"]
    get = _trajectory_of(small_run)
    fig = outcomes_figure(mine, get)
    columns = len(representative_episodes(mine)["SpeedTransient"])
    assert len(fig.axes) == 4 * columns  # depth error, pitch, planes, and the speed
    speed_axes = fig.axes[3 * columns :]
    for ax, r in zip(speed_axes, representative_episodes(mine)["SpeedTransient"].values(), strict=True):
        tr = get(r)
        crossing = speed_crossing_s(tr)
        assert crossing is not None and tr.time_s[0] < crossing < tr.time_s[-1]  # 2-2.6 u_cr down to 0.4-0.7
        k = int(np.searchsorted(tr.time_s, crossing))
        assert tr.speed_mps[k - 1] >= tr.critical_speed_mps > tr.speed_mps[k]
        vertical = [line.get_xdata()[0] for line in ax.get_lines() if len(set(line.get_xdata())) == 1]
        horizontal = [line.get_ydata()[0] for line in ax.get_lines() if len(set(line.get_ydata())) == 1]
        assert crossing in vertical and tr.critical_speed_mps in horizontal
        assert any(text.get_text().startswith("u = u_cr") for text in ax.texts)


def test_speed_crossing_is_interpolated_and_absent_at_constant_speed():
    info = {
        "time_s": 0.0,
        "depth_error_m": 0.0,
        "pitch_rad": 0.0,
        "heave_mps": 0.0,
        "pitch_rate_radps": 0.0,
        "speed_mps": 2.0,
        "stern_plane_rad": 0.0,
        "bow_plane_rad": 0.0,
        "depth_m": 10.0,
        "depth_command_m": 10.0,
        "critical_speed_mps": 1.0,
    }
    recorder = TrajectoryRecorder(info)
    for k in range(1, 5):
        recorder.record(
            np.zeros(1), info | {"time_s": 10.0 * k, "speed_mps": 2.0 - 0.4 * k}
        )  # 1.2 at 20 s, 0.8 at 30 s
    assert speed_crossing_s(recorder.finish("", 0.4, 40.0)) == pytest.approx(25.0)
    level = TrajectoryRecorder(info)
    level.record(np.zeros(1), info | {"time_s": 1.0})
    assert speed_crossing_s(level.finish("", 0.4, 1.0)) is None


def test_replay_gives_the_recorded_episode_and_refuses_another(small_run):
    r = next(r for r in small_run.results if r.metrics.outcome == "wrong_branch")
    tr = replay_trajectory(r, small_run.controllers[r.controller])
    assert tr.metrics() == r.metrics
    with pytest.raises(ValueError, match="the results say 'success'"):
        replay_trajectory(
            dataclasses.replace(r, metrics=dataclasses.replace(r.metrics, outcome="success")),
            small_run.controllers[r.controller],
        )


def test_outcome_plot_is_written_and_needs_one_scenario_with_trajectories(tmp_path: Path, small_run):
    get = _trajectory_of(small_run)
    mine = [r for r in small_run.results if r.scenario == "LowSpeed"]
    path = plot_outcomes(mine, tmp_path / "plots" / "t.png", get)
    assert path.read_bytes().startswith(b"\x89PNG") and [p.name for p in path.parent.iterdir()] == ["t.png"]
    with pytest.raises(ValueError, match="pass the episodes of one scenario"):
        outcomes_figure(small_run.results, get)
    with pytest.raises(ValueError, match="has no trajectory"):
        outcomes_figure(mine)  # no trajectories kept, and no way to replay given
