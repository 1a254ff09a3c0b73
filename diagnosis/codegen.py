"""Residual code to deploy: standalone Python or C evaluating a model's ARRs sample by sample.

:func:`generate_code` writes, for a set of ARRs, a module that does what
:class:`~diagnosis.streaming.StreamingEvaluation` does (``method="savgol"``, ``threshold="interval"``, the
given ``dt``, ``margin`` and ``persistence``), with no sympy, numpy or networkx at run time:

* the Savitzky-Golay derivative estimates: the coefficients (``scipy.signal.savgol_coeffs`` for the step
  ``dt``) and the one-sided fits of the first and the last window (exact least squares, computed in
  rationals at generation time) are constants of the module; a ring buffer of one window per ARR is
  all the memory a stream keeps;
* running trapezoid sums for the integrals of the ARR (from 0 at the stream's first sample);
* the nominal residual ``r_n``, printed from the same common-subexpression form the library evaluates;
* the interval threshold ``[B_lo, B_hi]``: the same interval operations, in the same order, as
  :func:`~diagnosis.intervals.affine_range` (or :func:`~diagnosis.intervals.compile_interval`, the natural
  extension, when Psi_2 is not affine in its deltas), each bound rounded outward by one ``nextafter``
  (transcendental results widened as the library widens them);
* violations ``-r_n`` outside ``[B_lo - margin, B_hi + margin]`` and alarms after ``persistence``
  consecutive violations.

A sample becomes final once its derivative window has arrived (``window // 2`` samples later); the
stream's end (``flush``) finalizes the rest with the one-sided fit.  The values are the library's up to
rounding: the interior derivative sums are done in scipy's order (bitwise equal), the bounds of ``+ - *
/ sqrt`` are bitwise equal, the one-sided fits and the residual's expression agree to a few ulps.  The
thresholds are sound up to IEEE 754 rounding to nearest (each bound stepped one ulp outward after a
correctly rounded operation); compile the C without ``-ffast-math`` (``-ffp-contract=off`` on machines
with fused multiply-add).

Not generated (a :class:`CodegenError` says so): ``method="central"`` for an ARR with derivatives,
antiderivative columns, the BG-LFT threshold, and functions outside ``Abs``, ``sign``, ``sqrt``, powers,
``exp``, ``log``, ``tanh``, ``Min``, ``Max`` (and, in the residual alone, the trigonometric and hyperbolic
functions): ``Piecewise`` for instance.

Examples
--------
>>> from bondgraph.library import rlc_circuit
>>> from diagnosis import derive_arrs
>>> files = generate_code(derive_arrs(rlc_circuit()), "python", dt=0.001, name="rlc")
>>> sorted(files)
['manifest.json', 'rlc.py']
>>> import importlib.util, pathlib, tempfile
>>> path = pathlib.Path(tempfile.mkdtemp()) / "rlc.py"
>>> _ = path.write_text(files["rlc.py"])
>>> spec = importlib.util.spec_from_file_location("rlc", path)
>>> rlc = importlib.util.module_from_spec(spec)
>>> spec.loader.exec_module(rlc)
>>> monitor = rlc.Monitor()
>>> monitor.signals
('V', 'i', 'v_C')
>>> out = [monitor.push(0.001 * k, {"V": 1.0, "i": 0.0, "v_C": 1.0}) for k in range(20)]
>>> [len(o["ARR_J1"]) for o in out[9:12]]    # the first window (11 samples) finalizes 6 samples at once
[0, 6, 1]
>>> index, t, residual, lower, upper, violation, alarm = out[11]["ARR_J1"][0]
>>> index, residual, violation
(6, 0.0, False)
"""

from __future__ import annotations

import json
import math
import numbers
import re
from fractions import Fraction

import numpy as np
import sympy as sp
from scipy.signal import savgol_coeffs
from sympy.printing.c import C99CodePrinter
from sympy.printing.pycode import PythonCodePrinter

from bondgraph.errors import PHMError

from .deltas import delta
from .derivatives import check_savgol_settings, default_window
from .detection import check_options, fitting_order
from .intervals import affine_range, compile_interval, enclose, kernels, rounding
from .records import MAX_MAGNITUDE, UNIFORM_RTOL

__all__ = ["LANGUAGES", "CodegenError", "generate_code"]

#: The languages :func:`generate_code` writes.
LANGUAGES = ("python", "c")

_EPS = float(np.finfo(float).eps)  # ndimage's symmetry test of a filter compares with DBL_EPSILON


class CodegenError(PHMError, ValueError):
    """An ARR set, or an option, the code generator cannot turn into code; the message names the ARR."""


# ------------------------------------------------------------------------------------------------ public

