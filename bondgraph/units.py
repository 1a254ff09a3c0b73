"""Units of parameters and signals, and the dimensional check of a bond graph.

A unit is written in coherent SI, the units a model's values are given in: the base units ``m kg s A K
mol cd``, the named derived units ``N Pa J W C V F Ohm S Wb T H Hz`` and the angles ``rad sr``, joined by
``*`` (or ``.``) and ``/``, with powers ``^n`` (``^-1``, ``^(1/2)``) and parentheses, e.g. ``"N*m*s/rad"``,
``"m^3/s"``, ``"Pa*s/m^3"``; ``"1"`` is a pure number.  Prefixed units (``mH``, ``kPa``) are refused: a
value in the model is a number of SI units, and a prefix would make it lie.  The text is parsed, never
evaluated.

An angle is a pure number for the check (``N*m*s/rad`` and ``N*m*s`` are the same dimension) but is kept in
the text, so that a friction reads ``N*m*s/rad`` and a speed ``rad/s``.

:mod:`bondgraph.dimensions` checks a model's units with these.

Examples
--------
>>> torque_per_speed = parse_unit("N*m*s/rad")
>>> str(torque_per_speed), torque_per_speed.same_dimension(parse_unit("kg*m^2/s"))
('N*m*s/rad', True)
>>> str(parse_unit("V") / parse_unit("A")), parse_unit("V/A").same_dimension(parse_unit("Ohm"))
('V/A', True)
>>> parse_unit("mH", where="I 'L'")
Traceback (most recent call last):
...
bondgraph.errors.ModelError: I 'L': unit 'mH': 'mH' is not a coherent SI unit (no prefixes: give the value in H, ...)
"""

from __future__ import annotations

import functools
import re
from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction

import sympy as sp

from .errors import ModelError

__all__ = ["ATOMS", "BASE", "DIMENSIONLESS", "SECOND", "TIME", "Unit", "UnitError", "dimension_of", "parse_unit"]

#: The SI base dimensions, in the order of :attr:`Unit.dimension`.
BASE = ("m", "kg", "s", "A", "K", "mol", "cd")


def _dims(**exponents: int) -> tuple[Fraction, ...]:
    return tuple(Fraction(exponents.get(b, 0)) for b in BASE)


#: Each unit symbol a unit text may use, and its dimension in :data:`BASE`.
ATOMS = {
    "m": _dims(m=1), "kg": _dims(kg=1), "s": _dims(s=1), "A": _dims(A=1), "K": _dims(K=1), "mol": _dims(mol=1),
    "cd": _dims(cd=1), "rad": _dims(), "sr": _dims(), "Hz": _dims(s=-1),
    "N": _dims(kg=1, m=1, s=-2), "Pa": _dims(kg=1, m=-1, s=-2), "J": _dims(kg=1, m=2, s=-2),
    "W": _dims(kg=1, m=2, s=-3), "C": _dims(s=1, A=1), "V": _dims(kg=1, m=2, s=-3, A=-1),
    "F": _dims(kg=-1, m=-2, s=4, A=2), "Ohm": _dims(kg=1, m=2, s=-3, A=-2), "S": _dims(kg=-1, m=-2, s=3, A=2),
    "Wb": _dims(kg=1, m=2, s=-2, A=-1), "T": _dims(kg=1, s=-2, A=-1), "H": _dims(kg=1, m=2, s=-2, A=-2),
}
_ALIASES = {"Ω": "Ohm", "ohm": "Ohm"}
_PREFIXES = {"k": "k", "M": "M", "G": "G", "m": "m", "u": "u", "µ": "µ", "μ": "μ", "n": "n", "p": "p", "c": "c",
             "d": "d"}


