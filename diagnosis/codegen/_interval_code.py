"""The interval threshold as straight-line code: the library's interval operations on Psi_2, in the same order,
each bound rounded outward by one ``nextafter`` (transcendental results widened as the library widens them)."""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from ..intervals import compile_interval, enclose, kernels, product_parts, rounding
from ._errors import CodegenError
from ._plan import Plan

__all__ = ["interval_code", "transcendental_widening"]


class _Value:
    """An interval value at generation time: a constant pair (``lo is hi`` for an exact point, as in the
    library's kernels), a point computed at run time (one double), or a pair computed at run time."""

    def __init__(self, kind: str, lo, hi=None) -> None:
        self.kind, self.lo, self.hi = kind, lo, lo if hi is None else hi

    @property
    def point(self) -> bool:
        return self.kind == "point" or (self.kind == "const" and self.lo is self.hi)


class _IntervalEmitter:
    """Straight-line code for the library's interval evaluator of Psi_2, operation for operation.

    Each method mirrors a kernel of :mod:`diagnosis.intervals.kernels` (the same branches, decided at
    generation time from which values are exact points), so that the generated bounds are the library's.
    """

    def __init__(self, lang: str, name: str, boxes: dict, points: list) -> None:
        self.lang, self.name, self.boxes = lang, name, boxes
        self.leaves = {p: _Value("point", f"p{k}") for k, p in enumerate(points)}
        for d, (lo, hi) in boxes.items():
            self.leaves[d] = _Value("const", np.float64(lo), np.float64(hi))
        self.point_set = frozenset(points)
        self.lines: list[tuple[str, str]] = []
        self.memo: dict = {}

    # -- text ------------------------------------------------------------------------------------------
    def num(self, x) -> str:
        x = float(x)
        if math.isnan(x):
            return "math.nan" if self.lang == "python" else "NAN"
        if math.isinf(x):
            text = "_INF" if self.lang == "python" else "INFINITY"
            return text if x > 0 else "-" + text
        return repr(x) if self.lang == "python" else f"({x!r})"

    def text(self, v: _Value, side: str) -> str:
        bound = v.lo if side == "lo" else v.hi
        return self.num(bound) if v.kind == "const" else bound

    def call(self, op: str, *args: str) -> str:
        names = {"down": ("_down", "bg_down"), "up": ("_up", "bg_up"), "mn": ("_mn", "bg_mn"),
                 "mx": ("_mx", "bg_mx"), "fmn": ("_fmn", "fmin"), "fmx": ("_fmx", "fmax"),
                 "sqrt": ("_sqrt", "sqrt"), "exp": ("_exp", "exp"), "log": ("_log", "log"),
                 "tanh": ("math.tanh", "tanh"), "abs": ("abs", "fabs"), "sign": ("_sign", "bg_sign"),
                 "dt": ("_dt", "bg_dt"), "ut": ("_ut", "bg_ut"), "pw": ("_pw", "pow")}
        return f"{names[op][self.lang == 'c']}({', '.join(args)})"

    def div_text(self, a: str, b: str) -> str:
        return f"_q({a}, {b})" if self.lang == "python" else f"({a} / {b})"

    def where(self, condition: str, yes: str, no: str) -> str:
        if self.lang == "python":
            return f"({yes} if {condition} else {no})"
        return f"(({condition}) ? {yes} : {no})"

    def both(self, a: str, b: str) -> str:
        return f"{a} and {b}" if self.lang == "python" else f"{a} && {b}"

    def tmp(self, text: str) -> str:
        name = f"a{len(self.lines)}"
        self.lines.append((name, text))
        return name

    def pair(self, lo: str, hi: str) -> _Value:
        return _Value("pair", self.tmp(lo), self.tmp(hi))

    def const(self, pair) -> _Value:
        return _Value("const", pair[0], pair[1])

    # -- kernels -----------------------------------------------------------------------------------------
    def add(self, a: _Value, b: _Value) -> _Value:
        if a.kind == "const" and b.kind == "const":
            return self.const(rounding.guarded(lambda: kernels.add((a.lo, a.hi), (b.lo, b.hi)), 2))
        if self._zero(a) or self._zero(b):
            return b if self._zero(a) else a
        if a.point and b.point:
            s = self.tmp(f"{self.text(a, 'lo')} + {self.text(b, 'lo')}")
            return self.pair(self.call("down", s), self.call("up", s))
        return self.pair(self.call("down", f"{self.text(a, 'lo')} + {self.text(b, 'lo')}"),
                         self.call("up", f"{self.text(a, 'hi')} + {self.text(b, 'hi')}"))

    @staticmethod
    def _zero(v: _Value) -> bool:
        return v.kind == "const" and v.point and v.lo == 0

    def neg(self, a: _Value) -> _Value:
        if a.kind == "const":
            return self.const(kernels.neg((a.lo, a.hi)))
        if a.kind == "point":
            return _Value("point", self.tmp(f"-{a.lo}"))
        return _Value("pair", self.tmp(f"-{a.hi}"), self.tmp(f"-{a.lo}"))

    def mul(self, a: _Value, b: _Value) -> _Value:
        if a.kind == "const" and b.kind == "const":
            return self.const(rounding.guarded(lambda: kernels.mul((a.lo, a.hi), (b.lo, b.hi)), 2))
        if a.point:
            a, b = b, a
        if b.point:
            return self.scale(a, b)
        al, ah, bl, bh = (self.text(a, "lo"), self.text(a, "hi"), self.text(b, "lo"), self.text(b, "hi"))
        p = [self.tmp(f"{x} * {y}") for x, y in ((al, bl), (al, bh), (ah, bl), (ah, bh))]
        lo = self.call("fmn", self.call("fmn", p[0], p[1]), self.call("fmn", p[2], p[3]))
        hi = self.call("fmx", self.call("fmx", p[0], p[1]), self.call("fmx", p[2], p[3]))
        return self.pair(self.call("down", lo), self.call("up", hi))

    def scale(self, a: _Value, b: _Value) -> _Value:
        """``a`` times the exact point ``b`` (the library's ``_scale``)."""
        lo, hi, p = self.text(a, "lo"), self.text(a, "hi"), self.text(b, "lo")
        if b.kind == "const":
            value = float(b.lo)
            if value == 0:
                return self.const(kernels.point(0.0))
            if value in (1.0, -1.0):
                return a if value == 1 else self.neg(a)
            if a.point:
                s = self.tmp(f"{lo} * {p}")
                return self.pair(self.call("down", s), self.call("up", s))
            if value > 0:
                return self.pair(self.call("down", f"{lo} * {p}"), self.call("up", f"{hi} * {p}"))
            return self.pair(self.call("down", f"{hi} * {p}"), self.call("up", f"{lo} * {p}"))
        if a.point:
            s = self.tmp(f"{lo} * {p}")
            return self.pair(self.call("down", s), self.call("up", s))
        x1, x2 = self.tmp(f"{lo} * {p}"), self.tmp(f"{hi} * {p}")
        return self.pair(self.call("down", self.call("mn", x1, x2)), self.call("up", self.call("mx", x1, x2)))

    def div(self, a: _Value, b: _Value) -> _Value:
        if a.kind == "const" and b.kind == "const":
            return self.const(rounding.guarded(lambda: kernels.div((a.lo, a.hi), (b.lo, b.hi)), 2))
        al, ah, bl, bh = (self.text(a, "lo"), self.text(a, "hi"), self.text(b, "lo"), self.text(b, "hi"))
        if b.point:
            if b.kind == "const" and float(b.lo) in (1.0, -1.0):
                return a if float(b.lo) == 1.0 else self.neg(a)
            if a.point:
                s = self.tmp(self.div_text(al, bl))
                lo, hi = self.call("down", s), self.call("up", s)
            else:
                q1, q2 = self.tmp(self.div_text(al, bl)), self.tmp(self.div_text(ah, bl))
                lo, hi = self.call("down", self.call("mn", q1, q2)), self.call("up", self.call("mx", q1, q2))
            if b.kind == "const":
                return self.pair(self.num(-math.inf), self.num(math.inf)) if float(b.lo) == 0 else self.pair(lo, hi)
            zero = f"{bl} == 0.0"
        else:
            if a.point:
                q1, q2 = self.tmp(self.div_text(al, bl)), self.tmp(self.div_text(al, bh))
                lo, hi = self.call("mn", q1, q2), self.call("mx", q1, q2)
            else:
                q = [self.tmp(self.div_text(x, y)) for x, y in ((al, bl), (al, bh), (ah, bl), (ah, bh))]
                lo = self.call("fmn", self.call("fmn", q[0], q[1]), self.call("fmn", q[2], q[3]))
                hi = self.call("fmx", self.call("fmx", q[0], q[1]), self.call("fmx", q[2], q[3]))
            lo, hi = self.call("down", lo), self.call("up", hi)
            zero = self.both(f"{bl} <= 0.0", f"{bh} >= 0.0")
        return self.pair(self.where(zero, self.num(-math.inf), lo), self.where(zero, self.num(math.inf), hi))

    def pow_bounds(self, x: str, n: int) -> _Value:
        result, base = None, _Value("point", x)
        while True:
            if n & 1:
                result = base if result is None else self.mul(result, base)
            n >>= 1
            if not n:
                return result
            base = self.mul(base, base)

    def pow_int(self, a: _Value, n: int) -> _Value:
        if a.kind == "const":
            return self.const(rounding.guarded(lambda: kernels.pow_int((a.lo, a.hi), n), 2))
        if n == 0:
            return self.const(kernels.point(1.0))
        if n == 1:
            return a
        if n < 0:
            return self.div(self.const(kernels.point(1.0)), self.pow_int(a, -n))
        even = n % 2 == 0
        lo, hi = self.text(a, "lo"), self.text(a, "hi")
        if a.point:
            bounds = self.pow_bounds(lo, n)
            low, high = self.text(bounds, "lo"), self.text(bounds, "hi")
        elif even:
            nearest = self.tmp(self.call("mx", lo, self.call("mn", hi, "0.0")))
            far = self.tmp(self.call("mx", f"-{lo}", hi))
            low, high = self.text(self.pow_bounds(nearest, n), "lo"), self.text(self.pow_bounds(far, n), "hi")
        else:
            low, high = self.text(self.pow_bounds(lo, n), "lo"), self.text(self.pow_bounds(hi, n), "hi")
        return self.pair(self.call("mx", low, "0.0") if even else low, high)

    def sqrt(self, a: _Value) -> _Value:
        if a.kind == "const":
            return self.const(rounding.guarded(lambda: kernels.sqrt((a.lo, a.hi)), 2))
        lo, hi = self.text(a, "lo"), self.text(a, "hi")
        if a.point:  # a negative point: the library raises; here NaN, whose bounds are (0, inf)
            root = self.tmp(self.call("sqrt", lo))
            return self.pair(self.call("mx", self.call("down", root), "0.0"), self.call("up", root))
        low = self.call("sqrt", self.call("mx", lo, "0.0"))
        return self.pair(self.call("mx", self.call("down", low), "0.0"), self.call("up", self.call("sqrt", hi)))

    def monotone(self, a: _Value, fn: str, clip_closed: bool | None = None) -> tuple[str, str]:
        lo, hi = self.text(a, "lo"), self.text(a, "hi")
        if clip_closed is False and not a.point:  # log: the part at or below 0 cut off
            lo = self.tmp(self.call("mx", lo, "0.0"))
        if a.point:
            value = self.tmp(self.call(fn, lo))
            return self.tmp(self.call("dt", value)), self.tmp(self.call("ut", value))
        return self.tmp(self.call("dt", self.call(fn, lo))), self.tmp(self.call("ut", self.call(fn, hi)))

    def unary(self, fn, a: _Value) -> _Value:
        if a.kind == "const":
            table = {sp.exp: kernels.exp, sp.log: kernels.log, sp.Abs: kernels.absolute, sp.sign: kernels.sign,
                     sp.tanh: kernels.tanh}
            return self.const(rounding.guarded(lambda: table[fn]((a.lo, a.hi)), 2))
        lo, hi = self.text(a, "lo"), self.text(a, "hi")
        if fn is sp.Abs:
            if a.point:
                return _Value("point", self.tmp(self.call("abs", lo)))
            return self.pair(self.call("mx", self.call("mx", lo, f"-{hi}"), "0.0"), self.call("mx", f"-{lo}", hi))
        if fn is sp.sign:
            if a.point:
                return _Value("point", self.tmp(self.call("sign", lo)))
            return self.pair(self.call("sign", lo), self.call("sign", hi))
        if fn is sp.exp:
            low, high = self.monotone(a, "exp")
            return self.pair(self.call("mx", low, "0.0"), high)
        if fn is sp.log:
            low, high = self.monotone(a, "log", clip_closed=False)
            return _Value("pair", low, high)
        if fn is sp.tanh:
            low, high = self.monotone(a, "tanh")
            return self.pair(self.call("mx", low, "-1.0"), self.call("mn", high, "1.0"))
        raise CodegenError(f"{self.name}: cannot generate the interval of {fn.__name__} in Psi_2; supported: "
                           "Abs, sign, sqrt and powers, exp, log, tanh, Min, Max")

    def extreme(self, which: str, a: _Value, b: _Value) -> _Value:
        if a.kind == "const" and b.kind == "const":
            kernel = kernels.minimum if which == "mn" else kernels.maximum
            return self.const(kernel((a.lo, a.hi), (b.lo, b.hi)))
        if a.point and b.point:
            return _Value("point", self.tmp(self.call(which, self.text(a, "lo"), self.text(b, "lo"))))
        return self.pair(self.call(which, self.text(a, "lo"), self.text(b, "lo")),
                         self.call(which, self.text(a, "hi"), self.text(b, "hi")))

    # -- the expression walk (the library's _compile) ----------------------------------------------------
    def varies(self, expr) -> bool:
        return bool(self.point_set) and expr.has(*self.point_set)

    def compile(self, expr: sp.Expr) -> _Value:
        if expr in self.leaves:
            return self.leaves[expr]
        if expr in self.memo:
            return self.memo[expr]
        if expr.is_number:
            box = enclose(expr)
            value = (np.float64(box.lo),) * 2 if box.lo == box.hi else (np.float64(box.lo), np.float64(box.hi))
            result = self.const(value)
        elif not self.varies(expr):  # deltas and numbers alone: the library evaluates it once, so do we
            with np.errstate(all="ignore"):
                band = compile_interval(expr, [], self.boxes)()
            result = _Value("const", np.float64(band.lo), np.float64(band.hi))
        else:
            result = self.operation(expr)
        self.memo[expr] = result
        return result

    def fold(self, kernel, values: list) -> _Value:
        acc = values[0]
        for v in values[1:]:
            acc = kernel(acc, v)
        return acc

    def operation(self, expr) -> _Value:
        if expr.is_Add:
            return self.fold(self.add, [self.compile(a) for a in expr.args])
        if isinstance(expr, (sp.Min, sp.Max)):
            which = "mn" if isinstance(expr, sp.Min) else "mx"
            return self.fold(lambda a, b: self.extreme(which, a, b), [self.compile(a) for a in expr.args])
        if expr.is_Mul:
            numer, denom = product_parts(expr)   # as the library's compiler splits it: the same roundings
            numer.sort(key=self.varies)
            top = self.fold(self.mul, [self.compile(f) for f in numer])
            if not denom:
                return top
            return self.div(top, self.fold(self.mul, [self.compile(f) for f in denom]))
        if expr.is_Pow:
            base, e = self.compile(expr.base), expr.exp
            if e.is_Integer:
                return self.pow_int(base, int(e))
            if e.is_Rational and e.q == 2:
                return self.pow_int(self.sqrt(base), int(e.p))
            if e.is_number:
                box = enclose(e)
                if box.lo == box.hi and float(box.lo).is_integer():
                    return self.pow_int(base, int(box.lo))
                if box.lo == box.hi and float(box.lo) == 0.5:
                    return self.sqrt(base)
            raise CodegenError(f"{self.name}: cannot generate the interval of the power {expr} in Psi_2 "
                               "(integer and half-integer exponents are supported)")
        if len(expr.args) == 1 and expr.func in (sp.exp, sp.log, sp.Abs, sp.sign, sp.tanh):
            return self.unary(expr.func, self.compile(expr.args[0]))
        raise CodegenError(f"{self.name}: cannot generate the interval of {expr.func.__name__} in Psi_2 ({expr})")

    def affine(self, expr: sp.Expr) -> _Value:
        """The library's :func:`affine_range`: ``g0 + sum delta_i g_i``, each delta's coefficient collected."""
        deltas = set(self.boxes)
        terms = []
        for d in self.boxes:
            g = sp.diff(expr, d)
            if g.free_symbols & deltas:
                g = sp.expand(g)
            if g != 0:
                terms.append((d, g))
        acc = self.compile(expr.xreplace({d: 0 for d in self.boxes}))
        for d, g in terms:
            acc = self.add(acc, self.mul(self.leaves[d], self.compile(g)))
        return acc


def interval_code(plan: Plan, lang: str) -> tuple[list[tuple[str, str]], str, str]:
    """The lines computing the threshold of ``plan``'s ARR, and the texts of its lower and upper bound."""
    emitter = _IntervalEmitter(lang, plan.name, plan.boxes, plan.points)
    with np.errstate(all="ignore"):
        band = emitter.affine(plan.uncertain) if plan.interval_form == "affine" else emitter.compile(plan.uncertain)
    lo, hi = emitter.text(band, "lo"), emitter.text(band, "hi")
    # the library's sanitize: a NaN bound (0 * inf of infinite points) is the sound hull
    lo = emitter.where(f"{lo} != {lo}", emitter.num(-math.inf), lo)
    hi = emitter.where(f"{hi} != {hi}", emitter.num(math.inf), hi)
    return emitter.lines, lo, hi


def transcendental_widening() -> tuple[float, float]:
    """The relative and absolute widening of a transcendental bound (:mod:`diagnosis.intervals.rounding`)."""
    ulps = rounding.TRANSCENDENTAL_ULPS
    return (2 * ulps + 1) * rounding.EPS, (ulps + 1) * 5e-324
