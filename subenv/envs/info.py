"""The environments' ``info``, from a step's report (:data:`subenv.envs.transition.REPORT_KEYS`).

The values are computed once, in the transition; these functions only name them: a dict of
floats for one sub-environment (:func:`step_info`), Gymnasium's vector form for many
(:func:`step_infos`).
"""

from __future__ import annotations

from typing import Any, Final

import numpy as np

from subenv.envs import transition as tr

__all__ = ["INFO_KEYS", "step_info", "step_infos"]

_REASON: Final = tr.REPORT_KEYS.index("reason")
INFO_KEYS: Final = (*tr.REPORT_KEYS[:_REASON], "termination_reason")
"""The keys of a step's ``info``: the report's rows before the reason code, then the reason's name."""
_VALUE_KEYS: Final = INFO_KEYS[:-1]
_MASK_KEYS: Final = tuple("_" + key for key in INFO_KEYS)
_REASONS: Final = np.array(tr.REASONS, dtype=object)
_COPY_REASONS_FROM: Final = 1024
"""From this many sub-environments the termination reasons start as a copy of an array of "" (below it
a ``take`` costs less)."""


def step_info(values: list[float]) -> dict[str, Any]:
    """The ``info`` of one sub-environment from its report column (as a list of floats)."""
    # Not strict: the column goes on past the value keys (the reason code, the reward and the end), and
    # zip stops at the last key.
    info: dict[str, Any] = dict(zip(_VALUE_KEYS, values, strict=False))
    info["termination_reason"] = tr.REASONS[int(values[_REASON])]
    return info


def step_infos(
    report: np.ndarray, mask: np.ndarray | None = None, no_reasons: np.ndarray | None = None
) -> dict[str, Any]:
    """Gymnasium's vector ``info`` from a report (its rows are handed out): every key an array over
    the sub-environments, with its ``"_" + key`` mask; with ``mask``, only those sub-environments
    report and the others are zero (None for strings), as in ``SyncVectorEnv``.

    ``no_reasons``: an array of ``""`` as long as the report, to copy from (saves a ``take`` at large N).
    """
    n = report.shape[1]
    values = list(report[:_REASON])
    codes = report[_REASON]
    if no_reasons is None or n < _COPY_REASONS_FROM:
        reasons = _REASONS.take(codes.astype(np.intp))
    else:
        ended = np.flatnonzero(codes != 0.0)
        reasons = no_reasons.copy()
        reasons[ended] = _REASONS.take(codes[ended].astype(np.intp))
    values.append(reasons)
    if mask is None:
        masks = np.ones((len(INFO_KEYS), n), dtype=bool)
    else:
        for value in values:
            value[~mask] = None if value.dtype == object else 0.0
        masks = np.tile(mask, (len(INFO_KEYS), 1))
    infos: dict[str, Any] = dict(zip(INFO_KEYS, values, strict=True))
    infos.update(zip(_MASK_KEYS, masks, strict=True))
    return infos
