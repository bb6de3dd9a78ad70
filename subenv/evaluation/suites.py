"""Named evaluation suites: which scenarios a comparison runs, how many episodes, how long, and which of
its episodes the score counts.

A suite is data (a frozen dataclass in a registry), like a scenario; :func:`resolve_suite` is the one
place a suite's name (or a list of scenario names) becomes a :class:`Suite`. The episodes of a suite are
fixed by a base seed: episode ``i`` of every scenario is ``reset(seed=base_seed + i)``, for every
controller, so all controllers meet the same episodes. (This is also how
``gym.make_vec(id, num_envs=N).reset(seed=base_seed)`` seeds its sub-environments, so a batched
run draws the same episodes.)
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from subenv.scenarios.registry import scenario_for_env_id, scenario_names

__all__ = [
    "BENCHMARK_SUITES",
    "DEFAULT_SEED",
    "DEFAULT_SUITE",
    "Suite",
    "check_scenarios",
    "get_suite",
    "register_suite",
    "resolve_suite",
    "scenario_of",
    "suite_names",
]

BENCHMARK_SUITES: Final = ("default", "hard")
"""The suites ``subenv evaluate`` (``./dev run``) runs when the caller names none: the default track and
the Hard track, each its own leaderboard."""
DEFAULT_SEED: Final = 10_000
"""Base seed of evaluations: away from the small seeds (0, 1, 2, ...) that training runs and
examples use, so an agent is not scored on the very episodes it was trained on."""

DEFAULT_SUITE: Final = "default"


@dataclass(frozen=True)
class Suite:
    """A named set of scenarios to compare controllers on.

    Attributes
    ----------
    name : str
        Registry key (``subenv evaluate --suite NAME``).
    description : str
        One line on what the suite measures.
    scenarios : tuple of str
        Registered scenario names (``subenv.scenarios.scenario_names()``), run in this order.
    episodes : int
        Episodes per scenario and controller when the caller does not say.
    max_duration_s : float or None
        Truncate every episode at this time [s] (the scenario's own duration applies too);
        None runs the scenarios' full lengths.
    scored_by : str
        The classifier whose True episodes the score counts (:func:`subenv.evaluation.classify.classify`):
        ``"winnable"`` (a depth-holding trim exists within the limits), or another registered one (the
        Hard suite's ``"achievable"``, read from stored certificates: :mod:`subenv.evaluation.achievable`).
    uninformed_twins : bool
        Where the caller names no controllers, run each one that takes the environment's settings
        (:class:`~subenv.evaluation.controller.InformedController`) twice: told them, and untold as
        ``<name>:uninformed``; for a suite whose environments have settings worth knowing (the Hard
        suite's rate and pitch limits).
    """

    name: str
    description: str
    scenarios: tuple[str, ...]
    episodes: int
    max_duration_s: float | None = None
    scored_by: str = "winnable"
    uninformed_twins: bool = False

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError("a suite needs a name")
        if not self.scenarios or len(set(self.scenarios)) != len(self.scenarios):
            raise ValueError(
                f"suite {self.name!r}: scenarios={self.scenarios!r} must be non-empty and distinct"
            )
        episodes = self.episodes
        if not (isinstance(episodes, int) and not isinstance(episodes, bool) and episodes >= 1):
            raise ValueError(f"suite {self.name!r}: episodes={self.episodes!r} must be an integer >= 1")
        if self.max_duration_s is not None and not (
            math.isfinite(self.max_duration_s) and self.max_duration_s > 0
        ):
            raise ValueError(
                f"suite {self.name!r}: max_duration_s={self.max_duration_s!r} must be None or a "
                "finite number > 0"
            )
        if not (isinstance(self.scored_by, str) and self.scored_by):
            raise ValueError(f"suite {self.name!r}: scored_by={self.scored_by!r} must be a classifier's name")


_REGISTRY: dict[str, Suite] = {}


def register_suite(suite: Suite, *, overwrite: bool = False) -> Suite:
    """Make a suite selectable by name."""
    if suite.name in _REGISTRY and not overwrite:
        raise ValueError(f"suite {suite.name!r} is already registered; pass overwrite=True to replace it")
    _REGISTRY[suite.name] = suite
    return suite


def suite_names() -> list[str]:
    """Names of the registered suites, in registration order."""
    return list(_REGISTRY)


def check_scenarios(names: tuple[str, ...] | list[str]) -> None:
    """Raise ValueError naming the first unknown scenario and listing the known ones."""
    known = scenario_names()
    for name in names:
        if name not in known:
            raise ValueError(f"scenario={name!r} is unknown: must be one of {known}")


def get_suite(name: str) -> Suite:
    """The registered suite ``name``, its scenarios checked against the scenario registry.

    Raises ValueError listing the known suites (or the known scenarios, if the suite names one
    that is not registered).
    """
    try:
        suite = _REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"suite={name!r} is unknown: must be one of {suite_names()}") from None
    check_scenarios(suite.scenarios)
    return suite


def scenario_of(name: str) -> str:
    """The scenario name of ``"LowSpeed"`` or ``"subenv/LowSpeed-v0"`` (checked)."""
    scenario = name
    if name == "subenv/DivePlane-v0":
        scenario = "Randomized"
    elif "/" in name:
        found = scenario_for_env_id(name)
        if found is None:
            parsed = re.fullmatch(r"subenv/(\w+)-v(\d+)", name)
            if parsed is None:
                raise ValueError(
                    f"env id {name!r} is not a subenv id: must be 'subenv/<Scenario>-v<version>'"
                )
            base, version = parsed.groups()
            found = base if version == "0" else f"{base}-v{version}"  # (unknown: check_scenarios says so)
        scenario = found
    check_scenarios([scenario])
    return scenario


def resolve_suite(suite: Suite | str | Sequence[str] | None) -> Suite:
    """A :class:`Suite` from itself, a registered suite name, a scenario name or id, or a list of them
    (None: :data:`DEFAULT_SUITE`).

    A list of one name is that name (as ``subenv evaluate --suite tiny`` gives it). A name that is both a
    suite and a scenario is the suite. A list of scenarios is the suite ``"custom"`` (10 episodes, scored
    by ``winnable``). Raises ValueError naming an unknown name and listing the known suites and
    scenarios.
    """
    if suite is None:
        suite = DEFAULT_SUITE
    if isinstance(suite, Suite):
        check_scenarios(suite.scenarios)
        return suite
    if not isinstance(suite, str) and len(suite) == 1:
        suite = suite[0]  # (one name: a suite's or a scenario's, as a name alone)
    if isinstance(suite, str):
        if suite in suite_names():
            return get_suite(suite)
        try:
            suite = [scenario_of(suite)]
        except ValueError:
            raise ValueError(
                f"suite={suite!r} is unknown: must be a suite name (one of {suite_names()}) or a scenario "
                f"name (one of {scenario_names()})"
            ) from None
    names = tuple(scenario_of(s) for s in suite)
    return Suite(name="custom", description="scenarios chosen by the caller", scenarios=names, episodes=10)


register_suite(
    Suite(
        name="default",
        description=(
            "The base scenarios: design speed, below, near and through critical, periscope depth (the free "
            "surface's suction; calm, and in a head sea), ballast offset."
        ),
        scenarios=(
            "Nominal",
            "LowSpeed",
            "NearCritical",
            "SpeedTransient",
            "PeriscopeDepth-v1",
            "PeriscopeDepthWaves",
            "BallastOffset",
        ),
        episodes=100,
    )
)
register_suite(
    Suite(
        name="hard",
        description=(
            "The Hard track: rate-limited planes through u_cr, a ballast offset with noise and tighter "
            "limits, a rough sea at periscope depth, gusts near u_cr; scored over the episodes a stored "
            "full-information plan certifies achievable (50 seeds certified per scenario)."
        ),
        scenarios=(
            "HardRateTransient",
            "HardBallastLimits",
            "HardWaves18",
            "HardGusts",
        ),
        # 50: the seeds the certificates cover (the oracle's search took an hour of CPU for 50 seeds of the
        # six candidates), and what keeps `subenv evaluate`'s two tracks within ./dev run's budget.
        episodes=50,
        scored_by="achievable",
        uninformed_twins=True,
    )
)
register_suite(
    Suite(
        name="reversal",
        description=(
            "Where dive-plane reversal bites: below, near and decelerating through the critical speed."
        ),
        scenarios=("LowSpeed", "NearCritical", "SpeedTransient"),
        episodes=100,
    )
)
register_suite(
    Suite(
        name="randomized",
        description=(
            "The Randomized scenario: any base scenario with z_GB, C_D, sensor noise and a disturbance drawn."
        ),
        scenarios=("Randomized",),
        episodes=200,
    )
)
register_suite(
    Suite(
        name="tiny",
        description="For tests and smoke runs: design speed and below critical, 2 episodes each.",
        scenarios=("Nominal", "LowSpeed"),
        episodes=2,
    )
)
