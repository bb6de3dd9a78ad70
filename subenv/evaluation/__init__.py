"""Evaluation: the controller interface and registry, and the harness that compares controllers.

- :mod:`~subenv.evaluation.controller`: the :class:`Controller` protocol (and :class:`BatchController`,
  acting on many episodes at once) and its registry.
- :mod:`~subenv.evaluation.metrics`: per-episode metrics from a recorded trajectory.
- :mod:`~subenv.evaluation.rollout`: running controllers on episodes, batched in the vector
  environment (:func:`evaluate`).
- :mod:`~subenv.evaluation.progress`: progress on a terminal or in a log, the first run's compile notice.
- :mod:`~subenv.evaluation.suites`: named sets of scenarios (``default``, ``reversal``, ...).
- :mod:`~subenv.evaluation.results`: tables, confidence intervals, the leaderboard, atomic writes.
- :mod:`~subenv.evaluation.plots`: trajectory and metrics-versus-speed figures (matplotlib).
- :mod:`~subenv.evaluation.comparison`: :func:`run_comparison`, what ``subenv evaluate`` runs.
"""

from subenv.evaluation.comparison import DEFAULT_OUT_DIR, Comparison, run_comparison, write_comparison
from subenv.evaluation.controller import (
    ENTRY_POINT_GROUP,
    BatchController,
    Controller,
    ControllerFactory,
    SingleRowMixin,
    check_batch,
    controller_names,
    discover_controllers,
    make_controller,
    register_controller,
)
from subenv.evaluation.metrics import EpisodeMetrics, episode_metrics
from subenv.evaluation.rollout import (
    ControllerError,
    ControllerFailure,
    EpisodeResult,
    Trajectory,
    evaluate,
    run_episode,
    run_episodes,
)
from subenv.evaluation.suites import (
    DEFAULT_SEED,
    DEFAULT_SUITE,
    Suite,
    get_suite,
    register_suite,
    suite_names,
)

__all__ = [
    "DEFAULT_OUT_DIR",
    "DEFAULT_SEED",
    "DEFAULT_SUITE",
    "ENTRY_POINT_GROUP",
    "BatchController",
    "Comparison",
    "Controller",
    "ControllerError",
    "ControllerFactory",
    "ControllerFailure",
    "EpisodeMetrics",
    "EpisodeResult",
    "SingleRowMixin",
    "Suite",
    "Trajectory",
    "check_batch",
    "controller_names",
    "discover_controllers",
    "episode_metrics",
    "evaluate",
    "get_suite",
    "make_controller",
    "register_controller",
    "register_suite",
    "run_comparison",
    "run_episode",
    "run_episodes",
    "suite_names",
    "write_comparison",
]
