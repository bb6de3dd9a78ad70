"""The controller interface shared by classical baselines and trained agents, and its registry.

A controller maps an observation to an action in [-1, 1]. It declares which action space it drives
(``control`` and ``alpha`` are passed to the environment), and is told at every episode start what
the environment reports (``info`` at reset: speed, critical speed, depth command, ...) and the
vehicle it was designed for. It never reads the environment's internals.

A controller may also act on a batch of episodes at once (:class:`BatchController`:
``reset_batch`` with one ``info`` per episode, then ``act_batch`` on an ``(N, obs_dim)`` array of
observations, one row per episode, keeping any per-episode state, such as an integrator, per
row). The harness then steps all the episodes of a scenario together in one vector environment;
a controller without the batch methods is run one episode at a time. :class:`SingleRowMixin`
gives a batch controller its single-episode ``reset`` and ``act``, so that there is one copy of
the control law.

A controller may also be told the environment's settings (:class:`InformedController`: an ``inform``
method). The harness calls it before the episodes of each scenario with that scenario's settings (the
planes' rate limit, the pitch limit, the control period, ...:
:func:`subenv.evaluation.environments.env_settings`), so that a controller that designs for the limits
(the MPC) meets the environment it runs in; a controller without the method is not told, and
:func:`uninformed` runs one that has it without telling it. Whether a controller was told is in its
results (``informed``) and its leaderboard row.

Controllers come from other packages, never from ``subenv`` itself (which imports none of them):

- an installed package declares each of its controllers in the ``subenv.controllers`` entry-point
  group, the name being the controller's and the value a zero-argument factory (a class will do)::

      [project.entry-points."subenv.controllers"]
      my_pid = "my_package.pid:DepthPID"

  :func:`controller_names` and :func:`make_controller` load them the first time they are called
  (:func:`discover_controllers`); this is how the classical baselines (``subenv_baselines``) and the
  shipped agents (``subenv_agents``) of this distribution arrive;
- a module on the path calls :func:`register_controller` when it is imported (``subenv evaluate
  --plugins``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from importlib.metadata import EntryPoint, entry_points
from typing import Any, Final, Literal, Protocol, runtime_checkable

import numpy as np

from subenv.vehicles.vehicle import Vehicle

__all__ = [
    "ENTRY_POINT_GROUP",
    "UNINFORMED_SUFFIX",
    "BatchController",
    "Controller",
    "ControllerFactory",
    "InformedController",
    "SingleRowMixin",
    "Uninformed",
    "check_batch",
    "controller_names",
    "discover_controllers",
    "informed",
    "make_controller",
    "register_controller",
    "uninformed",
]

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


@runtime_checkable
class BatchController(Controller, Protocol):
    """A :class:`Controller` that also acts on N episodes at once, one row each.

    Row ``i`` of every ``act_batch`` call belongs to the episode of ``infos[i]`` given to the last
    ``reset_batch``, and its action must be what ``reset(infos[i], vehicle)`` then ``act`` on that
    row's observations would give (the harness's results do not depend on the batch size:
    ``tests/evaluation/test_batched_harness.py``). The row of an episode that has ended keeps
    coming, with the observations of an episode nobody records, until the batch's last episode
    ends: its actions are ignored, but must be finite.
    """

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Start ``len(infos)`` episodes: ``infos[i]`` is episode i's reset ``info`` (as ``reset`` gets
        it)."""
        ...

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """Actions for ``observations`` of shape (N, obs_dim), one row per episode: shape (N, n_actions),
        float32 in [-1, 1]."""
        ...


@runtime_checkable
class InformedController(Controller, Protocol):
    """A :class:`Controller` that is told the environment's settings before it runs a scenario."""

    def inform(self, settings: Mapping[str, Any]) -> None:
        """Take the settings of the environment the next episodes run in: every argument of
        :class:`~subenv.envs.DivePlaneEnv` but the scenario, vehicle, control and alpha
        (:func:`subenv.evaluation.environments.env_settings`: ``dt``, ``substeps``,
        ``plane_rate_limit_radps``, ``max_pitch_rad``, ``max_depth_error_m`` (None: the environment's
        default for the vehicle), ...), each with its value there."""
        ...


def informed(controller: Controller) -> bool:
    """Whether the harness tells ``controller`` the environment's settings (it has ``inform``)."""
    return isinstance(controller, InformedController)


UNINFORMED_SUFFIX: Final = ":uninformed"
"""The name of a controller run without being told the settings is its own with this suffix
(``mpc:uninformed``); :func:`~subenv.evaluation.rollout.resolve_controllers` makes one from that name."""


