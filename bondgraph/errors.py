"""Errors raised by the toolkit on bad input.  Each names the node, bond, signal, file or option at fault.

:class:`PHMError` is the base of them all (``bondgraph``, ``diagnosis`` and the ``bgphm`` command
line), and each is also a :class:`ValueError`.

>>> from bondgraph import BondGraph
>>> try:
...     BondGraph().add("X", "Q")
... except PHMError as error:
...     print(type(error).__name__, "-", error)
ModelError - node 'X': unknown kind 'Q' (expected one of 0, 1, C, De, Df, GY, I, MGY, MSe, MSf, MTF, R, Se, Sf, TF)
"""

from __future__ import annotations

import re
from collections.abc import Callable

__all__ = [
    "CausalityError", "EquationError", "FmuError", "LawError", "ModelError", "PHMError", "PHMWarning", "SettingError",
    "SimulationError",
]


class PHMError(Exception):
    """Base of every error the toolkit raises on bad input, so that a user can catch them all.

    Bad input is a model, a law, a record, a model file or a command line that the toolkit cannot
    use, or equations or a simulation that cannot be had from it.  A wrong argument to a function
    (an unknown option name, say) is a plain :class:`ValueError` or :class:`KeyError`.

    Examples
    --------
    >>> import numpy as np
    >>> from diagnosis import RecordError, as_record
    >>> issubclass(RecordError, PHMError), issubclass(ModelError, PHMError)
    (True, True)
    >>> try:
    ...     as_record({"t": np.array([0.0, 1.0])}, ["omega"])
    ... except PHMError as error:
    ...     print(error)
    record: missing column(s) ['omega']; columns present: ['t']
    """


class PHMWarning(UserWarning):
    """Base of every warning the toolkit issues, so that a user can filter them all at once.

    Each warning of the toolkit derives from it (and keeps its own second base, ``UserWarning`` or
    ``RuntimeWarning``): ARR derivation, records, interval evaluation, filters, identification,
    sampling and metrics.

    Examples
    --------
    >>> import warnings
    >>> from prognosis.statespace import FilterWarning
    >>> issubclass(FilterWarning, PHMWarning), issubclass(FilterWarning, RuntimeWarning)
    (True, True)
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", PHMWarning)   # silence the toolkit, not numpy
    ...     warnings.warn("covariance repaired", FilterWarning)
    """


class ModelError(PHMError, ValueError):
    """The bond graph violates the model contract (kind, bonds, values, laws, names)."""


class LawError(ModelError):
    """A constitutive law or modulus that cannot be parsed, is unsafe, or cannot be inverted."""


class CausalityError(PHMError, ValueError):
    """Equations were requested for a causal assignment that cannot give them."""


class EquationError(PHMError, ValueError):
    """State or output equations that cannot be derived (e.g. an unsolvable algebraic loop)."""


class SimulationError(PHMError, ValueError):
    """Bad simulation input: missing signal, unknown parameter or state, wrong shape."""


class FmuError(PHMError, ValueError):
    """An FMU that cannot be written (:mod:`bondgraph.fmu_export`) or read and run
    (:mod:`bondgraph.fmu_plant`): a path that is no FMU, a missing variable, a missing C compiler."""


class SettingError(PHMError, ValueError):
    """A setting that does not fit the data (a calibration stretch holding a fault, a filter step longer
    than the record); ``setting`` is its Python name.

    The message names the setting where ``{setting}`` stands in ``template`` (and another setting
    where ``{setting:name}`` stands), so that a command line can name its own options instead
    (:meth:`naming`).

    >>> error = SettingError("pairs", "{setting}: needs {setting:method} 'resample-move'")
    >>> print(error)
    pairs: needs method 'resample-move'
    >>> print(error.naming(lambda name: {"method": "--filter"}.get(name, "--" + name)))
    --pairs: needs --filter 'resample-move'
    """

    def __init__(self, setting: str, template: str):
        self.setting, self.template = setting, template
        super().__init__(self.naming(str))

    def naming(self, name: Callable[[str], str]) -> str:
        """The message with ``name(setting)`` for each setting it names (a value's braces stay as they are)."""
        return re.sub(r"\{setting(?::(\w+))?\}", lambda m: name(m.group(1) or self.setting), self.template)

    def within(self, prefix: str) -> "SettingError":
        """The same error with ``prefix`` before its message (e.g. the asset whose record it concerns)."""
        return SettingError(self.setting, prefix + self.template)
