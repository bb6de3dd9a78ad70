"""The vertical-plane dynamics: one pure, batched right-hand side and its integrator."""

from subenv.dynamics.hull import HullTable, crossflow_integrals, crossflow_point
from subenv.dynamics.integrate import CONTROL_PERIOD_S, SUBSTEPS, control_period_point, rk4, rk4_step
from subenv.dynamics.model import (
    PARAM_FIELDS,
    ModelParams,
    derivatives,
    dual_plane_angles,
    model_params,
    pack_params,
    rhs_point,
    stack_params,
)

__all__ = [
    "CONTROL_PERIOD_S",
    "PARAM_FIELDS",
    "SUBSTEPS",
    "HullTable",
    "ModelParams",
    "control_period_point",
    "crossflow_integrals",
    "crossflow_point",
    "derivatives",
    "dual_plane_angles",
    "model_params",
    "pack_params",
    "rhs_point",
    "rk4",
    "rk4_step",
    "stack_params",
]
