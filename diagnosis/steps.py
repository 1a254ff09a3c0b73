"""Steps in input signals, and the samples around them where derivative estimates cannot be trusted.

A square-wave voltage or a valve that snaps open is a discontinuity: the input itself jumps, and so
do the first derivatives of the states it drives.  A derivative estimator fits a smooth polynomial
over a window of samples; across a jump the fit is wrong for the whole window, and an ARR that uses
such an estimate (or holds the input beside a smoothed derivative) shows a spike of a healthy
system's residual at every step.  Those samples are left undecided (NaN) rather than judged.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

__all__ = ["STEP_SIGMAS", "STEP_SHARE", "step_indices", "step_mask"]

#: A jump between two samples is a step when it exceeds this many robust standard deviations of the
#: signal's sample-to-sample changes ...
STEP_SIGMAS = 8.0
#: ... and this share of the signal's range (a smooth input's changes per sample are far below it).
STEP_SHARE = 0.02


def step_indices(values: np.ndarray) -> np.ndarray:
    """Indices ``k`` where ``values`` jumps between samples ``k - 1`` and ``k``.

    Examples
    --------
    >>> t = np.linspace(0.0, 4.0, 401)
    >>> square = np.where((t >= 1.0) & (t < 3.0), 5.0, 0.0)
    >>> step_indices(square).tolist()
    [100, 300]
    >>> step_indices(np.sin(t)).tolist()
    []
    """
    x = np.asarray(values, float)
    if x.size < 3:
        return np.zeros(0, int)
    change = np.abs(np.diff(x))
    finite = change[np.isfinite(change)]
    if finite.size == 0:
        return np.zeros(0, int)
    spread = 1.4826 * float(np.median(np.abs(finite - np.median(finite))))
    span = float(np.nanmax(x) - np.nanmin(x))
    with np.errstate(invalid="ignore"):
        jump = (change > STEP_SIGMAS * spread) & (change > STEP_SHARE * span) & (change > 0)
    return np.flatnonzero(jump) + 1


def step_mask(columns: Mapping[str, np.ndarray], signals: Iterable[str], reach: int) -> np.ndarray:
    """True at the samples within ``reach`` samples of a step of any of ``signals`` in ``columns``.

    Examples
    --------
    >>> u = np.array([0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    >>> step_mask({"u": u, "t": np.arange(9.0)}, ["u"], 1).astype(int).tolist()
    [0, 0, 1, 1, 1, 1, 0, 0, 0]
    """
    size = len(columns["t"])
    mask = np.zeros(size, bool)
    for name in signals:
        for k in step_indices(columns[name]):
            # the jump lies between samples k - 1 and k: both sides are reached
            mask[max(k - 1 - reach, 0):min(k + reach + 1, size)] = True
    return mask
