"""Per-episode metrics of a depth controller, computed from a recorded trajectory.

Every metric is a pure function of the sampled signals (time, depth error, pitch, pitch rate,
plane angles), the episode's termination reason and the plane limit; every tolerance is a named
constant below with the reasoning behind its value. The harness records the environment's true
state (``info``), not the noisy observation, so the metrics judge where the boat actually was.

Sampling convention: sample ``k`` is the state at ``time_s[k]`` (sample 0 is the reset). The
plane angles of sample ``k >= 1`` are the angles applied during the step that ended at
``time_s[k]`` (zero-order hold), so time fractions and RMS values of the planes weight sample
``k`` by ``time_s[k] - time_s[k-1]`` and ignore sample 0 (the planes before the first command).
Integrals of the state use the trapezoidal rule.

Windows (on SUBOFF; every length and time below is Froude-scaled on a vehicle of another size):

- the **hold window**: the final :data:`HOLD_WINDOW_S` (60 s) of the record, on which success and the
  wrong branch are judged;
- the **regulation window**: the control periods that start at least :data:`APPROACH_S` (60 s) after
  the depth order in force was given (today the order is given once, at the reset), up to the
  scheduled end of the episode; regulation accuracy is judged on it.

The metrics a score is built from (:mod:`subenv.evaluation.score`): success; the regulation accuracy
``a`` (time fraction of the regulation window within :data:`REGULATION_BAND_M`); the plane effort ``e``
(RMS plane angle per plane over the limit); and the quality ``q = 0.8 a + 0.2 (1 - e^2)`` of
:func:`episode_quality`. The others (IAE, settling, overshoot, peak pitch, time saturated, safety
events) are what a control engineer reads beside them.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import ArrayLike

from subenv import _validation as check
from subenv.vehicles.scaling import froude_factor

__all__ = [
    "APPROACH_S",
    "DEPTH_TOLERANCE_M",
    "HOLD_WINDOW_S",
    "NON_LEVEL_PITCH_RAD",
    "OUTCOMES",
    "PINNED_FRACTION",
    "QUALITY_ACCURACY_WEIGHT",
    "QUALITY_EFFORT_WEIGHT",
    "REGULATION_BAND_M",
    "SAFETY_EVENTS",
    "SATURATION_LEVEL",
    "STEADY_DEPTH_CHANGE_M",
    "STEADY_PITCH_RATE_RADPS",
    "EpisodeMetrics",
    "episode_metrics",
    "episode_quality",
    "episode_success",
    "regulation_window",
]

DEPTH_TOLERANCE_M: Final = 0.5
"""|depth error| within which the ordered depth counts as reached [m].

About one hull diameter of SUBOFF (0.508 m, for a 4.26 m hull): a boat within its own diameter
of the ordered depth is where it was sent. It is 10 times the sensor noise of the ``Randomized``
scenario (0.05 m), so noise alone never breaks it, and a quarter of the initial offsets the
scenarios draw (up to 2 m), so an episode that never corrects its start does not pass.
"""

HOLD_WINDOW_S: Final = 60.0
"""Length of the final stretch of an episode over which success and the wrong branch are judged [s].

Long against the closed-loop time constants of the thesis design (poles at -0.3 to -0.33 1/s,
about 3 s; the baselines settle within 20-60 s) and long enough that the slowest drift of a
pitched, plane-saturated equilibrium (0.014-0.026 m/s at 0.2-0.9 u_cr, from
``subenv.analysis.equilibria``) covers more than the 0.5 m tolerance within it, yet short enough
to fit after the transient of every scenario (episodes last 200-600 s; ``SpeedTransient``
reaches its final speed by 330 s at the latest).
"""

SATURATION_LEVEL: Final = 0.99
"""A plane counts as saturated at or above this fraction of its limit.

Exactly at the limit in the environment (the applied angle is clipped), 1% below it to allow for
a rate-limited plane creeping towards the limit and for float rounding.
"""

PINNED_FRACTION: Final = 0.9
"""On the wrong branch, a plane is at one and the same limit more than this fraction of the window.