def generate_code(arrs, lang: str = "python", *, dt: float, method: str = "savgol", window: int | None = None,
                  polyorder: int | None = None, margin: float = 0.0, persistence: int = 1,
                  name: str = "residuals") -> dict[str, str]:
    """Standalone code evaluating ``arrs`` sample by sample as :class:`~diagnosis.StreamingEvaluation` does.

    Parameters
    ----------
    arrs : sequence of ARR
        The ARR set (e.g. ``derive_arrs(model)``); every ARR gets its stream in the one module.
    lang : {"python", "c"}
        Python 3 with the ``math`` module alone, or C99 with ``libm`` alone.
    dt : float
        The sampling step: the Savitzky-Golay coefficients are computed for it, and a stream refuses a
        step off it by more than a relative 1e-6 (as ``StreamingEvaluation(dt=dt)``).
    method, window, polyorder, margin, persistence
        As for :class:`~diagnosis.StreamingEvaluation` (``method="central"`` only for ARRs without
        derivatives).
    name : str
        The module's name: the Python file ``NAME.py``; the C files ``NAME.h``, ``NAME.c`` and the prefix of
        their public names (made a valid identifier).

    Returns
    -------
    dict
        File name -> text: the module's files and ``manifest.json`` (the signals, each ARR's columns,
        the options).

    Raises
    ------
    CodegenError
        An unknown language, a bad option, a set without ARRs, two ARRs whose names map to one identifier,
        or an ARR that cannot be generated (named, with the reason).

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> files = generate_code(derive_arrs(rlc_circuit()), "c", dt=0.001, name="rlc")
    >>> sorted(files)
    ['manifest.json', 'rlc.c', 'rlc.h']
    >>> "int rlc_ARR_J1_push(rlc_ARR_J1_state *s, double t, const double *x, rlc_sample *out);" in files["rlc.h"]
    True
    """
    if lang not in LANGUAGES:
        raise CodegenError(f"lang must be one of {', '.join(map(repr, LANGUAGES))}, got {lang!r}")
    if isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not math.isfinite(dt) or dt <= 0:
        raise CodegenError(f"dt: the sampling step must be a finite number > 0, got {dt!r}")
    arrs = list(arrs)
    if not arrs:
        raise CodegenError("no ARR to generate code for (an empty set)")
    prefix = _identifier(name, "name")
    plans = [_Plan(arr, index, dt=float(dt), method=method, window=window, polyorder=polyorder, margin=margin,
                   persistence=persistence) for index, arr in enumerate(arrs)]
    _unique([(p.ident, p.name) for p in plans], "ARR names")
    signals = tuple(dict.fromkeys(s for p in plans for s in p.columns))
    options = {"method": method, "window": window, "polyorder": polyorder, "dt": float(dt), "margin": float(margin),
               "persistence": int(persistence), "threshold": "interval"}
    manifest = {"module": prefix, "language": lang, "signals": list(signals), "options": options,
                "arrs": [{"name": p.name, "identifier": p.ident, "columns": list(p.columns), "window": p.window,
                          "delay": p.lag, "interval": p.interval_form} for p in plans],
                "generator": "bondgraph-phm diagnosis.codegen"}
    files = {"manifest.json": json.dumps(manifest, indent=1) + "\n"}
    if lang == "python":
        files[f"{prefix}.py"] = _python_module(plans, signals, options)
    else:
        header, source = _c_module(plans, prefix, options)
        files[f"{prefix}.h"], files[f"{prefix}.c"] = header, source
    return files


# ------------------------------------------------------------------------------------------------ names

def _identifier(text: str, what: str) -> str:
    """``text`` mapped to a C and Python identifier: other characters become ``_``, a leading digit gets ``_``."""
    if not isinstance(text, str) or not text:
        raise CodegenError(f"{what}: a non-empty name is needed, got {text!r}")
    ident = re.sub(r"[^A-Za-z0-9_]", "_", text)
    return "_" + ident if ident[0].isdigit() else ident


def _unique(pairs: list[tuple[str, str]], what: str) -> None:
    seen: dict = {}
    for ident, original in pairs:
        if ident in seen and seen[ident] != original:
            raise CodegenError(f"{what}: {seen[ident]!r} and {original!r} both become the identifier {ident!r}; "
                               "rename one")
        seen[ident] = original


def _c_string(text: str) -> str:
    """A C string literal of ``text``'s UTF-8 bytes: letters, digits and ``_`` as they are, the rest octal."""
    return '"' + "".join(chr(b) if chr(b).isalnum() and b < 128 or b == 95 else f"\\{b:03o}"
                         for b in text.encode()) + '"'


# ------------------------------------------------------------------------------------------------ plan

class _Plan:
    """What one ARR's stream computes: its columns, derivative filters, integrals, and expressions."""

    def __init__(self, arr, index: int, *, dt: float, method: str, window, polyorder, margin, persistence) -> None:
        try:
            check_options(arr, "generate_code", method=method, margin=margin, persistence=persistence)
        except (TypeError, ValueError) as exc:
            raise CodegenError(str(exc)) from None
        self.name, self.index = arr.name, index
        self.ident = _identifier(arr.name, "ARR name")
        compiled = arr.compiled
        self.columns = tuple(compiled.signals)
        self.npoints = len(compiled.points)
        position = {p: k for k, p in enumerate(compiled.points)}
        column = {n: k for k, n in enumerate(self.columns)}
        self.signal_points = [(position[sp.Symbol(n)], column[n]) for n in self.columns]
        self.margin, self.persistence, self.dt = float(margin), int(persistence), dt
        polyorder = fitting_order(arr, polyorder)
        derivatives = compiled.derivatives
        if derivatives and method != "savgol":
            raise CodegenError(f"{arr.name}: method={method!r}: only Savitzky-Golay derivatives are generated; "
                               "use method='savgol'")
        if derivatives:
            if window is None and isinstance(polyorder, numbers.Integral) and not isinstance(polyorder, bool):
                window = default_window(polyorder)
            try:
                for signal, order in derivatives.values():
                    check_savgol_settings(signal, order, window, polyorder)
            except ValueError as exc:
                raise CodegenError(f"{arr.name}: {exc}") from None
            window = window if window is not None else default_window()
            half = window // 2
            self.window, self.half, self.lag, self.keep, self.ready_at = window, half, half, window, window
        else:
            self.window, self.half, self.lag, self.keep, self.ready_at = 0, 0, 0, 1, 1
        orders = sorted({order for _, order in derivatives.values()})
        self.orders = [_filters(self.window, polyorder, order, dt) for order in orders]
        self.derivs = [(position[s], column[n], orders.index(order), int(order >= 2))
                       for s, (n, order) in derivatives.items()]
        self.integrals = [(position[s], _checked(arr.name, f"the integrand of {s}", g))
                          for s, g in compiled.integrals.items()]
        self.nominal = _checked(arr.name, "r_n", compiled.nominal)
        self.interval_form, self.uncertain, self.boxes = _interval_form(arr, compiled)
        self.points = list(compiled.points)


