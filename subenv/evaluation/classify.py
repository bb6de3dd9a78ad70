"""The classify stage: which episodes can be won, and which of them the score counts.

Every episode is classified after it is rolled out, from what was drawn for it (its loading, its
speeds, its depth order, its sea and surface: an :class:`EpisodeDraw`), never from how a controller
flew it, so that every controller of a comparison is judged on the same episodes.

- ``winnable`` (:func:`winnable_episode`): the loading has a depth-holding trim within the plane and
  pitch limits at the speed the episode holds at its end, with every plane pair the vehicle has free
  (:func:`subenv.analysis.winnable`): a static test, necessary and not sufficient.
- ``achievable`` (:func:`~subenv.evaluation.achievable.achievable_episode`): a full-information plan,
  stored per id and seed, won the episode on replay (:mod:`subenv.evaluation.achievable`); the Hard
  suite is scored by it.
- A suite scores the episodes its classifier calls True (:attr:`Suite.scored_by
  <subenv.evaluation.suites.Suite.scored_by>`). A classifier is a function of the :class:`EpisodeDraw`
  (which names the scenario and the seed), registered by name with :func:`register_classifier`.

An episode whose classifier cannot say (None: no certificate stored) is judged by ``winnable``
instead (:attr:`EpisodeResult.counts <subenv.evaluation.measure.EpisodeResult.counts>`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

from subenv.analysis.winnable import winnable
from subenv.dynamics.free_surface import NO_FREE_SURFACE, FreeSurface
from subenv.dynamics.waves import SeaState
from subenv.envs.config import DivePlaneConfig
from subenv.evaluation.achievable import achievable_episode
from subenv.scenarios.scenario import EpisodeConfig
from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "Classification",
    "Classifier",
    "EpisodeDraw",
    "check_classifier",
    "classifier_names",
    "classify",
    "register_classifier",
    "winnable_episode",
]


@dataclass(frozen=True)
class EpisodeDraw:
    """What was drawn for one episode: all a classifier may read.

    Attributes
    ----------
    scenario : str
        The scenario's name.
    seed : int
        The episode's reset seed.
    loading : Vehicle
        The episode's vehicle, as loaded for it (its ballast, drag, ...).
    episode : EpisodeConfig
        The episode's draw: speed profile, depth order, sea state, free surface.
    critical_speed_mps : float
        u_cr of the loading and the controller's plane allocation [m/s] (what relative speeds are of).
    max_pitch_rad : float
        The environment's pitch limit [rad].
    options : mapping or None
        The reset options (``speed``, ``depth_command``) that placed the episode, if any.
    config : DivePlaneConfig or None
        The environment's configuration (its scenario, vehicle and settings; None: not known).
    max_episode_steps : int or None
        Where the environment truncated episodes (None: at the scenario's duration only).
    """

    scenario: str
    seed: int
    loading: Vehicle
    episode: EpisodeConfig
    critical_speed_mps: float
    max_pitch_rad: float
    options: Mapping[str, Any] | None = None
    config: DivePlaneConfig | None = None
    max_episode_steps: int | None = None

    @property
    def final_speed_mps(self) -> float:
        """The speed the episode holds at its end [m/s]: its profile's last knot, or the reset's ``speed``."""
        if self.options and "speed" in self.options:
            return float(self.options["speed"])
        last = self.episode.speed_knots[-1][1]
        return float(last) * (self.critical_speed_mps if self.episode.speed_relative else 1.0)

    @property
    def depth_command_m(self) -> float:
        """The ordered depth [m]: the draw's, or the reset's ``depth_command``."""
        if self.options and "depth_command" in self.options:
            return float(self.options["depth_command"])
        return float(self.episode.depth_command_m)


Classifier = Callable[[EpisodeDraw], "bool | None"]
"""A function of an episode's draw: True, False, or None when it cannot say."""


@lru_cache(maxsize=4096)
def _winnable(
    loading: Vehicle,
    final_speed_mps: float,
    max_pitch_rad: float,
    depth_m: float = 0.0,
    free_surface: FreeSurface = NO_FREE_SURFACE,
    sea_state: SeaState | None = None,
) -> bool:
    """:func:`subenv.analysis.winnable` (about 4 ms), once per loading and speed (and ordered depth, near
    the surface): every controller of a comparison runs the same episodes."""
    return winnable(loading, (final_speed_mps,), max_pitch_rad, depth_m, free_surface, sea_state)


def winnable_episode(draw: EpisodeDraw) -> bool:
    """Whether the episode can be won at the speed it holds at its end: a depth-holding trim exists
    within the plane and pitch limits (near the surface: at the ordered depth, with its suction and
    sea)."""
    if draw.episode.free_surface is None and draw.episode.sea_state is None:
        return _winnable(draw.loading, draw.final_speed_mps, draw.max_pitch_rad)
    return _winnable(
        draw.loading,
        draw.final_speed_mps,
        draw.max_pitch_rad,
        draw.depth_command_m,
        draw.episode.free_surface or NO_FREE_SURFACE,
        draw.episode.sea_state,
    )


_CLASSIFIERS: dict[str, Classifier] = {"winnable": winnable_episode, "achievable": achievable_episode}


def register_classifier(name: str, classifier: Classifier, *, overwrite: bool = False) -> None:
    """Make ``classifier`` available to suites by name (:attr:`Suite.scored_by
    <subenv.evaluation.suites.Suite.scored_by>`)."""
    if name in _CLASSIFIERS and not overwrite:
        raise ValueError(f"classifier {name!r} is already registered; pass overwrite=True to replace it")
    _CLASSIFIERS[name] = classifier


def classifier_names() -> list[str]:
    """The registered classifiers' names, ``winnable`` first."""
    return list(_CLASSIFIERS)


def check_classifier(name: str) -> str:
    """``name`` if it is a registered classifier; ValueError listing the known ones otherwise."""
    if name not in _CLASSIFIERS:
        raise ValueError(f"scored_by={name!r} is unknown: must be one of {classifier_names()}")
    return name


@dataclass(frozen=True)
class Classification:
    """An episode's classes: whether it is winnable, and whether the score counts it."""

    winnable: bool
    scored: bool | None
    """The suite's classifier's verdict (:attr:`Suite.scored_by
    <subenv.evaluation.suites.Suite.scored_by>`); None when it cannot say (``winnable`` decides then)."""


def classify(draw: EpisodeDraw, scored_by: str = "winnable") -> Classification:
    """Classify one episode: winnable, and scored by the classifier named ``scored_by``."""
    can_win = winnable_episode(draw)
    verdict = can_win if scored_by == "winnable" else _CLASSIFIERS[check_classifier(scored_by)](draw)
    return Classification(winnable=can_win, scored=None if verdict is None else bool(verdict))
