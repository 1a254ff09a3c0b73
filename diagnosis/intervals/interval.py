"""The interval types :class:`Interval` and :class:`IntervalArray`, and their operators.

Both run the pair kernels of :mod:`~diagnosis.intervals.kernels` under
:func:`~diagnosis.intervals.rounding.guarded` (:func:`apply`), so numpy's float
warnings are off and the :class:`~diagnosis.intervals.IntervalWarning` of one
operation is issued once. Operands may be intervals, numbers or arrays (exact
points); the result is an :class:`Interval` when every operand is a scalar, an
:class:`IntervalArray` of the broadcast shape otherwise.
"""

from __future__ import annotations

import math
from typing import Union

import numpy as np

from . import kernels, rounding
from .kernels import Pair

__all__ = ["Interval", "IntervalArray", "Number", "apply", "fit", "trusted_array", "trusted_interval"]

Number = Union[int, float, np.integer, np.floating]

_INF = math.inf


def _as_pair(x) -> tuple[Pair, tuple[int, ...] | None]:
    """Operand as a (lo, hi) pair and its shape (None for a scalar)."""
    if isinstance(x, Interval):
        return (np.float64(x.lo), np.float64(x.hi)), None
    if isinstance(x, IntervalArray):
        return (x.lo, x.hi), x.shape
    if isinstance(x, (int, float, np.integer, np.floating)):
        return kernels.point(x), None
    if isinstance(x, (np.ndarray, list, tuple)):
        arr = np.asarray(x, dtype=float)
        return (arr, arr), arr.shape
    raise TypeError(f"cannot use {type(x).__name__} as an interval operand")


def _result(pair: Pair, shapes) -> Interval | IntervalArray:
    lo, hi = rounding.sanitize(*pair)
    shapes = [s for s in shapes if s is not None]
    if not shapes:
        return Interval._raw(float(lo), float(hi))
    shape = np.broadcast_shapes(*shapes)
    return IntervalArray._raw(*fit(lo, hi, shape))


