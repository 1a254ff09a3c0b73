"""Constitutive laws: safe parsing of law strings and solving a law for a variable.

A law is an implicit relation equal to zero, e.g. ``f - a*sign(e)*sqrt(Abs(e))``
for a valve.  Strings are parsed with :mod:`ast` into sympy expressions; nothing
is ever passed to ``eval`` or ``sympify``.  Only arithmetic, numbers, the names
the caller allows and the functions in :data:`FUNCTIONS` are accepted.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable, Mapping

import sympy as sp

from .errors import LawError

__all__ = [
    "CONSTANTS", "FUNCTIONS", "MAX_EXPONENT", "MAX_LENGTH", "MAX_POWER_BITS", "check_finite",
    "parse_expression", "signed_power_inverse", "solve_for",
]

FUNCTIONS = {
    "sign": sp.sign,
    "Abs": sp.Abs,
    "sqrt": sp.sqrt,
    "exp": sp.exp,
    "log": sp.log,
    "sin": sp.sin,
    "cos": sp.cos,
    "tanh": sp.tanh,
    "Min": sp.Min,
    "Max": sp.Max,
}
CONSTANTS = {"pi": sp.pi}
MAX_LENGTH = 2000
MAX_EXPONENT = 100
MAX_POWER_BITS = 4096  # a power of numbers may not be larger than this many bits

_BINARY = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
}


def parse_expression(text: str, names: Mapping[str, sp.Basic], *, where: str = "law",
                     functions: Mapping[str, Callable] | None = None) -> sp.Expr:
    """Parse an arithmetic expression string into sympy without ``eval``.

    Parameters
    ----------
    text : str
        The expression, e.g. ``"f - a*sign(e)*sqrt(Abs(e))"``.
    names : mapping
        The only identifiers allowed, mapped to the sympy objects they stand for.
    where : str
        What the expression belongs to, used in error messages.
    functions : mapping, optional
        Functions allowed beside :data:`FUNCTIONS`: name -> a function of sympy arguments returning a
        sympy expression (an input signal's ``step``, say: :mod:`bondgraph.inputs`).

    Examples
    --------
    >>> import sympy as sp
    >>> e, f, a = sp.symbols("e f a")
    >>> parse_expression("f - a*sqrt(Abs(e))", {"e": e, "f": f, "a": a})
    -a*sqrt(Abs(e)) + f

    A composed model's names are paths, read as one name:

    >>> parse_expression("e - motor.R_a*f", {"e": e, "f": f, "motor.R_a": sp.Symbol("motor.R_a")})
    e - f*motor.R_a
    """
    if not isinstance(text, str):
        raise LawError(f"{where}: expected a string, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise LawError(f"{where}: expression longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise LawError(f"{where}: not a valid expression: {text!r} ({exc.msg})") from None
    allowed = {**FUNCTIONS, **(functions or {})}
    try:
        expression = _build(tree.body, names, where, allowed)
    except RecursionError:
        raise LawError(f"{where}: expression nested too deeply") from None
    check_finite(expression, where=where)
    return expression


def check_finite(expression: sp.Basic, *, where: str) -> None:
    """Raise a LawError naming ``where`` when ``expression`` holds an infinity or NaN.

    sympy turns ``e/0``, ``log(0)`` or ``0**-1`` into ``zoo`` (complex infinity), ``oo`` or ``nan``
    instead of failing; a law holding one has no numeric value and breaks causality and elimination.

    Examples
    --------
    >>> import sympy as sp
    >>> e, f = sp.symbols("e f")
    >>> check_finite(e - 2*f, where="R1 law")
    >>> check_finite(sp.log(0)*e - f, where="R1 law")
    Traceback (most recent call last):
    ...
    bondgraph.errors.LawError: R1 law: zoo*e - f is infinite or undefined (a division by zero, log(0)?)
    """
    if expression.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise LawError(f"{where}: {expression} is infinite or undefined (a division by zero, log(0)?)")


def _build(node: ast.AST, names: Mapping[str, sp.Basic], where: str, functions: Mapping[str, Callable]) -> sp.Expr:
    if isinstance(node, ast.Constant):
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise LawError(f"{where}: constant {value!r} is not a real number")
        if isinstance(value, float) and not math.isfinite(value):
            raise LawError(f"{where}: a numeric constant overflows to infinity")
        return sp.Integer(value) if isinstance(value, int) else sp.Float(value)
    if isinstance(node, (ast.Name, ast.Attribute)) and _dotted(node) is not None:
        name = _dotted(node)
        if name in names:
            return names[name]
        if name in CONSTANTS:
            return CONSTANTS[name]
        if name in functions:
            raise LawError(f"{where}: function {name!r} used without a call")
        allowed = ", ".join(sorted(names)) or "none"
        raise LawError(f"{where}: unknown name {name!r} (allowed: {allowed})")
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        operand = _build(node.operand, names, where, functions)
        return -operand if isinstance(node.op, ast.USub) else operand
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        left, right = _build(node.left, names, where, functions), _build(node.right, names, where, functions)
        if isinstance(node.op, ast.Div) and right.is_zero:  # sympy would give zoo, which no analysis can use
            raise LawError(f"{where}: division by zero in {ast.unparse(node)!r}")
        return _BINARY[type(node.op)](left, right)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
        base = _build(node.left, names, where, functions)
        exponent = _build(node.right, names, where, functions)
        # Guard against 9**9**9 or ((9**99)**99)**99 that sympy would expand exactly.
        if exponent.is_Number and abs(float(exponent)) > MAX_EXPONENT:
            raise LawError(f"{where}: exponent {exponent} exceeds {MAX_EXPONENT} in absolute value")
        if base.is_Number and exponent.is_Number and _bits(base) * abs(float(exponent)) > MAX_POWER_BITS:
            raise LawError(f"{where}: the power {ast.unparse(node)} is too large a number")
        return base**exponent
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name) or node.func.id not in functions:
            name = node.func.id if isinstance(node.func, ast.Name) else ast.unparse(node.func)
            raise LawError(f"{where}: call to {name!r} not allowed (allowed: {', '.join(functions)})")
        if node.keywords:
            raise LawError(f"{where}: keyword arguments not allowed in {node.func.id}()")
        args = [_build(arg, names, where, functions) for arg in node.args]
        if not args:
            raise LawError(f"{where}: {node.func.id}() needs an argument")
        try:
            return functions[node.func.id](*args)
        except (TypeError, ValueError) as exc:
            raise LawError(f"{where}: {ast.unparse(node)}: {exc}") from None
    raise LawError(f"{where}: {type(node).__name__} not allowed in {ast.unparse(node)!r}")


def _dotted(node: ast.AST) -> str | None:
    """The name ``a.b.c`` an attribute chain spells (a composed model's path, ``motor.R_a``), else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    return ".".join([node.id, *reversed(parts)])


def _bits(number: sp.Number) -> int:
    """Size in bits of a sympy number (numerator or denominator of a rational)."""
    if number.is_Rational:
        return max(abs(number.p).bit_length(), number.q.bit_length(), 1)
    return 64


def solve_for(law: sp.Expr, variable: sp.Symbol, *, where: str) -> sp.Expr:
    """Solve the implicit law ``law = 0`` for ``variable``.

    Linear dependence is solved directly; otherwise sympy's ``solve`` must find
    exactly one real-valued branch.  Raises :class:`LawError` naming ``where``
    when there is no explicit inverse, rather than guessing a root.

    Examples
    --------
    >>> import sympy as sp
    >>> e, f, R = sp.symbols("e f R")
    >>> solve_for(e - R*f, f, where="R1")
    e/R
    """
    coefficient = sp.diff(law, variable)
    if coefficient != 0 and not coefficient.has(variable):
        return -law.xreplace({variable: 0}) / coefficient
    try:
        solutions = sp.solve(law, variable, dict=False)
    except (NotImplementedError, ValueError):
        solutions = []
    if len(solutions) != 1:
        raise LawError(
            f"{where}: law {law} = 0 has no unique explicit solution for {variable} "
            f"({len(solutions)} found); causality needs it in this form"
        )
    return solutions[0]


def signed_power_inverse(law: sp.Expr, variable: sp.Basic) -> sp.Expr | None:
    """Solve ``law = 0`` for ``variable`` when it enters only as ``c sign(x) |x|^k`` (k > 0), else None.

    Such a law (an orifice, ``f = a sign(e) sqrt(|e|)``) is strictly monotonic in ``x``, so its inverse
    is unique: with ``w`` the value of ``sign(x) |x|^k`` the law gives, ``x = sign(w) |w|^(1/k)``.
    sympy's ``solve`` gives up on the sign and the absolute value.

    Examples
    --------
    >>> import sympy as sp
    >>> e, f, a = sp.symbols("e f a")
    >>> signed_power_inverse(f - a*sp.sign(e)*sp.sqrt(sp.Abs(e)), e)
    f*Abs(f/a)/a
    >>> signed_power_inverse(f - a*e**2, e) is None
    True
    """
    x = variable
    if not law.has(sp.sign(x)):
        return None
    shape = sp.Wild("k", exclude=[x])
    coefficient, power = sp.S.Zero, None
    rest = []
    # only the terms holding x are expanded: the rest may be a long expression of known signals
    terms = [t for term in sp.Add.make_args(law)
             for t in (sp.Add.make_args(sp.expand(term)) if term.has(x) else [term])]
    for term in terms:
        if not term.has(x):
            rest.append(term)
            continue
        factors = sp.Mul.make_args(term)
        sign = [f for f in factors if f == sp.sign(x)]
        roots = [f.match(sp.Abs(x) ** shape) for f in factors if f.has(x) and f != sp.sign(x)]
        others = [f for f in factors if not f.has(x)]
        if len(sign) != 1 or len(roots) != 1 or roots[0] is None:
            return None
        k = roots[0][shape]
        if not (k.is_number and k.is_positive) or (power is not None and k != power):
            return None
        power = k
        coefficient += sp.Mul(*others)
    if power is None or coefficient == 0:
        return None
    w = -sp.Add(*rest) / coefficient
    return sp.sign(w) * sp.Abs(w) ** (1 / power) if power != sp.Rational(1, 2) else w * sp.Abs(w)
