"""Episode metrics on hand-made trajectories whose answers are known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from subenv.evaluation.metrics import (
    APPROACH_S,
    DEPTH_TOLERANCE_M,
    HOLD_WINDOW_S,
    NON_LEVEL_PITCH_RAD,
    OUTCOMES,
    REGULATION_BAND_M,
    STEADY_PITCH_RATE_RADPS,
    episode_metrics,
    episode_quality,
    episode_success,
    regulation_window,
)

LIMIT = 0.4  # rad
DT = 0.5  # s, the environments' control period


def _metrics(t, e, *, pitch=None, rate=None, stern=None, bow=None, reason="", duration=None, **kwargs):
    n = len(t)
    zeros = np.zeros(n)
    return episode_metrics(
        t,
        e,
        zeros if pitch is None else pitch,
        zeros if rate is None else rate,
        zeros if stern is None else stern,
        zeros if bow is None else bow,
        termination_reason=reason,
        plane_limit_rad=LIMIT,
        episode_duration_s=duration,
        **kwargs,
    )


def _time(duration_s: float, dt: float = DT) -> np.ndarray:
    return np.arange(0.0, duration_s + dt / 2, dt)


def test_exponential_approach_succeeds_with_known_settling_time_and_iae():
    t = _time(200.0)
    e = 2.0 * np.exp(-t / 10.0)  # 2 m too deep, time constant 10 s
    m = _metrics(t, e)
    assert m.success and m.outcome == "success" and not m.terminated
    # |e| <= 0.5 m from t = 10 ln 4 = 13.86 s: the first sample after is 14.0 s.
    assert m.settling_time_s == pytest.approx(14.0)
    # IAE = 20 (1 - exp(-20)) m s; the trapezoidal rule errs by ~h^2 / (12 tau^2) relative.
    assert m.iae_m_s == pytest.approx(20.0 * (1 - math.exp(-20.0)), rel=5e-4)
    assert m.overshoot_m == 0.0  # never crosses to the shallow side
    assert m.peak_pitch_deg == 0.0 and m.plane_rms_rad == 0.0 and m.saturated_fraction == 0.0
    assert m.hold_max_abs_error_m == pytest.approx(2.0 * math.exp(-14.0), rel=1e-9)
    assert m.duration_s == 200.0


def test_overshoot_is_the_excursion_past_the_ordered_depth_on_the_far_side():
    t = np.arange(12.0)
    too_deep = np.array([2.0, 1.0, 0.0, -0.3, -0.7, -0.2, 0.4, 0.1, 0.0, 0.0, 0.0, 0.0])
    assert _metrics(t, too_deep).overshoot_m == pytest.approx(0.7)
    assert _metrics(t, -too_deep).overshoot_m == pytest.approx(0.7)  # too shallow: the deep side
    assert _metrics(t, np.abs(too_deep)).overshoot_m == 0.0  # approaches from one side only
    at_depth = np.array([0.0, 0.2, -0.6, 0.1] + [0.0] * 8)
    assert _metrics(t, at_depth).overshoot_m == pytest.approx(0.6)  # no initial error: any excursion


def test_constant_offset_fails_settles_never_and_integrates_exactly():
    t = _time(300.0)
    e = np.full_like(t, 1.0)
    m = _metrics(t, e)
    assert not m.success and m.settling_time_s == math.inf
    assert m.iae_m_s == pytest.approx(300.0)
    # Steady and off depth with the planes free (here: level and idle): a steady offset.
    assert m.steady_offset and not m.wrong_branch and m.outcome == "steady_offset"


def test_success_needs_the_whole_final_window_within_tolerance():
    t = _time(300.0)
    e = np.zeros_like(t)
    e[t == 100.0] = 3.0  # an excursion before the window is allowed
    assert _metrics(t, e).success
    late = e.copy()
    late[t == 300.0 - HOLD_WINDOW_S + 1.0] = DEPTH_TOLERANCE_M + 0.01  # one sample in the window
    m = _metrics(t, late)
    assert not m.success and m.hold_max_abs_error_m == pytest.approx(0.51)
    assert m.settling_time_s == pytest.approx(300.0 - HOLD_WINDOW_S + 1.0 + DT)
    exactly = e.copy()
    exactly[-1] = DEPTH_TOLERANCE_M  # the tolerance is inclusive
    assert _metrics(t, exactly).success


@pytest.mark.parametrize(
    ("duration_s", "off_depth_at_s", "reason", "success"),
    [
        (300.0, None, "", True),
        (300.0, 300.0 - HOLD_WINDOW_S - DT, "", True),  # the last sample before the window
        (300.0, 300.0 - HOLD_WINDOW_S, "", False),  # the window's first sample is in it
        (300.0, 300.0, "", False),
        (300.0, None, "broached", False),
        (HOLD_WINDOW_S - DT, None, "", False),  # shorter than the window
        (HOLD_WINDOW_S, None, "", True),  # exactly the window
    ],
)
def test_success_from_the_last_time_off_depth_agrees_with_the_whole_record(
    duration_s: float, off_depth_at_s: float | None, reason: str, success: bool
) -> None:
    # What a training callback keeps (start, end, last time off depth) decides as the record does.
    t = _time(duration_s)
    e = np.zeros_like(t)
    if off_depth_at_s is not None:
        e[t == off_depth_at_s] = DEPTH_TOLERANCE_M + 0.01
    last_outside_s = -math.inf if off_depth_at_s is None else off_depth_at_s
    streamed = episode_success(
        terminated=reason != "", start_s=float(t[0]), end_s=float(t[-1]), last_outside_s=last_outside_s
    )
    assert streamed == _metrics(t, e, reason=reason).success == success


def test_a_record_shorter_than_the_window_cannot_succeed():
    t = _time(HOLD_WINDOW_S / 2)
    m = _metrics(t, np.zeros_like(t))
    assert not m.success and m.settling_time_s == 0.0 and m.outcome == "unsettled"


def test_termination_fails_the_episode_and_charges_the_rest_of_its_time():
    t = _time(100.0)
    e = np.full_like(t, -1.0)  # 1 m shallow, then broached at 100 s of a 300 s episode
    m = _metrics(t, e, reason="broached", duration=300.0)
    assert m.broached and m.terminated and not m.success
    assert m.settling_time_s == math.inf
    assert m.iae_m_s == pytest.approx(100.0 + 200.0)
    assert m.outcome == "broached" and not m.steady_offset
    assert _metrics(t, e, reason="broached").iae_m_s == pytest.approx(100.0)  # no schedule given
    assert _metrics(t, np.zeros_like(t), reason="pitch_limit").outcome == "pitch_limit"


def test_saturation_fraction_weights_each_step_by_its_length():
    t = np.arange(11.0)  # 10 steps of 1 s; sample k holds the planes of step (t[k-1], t[k]]
    stern = LIMIT * np.array([0.9, 1.0, 1.0, 1.0, 0.5, 0.0, 0.0, -1.0, -0.995, 0.98, 0.0])
    m = _metrics(t, np.zeros(11), stern=stern)
    assert m.saturated_fraction == pytest.approx(5 / 10)  # steps 1, 2, 3, 7, 8 (sample 0 unused)
    bow = np.zeros(11)
    bow[5] = LIMIT  # the bow planes at their limit count too
    assert _metrics(t, np.zeros(11), stern=stern, bow=bow).saturated_fraction == pytest.approx(6 / 10)
    uneven = np.array([0.0, 1.0, 4.0])  # steps of 1 s and 3 s, saturated in the second only
    m = _metrics(uneven, np.zeros(3), stern=np.array([0.0, 0.0, LIMIT]))
    assert m.saturated_fraction == pytest.approx(3 / 4)


def test_plane_rms_combines_stern_and_bow_planes():
    t = _time(100.0)
    m = _metrics(t, np.zeros_like(t), stern=np.full_like(t, 0.3), bow=np.full_like(t, -0.4))
    assert m.plane_rms_rad == pytest.approx(0.5)
    stern = np.where(np.arange(t.size) % 2 == 1, 0.2, 0.0)  # half the steps at 0.2 rad
    assert _metrics(t, np.zeros_like(t), stern=stern).plane_rms_rad == pytest.approx(0.2 / math.sqrt(2))


def test_peak_pitch_is_the_largest_absolute_pitch_in_degrees():
    t = np.arange(5.0)
    m = _metrics(t, np.zeros(5), pitch=np.radians([0.0, 2.0, -7.5, 3.0, 0.0]))
    assert m.peak_pitch_deg == pytest.approx(7.5)


def _wrong_branch_episode(duration_s: float = 600.0, pitch_deg: float = 3.0):
    """A boat pitched steadily at ``pitch_deg`` with its stern planes pinned, drifting 0.02 m/s."""
    t = _time(duration_s)
    e = 0.02 * t  # drifting off the ordered depth (the saturated branch's drift at ~0.3 u_cr)
    pitch = np.full_like(t, math.radians(pitch_deg))
    rate = np.zeros_like(t)
    stern = np.full_like(t, LIMIT)
    return t, e, pitch, rate, stern


def test_wrong_branch_detects_a_steady_pitched_state_with_pinned_planes():
    t, e, pitch, rate, stern = _wrong_branch_episode()
    m = _metrics(t, e, pitch=pitch, rate=rate, stern=stern)
    assert m.wrong_branch and not m.success and not m.steady_offset
    assert m.outcome == "wrong_branch" and m.saturated_fraction == 1.0
    # It explains a later termination: broaching after drifting up on the wrong branch.
    up = _metrics(t, -e, pitch=-pitch, rate=rate, stern=stern, reason="broached", duration=900.0)
    assert up.wrong_branch and up.broached and up.outcome == "wrong_branch"
    # Negative stern limit, or the bow planes pinned while the stern planes are free: the same.
    assert _metrics(t, e, pitch=pitch, rate=rate, stern=-stern).wrong_branch
    assert _metrics(t, e, pitch=pitch, rate=rate, bow=stern).wrong_branch


@pytest.mark.parametrize(
    "change",
    [
        "chattering",  # saturated all the time, but between +limit and -limit: not pinned
        "level",  # pinned but level (e.g. against excess buoyancy)
        "swinging",  # pitch rate above the steadiness bound
        "held",  # within tolerance: the ordered depth is held
        "brief",  # pinned only 80% of the window
        "short",  # the record does not cover a window
    ],
)
def test_wrong_branch_rejects_near_misses(change: str):
    t, e, pitch, rate, stern = _wrong_branch_episode()
    window = t >= t[-1] - HOLD_WINDOW_S
    if change == "chattering":
        stern = np.where(np.arange(t.size) % 2 == 0, LIMIT, -LIMIT)
    elif change == "level":
        pitch = np.full_like(t, 0.5 * NON_LEVEL_PITCH_RAD)
    elif change == "swinging":
        rate = np.where(window, 1.5 * STEADY_PITCH_RATE_RADPS * np.sin(t), 0.0)
    elif change == "held":
        e = np.zeros_like(t)
    elif change == "brief":
        idx = np.flatnonzero(window)
        stern = stern.copy()
        stern[idx[-int(0.2 * idx.size) :]] = 0.5 * LIMIT
    elif change == "short":
        keep = t <= HOLD_WINDOW_S - 10.0
        t, e, pitch, rate, stern = t[keep], e[keep], pitch[keep], rate[keep], stern[keep]
    m = _metrics(t, e, pitch=pitch, rate=rate, stern=stern)
    assert not m.wrong_branch
    assert m.outcome == ("success" if change == "held" else m.outcome)


def test_steady_offset_needs_a_settled_depth():
    t = _time(600.0)
    pitch = np.full_like(t, math.radians(3.0))
    settled = _metrics(t, np.full_like(t, 2.0), pitch=pitch, stern=np.full_like(t, 0.1))
    assert settled.steady_offset and settled.outcome == "steady_offset"
    drifting = _metrics(t, 2.0 + 0.01 * t, pitch=pitch, stern=np.full_like(t, 0.1))  # 0.6 m per window
    assert not drifting.steady_offset and drifting.outcome == "unsettled"


def test_a_slow_drift_is_not_a_steady_offset():
    """sac on LowSpeed, seed 10012: 1.04 to 0.87 m over the final 60 s, still converging, was labelled
    a steady offset (the ends 0.16 m apart, under the former 0.25 m); a zero-mean swing about a
    settled offset (0.1 m, waves) is still one."""
    t = _time(600.0)
    pitch, stern = np.full_like(t, math.radians(3.0)), np.full_like(t, 0.1)
    converging = _metrics(t, 1.04 - 0.0028 * (t - (t[-1] - HOLD_WINDOW_S)), pitch=pitch, stern=stern)
    assert not converging.steady_offset and converging.outcome == "unsettled"
    swinging = _metrics(t, 1.0 + 0.1 * np.sin(2 * math.pi * t / 10.0), pitch=pitch, stern=stern)
    assert swinging.steady_offset and swinging.outcome == "steady_offset"


def test_outcomes_are_the_documented_ones():
    t = _time(300.0)
    assert _metrics(t, np.zeros_like(t)).outcome in OUTCOMES
    assert OUTCOMES[0] == "success"


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"time_s": [0.0, 1.0, 1.0]}, "strictly increasing"),
        ({"time_s": [0.0]}, "at least 2"),
        ({"depth_error_m": [0.0, 1.0]}, "must have 3"),
        ({"pitch_rad": [0.0, math.nan, 0.0]}, "NaN"),
        ({"plane_limit_rad": 0.0}, "plane_limit_rad"),
    ],
)
def test_bad_input_is_a_clear_error(kwargs, match):
    args = {
        "time_s": [0.0, 1.0, 2.0],
        "depth_error_m": [0.0] * 3,
        "pitch_rad": [0.0] * 3,
        "pitch_rate_radps": [0.0] * 3,
        "stern_plane_rad": [0.0] * 3,
        "bow_plane_rad": [0.0] * 3,
        "termination_reason": "",
        "plane_limit_rad": LIMIT,
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        episode_metrics(**args)


@pytest.mark.parametrize("case", ["settled", "within", "wrong_branch", "steady_offset", "late"])
def test_a_froude_scaled_episode_is_judged_as_the_models(case) -> None:  # type: ignore[no-untyped-def]
    """length_ratio: an episode of a boat lambda times larger, in scaled units (times x sqrt(lambda), depths
    x lambda, rates x 1/sqrt(lambda)), gets the model episode's outcome."""
    t = _time(300.0)
    e = {
        "settled": 2.0 * np.exp(-t / 20.0),
        "within": np.full(t.size, 0.3),
        "wrong_branch": 0.8 + 0.004 * t,
        "steady_offset": np.full(t.size, 0.8),
        "late": np.where(t < 270.0, 2.0, 0.1),
    }[case]
    pitch = np.full(t.size, 0.05) if case == "wrong_branch" else np.zeros(t.size)
    stern = np.full(t.size, LIMIT) if case == "wrong_branch" else np.zeros(t.size)
    rate = np.full(t.size, 0.5 * STEADY_PITCH_RATE_RADPS)
    ratio = 24.0
    root = math.sqrt(ratio)
    model = episode_metrics(t, e, pitch, rate, stern, stern * 0, termination_reason="", plane_limit_rad=LIMIT)
    full = episode_metrics(
        t * root,
        e * ratio,
        pitch,
        rate / root,
        stern,
        stern * 0,
        termination_reason="",
        plane_limit_rad=LIMIT,
        length_ratio=ratio,
    )
    expected = {"settled": "success", "within": "success", "late": "unsettled"}.get(case, case)
    assert full.outcome == model.outcome == expected
    if case == "within":  # 7.2 m off at full scale: within the scaled tolerance, not within 0.5 m
        unscaled = episode_metrics(
            t * root,
            e * ratio,
            pitch,
            rate / root,
            stern,
            stern * 0,
            termination_reason="",
            plane_limit_rad=LIMIT,
        )
        assert unscaled.outcome == "steady_offset"


