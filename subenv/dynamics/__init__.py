"""The vertical-plane dynamics: one pure, batched right-hand side and its integrator.

For users: :func:`derivatives` (d/dt of the state for any batch of states, inputs and loadings;
:func:`derivatives_with` the same with the loading fixed, for a solver's one-state calls),
:func:`model_params` (a vehicle reduced to the model's numbers; :func:`stack_params` for a batch of
loadings), :func:`rk4` (the reference integrator), :func:`control_period` (the environments' compiled
integrator over one control period, for any batch of states), :func:`dual_plane_angles` (eq. 2.58) and
:func:`crossflow_integrals` (the hull's cross-flow drag). The compiled kernels the environments run
(:mod:`subenv.dynamics.model`, :mod:`~subenv.dynamics.hull`, :mod:`~subenv.dynamics.integrate`) are
in the submodules.
"""

from subenv.dynamics.hull import HullTable, crossflow_integrals
from subenv.dynamics.integrate import CONTROL_PERIOD_S, SUBSTEPS, control_period, rk4
from subenv.dynamics.model import (
    ModelParams,
    derivatives,
    derivatives_with,
    dual_plane_angles,
    model_params,
    stack_params,
)

__all__ = [
    "CONTROL_PERIOD_S",
    "SUBSTEPS",
    "HullTable",
    "ModelParams",
    "control_period",
    "crossflow_integrals",
    "derivatives",
    "derivatives_with",
    "dual_plane_angles",
    "model_params",
    "rk4",
    "stack_params",
]
