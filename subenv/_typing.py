"""Type aliases shared across the package."""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
import numpy.typing as npt

FloatArray: TypeAlias = npt.NDArray[np.float64]
"""A float64 array (states are ``(..., 4)``: pitch, heave, pitch rate, depth)."""

ArrayLike: TypeAlias = float | npt.NDArray[np.float64]
"""A float, or a float64 array that broadcasts against the batch."""
