r"""Interval arithmetic with outward rounding for robust fault-detection thresholds.

The uncertain part :math:`\Psi_2` of an interval-valued ARR (seed 003, Jha et
al. 2016, section 2.3) is an expression in point-valued signals, point-valued
nominal parameters and interval-valued multiplicative uncertainties
:math:`[\delta_\theta]`. Its range :math:`[\underline B(t), \overline B(t)]`
over the uncertainty box is the detection threshold: a fault is declared when
:math:`-r_n(t)` leaves it (eqs. 16-20).

Natural interval extension
--------------------------
:func:`compile_interval` replaces every real operation of the sympy expression
by its interval counterpart (seed 003, Appendix A, Definition A.2). Each
interval operation encloses the exact range of the real operation over its
arguments, so the result is a rational interval function, inclusion isotonic
(Moore; Lemma A.3.1), and by the fundamental theorem of interval analysis
(Theorem A.1)

.. math:: f(X_1, \dots, X_n) \subseteq F(X_1, \dots, X_n).

The enclosure is sound but overestimates when an interval symbol occurs more
than once (the *dependency problem*): every occurrence is treated as an
independent variable, so :math:`\delta - \delta` over :math:`[-1, 1]` gives
:math:`[-2, 2]` instead of :math:`[0, 0]`. For the BG-LFT form
:math:`g_0 + \sum_i \delta_i g_i` each :math:`\delta_i` occurs once after
:func:`sympy.collect`; :func:`range_linear` evaluates that collected form,
whose natural extension is the exact range up to rounding.

Outward rounding
----------------
Every computed lower bound ``l`` becomes ``np.nextafter(l, -inf)`` and every
upper bound ``h`` becomes ``np.nextafter(h, +inf)``, bit for bit; on arrays the
step is an integer operation on the bit pattern, about twice as fast as
numpy's ``nextafter``, which calls libm once per element. One ulp suffices for
``+ - * /`` and ``sqrt``, which IEEE 754 rounds correctly (the exact result
lies within half an ulp of the computed one). numpy's ``exp``, ``log``,
``tanh``, ``sin``, ``cos`` and ``power`` are not correctly rounded (glibc
documents errors of 1 to 2 ulps, numpy's SIMD kernels up to 4), so their
bounds move out by ``(2 k + 1) eps |x| + (k + 1) tiny`` with
``k =`` :data:`TRANSCENDENTAL_ULPS` (``eps = 2**-52``, ``tiny = 2**-1074``):
at least ``k`` ulps even across a power of two, plus one for the rounding of
the widening itself. Integer powers are products of outward-rounded interval
multiplications (square-and-multiply), so they need no error model. Exact
results are not widened: negation, ``abs``, ``sign``, ``min``, ``max``, the
lower bound 0 of an even power, adding the constant 0 and multiplying by the
constants 0, 1 and -1. A constant that is not a double (``1/3``,
``pi``, a sympy ``Float`` of more than 53 bits) becomes the interval between
the two doubles around it.

Examples
--------
>>> delta = Interval(-1.0, 1.0)
>>> delta - delta
Interval(-2.0000000000000004, 2.0000000000000004)
>>> Interval(0.1, 0.1) + Interval(0.2, 0.2)
Interval(0.3, 0.3000000000000001)
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from contextvars import ContextVar
from fractions import Fraction
from typing import Any, Union

import numpy as np
import sympy as sp

__all__ = [
    "TRANSCENDENTAL_ULPS",
    "Interval",
    "IntervalArray",
    "IntervalWarning",
    "abs_",
    "compile_interval",
    "cos",
    "enclose",
    "exp",
    "iabs",
    "log",
    "maximum",
    "minimum",
    "power",
    "range_linear",
    "sign",
    "sin",
    "sqrt",
    "tanh",
]

TRANSCENDENTAL_ULPS = 4
"""Assumed worst error, in ulps, of numpy's exp, log, tanh, sin, cos and power."""

_EPS = float(np.finfo(float).eps)  # 2**-52, the ulp of 1.0
_TINY = 5e-324  # 2**-1074, the smallest subnormal: the ulp near 0
_MAX = float(np.finfo(float).max)
_INF = math.inf
# Doubled so that the margin holds when the exact value lies across a power of two.
_TRANS_REL = (2 * TRANSCENDENTAL_ULPS + 1) * _EPS
_TRANS_SUB = (TRANSCENDENTAL_ULPS + 1) * _TINY
_TWO_PI = 2.0 * math.pi
_HALF_PI = 0.5 * math.pi


def _point(value) -> tuple:
    """An exact point: a pair whose two bounds are the same object."""
    value = np.float64(value)  # numpy scalars: x / 0 gives inf, not ZeroDivisionError
    return value, value