The thesis's failure mode (Riedel 1993 Ch. III.A; eqs 4.40-4.42) is a steady state with the
planes pinned at one limit. 90% rather than 100% admits a brief excursion off the limit (a
disturbance, the end of the approach to the equilibrium); "one and the same" limit excludes a
controller chattering between +limit and -limit, which is saturated but not pinned.
"""

NON_LEVEL_PITCH_RAD: Final = math.radians(0.5)
"""|pitch| above which a steady state is non-level [rad] (0.5 deg).

The saturated pitched equilibria of SUBOFF lie at 0.72 deg (0.3 u_cr, the slowest speed of
``LowSpeed``) to 6.5 deg (0.9 u_cr) with the thesis's gain, and higher with a ballast offset
(``subenv.analysis.equilibria``; 0.32 deg only at 0.2 u_cr, below every scenario). 0.5 deg sits
below all of them, and excludes a level boat whose planes are pinned for another reason (too
little plane authority, e.g. against excess buoyancy), which is a different failure.
"""

STEADY_PITCH_RATE_RADPS: Final = math.radians(0.2)
"""|pitch rate| at or below which the pitch counts as steady [rad/s] (0.2 deg/s).

At a pitched equilibrium q is zero. Measured on the wrong-branch windows of the thesis
controller and the baselines (40 episodes per scenario): max |q| below 0.05 deg/s (mostly below
0.001) without a random disturbance, up to 0.16 deg/s under the ``Randomized`` scenario's 2 N
heave-force disturbance. A boat still swinging towards the pitch limit or oscillating about level
moves faster than this at some point of the window.
"""

STEADY_DEPTH_CHANGE_M: Final = 0.05
"""|drift of the depth error| over the window at or below which the depth counts as steady [m].

The drift is the slope of the least-squares line through the depth error over the window times the
window's length: a boat still converging or diverging slowly drifts, however its error ends, and a
zero-mean oscillation (waves, a random disturbance) does not. A tenth of the tolerance in 60 s
(0.0008 m/s) is an order of magnitude slower than the drift of the saturated equilibria (0.014-0.026
m/s at 0.2-0.9 u_cr), so a boat that drifts less than this has settled. The former test, the change
between the window's ends against 0.25 m, called settled a boat converging at 0.003 m/s (``sac`` on
``LowSpeed``, seed 10012: 1.04 to 0.87 m in the final 60 s). Used by ``steady_offset`` only.
"""


REGULATION_BAND_M: Final = 0.1
"""|depth error| within which the depth counts as regulated [m] (regulation accuracy).

A fifth of the success tolerance (:data:`DEPTH_TOLERANCE_M`, about a fifth of SUBOFF's hull diameter):
success asks whether the boat is where it was sent, this band how tightly it holds there. It is twice
the ``Randomized`` scenario's depth-sensor noise (0.05 m), so a controller that filters its measurement
can hold it (the metrics judge the true depth), and the best baselines do: ``mpc`` and
``reversal_aware`` enter it within a minute of the reset (the median, in every scenario of the default
suite: the note of :data:`APPROACH_S`), while a controller without integral action settles outside it with a
ballast offset.
"""

APPROACH_S: Final = 60.0
"""Time after a depth order before the regulation window starts [s].

The approach to the ordered depth (up to 2 m away at the reset) is not regulation: the IAE and the
settling time measure it. Measured on the default suite (20 episodes per scenario, seeds 10000-10019),
the first entry into the 0.1 m band takes ``mpc`` 12-49 s (the median per scenario; 90th percentile
16-84 s, the slowest on LowSpeed) and ``reversal_aware`` 11-35 s (90th percentile 17-68 s); ``lqr`` and
``scheduled`` take 10-75 s. 60 s lets every baseline's typical approach end before the window starts,
so that the window judges holding, and leaves 140 s of the shortest episodes (Nominal's 200 s) to judge
it on. A controller that is still approaching after 60 s is charged for it, as it should be.
"""

QUALITY_ACCURACY_WEIGHT: Final = 0.8
QUALITY_EFFORT_WEIGHT: Final = 0.2
"""The weights of :func:`episode_quality`: 4/5 on the task (regulation accuracy), 1/5 on small plane
motion, DeepMind Control Suite's split (``dm_control/suite/cartpole.py``: ``small_control = (4 +
small_control) / 5``, the control term quadratic in the action, 1 - u^2, as here 1 - e^2)."""

SAFETY_EVENTS: Final = ("broached", "pitch_limit")
"""The termination reasons that are safety events: the hull broke the surface, or the pitch passed the
environment's limit. (Leaving the depth band and a diverged state end an episode too, but are failures
of control, not hazards to the boat.)"""


OUTCOMES: Final = (
    "success",
    "wrong_branch",
    "steady_offset",
    "broached",
    "left_depth_band",
    "pitch_limit",
    "diverged",
    "unsettled",
)
"""The values of :attr:`EpisodeMetrics.outcome`, in order of precedence.

