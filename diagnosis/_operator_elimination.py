"""Residuals of linear sets that substitution cannot close: elimination with d/dt as an operator.

A minimal set whose matching leaves a loop through a state has no residual by solving each equation for
one unknown: a spring and a damper in parallel whose deflection is not measured give ``q/C + c dq/dt = F``,
an ODE in ``q``.  When the set is linear in its unknowns with constant coefficients, the unknowns can
still be eliminated by differentiation alone: with ``d/dt`` written as an operator ``s`` (constant
coefficients commute with it), a fraction-free Gaussian elimination over polynomials in ``s`` leaves one
relation ``sum_j P_j(s) g_j = 0`` in the known terms ``g_j`` of the equations, read back with ``s^k g`` as
the k-th derivative of ``g``.  A minimal set of ``n + 1`` equations in ``n`` unknowns leaves exactly one
such relation (the polynomial view of linear residual generation of Nyberg and Frisk (2006)).

The result is exact: no integral, no operation cap, and the same elimination run on the equations with
theta (1 + delta_theta) gives the nominal relation at delta = 0, so the BG-LFT split holds.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.polys.polyerrors import CoercionFailed

from bondgraph.calculus import time_derivative
from bondgraph.structure import T

__all__ = ["MAX_TERMS", "operator_order", "operator_residual"]

#: The most terms a polynomial entry may reach during an elimination before the set is given up (its
#: relation would be over any operation cap, and sympy's polynomial arithmetic grows with it: a long RLC
#: ladder's set of 70 equations ran for minutes).
MAX_TERMS = 4000


class _TooLarge(Exception):
    """An entry of the elimination outgrew :data:`MAX_TERMS`."""


#: The prime of the finite field :func:`operator_order` computes in (2**31 - 1).
_PRIME = 2147483647

#: The operator standing for d/dt in the coefficients.
_S = sp.Dummy("s")


@dataclass
class _Row:
    """``sum_u coefficients[u](s) u + sum_g known[g](s) g = 0``: polynomials in the parameters and ``s`` acting on
    the unknowns and on the known terms ``g`` of the equation."""

    coefficients: dict
    known: dict

    def combined(self, a, other: _Row, b) -> _Row:
        """``(a * self - b * other) / gcd``, zero entries dropped: fraction-free, the common factor taken out."""
        def mix(mine: dict, theirs: dict) -> dict:
            out = {}
            for key in dict.fromkeys([*mine, *theirs]):
                value = a * mine[key] if key in mine else 0
                if key in theirs:
                    value = value - b * theirs[key]
                if value:
                    out[key] = value
            return out
        row = _Row(mix(self.coefficients, other.coefficients), mix(self.known, other.known))
        if max(map(len, [*row.coefficients.values(), *row.known.values()]), default=0) > MAX_TERMS:
            raise _TooLarge
        return row.reduced()

    def reduced(self) -> _Row:
        entries = [*self.coefficients.values(), *self.known.values()]
        if not entries:
            return self
        common = entries[0]
        for entry in entries[1:]:
            common = common.gcd(entry)
            if common == 1:
                return self
        return _Row({u: c.exquo(common) for u, c in self.coefficients.items()},
                    {g: c.exquo(common) for g, c in self.known.items()})


def operator_residual(equations: list, unknowns: list) -> sp.Expr | None:
    """The relation left in known signals when ``unknowns`` are eliminated from linear ``equations``.

    Parameters
    ----------
    equations : list of sympy.Eq
        The set's equations: bond variables (symbols), states (functions of ``t``) and their derivatives,
        known signals, parameters.
    unknowns : list
        The bond-variable symbols and state functions to eliminate.

    Returns
    -------
    sympy.Expr or None
        The residual, in the known signals and their derivatives, polynomial in the parameters; None when
        an equation is not linear in the unknowns with coefficients rational in the parameters, or nothing
        is left once they are eliminated.

    Examples
    --------
    A force ``F`` measured across a spring and a damper in parallel, the velocity ``v`` across them measured
    (``q/C + c dq/dt = F``: the deflection ``q`` cannot be solved for, differentiating once removes it):

    >>> import sympy as sp
    >>> from bondgraph.structure import T
    >>> q, F, v = sp.Function("q")(T), sp.Function("F")(T), sp.Function("v")(T)
    >>> C, c, f = sp.symbols("C c f")
    >>> equations = [sp.Eq(q / C + c * f, F), sp.Eq(sp.Derivative(q, T), f), sp.Eq(f, v)]
    >>> operator_residual(equations, [q, f])
    -C*c*Derivative(v(t), t) + C*Derivative(F(t), t) - v(t)
    >>> operator_order(equations, [q, f])
    1
    """
    parsed = _parsed(equations, unknowns)
    if parsed is None:
        return None
    rows = _in_ring(parsed, [*_parameters(parsed), _S], sp.ZZ)
    if rows is None:
        return None
    try:
        left = _eliminated(rows)
    except _TooLarge:
        return None
    return None if left is None else _read_back(left)


def operator_order(equations: list, unknowns: list) -> int | None:
    """The highest derivative :func:`operator_residual` would take of a known term, found cheaply: the same
    elimination with the parameters at random values modulo a large prime (a generic point: the degrees are
    those of the symbolic result but for a vanishing fraction of draws; exact arithmetic in a finite field
    does not grow as rationals do).  None where it would give None."""
    parsed = _parsed(equations, unknowns)
    if parsed is None:
        return None
    draw = random.Random(20261128)
    point = {x: sp.Integer(draw.randrange(2, _PRIME)) for x in _parameters(parsed)}
    numeric = [({u: c.xreplace(point) for u, c in coefficients.items()},
                {g: c.xreplace(point) for g, c in known.items()}) for coefficients, known in parsed]
    rows = _in_ring(numeric, [_S], sp.GF(_PRIME))
    try:
        left = None if rows is None else _eliminated(rows)
    except _TooLarge:
        return None
    if left is None:
        return None
    return max(max(m[0] for m in c.monoms()) + _order(g) for g, c in left.known.items())


def _parameters(parsed: list) -> list:
    """The symbols of the coefficients (parameters and their deltas), in name order."""
    found = set().union(*(c.free_symbols for row in parsed for c in [*row[0].values(), *row[1].values()]))
    return sorted(found - {_S}, key=str)


def _order(known: sp.Expr) -> int:
    """The highest derivative a known term holds already."""
    return max((d.derivative_count for d in known.atoms(sp.Derivative)), default=0)


def _parsed(equations: list, unknowns: list) -> list | None:
    """Each equation as (unknown -> coefficient in ``s``, known term -> 1), coefficients as sympy expressions."""
    parsed = []
    for equation in equations:
        row = _row(equation, unknowns)
        if row is None:
            return None
        parsed.append(row)
    return parsed


def _row(equation: sp.Eq, unknowns: list) -> tuple | None:
    """The equation as operators on the unknowns and its known part; None unless linear with constant coefficients."""
    expression = equation.lhs - equation.rhs
    functions = [u for u in unknowns if isinstance(u, AppliedUndef)]
    jets, mapping = {}, {}
    for d in expression.atoms(sp.Derivative):
        if d.expr in functions:
            mapping[d] = jets.setdefault((d.expr, d.derivative_count), sp.Dummy())
    expression = expression.xreplace(mapping)
    for u in unknowns:
        if expression.has(u):
            expression = expression.xreplace({u: jets.setdefault((u, 0), sp.Dummy())})
    symbols = set(jets.values())
    coefficients: dict = {}
    for (u, order), symbol in jets.items():
        slope = sp.diff(expression, symbol)
        if slope.free_symbols & symbols or slope.has(AppliedUndef, sp.Derivative, T):
            return None
        coefficients[u] = coefficients.get(u, 0) + slope * _S ** order
    known = sp.expand(expression.xreplace({s: 0 for s in symbols}))
    coefficients = {u: c for u, c in coefficients.items() if c != 0}
    return coefficients, ({known: sp.S.One} if known != 0 else {})


def _in_ring(parsed: list, generators: list, domain) -> list | None:
    """The rows with polynomial entries in ``generators`` over ``domain``, each row's denominators cleared."""
    ring = sp.ring(generators, domain)[0]
    rows = []
    for coefficients, known in parsed:
        fractions = {key: sp.fraction(sp.together(c)) for key, c in [*coefficients.items(), *known.items()]}
        try:
            scale = ring(1)
            for _, denominator in fractions.values():
                scale = scale.lcm(ring.from_expr(denominator))
            entries = {key: ring.from_expr(n) * scale.exquo(ring.from_expr(d)) for key, (n, d) in fractions.items()}
        except (CoercionFailed, ValueError):   # a coefficient not rational in the parameters (a root, a function)
            return None
        rows.append(_Row({u: entries[u] for u in coefficients}, {g: entries[g] for g in known}).reduced())
    return rows


