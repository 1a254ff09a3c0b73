"""The multiplicative uncertainty symbols ``delta_<param>`` and how they are typeset.

An uncertain parameter's true value is ``value * (1 + delta)``, with ``delta`` in the element's
``uncertainty`` interval; the uncertain part Psi_2 of an ARR is written in these symbols.  The
naming is spelt in one place: :func:`delta` writes it and :func:`delta_parameter` reads it, for the
derivation (splitting Psi_2 into terms), the thresholds (the box of each delta) and the LaTeX and
MathML typesetting below.

Example
-------
>>> import sympy as sp
>>> delta("R_a"), delta_parameter(delta("R_a")), delta_parameter(sp.Symbol("R_a"))
(delta_R_a, 'R_a', None)
>>> w = -sp.Symbol("R_a") * delta("R_a") * sp.Function("i")(sp.Symbol("t"))   # a BG-LFT term of Psi_2
>>> print(latex(w))
- R_{a} \\delta_{R_{a}} i{\\left(t \\right)}
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.mathml import MathMLPresentationPrinter

PREFIX = "delta_"


def delta(parameter: str) -> sp.Symbol:
    """The multiplicative uncertainty symbol of a parameter: ``delta_<param>``.

    The true value of an uncertain parameter is ``value * (1 + delta)``, with
    ``delta`` in the element's ``uncertainty`` interval.

    Parameters
    ----------
    parameter : str
        A parameter name.

    Returns
    -------
    sympy.Symbol

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> from diagnosis import derive_arrs
    >>> delta("R_a")
    delta_R_a
    >>> arr = derive_arrs(dc_motor())[0]
    >>> arr.uncertain.has(delta("R_a")), arr.uncertain.has(delta("J"))
    (True, False)
    >>> arr.terms["R_a"]
    -R_a*delta_R_a*i(t)
    """
    return sp.Symbol(f"{PREFIX}{parameter}")


def delta_parameter(symbol: sp.Symbol) -> str | None:
    """The parameter whose uncertainty :func:`delta` names with ``symbol``, or None for any other symbol.

    >>> delta_parameter(delta("L_a")), delta_parameter(sp.Symbol("L_a"))
    ('L_a', None)
    """
    return symbol.name[len(PREFIX):] if symbol.name.startswith(PREFIX) else None


def latex(expression: sp.Expr) -> str:
    r"""LaTeX of an ARR expression, each ``delta_<param>`` typeset as delta with the parameter's own subscript.

    sympy alone reads ``delta_L_a`` as two subscripts and prints ``\delta_{L a}``.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> from diagnosis import derive_arrs
    >>> print(latex(derive_arrs(dc_motor())[0].terms["L_a"]))
    - L_{a} \delta_{L_{a}} \frac{d}{d t} i{\left(t \right)}
    """
    names = {s: f"\\delta_{{{sp.latex(sp.Symbol(delta_parameter(s)))}}}"
             for s in expression.free_symbols if delta_parameter(s) is not None}
    return sp.latex(expression, symbol_names=names)


def mathml(expression: sp.Expr) -> str:
    """Presentation MathML of an ARR expression, typeset as :func:`latex` does.

    ``delta_L_a`` is a delta with subscript ``L_a`` and a signal ``omega_m(t)`` a subscripted omega
    of t (sympy alone prints the function's raw name).  The result is the content of a ``<math>``
    element.

    Examples
    --------
    >>> t = sp.Symbol("t")
    >>> print(mathml(delta("L_a")))
    <msub><mi>&#948;</mi><msub><mi>L</mi><mi>a</mi></msub></msub>
    >>> print(mathml(sp.Function("omega_m")(t)))
    <mrow><msub><mi>&#969;</mi><mi>m</mi></msub><mo>(</mo><mi>t</mi><mo>)</mo></mrow>
    """
    return _Presentation({}).doprint(expression)


class _Presentation(MathMLPresentationPrinter):
    """sympy's presentation MathML printer, with the delta and signal typesetting of :func:`mathml`.

    The ``_print_<Type>`` methods are sympy's printer protocol: they override its defaults.
    """

    def _print_Symbol(self, sym, style="plain"):
        parameter = delta_parameter(sym)
        if parameter is not None:
            return self._print(sp.IndexedBase("delta")[sp.Symbol(parameter)])
        return super()._print_Symbol(sym, style)

    def _print_AppliedUndef(self, signal):
        row = self.dom.createElement("mrow")
        row.appendChild(self._print(sp.Symbol(signal.func.__name__)))
        row.appendChild(self._operator("("))
        for i, argument in enumerate(signal.args):
            if i:
                row.appendChild(self._operator(","))
            row.appendChild(self._print(argument))
        row.appendChild(self._operator(")"))
        return row

    def _operator(self, text: str):
        mark = self.dom.createElement("mo")
        mark.appendChild(self.dom.createTextNode(text))
        return mark
