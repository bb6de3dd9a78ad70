"""The vertical-plane dynamics: one pure, batched right-hand side and its integrator."""

from subenv.dynamics.hull import HullTable, crossflow_integrals
from subenv.dynamics.integrate import CONTROL_PERIOD_S, SUBSTEPS, rk4, rk4_step
from subenv.dynamics.model import (
    STATE_NAMES,
    ModelParams,
    derivatives,
    dual_plane_angles,
    model_params,
    stack_params,
)

__all__ = [
    "CONTROL_PERIOD_S",
    "STATE_NAMES",
    "SUBSTEPS",
    "HullTable",
    "ModelParams",
    "crossflow_integrals",
    "derivatives",
    "dual_plane_angles",
    "model_params",
    "rk4",
    "rk4_step",
    "stack_params",
]