def _checked(name: str, where: str, expression: sp.Expr) -> sp.Expr:
    """``expression`` if every function in it can be printed, else a CodegenError naming the ARR."""
    allowed = (sp.Abs, sp.sign, sp.exp, sp.log, sp.sin, sp.cos, sp.tan, sp.sinh, sp.cosh, sp.tanh, sp.asin, sp.acos,
               sp.atan, sp.atan2, sp.Min, sp.Max)
    for f in expression.atoms(sp.Function):
        if not isinstance(f, allowed):
            raise CodegenError(f"{name}: cannot generate code for the function {type(f).__name__} in {where} "
                               f"({f}); supported: Abs, sign, sqrt and powers, exp, log, trigonometric and "
                               "hyperbolic functions, Min, Max")
    return expression


def _filters(window: int, polyorder: int, order: int, dt: float) -> dict:
    """The Savitzky-Golay filter of one derivative order: interior weights in ndimage's correlation order,
    ndimage's symmetry class of them, the one-sided fits of the first and last window, their divisor."""
    weights = savgol_coeffs(window, polyorder, deriv=order, delta=dt)[::-1]  # convolve1d correlates reversed
    half = window // 2
    sym = 0
    if window & 1:
        if all(abs(weights[half + i] - weights[half - i]) <= _EPS for i in range(1, half + 1)):
            sym = 1
        elif all(abs(weights[half + i] + weights[half - i]) <= _EPS for i in range(1, half + 1)):
            sym = -1
    fit = _fit_matrix(window, polyorder)  # polynomial coefficients (lowest power first) from the window
    rows = []
    for position in list(range(half)) + list(range(window - half, window)):
        row = [Fraction(0)] * window
        for k in range(order, polyorder + 1):
            factor = Fraction(math.factorial(k) // math.factorial(k - order)) * Fraction(position) ** (k - order)
            for j in range(window):
                row[j] += factor * fit[k][j]
        rows.append([float(v) for v in row])
    return {"weights": [float(w) for w in weights], "sym": sym, "start": rows[:half], "end": rows[half:],
            "divisor": dt ** order}


def _fit_matrix(window: int, polyorder: int) -> list[list[Fraction]]:
    """``(A^T A)^-1 A^T`` for the Vandermonde matrix ``A`` of positions ``0 .. window - 1``, in exact rationals."""
    a = sp.Matrix(window, polyorder + 1, lambda j, k: sp.Integer(j) ** k)
    m = (a.T * a).inv() * a.T
    return [[Fraction(int(sp.fraction(v)[0]), int(sp.fraction(v)[1])) for v in m.row(k)]
            for k in range(polyorder + 1)]


def _interval_form(arr, compiled) -> tuple[str, sp.Expr, dict]:
    """Which evaluator the library uses for the threshold ("affine" or "natural"), Psi_2, and the delta boxes."""
    boxes = {delta(p): tuple(map(float, box)) for p, box in arr.uncertainties.items()}
    uncertain = compiled.uncertain
    try:
        with np.errstate(all="ignore"):
            affine_range(uncertain, compiled.points, boxes)
        return "affine", uncertain, boxes
    except ValueError:
        try:
            with np.errstate(all="ignore"):
                compile_interval(uncertain, compiled.points, boxes)
        except ValueError as exc:
            raise CodegenError(f"{arr.name}: the interval threshold cannot be evaluated: {exc}") from None
        return "natural", uncertain, boxes


# ------------------------------------------------------------------------------------------------ printers

def _float_text(expr: sp.Float) -> str:
    """The double lambdify's printed literal parses to (sympy prints 15 significant digits), at full precision."""
    return repr(float(PythonCodePrinter().doprint(expr)))


class _Names:
    """Symbols printed under the names the generated code gives them (never a user's name)."""

    def __init__(self, names: dict, **settings) -> None:
        super().__init__(settings)
        self._names = names

    def _print_Symbol(self, expr):
        if expr not in self._names:
            raise CodegenError(f"unexpected symbol {expr} in a relation")
        return self._names[expr]


class _PythonPrinter(_Names, PythonCodePrinter):
    """Python with ``math``: NaN-propagating sign, Min and Max, and powers that never turn complex."""

    def _print_Float(self, expr):
        return _float_text(expr)

    def _print_sign(self, expr):
        return f"_sign({self._print(expr.args[0])})"

    def _print_Min(self, expr):
        return self._fold("_mn", expr.args)

    def _print_Max(self, expr):
        return self._fold("_mx", expr.args)

    def _fold(self, name, args):
        text = self._print(args[0])
        for a in args[1:]:
            text = f"{name}({text}, {self._print(a)})"
        return text

    def _print_Pow(self, expr, rational=False):
        e = expr.exp
        if e.is_Integer or e in (sp.S.Half, -sp.S.Half):
            return super()._print_Pow(expr, rational=rational)
        return f"_pw({self._print(expr.base)}, {self._print(e)})"


class _CPrinter(_Names, C99CodePrinter):
    """C99 with ``libm``: NaN-propagating sign, Min and Max, doubles printed as lambdify reads them."""

    def _print_Float(self, expr):
        return _float_text(expr)

    def _print_sign(self, expr):
        return f"bg_sign({self._print(expr.args[0])})"

    def _print_Min(self, expr):
        return self._fold("bg_mn", expr.args)

    def _print_Max(self, expr):
        return self._fold("bg_mx", expr.args)

    def _fold(self, name, args):
        text = self._print(args[0])
        for a in args[1:]:
            text = f"{name}({text}, {self._print(a)})"
        return text


def _printed(expression: sp.Expr, points: list, lang: str) -> tuple[list[tuple[str, str]], str]:
    """``([(temporary, text), ...], result text)``: the common subexpressions lambdify(cse=True) evaluates.

    The expression keeps the ARR's symbols, so that its terms print in lambdify's order (sympy orders them
    by name); the printer names point ``k`` ``p<k>`` and temporary ``k`` ``c<k>``."""
    temporaries, result = sp.cse(expression, list=False)
    names = {p: f"p{k}" for k, p in enumerate(points)}
    names.update({s: f"c{k}" for k, (s, _) in enumerate(temporaries)})
    printer = (_PythonPrinter if lang == "python" else _CPrinter)(names)
    return [(names[s], printer.doprint(e)) for s, e in temporaries], printer.doprint(result)


# ------------------------------------------------------------------------------------------------ intervals

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


def _interval_code(plan: _Plan, lang: str) -> tuple[list[tuple[str, str]], str, str]:
    """The lines computing the threshold of ``plan``'s ARR, and the texts of its lower and upper bound."""
    emitter = _IntervalEmitter(lang, plan.name, plan.boxes, plan.points)
    with np.errstate(all="ignore"):
        band = emitter.affine(plan.uncertain) if plan.interval_form == "affine" else emitter.compile(plan.uncertain)
    lo, hi = emitter.text(band, "lo"), emitter.text(band, "hi")
    # the library's sanitize: a NaN bound (0 * inf of infinite points) is the sound hull
    lo = emitter.where(f"{lo} != {lo}", emitter.num(-math.inf), lo)
    hi = emitter.where(f"{hi} != {hi}", emitter.num(math.inf), hi)
    return emitter.lines, lo, hi


# ------------------------------------------------------------------------------------------------ Python

_PY_HEADER = '''"""Residuals, interval thresholds and alarms of the ARRs {names}, sample by sample.

Generated by bondgraph-phm (diagnosis.codegen); do not edit.  Needs Python 3.9+ and its math module alone.

    monitor = Monitor()
    for t, row in samples:                  # row: signal name -> value (NaN marks a gap)
        for name, finals in monitor.push(t, row).items():
            for index, t_i, residual, lower, upper, violation, alarm in finals:
                ...
    monitor.flush()                         # at the end: the samples still waiting for their window

A sample becomes final once its Savitzky-Golay window has arrived (the ARR's DELAY samples later).
Options: {options}.
"""

import math

_INF = math.inf
_MAX = 1.7976931348623157e+308
_TREL = {trel!r}
_TSUB = {tsub!r}
MAX_MAGNITUDE = {max_magnitude!r}
UNIFORM_RTOL = {rtol!r}
DT = {dt!r}
MARGIN = {margin!r}
PERSISTENCE = {persistence!r}


def _down(x):
    return -_INF if x != x else math.nextafter(x, -_INF)


def _up(x):
    return _INF if x != x else math.nextafter(x, _INF)


def _mn(a, b):
    return math.nan if a != a or b != b else (a if a <= b else b)


def _mx(a, b):
    return math.nan if a != a or b != b else (a if a >= b else b)


def _fmn(a, b):
    return b if a != a else a if b != b else (a if a <= b else b)


def _fmx(a, b):
    return b if a != a else a if b != b else (a if a >= b else b)


def _q(a, b):
    try:
        return a / b
    except ZeroDivisionError:
        return math.nan if a != a or a == 0 else math.copysign(_INF, a) * math.copysign(1.0, b)


def _sqrt(x):
    return math.sqrt(x) if x >= 0 else math.nan


def _exp(x):
    try:
        return math.exp(x)
    except OverflowError:
        return _INF


def _log(x):
    return math.log(x) if x > 0 else -_INF if x == 0 else math.nan


def _sign(x):
    return x if x != x else 1.0 if x > 0 else -1.0 if x < 0 else 0.0


def _pw(x, e):
    try:
        return math.pow(x, e)
    except ValueError:
        return math.nan
    except OverflowError:
        return _INF


def _dt(x):
    x = _mn(x, _MAX)
    return x - (abs(x) * _TREL + _TSUB)


def _ut(x):
    x = _mx(x, -_MAX)
    return x + (abs(x) * _TREL + _TSUB)
'''

_PY_ENGINE = '''

class ARRStream:
    """One ARR over a stream: ``push(t, row)`` (``row``: the ARR's COLUMNS in order) returns the samples that
    became final, each ``(index, t, residual, lower, upper, violation, alarm)``; ``flush()`` ends the stream."""

    def __init__(self, name):
        spec = SPECS[name]
        self.name = name
        self.columns = spec["columns"]
        self._spec = spec
        keep = spec["keep"]
        self._t = [0.0] * keep
        self._x = [[0.0] * keep for _ in self.columns]
        self._integral = [0.0] * len(spec["integrals"])
        self._integrand = [0.0] * len(spec["integrals"])
        self.samples = 0
        self.final = 0
        self._run = 0
        self._t_final = math.nan
        self._ended = False

    def push(self, t, row):
        spec, keep = self._spec, self._spec["keep"]
        if self._ended:
            raise ValueError(f"{self.name}: the stream has ended (flush() was called)")
        t = float(t)
        if not math.isfinite(t) or abs(t) > MAX_MAGNITUDE:
            raise ValueError(f"{self.name}: t must be a finite number, got {t!r}")
        row = [float(v) for v in row]
        if len(row) != len(self.columns):
            raise ValueError(f"{self.name}: {len(row)} values, expected {len(self.columns)} ({self.columns})")
        for name, v in zip(self.columns, row):
            if abs(v) > MAX_MAGNITUDE:
                raise ValueError(f"{self.name}: {name} = {v!r} at t = {t!r} is infinite or too large")
        if self.samples:
            last = self._t[(self.samples - 1) % keep]
            step = t - last
            if step <= 0:
                raise ValueError(f"{self.name}: t must increase: t = {t!r} follows t = {last!r}")
            if spec["uniform"] and abs(step - DT) > UNIFORM_RTOL * DT:
                raise ValueError(f"{self.name}: t = {t!r} comes {step!r} after the previous sample, but the "
                                 f"step is {DT!r}")
        position = self.samples % keep
        self._t[position] = t
        for column, v in zip(self._x, row):
            column[position] = v
        self.samples += 1
        out = []
        if self.samples >= spec["ready_at"]:
            while self.final < self.samples - spec["lag"]:
                out.append(self._finalize(self.final, False))
                self.final += 1
        return out

    def flush(self):
        if self._ended:
            return []
        if self.final < self.samples < self._spec["ready_at"]:
            raise ValueError(f"{self.name}: the stream has {self.samples} samples, fewer than the "
                             f"{self._spec['ready_at']} of the Savitzky-Golay window")
        out = [self._finalize(i, True) for i in range(self.final, self.samples)]
        self.final = self.samples
        self._ended = True
        return out

    def _finalize(self, i, at_end):
        spec, keep, x = self._spec, self._spec["keep"], self._x
        window, half, count = spec["window"], spec["half"], self.samples
        p = [0.0] * spec["npoints"]
        position = i % keep
        for point, column in spec["signals"]:
            p[point] = x[column][position]
        for point, column, o, trusted in spec["derivatives"]:
            weights, sym, start, end, divisor = spec["orders"][o]
            xs = x[column]
            if i < half:
                row, first = start[i], 0
            elif at_end and i >= count - half:
                row, first = end[i - count + half], count - window
            else:
                row = None
            if row is not None:
                acc = row[0] * xs[first % keep]
                for j in range(1, window):
                    acc += row[j] * xs[(first + j) % keep]
                value = acc / divisor
            else:
                first = i - half
                if sym == 0:
                    acc = xs[(first + window - 1) % keep] * weights[window - 1]
                    for j in range(window - 1):
                        acc += xs[(first + j) % keep] * weights[j]
                else:
                    acc = xs[(first + half) % keep] * weights[half]
                    for j in range(half):
                        acc += (xs[(first + j) % keep] + sym * xs[(first + window - 1 - j) % keep]) * weights[j]
                value = acc
            if trusted and (i < half or (at_end and i >= count - half)):
                value = math.nan
            p[point] = value
        t = self._t[position]
        for k, (point, integrand) in enumerate(spec["integrals"]):
            g = integrand(p)
            if i == 0:
                total = 0.0 if g == g else math.nan
            else:
                total = self._integral[k] + (t - self._t_final) * (g + self._integrand[k]) / 2.0
                total = total if g == g else math.nan
            self._integral[k], self._integrand[k] = total, g
            p[point] = total
        self._t_final = t
        residual, lower, upper = spec["evaluate"](p)
        violation = -residual < lower - MARGIN or -residual > upper + MARGIN
        self._run = min(self._run + 1, PERSISTENCE) if violation else 0
        return (i, t, residual, lower, upper, violation, self._run >= PERSISTENCE)


class Monitor:
    """Every ARR of the module over one stream: ``push(t, row)`` with ``row`` signal name -> value returns
    ARR name -> its samples that became final; ``flush()`` the rest."""

    def __init__(self):
        self.signals = SIGNALS
        self.streams = {name: ARRStream(name) for name in SPECS}

    def push(self, t, row):
        missing = [s for s in self.signals if s not in row]
        if missing:
            raise ValueError(f"missing signal(s) {missing}; every sample needs {list(self.signals)}")
        return {name: s.push(t, [row[c] for c in s.columns]) for name, s in self.streams.items()}

    def flush(self):
        return {name: s.flush() for name, s in self.streams.items()}
'''


def _python_module(plans: list[_Plan], signals: tuple, options: dict) -> str:
    parts = [_PY_HEADER.format(
        names=", ".join(p.name for p in plans), options=", ".join(f"{k}={v!r}" for k, v in options.items()),
        trel=_trans()[0], tsub=_trans()[1],
        max_magnitude=MAX_MAGNITUDE, rtol=UNIFORM_RTOL, dt=options["dt"], margin=options["margin"],
        persistence=options["persistence"])]
    specs = []
    for plan in plans:
        k = plan.index
        parts.append(f"\n\ndef _evaluate_{k}(p):\n    \"\"\"{plan.ident}: (residual, lower, upper) from the point "
                     "values.\"\"\"\n")
        parts.append(f"    {', '.join(f'p{j}' for j in range(plan.npoints))}, = p\n")
        temporaries, result = _printed(plan.nominal, plan.points, "python")
        parts.append("    try:\n")
        parts.extend(f"        {s} = {e}\n" for s, e in temporaries)
        parts.append(f"        residual = float({result})\n")
        parts.append("    except (ArithmeticError, ValueError):\n        residual = math.nan\n")
        lines, lo, hi = _interval_code(plan, "python")
        parts.extend(f"    {s} = {e}\n" for s, e in lines)
        parts.append(f"    return residual, {lo}, {hi}\n")
        integrands = []
        for m, (_, g) in enumerate(plan.integrals):
            parts.append(f"\n\ndef _integrand_{k}_{m}(p):\n")
            parts.append(f"    {', '.join(f'p{j}' for j in range(plan.npoints))}, = p\n")
            temporaries, result = _printed(g, plan.points, "python")
            parts.append("    try:\n")
            parts.extend(f"        {s} = {e}\n" for s, e in temporaries)
            parts.append(f"        return float({result})\n")
            parts.append("    except (ArithmeticError, ValueError):\n        return math.nan\n")
            integrands.append(f"({plan.integrals[m][0]}, _integrand_{k}_{m})")
        orders = ", ".join(f"({tuple(o['weights'])!r}, {o['sym']}, {_rows(o['start'])}, {_rows(o['end'])}, "
                           f"{o['divisor']!r})" for o in plan.orders)
        specs.append(
            f"    {plan.name!r}: {{\n        \"columns\": {plan.columns!r},\n        \"npoints\": {plan.npoints},\n"
            f"        \"keep\": {plan.keep}, \"window\": {plan.window}, \"half\": {plan.half}, "
            f"\"lag\": {plan.lag}, \"ready_at\": {plan.ready_at}, \"uniform\": {bool(plan.derivs)},\n"
            f"        \"signals\": {tuple(plan.signal_points)!r},\n"
            f"        \"derivatives\": {tuple(plan.derivs)!r},\n"
            f"        \"orders\": ({orders}{',' if len(plan.orders) == 1 else ''}),\n"
            f"        \"integrals\": ({', '.join(integrands)}{',' if len(integrands) == 1 else ''}),\n"
            f"        \"evaluate\": _evaluate_{k},\n    }},\n")
    parts.append(f"\n\nSIGNALS = {signals!r}\n")
    parts.append("DELAY = {" + ", ".join(f"{p.name!r}: {p.lag}" for p in plans) + "}\n")
    parts.append("SPECS = {\n" + "".join(specs) + "}\n")
    parts.append(_PY_ENGINE)
    return "".join(parts)


def _rows(rows: list) -> str:
    return "(" + "".join(f"{tuple(r)!r}, " for r in rows) + ")"


def _trans() -> tuple[float, float]:
    """The relative and absolute widening of a transcendental bound (:mod:`diagnosis.intervals.rounding`)."""
    ulps = rounding.TRANSCENDENTAL_ULPS
    return (2 * ulps + 1) * rounding.EPS, (ulps + 1) * 5e-324


# ------------------------------------------------------------------------------------------------ C

_C_HEADER = '''/* Residuals, interval thresholds and alarms of {count} ARR(s), sample by sample.
 * Generated by bondgraph-phm (diagnosis.codegen); do not edit.  C99, libm alone:
 *     cc -O2 -std=c99 -ffp-contract=off -c {prefix}.c   (never -ffast-math: the bounds rely on IEEE rounding)
 * Per ARR: a state (init), push one sample (its columns in order), flush at the end; each call writes
 * the samples that became final into out (at most {upper}_MAX_OUT of them) and returns their number,
 * or a negative error: {upper}_ERR_TIME (t not increasing or not finite), {upper}_ERR_STEP (a step off
 * {upper}_DT by more than 1e-6 relative), {upper}_ERR_VALUE (a value infinite or beyond 1e150; NaN is a gap),
 * {upper}_ERR_ENDED (push after flush), {upper}_ERR_SHORT (flush before the first window was complete).
 */
#ifndef {guard}
#define {guard}

#include <stddef.h>

#define {upper}_DT {dt}
#define {upper}_MARGIN {margin}
#define {upper}_PERSISTENCE {persistence}
#define {upper}_MAX_OUT {max_out}
#define {upper}_ERR_TIME (-1)
#define {upper}_ERR_STEP (-2)
#define {upper}_ERR_VALUE (-3)
#define {upper}_ERR_ENDED (-4)
#define {upper}_ERR_SHORT (-5)

typedef struct {{
    long index;           /* the sample's index in the stream (0 for the first) */
    double t, residual, lower, upper;
    int violation, alarm;
}} {prefix}_sample;

typedef struct {{
    long count, final;
    int ended, run;
    double t_final;
}} {prefix}_core;
'''

_C_ENGINE = '''
#include <float.h>
#include <math.h>
#include <stddef.h>

#include "{prefix}.h"

#define BG_TREL {trel}
#define BG_TSUB {tsub}
#define BG_MAX_MAGNITUDE {max_magnitude}
#define BG_RTOL {rtol}

/* Outward rounding: one ulp down (up) after a correctly rounded operation; NaN gives the sound -inf (+inf). */
static inline double bg_down(double x) {{ return nextafter(fmax(x, -INFINITY), -INFINITY); }}
static inline double bg_up(double x) {{ return nextafter(fmin(x, INFINITY), INFINITY); }}
/* numpy's minimum and maximum: NaN wins (fmin and fmax, where NaN loses, are libm's). */
static inline double bg_mn(double a, double b) {{ return (a != a || b != b) ? NAN : (a <= b ? a : b); }}
static inline double bg_mx(double a, double b) {{ return (a != a || b != b) ? NAN : (a >= b ? a : b); }}
static inline double bg_sign(double x) {{ return x != x ? x : (x > 0 ? 1.0 : (x < 0 ? -1.0 : 0.0)); }}
/* a transcendental result widened by the library's margin for libm's error */
static inline double bg_dt(double x) {{ x = bg_mn(x, DBL_MAX); return x - (fabs(x) * BG_TREL + BG_TSUB); }}
static inline double bg_ut(double x) {{ x = bg_mx(x, -DBL_MAX); return x + (fabs(x) * BG_TREL + BG_TSUB); }}

typedef struct {{
    int ncols, npoints, keep, window, half, lag, ready_at, uniform, nsig, nder, nint;
    const int *sig;        /* (point, column) pairs */
    const int *der;        /* (point, column, order index, trusted) quadruples */
    const double *weights; /* per order: window interior weights, in scipy.ndimage's order */
    const int *sym;        /* per order: 1 symmetric, -1 antisymmetric, 0 neither (ndimage's test) */
    const double *start;   /* per order: half x window, the first window's one-sided fit */
    const double *end;     /* per order: half x window, the last window's one-sided fit */
    const double *divisor; /* per order: dt ** order */
    const int *ipoint;     /* per integral: its point */
    double (*integrand)(int k, const double *p);
    void (*evaluate)(const double *p, double *r, double *lo, double *hi);
}} bg_spec;

static double bg_derivative(const bg_spec *s, const double *x, int o, long i, long count, int at_end) {{
    int window = s->window, half = s->half, keep = s->keep, j;
    const double *row = NULL;
    long first;
    double acc;
    if (i < half) {{
        row = s->start + ((size_t)o * half + (size_t)i) * window;
        first = 0;
    }} else if (at_end && i >= count - half) {{
        row = s->end + ((size_t)o * half + (size_t)(i - count + half)) * window;
        first = count - window;
    }}
    if (row) {{
        acc = row[0] * x[first % keep];
        for (j = 1; j < window; j++) acc += row[j] * x[(first + j) % keep];
        return acc / s->divisor[o];
    }}
    first = i - half;
    {{
        const double *w = s->weights + (size_t)o * window;
        int sym = s->sym[o];
        if (sym == 0) {{
            acc = x[(first + window - 1) % keep] * w[window - 1];
            for (j = 0; j < window - 1; j++) acc += x[(first + j) % keep] * w[j];
        }} else {{
            acc = x[(first + half) % keep] * w[half];
            for (j = 0; j < half; j++) {{
                double a = x[(first + j) % keep], b = x[(first + window - 1 - j) % keep];
                acc += (sym > 0 ? a + b : a - b) * w[j];
            }}
        }}
    }}
    return acc;
}}

static void bg_finalize(const bg_spec *s, {prefix}_core *c, const double *tr, const double *x, double *integral,
                        double *integrand, long i, int at_end, {prefix}_sample *out) {{
    double p[{max_points}];
    int k, keep = s->keep;
    long position = i % keep;
    double t = tr[position], r, lo, hi;
    for (k = 0; k < s->npoints; k++) p[k] = 0.0;
    for (k = 0; k < s->nsig; k++) p[s->sig[2 * k]] = x[(size_t)s->sig[2 * k + 1] * keep + position];
    for (k = 0; k < s->nder; k++) {{
        const int *d = s->der + 4 * k;
        double v = bg_derivative(s, x + (size_t)d[1] * keep, d[2], i, c->count, at_end);
        if (d[3] && (i < s->half || (at_end && i >= c->count - s->half))) v = NAN;
        p[d[0]] = v;
    }}
    for (k = 0; k < s->nint; k++) {{
        double g = s->integrand(k, p), total;
        if (i == 0) total = 0.0;
        else total = integral[k] + (t - c->t_final) * (g + integrand[k]) / 2.0;
        if (g != g) total = NAN;
        integral[k] = total;
        integrand[k] = g;
        p[s->ipoint[k]] = total;
    }}
    c->t_final = t;
    s->evaluate(p, &r, &lo, &hi);
    out->index = i;
    out->t = t;
    out->residual = r;
    out->lower = lo;
    out->upper = hi;
    out->violation = (-r < lo - {upper}_MARGIN) || (-r > hi + {upper}_MARGIN);
    c->run = out->violation ? (c->run + 1 < {upper}_PERSISTENCE ? c->run + 1 : {upper}_PERSISTENCE) : 0;
    out->alarm = c->run >= {upper}_PERSISTENCE;
}}

static void bg_init({prefix}_core *c) {{
    c->count = 0;
    c->final = 0;
    c->ended = 0;
    c->run = 0;
    c->t_final = NAN;
}}

static int bg_push(const bg_spec *s, {prefix}_core *c, double *tr, double *x, double *integral, double *integrand,
                   double t, const double *values, {prefix}_sample *out) {{
    int k, n = 0, keep = s->keep;
    long position;
    if (c->ended) return {upper}_ERR_ENDED;
    if (!(fabs(t) <= BG_MAX_MAGNITUDE)) return {upper}_ERR_TIME;
    for (k = 0; k < s->ncols; k++)
        if (fabs(values[k]) > BG_MAX_MAGNITUDE) return {upper}_ERR_VALUE;
    if (c->count) {{
        double step = t - tr[(c->count - 1) % keep];
        if (step <= 0) return {upper}_ERR_TIME;
        if (s->uniform && fabs(step - {upper}_DT) > BG_RTOL * {upper}_DT) return {upper}_ERR_STEP;
    }}
    position = c->count % keep;
    tr[position] = t;
    for (k = 0; k < s->ncols; k++) x[(size_t)k * keep + position] = values[k];
    c->count++;
    if (c->count >= s->ready_at)
        while (c->final < c->count - s->lag) {{
            bg_finalize(s, c, tr, x, integral, integrand, c->final, 0, out + n++);
            c->final++;
        }}
    return n;
}}

static int bg_flush(const bg_spec *s, {prefix}_core *c, double *tr, double *x, double *integral, double *integrand,
                    {prefix}_sample *out) {{
    int n = 0;
    if (c->ended) return 0;
    if (c->final < c->count && c->count < s->ready_at) return {upper}_ERR_SHORT;
    while (c->final < c->count) {{
        bg_finalize(s, c, tr, x, integral, integrand, c->final, 1, out + n++);
        c->final++;
    }}
    c->ended = 1;
    return n;
}}
'''

_C_ARR_HEADER = '''
/* {name}: columns {columns_comment} */
#define {upper}_{ident}_NCOLS {ncols}
#define {upper}_{ident}_DELAY {lag}
{column_macros}
extern const char *const {prefix}_{ident}_columns[{ncols}];
typedef struct {{
    {prefix}_core core;
    double t[{keep}];
    double x[{xsize}];
    double integral[{nint}];
    double integrand[{nint}];
}} {prefix}_{ident}_state;
void {prefix}_{ident}_init({prefix}_{ident}_state *s);
size_t {prefix}_{ident}_size(void); /* sizeof the state, for callers that allocate it (ctypes) */
int {prefix}_{ident}_push({prefix}_{ident}_state *s, double t, const double *x, {prefix}_sample *out);
int {prefix}_{ident}_flush({prefix}_{ident}_state *s, {prefix}_sample *out);
/* A whole record: n samples (t[k], x[k * NCOLS + column]), pushed one by one, then flushed if flush != 0; the
 * final samples go to the arrays (room for n); returns their number, or a negative error. */
long {prefix}_{ident}_run({prefix}_{ident}_state *s, long n, const double *t, const double *x, int flush,
                          double *t_out, double *residual, double *lower, double *upper, int *alarm);
'''

_C_ARR_SOURCE = '''
const char *const {prefix}_{ident}_columns[{ncols}] = {{{column_strings}}};

static const int bg_{k}_sig[] = {{{sig}}};
static const int bg_{k}_der[] = {{{der}}};
static const double bg_{k}_weights[] = {{{weights}}};
static const int bg_{k}_sym[] = {{{sym}}};
static const double bg_{k}_start[] = {{{start}}};
static const double bg_{k}_end[] = {{{end}}};
static const double bg_{k}_divisor[] = {{{divisor}}};
static const int bg_{k}_ipoint[] = {{{ipoint}}};

static double bg_{k}_integrand(int m, const double *p) {{
{integrand_unpack}{integrand_body}    (void)m;
    (void)p;
    return NAN;
}}

static void bg_{k}_evaluate(const double *p, double *r_out, double *lo_out, double *hi_out) {{
{unpack}    {{
{residual_body}    }}
{interval_body}    *lo_out = {lo};
    *hi_out = {hi};
}}

static const bg_spec bg_{k}_spec = {{{ncols}, {npoints}, {keep}, {window}, {half}, {lag}, {ready_at}, {uniform},
    {nsig}, {nder}, {nint}, bg_{k}_sig, bg_{k}_der, bg_{k}_weights, bg_{k}_sym, bg_{k}_start, bg_{k}_end,
    bg_{k}_divisor, bg_{k}_ipoint, bg_{k}_integrand, bg_{k}_evaluate}};

void {prefix}_{ident}_init({prefix}_{ident}_state *s) {{ bg_init(&s->core); }}

size_t {prefix}_{ident}_size(void) {{ return sizeof({prefix}_{ident}_state); }}

int {prefix}_{ident}_push({prefix}_{ident}_state *s, double t, const double *x, {prefix}_sample *out) {{
    return bg_push(&bg_{k}_spec, &s->core, s->t, s->x, s->integral, s->integrand, t, x, out);
}}

int {prefix}_{ident}_flush({prefix}_{ident}_state *s, {prefix}_sample *out) {{
    return bg_flush(&bg_{k}_spec, &s->core, s->t, s->x, s->integral, s->integrand, out);
}}

long {prefix}_{ident}_run({prefix}_{ident}_state *s, long n, const double *t, const double *x, int flush,
                          double *t_out, double *residual, double *lower, double *upper, int *alarm) {{
    {prefix}_sample out[{upper}_MAX_OUT];
    long k, m = 0;
    int j, got;
    for (k = 0; k <= n; k++) {{
        if (k < n) got = {prefix}_{ident}_push(s, t[k], x + (size_t)k * {ncols}, out);
        else if (flush) got = {prefix}_{ident}_flush(s, out);
        else break;
        if (got < 0) return got;
        for (j = 0; j < got; j++, m++) {{
            t_out[m] = out[j].t;
            residual[m] = out[j].residual;
            lower[m] = out[j].lower;
            upper[m] = out[j].upper;
            alarm[m] = out[j].alarm;
        }}
    }}
    return m;
}}
'''


def _c_numbers(values) -> str:
    values = list(values)
    if not values:
        return "0"
    return ", ".join(repr(float(v)) for v in values)


def _c_module(plans: list[_Plan], prefix: str, options: dict) -> tuple[str, str]:
    upper = prefix.upper()
    max_out = max(max(p.half + 1, 1) for p in plans)
    header = [_C_HEADER.format(count=len(plans), prefix=prefix, upper=upper, guard=f"{upper}_H_GENERATED",
                               dt=repr(options["dt"]), margin=repr(options["margin"]),
                               persistence=options["persistence"], max_out=max_out)]
    trel, tsub = _trans()
    source = [f"/* Generated by bondgraph-phm (diagnosis.codegen) from {len(plans)} ARR(s); do not edit. */\n",
              _C_ENGINE.format(prefix=prefix, upper=upper, trel=repr(trel), tsub=repr(tsub),
                               max_magnitude=repr(MAX_MAGNITUDE), rtol=repr(UNIFORM_RTOL),
                               max_points=max(p.npoints for p in plans) or 1)]
    for plan in plans:
        k, ident = plan.index, plan.ident
        column_idents = [_identifier(c, "signal name") for c in plan.columns]
        _unique(list(zip(column_idents, plan.columns)), f"{plan.name}: signal names")
        macros = "".join(f"#define {upper}_{ident}_COL_{c} {j}\n" for j, c in enumerate(column_idents))
        header.append(_C_ARR_HEADER.format(
            name=ident, columns_comment=", ".join(column_idents), upper=upper, ident=ident, prefix=prefix,
            ncols=len(plan.columns), lag=plan.lag, column_macros=macros, keep=plan.keep,
            xsize=len(plan.columns) * plan.keep, nint=max(1, len(plan.integrals))))
        integrand_body = []
        for m, (_, g) in enumerate(plan.integrals):
            temporaries, result = _printed(g, plan.points, "c")
            integrand_body.append(f"    if (m == {m}) {{\n")
            integrand_body.extend(f"        const double {s} = {e};\n" for s, e in temporaries)
            integrand_body.append(f"        return {result};\n    }}\n")
        temporaries, result = _printed(plan.nominal, plan.points, "c")
        residual_body = "".join(f"        const double {s} = {e};\n" for s, e in temporaries)
        residual_body += f"        *r_out = {result};\n"
        lines, lo, hi = _interval_code(plan, "c")
        interval_body = "".join(f"    const double {s} = {e};\n" for s, e in lines)
        unpack = "".join(f"    const double p{j} = p[{j}];\n    (void)p{j};\n" for j in range(plan.npoints))
        source.append(_C_ARR_SOURCE.format(
            prefix=prefix, upper=upper, ident=ident, k=k, ncols=len(plan.columns),
            column_strings=", ".join(_c_string(c) for c in plan.columns),
            sig=", ".join(str(v) for pair in plan.signal_points for v in pair) or "0",
            der=", ".join(str(v) for quad in plan.derivs for v in quad) or "0",
            weights=_c_numbers(w for o in plan.orders for w in o["weights"]),
            sym=", ".join(str(o["sym"]) for o in plan.orders) or "0",
            start=_c_numbers(v for o in plan.orders for row in o["start"] for v in row),
            end=_c_numbers(v for o in plan.orders for row in o["end"] for v in row),
            divisor=_c_numbers(o["divisor"] for o in plan.orders),
            ipoint=", ".join(str(point) for point, _ in plan.integrals) or "0",
            integrand_body="".join(integrand_body), unpack=unpack,
            integrand_unpack=unpack if plan.integrals else "", residual_body=residual_body,
            interval_body=interval_body, lo=lo, hi=hi, npoints=plan.npoints, keep=plan.keep, window=plan.window,
            half=plan.half, lag=plan.lag, ready_at=plan.ready_at, uniform=int(bool(plan.derivs)),
            nsig=len(plan.signal_points), nder=len(plan.derivs), nint=len(plan.integrals)))
    header.append(f"\n#endif /* {upper}_H_GENERATED */\n")
    return "".join(header), "".join(source)
