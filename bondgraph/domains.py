"""Physical domains of parameters: where a parameter's value may lie.

A resistance, a capacitance or an inertia is positive: ``R = 0`` makes a simulation stall and a
threshold divide by zero, a negative capacitance stores energy it never received.  So every
parameter has a domain, one of :data:`DOMAINS`:

============  ======================  =====================================================
domain        values                  default for
============  ======================  =====================================================
``positive``  ``value > 0``           the parameter of C, I and R elements (with or without a law)
``negative``  ``value < 0``           -
``nonzero``   ``value != 0``          -
``real``      any finite value        TF, GY, MTF, MGY moduli, source values, law constants
============  ======================  =====================================================

An element says otherwise with its ``domain`` attribute (its own parameter or source value) and
``domains`` (a mapping for its law constants, e.g. ``{"M": "positive"}``).  The nominal value must
lie in the domain, and so must the whole uncertainty box ``value * (1 + [lo, hi])``.  A parameter
shared by several elements gets the intersection of their domains.

:func:`bounds` gives a domain as an open interval ``(lo, hi)``, what
:attr:`bondgraph.model.BondGraph.domains` reports for prognosis to flag an estimate outside it.  A
``nonzero`` parameter reports the open half-line of its nominal value: a value that drifts cannot
change sign without passing through zero.

Examples
--------
>>> contains("positive", 0.0), contains("nonzero", -2.0), bounds("positive", 5.0)
(False, True, (0.0, inf))
>>> bounds("nonzero", -2.0), bounds("real", 1.0)
((-inf, 0.0), (-inf, inf))
>>> default_domain("C"), default_domain("TF"), intersect("nonzero", "positive")
('positive', 'real', 'positive')
"""

from __future__ import annotations

import math

from . import elements as el
from .errors import ModelError

__all__ = ["DOMAINS", "CONSTANT_DOMAIN", "default_domain", "read_domain", "contains", "bounds", "intersect",
           "describe", "check_in_domain"]

#: The signs each domain allows (+1, 0, -1), in the order the domains are listed to a user.
_SIGNS = {"positive": frozenset({1}), "negative": frozenset({-1}), "nonzero": frozenset({1, -1}),
          "real": frozenset({1, 0, -1})}
#: Every domain name.
DOMAINS = tuple(_SIGNS)
#: The domain of a law constant (``params``) unless the element's ``domains`` says otherwise.
CONSTANT_DOMAIN = "real"
_TEXT = {"positive": "(0, inf)", "negative": "(-inf, 0)", "nonzero": "(value != 0)", "real": "(any value)"}


def default_domain(kind: str) -> str:
    """The domain of an element's own parameter or value when it gives none: positive for C, I, R.

    >>> default_domain("R"), default_domain("Se")
    ('positive', 'real')
    """
    return "positive" if kind in el.STORAGE | {"R"} else "real"


def read_domain(value: object, *, where: str) -> str:
    """Return ``value`` if it is a domain name, else raise :class:`ModelError` at ``where``.

    >>> read_domain("postive", where="R 'R1'")
    Traceback (most recent call last):
    ...
    bondgraph.errors.ModelError: R 'R1': domain 'postive' is not one of positive, negative, nonzero, real
    """
    if not isinstance(value, str) or value not in _SIGNS:
        raise ModelError(f"{where}: domain {value!r} is not one of {', '.join(DOMAINS)}")
    return value


def _sign(value: float) -> int:
    return (value > 0) - (value < 0)


def contains(domain: str, value: float) -> bool:
    """Whether the finite number ``value`` lies in ``domain``."""
    return _sign(value) in _SIGNS[domain]


def bounds(domain: str, value: float | None = None) -> tuple[float, float]:
    """The domain as an open interval ``(lo, hi)``; ``nonzero`` gives the half-line of ``value``.

    >>> bounds("negative"), bounds("nonzero", 3.0), bounds("nonzero")
    ((-inf, 0.0), (0.0, inf), (-inf, inf))
    """
    signs = _SIGNS[domain]
    if signs == _SIGNS["nonzero"] and value is not None and value != 0:
        signs = frozenset({_sign(value)})
    lo = 0.0 if signs == _SIGNS["positive"] else -math.inf
    hi = 0.0 if signs == _SIGNS["negative"] else math.inf
    return (lo, hi)


def intersect(first: str, second: str) -> str | None:
    """The domain of a parameter in both ``first`` and ``second``, or None if they share no value.

    >>> intersect("real", "negative"), intersect("positive", "negative")
    ('negative', None)
    """
    common = _SIGNS[first] & _SIGNS[second]
    return next((name for name, signs in _SIGNS.items() if signs == common), None)


def describe(domain: str) -> str:
    """A domain for a message: its name and its values.

    >>> describe("positive")
    'positive (0, inf)'
    """
    return f"{domain} {_TEXT[domain]}"


def check_in_domain(domain: str, value: float | None, box: tuple[float, float] | None, *, where: str,
                    what: str, hint: str = "") -> None:
    """Raise :class:`ModelError` unless ``value`` and its uncertainty box ``value * (1 + box)`` lie in ``domain``.

    ``what`` names the parameter (``"parameter 'R'"``) and ``hint`` is added to the message; a missing
    value (a law that does not use its parameter) is not checked.

    >>> check_in_domain("positive", 0.0, None, where="R 'R1'", what="parameter 'R1'")
    Traceback (most recent call last):
    ...
    bondgraph.errors.ModelError: R 'R1': parameter 'R1' = 0 is outside its domain positive (0, inf)
    >>> check_in_domain("real", -1.0, (-0.1, 0.1), where="TF 'TF'", what="parameter 'n'")  # any sign
    """
    if value is None:
        return
    if not contains(domain, value):
        raise ModelError(f"{where}: {what} = {value:g} is outside its domain {describe(domain)}"
                         + (f"; {hint}" if hint else ""))
    if box is None:
        return
    ends = (value * (1 + box[0]), value * (1 + box[1]))
    outside = [end for end in ends if not contains(domain, end)]
    if outside:
        raise ModelError(f"{where}: the uncertainty {box} of {what} lets it reach {min(outside, key=abs):g}, "
                         f"outside its domain {describe(domain)}" + (f"; {hint}" if hint else ""))
