"""What a name in a model may look like: node ids, bond labels, parameters, constants and signals.

A model file is data, and its names travel far: into sympy symbols, equations, reports (HTML,
MathML, LaTeX), drawings (SVG, TikZ) and the command line (``--fail P=V``).  So a name is a name,
never markup: ASCII letters, digits and underscores, at most :data:`MAX_NAME_LENGTH` characters.
A model composed of sub-models (:mod:`bondgraph.composition`) names what it took from a part by its
path, the part's name and the element's joined by dots (:data:`PATH_SEPARATOR`): ``motor.R_a``.

* Node ids and bond labels match :data:`NODE_ID_PATTERN` (``1_2``, ``0_s`` and ``belt.0_s`` are fine;
  an integer id prints as its digits).
* Parameter, law-constant and signal names match :data:`NAME_PATTERN`, a Python identifier or a
  dotted path of them, because they are written in expressions (laws, moduli) and in ``--fail P=V``.  A parametric node
  whose id is not an identifier (``1R``) names its parameter with ``param``.

The checks run where :class:`~bondgraph.model.BondGraph` reads its elements and bonds, so JSON
files, Python model files and the DSL obey the same rules.  The model's display name is free text:
the writers escape it.

Examples
--------
>>> check_node_id("1_e", where="node '1_e'")
'1_e'
>>> check_name("omega_m", where="Df 'omega_m'", what="signal")
'omega_m'
>>> check_name("1R", where="R '1R'", what="parameter", hint="give it a 'param' that is one")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
bondgraph.errors.ModelError: R '1R': parameter name '1R' is not an identifier (...); give it a 'param' that is one
"""

from __future__ import annotations

import re
from collections.abc import Hashable

from .errors import ModelError

__all__ = ["MAX_NAME_LENGTH", "NODE_ID_PATTERN", "NAME_PATTERN", "PATH_SEPARATOR", "is_node_id", "is_name",
           "check_node_id", "check_name"]

#: The longest name, node id or label (characters).
MAX_NAME_LENGTH = 64
#: Joins a part's name and a name inside it in a composed model: ``motor.R_a``.
PATH_SEPARATOR = "."
#: Node ids and bond labels: ASCII letters, digits and underscores (integers are accepted as their digits),
#: or a path of them joined by dots.
NODE_ID_PATTERN = r"[A-Za-z0-9_]+(?:\.[A-Za-z0-9_]+)*"
#: Parameter, law-constant and signal names: ASCII identifiers, or a path of them joined by dots, since they
#: appear in expressions (where ``motor.R_a`` reads as one name).
NAME_PATTERN = r"[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*"

_NODE_ID = re.compile(NODE_ID_PATTERN)
_NAME = re.compile(NAME_PATTERN)


def _text(value: Hashable) -> str | None:
    """The printed form of an id: a str as it is, a non-negative int as its digits, anything else None."""
    if isinstance(value, bool):  # True is an int to Python, not an id to us
        return None
    if isinstance(value, int):
        return str(value) if value >= 0 else None
    return value if isinstance(value, str) else None


def is_node_id(value: Hashable) -> bool:
    """Whether ``value`` may be a node id or bond label (:data:`NODE_ID_PATTERN`, at most 64 characters).

    >>> is_node_id("0_s"), is_node_id(12), is_node_id("belt.0_s"), is_node_id("<img>"), is_node_id("a.")
    (True, True, True, False, False)
    >>> is_node_id("a" * 65)
    False
    """
    text = _text(value)
    return text is not None and len(text) <= MAX_NAME_LENGTH and _NODE_ID.fullmatch(text) is not None


def is_name(value: object) -> bool:
    """Whether ``value`` may name a parameter, law constant or signal (:data:`NAME_PATTERN`, at most 64).

    >>> is_name("k_belt"), is_name("motor.R_a"), is_name("1R"), is_name("motor.1R"), is_name("é"), is_name(3)
    (True, True, False, False, False, False)
    """
    return isinstance(value, str) and len(value) <= MAX_NAME_LENGTH and _NAME.fullmatch(value) is not None


def _shown(value: object) -> str:
    """The offending value in a message: its repr, shortened so a megabyte id gives a one-line error."""
    text = repr(value)
    return text if len(text) <= 80 else f"{text[:60]}...' ({len(str(value))} characters)"


def check_node_id(value: Hashable, *, where: str = "", what: str = "node id") -> Hashable:
    """Return ``value`` if it is a valid node id or bond label, else raise :class:`ModelError` at ``where``.

    ``what`` says which it is (``"node id"``, ``"label"``); the message starts with ``where`` if given.

    >>> check_node_id("J<1>", where="node 'J<1>'")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    bondgraph.errors.ModelError: node 'J<1>': node id 'J<1>' is not a name (ASCII letters, digits and _, ...)
    """
    if not is_node_id(value):
        raise ModelError(f"{where + ': ' if where else ''}{what} {_shown(value)} is not a name (ASCII letters, digits "
                         f"and _, parts of a path joined by dots, at most {MAX_NAME_LENGTH} characters)")
    return value


def check_name(value: object, *, where: str, what: str, hint: str = "") -> str:
    """Return ``value`` if it is a valid parameter, constant or signal name, else raise :class:`ModelError`.

    ``what`` says which name it is (``"parameter"``, ``"constant"``, ``"signal"``); ``hint`` is added
    to the message, e.g. how to give the name explicitly.

    >>> check_name("u-1", where="Se 'u'", what="signal")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    bondgraph.errors.ModelError: Se 'u': signal name 'u-1' is not an identifier (ASCII letters, digits and _, ...)
    """
    if not is_name(value):
        raise ModelError(f"{where}: {what} name {_shown(value)} is not an identifier (ASCII letters, digits and _, "
                         f"not starting with a digit; parts of a path joined by dots; at most {MAX_NAME_LENGTH} "
                         "characters)" + (f"; {hint}" if hint else ""))
    return value
