"""Outward rounding of interval bounds, and the bookkeeping of :class:`IntervalWarning`.

A bound computed by one correctly rounded operation (``+ - * /``, ``sqrt``) moves
one ulp outward (:func:`down`, :func:`up`); a bound computed by numpy's
transcendental functions moves out by the margin of :data:`TRANSCENDENTAL_ULPS`
(:func:`down_transcendental`, :func:`up_transcendental`). The package docstring
of :mod:`diagnosis.intervals` gives the reasons for both.

Warnings raised by the kernels inside one evaluation (:func:`guarded`) are
summed per message (:func:`warn`) and issued once at its end.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from contextvars import ContextVar
from typing import Any

import numpy as np

from bondgraph.errors import PHMWarning

__all__ = [
    "EPS", "TRANSCENDENTAL_ULPS", "IntervalWarning", "down", "down_transcendental", "guarded", "rounded",
    "sanitize", "up", "up_transcendental", "warn",
]

TRANSCENDENTAL_ULPS = 4
"""Assumed worst error, in ulps, of numpy's exp, log, tanh, sin, cos and power."""

EPS = float(np.finfo(float).eps)  # 2**-52, the ulp of 1.0
_TINY = 5e-324  # 2**-1074, the smallest subnormal: the ulp near 0
_MAX = float(np.finfo(float).max)
_INF = math.inf
# Doubled so that the margin holds when the exact value lies across a power of two.
_TRANS_REL = (2 * TRANSCENDENTAL_ULPS + 1) * EPS
_TRANS_SUB = (TRANSCENDENTAL_ULPS + 1) * _TINY
_SHORT = 256  # up to this size, up and down call nextafter (fewer calls); beyond, bit operations (faster)


class IntervalWarning(PHMWarning, RuntimeWarning):
    """An interval operation left its domain and returned a widened, still sound, result."""


def _step_up(a: np.ndarray) -> np.ndarray:
    """One float up, in place, for finite ``a`` or ``-inf``, with ``-0.0`` already ``+0.0``.

    Non-negative floats order like their int64 bit patterns, negative ones in
    reverse, so the successor adds 1 to the pattern of a positive float and
    subtracts 1 from that of a negative one.
    """
    bits = a.view(np.int64)
    step = bits >> 63  # -1 for negative floats, 0 otherwise
    step |= 1
    bits += step
    return a


def _next_short(x, toward: float) -> np.ndarray:
    """``np.nextafter(x, toward)`` with NaN sent to ``toward``: the same floats as the bit operations.

    ``fmin(x, inf)`` (``fmax(x, -inf)`` going down) is ``x`` itself, or ``toward`` for a NaN, whose
    step toward itself stays there: two calls with no test of the values.  For a short array the
    calls are the cost; for a long one the bit operations are faster than libm's ``nextafter`` per
    element.  Stepping the largest float to ``inf`` raises numpy's overflow flag (a warning outside
    :func:`guarded`, where the kernels run).
    """
    known = np.fmin(x, toward) if toward > 0 else np.fmax(x, toward)
    return np.nextafter(known, toward)


def up(x):
    """``np.nextafter(x, +inf)``: one ulp up (exact; a bit operation, not a libm call per element).

    An unknown (NaN) value gets the sound upper bound ``+inf``: stepping a NaN's bit pattern could
    wrap it to ``-0.0`` (``0x7fff...f + 1``), a finite bound for a missing sample, and which NaN
    pattern an array holds depends on numpy's loops, hence on the array's length.

    >>> up(np.array([1.0, np.nan, -np.inf])).tolist()
    [1.0000000000000002, inf, -1.7976931348623157e+308]
    """
    if np.ndim(x) == 0:
        return np.nextafter(np.float64(x), _INF) if not np.isnan(x) else np.float64(_INF)
    if np.size(x) <= _SHORT:
        return _next_short(x, _INF)
    a = np.fmin(x, _MAX)  # MAX steps to +inf, as nextafter(+inf, +inf) = +inf; NaN becomes MAX, hence +inf
    a += 0.0  # -0.0 + 0.0 = +0.0, whose successor is the smallest subnormal
    return _step_up(a)


def down(x):
    """``np.nextafter(x, -inf)``, as ``-nextafter(-x, +inf)``; ``-inf`` for NaN (see :func:`up`).

    >>> down(np.array([1.0, np.nan])).tolist()
    [0.9999999999999999, -inf]
    """
    if np.ndim(x) == 0:
        return np.nextafter(np.float64(x), -_INF) if not np.isnan(x) else np.float64(-_INF)
    if np.size(x) <= _SHORT:
        return _next_short(x, -_INF)
    a = np.negative(x)
    np.fmin(a, _MAX, out=a)
    a += 0.0
    return np.negative(_step_up(a), out=a)


def _widen_down(x, rel: float, sub: float):
    """A lower bound at least ``rel |x| + sub`` below ``x`` (several ulps at once).

    ``rel`` must exceed the relative error of ``x`` by one ``eps``: then the exact
    difference lies below the float just under the true value, and rounding to
    nearest cannot pass it.
    """
    x = np.minimum(x, _MAX)  # an overflowed lower bound (+inf) becomes the largest float
    w = np.abs(x) * rel
    w += sub
    return x - w


def _widen_up(x, rel: float, sub: float):
    """An upper bound at least ``rel |x| + sub`` above ``x``; mirror of :func:`_widen_down`."""
    x = np.maximum(x, -_MAX)
    w = np.abs(x) * rel
    w += sub
    return x + w


def down_transcendental(x):
    """Lower bound of a transcendental result (see :data:`TRANSCENDENTAL_ULPS`)."""
    return _widen_down(x, _TRANS_REL, _TRANS_SUB)


def up_transcendental(x):
    """Upper bound of a transcendental result (see :data:`TRANSCENDENTAL_ULPS`)."""
    return _widen_up(x, _TRANS_REL, _TRANS_SUB)


def rounded(x) -> tuple[Any, Any]:
    """Enclose a value computed by one correctly rounded operation."""
    return down(x), up(x)


# Warnings raised inside one evaluation are summed and issued once at its end.
_PENDING: ContextVar[dict | None] = ContextVar("_PENDING", default=None)


def warn(template: str, count: int) -> None:
    """Record ``count`` elements for ``template`` (which has a ``{count}`` field)."""
    pending = _PENDING.get()
    if pending is None:
        warnings.warn(template.format(count=count), IntervalWarning, stacklevel=4)
    else:
        pending[template] = pending.get(template, 0) + count


def guarded(compute: Callable[[], Any], stacklevel: int):
    """Run ``compute()`` with numpy's float warnings off, then issue the IntervalWarnings.

    ``stacklevel`` counts from the caller of this function, as in ``warnings.warn``.
    """
    pending: dict = {}
    token = _PENDING.set(pending)
    try:
        with np.errstate(all="ignore"):  # inf and NaN are handled explicitly
            result = compute()
    finally:
        _PENDING.reset(token)
    for template, count in pending.items():
        warnings.warn(template.format(count=count), IntervalWarning, stacklevel=stacklevel + 1)
    return result


def sanitize(lo, hi) -> tuple[Any, Any]:
    """Replace NaN bounds (e.g. ``0 * inf`` of infinite points) by the sound hull."""
    if np.isnan(lo).any():
        lo = np.where(np.isnan(lo), -_INF, lo)
    if np.isnan(hi).any():
        hi = np.where(np.isnan(hi), _INF, hi)
    return lo, hi
