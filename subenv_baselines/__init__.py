"""Classical depth controllers built on :mod:`subenv` only, registered with the evaluation harness.

- ``thesis``: the thesis's pole placement at 5 fps (Riedel 1993 Ch. II.B, eq. 2.98).
- ``scheduled``: the same pole placement repeated over a speed grid and interpolated.
- ``lqr``: LQR with integral action on the stern planes, scheduled over speed.
- ``reversal_aware``: LQR with integral action and a bow/stern allocation chosen to keep the
  critical speed away from the operating speed.
- ``mpc``: model-predictive control of both planes, re-linearised every period (needs the ``mpc``
  extra, DAQP; :data:`OPTIONAL_CONTROLLERS`).

Every controller designs itself from :mod:`subenv.analysis` (linear model, critical speed) at its
first reset, for the design vehicle the harness passes; none uses numbers typed in.

They reach :func:`subenv.evaluation.make_controller` and ``subenv evaluate`` through the
``subenv.controllers`` entry points of ``pyproject.toml`` (one per name of :data:`CONTROLLERS`),
the way any installed package adds its controllers; importing this package registers nothing.
(The name is prefixed: a top-level ``baselines`` is OpenAI Baselines' on PyPI.)
"""

from subenv_baselines.lqr import ScheduledLQR
from subenv_baselines.reversal_aware import ReversalAware
from subenv_baselines.scheduled import GainScheduledPolePlacement
from subenv_baselines.thesis import ThesisPolePlacement

CONTROLLERS: dict[str, type] = {
    "thesis": ThesisPolePlacement,
    "scheduled": GainScheduledPolePlacement,
    "lqr": ScheduledLQR,
    "reversal_aware": ReversalAware,
}

OPTIONAL_CONTROLLERS: dict[str, str] = {
    "mpc": "subenv_baselines.mpc:DepthMPC",
}
"""The controllers that need an optional dependency, as entry-point values (importing them here would make
the whole package need it): without their extra they are skipped with a one-line note."""

__all__ = [
    "CONTROLLERS",
    "OPTIONAL_CONTROLLERS",
    "GainScheduledPolePlacement",
    "ReversalAware",
    "ScheduledLQR",
    "ThesisPolePlacement",
]
