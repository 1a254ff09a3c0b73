"""Errors raised by the bond graph core.  Each names the node, bond or signal at fault."""

from __future__ import annotations


class ModelError(ValueError):
    """The bond graph violates the model contract (kind, bonds, values, laws, names)."""


class LawError(ModelError):
    """A constitutive law or modulus that cannot be parsed, is unsafe, or cannot be inverted."""


class CausalityError(ValueError):
    """Equations were requested for a causal assignment that cannot give them."""


class EquationError(ValueError):
    """State or output equations that cannot be derived (e.g. an unsolvable algebraic loop)."""


class SimulationError(ValueError):
    """Bad simulation input: missing signal, unknown parameter or state, wrong shape."""