Every episode has exactly one outcome: the first of these that applies.

1. ``success``: see :attr:`EpisodeMetrics.success`.
2. ``wrong_branch``: the final hold window shows the thesis's failure mode (a steady pitch with a
   plane pinned, off depth), whatever ended the episode. It comes before the termination reason
   because it explains it: a boat on the wrong branch drifts off depth until it broaches or leaves
   the depth band, so such an episode counts as ``wrong_branch``, not ``broached``.
3. ``steady_offset``: ran to the time limit settled off depth with the planes free.
4. The environment's termination reason: ``broached``, ``left_depth_band``, ``pitch_limit``,
   ``diverged`` (at most one per episode).
5. ``unsettled``: ran to the time limit off depth, still moving.

The boolean fields :attr:`EpisodeMetrics.broached` and :attr:`EpisodeMetrics.terminated` say what
ended the episode and may overlap an outcome (a wrong-branch episode can have ``broached``
true); the tables count outcomes (:func:`subenv.evaluation.results.outcome_counts`), so their
failure counts add up to the failures.
"""


@dataclass(frozen=True)
class EpisodeMetrics:
    """The metrics of one episode; see :func:`episode_metrics` for the definitions.

    Attributes
    ----------
    outcome : str
        One of :data:`OUTCOMES`, the first that applies in its order of precedence:
        ``"success"``; else ``"wrong_branch"`` or ``"steady_offset"`` if the episode ended so
        (these explain a later termination, so they take precedence); else the termination
        reason; else ``"unsettled"`` (ran to the time limit off depth, still moving).
    success : bool
        Not terminated, and |depth error| <= tolerance over the whole final hold window.
    terminated : bool
        The environment ended the episode (any termination reason).
    termination_reason : str
        The environment's reason ("" when the episode ran to its time limit).
    broached : bool
        Terminated by broaching (the hull broke the surface), whatever the outcome (a
        wrong-branch episode that ends by broaching has ``outcome == "wrong_branch"``).
    wrong_branch : bool
        Ended at the thesis's failure mode: a steady, non-level pitch with a plane pinned at one
        limit, off the ordered depth.
    steady_offset : bool
        Ran to the time limit settled off the ordered depth with the planes free (steady pitch
        and depth): a depth-holding non-level equilibrium (eq. 4.4) or a steady-state error.
    iae_m_s : float
        Integrated absolute depth error [m s].
    settling_time_s : float
        Time from the reset after which |depth error| stays within the tolerance [s]; inf if the
        episode ends outside it or terminated.
    overshoot_m : float
        Largest excursion past the ordered depth on the side opposite the initial error [m].
    peak_pitch_deg : float
        Largest |pitch| [deg].
    plane_rms_rad : float
        Root mean square of the applied plane angles (stern and bow together) [rad].
    saturated_fraction : float
        Fraction of the time with any plane at its limit (either sign).
    hold_max_abs_error_m : float
        Largest |depth error| over the final hold window [m] (what ``success`` compares with the
        tolerance).
    final_abs_error_m : float
        |depth error| at the last sample [m].
    duration_s : float
        Recorded length of the episode [s].
    regulation_accuracy : float
        Time fraction of the regulation window with |depth error| <= :data:`REGULATION_BAND_M`, in
        [0, 1]; the time a terminated episode did not run counts as outside.
    plane_effort : float
        RMS plane angle per plane of the vehicle over the plane limit, in [0, 1]: 0 with the planes
        still, 1 with every plane held at its limit.
    pitch_limit : bool
        Terminated by the pitch limit.
    safety_event : bool
        Terminated by a safety event (:data:`SAFETY_EVENTS`: broached or the pitch limit).
    quality : float
        :func:`episode_quality` of the regulation accuracy and the plane effort, in [0, 1]. Defined
        for every episode; the score reads it on the won ones.
    """

    outcome: str
    success: bool
    terminated: bool
    termination_reason: str
    broached: bool
    wrong_branch: bool
    steady_offset: bool
    iae_m_s: float
    settling_time_s: float
    overshoot_m: float
    peak_pitch_deg: float
    plane_rms_rad: float
    saturated_fraction: float
    hold_max_abs_error_m: float
    final_abs_error_m: float
    duration_s: float
    regulation_accuracy: float
    plane_effort: float
    pitch_limit: bool
    safety_event: bool
    quality: float

    def as_dict(self) -> dict[str, Any]:
        """The fields as a flat dict (for tables)."""
        return asdict(self)


def _vector(name: str, value: ArrayLike, n: int | None) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim != 1:
        raise ValueError(f"{name} has shape {a.shape}: must be one-dimensional")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} has {a.shape[0]} samples: must have {n} (as many as time_s)")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} holds NaN or infinite values")
    return a


def _slack(end_s: float) -> float:
    """A small slack that absorbs float sums of dt in the windows' comparisons."""
    return 1e-9 * max(1.0, abs(end_s))


