"""Tests of diagnosis.intervals: soundness, outward rounding, dependency problem (speed: benchmarks/bench_intervals.py).

Soundness is checked two ways on seeded random boxes: (a) the float value of
the operation at random points of the boxes lies inside the interval result,
for every case; (b) the result contains the enclosure computed by mpmath's
``iv`` context at 50 digits (the oracle), on a subsample. Rational operations
are also checked exactly with :class:`fractions.Fraction` by hypothesis.
"""

from __future__ import annotations

import math
import warnings
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from mpmath import iv, mp, mpf

from diagnosis.intervals import (
    Interval,
    IntervalArray,
    IntervalWarning,
    absolute,
    affine_range,
    compile_interval,
    cos,
    enclose,
    exp,
    log,
    maximum,
    minimum,
    power,
    sign,
    sin,
    sqrt,
    tanh,
)

N = 20_000  # random cases per operation, all checked against point values
N_ORACLE = 1_500  # of which checked against the 50-digit mpmath oracle
EPS = np.finfo(float).eps
POWERS = [2, 3, 4, 5, 7, -1, -2, -3]
REAL_POWERS = [0.5, 1.5, 2.5, -0.5, 0.3]
EXACT_EXAMPLES = 1_500  # hypothesis examples of the exact rational checks


@pytest.fixture(autouse=True, scope="module")
def fifty_digits():
    """Run the oracle at 50 digits and restore mpmath's precision afterwards."""
    saved = iv.dps, mp.dps
    iv.dps, mp.dps = 50, 50
    yield
    iv.dps, mp.dps = saved


# --------------------------------------------------------------------------
# Random boxes and points
# --------------------------------------------------------------------------


