"""Classical depth controllers built on :mod:`subenv` only, registered with the evaluation harness.

- ``thesis``: the thesis's pole placement at 5 fps (Riedel 1993 Ch. II.B, eq. 2.98).
- ``scheduled``: the same pole placement repeated over a speed grid and interpolated.
- ``lqr``: LQR with integral action on the stern planes, scheduled over speed.
- ``reversal_aware``: LQR with integral action and a bow/stern allocation chosen to keep the
  critical speed away from the operating speed.

Every controller designs itself from :mod:`subenv.analysis` (linear model, critical speed) at its
first reset, for the design vehicle the harness passes; none uses numbers typed in.
"""

from baselines.lqr import ScheduledLQR
from baselines.reversal_aware import ReversalAware
from baselines.scheduled import GainScheduledPolePlacement
from baselines.thesis import ThesisPolePlacement
from subenv.evaluation import controller_names, register_controller

CONTROLLERS = {
    "thesis": ThesisPolePlacement,
    "scheduled": GainScheduledPolePlacement,
    "lqr": ScheduledLQR,
    "reversal_aware": ReversalAware,
}

for _name, _cls in CONTROLLERS.items():
    if _name not in controller_names():
        register_controller(_name, _cls)

__all__ = ["CONTROLLERS", "GainScheduledPolePlacement", "ReversalAware", "ScheduledLQR", "ThesisPolePlacement"]