def _hold_window(start_s: float, end_s: float, hold_window_s: float) -> tuple[float, bool]:
    """The start of the hold window of an episode sampled from ``start_s`` to ``end_s`` (the samples
    at or after it are in the window), and whether the episode covers the window."""
    slack = _slack(end_s)
    window_start = end_s - hold_window_s - slack
    return window_start, start_s <= window_start + 2 * slack


def episode_success(
    *,
    terminated: bool,
    start_s: float,
    end_s: float,
    last_outside_s: float,
    hold_window_s: float = HOLD_WINDOW_S,
) -> bool:
    """Whether an episode succeeded: :attr:`EpisodeMetrics.success`, from what a running episode can keep.

    :func:`episode_metrics` calls this with the whole record; a training callback that sees one step
    at a time (``subenv_agents.curriculum``) keeps only the time of the last sample off depth.

    Parameters
    ----------
    terminated : bool
        The episode was terminated (broached, left the depth band, ...) rather than run to its
        time limit.
    start_s, end_s : float
        Times of the episode's first (the reset) and last samples [s].
    last_outside_s : float
        Time of the last sample with |depth error| not within the depth tolerance
        (:data:`DEPTH_TOLERANCE_M`; a nan error counts as outside) [s]; ``-inf`` if none was.
    hold_window_s : float
        See :data:`HOLD_WINDOW_S`.

    Returns
    -------
    bool
        Not terminated, the record covers the final ``hold_window_s``, and no sample of that window
        (its first included) is off depth.
    """
    window_start, covers_window = _hold_window(start_s, end_s, hold_window_s)
    return (not terminated) and covers_window and last_outside_s < window_start


