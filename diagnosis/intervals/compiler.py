"""Compilation of sympy expressions into vectorized interval evaluators, and enclosure of exact constants.

:func:`compile_interval` builds the natural interval extension of an
expression; :func:`affine_range` the exact range of an affine form of
independent intervals; :func:`enclose` the tightest interval around a number.
The sympy tree is walked once, into closures that run the pair kernels of
:mod:`~diagnosis.intervals.kernels` on numpy arrays.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp

from . import interval, kernels, rounding
from .interval import Interval, IntervalArray
from .kernels import Pair

__all__ = ["EXPAND_LIMIT", "Node", "affine_range", "compile_interval", "enclose", "product_parts"]

Node = Callable[[Sequence[np.ndarray]], Pair]

_UNARY = {
    sp.exp: kernels.exp,
    sp.log: kernels.log,
    sp.Abs: kernels.absolute,
    sp.sign: kernels.sign,
    sp.tanh: kernels.tanh,
    sp.sin: kernels.sin,
    sp.cos: kernels.cos,
}
_NARY = {sp.Add: kernels.add, sp.Min: kernels.minimum, sp.Max: kernels.maximum}


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
        return kernels.point(value)
    if not certain:
        return rounding.rounded(value)
    return (value, rounding.up(value)) if Fraction(value) < exact else (rounding.down(value), value)


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
    return interval.trusted_interval(float(lo), float(hi))


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


def product_parts(expr: sp.Mul) -> tuple[list, list]:
    """A product's factors as ``(numerator, denominator)``: a fraction split, a negative integer power
    moved below; the numerator never empty.  One division then rounds once, where reciprocals round each.

    >>> x, y = sp.symbols("x y")
    >>> product_parts(sp.Rational(3, 4) * x / y**2)
    ([3, x], [4, y**2])
    """
    numer, denom = [], []
    for factor in expr.args:
        if factor.is_Rational and not factor.is_Integer:
            numer.append(sp.Integer(factor.p))
            denom.append(sp.Integer(factor.q))
        elif factor.is_Pow and factor.exp.is_Integer and factor.exp < 0:
            denom.append(sp.Pow(factor.base, -factor.exp))
        else:
            numer.append(factor)
    return [f for f in numer if f != 1] or [sp.Integer(1)], denom


def _compile_mul(expr: sp.Mul, env: _Env) -> Node:
    """Product as one division ``numerator / denominator``: fewer roundings than reciprocals."""
    numer, denom = product_parts(expr)
    # constant factors (numbers, interval symbols) first: their product stays a scalar
    numer.sort(key=env.varies)
    top = _fold(kernels.mul, [_compile(f, env) for f in numer])
    if not denom:
        return top
    bottom = _fold(kernels.mul, [_compile(f, env) for f in denom])
    return lambda values: kernels.div(top(values), bottom(values))


def _compile_pow(expr: sp.Pow, env: _Env) -> Node:
    base = _compile(expr.base, env)
    e = expr.exp
    if e.is_Integer:
        n = int(e)
        return lambda values: kernels.pow_int(base(values), n)
    if e.is_Rational and e.q == 2:
        p = int(e.p)
        return lambda values: kernels.pow_int(kernels.sqrt(base(values)), p)
    if e.is_number:
        r = _constant(e)
        if kernels.is_point(r):  # a double exponent, e.g. 2.0 or 0.5
            n = float(r[0])
            return lambda values: kernels.power(base(values), n)
        return lambda values: kernels.real_pow(base(values), r)
    exponent = _compile(e, env)  # x**y = exp(y log x), defined for x > 0
    return lambda values: kernels.exp(kernels.mul(exponent(values), kernels.log(base(values))))


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
        return interval.fit(*rounding.sanitize(*node(arrays)), shape)
    flat = [a if a.ndim == 0 else np.broadcast_to(a, shape).reshape(-1) for a in arrays]
    lo, hi = np.empty(size), np.empty(size)
    for start in range(0, size, _CHUNK):
        block = slice(start, start + _CHUNK)
        lo[block], hi[block] = rounding.sanitize(*node([a if a.ndim == 0 else a[block] for a in flat]))
    return lo.reshape(shape), hi.reshape(shape)


def _evaluator(node: Node, points: Sequence[sp.Symbol], expr: sp.Expr) -> Callable[..., IntervalArray]:
    names = ", ".join(str(p) for p in points)
    count = len(points)

    def evaluate(*values) -> IntervalArray:
        if len(values) != count:
            raise TypeError(f"expected {count} point value(s) ({names}), got {len(values)}")
        arrays = [np.asarray(v, dtype=float) for v in values]
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
        lo, hi = rounding.guarded(lambda: _in_chunks(node, arrays, shape), 2)
        return interval.trusted_array(lo, hi)

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
    problem); :func:`affine_range` gives the exact range instead.
    """
    expr = sp.sympify(expr)
    node = rounding.guarded(lambda: _compile(expr, _Env(points, intervals)), 2)
    return _evaluator(node, points, expr)


