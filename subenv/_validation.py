"""Argument checks shared by the package: each error names the parameter, its value and what is allowed.

A check runs before anything changes, raises ``ValueError`` and returns the value in its plain
Python type. Reals are Python and NumPy reals, never bools or strings; integers are Python and NumPy
integers; a value too large for a float (``10**400``) is refused with ``ValueError`` like any other.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = [
    "integer",
    "interval",
    "is_finite",
    "is_integer",
    "is_number",
    "mapping",
    "non_negative",
    "number",
    "positive",
    "real_array",
    "require",
    "seed",
]


def is_number(value: Any) -> bool:
    """A real number (Python or NumPy), not a bool."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_)
    )


def is_integer(value: Any) -> bool:
    """An integer (Python or NumPy), not a bool."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def is_finite(value: Any) -> bool:
    """A real number (see :func:`is_number`) that is neither infinite, nan nor too large for a float."""
    if not is_number(value):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an int beyond the float range, such as 10**400
        return False


def require(name: str, value: Any, ok: bool | np.bool_, allowed: str) -> None:
    """Raise ``ValueError("{name}={value!r} is invalid: must be {allowed}")`` unless ``ok``."""
    if not ok:
        raise ValueError(f"{name}={_shown(value)} is invalid: must be {allowed}")


def _shown(value: Any) -> str:
    """``repr(value)``; an integer beyond the float range by its size (its repr may be thousands of digits),
    also in a list or tuple."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > sys.float_info.max:
        return f"<an integer of {value.bit_length()} bits>"
    if type(value) in (list, tuple):
        shown = ", ".join(_shown(v) for v in value)
        return f"[{shown}]" if isinstance(value, list) else f"({shown}{',' if len(value) == 1 else ''})"
    return repr(value)


def number(name: str, value: Any, low: float = -math.inf, high: float = math.inf) -> float:
    """A finite number in [low, high]."""
    ok = is_finite(value) and low <= value <= high
    if math.isinf(low) and math.isinf(high):
        allowed = "a finite number"
    else:
        allowed = f"a finite number in [{low}, {high}]"
    require(name, value, ok, allowed)
    return float(value)


def positive(name: str, value: Any, upper: float = math.inf) -> float:
    """A finite number in (0, upper]."""
    ok = is_finite(value) and 0 < value <= upper
    require(
        name, value, ok, f"a finite number in (0, {upper}]" if math.isfinite(upper) else "a finite number > 0"
    )
    return float(value)


def non_negative(name: str, value: Any) -> float:
    """A finite number >= 0."""
    require(name, value, is_finite(value) and value >= 0, "a finite number >= 0")
    return float(value)


def integer(name: str, value: Any, low: int, high: int | None = None) -> int:
    """An integer (Python or NumPy, not a bool) in [low, high]."""
    ok = is_integer(value) and low <= value and (high is None or value <= high)
    require(name, value, ok, f"an integer in [{low}, {high}]" if high is not None else f"an integer >= {low}")
    return int(value)


def seed(name: str, value: Any) -> int | None:
    """A seed of ``reset(seed=...)``: None, or an integer >= 0 (Python or NumPy, not a bool) as a Python int.

    Gymnasium's ``np_random`` takes only a Python int >= 0 (it raises ``gymnasium.error.Error`` for a NumPy
    integer and a negative one; a bool it takes as 0 or 1): the environments give it this one, so that
    ``np.int64(3)`` draws what ``3`` draws.
    """
    require(name, value, value is None or (is_integer(value) and value >= 0), "None or an integer >= 0")
    return None if value is None else int(value)


def mapping(name: str, value: Any) -> dict[str, Any]:
    """None (empty) or a mapping (a dict), as a new dict: ``reset(options=...)``."""
    require(name, value, value is None or isinstance(value, Mapping), "None or a dict")
    return dict(value) if value is not None else {}


def interval(name: str, value: Any, low: float = -math.inf, high: float = math.inf) -> tuple[float, float]:
    """A ``(low, high)`` pair of finite numbers within [low, high], its first at most its second."""
    ok = (
        isinstance(value, tuple)
        and len(value) == 2
        and all(is_finite(v) for v in value)
        and low <= value[0] <= value[1] <= high
    )
    require(name, value, ok, f"a (low, high) pair of finite numbers with {low} <= low <= high <= {high}")
    return float(value[0]), float(value[1])


def real_array(name: str, value: Any) -> np.ndarray:
    """``value`` as a float64 array of real numbers (Python or NumPy; not bools, complex numbers,
    strings or a ragged sequence)."""
    try:
        array = np.asarray(value)
    except (ValueError, TypeError):  # a ragged sequence
        raise ValueError(
            f"{name}={value!r} is invalid: must be an array of real numbers of one shape"
        ) from None
    if array.dtype.kind not in "iuf":
        raise ValueError(f"{name}={value!r} is invalid: must hold real numbers (it holds {array.dtype})")
    return array.astype(np.float64, copy=False)
