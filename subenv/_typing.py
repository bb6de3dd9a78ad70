"""Type aliases shared across the package."""

from __future__ import annotations

from typing import TypeAlias, Union

import numpy as np
import numpy.typing as npt

FloatArray: TypeAlias = npt.NDArray[np.float64]
"""A float64 array (states are ``(..., 4)``: pitch, heave, pitch rate, depth)."""

ArrayLike: TypeAlias = Union[float, npt.ArrayLike]
"""A scalar or anything numpy turns into a float array."""
