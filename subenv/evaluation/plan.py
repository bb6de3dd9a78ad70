"""The resolve stage: what a comparison runs, resolved once, before any episode.

:func:`resolve` turns a caller's arguments (controller names or instances, a suite name or scenario
names, episodes, a base seed, a vehicle, the environment's settings) into a :class:`Plan`, checking each
with a one-line ValueError naming it. The other stages read the plan: roll out
(:func:`subenv.evaluation.rollout.roll_out`), classify, measure, report
(:func:`subenv.evaluation.comparison.run_comparison`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from subenv.evaluation.classify import check_classifier
from subenv.evaluation.controller import (
    UNINFORMED_SUFFIX,
    Controller,
    controller_names,
    informed,
    make_controller,
    uninformed,
)
from subenv.evaluation.environments import check_env_kwargs
from subenv.evaluation.suites import DEFAULT_SEED, DEFAULT_SUITE, Suite, resolve_suite
from subenv.vehicles.loader import load_vehicle
from subenv.vehicles.vehicle import Vehicle

__all__ = ["Plan", "needs_bow_planes", "resolve", "resolve_controllers", "with_uninformed_twins"]


@dataclass(frozen=True)
class Plan:
    """A comparison, resolved: every controller on the same episodes of every scenario of the suite.

    Attributes
    ----------
    suite : Suite
    controllers : tuple of Controller
        In the order run; their names are distinct.
    episodes : int
        Episodes per scenario and controller.
    seed : int
        Base seed: episode i of every scenario is ``reset(seed=seed + i)``.
    vehicle : Vehicle
        The vehicle of every environment (loaded once, shared).
    vehicle_name : str
        How the caller named it (a shipped name or a file), for the record.
    env_kwargs : dict
        The environment's settings the caller gave (checked; :mod:`subenv.evaluation.environments`).
    """

    suite: Suite
    controllers: tuple[Controller, ...]
    episodes: int
    seed: int
    vehicle: Vehicle
    vehicle_name: str
    env_kwargs: dict[str, Any] = field(default_factory=dict)

    @property
    def seeds(self) -> range:
        """The reset seeds of every scenario's episodes."""
        return range(self.seed, self.seed + self.episodes)


def _whole(name: str, value: Any, low: int) -> int:
    if not (isinstance(value, int) and not isinstance(value, bool) and value >= low):
        raise ValueError(f"{name}={value!r} is invalid: must be an integer >= {low}")
    return value


def resolve(
    controllers: Sequence[Controller | str] | None,
    suite: Suite | str | Sequence[str] | None = DEFAULT_SUITE,
    episodes: int | None = None,
    seed: int = DEFAULT_SEED,
    *,
    vehicle: str | Vehicle = "suboff",
    env_kwargs: Mapping[str, Any] | None = None,
) -> Plan:
    """The :class:`Plan` of a comparison; the arguments are :func:`subenv.evaluation.evaluate`'s.

    Raises
    ------
    ValueError
        An unknown vehicle, controller, suite or scenario (the message lists the known names), bad
        ``episodes`` or ``seed``, or ``env_kwargs`` the environment refuses (the key named).
    TypeError
        A controller that is not a :class:`~subenv.evaluation.Controller`.
    """
    boat = vehicle if isinstance(vehicle, Vehicle) else load_vehicle(vehicle)
    ctrls = resolve_controllers(controllers, boat)
    the_suite = resolve_suite(suite)
    check_classifier(the_suite.scored_by)
    if controllers is None and the_suite.uninformed_twins:
        ctrls = with_uninformed_twins(ctrls)
    return Plan(
        suite=the_suite,
        controllers=tuple(ctrls),
        episodes=_whole("episodes", the_suite.episodes if episodes is None else episodes, 1),
        seed=_whole("seed", seed, 0),
        vehicle=boat,
        vehicle_name=vehicle if isinstance(vehicle, str) else vehicle.name,
        env_kwargs=check_env_kwargs(env_kwargs, the_suite.scenarios, boat),
    )


def with_uninformed_twins(controllers: Sequence[Controller]) -> list[Controller]:
    """``controllers``, each that takes the environment's settings followed by a fresh instance of it run
    untold, ``<name>:uninformed`` (:attr:`Suite.uninformed_twins
    <subenv.evaluation.suites.Suite.uninformed_twins>`; registered controllers only, as the default
    selection is)."""
    names = {c.name for c in controllers}
    twinned: list[Controller] = []
    for c in controllers:
        twinned.append(c)
        twin = c.name + UNINFORMED_SUFFIX
        if informed(c) and twin not in names:
            twinned.append(_made(twin))
    return twinned


def needs_bow_planes(controller: Controller) -> bool:
    """Whether ``controller`` moves the bow planes (``control="independent"``, or dual control with
    alpha != 0)."""
    return controller.control == "independent" or float(controller.alpha) != 0.0


def _made(name: str) -> Controller:
    """The registered controller ``name``, or ``<name>:uninformed`` (:func:`uninformed`)."""
    if name.endswith(UNINFORMED_SUFFIX) and name != UNINFORMED_SUFFIX:
        return uninformed(make_controller(name.removesuffix(UNINFORMED_SUFFIX)))
    return make_controller(name)


def resolve_controllers(
    controllers: Sequence[Controller | str] | None, vehicle: Vehicle | None = None
) -> list[Controller]:
    """Controllers from instances or registered names (None: every registered controller but those whose
    ``in_default_comparison`` attribute is False, and on a ``vehicle`` without bow planes those that move
    them, :func:`needs_bow_planes`).

    A name ``<name>:uninformed`` is the registered controller ``name`` run without being told the
    environment's settings (:func:`~subenv.evaluation.controller.uninformed`).

    Raises ValueError for an unknown name (listing the known ones), an empty selection, two
    controllers with one name, or a named controller that moves bow planes ``vehicle`` does not have;
    TypeError for an object that is not a :class:`~subenv.evaluation.Controller`.
    """
    named = controllers is not None
    if controllers is None:
        names = controller_names()
        if not names:
            raise ValueError(
                "no controllers are registered: install a package that declares some in the "
                "'subenv.controllers' entry-point group, or call subenv.evaluation.register_controller"
            )
        # A controller whose class says in_default_comparison = False (a plugin's that is too slow for
        # the comparison of every registered one, say) runs when named only.
        made = [make_controller(name) for name in names]
        controllers = [c for c in made if getattr(c, "in_default_comparison", True)] or made
    if isinstance(controllers, str):
        controllers = [controllers]
    resolved = [_made(c) if isinstance(c, str) else c for c in controllers]
    if not resolved:
        raise ValueError("controllers is empty: name at least one")
    for c in resolved:
        if not isinstance(c, Controller):
            raise TypeError(f"{c!r} is not a Controller (needs name, control, alpha, reset(), act())")
        if c.control not in ("dual", "independent"):
            raise ValueError(f"controller {c.name!r}: control={c.control!r} must be 'dual' or 'independent'")
    names = [c.name for c in resolved]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ValueError(f"controller names {duplicates} appear more than once: the tables are keyed by name")
    if vehicle is not None and not vehicle.planes.has_bow_planes:
        bow = [c.name for c in resolved if needs_bow_planes(c)]
        if bow and named:
            raise ValueError(
                f"controllers {bow} move the bow planes (control='independent' or alpha != 0), and "
                f"vehicle {vehicle.name!r} has none: leave them out"
            )
        resolved = [c for c in resolved if not needs_bow_planes(c)] or resolved
    return resolved
