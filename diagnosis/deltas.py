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

Both printers write a name with underscores as nested subscripts (``h_tank_2`` is h sub tank sub 2),
a time derivative as ``d^n x / d t^n`` and an integral with an upright d (ISO 80000-2), so the
same expression reads the same in MathML and in LaTeX.
"""

from __future__ import annotations

import html
import re

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.printing.latex import LatexPrinter
from sympy.printing.mathml import MathMLPresentationPrinter
from sympy.printing.precedence import PRECEDENCE

from bondgraph.drawing import latex_escape

__all__ = ["MATHML_ELEMENTS", "PREFIX", "delta", "delta_parameter", "latex", "mathml", "summands"]

PREFIX = "delta_"

#: A symbol or function name (or a part of one, ``2`` in ``h_2``) sympy may typeset in LaTeX as it likes
#: (Greek letters, trailing digits): ASCII letters, digits and ``_``.  Any other name is printed as escaped
#: text, so that it cannot carry markup.
_PLAIN = re.compile(r"[A-Za-z0-9_]+")
#: The elements the MathML printer writes; anything else in its output is refused (defence in depth).
MATHML_ELEMENTS = frozenset({"math", "mrow", "mi", "mn", "mo", "msub", "msup", "msubsup", "mfrac", "msqrt",
                             "mroot", "mfenced", "mtext", "mspace", "munder", "mover", "munderover", "mtable",
                             "mtr", "mtd", "mstyle", "mpadded", "mphantom", "menclose"})
_TAG = re.compile(r"<\s*/?\s*([^\s/>]+)")
_XML_ILLEGAL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f\ud800-\udfff\ufffe\uffff]")
#: The minus sign (U+2212): sympy writes the hyphen-minus, which a browser sets as a short hyphen.
_MINUS = "\u2212"


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

    sympy alone reads ``delta_L_a`` as two subscripts and prints ``\delta_{L a}``.  A name with
    underscores is written as nested subscripts, and the time derivative of a signal as
    ``\frac{\mathrm{d}^{n} x}{\mathrm{d} t^{n}}`` (sympy writes ``\frac{d^{n}}{d t^{n}} x{\left(t \right)}``).

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> from diagnosis import derive_arrs
    >>> print(latex(derive_arrs(dc_motor())[0].terms["L_a"]))
    - L_{a} \delta_{L_{a}} \frac{\mathrm{d} i}{\mathrm{d} t}
    >>> t = sp.Symbol("t")
    >>> print(latex(sp.Derivative(sp.Function("omega_m")(t), (t, 2))))
    \frac{\mathrm{d}^{2} \omega_{m}}{\mathrm{d} t^{2}}
    >>> print(latex(sp.Symbol("h_tank_2") * sp.Integral(sp.Function("q")(t), (t, 0, t))))
    h_{tank_{2}} \int\limits_{0}^{t} q{\left(t \right)}\, \mathrm{d}t
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
    >>> print(mathml(sp.Function("omega_m")(t)).replace(' stretchy="false"', ""))
    <mrow><msub><mi>&#969;</mi><mi>m</mi></msub><mrow><mo>(</mo><mi>t</mi><mo>)</mo></mrow></mrow>

    A name with underscores is nested subscripts, a time derivative ``d^n x / d t^n`` with an upright d
    (sympy writes the differential sign U+2146 and ``d^2 / d^2 t``), the minus sign U+2212:

    >>> print(mathml(sp.Symbol("h_tank_2")))
    <msub><mi>h</mi><msub><mi>tank</mi><mn>2</mn></msub></msub>
    >>> print(mathml(-sp.Derivative(sp.Function("x")(t), (t, 2))).replace('<mi mathvariant="normal">d</mi>', "d"))
    <mrow><mo>&#8722;</mo><mfrac><mrow><msup>d<mn>2</mn></msup><mi>x</mi></mrow><mrow>d<msup><mi>t</mi><mn>2</mn></msup></mrow></mfrac></mrow>

    Text is escaped (sympy alone writes a name, or the ``<`` of an inequality, raw):

    >>> print(mathml(sp.Symbol("<b>x</b>")))
    <mi>&lt;b&gt;x&lt;/b&gt;</mi>
    """
    text = _Presentation({}).doprint(expression)
    for tag in _TAG.findall(text):  # every element must be MathML, whatever sympy printed
        if tag not in MATHML_ELEMENTS:
            raise ValueError(f"mathml: the printed expression holds a <{tag}> element, which is not MathML")
    return text


