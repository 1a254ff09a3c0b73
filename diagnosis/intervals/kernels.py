"""Interval kernels on ``(lo, hi)`` pairs: the arithmetic under :class:`~diagnosis.intervals.Interval`.

>>> lo, hi = mul((np.float64(-1.0), np.float64(2.0)), point(3.0))   # [-1, 2] * 3, rounded outward
>>> float(lo), float(hi)
(-3.0000000000000004, 6.000000000000001)

A pair holds two floats or two arrays of broadcastable shapes; ``lo is hi``
marks an exact point (:func:`point`), whose result a kernel computes once and
rounds outward once, or not at all when it is exact. Every kernel returns an
enclosure of the range of its real operation over its arguments, rounded
outward by :mod:`~diagnosis.intervals.rounding`; a kernel that leaves its domain
records an :class:`~diagnosis.intervals.IntervalWarning` with
:func:`~diagnosis.intervals.rounding.warn`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from . import rounding

__all__ = [
    "Pair", "absolute", "add", "cos", "div", "exp", "is_point", "log", "maximum", "minimum", "mul", "neg",
    "point", "pow_int", "power", "real_pow", "sign", "sin", "sqrt", "sub", "tanh",
]

Pair = tuple[Any, Any]  # (lo, hi), floats or arrays; ``lo is hi`` marks an exact point

_INF = math.inf
_TWO_PI = 2.0 * math.pi
_HALF_PI = 0.5 * math.pi


def point(value) -> tuple:
    """An exact point: a pair whose two bounds are the same object."""
    value = np.float64(value)  # numpy scalars: x / 0 gives inf, not ZeroDivisionError
    return value, value


_ZERO = point(0.0)
_ONE = point(1.0)


def is_point(a: Pair) -> bool:
    """Whether ``a`` is an exact point (its two bounds are the same object)."""
    return a[0] is a[1]


def _is_zero(a: Pair) -> bool:
    """Whether ``a`` is the exact scalar point 0, whose addition is exact."""
    return is_point(a) and np.ndim(a[0]) == 0 and a[0] == 0


def add(a: Pair, b: Pair) -> Pair:
    """Enclosure of ``a + b``."""
    if _is_zero(a) or _is_zero(b):
        return b if _is_zero(a) else a
    if is_point(a) and is_point(b):
        return rounding.rounded(a[0] + b[0])
    return rounding.down(a[0] + b[0]), rounding.up(a[1] + b[1])


def sub(a: Pair, b: Pair) -> Pair:
    """Enclosure of ``a - b``."""
    if _is_zero(b):
        return a
    if is_point(a) and is_point(b):
        return rounding.rounded(a[0] - b[0])
    return rounding.down(a[0] - b[1]), rounding.up(a[1] - b[0])


def neg(a: Pair) -> Pair:
    """``-a`` (exact: the bounds swap and change sign)."""
    if is_point(a):
        n = -a[0]
        return n, n
    return -a[1], -a[0]


def _scale(a: Pair, p) -> Pair:
    """``a`` (an interval or a point) times the exact point ``p``."""
    lo, hi = a
    if np.ndim(p) == 0 and float(p) in (0.0, 1.0, -1.0):
        if p == 0:
            return _ZERO  # 0 * x = 0 for every real x, even in an unbounded interval
        return a if p == 1 else neg(a)  # exact: no rounding
    if is_point(a):
        return rounding.rounded(lo * p)
    if np.ndim(p) == 0:
        return (rounding.down(lo * p), rounding.up(hi * p)) if p > 0 else (rounding.down(hi * p), rounding.up(lo * p))
    x1, x2 = lo * p, hi * p
    return rounding.down(np.minimum(x1, x2)), rounding.up(np.maximum(x1, x2))


def mul(a: Pair, b: Pair) -> Pair:
    """Enclosure of ``a * b`` (the hull of the four bound products, an exact point factor scaled once)."""
    if is_point(a):
        a, b = b, a
    if is_point(b):
        return _scale(a, b[0])
    al, ah = a
    bl, bh = b
    p1, p2, p3, p4 = al * bl, al * bh, ah * bl, ah * bh
    # fmin/fmax drop 0 * inf products; another endpoint product then gives the bound
    lo = np.fmin(np.fmin(p1, p2), np.fmin(p3, p4))
    hi = np.fmax(np.fmax(p1, p2), np.fmax(p3, p4))
    return rounding.down(lo), rounding.up(hi)


def _zero_hull(lo, hi, zero) -> Pair:
    """Set the elements whose divisor contains 0 to (-inf, inf) and say how many.

    The count is over the elements of this division's result.
    """
    zero = np.broadcast_to(zero, np.broadcast_shapes(np.shape(lo), np.shape(zero)))
    count = int(np.count_nonzero(zero))
    if count:
        rounding.warn("division by an interval containing 0 in {count} element(s); result set to (-inf, inf)", count)
        lo = np.where(zero, -_INF, lo)
        hi = np.where(zero, _INF, hi)
    return lo, hi


def div(a: Pair, b: Pair) -> Pair:
    """Enclosure of ``a / b``; where the divisor contains 0 the result is ``(-inf, inf)``, with a warning."""
    al, ah = a
    bl, bh = b
    if is_point(b):
        if np.ndim(bl) == 0 and float(bl) in (1.0, -1.0):
            return a if float(bl) == 1.0 else neg(a)
        if is_point(a):
            lo, hi = rounding.rounded(al / bl)
        else:
            q1, q2 = al / bl, ah / bl
            lo, hi = rounding.down(np.minimum(q1, q2)), rounding.up(np.maximum(q1, q2))
        return _zero_hull(lo, hi, bl == 0)
    if is_point(a):
        q1, q2 = al / bl, al / bh
        lo, hi = np.minimum(q1, q2), np.maximum(q1, q2)
    else:
        q1, q2, q3, q4 = al / bl, al / bh, ah / bl, ah / bh
        # fmin/fmax drop inf/inf quotients; another endpoint quotient gives the bound
        lo = np.fmin(np.fmin(q1, q2), np.fmin(q3, q4))
        hi = np.fmax(np.fmax(q1, q2), np.fmax(q3, q4))
    return _zero_hull(rounding.down(lo), rounding.up(hi), (bl <= 0) & (bh >= 0))


def _pow_bounds(x, n: int) -> Pair:
    """Enclose ``x**n`` (n >= 2) for the point (array) ``x`` by square-and-multiply.

    Each product is an outward-rounded interval product, so the enclosure is
    rigorous: one ulp per multiplication, about ``2 log2(n)`` in all.
    """
    result, base = None, (x, x)
    while True:
        if n & 1:
            result = base if result is None else mul(result, base)
        n >>= 1
        if not n:
            return result
        base = mul(base, base)


def pow_int(a: Pair, n: int) -> Pair:
    """Integer power; an even power of an interval containing 0 has lower bound 0."""
    if n == 0:
        return _ONE
    if n == 1:
        return a
    if n < 0:
        return div(_ONE, pow_int(a, -n))
    lo, hi = a
    even = n % 2 == 0
    if is_point(a):
        low, high = _pow_bounds(lo, n)
    elif even:
        nearest = np.maximum(lo, np.minimum(hi, 0.0))  # the element of [lo, hi] closest to 0
        low, high = _pow_bounds(nearest, n)[0], _pow_bounds(np.maximum(-lo, hi), n)[1]
    else:  # odd powers are increasing
        low, high = _pow_bounds(lo, n)[0], _pow_bounds(hi, n)[1]
    return (np.maximum(low, 0.0) if even else low), high


def _clip_domain(a: Pair, name: str, closed: bool) -> Pair:
    """Restrict ``a`` to ``[0, inf)`` (``closed``) or ``(0, inf)``; warn when it had to.

    Raises ValueError when an element lies entirely outside the domain.
    """
    lo, hi = a
    outside = hi < 0 if closed else hi <= 0
    if np.any(outside):
        bound = "below 0" if closed else "at or below 0"
        raise ValueError(f"{name} of an interval entirely {bound} in {int(np.count_nonzero(outside))} element(s)")
    partial = lo < 0 if closed else lo <= 0
    count = int(np.count_nonzero(partial))
    if count:
        rounding.warn(
            name + " of an interval partly outside its domain in {count} element(s); clipped to the domain", count
        )
        return np.maximum(lo, 0.0), hi
    return a


def sqrt(a: Pair) -> Pair:
    """Enclosure of ``sqrt(a)``; the part of ``a`` below 0 is cut off with a warning."""
    a = _clip_domain(a, "sqrt", closed=True)
    if is_point(a):
        root = np.sqrt(a[0])
        return np.maximum(rounding.down(root), 0.0), rounding.up(root)
    return np.maximum(rounding.down(np.sqrt(a[0])), 0.0), rounding.up(np.sqrt(a[1]))


def _monotone(a: Pair, fn) -> Pair:
    """Enclose an increasing transcendental function evaluated by numpy."""
    if is_point(a):
        value = fn(a[0])
        return rounding.down_transcendental(value), rounding.up_transcendental(value)
    return rounding.down_transcendental(fn(a[0])), rounding.up_transcendental(fn(a[1]))


def exp(a: Pair) -> Pair:
    """Enclosure of ``exp(a)`` (increasing), widened for libm's error."""
    lo, hi = _monotone(a, np.exp)
    return np.maximum(lo, 0.0), hi


