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

import html
import re

import sympy as sp
from sympy.printing.latex import LatexPrinter
from sympy.printing.mathml import MathMLPresentationPrinter

from bondgraph.drawing import latex_escape

__all__ = ["MATHML_ELEMENTS", "PREFIX", "delta", "delta_parameter", "latex", "mathml"]

PREFIX = "delta_"

#: A symbol or function name sympy may typeset in LaTeX as it likes (split at ``_``, Greek letters): an
#: ASCII identifier.  Any other name is printed as escaped text, so that it cannot carry markup.
_PLAIN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: The elements the MathML printer writes; anything else in its output is refused (defence in depth).
MATHML_ELEMENTS = frozenset({"math", "mrow", "mi", "mn", "mo", "msub", "msup", "msubsup", "mfrac", "msqrt",
                             "mroot", "mfenced", "mtext", "mspace", "munder", "mover", "munderover", "mtable",
                             "mtr", "mtd", "mstyle", "mpadded", "mphantom", "menclose"})
_TAG = re.compile(r"<\s*/?\s*([^\s/>]+)")
_XML_ILLEGAL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f\ud800-\udfff\ufffe\uffff]")


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
    printer = _Latex()
    names = {s: f"\\delta_{{{printer.doprint(sp.Symbol(delta_parameter(s)))}}}"
             for s in expression.free_symbols if delta_parameter(s) is not None}
    return _Latex({"symbol_names": names}).doprint(expression)


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

    Text is escaped (sympy alone writes a name, or the ``<`` of an inequality, raw):

    >>> print(mathml(sp.Symbol("<b>x</b>")))
    <mi>&lt;b&gt;x&lt;/b&gt;</mi>
    """
    text = _Presentation({}).doprint(expression)
    for tag in _TAG.findall(text):  # every element must be MathML, whatever sympy printed
        if tag not in MATHML_ELEMENTS:
            raise ValueError(f"mathml: the printed expression holds a <{tag}> element, which is not MathML")
    return text


class _Latex(LatexPrinter):
    """sympy's LaTeX printer, with names that are not ASCII identifiers escaped as ``\\text{...}``.

    sympy writes a symbol's or function's name as it is: ``}\\input{x}`` would leave its group.
    """

    def _deal_with_super_sub(self, string: str, style: str = "plain") -> str:
        if _PLAIN.fullmatch(string):
            return super()._deal_with_super_sub(string, style)
        return rf"\text{{{latex_escape(string)}}}"


class _Presentation(MathMLPresentationPrinter):
    """sympy's presentation MathML printer, with the delta and signal typesetting of :func:`mathml`.

    The ``_print_<Type>`` methods are sympy's printer protocol: they override its defaults.
    """

    def _print_Symbol(self, sym, style="plain"):
        parameter = delta_parameter(sym)
        if parameter is not None:
            return self._print(sp.IndexedBase("delta")[sp.Symbol(parameter)])
        return super()._print_Symbol(sym, style)

    def doprint(self, expr) -> str:
        """The MathML text, every text node escaped (sympy writes them raw, to keep its entities)."""
        root = self._print(expr)
        stack = [root]
        while stack:
            node = stack.pop()
            if node.nodeType == node.TEXT_NODE:
                node.data = _escape_text(node.data)
            stack.extend(node.childNodes)
        return root.toxml().encode("ascii", "xmlcharrefreplace").decode()

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


#: An entity or character reference sympy writes on purpose (``&InvisibleTimes;``, ``&#948;``).
_REFERENCE = re.compile(r"&(?:[A-Za-z][A-Za-z0-9]*|#[0-9]+|#x[0-9A-Fa-f]+);")


def _escape_text(text: str) -> str:
    """Text content safe in XML: ``<``, ``>`` and a bare ``&`` escaped, references kept, illegal characters replaced."""
    parts = []
    last = 0
    for match in _REFERENCE.finditer(text):
        parts += [html.escape(text[last:match.start()], quote=False), match.group()]
        last = match.end()
    parts.append(html.escape(text[last:], quote=False))
    return _XML_ILLEGAL.sub("\ufffd", "".join(parts))