def episode_quality(regulation_accuracy: ArrayLike, plane_effort: ArrayLike) -> np.ndarray:
    """The quality q = 0.8 a + 0.2 (1 - e^2): how well a won episode held depth, in [0, 1] (vectorised).

    ``a`` is the regulation accuracy and ``e`` the plane effort (:class:`EpisodeMetrics`). The task
    takes 4/5 of the weight and small plane motion 1/5 (:data:`QUALITY_ACCURACY_WEIGHT`), as the
    DeepMind Control Suite weighs them; the control term is quadratic, as DMC's ``small_control``
    (``rewards.tolerance(u, margin=1, value_at_margin=0, sigmoid="quadratic")`` = 1 - u^2), so
    1 - e^2 is the time mean of 1 - (plane / limit)^2 per plane. The terms are added (DMC multiplies
    the task reward by ``(4 + small_control) / 5``) so that the mean quality of a set of episodes is
    0.8 times their mean accuracy plus 0.2 times their mean 1 - e^2, each readable in the tables.

    References
    ----------
    Tassa, Y. et al. (2018). DeepMind Control Suite. arXiv:1801.00690 (Sec. 4: rewards in [0, 1];
    ``dm_control/suite/cartpole.py``, ``_get_reward``).
    """
    a = np.asarray(regulation_accuracy, dtype=float)
    e = np.asarray(plane_effort, dtype=float)
    return QUALITY_ACCURACY_WEIGHT * a + QUALITY_EFFORT_WEIGHT * (1.0 - e * e)


def regulation_window(
    time_s: np.ndarray, approach_s: float = APPROACH_S, order_times_s: ArrayLike | None = None
) -> np.ndarray:
    """Which control periods are in the regulation window: a boolean per step (``time_s[k - 1]`` to
    ``time_s[k]``, k = 1 .. n - 1), True when the step starts at least ``approach_s`` after the depth
    order in force then was given.

    Parameters
    ----------
    time_s : ndarray, shape (n,)
        Sample times [s], increasing.
    approach_s : float
        See :data:`APPROACH_S` (already Froude-scaled, if the episode is).
    order_times_s : array_like, optional
        Times at which a depth order was given [s], increasing, the first at or before ``time_s[0]``;
        default: once, at the reset (``time_s[0]``). An episode whose order changes restarts the
        window at each change.
    """
    start = time_s[:-1]
    if order_times_s is None:
        given: np.ndarray | float = float(time_s[0])
    else:
        orders = np.atleast_1d(np.asarray(order_times_s, dtype=float))
        given = orders[np.clip(np.searchsorted(orders, start, side="right") - 1, 0, None)]
    result: np.ndarray = start - given >= approach_s - _slack(float(time_s[-1]))
    return result


def _regulation_accuracy(
    t: np.ndarray,
    dts: np.ndarray,
    abs_e: np.ndarray,
    band_m: float,
    approach_s: float,
    scheduled_end_s: float,
) -> float:
    """Time fraction of the regulation window within ``band_m``: each step counts as within when the
    sample that ends it is (zero-order hold, as the planes); the window runs to ``scheduled_end_s``,
    and the part of it after the record's end (a terminated episode) counts as outside."""
    window = regulation_window(t, approach_s)
    held = float(np.dot(dts, window & (abs_e[1:] <= band_m)))
    recorded = float(np.dot(dts, window))
    window_start = float(t[0]) + approach_s
    missing = max(0.0, scheduled_end_s - max(float(t[-1]), window_start))
    total = recorded + missing
    return held / total if total > 0 else 0.0


def _plane_effort(mean_square: float, limit: float, count: int) -> float:
    """sqrt(``mean_square`` / count) / limit, at most 1: ``mean_square`` the time mean of the sum of the
    squared plane angles [rad^2]."""
    return min(1.0, math.sqrt(mean_square / count) / limit)


def _overshoot(e: np.ndarray, abs_e: np.ndarray) -> float:
    """The largest excursion past the ordered depth on the side opposite the initial error."""
    e0 = e[0]
    if e0 > 0:
        return max(0.0, float(-e.min()))
    if e0 < 0:
        return max(0.0, float(e.max()))
    return float(abs_e.max())


def _settling_time(t: np.ndarray, within: np.ndarray, terminated: bool) -> float:
    """The time from the reset to the first sample after the last one outside the tolerance."""
    if terminated or not within[-1]:
        return math.inf
    outside = np.flatnonzero(~within)
    return 0.0 if outside.size == 0 else float(t[outside[-1] + 1] - t[0])


def _iae(
    abs_e: np.ndarray, dts: np.ndarray, terminated: bool, duration: float, scheduled: float | None
) -> float:
    """Trapezoidal integral of |e|; a terminated episode is charged its final |e| until ``scheduled``."""
    iae = float(np.sum(0.5 * (abs_e[1:] + abs_e[:-1]) * dts))
    if terminated and scheduled is not None and scheduled > duration:
        iae += float(abs_e[-1]) * (scheduled - duration)
    return iae


