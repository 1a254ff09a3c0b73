"""Integrals an ARR can compute: uncertain parameters stand outside them.

A relation eliminated from a set of equations may integrate an expression that holds parameters,
``Integral(-C1*Derivative(v1(t), t) + (V(t) - v1(t))/R1, (t, 0, t))``.  Evaluated on a record, an
integral is a point value computed once from the samples; with a parameter inside, it would have to be
recomputed for every value of the parameter, and its deviation ``delta`` could not be bounded by
interval arithmetic over point values.  Integration is linear, so a factor free of time moves out:

    Integral(c1 g1 + c2 g2) = c1 Integral(g1) + c2 Integral(g2),

grouped by the factor holding the chosen symbols, inner integrals first (sympy writes
``Integral(Integral(g, (t, 0, t)), (t, 0, t))`` as one integral with two limits: each limit is an
integration of its own).  What stays inside holds no
chosen symbol unless it is not separable (``sqrt(a x(t))``); :func:`held_inside` names those.
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy as sp
from sympy.core.function import AppliedUndef

__all__ = ["factor_out_of_integrals", "held_inside"]

T = sp.Symbol("t")


def factor_out_of_integrals(expression: sp.Expr, symbols: Iterable[sp.Symbol]) -> sp.Expr:
    """``expression`` with each integrand's factors in ``symbols`` moved in front of its integral.

    Examples
    --------
    >>> import sympy as sp
    >>> t, R, C = sp.symbols("t R C")
    >>> v, V = sp.Function("v"), sp.Function("V")
    >>> e = sp.Integral((V(t) - v(t)) / R + C * sp.Integral(v(t) / R, (t, 0, t)), (t, 0, t))
    >>> factor_out_of_integrals(e, [R, C])
    C*Integral(v(t), (t, 0, t), (t, 0, t))/R + Integral(V(t) - v(t), (t, 0, t))/R
    """
    chosen = frozenset(symbols)
    if not chosen or not expression.has(sp.Integral):
        return expression
    return _factor(expression, chosen)


def held_inside(expression: sp.Expr, symbols: Iterable[sp.Symbol]) -> list[sp.Integral]:
    """The integrals of ``expression`` whose integrand still holds one of ``symbols``.

    >>> import sympy as sp
    >>> t, a = sp.symbols("t a")
    >>> x = sp.Function("x")
    >>> held_inside(sp.Integral(sp.sqrt(a * x(t)), (t, 0, t)), [a])
    [Integral(sqrt(a*x(t)), (t, 0, t))]
    """
    chosen = set(symbols)
    return sorted((i for i in expression.atoms(sp.Integral) if i.function.free_symbols & chosen), key=str)


def _factor(expression: sp.Expr, chosen: frozenset) -> sp.Expr:
    if not expression.has(sp.Integral):
        return expression
    if isinstance(expression, sp.Integral):
        # sympy writes a nested integral as one with several limits, innermost first
        integrand = _factor(expression.function, chosen)
        for limits in expression.limits:
            integrand = _factor_single(integrand, limits, chosen)
        return integrand
    if not expression.args:
        return expression
    return expression.func(*(_factor(a, chosen) for a in expression.args))


def _factor_single(integrand: sp.Expr, limits: tuple, chosen: frozenset) -> sp.Expr:
    """``Integral(integrand, limits)`` with the factors in ``chosen`` in front, grouped by factor."""
    groups: dict = {}
    # products distributed over sums, with signals, derivatives and inner integrals kept whole
    frozen = {a: sp.Dummy() for a in integrand.atoms(sp.Derivative, sp.Integral, AppliedUndef)}
    spread = sp.expand_mul(integrand.xreplace(frozen)).xreplace({d: a for a, d in frozen.items()})
    for term in sp.Add.make_args(spread):
        rest, factor = term.as_independent(*chosen, as_Add=False)
        if factor.has(T):  # the parameter is tangled with the signals: it stays inside
            rest, factor = term, sp.S.One
        groups[factor] = groups.get(factor, sp.S.Zero) + rest
    return sp.Add(*(factor * sp.Integral(rest, limits) for factor, rest in groups.items()))
