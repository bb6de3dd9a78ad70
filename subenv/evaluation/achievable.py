"""Achievable episodes: the certificates that an episode can be won, stored per id and seed, as data.

An episode is **achievable** when a plan of its actions wins it: a full-information reference solution,
computed once, offline, by an oracle that knows what no controller may know (the true state, the
episode's loading, its drawn heave force and sea; not the future of its depth orders), and checked by
replaying it in the environment through the evaluation harness (:class:`PlanReplay`). The oracle is
``subenv_baselines.oracle``, run by ``benchmarks/hard_certificates.py``, which writes these files;
``subenv`` never imports the oracle, so a wheel reads the certificates without it. The plan is the
certificate: the environment is deterministic given its seed and the actions. An episode the oracle did
not win is *not certified*, never proven impossible. The certificates are for independent planes (the most
authority); a controller with one command meets the same episodes.

The flags are a file of this package, ``data/achievable-<suite>.json`` (:data:`CERTIFICATE_FILES`), one
entry per id (its scenario, the vehicle and the environment's settings the plans were made and replayed
in) and per seed (``achievable``, the replay's ``outcome`` and ``hold_max_abs_error_m``, the SHA-256 of
the plan, :func:`plan_sha256`). A sample of the plans is in the repository
(``tests/data/certificates/``), whose tests replay them and check these flags.

:func:`achievable_episode` is the classifier ``"achievable"`` (:mod:`subenv.evaluation.classify`),
which scores the Hard suite. It says None (it cannot say; ``winnable`` decides then) for an episode it
holds no certificate for: another id or seed, another vehicle, environment settings other than those
certified (a caller's ``env_kwargs`` that change them), reset options, or an episode truncated before
its scenario's end.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from subenv.scenarios.registry import get_scenario
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.vehicle import Vehicle

if TYPE_CHECKING:  # (classify imports this module: the classifier's argument, for the annotation only)
    from subenv.evaluation.classify import EpisodeDraw

__all__ = [
    "CERTIFICATE_FILES",
    "CERTIFICATE_FORMAT",
    "CERTIFIED_SETTINGS",
    "CertifiedId",
    "EpisodeFlag",
    "PlanReplay",
    "achievable_episode",
    "certified_ids",
    "plan_sha256",
    "read_certificates",
]

DATA_PACKAGE: Final = "subenv.evaluation.data"
CERTIFICATE_FILES: Final = ("achievable-hard.json",)
"""The flag files of :data:`DATA_PACKAGE` the classifier reads (one per suite certified)."""
CERTIFICATE_FORMAT: Final = 1
"""The version of the files' layout (their ``"format"``)."""
CERTIFIED_SETTINGS: Final = ("dt", "substeps", "plane_rate_limit_radps", "max_pitch_rad", "max_depth_error_m")
"""The environment's settings a certificate holds for (those that change the episode's motion or its
end; the reward's weights and the observation's scale do not), stored with it as the plans were made."""


@dataclass(frozen=True)
class EpisodeFlag:
    """One episode's certificate, as stored: whether its plan won on replay, and what the replay gave."""

    achievable: bool
    outcome: str
    hold_max_abs_error_m: float
    plan_sha256: str
    """Of the plan's actions (:func:`plan_sha256`)."""
    stage: str
    """The oracle's stage whose plan won ("" where none did)."""


@dataclass(frozen=True)
class CertifiedId:
    """The certificates of one id: the conditions they hold for, and a flag per seed."""

    env_id: str
    scenario: str
    vehicle: str
    settings: Mapping[str, Any]
    """The environment's settings the plans were made in (:data:`CERTIFIED_SETTINGS`, as
    :class:`~subenv.envs.DivePlaneConfig` resolves the id's arguments)."""
    episodes: Mapping[int, EpisodeFlag]


def read_certificates(text: str) -> dict[str, CertifiedId]:
    """The certificates of one flag file's JSON text, by id; ValueError naming what is wrong with it."""
    data = json.loads(text)
    if not isinstance(data, dict) or data.get("format") != CERTIFICATE_FORMAT:
        raise ValueError(
            f"a certificate file must be a JSON object with format {CERTIFICATE_FORMAT}, "
            f"not {str(data)[:60]!r}"
        )
    found = {}
    for env_id, entry in data["ids"].items():
        found[env_id] = CertifiedId(
            env_id=env_id,
            scenario=entry["scenario"],
            vehicle=entry["vehicle"],
            settings=dict(entry["settings"]),
            episodes={int(seed): EpisodeFlag(**flag) for seed, flag in entry["episodes"].items()},
        )
    return found


