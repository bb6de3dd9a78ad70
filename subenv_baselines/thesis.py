"""The thesis's controller: full-state feedback placed once at 5 fps (Riedel 1993 Ch. II.B)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from subenv.analysis import thesis_gain
from subenv.evaluation import SingleRowMixin
from subenv.vehicles import Vehicle
from subenv_baselines._common import feedback_state, row_dot


class ThesisPolePlacement(SingleRowMixin):
    """delta = -K (theta, w, q, Z - Z_cmd), K placed at 5 fps with poles (-0.3, -0.31, -0.32, -0.33).

    Designed once from the linear model of :mod:`subenv.analysis` (the gains of eq. 2.98, in SI)
    and never changed: it holds depth at its design speed and, below the critical speed, drives
    the boat to the pitched, plane-saturated equilibrium of Ch. III (dual control, alpha = 0).
    """

    name = "thesis"
    control = "dual"
    alpha = 0.0

    def __init__(self) -> None:
        self._gain: np.ndarray | None = None
        self._vehicle: Vehicle | None = None
        self._limit = 0.4

    @property
    def gain(self) -> np.ndarray:
        """K of (theta, w, q, Z - Z_cmd), in SI units, placed for the last reset's vehicle."""
        if self._gain is None:
            raise RuntimeError("call reset() first: the gain is designed for the episode's vehicle")
        return self._gain

    def reset_batch(self, infos: Sequence[Mapping[str, Any]], vehicle: Vehicle) -> None:
        """Place the gain for ``vehicle`` unless it is the vehicle already designed for (the controller
        keeps no per-episode state, so ``infos`` is not read)."""
        if vehicle is not self._vehicle:  # design once per design model
            self._gain = thesis_gain(vehicle, self.alpha)
            self._vehicle = vehicle
            self._limit = vehicle.planes.limit_rad

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """The normalised stern-plane command of every episode, shape (N, 1): -K x clipped to the limit."""
        delta = -row_dot(self.gain, feedback_state(observations))
        return np.clip(delta / self._limit, -1.0, 1.0).astype(np.float32)[:, None]
