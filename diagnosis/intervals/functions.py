"""Elementwise functions of intervals: sqrt, exp, log, absolute value, sign, minimum, maximum, tanh, sin, cos, power.

Each takes an :class:`~diagnosis.intervals.Interval`, an
:class:`~diagnosis.intervals.IntervalArray`, a number or an array (exact points)
and returns an enclosure of the range of the real function, rounded outward;
see the package docstring of :mod:`diagnosis.intervals` for the error model.
"""

from __future__ import annotations

from typing import Union

import numpy as np

from . import interval, kernels
from .interval import Interval, IntervalArray, Number

__all__ = [
    "Operand", "absolute", "cos", "exp", "log", "maximum", "minimum", "power", "sign", "sin", "sqrt", "tanh",
]

Operand = Union[Interval, IntervalArray, Number, np.ndarray]


def sqrt(x: Operand) -> Interval | IntervalArray:
    """Square root; an interval partly below 0 is clipped to ``[0, hi]`` with a warning.

    Raises ValueError for an interval entirely below 0.

    Examples
    --------
    >>> sqrt(Interval(4.0, 9.0))
    Interval(1.9999999999999998, 3.0000000000000004)
    """
    return interval.apply(kernels.sqrt, x)


def exp(x: Operand) -> Interval | IntervalArray:
    """Exponential, widened by :data:`TRANSCENDENTAL_ULPS` ulps.

    Examples
    --------
    >>> exp(Interval(0.0, 1.0)).contains(Interval(1.0, 2.718281828459045))
    True
    """
    return interval.apply(kernels.exp, x)


def log(x: Operand) -> Interval | IntervalArray:
    """Natural logarithm on ``(0, hi]``; a lower bound ``<= 0`` gives ``-inf`` with a warning.

    Raises ValueError for an interval with ``hi <= 0``.

    Examples
    --------
    >>> log(Interval(1.0, 1.0)).contains(0.0)
    True
    """
    return interval.apply(kernels.log, x)


def absolute(x: Operand) -> Interval | IntervalArray:
    """Absolute value ``[max(lo, -hi, 0), max(-lo, hi)]`` (exact); ``abs(x)`` for an interval operand.

    Examples
    --------
    >>> absolute(Interval(-3.0, 2.0))
    Interval(0.0, 3.0)
    >>> abs(Interval(-3.0, 2.0))
    Interval(0.0, 3.0)
    """
    return interval.apply(kernels.absolute, x)


def sign(x: Operand) -> Interval | IntervalArray:
    """Sign, ``[sign(lo), sign(hi)]`` (exact; nondecreasing).

    Examples
    --------
    >>> sign(Interval(-3.0, 0.0))
    Interval(-1.0, 0.0)
    """
    return interval.apply(kernels.sign, x)


def minimum(x: Operand, y: Operand) -> Interval | IntervalArray:
    """Elementwise minimum ``[min(x.lo, y.lo), min(x.hi, y.hi)]`` (exact).

    Examples
    --------
    >>> minimum(Interval(0.0, 3.0), 1.0)
    Interval(0.0, 1.0)
    """
    return interval.apply(kernels.minimum, x, y)


def maximum(x: Operand, y: Operand) -> Interval | IntervalArray:
    """Elementwise maximum ``[max(x.lo, y.lo), max(x.hi, y.hi)]`` (exact).

    Examples
    --------
    >>> maximum(Interval(0.0, 3.0), 1.0)
    Interval(1.0, 3.0)
    """
    return interval.apply(kernels.maximum, x, y)


def tanh(x: Operand) -> Interval | IntervalArray:
    """Hyperbolic tangent (increasing), clipped to ``[-1, 1]``.

    Examples
    --------
    >>> tanh(Interval(-1e3, 1e3))
    Interval(-1.0, 1.0)
    """
    return interval.apply(kernels.tanh, x)


def sin(x: Operand) -> Interval | IntervalArray:
    """Sine; the bound is exactly 1 (or -1) where the interval spans ``pi/2 + 2 k pi`` (``-pi/2 + 2 k pi``).

    Examples
    --------
    >>> sin(Interval(1.0, 2.0)).hi
    1.0
    >>> sin(Interval(0.0, 7.0))
    Interval(-1.0, 1.0)
    """
    return interval.apply(kernels.sin, x)


def cos(x: Operand) -> Interval | IntervalArray:
    """Cosine; the bound is exactly 1 (or -1) where the interval spans ``2 k pi`` (``pi + 2 k pi``).

    Examples
    --------
    >>> cos(Interval(3.0, 3.5)).lo
    -1.0
    """
    return interval.apply(kernels.cos, x)


def power(x: Operand, n: Number) -> Interval | IntervalArray:
    """``x**n``: exact-rule integer powers, or a real power of ``x >= 0``.

    An even power of an interval containing 0 has lower bound 0; a negative
    power divides 1 by the positive power.

    Examples
    --------
    >>> power(Interval(-2.0, 1.0), 3)
    Interval(-8.000000000000004, 1.0)
    >>> power(Interval(-2.0, 1.0), 2)
    Interval(0.0, 4.000000000000001)
    >>> power(Interval(2.0, 4.0), -1)
    Interval(0.24999999999999997, 0.5000000000000001)
    """
    return interval.apply(lambda a: kernels.power(a, n), x)