def boxes(rng, n=N, centre=3.0, width=(-8, 1), positive=False):
    """Random intervals: centres over 10**[-centre, centre], widths over 10**width.

    A tenth are degenerate and a tenth straddle 0 (unless ``positive``).
    """
    mid = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-centre, centre, n)
    half = np.abs(mid) * 10.0 ** rng.uniform(*width, n) + 10.0 ** rng.uniform(-6, 0, n)
    lo, hi = mid - half * rng.uniform(0, 1, n), mid + half * rng.uniform(0, 1, n)
    hi[: n // 10] = lo[: n // 10]
    if not positive:
        lo[n // 10 : n // 5], hi[n // 10 : n // 5] = -half[n // 10 : n // 5], half[n // 10 : n // 5] * 0.7
    else:
        lo, hi = np.abs(lo), np.abs(hi)
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
    perm = rng.permutation(n)
    return lo[perm], hi[perm]


def points_in(rng, lo, hi):
    """Random points of each box, a tenth of them exactly at an end."""
    x = np.clip(lo + rng.uniform(0, 1, lo.shape) * (hi - lo), lo, hi)
    ends = rng.uniform(0, 1, lo.shape)
    return np.where(ends < 0.05, lo, np.where(ends < 0.1, hi, x))


def ivbox(lo: float, hi: float):
    return iv.mpf([float(lo), float(hi)])


def assert_encloses(result: IntervalArray, oracle, *args, idx) -> None:
    """``result[i]`` contains ``oracle(*intervals_i)`` computed at 50 digits."""
    for i in idx:
        exact = oracle(*(ivbox(lo[i], hi[i]) for lo, hi in args))
        assert mpf(float(result.lo[i])) <= exact.a, (i, result[i], exact)
        assert mpf(float(result.hi[i])) >= exact.b, (i, result[i], exact)


def iv_tanh(x):
    """Rigorous tanh for the oracle (mpmath's iv has none): 1 - 2 / (exp(2 x) + 1)."""
    return 1 - 2 / (iv.exp(2 * x) + 1)


def iv_sign(x):
    return iv.mpf([mp.sign(x.a), mp.sign(x.b)])


def iv_min(x, y):
    return iv.mpf([min(x.a, y.a), min(x.b, y.b)])


def iv_max(x, y):
    return iv.mpf([max(x.a, y.a), max(x.b, y.b)])


# --------------------------------------------------------------------------
# Soundness of single operations on random batches
# --------------------------------------------------------------------------

BINARY = {  # interval operation, float operation, oracle
    "add": (lambda x, y: x + y, np.add, lambda x, y: x + y),
    "sub": (lambda x, y: x - y, np.subtract, lambda x, y: x - y),
    "mul": (lambda x, y: x * y, np.multiply, lambda x, y: x * y),
    "div": (lambda x, y: x / y, np.divide, lambda x, y: x / y),
    "min": (minimum, np.minimum, iv_min),
    "max": (maximum, np.maximum, iv_max),
}


@pytest.mark.parametrize("name", sorted(BINARY))
def test_binary_operation_is_sound(name):
    op, point, oracle = BINARY[name]
    rng = np.random.default_rng(sorted(BINARY).index(name))
    xl, xh = boxes(rng)
    yl, yh = boxes(rng)
    if name == "div":  # keep 0 out of the divisor here; see the division tests below
        shift = np.where(yl > 0, 0.0, np.where(yh < 0, 0.0, yh - yl + 1.0))
        yl, yh = yl + shift, yh + shift
    X, Y = IntervalArray(xl, xh), IntervalArray(yl, yh)
    x, y = points_in(rng, xl, xh), points_in(rng, yl, yh)
    Z = op(X, Y)
    assert Z.contains(point(x, y)).all()
    assert_encloses(Z, oracle, (xl, xh), (yl, yh), idx=range(N_ORACLE))


def test_mixed_interval_point_operations_are_sound():
    """Interval op point and point op interval take the point fast paths."""
    rng = np.random.default_rng(7)
    xl, xh = boxes(rng)
    p = points_in(rng, *boxes(rng))
    X = IntervalArray(xl, xh)
    x = points_in(rng, xl, xh)
    nonzero = np.where(p == 0, 1.0, p)
    for Z, value in [(X * p, x * p), (p * X, p * x), (X / nonzero, x / nonzero), (p - X, p - x), (X + p, x + p)]:
        assert Z.contains(value).all()
    assert_encloses(p * X, lambda a, b: a * b, (p, p), (xl, xh), idx=range(N_ORACLE))


UNARY = {
    "sqrt": (sqrt, iv.sqrt, dict(positive=True)),
    "exp": (exp, iv.exp, dict(centre=1.8)),
    "log": (log, iv.log, dict(positive=True)),
    "abs": (absolute, abs, {}),
    "sign": (sign, iv_sign, {}),
    "tanh": (tanh, iv_tanh, dict(centre=1.5)),
    "sin": (sin, iv.sin, dict(centre=4, width=(-12, 0.5))),
    "cos": (cos, iv.cos, dict(centre=4, width=(-12, 0.5))),
}


@pytest.mark.parametrize("name", sorted(UNARY))
def test_unary_function_is_sound(name):
    fn, oracle, shape = UNARY[name]
    rng = np.random.default_rng(100 + sorted(UNARY).index(name))
    xl, xh = boxes(rng, **shape)
    if name == "log":
        xl = np.where(xl == 0, 1e-300, xl)
    X = IntervalArray(xl, xh)
    x = points_in(rng, xl, xh)
    Z = fn(X)
    reference = {"abs": np.abs}.get(name, getattr(np, name))
    assert Z.contains(reference(x)).all()
    assert_encloses(Z, oracle, (xl, xh), idx=range(N_ORACLE))


@pytest.mark.parametrize("n", POWERS)
def test_integer_power_is_sound(n):
    rng = np.random.default_rng(200 + n)
    xl, xh = boxes(rng, centre=1.5)
    if n < 0:  # 0 in the base is tested with division
        shift = np.where(xl > 0, 0.0, np.where(xh < 0, 0.0, xh - xl + 0.5))
        xl, xh = xl + shift, xh + shift
    X = IntervalArray(xl, xh)
    x = points_in(rng, xl, xh)
    Z = X**n
    assert Z.contains(np.power(x, float(n))).all()
    assert_encloses(Z, lambda a: a**n, (xl, xh), idx=range(N_ORACLE))
    if n % 2 == 0 and n > 0:
        straddle = (xl <= 0) & (xh >= 0)
        assert straddle.any() and (Z.lo[straddle] == 0.0).all()


@pytest.mark.parametrize("r", REAL_POWERS)
def test_real_power_is_sound(r):
    rng = np.random.default_rng(300 + int(10 * r))
    xl, xh = boxes(rng, centre=2, positive=True)
    X = IntervalArray(xl, xh)
    x = points_in(rng, xl, xh)
    Z = power(X, r)
    assert Z.contains(np.power(x, r)).all()
    assert_encloses(Z, lambda a: a ** mpf(r), (xl, xh), idx=range(N_ORACLE // 3))


def test_sin_cos_contain_interior_extrema():
    assert sin(Interval(1.0, 2.0)).hi == 1.0  # pi/2 inside
    assert sin(Interval(4.0, 5.0)).lo == -1.0  # 3 pi/2 inside
    assert cos(Interval(-0.1, 0.1)).hi == 1.0
    assert cos(Interval(3.0, 3.5)).lo == -1.0
    assert sin(Interval(-10.0, -9.0)).hi < 1.0  # no peak in [-10, -9]
    far = 2 * math.pi * 1e5 + math.pi / 2  # a peak far from 0
    assert sin(Interval(far - 1e-3, far + 1e-3)).hi == 1.0
    assert sin(Interval(0.0, 100.0)) == Interval(-1.0, 1.0)


# --------------------------------------------------------------------------
# Exact checks of rational operations with hypothesis
# --------------------------------------------------------------------------

finite = st.floats(min_value=-1e12, max_value=1e12, allow_nan=False, allow_infinity=False)


@st.composite
def interval_and_point(draw, values=finite):
    a, b = draw(values), draw(values)
    t = draw(st.floats(min_value=0.0, max_value=1.0))
    lo, hi = min(a, b), max(a, b)
    x = min(max(lo + t * (hi - lo), lo), hi)
    return Interval(lo, hi), x


EXACT = {
    "+": lambda x, y: x + y,
    "-": lambda x, y: x - y,
    "*": lambda x, y: x * y,
    "/": lambda x, y: x / y,
}


def contains_exactly(Z: Interval, value: Fraction) -> bool:
    """``Z.lo <= value <= Z.hi`` in exact arithmetic (infinite bounds allowed)."""
    above = Z.lo == -math.inf or Fraction(Z.lo) <= value
    below = Z.hi == math.inf or value <= Fraction(Z.hi)
    return above and below


@pytest.mark.slow  # 1500 exact rational cases: 2-3 s
@settings(max_examples=EXACT_EXAMPLES, deadline=None, derandomize=True, database=None)
@given(interval_and_point(), interval_and_point(), st.sampled_from(sorted(EXACT)))
def test_rational_operations_contain_the_exact_value(a, b, op):
    (X, x), (Y, y) = a, b
    if op == "/" and Y.contains(0.0):
        return
    Z = EXACT[op](X, Y)
    assert contains_exactly(Z, EXACT[op](Fraction(x), Fraction(y)))
    assert contains_exactly(EXACT[op](X, y), EXACT[op](Fraction(x), Fraction(y)))
    assert contains_exactly(EXACT[op](x, Y), EXACT[op](Fraction(x), Fraction(y)))


@pytest.mark.filterwarnings("ignore::diagnosis.intervals.IntervalWarning")  # x**-6 may underflow to [0, tiny]
@settings(max_examples=1000, deadline=None, derandomize=True, database=None)
@given(
    interval_and_point(st.floats(min_value=-1e3, max_value=1e3, allow_nan=False)),
    st.integers(min_value=-6, max_value=9),
)
@pytest.mark.slow
def test_integer_power_contains_the_exact_value(a, n):
    X, x = a
    if n < 0 and X.contains(0.0):
        return
    assert contains_exactly(X**n, Fraction(x) ** n)


# --------------------------------------------------------------------------
# Compiled sympy expressions
# --------------------------------------------------------------------------

x, y, d1, d2 = sp.symbols("x y delta_1 delta_2")
BOX = {d1: (-0.1, 0.2), d2: (-0.05, 0.05)}
EXPRESSIONS = [
    -(d1 * 0.5 * x + d2 * 1.3 * y + (d1 * 2.7 * x + d2 * 0.01 * y) / 3.75),
    x * (1 + d1) - y**2 * (1 + d2) / 3 + sp.Rational(1, 7) * x * y,
    sp.sqrt(sp.Abs(x)) * (1 + d1) + sp.exp(d2 * y / 10) * sp.sign(x),
    sp.sin(x * (1 + d1)) + sp.cos(y + d2) * sp.tanh(x * d1),
    sp.Min(x, y * (1 + d1)) - sp.Max(x * d2, y) + sp.pi * d1,
    sp.log(1 + x**2 * (1 + d1)) / (2 + d2) + x**-2,
    (x**3 * (1 + d1) + y**4 * d2) * sp.exp(-sp.Abs(x)),
    sp.sqrt(x**2 + y**2) * (1 + d1) ** sp.Rational(3, 2),
    (1 + d1) ** (-2) * x + y / (1 + d2) - d1 * d2 * x * y,
]


def iv_eval(expr, env):
    """Natural interval extension of ``expr`` in mpmath's iv context (the oracle)."""
    if expr in env:
        return env[expr]
    if expr.is_Rational:
        return iv.mpf(int(expr.p)) / int(expr.q)
    if expr.is_Float:
        return iv.mpf(float(expr))
    if expr == sp.pi:
        return iv.pi
    args = [iv_eval(a, env) for a in expr.args]
    if expr.is_Add:
        return sum(args[1:], args[0])
    if expr.is_Mul:
        result = args[0]
        for a in args[1:]:
            result = result * a
        return result
    if expr.is_Pow:
        base = args[0]
        if expr.exp.is_Integer:
            return base ** int(expr.exp)
        return iv.sqrt(base) if expr.exp == sp.S.Half else base ** mpf(float(expr.exp))
    table = {
        sp.exp: iv.exp,
        sp.log: iv.log,
        sp.sin: iv.sin,
        sp.cos: iv.cos,
        sp.tanh: iv_tanh,
        sp.Abs: abs,
        sp.sign: iv_sign,
        sp.Min: iv_min,
        sp.Max: iv_max,
    }
    return table[expr.func](*args)


@pytest.mark.parametrize("k", range(len(EXPRESSIONS)))
def test_compiled_expression_is_sound(k):
    expr = EXPRESSIONS[k]
    rng = np.random.default_rng(400 + k)
    xs = rng.standard_normal(N) * 10.0 ** rng.uniform(-1, 1.5, N)
    ys = rng.standard_normal(N) * 10.0 ** rng.uniform(-1, 1.5, N)
    B = compile_interval(expr, [x, y], BOX)(xs, ys)
    assert B.shape == (N,)
    # (a) point values for deltas drawn strictly inside the box
    point = sp.lambdify([x, y, d1, d2], expr, "numpy")
    for _ in range(3):
        u1, u2 = (rng.uniform(0.01, 0.99, N) for _ in range(2))
        v = point(xs, ys, -0.1 + 0.3 * u1, -0.05 + 0.1 * u2)
        assert B.contains(v).all()
    # (b) the natural extension evaluated by mpmath at 50 digits
    for i in range(N_ORACLE // 5):
        env = {x: iv.mpf(float(xs[i])), y: iv.mpf(float(ys[i])), d1: ivbox(*BOX[d1]), d2: ivbox(*BOX[d2])}
        exact = iv_eval(expr, env)
        assert mpf(float(B.lo[i])) <= exact.a and mpf(float(B.hi[i])) >= exact.b, (i, B[i], exact)


def test_compiled_evaluator_broadcasts_and_checks_arguments():
    f = compile_interval(d1 * x + y, [x, y], BOX)
    assert f(np.ones((2, 3)), 1.0).shape == (2, 3)
    assert f(1.0, 2.0).shape == ()
    assert compile_interval(d1 + sp.pi, [], BOX)().contains(Interval(math.pi - 0.1, math.pi + 0.2)).all()
    with pytest.raises(TypeError, match="expected 2"):
        f(1.0)


def test_unknown_symbols_and_functions_are_named():
    with pytest.raises(ValueError, match="omega_m"):
        compile_interval(sp.Function("omega_m")(sp.Symbol("t")), [x], BOX)
    with pytest.raises(ValueError, match="unknown symbol z"):
        compile_interval(x + sp.Symbol("z"), [x], BOX)
    with pytest.raises(ValueError, match="floor"):
        compile_interval(sp.floor(x), [x], BOX)
    with pytest.raises(ValueError, match="both"):
        compile_interval(x, [x], {x: (0.0, 1.0)})


# --------------------------------------------------------------------------
# Outward rounding
# --------------------------------------------------------------------------


def test_outward_rounding_contains_the_decimal_sum():
    Z = Interval(0.1, 0.1) + Interval(0.2, 0.2)
    assert contains_exactly(Z, Fraction(3, 10))
    assert Z.lo < 0.1 + 0.2 < Z.hi  # widened on both sides of the rounded sum
    assert mpf(Z.lo) <= mpf("0.3") <= mpf(Z.hi)


def test_non_representable_constants_are_widened():
    third = enclose(sp.Rational(1, 3))
    assert third.lo < third.hi and contains_exactly(third, Fraction(1, 3))
    assert enclose(sp.Rational(3, 8)) == Interval(0.375, 0.375)  # a double: kept exact
    assert enclose(Fraction(1, 10)).contains(0.1) and contains_exactly(enclose(Fraction(1, 10)), Fraction(1, 10))
    pi = enclose(sp.pi)
    assert mpf(pi.lo) < mp.pi < mpf(pi.hi)
    f = compile_interval(sp.Rational(1, 3) * x, [x], {})
    assert contains_exactly(f(1.0)[()], Fraction(1, 3))
    long_float = sp.Float("0.1", 40)  # more than 53 bits
    assert contains_exactly(enclose(long_float), Fraction(sp.Rational(long_float).p, sp.Rational(long_float).q))


def test_bounds_move_exactly_one_ulp_for_correctly_rounded_operations():
    special = np.array([0.0, -0.0, 5e-324, -5e-324, 1.0, -1.0, 2.0, -2.0, 1e308, -1e308, 3.7, -2.2e-308])
    rng = np.random.default_rng(11)
    values = np.concatenate([special, rng.standard_normal(1000) * 10.0 ** rng.uniform(-300, 300, 1000)])
    Z = IntervalArray(values) + Interval(0.0, 0.0)  # exact sum, then one step out
    assert (Z.lo == np.nextafter(values, -np.inf)).all()
    assert (Z.hi == np.nextafter(values, np.inf)).all()
    top = Interval(1e308, 1e308) + Interval(1e308, 1e308)  # overflow stays sound
    assert top.lo == np.finfo(float).max and top.hi == math.inf


def test_exact_operations_are_not_widened():
    X = Interval(-3.0, 2.0)
    assert absolute(X) == Interval(0.0, 3.0) and abs(X) == absolute(X)
    assert -X == Interval(-2.0, 3.0)
    assert sign(X) == Interval(-1.0, 1.0)
    assert minimum(X, 1.0) == Interval(-3.0, 1.0) and maximum(X, 1.0) == Interval(1.0, 2.0)
    assert (X**2).lo == 0.0 and X * 1 == X and X + 0 == X


# --------------------------------------------------------------------------
# Dependency problem and the exact range of the BG-LFT form
# --------------------------------------------------------------------------


def test_dependency_problem():
    delta = Interval(-1.0, 1.0)
    assert (delta - delta).contains(Interval(-2.0, 2.0))
    f = compile_interval(sp.Add(d1, -d1, evaluate=False), [], {d1: (-1.0, 1.0)})
    B = f()
    assert B.lo <= -2.0 and B.hi >= 2.0
    g = affine_range(sp.Add(d1, -d1, evaluate=False), [], {d1: (-1.0, 1.0)})
    assert g().lo == 0.0 and g().hi == 0.0


@pytest.mark.slow
def test_affine_range_is_exact_on_the_bg_lft_form():
    x1, x2, x3 = sp.symbols("x1 x2 x3")
    d3, d4 = sp.symbols("delta_3 delta_4")
    box = {d1: (-0.05, 0.05), d2: (0.0, 0.2), d3: (-0.1, 0.1), d4: (-0.02, 0.03)}
    # delta_1 and delta_2 occur twice: the natural extension overestimates
    expr = -(d1 * 0.5 * x1 + d2 * 1.3 * x2 + (d3 * 2.7 * x1 + d4 * 0.01 * x3) / 3.75) + d1 * x2 * x3 - d2 * x1
    rng = np.random.default_rng(5)
    X = [rng.standard_normal(N) * 10.0 ** rng.uniform(-1, 2, N) for _ in range(3)]
    exact = affine_range(expr, [x1, x2, x3], box)(*X)
    natural = compile_interval(expr, [x1, x2, x3], box)(*X)
    # both enclose the range; the collected form is narrower unless the signs line up
    assert (natural.width >= exact.width * (1 - 1e-12)).all()
    assert (natural.width > exact.width * (1 + 1e-6)).mean() > 0.5
    vertex = sp.lambdify([x1, x2, x3, d1, d2, d3, d4], expr, "mpmath")
    corners = [dict(zip(box, c)) for c in np.array(np.meshgrid(*box.values())).reshape(4, -1).T]
    for i in range(300):
        pts = [mpf(float(v[i])) for v in X]
        values = [vertex(*pts, *(mpf(c[d]) for d in box)) for c in corners]
        low, high = min(values), max(values)
        scale = max(abs(v) for v in values) + sum(abs(p) for p in pts) * 0.2
        assert mpf(float(exact.lo[i])) <= low and mpf(float(exact.hi[i])) >= high
        assert low - mpf(float(exact.lo[i])) <= 16 * EPS * scale, i  # a few ulps, never narrower
        assert mpf(float(exact.hi[i])) - high <= 16 * EPS * scale, i


def test_affine_range_rejects_non_affine_forms():
    for bad in [d1 * d2 * x, d1**2 * x, sp.sin(d1) * x, x / (1 + d1)]:
        with pytest.raises(ValueError, match="delta"):
            affine_range(bad, [x], BOX)


# --------------------------------------------------------------------------
# Domain errors and warnings
# --------------------------------------------------------------------------


def test_division_by_an_interval_containing_zero():
    with pytest.warns(IntervalWarning, match="1 element"):
        Z = Interval(1.0, 2.0) / Interval(-1.0, 1.0)
    assert Z == Interval(-math.inf, math.inf)
    divisor = IntervalArray([-1.0, 1.0, 0.0, -2.0, 0.0], [1.0, 2.0, 0.0, -1.0, 3.0])
    with pytest.warns(IntervalWarning, match="3 element"):
        Z = 1.0 / divisor
    assert not np.isnan(Z.lo).any() and not np.isnan(Z.hi).any()
    assert np.isinf(Z.lo[[0, 2, 4]]).all() and np.isfinite(Z.lo[[1, 3]]).all()
    f = compile_interval(x / d1, [x], {d1: (-1.0, 1.0)})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        B = f(np.arange(200_000.0))
    assert [str(w.message) for w in caught] == [
        "division by an interval containing 0 in 200000 element(s); result set to (-inf, inf)"
    ]
    assert (B.lo == -math.inf).all() and (B.hi == math.inf).all()


def test_short_and_long_arrays_step_to_the_same_floats():
    """up and down take nextafter on short arrays and bit operations on long ones: the same floats, bit for bit."""
    from diagnosis.intervals import rounding

    tiny, huge = 5e-324, float(np.finfo(float).max)
    special = [0.0, -0.0, math.inf, -math.inf, math.nan, tiny, -tiny, huge, -huge, 1.0, -1.0, 2.2250738585072014e-308]
    rng = np.random.default_rng(11)
    values = np.concatenate([special, rng.standard_normal(400) * 10.0 ** rng.integers(-300, 300, 400)])
    for step in (rounding.up, rounding.down):
        with np.errstate(over="ignore"):  # as inside rounding.guarded, where the kernels call them
            long = step(values)  # above the short size: bit operations
            short = np.concatenate([step(values[i:i + 100]) for i in range(0, values.size, 100)])
            expected = np.nextafter(values, (1 if step is rounding.up else -1) * math.inf)
        assert values.size > rounding._SHORT >= 100
        assert np.array_equal(long.view(np.int64), short.view(np.int64))
        finite = np.isfinite(values)
        assert np.array_equal(long[finite], expected[finite])


def test_a_missing_point_gives_the_whole_line_whatever_the_arrays_length():
    """A NaN point value is a missing sample: (-inf, inf), never a finite bound made of a NaN's bits."""
    from diagnosis.intervals import rounding

    assert rounding.up(np.array([np.nan])).tolist() == [math.inf]
    assert rounding.down(np.array([np.nan])).tolist() == [-math.inf]
    every_bit = np.array([0x7FFFFFFFFFFFFFFF, -1], dtype=np.int64).view(float)  # NaNs numpy's loops may produce
    assert rounding.up(every_bit).tolist() == [math.inf] * 2  # the first stepped to -0.0
    assert rounding.down(every_bit).tolist() == [-math.inf] * 2
    f = affine_range(d1 * (-6.5e-5 * x) + d2 * (2.0 * x), [x], {d1: (0.0, 0.2), d2: (-0.05, 0.05)})
    for n in (1, 3, 14, 100):
        values = np.linspace(1.0, 2.0, n)
        values[n // 2] = np.nan
        band = f(values)
        assert band.lo[n // 2] == -math.inf and band.hi[n // 2] == math.inf
        assert np.isfinite(np.delete(band.lo, n // 2)).all() and np.isfinite(np.delete(band.hi, n // 2)).all()


def test_sqrt_and_log_domains():
    with pytest.raises(ValueError, match="sqrt"):
        sqrt(Interval(-2.0, -1.0))
    with pytest.raises(ValueError, match="log"):
        log(Interval(-1.0, 0.0))
    with pytest.warns(IntervalWarning, match="sqrt"):
        assert sqrt(Interval(-1.0, 4.0)).contains(Interval(0.0, 2.0))
    with pytest.warns(IntervalWarning, match="log"):
        assert log(Interval(0.0, 1.0)).lo == -math.inf
    with pytest.raises(ValueError, match="sqrt"):
        compile_interval(sp.sqrt(x), [x], {})(np.array([1.0, -1.0]))


# --------------------------------------------------------------------------
# Types
# --------------------------------------------------------------------------


def test_interval_validation_and_immutability():
    with pytest.raises(ValueError):
        Interval(2.0, 1.0)
    with pytest.raises(ValueError):
        Interval(math.nan, 1.0)
    with pytest.raises(ValueError):
        IntervalArray([0.0, 2.0], [1.0, 1.0])
    X = Interval(1.0, 2.0)
    with pytest.raises(AttributeError):
        X.lo = 0.0
    assert (X.width, X.mid, 1.5 in X, repr(X)) == (1.0, 1.5, True, "Interval(1.0, 2.0)")


@pytest.mark.parametrize(
    "left, right",
    [
        (Interval(1.0, 2.0), IntervalArray([1.0, 2.0], [3.0, 4.0])),
        (np.array([1.0, 2.0]), Interval(1.0, 2.0)),
        (np.array([1.0, 2.0]), IntervalArray([1.0, 2.0], [3.0, 4.0])),
        (np.float64(2.0), IntervalArray([1.0, 2.0], [3.0, 4.0])),
        (3, IntervalArray([1.0, 2.0], [3.0, 4.0])),
    ],
)
def test_mixed_operands_in_any_order(left, right):
    for a, b in [(left, right), (right, left)]:
        for op in [lambda p, q: p + q, lambda p, q: p - q, lambda p, q: p * q, lambda p, q: p / q]:
            Z = op(a, b)
            assert isinstance(Z, IntervalArray) and Z.shape == (2,)
            lower_ends = [np.broadcast_to(getattr(v, "lo", v), (2,)) for v in (a, b)]
            assert Z.contains(op(*lower_ends)).all()
    assert isinstance(2.0 * Interval(1.0, 2.0), Interval)
    assert isinstance(np.float64(2.0) * Interval(1.0, 2.0), Interval)


def test_interval_array_indexing():
    X = IntervalArray([0.0, 1.0, 2.0], [1.0, 2.0, 3.0])
    assert len(X) == 3 and X[1] == Interval(1.0, 2.0)
    assert isinstance(X[1:], IntervalArray) and X[1:].shape == (2,)
    assert [Z.lo for Z in X] == [0.0, 1.0, 2.0]


def test_midpoints_of_unbounded_intervals_agree_between_scalar_and_array():
    ends = [(-math.inf, math.inf), (-math.inf, 1.0), (1.0, math.inf), (-1e308, 1e308), (1.0, 3.0)]
    X = IntervalArray(*zip(*ends))
    assert X.mid.tolist() == [Interval(lo, hi).mid for lo, hi in ends] == [0.0, -math.inf, math.inf, 0.0, 2.0]


# --------------------------------------------------------------------------
# A million samples (how fast: benchmarks/bench_intervals.py)
# --------------------------------------------------------------------------


def test_compiled_evaluation_of_a_million_samples():
    x1, x2, x3 = sp.symbols("x1 x2 x3")
    d3, d4 = sp.symbols("delta_3 delta_4")
    a, b, c, d = 0.5, 1.3, 2.7, 0.01
    expr = -(d1 * a * x1 + d2 * b * x2 + (d3 * c * x1 + d4 * d * x3) / 3.75)
    box = {d1: (-0.05, 0.05), d2: (0.0, 0.2), d3: (-0.1, 0.1), d4: (-0.02, 0.03)}
    f = compile_interval(expr, [x1, x2, x3], box)
    X = [np.random.default_rng(i).standard_normal(1_000_000) for i in range(3)]
    B = f(*X)
    assert B.shape == (1_000_000,)


def test_random_case_budget():
    """The random tests above check well over 10**5 cases against point values."""
    batches = len(BINARY) + 5 + len(UNARY) + len(POWERS) + len(REAL_POWERS) + 3 * len(EXPRESSIONS) + 1
    oracle = N_ORACLE * (len(BINARY) + 1 + len(UNARY) + len(POWERS)) + N_ORACLE // 3 * len(REAL_POWERS)
    assert N * batches + 3 * EXACT_EXAMPLES >= 10**6 and oracle >= 3 * 10**4