def summands(expression: sp.Expr) -> list[sp.Expr]:
    """The terms of a sum in the order :func:`latex` and :func:`mathml` print them (a non-sum is one term).

    A long relation is broken between these terms, each line printed on its own, so the lines must
    follow the printed order.

    Examples
    --------
    >>> a, b, c = sp.symbols("a b c")
    >>> summands(c - a + 2 * b), summands(a * b)
    ([-a, 2*b, c], [a*b])
    """
    if not isinstance(expression, sp.Add):
        return [expression]
    return list(_Latex()._as_ordered_terms(expression))  # sympy's own ordering, which its Add printers use


def _subscripted(name: str) -> tuple[str, str] | None:
    """``(base, subscript)`` of ``base_subscript`` (split at the first ``_``), or None.

    None for a name without ``_``, and for one with an empty part (``_x``, ``x_``, ``x__y``): no
    reading of those as subscripts is obvious, so they are printed as written.
    """
    base, _, rest = name.partition("_")
    if not rest or "" in name.split("_"):
        return None
    return base, rest


def _odd_underscores(name: str) -> bool:
    """A name whose underscores are not subscripts (an empty part between them): printed as written."""
    return "_" in name and _subscripted(name) is None


class _Latex(LatexPrinter):
    """sympy's LaTeX printer: names escaped or nested as subscripts, derivatives as d^n x / d t^n.

    sympy writes a symbol's or function's name as it is: ``}\\input{x}`` would leave its group.  The
    ``_print_<Type>`` methods are sympy's printer protocol: they override its defaults.
    """

    def __init__(self, settings: dict | None = None):
        super().__init__({"diff_operator": "rd", **(settings or {})})  # upright d, for integrals too

    def _deal_with_super_sub(self, string: str, style: str = "plain") -> str:
        if not _PLAIN.fullmatch(string) or _odd_underscores(string):
            return rf"\text{{{latex_escape(string)}}}"
        split = _subscripted(string)
        if split is None:
            return super()._deal_with_super_sub(string, style)
        base, subscript = split
        return f"{self._deal_with_super_sub(base, style)}_{{{self._deal_with_super_sub(subscript)}}}"

    def _print_Derivative(self, derivative):
        d = self._settings["diff_operator_latex"]
        order = derivative.derivative_count
        top = d if order == 1 else f"{d}^{{{order}}}"
        bottom = " ".join(f"{d} {self._print(v)}" + (f"^{{{n}}}" if n > 1 else "")
                          for v, n in derivative.variable_count)
        function = _differentiated_signal(derivative)
        if function is not None:
            return rf"\frac{{{top} {self._deal_with_super_sub(function)}}}{{{bottom}}}"
        return rf"\frac{{{top}}}{{{bottom}}} {self.parenthesize(derivative.expr, PRECEDENCE['Mul'])}"


def _differentiated_signal(derivative: sp.Derivative) -> str | None:
    """The name of the signal ``x(t)`` a derivative d^n x / dt^n differentiates, or None for another expression.

    The signal is written without its argument in the numerator (``d x / d t``) when the derivative
    is taken in its arguments only.
    """
    expr = derivative.expr
    if isinstance(expr, AppliedUndef) and {v for v, _ in derivative.variable_count} <= set(expr.args):
        return expr.func.__name__
    return None