@cache
def certified_ids() -> dict[str, CertifiedId]:
    """Every id the package holds certificates for (read once, from :data:`CERTIFICATE_FILES`)."""
    found: dict[str, CertifiedId] = {}
    for name in CERTIFICATE_FILES:
        found |= read_certificates(resources.files(DATA_PACKAGE).joinpath(name).read_text("utf-8"))
    return found


def _same(value: Any, certified: Any) -> bool:
    """A setting equal to the certified one (floats exactly; None only as None)."""
    if isinstance(certified, float) and isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value) == certified or (math.isnan(certified) and math.isnan(value))
    return bool(value == certified)


def achievable_episode(draw: EpisodeDraw) -> bool | None:
    """Whether a stored certificate says the episode can be won (True), was not certified (False), or
    None where none applies (the module docstring)."""
    config = draw.config
    if config is None or draw.options:
        return None
    certified = certified_ids().get(config.scenario.env_id)
    if certified is None or certified.scenario != draw.scenario:
        return None
    if config.scenario != get_scenario(certified.scenario):  # (an unregistered scenario of that name)
        return None
    flag = certified.episodes.get(draw.seed)
    if flag is None:
        return None
    if not all(_same(getattr(config, name), value) for name, value in certified.settings.items()):
        return None
    if config.vehicle != _vehicle(certified.vehicle):
        return None
    if (
        draw.max_episode_steps is not None
        and draw.max_episode_steps * config.dt < draw.episode.duration_s - 1e-9
    ):
        return None
    return flag.achievable


@cache
def _vehicle(name: str) -> Any:
    return load_vehicle(name)


def plan_sha256(actions: np.ndarray) -> str:
    """The SHA-256 of a plan: its actions as the environment takes them, float32 little-endian, one row
    per step (stern, bow)."""
    return hashlib.sha256(np.ascontiguousarray(actions, dtype="<f4").tobytes()).hexdigest()


class PlanReplay:
    """A batch controller that plays stored plans, one per episode in the order of the seeds run (float32
    actions, one row per step, independent planes), each held at its last action past its end. Run one
    episode at a time (``reset``, ``act``), each reset takes the next plan.

    How a certificate is checked: ``run_episodes(PlanReplay(plans), env_id, seeds)`` replays them in the
    harness's own environments; the episodes the plans win are the achievable ones.
    """

    name, control, alpha = "oracle_plan", "independent", 0.0

    def __init__(self, plans: Sequence[np.ndarray]) -> None:
        self.plans = [np.asarray(p, dtype=np.float32) for p in plans]
        for p in self.plans:
            if p.ndim != 2 or p.shape[1] != 2 or len(p) == 0 or not np.isfinite(p).all():
                raise ValueError(f"a plan must be a finite (steps, 2) array, not one of shape {p.shape}")
        self._playing = self.plans
        self._next = 0  # (the plan the next one-episode reset plays)
        self._steps = 0

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Start the plans again from their first action (one plan per episode)."""
        if len(infos) != len(self.plans):
            raise ValueError(f"{len(infos)} episodes for {len(self.plans)} plans: one plan per episode")
        self._playing, self._steps = self.plans, 0

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The plans' actions of this step."""
        k = self._steps
        self._steps += 1
        return np.stack([p[min(k, len(p) - 1)] for p in self._playing])

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        """One episode: the next plan."""
        if self._next >= len(self.plans):
            raise ValueError(f"episode {self._next + 1} for {len(self.plans)} plans: one plan per episode")
        self._playing, self._steps = self.plans[self._next : self._next + 1], 0
        self._next += 1

    def act(self, observation: np.ndarray) -> np.ndarray:
        """One episode: :meth:`act_batch` of one."""
        action: np.ndarray = self.act_batch(np.asarray(observation)[None])[0]
        return action
