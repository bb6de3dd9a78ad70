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
    "DEPTH_TOLERANCE_M",
    "HOLD_WINDOW_S",
    "NON_LEVEL_PITCH_RAD",
    "OUTCOMES",
    "PINNED_FRACTION",
    "SATURATION_LEVEL",
    "STEADY_DEPTH_CHANGE_M",
    "STEADY_PITCH_RATE_RADPS",
    "EpisodeMetrics",
    "episode_metrics",
    "episode_success",
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

STEADY_DEPTH_CHANGE_M: Final = 0.25
"""|change of depth error| over the window at or below which the depth counts as steady [m].

Half the tolerance in 60 s (0.004 m/s): an order of magnitude slower than the drift of the
saturated equilibria (0.014-0.026 m/s at 0.2-0.9 u_cr), so a boat that moves less than this has
settled, not drifted. Used by ``steady_offset`` only.
"""


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


def _hold_window(start_s: float, end_s: float, hold_window_s: float) -> tuple[float, bool]:
    """The start of the hold window of an episode sampled from ``start_s`` to ``end_s`` (the samples
    at or after it are in the window), and whether the episode covers the window."""
    # A small slack absorbs float sums of dt.
    slack = 1e-9 * max(1.0, abs(end_s))
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
        early (broaching, leaving the depth band) never lowers it.
    depth_tolerance_m : float
        See :data:`DEPTH_TOLERANCE_M`.
    hold_window_s : float
        See :data:`HOLD_WINDOW_S`.
    length_ratio : float
        lambda of an episode Froude-scaled to a vehicle of another size
        (:attr:`subenv.envs.config.DivePlaneConfig.length_ratio`): the tolerances above and the
        steadiness thresholds are the reference vehicle's (SUBOFF's) and are scaled with it, lengths
        x lambda, times x sqrt(lambda), rates x 1/sqrt(lambda). 1 on SUBOFF.

    Returns
    -------
    EpisodeMetrics
        With these definitions (W: the hold window, the samples with t >= t_end - W; tol: the
        depth tolerance; "steady": max |q| over W <= 0.2 deg/s):

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
        - ``broached``: ``termination_reason == "broached"``.
        - ``wrong_branch``: the record covers W (whatever ended it) and over W: one plane is at
          one and the same limit (>= 0.99 of it, same sign) more than 90% of the time, the pitch
          is steady, |theta| > 0.5 deg at every sample, and max |e| > tol. This is the
          equilibrium the thesis's controller reaches below the critical speed: level flight
          unstable, the boat steady at a pitch with its planes pinned, drifting off the ordered
          depth (often until it broaches or leaves the depth band, so a terminated episode can
          be on the wrong branch).
        - ``steady_offset``: not terminated, not ``wrong_branch``, and over W the pitch is
          steady, |e| changes by at most 0.25 m, and max |e| > tol: the boat has settled off
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
    length, time, rate = (froude_factor(q, length_ratio) for q in ("length", "time", "rate"))
    depth_tolerance_m, hold_window_s = depth_tolerance_m * length, hold_window_s * time
    steady_rate, steady_change = STEADY_PITCH_RATE_RADPS * rate, STEADY_DEPTH_CHANGE_M * length
    if episode_duration_s is not None:
        check.positive("episode_duration_s", episode_duration_s)

    terminated = termination_reason != ""
    abs_e = np.abs(e)
    duration = float(t[-1] - t[0])
    within = abs_e <= depth_tolerance_m

    # Hold window W: the samples of the final W seconds, and the steps (zero-order-hold intervals)
    # lying wholly in it.
    start_s, end_s = float(t[0]), float(t[-1])
    window_start, covers_window = _hold_window(start_s, end_s, hold_window_s)
    in_window = t >= window_start
    hold_max = float(abs_e[in_window].max())
    outside = np.flatnonzero(~within)
    last_outside_s = float(t[outside[-1]]) if outside.size else -math.inf
    success = episode_success(
        terminated=terminated,
        start_s=start_s,
        end_s=end_s,
        last_outside_s=last_outside_s,
        hold_window_s=hold_window_s,
    )

    # Settling: the first sample after the last one outside the tolerance.
    if terminated or not within[-1]:
        settling = math.inf
    else:
        settling = 0.0 if outside.size == 0 else float(t[outside[-1] + 1] - t[0])

    e0 = e[0]
    if e0 > 0:
        overshoot = max(0.0, float(-e.min()))
    elif e0 < 0:
        overshoot = max(0.0, float(e.max()))
    else:
        overshoot = float(abs_e.max())

    iae = float(np.sum(0.5 * (abs_e[1:] + abs_e[:-1]) * dts))
    if terminated and episode_duration_s is not None and episode_duration_s > duration:
        iae += float(abs_e[-1]) * (episode_duration_s - duration)

    # Planes: zero-order hold, sample k (k >= 1) weighted by the step that ended at t_k.
    level = SATURATION_LEVEL * plane_limit_rad
    planes = np.stack([stern[1:], bow[1:]])  # (2, n - 1)
    saturated = (np.abs(planes) >= level).any(axis=0)
    plane_rms = math.sqrt(float(np.sum((planes**2).sum(axis=0) * dts)) / duration)
    saturated_fraction = float(np.sum(dts[saturated])) / duration

    wrong_branch = steady_offset = False
    if covers_window:
        steps = t[:-1] >= window_start
        window_time = float(np.sum(dts[steps]))
        pinned = max(
            float(np.sum(dts[steps & (sign * planes[p] >= level)])) / window_time
            for p in (0, 1)
            for sign in (1.0, -1.0)
        )
        steady_pitch = float(np.abs(q[in_window]).max()) <= steady_rate
        off_depth = hold_max > depth_tolerance_m
        wrong_branch = (
            pinned > PINNED_FRACTION
            and steady_pitch
            and float(np.abs(theta[in_window]).min()) > NON_LEVEL_PITCH_RAD
            and off_depth
        )
        e_window = e[in_window]
        steady_offset = (
            not terminated
            and not wrong_branch
            and steady_pitch
            and abs(float(e_window[-1] - e_window[0])) <= steady_change
            and off_depth
        )

    if success:
        outcome = "success"
    elif wrong_branch:
        outcome = "wrong_branch"
    elif steady_offset:
        outcome = "steady_offset"
    elif terminated:
        outcome = termination_reason
    else:
        outcome = "unsettled"

    return EpisodeMetrics(
        outcome=outcome,
        success=success,
        terminated=terminated,
        termination_reason=termination_reason,
        broached=termination_reason == "broached",
        wrong_branch=bool(wrong_branch),
        steady_offset=bool(steady_offset),
        iae_m_s=iae,
        settling_time_s=settling,
        overshoot_m=overshoot,
        peak_pitch_deg=math.degrees(float(np.abs(theta).max())),
        plane_rms_rad=plane_rms,
        saturated_fraction=saturated_fraction,
        hold_max_abs_error_m=hold_max,
        final_abs_error_m=float(abs_e[-1]),
        duration_s=duration,
    )