def test_regulation_accuracy_is_the_time_in_the_band_after_the_approach():
    """300 s, 1 m off until 100 s, then 5 cm off: the window is the steps starting at 60 s or later (240 s),
    each in the band when the sample that ends it is: the steps ending at 100 s to 300 s, 200.5 s."""
    t = _time(300.0)
    e = np.where(t < 100.0, 1.0, 0.5 * REGULATION_BAND_M)
    assert APPROACH_S == 60.0
    assert _metrics(t, e).regulation_accuracy == pytest.approx(200.5 / 240.0)
    assert _metrics(t, np.full_like(t, REGULATION_BAND_M)).regulation_accuracy == 1.0  # the band is inclusive
    assert _metrics(t, np.where(t < 59.0, 2.0, 0.0)).regulation_accuracy == 1.0  # the approach is free
    assert _metrics(t, np.full_like(t, 0.11)).regulation_accuracy == 0.0


def test_a_terminated_episode_is_charged_its_missing_time_outside_the_band():
    t = _time(150.0)
    m = _metrics(t, np.zeros_like(t), reason="broached", duration=300.0)
    assert m.regulation_accuracy == pytest.approx(90.0 / 240.0)  # 90 s held of a 240 s window
    assert _metrics(t, np.zeros_like(t), reason="broached").regulation_accuracy == 1.0  # no schedule given
    short = _time(50.0)  # ended before the window opened
    assert _metrics(short, np.zeros_like(short), reason="broached", duration=300.0).regulation_accuracy == 0.0
    assert _metrics(short, np.zeros_like(short)).regulation_accuracy == 0.0  # no window at all


