"""The controller interface shared by classical baselines and trained agents, and its registry.

A controller maps an observation to an action in [-1, 1]. It declares which action space it drives
(``control`` and ``alpha`` are passed to the environment), and is told at every episode start what
the environment reports (``info`` at reset: speed, critical speed, depth command, ...) and the
vehicle it was designed for. It never reads the environment's internals.

Other packages (``baselines``, ``agents``) register factories with :func:`register_controller`
when they are imported; ``subenv`` itself imports neither.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np

from subenv.vehicles.vehicle import Vehicle

__all__ = ["Controller", "ControllerFactory", "controller_names", "make_controller", "register_controller"]

ControlMode = Literal["dual", "independent"]


@runtime_checkable
class Controller(Protocol):
    """What the evaluation harness (and any user loop) needs from a depth controller.

    Attributes
    ----------
    name : str
        Short name used in tables and plots.
    control : {"dual", "independent"}
        The environment's action space this controller drives: one dual command or
        (stern, bow) planes.
    alpha : float
        The environment's bow/stern allocation for ``control="dual"`` (0 otherwise).
    """

    name: str
    control: ControlMode
    alpha: float

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        """Start an episode: ``info`` is what ``env.reset`` returned, ``vehicle`` the design model."""
        ...

    def act(self, observation: np.ndarray) -> np.ndarray:
        """The action for ``observation`` (float32, in [-1, 1], shaped like the action space)."""
        ...


ControllerFactory = Callable[[], Controller]
_REGISTRY: dict[str, ControllerFactory] = {}


def register_controller(name: str, factory: ControllerFactory, *, overwrite: bool = False) -> None:
    """Make a controller available by name to :func:`make_controller` and ``subenv evaluate``."""
    if name in _REGISTRY and not overwrite:
        raise ValueError(f"controller {name!r} is already registered; pass overwrite=True to replace it")
    _REGISTRY[name] = factory


def controller_names() -> list[str]:
    """Names of the registered controllers, in registration order."""
    return list(_REGISTRY)


def make_controller(name: str) -> Controller:
    """A new controller by registered name; a ValueError lists the known names."""
    try:
        factory = _REGISTRY[name]
    except KeyError:
        raise ValueError(f"controller={name!r} is unknown: must be one of {controller_names()}") from None
    return factory()