def _eliminated(rows: list) -> _Row | None:
    """The row left, in known terms only, once every unknown is eliminated; None if none is left."""
    while any(row.coefficients for row in rows):
        index, unknown = _pivot(rows)
        pivot = rows.pop(index)
        a = pivot.coefficients[unknown]
        rows = [row.combined(a, pivot, row.coefficients[unknown]) if unknown in row.coefficients else row
                for row in rows]
        rows = [row for row in rows if row.coefficients or row.known]
    left = [row for row in rows if row.known]
    return min(left, key=lambda row: sum(len(c) for c in row.known.values())) if left else None


def _pivot(rows: list) -> tuple[int, object]:
    """The (row, unknown) to eliminate next: the fewest fill-ins (Markowitz), then the smallest coefficient."""
    holders: dict = {}
    for row in rows:
        for u in row.coefficients:
            holders[u] = holders.get(u, 0) + 1
    best = None
    for i, row in enumerate(rows):
        for u, c in row.coefficients.items():
            key = ((len(row.coefficients) - 1) * (holders[u] - 1), not c.is_ground, len(c), i)
            if best is None or key < best[0]:
                best = (key, i, u)
    return best[1], best[2]


def _read_back(row: _Row) -> sp.Expr:
    """``sum_g P_g(s) g`` with ``s^k g`` read as the k-th time derivative of ``g``."""
    terms = []
    for known, operator in row.known.items():
        for (power,), coefficient in sp.Poly(operator.as_expr(), _S).terms():
            terms.append(sp.factor_terms(coefficient) * time_derivative(known, power))
    return sp.Add(*terms)