#: The largest derivative (sympy operations) :func:`affine_range` expands to collect it: nested non-linear
#: laws expand without bound, and the natural extension is sound for them anyway.
EXPAND_LIMIT = 200


def _coefficient(expr: sp.Expr, delta: sp.Symbol, deltas: set) -> sp.Expr:
    """``d expr / d delta``, which must be free of every interval symbol."""
    g = sp.diff(expr, delta)
    if g.free_symbols & deltas and sp.count_ops(g) > EXPAND_LIMIT:
        raise ValueError(f"expression is too large to collect in {delta} ({sp.count_ops(g)} operations)")
    if g.free_symbols & deltas:
        g = sp.expand(g)
    if g.free_symbols & deltas:
        raise ValueError(
            f"expression is not of the form g0 + sum(delta_i * g_i): its derivative in {delta} "
            f"still contains {sorted(map(str, g.free_symbols & deltas))}"
        )
    return g


def affine_range(
    expr: sp.Expr,
    points: Sequence[sp.Symbol],
    intervals: Mapping[sp.Symbol, tuple[float, float]],
) -> Callable[..., IntervalArray]:
    r"""Compile the exact range of an affine form of independent intervals.

    The expression must be an affine form :math:`f = g_0 + \sum_i \delta_i g_i`
    of its interval symbols: each :math:`\delta_i` ranges over its interval
    independently of the others, and :math:`g_0` and the coefficients
    :math:`g_i` depend on the point symbols only (the BG-LFT form). Collected
    that way, each :math:`\delta_i` occurs once, so the natural extension
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
    >>> f = affine_range(d * x1 - d * x2, [x1, x2], {d: (-1.0, 1.0)})
    >>> f.collected
    delta*(x1 - x2)
    >>> b = f([1.0, 2.0], 1.0)
    >>> b.lo.tolist(), b.hi.tolist()
    ([-1e-323, -1.0000000000000004], [1e-323, 1.0000000000000004])
    """
    expr = sp.sympify(expr)
    env = _Env(points, intervals)
    rounding.guarded(lambda: _compile(expr, env), 2)  # rejects unknown symbols and unsupported functions
    deltas = set(intervals)
    terms = [(d, _coefficient(expr, d, deltas)) for d in intervals]
    terms = [(d, g) for d, g in terms if g != 0]
    g0 = expr.xreplace({d: 0 for d in intervals})
    base = rounding.guarded(lambda: _compile(g0, env), 2)
    compiled = [(env.leaves[d](()), rounding.guarded(lambda: _compile(g, env), 2)) for d, g in terms]

    def node(values):
        acc = base(values)
        for box, g in compiled:
            acc = kernels.add(acc, kernels.mul(box, g(values)))
        return acc

    collected = g0 + sp.Add(*[sp.Mul(d, sp.factor_terms(g), evaluate=False) for d, g in terms], evaluate=False)
    evaluate = _evaluator(node, points, collected)
    evaluate.collected = collected
    return evaluate