def _steady_states(
    t: np.ndarray,
    dts: np.ndarray,
    e: np.ndarray,
    theta: np.ndarray,
    q: np.ndarray,
    planes: np.ndarray,
    *,
    window_start: float,
    level: float,
    off_depth: bool,
    terminated: bool,
    steady_rate: float,
    steady_change: float,
) -> tuple[bool, bool]:
    """(wrong_branch, steady_offset) over a hold window the record covers (the definitions of
    :func:`episode_metrics`)."""
    in_window = t >= window_start
    steps = t[:-1] >= window_start
    window_time = float(np.sum(dts[steps]))
    pinned = max(
        float(np.sum(dts[steps & (sign * planes[p] >= level)])) / window_time
        for p in (0, 1)
        for sign in (1.0, -1.0)
    )
    steady_pitch = float(np.abs(q[in_window]).max()) <= steady_rate
    wrong_branch = (
        pinned > PINNED_FRACTION
        and steady_pitch
        and float(np.abs(theta[in_window]).min()) > NON_LEVEL_PITCH_RAD
        and off_depth
    )
    t_window = t[in_window]
    slope = float(np.polyfit(t_window - t_window[0], e[in_window], 1)[0])
    steady_offset = (
        not terminated
        and not wrong_branch
        and steady_pitch
        and abs(slope) * float(t_window[-1] - t_window[0]) <= steady_change
        and off_depth
    )
    return bool(wrong_branch), bool(steady_offset)


def _outcome(success: bool, wrong_branch: bool, steady_offset: bool, termination_reason: str) -> str:
    """The first outcome of :data:`OUTCOMES` that applies."""
    if success:
        return "success"
    if wrong_branch:
        return "wrong_branch"
    if steady_offset:
        return "steady_offset"
    return termination_reason or "unsettled"


