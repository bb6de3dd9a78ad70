"""The measure stage: an episode's record and classes become its :class:`EpisodeResult`.

The metrics are those of :mod:`subenv.evaluation.metrics` (defined there, once); this module puts
them beside what was run (controller, scenario, seed, speeds, depth order) and how the episode is
classified (:mod:`subenv.evaluation.classify`), as one row of the per-episode table (``results.csv``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from subenv.evaluation.classify import Classification
from subenv.evaluation.controller import Controller
from subenv.evaluation.metrics import EpisodeMetrics
from subenv.evaluation.trajectory import Trajectory

__all__ = ["EpisodeResult", "measure"]


@dataclass(frozen=True)
class EpisodeResult:
    """One controller on one episode: what was run, and its metrics (and trajectory, if kept)."""

    controller: str
    scenario: str
    episode: int
    seed: int
    control: str
    alpha: float
    initial_speed_mps: float
    final_speed_mps: float
    """Speed at the end of the episode [m/s]: the speed over the hold window, on which success
    depends (equal to the initial speed except in ``SpeedTransient``)."""
    critical_speed_mps: float
    """Critical speed of the episode's loading and the controller's alpha (info at reset)."""
    depth_command_m: float
    initial_depth_error_m: float
    episode_duration_s: float
    steps: int
    metrics: EpisodeMetrics
    trajectory: Trajectory | None = field(default=None, repr=False, compare=False)
    winnable: bool | None = None
    """Whether the episode's loading has a depth-holding trim within the plane limits and the pitch limit
    at the speed it is to hold at its end, with every plane pair the vehicle has free
    (:func:`subenv.analysis.winnable`): where it has none no controller can succeed. None: not determined."""
    scored: bool | None = None
    """Whether the score counts the episode: its suite's classifier's verdict
    (:attr:`Suite.scored_by <subenv.evaluation.suites.Suite.scored_by>`, ``winnable`` by default). None:
    not classified, or the classifier cannot say (:attr:`counts`)."""
    informed: bool = False
    """Whether the controller was told the environment's settings before the episode
    (:class:`~subenv.evaluation.controller.InformedController`)."""

    @property
    def counts(self) -> bool:
        """Whether the score counts the episode: :attr:`scored`; where that is None, :attr:`winnable`;
        where both are None, True (an episode is left out only when it is known not to count)."""
        if self.scored is not None:
            return self.scored
        return self.winnable is not False

    def row(self) -> dict[str, Any]:
        """One flat row of the tidy per-episode table (``results.csv``; its columns:
        :data:`subenv.evaluation.results_format.RESULTS_COLUMNS`)."""
        base = {
            "controller": self.controller,
            "scenario": self.scenario,
            "episode": self.episode,
            "seed": self.seed,
            "control": self.control,
            "alpha": self.alpha,
            "initial_speed_mps": self.initial_speed_mps,
            "final_speed_mps": self.final_speed_mps,
            "critical_speed_mps": self.critical_speed_mps,
            "final_speed_ratio": self.final_speed_mps / self.critical_speed_mps,
            "depth_command_m": self.depth_command_m,
            "initial_depth_error_m": self.initial_depth_error_m,
            "episode_duration_s": self.episode_duration_s,
            "steps": self.steps,
            "winnable": self.winnable,
        }
        return base | self.metrics.as_dict() | {"scored": self.scored, "informed": self.informed}


def measure(
    controller: Controller,
    scenario: str,
    seed: int,
    episode: int,
    trajectory: Trajectory,
    classification: Classification | None = None,
    *,
    keep: bool = False,
    informed: bool = False,
) -> EpisodeResult:
    """The :class:`EpisodeResult` of ``controller``'s episode ``episode`` (reset with ``seed``) of
    ``scenario``: its metrics from ``trajectory``, which it keeps if ``keep``."""
    return EpisodeResult(
        controller=controller.name,
        scenario=scenario,
        episode=episode,
        seed=seed,
        control=controller.control,
        alpha=float(controller.alpha),
        initial_speed_mps=float(trajectory.speed_mps[0]),
        final_speed_mps=float(trajectory.speed_mps[-1]),
        critical_speed_mps=trajectory.critical_speed_mps,
        depth_command_m=trajectory.depth_command_m,
        initial_depth_error_m=float(trajectory.depth_error_m[0]),
        episode_duration_s=trajectory.episode_duration_s,
        steps=trajectory.steps,
        metrics=trajectory.metrics(),
        trajectory=trajectory if keep else None,
        winnable=None if classification is None else classification.winnable,
        scored=None if classification is None else classification.scored,
        informed=informed,
    )
