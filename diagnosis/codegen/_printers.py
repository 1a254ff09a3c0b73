"""Sympy expressions printed as Python (``math``) and C99 (``libm``): the common subexpressions lambdify
evaluates, under the generated code's names, with doubles printed as lambdify reads them."""

from __future__ import annotations

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.pycode import PythonCodePrinter

from ._errors import CodegenError

__all__ = ["printed"]


def _float_text(expr: sp.Float) -> str:
    """The double lambdify's printed literal parses to (sympy prints 15 significant digits), at full precision."""
    return repr(float(PythonCodePrinter().doprint(expr)))


class _Printer:
    """What both languages print alike: symbols under the names the generated code gives them (never a user's
    name), doubles as lambdify reads them, and NaN-propagating sign, Min and Max under the helpers' names."""

    SIGN = MIN = MAX = ""  # the generated code's helpers (a language's printer names them)

    def __init__(self, names: dict, **settings) -> None:
        super().__init__(settings)
        self._names = names

    def _print_Symbol(self, expr):
        if expr not in self._names:
            raise CodegenError(f"unexpected symbol {expr} in a relation")
        return self._names[expr]

    def _print_Float(self, expr):
        return _float_text(expr)

    def _print_sign(self, expr):
        return f"{self.SIGN}({self._print(expr.args[0])})"

    def _print_Min(self, expr):
        return self._fold(self.MIN, expr.args)

    def _print_Max(self, expr):
        return self._fold(self.MAX, expr.args)

    def _fold(self, name, args):
        text = self._print(args[0])
        for a in args[1:]:
            text = f"{name}({text}, {self._print(a)})"
        return text


class _PythonPrinter(_Printer, PythonCodePrinter):
    """Python with ``math``: NaN-propagating sign, Min and Max, and powers that never turn complex."""

    SIGN, MIN, MAX = "_sign", "_mn", "_mx"

    def _print_Pow(self, expr, rational=False):
        e = expr.exp
        if e.is_Integer or e in (sp.S.Half, -sp.S.Half):
            return super()._print_Pow(expr, rational=rational)
        return f"_pw({self._print(expr.base)}, {self._print(e)})"


class _CPrinter(_Printer, C99CodePrinter):
    """C99 with ``libm``: NaN-propagating sign, Min and Max, doubles printed as lambdify reads them."""

    SIGN, MIN, MAX = "bg_sign", "bg_mn", "bg_mx"


def printed(expression: sp.Expr, points: list, lang: str) -> tuple[list[tuple[str, str]], str]:
    """``([(temporary, text), ...], result text)``: the common subexpressions lambdify(cse=True) evaluates.

    The expression keeps the ARR's symbols, so that its terms print in lambdify's order (sympy orders them
    by name); the printer names point ``k`` ``p<k>`` and temporary ``k`` ``c<k>``."""
    temporaries, result = sp.cse(expression, list=False)
    names = {p: f"p{k}" for k, p in enumerate(points)}
    names.update({s: f"c{k}" for k, (s, _) in enumerate(temporaries)})
    printer = (_PythonPrinter if lang == "python" else _CPrinter)(names)
    return [(names[s], printer.doprint(e)) for s, e in temporaries], printer.doprint(result)
