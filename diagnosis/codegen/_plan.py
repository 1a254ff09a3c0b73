"""What one ARR's stream needs: its columns, Savitzky-Golay filters and one-sided fits, integrals, expressions,
and the interval form of its threshold (the library's affine range or natural extension)."""

from __future__ import annotations

import math
import numbers
from fractions import Fraction

import numpy as np
import sympy as sp
from scipy.signal import savgol_coeffs

from ..deltas import delta
from ..derivatives import check_savgol_settings, default_window
from ..detection import check_options, fitting_order
from ..intervals import affine_range, compile_interval
from ._errors import CodegenError
from ._identifiers import identifier

__all__ = ["Plan"]

_EPS = float(np.finfo(float).eps)  # ndimage's symmetry test of a filter compares with DBL_EPSILON


class Plan:
    """What one ARR's stream computes: its columns, derivative filters, integrals, and expressions."""

    def __init__(self, arr, index: int, *, dt: float, method: str, window, polyorder, margin, persistence) -> None:
        try:
            check_options(arr, "generate_code", method=method, margin=margin, persistence=persistence)
        except (TypeError, ValueError) as exc:
            raise CodegenError(str(exc)) from None
        self.name, self.index = arr.name, index
        self.ident = identifier(arr.name, "ARR name")
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