_ZERO = _point(0.0)
_ONE = _point(1.0)

Number = Union[int, float, np.integer, np.floating]
Pair = tuple[Any, Any]  # (lo, hi), floats or arrays; ``lo is hi`` marks an exact point


class IntervalWarning(RuntimeWarning):
    """An interval operation left its domain and returned a widened, still sound, result."""


# --------------------------------------------------------------------------
# Outward rounding
# --------------------------------------------------------------------------


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


def _up(x):
    """``np.nextafter(x, +inf)``: one ulp up (exact; a bit operation, not a libm call per element)."""
    if np.ndim(x) == 0:
        return np.nextafter(np.float64(x), _INF)
    a = np.minimum(x, _MAX)  # MAX steps to +inf, as nextafter(+inf, +inf) = +inf
    a += 0.0  # -0.0 + 0.0 = +0.0, whose successor is the smallest subnormal
    return _step_up(a)


def _down(x):
    """``np.nextafter(x, -inf)``, as ``-nextafter(-x, +inf)``."""
    if np.ndim(x) == 0:
        return np.nextafter(np.float64(x), -_INF)
    a = np.negative(x)
    np.minimum(a, _MAX, out=a)
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


def _down_t(x):
    """Lower bound of a transcendental result (see :data:`TRANSCENDENTAL_ULPS`)."""
    return _widen_down(x, _TRANS_REL, _TRANS_SUB)


def _up_t(x):
    """Upper bound of a transcendental result (see :data:`TRANSCENDENTAL_ULPS`)."""
    return _widen_up(x, _TRANS_REL, _TRANS_SUB)


def _rounded(x) -> Pair:
    """Enclose a value computed by one correctly rounded operation."""
    return _down(x), _up(x)


# Warnings raised inside one evaluation are summed and issued once at its end.
_PENDING: ContextVar[dict | None] = ContextVar("_PENDING", default=None)


def _warn(template: str, count: int) -> None:
    """Record ``count`` elements for ``template`` (which has a ``{count}`` field)."""
    pending = _PENDING.get()
    if pending is None:
        warnings.warn(template.format(count=count), IntervalWarning, stacklevel=4)
    else:
        pending[template] = pending.get(template, 0) + count


def _guarded(compute: Callable[[], Any], stacklevel: int):
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


def _sanitize(lo, hi) -> Pair:
    """Replace NaN bounds (e.g. ``0 * inf`` of infinite points) by the sound hull."""
    if np.isnan(lo).any():
        lo = np.where(np.isnan(lo), -_INF, lo)
    if np.isnan(hi).any():
        hi = np.where(np.isnan(hi), _INF, hi)
    return lo, hi


# --------------------------------------------------------------------------
# Kernels on (lo, hi) pairs
# --------------------------------------------------------------------------


def _is_point(a: Pair) -> bool:
    return a[0] is a[1]


def _is_zero(a: Pair) -> bool:
    """Whether ``a`` is the exact scalar point 0, whose addition is exact."""
    return _is_point(a) and np.ndim(a[0]) == 0 and a[0] == 0


def _add(a: Pair, b: Pair) -> Pair:
    if _is_zero(a) or _is_zero(b):
        return b if _is_zero(a) else a
    if _is_point(a) and _is_point(b):
        return _rounded(a[0] + b[0])
    return _down(a[0] + b[0]), _up(a[1] + b[1])


def _sub(a: Pair, b: Pair) -> Pair:
    if _is_zero(b):
        return a
    if _is_point(a) and _is_point(b):
        return _rounded(a[0] - b[0])
    return _down(a[0] - b[1]), _up(a[1] - b[0])


def _neg(a: Pair) -> Pair:
    if _is_point(a):
        n = -a[0]
        return n, n
    return -a[1], -a[0]


def _scale(a: Pair, p) -> Pair:
    """``a`` (an interval or a point) times the exact point ``p``."""
    lo, hi = a
    if np.ndim(p) == 0 and float(p) in (0.0, 1.0, -1.0):
        if p == 0:
            return _ZERO  # 0 * x = 0 for every real x, even in an unbounded interval
        return a if p == 1 else _neg(a)  # exact: no rounding
    if _is_point(a):
        return _rounded(lo * p)
    if np.ndim(p) == 0:
        return (_down(lo * p), _up(hi * p)) if p > 0 else (_down(hi * p), _up(lo * p))
    x1, x2 = lo * p, hi * p
    return _down(np.minimum(x1, x2)), _up(np.maximum(x1, x2))


