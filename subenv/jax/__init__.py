"""subenv's physics traced by JAX, from the same source that numba compiles (the ``jax`` extra).

The vertical-plane dynamics of :mod:`subenv.dynamics` are written once, as scalar functions. numba
compiles them for the environments; this package hands the very same functions (their code, not a
copy of it) to JAX, with their names re-bound to JAX's operations (:func:`traced`), so that they run
under ``jax.jit`` and ``jax.vmap``, on a CPU or an accelerator:

- :func:`~subenv.jax.dynamics.derivatives`: d/dt of the state, batched as
  :func:`subenv.dynamics.derivatives`;
- :func:`~subenv.jax.dynamics.control_period`: one control period of the environments' integrator
  (:func:`subenv.dynamics.rk4` over the right-hand side), batched, in a sea if given one;
- :func:`make`: a registered id as a functional environment with gymnax 1.0's interface
  (:class:`DivePlaneJaxEnv`: ``reset(key, params)``, ``step(key, state, action, params)`` with the
  reset of ended episodes by a select and ``info["final_observation"]``), whose transition is
  :mod:`subenv.envs.transition`'s own functions, traced, and whose episodes are the Gymnasium
  environment's, drawn ahead into a table (:class:`EnvParams`) by the scenarios' own code; its
  states and episodes carry the environment they were made for (:class:`MadeFor`).

They agree with the compiled ones to about 1e-14, not bit for bit: XLA contracts multiply-adds and
rewrites divisions by constants (``tests/jax/test_dynamics.py`` holds them within 1e-12 over 20
control periods). Importing this package turns on JAX's 64-bit mode (``jax_enable_x64``): the
physics is written for float64.

On two CPU cores the compiled vector environment steps many times faster (``benchmarks/jax_env.py``):
this path is for accelerators, with a learner in the same compiled program.
"""

from __future__ import annotations

from subenv.extras import require

require("jax", "the physics on JAX (subenv.jax)", "jax")

# (The imports follow the extra's check, for its clear error, and 64-bit mode precedes subenv's own.)
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from subenv.jax._trace import traced  # noqa: E402
from subenv.jax.dynamics import control_period, derivatives  # noqa: E402
from subenv.jax.env import N_NORMALS, DivePlaneJaxEnv, EnvParams, EnvState, Episode, MadeFor, make  # noqa: E402

__all__ = [
    "N_NORMALS",
    "DivePlaneJaxEnv",
    "EnvParams",
    "EnvState",
    "Episode",
    "MadeFor",
    "control_period",
    "derivatives",
    "make",
    "traced",
]