@dataclass(frozen=True)
class Unit:
    """A unit: a product of unit symbols with rational powers (what is shown) and its SI dimension (what is
    checked).

    ``Unit`` values multiply, divide and take rational powers; two units are interchangeable when
    :meth:`same_dimension` holds (``V/A`` and ``Ohm``; ``rad/s`` and ``1/s``).  Build one with
    :func:`parse_unit`.

    >>> speed = parse_unit("rad/s")
    >>> str(speed * parse_unit("s")), str(speed ** 2), str(DIMENSIONLESS)
    ('rad', 'rad^2/s^2', '1')
    """

    factors: tuple[tuple[str, Fraction], ...] = ()  # (symbol, power), sorted by symbol, no zero power

    @staticmethod
    def of(factors: Mapping[str, Fraction | int]) -> Unit:
        """The unit of ``{symbol: power}``."""
        return Unit(tuple(sorted((s, Fraction(p)) for s, p in factors.items() if p != 0)))

    @property
    def dimension(self) -> tuple[Fraction, ...]:
        """The exponents of the SI base dimensions :data:`BASE` (angles count as pure numbers)."""
        return _dimension(self.factors)

    def same_dimension(self, other: Unit) -> bool:
        """Whether ``self`` and ``other`` measure the same kind of quantity (and may be equated)."""
        return _dimension(self.factors) == _dimension(other.factors)

    def __mul__(self, other: Unit) -> Unit:
        return _combine(self.factors, other.factors, 1)

    def __truediv__(self, other: Unit) -> Unit:
        return _combine(self.factors, other.factors, -1)

    def __pow__(self, power: Fraction | int) -> Unit:
        return Unit.of({s: p * Fraction(power) for s, p in self.factors})

    def __str__(self) -> str:
        above = [_power_text(s, p) for s, p in self._ordered() if p > 0]
        below = [_power_text(s, -p) for s, p in self._ordered() if p < 0]
        top = "*".join(above) or "1"
        if not below:
            return top
        bottom = below[0] if len(below) == 1 else "(" + "*".join(below) + ")"
        return f"{top}/{bottom}"

    def _ordered(self) -> list[tuple[str, Fraction]]:
        """Named derived units first, then base units, angles last (``N*m*s/rad``, not ``m*N*s/rad``)."""
        rank = {s: i for i, s in enumerate(("N", "Pa", "J", "W", "V", "A", "Ohm", "S", "F", "H", "C", "Wb", "T",
                                             "kg", "m", "s", "K", "mol", "cd", "Hz", "rad", "sr"))}
        return sorted(self.factors, key=lambda f: rank.get(f[0], len(rank)))


# A model's check multiplies the same few units over and over (its bonds carry a handful of kinds): caching the
# Fraction arithmetic makes it cheap enough to run on every structure() call.
@functools.lru_cache(maxsize=4096)
def _dimension(factors: tuple) -> tuple[Fraction, ...]:
    total = [Fraction(0)] * len(BASE)
    for symbol, power in factors:
        total = [a + power * b for a, b in zip(total, ATOMS[symbol])]
    return tuple(total)


@functools.lru_cache(maxsize=4096)
def _combine(left: tuple, right: tuple, sign: int) -> Unit:
    powers = dict(left)
    for symbol, power in right:
        powers[symbol] = powers.get(symbol, 0) + sign * power
    return Unit.of(powers)


def _power_text(symbol: str, power: Fraction) -> str:
    if power == 1:
        return symbol
    return f"{symbol}^{power}" if power.denominator == 1 else f"{symbol}^({power})"


#: The unit of a pure number.
DIMENSIONLESS = Unit()
#: The second, the unit of time: the factor between a flow and a displacement, an effort and a momentum.
SECOND = Unit.of({"s": 1})
#: The time symbol of the model contract (``bondgraph.structure.T``), in seconds.
TIME = sp.Symbol("t")

_TOKEN = re.compile(r"\s*(?:(?P<number>\d+(?:\.\d+)?)|(?P<name>[A-Za-zΩµμ]+)|(?P<op>\*\*|[*./^()\-+]))")


@functools.lru_cache(maxsize=1024)
def _parse(text: str) -> Unit:
    """The unit of ``text``; ValueError with the reason."""
    tokens = _tokens(text)
    unit, position = _product(tokens, 0)
    if position != len(tokens):
        raise ValueError(f"unexpected {tokens[position][1]!r}")
    return unit