def _mul(a: Pair, b: Pair) -> Pair:
    if _is_point(a):
        a, b = b, a
    if _is_point(b):
        return _scale(a, b[0])
    al, ah = a
    bl, bh = b
    p1, p2, p3, p4 = al * bl, al * bh, ah * bl, ah * bh
    # fmin/fmax drop 0 * inf products; another endpoint product then gives the bound
    lo = np.fmin(np.fmin(p1, p2), np.fmin(p3, p4))
    hi = np.fmax(np.fmax(p1, p2), np.fmax(p3, p4))
    return _down(lo), _up(hi)


def _zero_hull(lo, hi, zero) -> Pair:
    """Set the elements whose divisor contains 0 to (-inf, inf) and say how many.

    The count is over the elements of this division's result.
    """
    zero = np.broadcast_to(zero, np.broadcast_shapes(np.shape(lo), np.shape(zero)))
    count = int(np.count_nonzero(zero))
    if count:
        _warn("division by an interval containing 0 in {count} element(s); result set to (-inf, inf)", count)
        lo = np.where(zero, -_INF, lo)
        hi = np.where(zero, _INF, hi)
    return lo, hi


def _div(a: Pair, b: Pair) -> Pair:
    al, ah = a
    bl, bh = b
    if _is_point(b):
        if np.ndim(bl) == 0 and float(bl) in (1.0, -1.0):
            return a if float(bl) == 1.0 else _neg(a)
        if _is_point(a):
            lo, hi = _rounded(al / bl)
        else:
            q1, q2 = al / bl, ah / bl
            lo, hi = _down(np.minimum(q1, q2)), _up(np.maximum(q1, q2))
        return _zero_hull(lo, hi, bl == 0)
    if _is_point(a):
        q1, q2 = al / bl, al / bh
        lo, hi = np.minimum(q1, q2), np.maximum(q1, q2)
    else:
        q1, q2, q3, q4 = al / bl, al / bh, ah / bl, ah / bh
        # fmin/fmax drop inf/inf quotients; another endpoint quotient gives the bound
        lo = np.fmin(np.fmin(q1, q2), np.fmin(q3, q4))
        hi = np.fmax(np.fmax(q1, q2), np.fmax(q3, q4))
    return _zero_hull(_down(lo), _up(hi), (bl <= 0) & (bh >= 0))


def _pow_bounds(x, n: int) -> Pair:
    """Enclose ``x**n`` (n >= 2) for the point (array) ``x`` by square-and-multiply.

    Each product is an outward-rounded interval product, so the enclosure is
    rigorous: one ulp per multiplication, about ``2 log2(n)`` in all.
    """
    result, base = None, (x, x)
    while True:
        if n & 1:
            result = base if result is None else _mul(result, base)
        n >>= 1
        if not n:
            return result
        base = _mul(base, base)


def _pow_int(a: Pair, n: int) -> Pair:
    """Integer power; an even power of an interval containing 0 has lower bound 0."""
    if n == 0:
        return _ONE
    if n == 1:
        return a
    if n < 0:
        return _div(_ONE, _pow_int(a, -n))
    lo, hi = a
    even = n % 2 == 0
    if _is_point(a):
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
        _warn(name + " of an interval partly outside its domain in {count} element(s); clipped to the domain", count)
        return np.maximum(lo, 0.0), hi
    return a


def _sqrt(a: Pair) -> Pair:
    a = _clip_domain(a, "sqrt", closed=True)
    if _is_point(a):
        root = np.sqrt(a[0])
        return np.maximum(_down(root), 0.0), _up(root)
    return np.maximum(_down(np.sqrt(a[0])), 0.0), _up(np.sqrt(a[1]))


def _monotone(a: Pair, fn) -> Pair:
    """Enclose an increasing transcendental function evaluated by numpy."""
    if _is_point(a):
        value = fn(a[0])
        return _down_t(value), _up_t(value)
    return _down_t(fn(a[0])), _up_t(fn(a[1]))


def _exp(a: Pair) -> Pair:
    lo, hi = _monotone(a, np.exp)
    return np.maximum(lo, 0.0), hi


def _log(a: Pair) -> Pair:
    a = _clip_domain(a, "log", closed=False)
    return _monotone(a, np.log)  # a lower end clipped to 0 gives log(0) = -inf


def _tanh(a: Pair) -> Pair:
    lo, hi = _monotone(a, np.tanh)
    return np.maximum(lo, -1.0), np.minimum(hi, 1.0)


def _real_pow(a: Pair, r: Pair) -> Pair:
    """``x**r`` for x >= 0 and a real exponent interval ``r`` not containing 0.

    ``x**r`` is monotone in x and in r separately, so its range over the box is
    reached at a corner.
    """
    lo, hi = _clip_domain(a, "power with a non-integer exponent", closed=True)
    exponents = r[:1] if _is_point(r) else r
    corners = [np.power(x, e) for x in (lo, hi) for e in exponents]
    low = high = corners[0]
    for value in corners[1:]:
        low, high = np.minimum(low, value), np.maximum(high, value)
    return np.maximum(_down_t(low), 0.0), _up_t(high)


