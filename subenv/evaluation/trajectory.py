"""The record of an episode: the true state sampled at the reset and after every step.

The harness records the state the environment reports in ``info`` (not the possibly noisy
observation), so that the metrics judge where the boat actually was. :class:`TrajectoryRecorder`
collects N episodes stepped together (or one), and :class:`Trajectory` is one episode's record.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from subenv.evaluation.metrics import EpisodeMetrics, episode_metrics

__all__ = ["RECORDED", "Trajectory", "TrajectoryRecorder"]

RECORDED = (
    "time_s",
    "depth_error_m",
    "pitch_rad",
    "heave_mps",
    "pitch_rate_radps",
    "speed_mps",
    "stern_plane_rad",
    "bow_plane_rad",
    "depth_m",
)
"""The ``info`` keys recorded at every sample, in :class:`Trajectory`'s field order."""


@dataclass(frozen=True)
class Trajectory:
    """The true state of one episode, sampled at the reset and after every step (SI units).

    Arrays have one entry per sample (``steps + 1``); ``actions`` has one row per step. Plane
    angles of sample k >= 1 are those applied during the step ending at ``time_s[k]``.
    """

    time_s: np.ndarray
    depth_error_m: np.ndarray
    pitch_rad: np.ndarray
    heave_mps: np.ndarray
    pitch_rate_radps: np.ndarray
    speed_mps: np.ndarray
    stern_plane_rad: np.ndarray
    bow_plane_rad: np.ndarray
    depth_m: np.ndarray
    actions: np.ndarray
    termination_reason: str
    """The environment's reason; "" when the episode ran to its time limit (truncated)."""
    depth_command_m: float
    critical_speed_mps: float
    plane_limit_rad: float
    episode_duration_s: float
    """The scheduled length of the episode [s] (the scenario's, or the suite's cap)."""
    length_ratio: float = 1.0
    """lambda of the episode's Froude scaling (:attr:`subenv.envs.config.DivePlaneConfig.length_ratio`):
    its metrics' tolerances are scaled with it."""
    plane_count: int = 2
    """The planes the vehicle has: 2 (stern and bow), or 1 (stern planes alone)."""

    @property
    def steps(self) -> int:
        """Steps of the episode (samples less one)."""
        return int(self.time_s.shape[0] - 1)

    def metrics(self, **kwargs: Any) -> EpisodeMetrics:
        """:func:`~subenv.evaluation.metrics.episode_metrics` of this trajectory (kwargs: its tolerances)."""
        return episode_metrics(
            self.time_s,
            self.depth_error_m,
            self.pitch_rad,
            self.pitch_rate_radps,
            self.stern_plane_rad,
            self.bow_plane_rad,
            termination_reason=self.termination_reason,
            plane_limit_rad=self.plane_limit_rad,
            episode_duration_s=self.episode_duration_s,
            length_ratio=self.length_ratio,
            plane_count=self.plane_count,
            **kwargs,
        )


class TrajectoryRecorder:
    """Collects the ``info`` of N episodes stepped together (Gymnasium's vector ``info``, an array per
    key) or of one (a dict of floats), at the reset and after every step, into :class:`Trajectory` objects.
    """

    def __init__(self, reset_info: Mapping[str, Any]) -> None:
        self._samples = [self._sample(reset_info)]  # each (len(RECORDED), N)
        self._actions: list[np.ndarray] = []  # each (N, n_actions)
        self._depth_command_m = np.atleast_1d(np.asarray(reset_info["depth_command_m"], dtype=float))
        self._critical_speed_mps = np.atleast_1d(np.asarray(reset_info["critical_speed_mps"], dtype=float))
        self._stacked: tuple[np.ndarray, np.ndarray] | None = None

    @staticmethod
    def _sample(info: Mapping[str, Any]) -> np.ndarray:
        return np.array([info[key] for key in RECORDED], dtype=float).reshape(len(RECORDED), -1)

    def record(self, actions: np.ndarray, info: Mapping[str, Any]) -> None:
        """The actions of a step (shape (N, n_actions), or (n_actions,) for one episode) and its ``info``."""
        episodes = self._samples[0].shape[1]
        self._actions.append(np.array(actions, dtype=np.float32).reshape(episodes, -1))
        self._samples.append(self._sample(info))
        self._stacked = None

    def trajectory(
        self,
        episode: int,
        steps: int,
        termination_reason: str,
        plane_limit_rad: float,
        episode_duration_s: float,
        length_ratio: float = 1.0,
        plane_count: int = 2,
    ) -> Trajectory:
        """Episode ``episode``'s (its row) first ``steps`` steps."""
        if self._stacked is None:
            episodes = self._samples[0].shape[1]
            actions = (
                np.stack(self._actions) if self._actions else np.zeros((0, episodes, 1), dtype=np.float32)
            )
            self._stacked = np.stack(self._samples), actions
        samples, actions = self._stacked
        time_s, error, pitch, heave, rate, speed, stern, bow, depth = (
            np.ascontiguousarray(column) for column in samples[: steps + 1, :, episode].T
        )
        return Trajectory(
            time_s=time_s,
            depth_error_m=error,
            pitch_rad=pitch,
            heave_mps=heave,
            pitch_rate_radps=rate,
            speed_mps=speed,
            stern_plane_rad=stern,
            bow_plane_rad=bow,
            depth_m=depth,
            actions=np.ascontiguousarray(actions[:steps, episode]),
            termination_reason=termination_reason,
            depth_command_m=float(self._depth_command_m[episode]),
            critical_speed_mps=float(self._critical_speed_mps[episode]),
            plane_limit_rad=plane_limit_rad,
            episode_duration_s=episode_duration_s,
            length_ratio=length_ratio,
            plane_count=plane_count,
        )

    def finish(
        self,
        termination_reason: str,
        plane_limit_rad: float,
        episode_duration_s: float,
        length_ratio: float = 1.0,
        plane_count: int = 2,
    ) -> Trajectory:
        """The trajectory of one episode, recorded to its end."""
        return self.trajectory(
            0,
            len(self._actions),
            termination_reason,
            plane_limit_rad,
            episode_duration_s,
            length_ratio,
            plane_count,
        )