class _Presentation(MathMLPresentationPrinter):
    """sympy's presentation MathML printer, with the typesetting of :func:`mathml`.

    The ``_print_<Type>`` methods are sympy's printer protocol: they override its defaults.
    """

    def _print_Symbol(self, sym, style="plain"):
        parameter = delta_parameter(sym)
        if parameter is not None:
            return self._print(sp.IndexedBase("delta")[sp.Symbol(parameter)])
        if sym.name.isdigit():  # a subscript such as the 2 of Psi_2: a number
            return self._element("mn", sym.name)
        if _odd_underscores(sym.name):
            return self._element("mi", sym.name)
        split = _subscripted(sym.name)
        if split is None:
            return super()._print_Symbol(sym, style)
        return self._element("msub", self._print(sp.Symbol(split[0])), self._print(sp.Symbol(split[1])))

    def doprint(self, expr) -> str:
        """The MathML text, every text node escaped (sympy writes them raw, to keep its entities)."""
        root = self._print(expr)
        stack = [root]
        while stack:
            node = stack.pop()
            if node.nodeType == node.TEXT_NODE:
                if node.data == "-" and node.parentNode.tagName == "mo":
                    node.data = _MINUS
                node.data = _escape_text(node.data)
            stack.extend(node.childNodes)
        return root.toxml().encode("ascii", "xmlcharrefreplace").decode()

    def _print_AppliedUndef(self, signal):
        # the arguments in a row of their own, so that "(" opens it: a browser then spaces it as a fence,
        # not as an operator between the name and the argument; and parentheses that never stretch, which
        # some math fonts (Latin Modern Math in Chromium) otherwise set loose, as "x ( t )"
        arguments = self._element("mrow", self._fence("("))
        for i, argument in enumerate(signal.args):
            if i:
                arguments.appendChild(self._element("mo", ","))
            arguments.appendChild(self._print(argument))
        arguments.appendChild(self._fence(")"))
        return self._element("mrow", self._print(sp.Symbol(signal.func.__name__)), arguments)

    def _fence(self, text: str):
        mark = self._element("mo", text)
        mark.setAttribute("stretchy", "false")
        return mark

    def _print_Derivative(self, derivative):
        order = derivative.derivative_count
        top = self._element("mrow", self._power(self._d(), order))
        bottom = self._element("mrow")
        for variable, count in derivative.variable_count:
            bottom.appendChild(self._d())
            bottom.appendChild(self._power(self._print(variable), count))
        function = _differentiated_signal(derivative)
        if function is not None:
            top.appendChild(self._print(sp.Symbol(function)))
            return self._element("mfrac", top, bottom)
        return self._element("mrow", self._element("mfrac", top, bottom),
                             self.parenthesize(derivative.expr, PRECEDENCE["Mul"]))

    def parenthesize(self, item, level, strict=False):
        """sympy's, less the parentheses it puts around a derivative in a product: ``L (di/dt)``.

        A signal's derivative is one fraction, which needs none (the LaTeX printer puts none).
        """
        if isinstance(item, sp.Derivative) and _differentiated_signal(item) is not None:
            return self._print(item)
        return super().parenthesize(item, level, strict)

    def _print_Integral(self, integral):
        """``∫_a^b f dt`` with a thin space and an upright d before each variable (sympy: U+2146, no space).

        A sum or a negative integrand is parenthesized, as the LaTeX printer does.
        """
        row = self._element("mrow")
        for variable, *bounds in reversed(integral.limits):
            sign = self._element("mo", "\u222b")
            if bounds:
                sign = self._element("msubsup" if len(bounds) == 2 else "msup", sign,
                                     *(self._print(bound) for bound in bounds))
            row.appendChild(sign)
        function = integral.function
        if function.is_Add or function.could_extract_minus_sign():
            row.appendChild(self._element("mrow", self._element("mo", "("), self._print(function),
                                          self._element("mo", ")")))
        else:
            row.appendChild(self.parenthesize(function, PRECEDENCE["Mul"], strict=True))
        for variable, *_ in reversed(integral.limits):
            space = self._element("mspace")
            space.setAttribute("width", "0.17em")
            row.appendChild(space)
            row.appendChild(self._d())
            row.appendChild(self._print(variable))
        return row

    def _d(self):
        """The upright d of a differential (ISO 80000-2)."""
        mark = self._element("mi", "d")
        mark.setAttribute("mathvariant", "normal")
        return mark

    def _power(self, base, exponent: int):
        return base if exponent == 1 else self._element("msup", base, self._print(sp.Integer(exponent)))

    def _element(self, tag: str, *children):
        """A MathML element holding ``children``: nodes, or one string as its text."""
        node = self.dom.createElement(tag)
        for child in children:
            node.appendChild(self.dom.createTextNode(child) if isinstance(child, str) else child)
        return node


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