def fit(lo, hi, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Bounds as float arrays of ``shape``; a point result is copied (it may be the caller's array)."""
    if lo is hi:
        lo = hi = np.array(np.broadcast_to(lo, shape), dtype=float)
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    lo = lo if lo.shape == shape else np.broadcast_to(lo, shape).copy()
    hi = hi if hi.shape == shape else np.broadcast_to(hi, shape).copy()
    return lo, hi


def apply(kernel, *operands, stacklevel: int = 3):
    """Run a pair kernel on Interval, IntervalArray, float or array operands."""
    pairs, shapes = zip(*(_as_pair(x) for x in operands))
    return rounding.guarded(lambda: _result(kernel(*pairs), shapes), stacklevel)


def _binary(kernel, x, y):
    """Operator: NotImplemented for a foreign operand, so Python tries the other side."""
    try:
        _as_pair(x), _as_pair(y)
    except TypeError:
        return NotImplemented
    return apply(kernel, x, y, stacklevel=4)


class _Arithmetic:
    """Operators shared by :class:`Interval` and :class:`IntervalArray`."""

    __slots__ = ()
    __array_ufunc__ = None  # numpy defers mixed operations to the reflected methods

    def __add__(self, other):
        return _binary(kernels.add, self, other)

    def __radd__(self, other):
        return _binary(kernels.add, other, self)

    def __sub__(self, other):
        return _binary(kernels.sub, self, other)

    def __rsub__(self, other):
        return _binary(kernels.sub, other, self)

    def __mul__(self, other):
        return _binary(kernels.mul, self, other)

    def __rmul__(self, other):
        return _binary(kernels.mul, other, self)

    def __truediv__(self, other):
        return _binary(kernels.div, self, other)

    def __rtruediv__(self, other):
        return _binary(kernels.div, other, self)

    def __neg__(self):
        return apply(kernels.neg, self)

    def __pos__(self):
        return self

    def __abs__(self):
        return apply(kernels.absolute, self)

    def __pow__(self, n):
        if not isinstance(n, (int, float, np.integer, np.floating)):
            return NotImplemented
        return apply(lambda a: kernels.power(a, n), self, stacklevel=4)


class Interval(_Arithmetic):
    """Closed interval ``[lo, hi]`` of reals with float bounds; immutable.

    Parameters
    ----------
    lo, hi : float
        Bounds, ``lo <= hi``; ``hi`` defaults to ``lo`` (a degenerate interval).
        Infinite bounds are allowed as long as the interval contains a real.

    Examples
    --------
    >>> x = Interval(-1.0, 2.0)
    >>> x ** 2
    Interval(0.0, 4.000000000000001)
    >>> x.width, x.mid, x.contains(0.5)
    (3.0, 0.5, True)
    >>> 1 - x
    Interval(-1.0000000000000002, 2.0000000000000004)
    """

    __slots__ = ("lo", "hi")

    def __init__(self, lo: Number, hi: Number | None = None) -> None:
        lo = float(lo)
        hi = lo if hi is None else float(hi)
        _validate(np.asarray(lo), np.asarray(hi))
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)

    @classmethod
    def _raw(cls, lo: float, hi: float) -> Interval:
        obj = object.__new__(cls)
        object.__setattr__(obj, "lo", lo)
        object.__setattr__(obj, "hi", hi)
        return obj

    def __setattr__(self, name, value):
        raise AttributeError("Interval is immutable")

    __delattr__ = __setattr__

    @property
    def width(self) -> float:
        """``hi - lo`` rounded to nearest."""
        return self.hi - self.lo

    @property
    def mid(self) -> float:
        """Midpoint ``lo/2 + hi/2`` (halved first so that it cannot overflow)."""
        if self.lo == -_INF and self.hi == _INF:
            return 0.0
        return 0.5 * self.lo + 0.5 * self.hi

    def contains(self, x) -> bool | np.ndarray:
        """Whether ``x`` (a number, an array elementwise, or an interval) lies in the interval."""
        if isinstance(x, (Interval, IntervalArray)):
            return (self.lo <= x.lo) & (x.hi <= self.hi)
        result = (self.lo <= np.asarray(x)) & (np.asarray(x) <= self.hi)
        return bool(result) if np.ndim(result) == 0 else result

    def __contains__(self, x) -> bool:
        return bool(self.contains(x))

    def __eq__(self, other) -> bool:
        if not isinstance(other, Interval):
            return NotImplemented
        return self.lo == other.lo and self.hi == other.hi

    def __hash__(self) -> int:
        return hash((self.lo, self.hi))

    def __repr__(self) -> str:
        return f"Interval({self.lo!r}, {self.hi!r})"

    def __reduce__(self):
        return (Interval, (self.lo, self.hi))


def _validate(lo: np.ndarray, hi: np.ndarray) -> None:
    """Raise ValueError unless every ``[lo, hi]`` is a non-empty set of reals."""
    if np.isnan(lo).any() or np.isnan(hi).any():
        raise ValueError("interval bounds must not be NaN")
    if np.any(lo > hi):
        raise ValueError(f"interval lower bound above upper bound in {int(np.count_nonzero(lo > hi))} element(s)")
    if np.any(lo == _INF) or np.any(hi == -_INF):
        raise ValueError("an interval must contain a real number (lo = +inf or hi = -inf given)")


class IntervalArray(_Arithmetic):
    """Array of intervals ``[lo[i], hi[i]]``, vectorized with numpy.

    Parameters
    ----------
    lo, hi : array_like
        Bounds of broadcastable shapes, ``lo <= hi`` elementwise; ``hi``
        defaults to ``lo`` (point values).

    Examples
    --------
    >>> import numpy as np
    >>> x = IntervalArray([0.0, 1.0, -2.0], [1.0, 3.0, -1.0])
    >>> y = x * Interval(-1.0, 2.0) + np.array([0.0, 1.0, 2.0])
    >>> y.lo.tolist()
    [-1.0000000000000004, -2.000000000000001, -2.0000000000000013]
    >>> y.hi.tolist()
    [2.000000000000001, 7.000000000000002, 4.000000000000001]
    >>> len(y), y.shape, y.contains(np.array([0.0, 7.0, 5.0])).tolist()
    (3, (3,), [True, True, False])
    """

    __slots__ = ("lo", "hi")

    def __init__(self, lo, hi=None) -> None:
        lo = np.asarray(lo, dtype=float)
        hi = lo if hi is None else np.asarray(hi, dtype=float)
        lo, hi = np.broadcast_arrays(lo, hi)
        _validate(lo, hi)
        self.lo, self.hi = lo, hi

    @classmethod
    def _raw(cls, lo: np.ndarray, hi: np.ndarray) -> IntervalArray:
        obj = object.__new__(cls)
        obj.lo, obj.hi = lo, hi
        return obj

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of the array of intervals, that of ``lo`` and ``hi``."""
        return self.lo.shape

    def __len__(self) -> int:
        return len(self.lo)

    def __getitem__(self, index) -> Interval | IntervalArray:
        lo, hi = self.lo[index], self.hi[index]
        if np.ndim(lo) == 0:
            return Interval._raw(float(lo), float(hi))
        return IntervalArray._raw(lo, hi)

    @property
    def width(self) -> np.ndarray:
        """``hi - lo`` rounded to nearest."""
        return self.hi - self.lo

    @property
    def mid(self) -> np.ndarray:
        """Midpoints ``lo/2 + hi/2``; 0 for ``[-inf, inf]``, as :meth:`Interval.mid`."""
        with np.errstate(invalid="ignore"):
            mid = 0.5 * self.lo + 0.5 * self.hi
        return np.where((self.lo == -_INF) & (self.hi == _INF), 0.0, mid)

    def contains(self, x) -> np.ndarray:
        """Elementwise whether ``x`` (numbers, an array or intervals) lies inside."""
        if isinstance(x, (Interval, IntervalArray)):
            return (self.lo <= x.lo) & (x.hi <= self.hi)
        x = np.asarray(x, dtype=float)
        return (self.lo <= x) & (x <= self.hi)

    def __repr__(self) -> str:
        return f"IntervalArray(lo={self.lo!r}, hi={self.hi!r})"


def trusted_interval(lo: float, hi: float) -> Interval:
    """An :class:`Interval` of bounds already known to be valid (a computed enclosure), without the checks."""
    return Interval._raw(lo, hi)


def trusted_array(lo: np.ndarray, hi: np.ndarray) -> IntervalArray:
    """An :class:`IntervalArray` of float arrays already known to be valid bounds of one shape, without the checks."""
    return IntervalArray._raw(lo, hi)