def _hits(lo, hi, offset: float):
    """Whether ``[lo, hi]`` may contain ``offset + 2 k pi`` for an integer k.

    The slack covers the rounding of the reduction (a few ulps of |t|) and errs
    toward True, which only widens the result to the sound value +-1.
    """
    t_lo = (lo - offset) / _TWO_PI
    t_hi = (hi - offset) / _TWO_PI
    slack = 4 * _EPS * (np.abs(t_lo) + np.abs(t_hi) + 1.0)
    return np.floor(t_hi + slack) >= t_lo - slack


def _periodic(a: Pair, fn, peak: float, trough: float) -> Pair:
    """Enclose sin or cos: endpoint values, then +-1 where a peak or trough lies inside."""
    lo, hi = a
    v_lo = fn(lo)
    v_hi = v_lo if _is_point(a) else fn(hi)
    low = np.maximum(_down_t(np.minimum(v_lo, v_hi)), -1.0)
    high = np.minimum(_up_t(np.maximum(v_lo, v_hi)), 1.0)
    low = np.where(_hits(lo, hi, trough), -1.0, low)
    high = np.where(_hits(lo, hi, peak), 1.0, high)
    return low, high


def _sin(a: Pair) -> Pair:
    return _periodic(a, np.sin, _HALF_PI, -_HALF_PI)


def _cos(a: Pair) -> Pair:
    return _periodic(a, np.cos, 0.0, math.pi)


def _abs(a: Pair) -> Pair:
    lo, hi = a
    if _is_point(a):
        m = np.abs(lo)
        return m, m
    return np.maximum(np.maximum(lo, -hi), 0.0), np.maximum(-lo, hi)


def _sign(a: Pair) -> Pair:
    if _is_point(a):
        s = np.sign(a[0])
        return s, s
    return np.sign(a[0]), np.sign(a[1])


def _min(a: Pair, b: Pair) -> Pair:
    if _is_point(a) and _is_point(b):
        m = np.minimum(a[0], b[0])
        return m, m
    return np.minimum(a[0], b[0]), np.minimum(a[1], b[1])


def _max(a: Pair, b: Pair) -> Pair:
    if _is_point(a) and _is_point(b):
        m = np.maximum(a[0], b[0])
        return m, m
    return np.maximum(a[0], b[0]), np.maximum(a[1], b[1])


def _power(a: Pair, n) -> Pair:
    """Power with a numeric exponent: integer, one half, or any real."""
    if float(n).is_integer():
        return _pow_int(a, int(n))
    if float(n) == 0.5:
        return _sqrt(a)
    e = float(n)
    return _real_pow(a, (e, e))


# --------------------------------------------------------------------------
# Public interval types
# --------------------------------------------------------------------------


def _as_pair(x) -> tuple[Pair, tuple[int, ...] | None]:
    """Operand as a (lo, hi) pair and its shape (None for a scalar)."""
    if isinstance(x, Interval):
        return (np.float64(x.lo), np.float64(x.hi)), None
    if isinstance(x, IntervalArray):
        return (x.lo, x.hi), x.shape
    if isinstance(x, (int, float, np.integer, np.floating)):
        return _point(x), None
    if isinstance(x, (np.ndarray, list, tuple)):
        arr = np.asarray(x, dtype=float)
        return (arr, arr), arr.shape
    raise TypeError(f"cannot use {type(x).__name__} as an interval operand")


def _result(pair: Pair, shapes) -> Interval | IntervalArray:
    lo, hi = _sanitize(*pair)
    shapes = [s for s in shapes if s is not None]
    if not shapes:
        return Interval._raw(float(lo), float(hi))
    shape = np.broadcast_shapes(*shapes)
    return IntervalArray._raw(*_fit(lo, hi, shape))