def log(a: Pair) -> Pair:
    """Enclosure of ``log(a)`` (increasing); the part of ``a`` at or below 0 is cut off with a warning."""
    a = _clip_domain(a, "log", closed=False)
    return _monotone(a, np.log)  # a lower end clipped to 0 gives log(0) = -inf


def tanh(a: Pair) -> Pair:
    """Enclosure of ``tanh(a)`` (increasing), widened for libm's error."""
    lo, hi = _monotone(a, np.tanh)
    return np.maximum(lo, -1.0), np.minimum(hi, 1.0)


def real_pow(a: Pair, r: Pair) -> Pair:
    """``x**r`` for x >= 0 and a real exponent interval ``r`` not containing 0.

    ``x**r`` is monotone in x and in r separately, so its range over the box is
    reached at a corner.
    """
    lo, hi = _clip_domain(a, "power with a non-integer exponent", closed=True)
    exponents = r[:1] if is_point(r) else r
    corners = [np.power(x, e) for x in (lo, hi) for e in exponents]
    low = high = corners[0]
    for value in corners[1:]:
        low, high = np.minimum(low, value), np.maximum(high, value)
    return np.maximum(rounding.down_transcendental(low), 0.0), rounding.up_transcendental(high)


def _hits(lo, hi, offset: float):
    """Whether ``[lo, hi]`` may contain ``offset + 2 k pi`` for an integer k.

    The slack covers the rounding of the reduction (a few ulps of |t|) and errs
    toward True, which only widens the result to the sound value +-1.
    """
    t_lo = (lo - offset) / _TWO_PI
    t_hi = (hi - offset) / _TWO_PI
    slack = 4 * rounding.EPS * (np.abs(t_lo) + np.abs(t_hi) + 1.0)
    return np.floor(t_hi + slack) >= t_lo - slack