def test_the_regulation_window_restarts_at_each_new_depth_order():
    t = _time(300.0)
    start = t[:-1]
    once = regulation_window(t)
    assert np.array_equal(once, start >= APPROACH_S)
    twice = regulation_window(t, order_times_s=[0.0, 100.0])
    assert np.array_equal(twice, (start >= 60.0) & (start < 100.0) | (start >= 160.0))


@pytest.mark.parametrize(
    ("stern", "bow", "plane_count", "effort"),
    [
        (0.2, 0.0, 2, math.sqrt(0.2**2 / 2) / LIMIT),  # stern planes only, on a boat with bow planes
        (0.2, 0.0, 1, 0.2 / LIMIT),  # a stern-only boat
        (0.2, -0.2, 2, 0.2 / LIMIT),  # both planes at 0.2 rad
        (LIMIT, LIMIT, 2, 1.0),  # both at their limit
        (0.0, 0.0, 2, 0.0),
    ],
)
def test_plane_effort_is_the_rms_angle_per_plane_over_the_limit(stern, bow, plane_count, effort):
    t = _time(200.0)
    m = _metrics(
        t, np.zeros_like(t), stern=np.full_like(t, stern), bow=np.full_like(t, bow), plane_count=plane_count
    )
    assert m.plane_effort == pytest.approx(effort, rel=1e-12)
    assert m.plane_effort == pytest.approx(m.plane_rms_rad / (LIMIT * math.sqrt(plane_count)), rel=1e-12)
    assert m.quality == pytest.approx(0.8 * 1.0 + 0.2 * (1 - effort**2), rel=1e-12)