def parse_unit(text: object, *, where: str = "unit") -> Unit:
    """Read a unit text (see the module's notes); raise :class:`~bondgraph.errors.ModelError` naming ``where``.

    >>> str(parse_unit("kg*m^2")), str(parse_unit("m^3 / s")), str(parse_unit("1"))
    ('kg*m^2', 'm^3/s', '1')
    >>> parse_unit("N*m/", where="R 'b'")
    Traceback (most recent call last):
    ...
    bondgraph.errors.ModelError: R 'b': unit 'N*m/': a unit symbol is missing at the end
    """
    if not isinstance(text, str) or not text.strip():
        raise ModelError(f"{where}: unit {text!r} is not a unit text such as 'N*m' or 'm^3/s'")
    try:
        return _parse(text.strip())
    except ValueError as exc:
        raise ModelError(f"{where}: unit {text!r}: {exc}") from None


def _tokens(text: str) -> list[tuple[str, str]]:
    tokens, position = [], 0
    while position < len(text):
        match = _TOKEN.match(text, position)
        if match is None:
            raise ValueError(f"{text[position]!r} is not part of a unit")
        kind = match.lastgroup
        value = match.group(kind)
        tokens.append((kind, "^" if value == "**" else value))
        position = match.end()
        while position < len(text) and text[position].isspace():
            position += 1
    return tokens


def _product(tokens: list, position: int) -> tuple[Unit, int]:
    """``factor (('*' | '.' | '/') factor)*``, left to right."""
    unit, position = _factor(tokens, position)
    while position < len(tokens) and tokens[position][1] in ("*", ".", "/"):
        operator = tokens[position][1]
        right, position = _factor(tokens, position + 1)
        unit = unit / right if operator == "/" else unit * right
    return unit, position


def _factor(tokens: list, position: int) -> tuple[Unit, int]:
    """``(symbol | '1' | '(' product ')') ['^' exponent]``."""
    if position >= len(tokens):
        raise ValueError("a unit symbol is missing at the end")
    kind, value = tokens[position]
    if value == "(":
        unit, position = _product(tokens, position + 1)
        if position >= len(tokens) or tokens[position][1] != ")":
            raise ValueError("a ')' is missing")
        position += 1
    elif kind == "number" and value == "1":
        unit, position = DIMENSIONLESS, position + 1
    elif kind == "name":
        unit, position = Unit.of({_symbol(value): 1}), position + 1
    else:
        raise ValueError(f"unexpected {value!r}")
    if position < len(tokens) and tokens[position][1] == "^":
        power, position = _exponent(tokens, position + 1)
        unit = unit ** power
    return unit, position


def _exponent(tokens: list, position: int) -> tuple[Fraction, int]:
    """``['-'] integer`` or ``'(' ['-'] integer '/' integer ')'``."""
    text = []
    closing = position < len(tokens) and tokens[position][1] == "("
    position += closing
    while position < len(tokens) and (tokens[position][0] == "number" or tokens[position][1] in "-+/"):
        if tokens[position][1] == "/" and not closing:
            break
        text.append(tokens[position][1])
        position += 1
    if closing:
        if position >= len(tokens) or tokens[position][1] != ")":
            raise ValueError("a ')' is missing after the exponent")
        position += 1
    try:
        return Fraction("".join(text)), position
    except (ValueError, ZeroDivisionError):
        raise ValueError(f"exponent {''.join(text)!r} is not a whole number or a fraction like (1/2)") from None


def _symbol(name: str) -> str:
    name = _ALIASES.get(name, name)
    if name in ATOMS:
        return name
    if len(name) > 1 and name[0] in _PREFIXES and name[1:] in ATOMS | _ALIASES.keys():
        raise ValueError(f"{name!r} is not a coherent SI unit (no prefixes: give the value in "
                         f"{_ALIASES.get(name[1:], name[1:])}, ...)")
    if name in ("g", "L", "l", "min", "h", "bar", "degC", "rpm"):
        raise ValueError(f"{name!r} is not a coherent SI unit (give the value in SI: kg, m^3, s, Pa, K, rad/s)")
    raise ValueError(f"unknown unit symbol {name!r} (known: {', '.join(ATOMS)})")