def _periodic(a: Pair, fn, peak: float, trough: float) -> Pair:
    """Enclose sin or cos: endpoint values, then +-1 where a peak or trough lies inside."""
    lo, hi = a
    v_lo = fn(lo)
    v_hi = v_lo if is_point(a) else fn(hi)
    low = np.maximum(rounding.down_transcendental(np.minimum(v_lo, v_hi)), -1.0)
    high = np.minimum(rounding.up_transcendental(np.maximum(v_lo, v_hi)), 1.0)
    low = np.where(_hits(lo, hi, trough), -1.0, low)
    high = np.where(_hits(lo, hi, peak), 1.0, high)
    return low, high


def sin(a: Pair) -> Pair:
    """Enclosure of ``sin(a)``, with the peaks and troughs ``a`` contains."""
    return _periodic(a, np.sin, _HALF_PI, -_HALF_PI)


def cos(a: Pair) -> Pair:
    """Enclosure of ``cos(a)``, with the peaks and troughs ``a`` contains."""
    return _periodic(a, np.cos, 0.0, math.pi)


def absolute(a: Pair) -> Pair:
    """``|a|`` (exact: 0 is the lower bound when ``a`` contains it)."""
    lo, hi = a
    if is_point(a):
        m = np.abs(lo)
        return m, m
    return np.maximum(np.maximum(lo, -hi), 0.0), np.maximum(-lo, hi)


def sign(a: Pair) -> Pair:
    """The range of ``sign`` over ``a``: a subset of [-1, 1]."""
    if is_point(a):
        s = np.sign(a[0])
        return s, s
    return np.sign(a[0]), np.sign(a[1])


def minimum(a: Pair, b: Pair) -> Pair:
    """``min(a, b)`` elementwise (exact)."""
    if is_point(a) and is_point(b):
        m = np.minimum(a[0], b[0])
        return m, m
    return np.minimum(a[0], b[0]), np.minimum(a[1], b[1])


def maximum(a: Pair, b: Pair) -> Pair:
    """``max(a, b)`` elementwise (exact)."""
    if is_point(a) and is_point(b):
        m = np.maximum(a[0], b[0])
        return m, m
    return np.maximum(a[0], b[0]), np.maximum(a[1], b[1])


def power(a: Pair, n) -> Pair:
    """Power with a numeric exponent: integer, one half, or any real."""
    if float(n).is_integer():
        return pow_int(a, int(n))
    if float(n) == 0.5:
        return sqrt(a)
    e = float(n)
    return real_pow(a, (e, e))
