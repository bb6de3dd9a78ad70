"""Evaluation: the controller interface and registry, and the harness that compares controllers.

The harness runs in stages, one module each:

1. resolve (:mod:`~subenv.evaluation.plan`): suite -> scenarios, controllers, episodes and seeds, the
   vehicle and the environment's settings (:mod:`~subenv.evaluation.environments`), once, checked;
2. roll out (:mod:`~subenv.evaluation.rollout`), batched in the vector environment, each episode
   recorded (:mod:`~subenv.evaluation.trajectory`), a controller's failure reported in one line
   (:mod:`~subenv.evaluation.failures`);
3. classify (:mod:`~subenv.evaluation.classify`): winnable, and whether the score counts the episode;
4. measure (:mod:`~subenv.evaluation.measure`): the per-episode metrics, defined in
   :mod:`~subenv.evaluation.metrics`;
5. report: the score with its intervals and paired comparisons (:mod:`~subenv.evaluation.score`),
   the tables (:mod:`~subenv.evaluation.results`, intervals from :mod:`~subenv.evaluation.stats`),
   the figures (:mod:`~subenv.evaluation.plots`), in the format of
   :mod:`~subenv.evaluation.results_format`.

:func:`evaluate` runs stages 1-4; :func:`run_comparison` (:mod:`~subenv.evaluation.comparison`, what
``subenv evaluate`` runs) all five. Also: :mod:`~subenv.evaluation.controller` (the
:class:`Controller` protocol, :class:`BatchController`, acting on many episodes at once, and the
registry), :mod:`~subenv.evaluation.suites` (named sets of scenarios) and
:mod:`~subenv.evaluation.progress` (progress on a terminal or in a log).
"""

from subenv.evaluation.comparison import (
    DEFAULT_OUT_DIR,
    Comparison,
    run_benchmark,
    run_comparison,
    write_comparison,
)
from subenv.evaluation.controller import (
    ENTRY_POINT_GROUP,
    BatchController,
    Controller,
    ControllerFactory,
    InformedController,
    SingleRowMixin,
    check_batch,
    controller_names,
    discover_controllers,
    make_controller,
    register_controller,
    uninformed,
)
from subenv.evaluation.metrics import EpisodeMetrics, episode_metrics
from subenv.evaluation.plan import Plan, resolve
from subenv.evaluation.rollout import (
    ControllerError,
    ControllerFailure,
    EpisodeResult,
    Trajectory,
    evaluate,
    roll_out,
    run_episode,
    run_episodes,
)
from subenv.evaluation.score import PairedComparison, Score, paired_comparisons, scores
from subenv.evaluation.suites import (
    BENCHMARK_SUITES,
    DEFAULT_SEED,
    DEFAULT_SUITE,
    Suite,
    get_suite,
    register_suite,
    suite_names,
)

__all__ = [
    "BENCHMARK_SUITES",
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
    "InformedController",
    "PairedComparison",
    "Plan",
    "Score",
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
    "paired_comparisons",
    "register_controller",
    "register_suite",
    "resolve",
    "roll_out",
    "run_benchmark",
    "run_comparison",
    "run_episode",
    "run_episodes",
    "scores",
    "suite_names",
    "uninformed",
    "write_comparison",
]
