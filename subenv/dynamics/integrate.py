"""Fixed-step fourth-order Runge-Kutta integration of the dynamics.

The environments hold the planes and the external force constant over a control step (zero-order
hold) and integrate that step with ``substeps`` classical RK4 steps. The step was chosen by the
accuracy tests in ``tests/dynamics/test_integrator.py``, which compare against
``scipy.integrate.solve_ivp`` at rtol 1e-10 over 600 s trajectories.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Final

from subenv._typing import FloatArray

__all__ = ["CONTROL_PERIOD_S", "SUBSTEPS", "rk4", "rk4_step"]

CONTROL_PERIOD_S: Final = 0.5
"""Default control period of the environments [s]."""

SUBSTEPS: Final = 2
"""Default RK4 steps per control period (step 0.25 s): worst error over 600 s, 0.15-1.8 m/s, open
and closed loop, below 1 mm in depth and 1e-5 rad in pitch (``tests/dynamics/test_integrator.py``)."""

Rhs = Callable[[float, FloatArray], FloatArray]
"""Right-hand side f(t, x) -> dx/dt, batched over the leading axes of x."""


def rk4_step(f: Rhs, t: float, x: FloatArray, dt: float) -> FloatArray:
    """One classical RK4 step of size ``dt`` from (t, x)."""
    k1 = f(t, x)
    k2 = f(t + 0.5 * dt, x + (0.5 * dt) * k1)
    k3 = f(t + 0.5 * dt, x + (0.5 * dt) * k2)
    k4 = f(t + dt, x + dt * k3)
    return x + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)


def rk4(f: Rhs, t: float, x: FloatArray, dt: float, substeps: int) -> FloatArray:
    """Integrate from t to t + dt with ``substeps`` equal RK4 steps."""
    h = dt / substeps
    for i in range(substeps):
        x = rk4_step(f, t + i * h, x, h)
    return x