def _fit(lo, hi, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Bounds as float arrays of ``shape``; a point result is copied (it may be the caller's array)."""
    if lo is hi:
        lo = hi = np.array(np.broadcast_to(lo, shape), dtype=float)
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    lo = lo if lo.shape == shape else np.broadcast_to(lo, shape).copy()
    hi = hi if hi.shape == shape else np.broadcast_to(hi, shape).copy()
    return lo, hi


def _apply(kernel, *operands, stacklevel: int = 3):
    """Run a pair kernel on Interval, IntervalArray, float or array operands."""
    pairs, shapes = zip(*(_as_pair(x) for x in operands))
    return _guarded(lambda: _result(kernel(*pairs), shapes), stacklevel)


def _binary(kernel, x, y):
    """Operator: NotImplemented for a foreign operand, so Python tries the other side."""
    try:
        _as_pair(x), _as_pair(y)
    except TypeError:
        return NotImplemented
    return _apply(kernel, x, y, stacklevel=4)


class _Arithmetic:
    """Operators shared by :class:`Interval` and :class:`IntervalArray`."""

    __slots__ = ()
    __array_ufunc__ = None  # numpy defers mixed operations to the reflected methods

    def __add__(self, other):
        return _binary(_add, self, other)

    def __radd__(self, other):
        return _binary(_add, other, self)

    def __sub__(self, other):
        return _binary(_sub, self, other)

    def __rsub__(self, other):
        return _binary(_sub, other, self)

    def __mul__(self, other):
        return _binary(_mul, self, other)

    def __rmul__(self, other):
        return _binary(_mul, other, self)

    def __truediv__(self, other):
        return _binary(_div, self, other)

    def __rtruediv__(self, other):
        return _binary(_div, other, self)

    def __neg__(self):
        return _apply(_neg, self)

    def __pos__(self):
        return self

    def __abs__(self):
        return _apply(_abs, self)

    def __pow__(self, n):
        if not isinstance(n, (int, float, np.integer, np.floating)):
            return NotImplemented
        return _apply(lambda a: _power(a, n), self, stacklevel=4)


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


# --------------------------------------------------------------------------
# Module functions
# --------------------------------------------------------------------------

Operand = Union[Interval, IntervalArray, Number, np.ndarray]


def sqrt(x: Operand) -> Interval | IntervalArray:
    """Square root; an interval partly below 0 is clipped to ``[0, hi]`` with a warning.

    Raises ValueError for an interval entirely below 0.

    Examples
    --------
    >>> sqrt(Interval(4.0, 9.0))
    Interval(1.9999999999999998, 3.0000000000000004)
    """
    return _apply(_sqrt, x)


def exp(x: Operand) -> Interval | IntervalArray:
    """Exponential, widened by :data:`TRANSCENDENTAL_ULPS` ulps.

    Examples
    --------
    >>> exp(Interval(0.0, 1.0)).contains(Interval(1.0, 2.718281828459045))
    True
    """
    return _apply(_exp, x)


def log(x: Operand) -> Interval | IntervalArray:
    """Natural logarithm on ``(0, hi]``; a lower bound ``<= 0`` gives ``-inf`` with a warning.

    Raises ValueError for an interval with ``hi <= 0``.

    Examples
    --------
    >>> log(Interval(1.0, 1.0)).contains(0.0)
    True
    """
    return _apply(_log, x)


def abs_(x: Operand) -> Interval | IntervalArray:
    """Absolute value ``[max(lo, -hi, 0), max(-lo, hi)]`` (exact).

    Examples
    --------
    >>> abs_(Interval(-3.0, 2.0))
    Interval(0.0, 3.0)
    """
    return _apply(_abs, x)


iabs = abs_


def sign(x: Operand) -> Interval | IntervalArray:
    """Sign, ``[sign(lo), sign(hi)]`` (exact; nondecreasing).

    Examples
    --------
    >>> sign(Interval(-3.0, 0.0))
    Interval(-1.0, 0.0)
    """
    return _apply(_sign, x)


def minimum(x: Operand, y: Operand) -> Interval | IntervalArray:
    """Elementwise minimum ``[min(x.lo, y.lo), min(x.hi, y.hi)]`` (exact).

    Examples
    --------
    >>> minimum(Interval(0.0, 3.0), 1.0)
    Interval(0.0, 1.0)
    """
    return _apply(_min, x, y)


def maximum(x: Operand, y: Operand) -> Interval | IntervalArray:
    """Elementwise maximum ``[max(x.lo, y.lo), max(x.hi, y.hi)]`` (exact).

    Examples
    --------
    >>> maximum(Interval(0.0, 3.0), 1.0)
    Interval(1.0, 3.0)
    """
    return _apply(_max, x, y)


def tanh(x: Operand) -> Interval | IntervalArray:
    """Hyperbolic tangent (increasing), clipped to ``[-1, 1]``.

    Examples
    --------
    >>> tanh(Interval(-1e3, 1e3))
    Interval(-1.0, 1.0)
    """
    return _apply(_tanh, x)


def sin(x: Operand) -> Interval | IntervalArray:
    """Sine; the bound is exactly 1 (or -1) where the interval spans ``pi/2 + 2 k pi`` (``-pi/2 + 2 k pi``).

    Examples
    --------
    >>> sin(Interval(1.0, 2.0)).hi
    1.0
    >>> sin(Interval(0.0, 7.0))
    Interval(-1.0, 1.0)
    """
    return _apply(_sin, x)


def cos(x: Operand) -> Interval | IntervalArray:
    """Cosine; the bound is exactly 1 (or -1) where the interval spans ``2 k pi`` (``pi + 2 k pi``).

    Examples
    --------
    >>> cos(Interval(3.0, 3.5)).lo
    -1.0
    """
    return _apply(_cos, x)


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
    return _apply(lambda a: _power(a, n), x)


def enclose(value: sp.Expr | Fraction | float) -> Interval:
    """Tightest float interval containing a number (sympy number, Fraction, int or float).

    Exactly representable values give a degenerate interval, others the two
    doubles around them (one ulp wide).

    Examples
    --------
    >>> import sympy as sp
    >>> enclose(sp.Rational(1, 3))
    Interval(0.3333333333333333, 0.33333333333333337)
    >>> enclose(sp.Rational(3, 4))
    Interval(0.75, 0.75)
    """
    if isinstance(value, Fraction):
        value = sp.Rational(value.numerator, value.denominator)
    lo, hi = _constant(sp.sympify(value))
    return Interval._raw(float(lo), float(hi))


# --------------------------------------------------------------------------
# Compilation of sympy expressions
# --------------------------------------------------------------------------

Node = Callable[[Sequence[np.ndarray]], Pair]

_UNARY = {
    sp.exp: _exp,
    sp.log: _log,
    sp.Abs: _abs,
    sp.sign: _sign,
    sp.tanh: _tanh,
    sp.sin: _sin,
    sp.cos: _cos,
}
_NARY = {sp.Add: _add, sp.Min: _min, sp.Max: _max}


def _fraction(number: sp.Expr) -> Fraction:
    """Exact value of a sympy Rational, or of a Float's binary mantissa and exponent."""
    rational = sp.Rational(number)
    return Fraction(int(rational.p), int(rational.q))


def _bracket(exact: Fraction, certain: bool = True) -> Pair:
    """The two doubles around ``exact`` (a point when ``exact`` is a double).

    When the side of the nearest double is not ``certain`` (``exact`` is itself
    an approximation), both sides are widened.
    """
    try:
        value = np.float64(float(exact))  # correctly rounded division of integers
    except OverflowError:
        raise ValueError("constant beyond the float range (about 1.8e308)") from None
    if Fraction(value) == exact and certain:
        return _point(value)
    if not certain:
        return _rounded(value)
    return (value, _up(value)) if Fraction(value) < exact else (_down(value), value)


def _constant(expr: sp.Expr) -> Pair:
    """Tightest enclosure of a numeric sympy expression; a point when it is a double."""
    if not expr.is_number:
        raise ValueError(f"{expr} is not a number")
    if expr.is_Rational or expr.is_Float:
        return _bracket(_fraction(expr))
    approx = expr.evalf(40)
    if not (approx.is_Float and approx.is_finite):
        raise ValueError(f"constant {expr} is not a finite real number")
    # 40 digits decide the side of the nearest double unless it is within 2**-100 of it
    close = _fraction(approx)
    nearest = Fraction(float(close)) if abs(close) < 2**1023 else close
    return _bracket(close, certain=abs(nearest - close) > abs(close) / 2**100)


def _leaf(pair: Pair) -> Node:
    return lambda values: pair


def _point_leaf(index: int) -> Node:
    def node(values):
        v = values[index]
        return v, v

    return node


def _fold(kernel, nodes: list[Node]) -> Node:
    if len(nodes) == 1:
        return nodes[0]

    def node(values):
        acc = nodes[0](values)
        for child in nodes[1:]:
            acc = kernel(acc, child(values))
        return acc

    return node


def _unary(kernel, child: Node) -> Node:
    return lambda values: kernel(child(values))


def _compile_mul(expr: sp.Mul, env: _Env) -> Node:
    """Product as one division ``numerator / denominator``: fewer roundings than reciprocals."""
    numer, denom = [], []
    for factor in expr.args:
        if factor.is_Rational and not factor.is_Integer:
            numer.append(sp.Integer(factor.p))
            denom.append(sp.Integer(factor.q))
        elif factor.is_Pow and factor.exp.is_Integer and factor.exp < 0:
            denom.append(sp.Pow(factor.base, -factor.exp))
        else:
            numer.append(factor)
    numer = [f for f in numer if f != 1] or [sp.Integer(1)]
    # constant factors (numbers, interval symbols) first: their product stays a scalar
    numer.sort(key=env.varies)
    top = _fold(_mul, [_compile(f, env) for f in numer])
    if not denom:
        return top
    bottom = _fold(_mul, [_compile(f, env) for f in denom])
    return lambda values: _div(top(values), bottom(values))


def _compile_pow(expr: sp.Pow, env: _Env) -> Node:
    base = _compile(expr.base, env)
    e = expr.exp
    if e.is_Integer:
        n = int(e)
        return lambda values: _pow_int(base(values), n)
    if e.is_Rational and e.q == 2:
        p = int(e.p)
        return lambda values: _pow_int(_sqrt(base(values)), p)
    if e.is_number:
        r = _constant(e)
        if _is_point(r):  # a double exponent, e.g. 2.0 or 0.5
            n = float(r[0])
            return lambda values: _power(base(values), n)
        return lambda values: _real_pow(base(values), r)
    exponent = _compile(e, env)  # x**y = exp(y log x), defined for x > 0
    return lambda values: _exp(_mul(exponent(values), _log(base(values))))


def _compile(expr: sp.Basic, env: _Env) -> Node:
    """Closure computing the natural interval extension of ``expr``."""
    if expr in env.leaves:
        return env.leaves[expr]
    if expr.is_number:
        return _leaf(_constant(expr))
    node = _compile_operation(expr, env)
    if not env.varies(expr):
        return _leaf(node(()))  # no point symbol below: evaluate once, at compile time
    return node


def _compile_operation(expr: sp.Basic, env: _Env) -> Node:
    if expr.is_Symbol:
        raise ValueError(f"unknown symbol {expr}: neither a point nor an interval symbol")
    if expr.func in _NARY:
        return _fold(_NARY[expr.func], [_compile(arg, env) for arg in expr.args])
    if expr.is_Mul:
        return _compile_mul(expr, env)
    if expr.is_Pow:
        return _compile_pow(expr, env)
    if expr.func in _UNARY and len(expr.args) == 1:
        return _unary(_UNARY[expr.func], _compile(expr.args[0], env))
    raise ValueError(f"unsupported function {expr.func.__name__} in interval expression: {expr}")


class _Env:
    """Leaf nodes of a compilation: point symbols read their argument, interval symbols are constants."""

    def __init__(self, points: Sequence[sp.Symbol], intervals: Mapping[sp.Symbol, Any]) -> None:
        self.points = frozenset(points)
        self.leaves: dict = {}
        for index, symbol in enumerate(points):
            if symbol in self.leaves:
                raise ValueError(f"point symbol {symbol} given twice")
            self.leaves[symbol] = _point_leaf(index)
        for symbol, bounds in intervals.items():
            if symbol in self.leaves:
                raise ValueError(f"symbol {symbol} given both as a point and as an interval")
            box = bounds if isinstance(bounds, Interval) else Interval(*bounds)
            self.leaves[symbol] = _leaf((np.float64(box.lo), np.float64(box.hi)))

    def varies(self, expr: sp.Basic) -> bool:
        """Whether ``expr`` contains a point symbol, i.e. changes from sample to sample."""
        return bool(self.points) and expr.has(*self.points)


_CHUNK = 1 << 16  # samples per block: the temporaries of one block stay in cache


def _in_chunks(node: Node, arrays: list[np.ndarray], shape: tuple[int, ...]) -> Pair:
    """Evaluate ``node`` block by block over the broadcast samples (bounded memory, faster)."""
    size = math.prod(shape)
    if size <= _CHUNK:
        return _fit(*_sanitize(*node(arrays)), shape)
    flat = [a if a.ndim == 0 else np.broadcast_to(a, shape).reshape(-1) for a in arrays]
    lo, hi = np.empty(size), np.empty(size)
    for start in range(0, size, _CHUNK):
        block = slice(start, start + _CHUNK)
        lo[block], hi[block] = _sanitize(*node([a if a.ndim == 0 else a[block] for a in flat]))
    return lo.reshape(shape), hi.reshape(shape)


def _evaluator(node: Node, points: Sequence[sp.Symbol], expr: sp.Expr) -> Callable[..., IntervalArray]:
    names = ", ".join(str(p) for p in points)
    count = len(points)

    def evaluate(*values) -> IntervalArray:
        if len(values) != count:
            raise TypeError(f"expected {count} point value(s) ({names}), got {len(values)}")
        arrays = [np.asarray(v, dtype=float) for v in values]
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
        lo, hi = _guarded(lambda: _in_chunks(node, arrays, shape), 2)
        return IntervalArray._raw(lo, hi)

    evaluate.__doc__ = f"Interval enclosure of {expr} for point values ({names})."
    evaluate.expr = expr
    evaluate.points = tuple(points)
    return evaluate


def compile_interval(
    expr: sp.Expr,
    points: Sequence[sp.Symbol],
    intervals: Mapping[sp.Symbol, tuple[float, float]],
) -> Callable[..., IntervalArray]:
    """Compile the natural interval extension of a sympy expression into a vectorized evaluator.

    The sympy tree is walked once; the returned function runs numpy array
    operations only.

    Parameters
    ----------
    expr : sympy.Expr
        Built from Add, Mul, Pow (integer, half-integer or real exponents),
        exp, log, Abs, sign, Min, Max, tanh, sin, cos and numbers.
    points : sequence of sympy.Symbol
        Point-valued symbols, in the order of the evaluator's arguments.
    intervals : mapping
        Interval-valued symbols to their bounds ``(lo, hi)`` (or an Interval).

    Returns
    -------
    callable
        ``f(*values) -> IntervalArray``, the values broadcast together and
        processed in blocks of 65536 samples. A NaN (missing) point value
        gives the hull ``(-inf, inf)``, never a NaN bound.

    Raises
    ------
    ValueError
        For a symbol that is neither a point nor an interval, or an unsupported
        function (both named in the message).

    Examples
    --------
    >>> import sympy as sp
    >>> d, x1, x2 = sp.symbols("delta x1 x2")
    >>> f = compile_interval(d * x1 - d * x2, [x1, x2], {d: (-1.0, 1.0)})
    >>> b = f([1.0, 2.0], 1.0)
    >>> b.lo.tolist(), b.hi.tolist()
    ([-2.0000000000000004, -3.000000000000001], [2.0000000000000004, 3.000000000000001])

    The two occurrences of ``delta`` are treated as independent (dependency
    problem); :func:`range_linear` gives the exact range instead.
    """
    expr = sp.sympify(expr)
    node = _guarded(lambda: _compile(expr, _Env(points, intervals)), 2)
    return _evaluator(node, points, expr)


def _coefficient(expr: sp.Expr, delta: sp.Symbol, deltas: set) -> sp.Expr:
    """``d expr / d delta``, which must be free of every interval symbol."""
    g = sp.diff(expr, delta)
    if g.free_symbols & deltas:
        g = sp.expand(g)
    if g.free_symbols & deltas:
        raise ValueError(
            f"expression is not of the form g0 + sum(delta_i * g_i): its derivative in {delta} "
            f"still contains {sorted(map(str, g.free_symbols & deltas))}"
        )
    return g


def range_linear(
    expr: sp.Expr,
    points: Sequence[sp.Symbol],
    intervals: Mapping[sp.Symbol, tuple[float, float]],
) -> Callable[..., IntervalArray]:
    r"""Compile the exact range of an expression affine in its interval symbols.

    For :math:`f = g_0 + \sum_i \delta_i g_i` with :math:`g_i` free of interval
    symbols (the BG-LFT form), each :math:`\delta_i` appears once in the
    collected form, so its natural extension
    :math:`[g_0] + \sum_i [\delta_i][g_i]` is the exact range up to rounding:

    .. math:: \sum_i \min(\underline\delta_i g_i, \overline\delta_i g_i) + g_0
              \le f \le \sum_i \max(\underline\delta_i g_i, \overline\delta_i g_i) + g_0.

    Parameters and result as for :func:`compile_interval`; the evaluator has an
    attribute ``collected``, the collected sympy expression.

    Raises
    ------
    ValueError
        If the expression is not affine in the interval symbols (a product or a
        nonlinear function of them), or contains unknown symbols or functions.

    Examples
    --------
    >>> import sympy as sp
    >>> d, x1, x2 = sp.symbols("delta x1 x2")
    >>> f = range_linear(d * x1 - d * x2, [x1, x2], {d: (-1.0, 1.0)})
    >>> f.collected
    delta*(x1 - x2)
    >>> b = f([1.0, 2.0], 1.0)
    >>> b.lo.tolist(), b.hi.tolist()
    ([-1e-323, -1.0000000000000004], [1e-323, 1.0000000000000004])
    """
    expr = sp.sympify(expr)
    env = _Env(points, intervals)
    _guarded(lambda: _compile(expr, env), 2)  # rejects unknown symbols and unsupported functions
    deltas = set(intervals)
    terms = [(d, _coefficient(expr, d, deltas)) for d in intervals]
    terms = [(d, g) for d, g in terms if g != 0]
    g0 = expr.xreplace({d: 0 for d in intervals})
    base = _guarded(lambda: _compile(g0, env), 2)
    compiled = [(env.leaves[d](()), _guarded(lambda: _compile(g, env), 2)) for d, g in terms]

    def node(values):
        acc = base(values)
        for box, g in compiled:
            acc = _add(acc, _mul(box, g(values)))
        return acc

    collected = g0 + sp.Add(*[sp.Mul(d, sp.factor_terms(g), evaluate=False) for d, g in terms], evaluate=False)
    evaluate = _evaluator(node, points, collected)
    evaluate.collected = collected
    return evaluate