class Uninformed:
    """``controller`` as it is, but never told the environment's settings (it keeps its own defaults).

    Named ``<name>:uninformed``, so that it can run beside the informed original in one comparison; it
    acts on batches when the original does.
    """

    def __init__(self, controller: Controller) -> None:
        self.controller = controller
        self.name = controller.name + UNINFORMED_SUFFIX
        self.control = controller.control
        self.alpha = controller.alpha

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        """The original's ``reset``."""
        self.controller.reset(info, vehicle)

    def act(self, observation: np.ndarray) -> np.ndarray:
        """The original's ``act``."""
        return self.controller.act(observation)

    def __getattr__(self, name: str) -> Any:
        # The batch methods are the original's where it has them (so isinstance(..., BatchController)
        # tells the truth); never its inform.
        if name in ("reset_batch", "act_batch"):
            return getattr(self.controller, name)
        raise AttributeError(name)


def uninformed(controller: Controller) -> Uninformed:
    """``controller`` run without being told the environment's settings (:class:`Uninformed`)."""
    if isinstance(controller, Uninformed):
        return controller
    return Uninformed(controller)


class SingleRowMixin:
    """``reset`` and ``act`` of a :class:`BatchController` as batches of one row."""

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        """``reset_batch([info], vehicle)``."""
        self.reset_batch([info], vehicle)  # type: ignore[attr-defined]

    def act(self, observation: np.ndarray) -> np.ndarray:
        """The one row of ``act_batch`` on ``observation`` as a batch of one."""
        action: np.ndarray = self.act_batch(np.asarray(observation)[None])[0]  # type: ignore[attr-defined]
        return action


def check_batch(observations: np.ndarray, rows: int) -> np.ndarray:
    """``observations`` as an array, checked to have shape (rows, obs_dim): one row per episode started
    by the last ``reset_batch`` (ValueError otherwise)."""
    obs = np.asarray(observations)
    if obs.ndim != 2 or obs.shape[0] != rows:
        raise ValueError(
            f"observations has shape {obs.shape}: must have shape ({rows}, obs_dim), one row per episode "
            "of the last reset_batch"
        )
    return obs


ControllerFactory = Callable[[], Controller]
_REGISTRY: dict[str, ControllerFactory] = {}

ENTRY_POINT_GROUP: Final = "subenv.controllers"
"""The entry-point group in which installed packages declare their controllers (name = factory)."""

_UNAVAILABLE: dict[str, str] | None = None
"""Declared controllers that could not be loaded, with the reason; None until the first discovery."""


def register_controller(name: str, factory: ControllerFactory, *, overwrite: bool = False) -> None:
    """Make a controller available by name to :func:`make_controller` and ``subenv evaluate``."""
    if name in _REGISTRY and not overwrite:
        raise ValueError(f"controller {name!r} is already registered; pass overwrite=True to replace it")
    _REGISTRY[name] = factory


def discover_controllers(declared: Iterable[EntryPoint] | None = None) -> dict[str, str]:
    """Register the controllers declared as entry points, and say which could not be loaded.

    Parameters
    ----------
    declared : iterable of importlib.metadata.EntryPoint, optional
        The declarations to load (default, and what :func:`controller_names` uses the first time:
        the :data:`ENTRY_POINT_GROUP` of every installed distribution). A name that is already
        registered keeps its factory.

    Returns
    -------
    dict of str to str
        The declared controllers whose module could not be imported (an optional dependency not
        installed), by name, with the error: every declaration so far. They are skipped, not
        registered; the message of the error is the package's advice (which extra to install).
    """
    global _UNAVAILABLE
    unavailable = {} if _UNAVAILABLE is None else _UNAVAILABLE
    for point in entry_points(group=ENTRY_POINT_GROUP) if declared is None else declared:
        if point.name in _REGISTRY:
            continue
        try:
            register_controller(point.name, point.load())
        except ImportError as exc:
            unavailable[point.name] = str(exc)
        else:
            unavailable.pop(point.name, None)
    _UNAVAILABLE = unavailable
    return dict(unavailable)


def _discover_once() -> None:
    if _UNAVAILABLE is None:
        discover_controllers()


def controller_names() -> list[str]:
    """Names of the registered controllers, in registration order (the installed ones on first use)."""
    _discover_once()
    return list(_REGISTRY)


def make_controller(name: str) -> Controller:
    """A new controller by registered name.

    The name it is registered under is its identity: the results, the tables and the replays of the
    plots know a controller by its ``name`` attribute, so a factory whose controller calls itself
    anything else (a plugin declared as ``liar`` making a controller named ``lqr``, which would
    publish rows under another controller's name) is refused.

    Raises
    ------
    ValueError
        ``name`` is not registered (the message lists the known names), or the controller's ``name``
        attribute is not ``name``.
    """
    _discover_once()
    try:
        factory = _REGISTRY[name]
    except KeyError:
        raise ValueError(f"controller={name!r} is unknown: must be one of {controller_names()}") from None
    controller = factory()
    own = getattr(controller, "name", None)
    if own != name:
        raise ValueError(
            f"controller {name!r} is invalid: its name attribute is {own!r}, and must be {name!r}, the name "
            "it is registered under (results are published by name)"
        )
    return controller