# ---------------------------------------------------------------------------------------- expressions

class UnitError(ModelError):
    """An expression whose units do not combine; the message says where."""


def dimension_of(expression: sp.Basic, units: Mapping[sp.Basic, Unit]) -> Unit:
    """The unit of a sympy expression whose symbols (and signal functions ``name(t)``) have ``units``.

    The time symbol ``t`` is in seconds; a derivative ``d/dt`` divides by it and an integral over ``t``
    multiplies by it.  Sums need terms of one dimension; the functions (``exp``, ``log``, ``sin``,
    ``tanh``, ...) need a pure number; ``Abs``, ``Min`` and ``Max`` keep their argument's unit, ``sign``
    gives a pure number.  Raises :class:`KeyError` for a name without a unit and :class:`UnitError` for
    units that do not combine.

    >>> e, f, k = sp.symbols("e f k")
    >>> units = {e: parse_unit("Pa"), f: parse_unit("m^3/s"), k: parse_unit("Pa*s^2/m^6")}
    >>> str(dimension_of(e - k * f * sp.Abs(f), units))
    'Pa'
    >>> dimension_of(e - k * f, units)
    Traceback (most recent call last):
    ...
    bondgraph.units.UnitError: the terms of e - f*k have units Pa and Pa*s/m^3
    """
    if expression in units:
        return units[expression]
    if expression == TIME:
        return SECOND
    if expression.is_Number or expression.is_NumberSymbol:
        return DIMENSIONLESS
    if isinstance(expression, sp.Symbol):
        raise KeyError(str(expression))
    if isinstance(expression, sp.Add) or isinstance(expression, (sp.Min, sp.Max)):
        terms = [dimension_of(a, units) for a in expression.args]
        if any(not terms[0].same_dimension(u) for u in terms[1:]):
            shown = " and ".join(dict.fromkeys(str(u) for u in terms))
            raise UnitError(f"the terms of {expression} have units {shown}")
        return min(terms, key=lambda u: len(str(u)))  # one dimension: shown in its simplest spelling (N*m/s)
    if isinstance(expression, sp.Mul):
        result = DIMENSIONLESS
        for factor in expression.args:
            result = result * dimension_of(factor, units)
        return result
    if isinstance(expression, sp.Pow):
        base, power = expression.args
        if power.is_Rational:
            return dimension_of(base, units) ** Fraction(int(power.p), int(power.q))
        _pure(base, units)
        _pure(power, units)
        return DIMENSIONLESS
    if isinstance(expression, sp.Derivative):  # d^n x / dt^n: x's unit over the variables' (time: s)
        result = dimension_of(expression.expr, units)
        for variable, count in expression.variable_count:
            result = result / dimension_of(variable, units) ** int(count)
        return result
    if isinstance(expression, sp.Integral):    # the integral over t: the integrand's unit times s
        result = dimension_of(expression.function, units)
        for limits in expression.limits:
            result = result * dimension_of(limits[0], units)
        return result
    if isinstance(expression, sp.Abs):
        return dimension_of(expression.args[0], units)
    if isinstance(expression, sp.sign):
        dimension_of(expression.args[0], units)
        return DIMENSIONLESS
    if isinstance(expression, sp.Function) or isinstance(expression, sp.Piecewise):
        for argument in expression.args:
            _pure(argument, units)
        return DIMENSIONLESS
    raise UnitError(f"cannot tell the unit of {expression}")


def _pure(expression: sp.Basic, units: Mapping[sp.Basic, Unit]) -> None:
    unit = dimension_of(expression, units)
    if not unit.same_dimension(DIMENSIONLESS):
        raise UnitError(f"{expression} must be a pure number, its unit is {unit}")
