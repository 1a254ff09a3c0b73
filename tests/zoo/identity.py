"""``r_n + Psi_2`` of an ARR on a reference run, evaluated here from the sympy expressions alone.

Signals and their derivatives come from the reference's exact values; an integral
``Integral(g, (t, 0, t))`` is the cumulative trapezoid of ``g`` on the reference grid, inner integrals
first.  The library's own evaluator is not used: this is the judge of it.
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from .reference import ReferenceRun


def _cumtrapz(tk: np.ndarray, y: np.ndarray) -> np.ndarray:
    out = np.zeros_like(y)
    out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(tk))
    return out


def _depth(integral: sp.Integral) -> int:
    inner = [i for i in integral.function.atoms(sp.Integral)]
    return len(integral.limits) + max((_depth(i) for i in inner), default=0)


def arr_values(expression: sp.Expr, run: ReferenceRun) -> np.ndarray:
    """``expression`` (signals, derivatives, integrals, numbers only) at every sample of ``run``."""
    tk = run.columns["t"]
    arrays: dict = {}
    replace: dict = {}

    def point(array: np.ndarray) -> sp.Symbol:
        symbol = sp.Dummy()
        arrays[symbol] = array
        return symbol

    for d in expression.atoms(sp.Derivative):
        (_, order), = d.variable_count
        replace[d] = point(run.derivatives[d.expr.func.__name__][int(order) - 1])
    for f in expression.atoms(AppliedUndef):
        replace[f] = point(run.columns[f.func.__name__])

    def numeric(e: sp.Expr) -> np.ndarray:
        e = e.xreplace(replace)
        symbols = list(arrays)
        fn = sp.lambdify(symbols, e, modules="numpy")
        return np.broadcast_to(np.asarray(fn(*(arrays[s] for s in symbols)), float), tk.shape)

    for integral in sorted(expression.atoms(sp.Integral), key=_depth):
        values = numeric(integral.function)
        for _ in integral.limits:  # Integral(g, L, L): sympy's form of a double integral
            values = _cumtrapz(tk, values)
        replace[integral] = point(values)
    return numeric(expression)


def identity_error(arr, run: ReferenceRun) -> float:
    """``max |r_n + Psi_2| / max |largest term of r_n|`` at the run's parameters (deltas from them)."""
    values = {sp.Symbol(p): v for p, v in arr.values.items()}
    deltas = {sp.Symbol(f"delta_{p}"): run.parameters[p] / arr.values[p] - 1.0 for p in arr.uncertainties}
    total = (arr.nominal + arr.uncertain).xreplace(deltas).xreplace(values)
    terms = sp.Add.make_args(sp.expand(arr.nominal.xreplace(values), deep=False))
    scale = max(float(np.nanmax(np.abs(arr_values(term, run)))) for term in terms)
    return float(np.nanmax(np.abs(arr_values(total, run)))) / max(scale, 1e-300)
