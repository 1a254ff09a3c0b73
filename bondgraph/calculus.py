"""Time derivatives of expressions in real signals, without sympy's complex forms.

Every function of time a model writes (a signal ``x(t)``, an energy variable ``q_C(t)``, their derivatives
and their integrals from the start of the record) and every parameter is a real number.  sympy does not
know it: ``diff(Abs(x(t)), t)`` gives ``(re(x) d re(x)/dt + im(x) d im(x)/dt) / Abs(x)``, and the
derivative of a real function is not known to be real even when the function is declared so.  Those
``re``/``im`` terms then look like signals to whoever reads the expression, and no numeric evaluator
can compute them.

:func:`time_derivative` applies the chain rule itself: each function of time is replaced by a real
symbol, differentiated by that symbol (``d|x|/dx = sign(x)``), and multiplied by the function's own
time derivative.  :func:`real_parts` removes ``re``/``im`` that an expression already holds.
"""

from __future__ import annotations

import sympy as sp
from sympy.core.function import AppliedUndef

from .structure import T

__all__ = ["real_parts", "time_derivative"]


def time_derivative(expression: sp.Expr, count: int = 1) -> sp.Expr:
    """The ``count``-th time derivative of ``expression``, every function of ``t`` and every symbol real.

    The Dirac pulses of a sign's derivative are dropped (they are zero almost everywhere, and a sampled
    record never sits on one).

    Parameters
    ----------
    expression : sympy.Expr
        Signals ``x(t)``, their derivatives, integrals ``Integral(g, (t, 0, t))``, parameters, ``t``.
    count : int
        How many times to differentiate (0 returns ``expression``).

    Returns
    -------
    sympy.Expr
        The derivative, free of ``re``, ``im`` and ``DiracDelta``.

    Examples
    --------
    >>> import sympy as sp
    >>> t, a = sp.Symbol("t"), sp.Symbol("a")
    >>> h = sp.Function("h")(t)
    >>> time_derivative(a * sp.Abs(sp.Derivative(h, t)))
    a*sign(Derivative(h(t), t))*Derivative(h(t), (t, 2))
    >>> time_derivative(sp.Integral(h**2, (t, 0, t)), 2)
    2*h(t)*Derivative(h(t), t)
    """
    if not (isinstance(count, (int, sp.Integer)) and count >= 0):   # Derivative.derivative_count is a sympy Integer
        raise ValueError(f"time_derivative: count {count!r} is not a non-negative integer")
    for _ in range(int(count)):
        expression = _once(sp.sympify(expression))
    return expression


def _once(expression: sp.Expr) -> sp.Expr:
    """One time derivative, addend by addend: each is differentiated by the stand-ins it holds only."""
    return sp.Add(*(_once_term(term) for term in sp.Add.make_args(expression)))


def _once_term(expression: sp.Expr) -> sp.Expr:
    """One time derivative by the chain rule over real stand-ins of the functions of time and the symbols."""
    if not expression.has(T):
        return sp.S.Zero
    rates = _rates(expression)
    stand_in = {atom: sp.Dummy(real=True) for atom in rates}
    # parameters (and any other symbol but t) are real constants: Abs(a x) then differentiates as sign(a x)
    stand_in.update({s: sp.Dummy(s.name, real=True) for s in expression.free_symbols if s != T})
    frozen = expression.xreplace(stand_in).replace(sp.Abs, _RealAbs).replace(sp.sign, _RealSign)
    total = sp.diff(frozen, T) + sp.Add(*(sp.diff(frozen, stand_in[atom]) * rate for atom, rate in rates.items()))
    total = total.xreplace({pulse: 0 for pulse in total.atoms(sp.DiracDelta)})   # from Heaviside, Min, Max
    back = {dummy: atom for atom, dummy in stand_in.items()}
    return total.replace(_RealAbs, sp.Abs).replace(_RealSign, sp.sign).xreplace(back)


class _RealAbs(sp.Function):
    """``Abs`` of a real argument: sympy's own asks whether ``1/a`` is real (``a`` might be zero) and, not
    sure, writes ``|x|`` as ``x/sign(x)``, which is 0/0 where ``x`` vanishes."""

    def fdiff(self, argindex: int = 1) -> sp.Expr:
        return _RealSign(self.args[0])


class _RealSign(sp.Function):
    """``sign`` of a real argument: its derivative is zero almost everywhere (the Dirac pulse dropped)."""

    def fdiff(self, argindex: int = 1) -> sp.Expr:
        return sp.S.Zero


def _rates(expression: sp.Expr) -> dict:
    """Each outermost function of time in ``expression`` -> its time derivative.

    ``x(t)`` gives ``Derivative(x(t), t)``, a derivative one order more, ``Integral(g, (t, 0, t))`` its
    integrand.  Only the outermost are taken: the ``x(t)`` inside a derivative or an integral belongs
    to it.
    """
    rates: dict = {}

    def visit(node: sp.Basic) -> None:
        if isinstance(node, sp.Integral) and node.limits == ((T, 0, T),):
            rates[node] = node.function
        elif isinstance(node, sp.Derivative) and isinstance(node.expr, AppliedUndef) and set(node.variables) == {T}:
            rates[node] = sp.Derivative(node.expr, (T, node.derivative_count + 1))
        elif isinstance(node, AppliedUndef) and node.args == (T,):
            rates[node] = sp.Derivative(node, T)
        else:
            for arg in node.args:
                visit(arg)

    visit(expression)
    return rates


def real_parts(expression: sp.Expr) -> sp.Expr:
    """``expression`` with ``re(x)`` as ``x`` and ``im(x)`` as 0: every quantity of a model is real.

    Examples
    --------
    >>> import sympy as sp
    >>> t = sp.Symbol("t")
    >>> x = sp.Function("x")(t)
    >>> real_parts(sp.re(sp.Derivative(x, t)) + sp.im(x) * x)
    Derivative(x(t), t)
    """
    if not expression.has(sp.re, sp.im):
        return expression
    return expression.replace(sp.re, lambda arg: arg).replace(sp.im, lambda arg: sp.S.Zero)
