"""A controller's failure: where it failed, on which episodes, and why, in one line.

A controller that raises in ``reset``, ``act`` (or their batch versions), or returns an action the
environment refuses (NaN, None, a wrong shape), fails: the harness raises :class:`ControllerError`,
whose :class:`ControllerFailure` names the controller, the scenario, the seed (the seeds of the
batch, when the failure is the batch's) and the error in one line.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

from subenv.evaluation.controller import Controller

__all__ = ["Blame", "ControllerError", "ControllerFailure", "one_line"]


@dataclass(frozen=True)
class ControllerFailure:
    """A controller that failed on a scenario: where, on which episodes, and why.

    The harness stops running the controller on that scenario (its episodes there are not kept); the
    one-line :attr:`message` is what ``subenv evaluate`` prints and records.
    """

    controller: str
    scenario: str
    seeds: tuple[int, ...]
    """The episodes it failed on: the one episode run alone, or the batch's rows whose actions the
    environment refused (NaN or inf); every episode of the batch when the failure is the whole batch's
    (an exception in ``reset_batch`` or ``act_batch``, actions of the wrong type or shape)."""
    call: str
    """The controller's method: ``reset``, ``act``, ``reset_batch`` or ``act_batch``."""
    step: int | None
    """The step whose action failed (1: the first action after the reset); None in a reset."""
    error: str
    """The exception it raised (``"RuntimeError: ..."``), or the environment's refusal of its action
    (``"action=[nan] is invalid: must be finite (no NaN or inf)"``), on one line."""

    @property
    def message(self) -> str:
        """One line: ``controller 'x' failed on LowSpeed, seed 10000, in act at step 3: <error>``."""
        where = self.call if self.step is None else f"{self.call} at step {self.step}"
        return (
            f"controller {self.controller!r} failed on {self.scenario}, {_seeds_text(self.seeds)}, in "
            f"{where}: {self.error}"
        )

    def __str__(self) -> str:
        return self.message


class ControllerError(RuntimeError):
    """A controller failed (:class:`ControllerFailure`, in :attr:`failure`); the message is its one line,
    and the exception the controller raised, if any, is the ``__cause__``."""

    def __init__(self, failure: ControllerFailure) -> None:
        super().__init__(failure)  # (the one argument: the exception pickles, as a Ray task's error does)
        self.failure = failure

    def __str__(self) -> str:
        return self.failure.message


def _seeds_text(seeds: Sequence[int]) -> str:
    """``seed 3``, ``seeds 3-9`` (consecutive) or ``seeds 3, 5, 8``."""
    if len(seeds) == 1:
        return f"seed {seeds[0]}"
    if list(seeds) == list(range(seeds[0], seeds[0] + len(seeds))):
        return f"seeds {seeds[0]}-{seeds[-1]}"
    return "seeds " + ", ".join(str(s) for s in seeds)


def one_line(text: str) -> str:
    """``text`` with its line breaks (a plugin's multi-line message) made spaces."""
    return " ".join(line.strip() for line in text.strip().splitlines() if line.strip())


_T = TypeVar("_T")


@dataclass(frozen=True)
class Blame:
    """Whose episodes run now: a failure of a controller's call there is reported with these."""

    controller: Controller
    scenario: str
    seeds: tuple[int, ...]

    def call(self, method: str, step: int | None, function: Callable[..., _T], *args: Any) -> _T:
        """``function(*args)``, the controller's ``method``; any exception it raises is its failure."""
        try:
            return function(*args)
        except Exception as exc:
            text = one_line(str(exc))
            raise self.failed(
                method, step, f"{type(exc).__name__}: {text}" if text else type(exc).__name__
            ) from exc

    def failed(
        self, method: str, step: int | None, error: str, seeds: Sequence[int] | None = None
    ) -> ControllerError:
        """The error of the controller's ``method`` failing with ``error``, on ``seeds`` if known (the rows
        the environment refused), otherwise on every episode it runs now."""
        return ControllerError(
            ControllerFailure(
                controller=self.controller.name,
                scenario=self.scenario,
                seeds=self.seeds if not seeds else tuple(seeds),
                call=method,
                step=step,
                error=error,
            )
        )
