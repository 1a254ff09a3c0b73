"""Input signals written as data: an expression of the time ``t``, or a table of samples.

A model's input (the signal of an ``Se`` or ``Sf`` source) is a number, a function of time or a
controller (:func:`bondgraph.simulate`).  Two kinds of function of time can be written down as data,
in a JSON model file (``graph.inputs``) or on the command line (``bgphm simulate --input``, ``--inputs``):

* :class:`InputExpression`: the text of an expression of ``t``, parsed by
  :func:`bondgraph.laws.parse_expression` (numbers, ``+ - * / **``, ``pi``, the law functions
  ``sign, Abs, sqrt, exp, log, sin, cos, tanh, Min, Max`` and ``step``), never evaluated: ``12*step(t - 0.5)``
  is a 12 V step at 0.5 s, ``5 + sin(7*t)`` a sine around 5, ``Min(24*t, 12)`` a ramp that levels off;
* :class:`TabulatedInput`: samples ``(t_k, u_k)``, linearly interpolated between them and held at
  the first and the last value outside them.

Both are callables ``u(t)`` of a time or an array of times, as the simulator calls an input.

>>> import numpy as np
>>> u = InputExpression("12*step(t - 0.5)")
>>> u(0.25), u(0.5), u(np.array([0.0, 1.0])).tolist()
(0.0, 12.0, [0.0, 12.0])
>>> TabulatedInput([0.0, 1.0, 2.0], [0.0, 10.0, 4.0])(np.array([-1.0, 0.5, 1.5, 9.0])).tolist()
[0.0, 5.0, 7.0, 4.0]
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .errors import SimulationError
from .laws import parse_expression
from .structure import T

__all__ = ["INPUT_FUNCTIONS", "InputExpression", "TabulatedInput"]

#: The functions an input expression may call beside the laws' (:data:`bondgraph.laws.FUNCTIONS`):
#: ``step(x)`` is 0 for ``x < 0`` and 1 from ``x = 0`` on, so that ``12*step(t - 0.5)`` is 12 from t = 0.5 s.
INPUT_FUNCTIONS = {"step": lambda x: sp.Heaviside(x, 1)}


class InputExpression:
    """An input signal given as the text of an expression of the time ``t`` (see the module docstring).

    The text is parsed by :func:`~bondgraph.laws.parse_expression` with the single name ``t`` and the
    functions of :data:`INPUT_FUNCTIONS`, then compiled by sympy's ``lambdify`` from the expression
    that parser built: the text itself is never evaluated.

    Parameters
    ----------
    text : str
        The expression, e.g. ``"12*step(t - 0.5)"``.
    where : str
        What the input is, for error messages (the file and the input's name, say).

    Attributes
    ----------
    text : str
        The expression as given (stripped); :func:`bondgraph.io.to_json` writes it back.
    expression : sympy.Expr

    Raises
    ------
    LawError
        For a text that is not a safe expression of ``t``, starting with ``where``.
    SimulationError
        When called at a time where the value is not finite (``1/t`` at 0), naming ``where`` and the time.

    Examples
    --------
    >>> u = InputExpression("5 + sin(7*t)", where="V")
    >>> u.expression, round(u(0.1), 6)
    (sin(7*t) + 5, 5.644218)
    >>> InputExpression("__import__('os')", where="V")
    Traceback (most recent call last):
    ...
    bondgraph.errors.LawError: V: call to '__import__' not allowed (allowed: sign, Abs, ..., Max, step)
    """

    def __init__(self, text: str, *, where: str = "input"):
        self.where = where
        self.expression = parse_expression(text, {"t": T}, where=where, functions=INPUT_FUNCTIONS)
        self.text = text.strip()
        self._function = sp.lambdify(T, self.expression, modules="numpy")

    def __call__(self, t):
        """The value at a time (a float) or at an array of times (an array of their shape)."""
        times = np.asarray(t, float)
        with np.errstate(all="ignore"):  # a value that is not finite is an error below, not a warning
            # a constant expression gives one number whatever the times: spread over them
            value = np.broadcast_to(np.asarray(self._function(times), float), times.shape)
        if not np.all(np.isfinite(value)):
            at = float(times.flat[int(np.argmin(np.isfinite(value).ravel()))])
            raise SimulationError(f"{self.where}: {self.text} is not finite at t = {at:g}")
        return float(value) if value.ndim == 0 else value.copy()

    def __reduce__(self):  # compiled anew from the text in another process
        return (_expression, (self.text, self.where))

    def __eq__(self, other) -> bool:
        return isinstance(other, InputExpression) and other.expression == self.expression

    def __hash__(self) -> int:
        return hash(self.expression)

    def __repr__(self) -> str:
        return f"InputExpression({self.text!r})"

    def __str__(self) -> str:
        return self.text


def _expression(text: str, where: str) -> InputExpression:
    return InputExpression(text, where=where)


class TabulatedInput:
    """An input signal given by samples ``(t_k, u_k)``: linear between them, held at the first and last outside.

    Parameters
    ----------
    t : array_like
        Finite, strictly increasing times (at least 2).
    values : array_like
        The input's value at each of them, finite (a gap has no value to give the model).
    where : str
        What the input is, for error messages (the file and the column, say).

    Raises
    ------
    SimulationError
        Naming ``where``: arrays of other shapes, fewer than 2 samples, a time that is not finite or
        does not increase, a value that is not finite.

    Examples
    --------
    >>> u = TabulatedInput([0.0, 1.0], [2.0, 4.0], where="inputs.csv: column 'U'")
    >>> u(0.25), u(5.0)
    (2.5, 4.0)
    >>> TabulatedInput([0.0, 1.0, 2.0], [1.0, float("nan"), 3.0], where="inputs.csv: column 'U'")
    Traceback (most recent call last):
    ...
    bondgraph.errors.SimulationError: inputs.csv: column 'U': no value at t = 1 (a gap); an input needs one ...
    """

    def __init__(self, t, values, *, where: str = "input"):
        self.where = where
        self.t, self.values = np.array(t, float), np.array(values, float)
        if self.t.ndim != 1 or self.t.shape != self.values.shape:
            raise SimulationError(f"{where}: times and values must be 1-D arrays of one length, got shapes "
                                  f"{self.t.shape} and {self.values.shape}")
        if self.t.size < 2:
            raise SimulationError(f"{where}: {self.t.size} sample(s); at least 2 are needed to interpolate")
        if not np.all(np.isfinite(self.t)) or np.any(np.diff(self.t) <= 0):
            raise SimulationError(f"{where}: the times must be finite and strictly increasing")
        bad = np.flatnonzero(~np.isfinite(self.values))
        if bad.size:
            raise SimulationError(f"{where}: no value at t = {self.t[bad[0]]:g} (a gap); an input needs one at "
                                  "every sample")

    def __call__(self, t):
        """The value at a time (a float) or at an array of times (an array of their shape)."""
        value = np.interp(np.asarray(t, float), self.t, self.values)  # holds the end values outside
        return float(value) if np.ndim(value) == 0 else value

    def __repr__(self) -> str:
        return f"TabulatedInput({self.t.size} samples, t in [{self.t[0]:g}, {self.t[-1]:g}])"