def episode_metrics(
    time_s: ArrayLike,
    depth_error_m: ArrayLike,
    pitch_rad: ArrayLike,
    pitch_rate_radps: ArrayLike,
    stern_plane_rad: ArrayLike,
    bow_plane_rad: ArrayLike,
    *,
    termination_reason: str,
    plane_limit_rad: float,
    episode_duration_s: float | None = None,
    depth_tolerance_m: float = DEPTH_TOLERANCE_M,
    hold_window_s: float = HOLD_WINDOW_S,
    length_ratio: float = 1.0,
    plane_count: int = 2,
) -> EpisodeMetrics:
    """Compute the :class:`EpisodeMetrics` of one recorded episode.

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Sample times [s], strictly increasing, n >= 2; ``time_s[0]`` is the reset.
    depth_error_m : array_like, shape (n,)
        Depth minus ordered depth [m] (positive: too deep).
    pitch_rad, pitch_rate_radps : array_like, shape (n,)
        Pitch [rad] (nose up positive) and pitch rate [rad/s].
    stern_plane_rad, bow_plane_rad : array_like, shape (n,)
        Applied plane angles [rad]; sample k is the angle held during the step ending at
        ``time_s[k]`` (sample 0 is not used).
    termination_reason : str
        The environment's ``info["termination_reason"]`` at the last step; "" if the episode
        was truncated (ran to its time limit).
    plane_limit_rad : float
        The planes' saturation angle [rad].
    episode_duration_s : float, optional
        The scheduled length of the episode [s]. If given and the episode terminated early, the
        IAE charges the final |depth error| for the rest of that time, so that ending an episode
        early (broaching, leaving the depth band) never lowers it, and the regulation window runs to
        it (the time not run counts as outside the band).
    depth_tolerance_m : float
        See :data:`DEPTH_TOLERANCE_M`.
    hold_window_s : float
        See :data:`HOLD_WINDOW_S`.
    length_ratio : float
        lambda of an episode Froude-scaled to a vehicle of another size
        (:attr:`subenv.envs.config.DivePlaneConfig.length_ratio`): the tolerances above, the
        regulation band and window, and the steadiness thresholds are the reference vehicle's
        (SUBOFF's) and are scaled with it, lengths x lambda, times x sqrt(lambda), rates x
        1/sqrt(lambda). 1 on SUBOFF.
    plane_count : int
        The planes the vehicle has (2: stern and bow; 1: stern planes alone, whose bow angles are
        zero): the plane effort is per plane of the vehicle.

    Returns
    -------
    EpisodeMetrics
        With these definitions (W: the hold window, the samples with t >= t_end - W; tol: the
        depth tolerance; "steady": max |q| over W <= 0.2 deg/s; R: the regulation window of
        :func:`regulation_window`, the steps starting at least :data:`APPROACH_S` after the order):

        - ``success``: not terminated, the record covers at least W, and |e| <= tol at every
          sample of W (:func:`episode_success`).
        - ``settling_time_s``: t_k - t_0 for the first sample k from which |e| <= tol at every
          later sample; 0 if always within; inf if the last sample is outside or the episode
          terminated.
        - ``overshoot_m``: with e_0 > 0 (too deep) the largest -e, with e_0 < 0 the largest e,
          floored at 0; with e_0 == 0 every excursion counts (max |e|).
        - ``iae_m_s``: trapezoidal integral of |e| over the record (extended as described for
          ``episode_duration_s``).
        - ``peak_pitch_deg``: max |theta|.
        - ``plane_rms_rad``: sqrt of the time mean of stern^2 + bow^2.
        - ``saturated_fraction``: time fraction with max(|stern|, |bow|) >= 0.99 limit.
        - ``broached``, ``pitch_limit``: the termination reason is that; ``safety_event``: either.
        - ``regulation_accuracy`` (a): the time fraction of R with |e| <= 0.1 m (the state at the
          end of each step), R running to the scheduled end (a terminated episode's missing time
          counts as outside); 0 if R is empty (an episode shorter than the approach).
        - ``plane_effort`` (e): sqrt(time mean of (stern^2 + bow^2) / plane_count) / limit, that is
          ``plane_rms_rad / (limit sqrt(plane_count))``: the RMS angle per plane of the vehicle as a
          fraction of the limit. With ``control="dual"`` the bow planes move as the allocation alpha
          moves them (not at all with alpha = 0) and count as they move; with ``"independent"`` both
          are the controller's. Every plane the vehicle has is in the mean, so a controller that
          leaves its bow planes still is charged for the stern planes only, not credited for an idle
          plane twice; a stern-only vehicle (plane_count = 1) has its stern planes alone.
        - ``quality``: :func:`episode_quality` (a, e).
        - ``wrong_branch``: the record covers W (whatever ended it) and over W: one plane is at
          one and the same limit (>= 0.99 of it, same sign) more than 90% of the time, the pitch
          is steady, |theta| > 0.5 deg at every sample, and max |e| > tol. This is the
          equilibrium the thesis's controller reaches below the critical speed: level flight
          unstable, the boat steady at a pitch with its planes pinned, drifting off the ordered
          depth (often until it broaches or leaves the depth band, so a terminated episode can
          be on the wrong branch).
        - ``steady_offset``: not terminated, not ``wrong_branch``, and over W the pitch is
          steady, e drifts by at most 0.05 m (the slope of its least-squares line over W times
          the length of W), and max |e| > tol: the boat has settled off
          the ordered depth with its planes free. With proportional depth feedback below and
          near u_cr this is the depth-holding pitched equilibrium of eq. 4.4 (the depth error
          supplies the plane angle the pitched trim needs); with a ballast offset and no integral
          action it is the steady-state error. The trajectory alone cannot tell the two apart.

    References
    ----------
    Riedel, J. S. (1993). Pitchfork bifurcations and dive plane reversal of submarines at low
    speeds. Naval Postgraduate School (Ch. III.A: the pitched, plane-saturated equilibria;
    eqs 4.3-4.4, 4.40-4.42: steady states with free and saturated planes).
    """
    t = _vector("time_s", time_s, None)
    n = t.shape[0]
    if n < 2:
        raise ValueError(f"time_s has {n} samples: an episode needs at least 2 (the reset and one step)")
    dts = np.diff(t)
    if not np.all(dts > 0):
        raise ValueError("time_s must be strictly increasing")
    e = _vector("depth_error_m", depth_error_m, n)
    theta = _vector("pitch_rad", pitch_rad, n)
    q = _vector("pitch_rate_radps", pitch_rate_radps, n)
    stern = _vector("stern_plane_rad", stern_plane_rad, n)
    bow = _vector("bow_plane_rad", bow_plane_rad, n)
    check.positive("plane_limit_rad", plane_limit_rad)
    check.positive("depth_tolerance_m", depth_tolerance_m)
    check.positive("hold_window_s", hold_window_s)
    check.integer("plane_count", plane_count, 1, 2)
    length, time, rate = (froude_factor(kind, length_ratio) for kind in ("length", "time", "rate"))
    depth_tolerance_m, hold_window_s = depth_tolerance_m * length, hold_window_s * time
    steady_rate, steady_change = STEADY_PITCH_RATE_RADPS * rate, STEADY_DEPTH_CHANGE_M * length
    if episode_duration_s is not None:
        check.positive("episode_duration_s", episode_duration_s)

    terminated = termination_reason != ""
    abs_e = np.abs(e)
    duration = float(t[-1] - t[0])
    within = abs_e <= depth_tolerance_m

    start_s, end_s = float(t[0]), float(t[-1])
    window_start, covers_window = _hold_window(start_s, end_s, hold_window_s)
    hold_max = float(abs_e[t >= window_start].max())
    outside = np.flatnonzero(~within)
    success = episode_success(
        terminated=terminated,
        start_s=start_s,
        end_s=end_s,
        last_outside_s=float(t[outside[-1]]) if outside.size else -math.inf,
        hold_window_s=hold_window_s,
    )

    # Planes: zero-order hold, sample k (k >= 1) weighted by the step that ended at t_k.
    level = SATURATION_LEVEL * plane_limit_rad
    planes = np.stack([stern[1:], bow[1:]])  # (2, n - 1)
    saturated = (np.abs(planes) >= level).any(axis=0)
    wrong_branch = steady_offset = False
    if covers_window:
        wrong_branch, steady_offset = _steady_states(
            t,
            dts,
            e,
            theta,
            q,
            planes,
            window_start=window_start,
            level=level,
            off_depth=hold_max > depth_tolerance_m,
            terminated=terminated,
            steady_rate=steady_rate,
            steady_change=steady_change,
        )
    scheduled_end = start_s + (duration if episode_duration_s is None else max(duration, episode_duration_s))
    accuracy = _regulation_accuracy(
        t, dts, abs_e, REGULATION_BAND_M * length, APPROACH_S * time, scheduled_end
    )
    mean_square = float(np.sum((planes**2).sum(axis=0) * dts)) / duration
    effort = _plane_effort(mean_square, plane_limit_rad, plane_count)
    return EpisodeMetrics(
        outcome=_outcome(success, wrong_branch, steady_offset, termination_reason),
        success=success,
        terminated=terminated,
        termination_reason=termination_reason,
        broached=termination_reason == "broached",
        wrong_branch=wrong_branch,
        steady_offset=steady_offset,
        iae_m_s=_iae(abs_e, dts, terminated, duration, episode_duration_s),
        settling_time_s=_settling_time(t, within, terminated),
        overshoot_m=_overshoot(e, abs_e),
        peak_pitch_deg=math.degrees(float(np.abs(theta).max())),
        plane_rms_rad=math.sqrt(mean_square),
        saturated_fraction=float(np.sum(dts[saturated])) / duration,
        hold_max_abs_error_m=hold_max,
        final_abs_error_m=float(abs_e[-1]),
        duration_s=duration,
        regulation_accuracy=accuracy,
        plane_effort=effort,
        pitch_limit=termination_reason == "pitch_limit",
        safety_event=termination_reason in SAFETY_EVENTS,
        quality=float(episode_quality(accuracy, effort)),
    )