def test_quality_weighs_accuracy_four_to_one_against_plane_motion():
    assert episode_quality(1.0, 0.0) == 1.0 and episode_quality(0.0, 1.0) == 0.0
    assert episode_quality(0.5, 0.5) == pytest.approx(0.8 * 0.5 + 0.2 * 0.75)
    np.testing.assert_allclose(episode_quality([1.0, 0.0], [0.0, 0.0]), [1.0, 0.2])


@pytest.mark.parametrize(
    ("reason", "pitch_limit", "safety_event"),
    [
        ("", False, False),
        ("broached", False, True),
        ("pitch_limit", True, True),
        ("left_depth_band", False, False),
    ],
)
def test_safety_events_are_broaching_and_the_pitch_limit(reason, pitch_limit, safety_event):
    t = _time(100.0)
    m = _metrics(t, np.zeros_like(t), reason=reason)
    assert (m.pitch_limit, m.safety_event) == (pitch_limit, safety_event)


def test_the_regulation_band_and_window_are_froude_scaled():
    """A boat 24 times larger, in scaled units: the band is 2.4 m and the approach 294 s."""
    ratio, root = 24.0, math.sqrt(24.0)
    t = _time(300.0)
    e = np.where(t < 100.0, 1.0, 0.05)
    model = _metrics(t, e)
    full = _metrics(t * root, e * ratio, length_ratio=ratio)
    assert full.regulation_accuracy == pytest.approx(model.regulation_accuracy, rel=1e-12)
    assert _metrics(t * root, e * ratio).regulation_accuracy < model.regulation_accuracy  # unscaled: worse
