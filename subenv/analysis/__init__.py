"""Analysis of the dive-plane model: linear models and critical speeds."""

from subenv.analysis.critical import critical_froude, critical_speed, froude_number
from subenv.analysis.linear import LinearModel, linear_model, numerical_jacobian

__all__ = [
    "LinearModel",
    "critical_froude",
    "critical_speed",
    "froude_number",
    "linear_model",
    "numerical_jacobian",
]
