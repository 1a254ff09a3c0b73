"""Numerical evaluation of ARR expressions on recorded data.

An ARR holds signals ``x(t)``, derivatives ``Derivative(x(t), (t, n))`` and
integrals ``Integral(g, (t, 0, t))`` of known expressions.  :class:`CompiledARR`
replaces each by a plain symbol once, lambdifies the nominal part, and turns a
record into the point values those symbols take at every sample:

* signals are read from the record's columns;
* derivatives are estimated (Savitzky-Golay by default, central differences,
  or exact values the user supplies), see :mod:`diagnosis.records`;
* integrals are cumulative trapezoids of the integrand from the start of the
  record (the energy variable is taken as zero there), or, when the record
  holds the antiderivative of a signal (encoder angles for measured speeds),
  differences of it: integrating measured noise would otherwise make a
  random walk.

Everything is vectorized over samples.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph.errors import PHMError

from .deltas import delta_parameter
from .derivatives import cumulative_integral, default_window, derivative
from .records import Record, RecordError, as_record

__all__ = [
    "NUMERIC_FUNCTIONS", "T", "ARRError", "CompiledARR", "antiderivative_integral", "compile_arr",
    "integral_depth", "read_record", "signal_derivative", "trusted_edge",
]


@dataclass
class CompiledARR:
    """An ARR's expressions in plain point symbols, ready for numpy.

    Attributes
    ----------
    points : list of sympy.Symbol
        Point-valued inputs, in order: signals, derivatives, integrals.
    signals : list of str
    derivatives : dict
        Point symbol -> (signal name, order).
    integrals : dict
        Point symbol -> integrand (in the point symbols of signals/derivatives).
    nominal : sympy.Expr
        ``r_n`` in the point symbols with nominal parameter values.
    uncertain : sympy.Expr
        Psi_2 in the point symbols, nominal values and ``delta_*`` symbols.
    terms : dict
        Parameter -> its Psi_2 term in the same symbols.
    symbols : dict
        Signal, derivative and integral expressions -> their point symbols.
    """

    arr: object
    points: list
    signals: list
    derivatives: dict
    integrals: dict
    nominal: sp.Expr
    uncertain: sp.Expr
    terms: dict
    symbols: dict = field(default_factory=dict, repr=False)
    _cache: dict = field(default_factory=dict, repr=False)

    def __getstate__(self) -> dict:
        """The state without the cached functions: lambdified code and interval evaluators do not pickle.

        They are rebuilt from the expressions on first use, so a compiled ARR shipped to another
        process (a pool or Dask worker) evaluates exactly as the original.

        >>> import pickle
        >>> from bondgraph.library import rlc_circuit
        >>> from diagnosis import derive_arrs
        >>> compiled = derive_arrs(rlc_circuit())[1].compiled
        >>> nominal = compiled.function("nominal", compiled.nominal)
        >>> copy = pickle.loads(pickle.dumps(compiled))
        >>> copy.function("nominal", copy.nominal)(1.0, 2.0, 3.0) == nominal(1.0, 2.0, 3.0)
        True
        """
        return {**self.__dict__, "_cache": {}}

    def cached(self, key: str, build: Callable[[], object]):
        """The value kept under ``key``, made by ``build()`` on first use (lambdified functions, evaluators).

        Everything numeric derived from the relation is built once per compiled ARR, however many
        records it evaluates.

        >>> from bondgraph.library import rlc_circuit
        >>> from diagnosis import derive_arrs
        >>> compiled = derive_arrs(rlc_circuit())[1].compiled
        >>> compiled.cached("answer", lambda: 42), compiled.cached("answer", lambda: 0)
        (42, 42)
        """
        if key not in self._cache:
            self._cache[key] = build()
        return self._cache[key]

    def function(self, key: str, expression: sp.Expr, extra: tuple = ()):
        """A cached numpy function of the point symbols (and ``extra`` symbols)."""
        return self.cached(key, lambda: sp.lambdify([*self.points, *extra], expression, modules="numpy", cse=True))

    def point_values(self, record: Record, *, method: str = "savgol", window: int | None = None,
                     polyorder: int = 3, exact: Mapping | None = None,
                     antiderivatives: Mapping | None = None) -> list[np.ndarray]:
        """The value of every point symbol at every sample of ``record``.

        ``exact``: signal (``"x"`` or ``"x:2"``) -> exact derivative values.
        ``antiderivatives``: signal -> record column holding its integral
        (e.g. ``{"omega_m": "theta_m"}``), used for integrals linear in them.
        """
        exact = dict(exact or {})
        values: dict = {sp.Symbol(name): record[name] for name in self.signals}
        for symbol, (name, order) in self.derivatives.items():
            values[symbol] = signal_derivative(record, name, order, method=method, window=window,
                                               polyorder=polyorder, exact=exact)
        for symbol in self.integrals:
            terms = self.antiderivative_terms(symbol, antiderivatives or {})
            if terms is not None:
                values[symbol] = antiderivative_integral(terms, {c: record[c] for c, _ in terms},
                                                         {c: record[c][0] for c, _ in terms})
                continue
            values[symbol] = cumulative_integral(record, self.integrand_values(symbol, values, len(record)),
                                                 name=str(self.integrals[symbol]))
        return [values[p] for p in self.points]

    def integrand_values(self, symbol: sp.Symbol, values: Mapping, samples: int) -> np.ndarray:
        """The integrand of the integral ``symbol`` at every sample, from the point values known so far.

        ``values`` maps point symbols to arrays of ``samples`` values; a point it does not hold yet (an
        integral computed after this one) counts as 0, as in :meth:`point_values`, which computes the
        integrals in order.

        >>> import sympy as sp
        >>> from bondgraph.library import torsion_bar_monitorable
        >>> from diagnosis import derive_arrs
        >>> arr = next(a for a in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")
        ...            if a.junction == "1_1")
        >>> compiled = arr.compiled
        >>> int0 = next(iter(compiled.integrals))
        >>> compiled.integrals[int0]
        -omega_Ld + 0.266666666666667*omega_m
        >>> speeds = {sp.Symbol("omega_Ld"): np.array([1.0, 2.0]), sp.Symbol("omega_m"): np.array([3.0, 6.0])}
        >>> np.round(compiled.integrand_values(int0, speeds, 2), 6).tolist()
        [-0.2, -0.4]
        """
        inputs = [values.get(p, np.zeros(samples)) for p in self.points]
        return np.broadcast_to(np.asarray(self.function(f"integrand {symbol}", self.integrals[symbol])(*inputs),
                                          float), (samples,))

    def antiderivative_terms(self, symbol: sp.Symbol, antiderivatives: Mapping) -> list[tuple[str, float]] | None:
        """``[(column, c_i), ...]`` when the integrand of ``symbol`` is ``sum c_i x_i`` and every ``x_i`` has its
        antiderivative in a record column (``antiderivatives``: signal -> column), else None.

        The integral is then ``sum c_i (X_i(t) - X_i(t_0))`` (:func:`antiderivative_integral`), read from
        the columns rather than integrated from noisy samples.
        """
        integrand = self.integrals[symbol]
        symbols = {sp.Symbol(signal): column for signal, column in antiderivatives.items()}
        if not integrand.free_symbols or not integrand.free_symbols <= set(symbols):
            return None
        coefficients = {x: sp.diff(integrand, x) for x in sorted(integrand.free_symbols, key=str)}
        if any(not c.is_number for c in coefficients.values()) or integrand.xreplace({x: 0 for x in coefficients}) != 0:
            return None
        return [(symbols[x], float(c)) for x, c in coefficients.items()]

    def residual(self, points: list[np.ndarray]) -> np.ndarray:
        """The nominal residual ``r_n`` at every sample."""
        return np.broadcast_to(np.asarray(self.function("nominal", self.nominal)(*points), float),
                               points[0].shape if points else ()).copy()


def trusted_edge(order: int, method: str, window: int | None, polyorder: int) -> int:
    """How many samples at each end of a record a derivative of this order is left undecided (NaN).

    At the ends of a record the estimate extrapolates a one-sided fit; a first derivative stays close,
    a second one does not (a start-up transient's curvature, and noise, come out tens of times too
    large), so those samples are left undecided rather than compared with a threshold: half a
    Savitzky-Golay window, or ``order`` samples for central differences.

    >>> trusted_edge(1, "savgol", None, 3), trusted_edge(2, "savgol", None, 3), trusted_edge(2, "central", None, 3)
    (0, 5, 2)
    """
    if order < 2 or method not in ("savgol", "central"):
        return 0
    return (window or default_window(polyorder)) // 2 if method == "savgol" else order


def signal_derivative(record: Record, name: str, order: int, *, method: str = "savgol", window: int | None = None,
                      polyorder: int = 3, exact: Mapping | None = None) -> np.ndarray:
    """The ``order``-th derivative of signal ``name`` as an ARR reads it: given in ``exact`` (under ``"x"`` or
    ``"x:2"``), or estimated and left undecided within :func:`trusted_edge` samples of either end.

    >>> from diagnosis import as_record
    >>> record = as_record({"t": np.arange(20) * 0.1, "x": (np.arange(20) * 0.1) ** 2})
    >>> signal_derivative(record, "x", 1)[[0, 10]].round(6).tolist()
    [0.0, 2.0]
    """
    key = name if order == 1 else f"{name}:{order}"
    if exact and key in exact:
        return derivative(record, name, order=order, method="exact", exact=exact[key], name=name)
    return _trusted(derivative(record, name, order=order, method=method, window=window, polyorder=polyorder,
                               name=name), order, method, window, polyorder)


def _trusted(values: np.ndarray, order: int, method: str, window: int | None, polyorder: int) -> np.ndarray:
    """A derivative of order 2 or more, NaN (undecided) within :func:`trusted_edge` samples of either end."""
    edge = trusted_edge(order, method, window, polyorder)
    if not edge:
        return values
    trusted = np.array(values, dtype=float, copy=True)
    trusted[:edge] = np.nan
    trusted[len(trusted) - edge:] = np.nan
    return trusted


def antiderivative_integral(terms: list[tuple[str, float]], columns: Mapping, origin: Mapping) -> np.ndarray:
    """``sum c_i (X_i - X_i(t_0))`` for ``terms`` from :meth:`CompiledARR.antiderivative_terms`.

    ``columns``: column -> its samples; ``origin``: column -> its value at the record's first sample.

    >>> antiderivative_integral([("theta", 2.0)], {"theta": np.array([1.0, 1.5, 3.0])}, {"theta": 1.0}).tolist()
    [0.0, 1.0, 4.0]
    """
    total = np.zeros(np.shape(columns[terms[0][0]]))
    for column, c in terms:
        total += c * (columns[column] - origin[column])
    return total


class ARRError(PHMError, ValueError):
    """An ARR that cannot be evaluated on a record; the message names the ARR and the term at fault."""


#: Functions of the point values that numpy computes (anything else in a relation is refused at compile time).
NUMERIC_FUNCTIONS = (sp.Abs, sp.sign, sp.exp, sp.log, sp.sin, sp.cos, sp.tan, sp.sinh, sp.cosh, sp.tanh, sp.asin,
                     sp.acos, sp.atan, sp.atan2, sp.Min, sp.Max, sp.Heaviside, sp.floor, sp.ceiling, sp.Piecewise)

T = sp.Symbol("t")


def _depth(integral: sp.Integral) -> int:
    """How deep ``integral`` nests: 1 plus the deepest integral inside, counting each of its limits."""
    inner = max((_depth(i) for i in integral.function.atoms(sp.Integral)), default=0)
    return inner + len(integral.limits)


def integral_depth(expression: sp.Expr) -> int:
    """How many integrations deep ``expression``'s deepest integral is (0 without integrals).

    >>> t = sp.Symbol("t"); x = sp.Function("x")
    >>> integral_depth(x(t) + sp.Integral(sp.Integral(x(t), (t, 0, t)), (t, 0, t)))
    2
    """
    return max((_depth(i) for i in expression.atoms(sp.Integral)), default=0)


def _check_numeric(name: str, nominal: sp.Expr, uncertain: sp.Expr, integrals: Mapping) -> None:
    """Raise an :class:`ARRError` unless every part of the relation is a function numpy can compute."""
    for where, expression in [("r_n", nominal), ("Psi_2", uncertain), *(
            (f"the integrand of {s}", g) for s, g in integrals.items())]:
        left = expression.atoms(sp.Derivative, sp.Integral, AppliedUndef, sp.Subs)
        if left:
            raise ARRError(f"{name}: cannot evaluate {sorted(map(str, left))[0]} in {where}")
        for f in expression.atoms(sp.Function):
            if not isinstance(f, NUMERIC_FUNCTIONS):
                raise ARRError(f"{name}: cannot evaluate the function {type(f).__name__} in {where} ({f})")
    for symbol, integrand in integrals.items():
        inside = sorted(str(s) for s in integrand.free_symbols if delta_parameter(s) is not None)
        if inside:
            raise ARRError(f"{name}: the uncertainty {inside[0]} sits inside an integral ({integrand}); its "
                           "range cannot be bounded from point values")


def compile_arr(arr) -> CompiledARR:
    """Compile an :class:`~diagnosis.derivation.ARR`: its signals, derivatives and integrals become point symbols.

    A signal ``x(t)`` becomes the symbol ``x``, its ``n``-th time derivative ``dn_x`` and the ``k``-th integral
    (in sorted order) ``int<k>`` (with ``_`` appended while the name is a signal's or another symbol's);
    nominal parameter values are substituted, the ``delta_*`` symbols of the uncertain part are kept.

    Each call compiles afresh; :attr:`ARR.compiled <diagnosis.derivation.ARR.compiled>` keeps one per ARR, so that
    its lambdified functions are built once.

    Raises
    ------
    ARRError
        For what a record cannot give: a derivative that is not a time derivative of a signal, an
        integral that does not start at the record's start, an integrand holding an uncertainty
        ``delta`` (:func:`diagnosis.integral_forms.factor_out_of_integrals` moves what it can out),
        or a function numpy cannot compute (``re``, ``im``, an unevaluated ``Subs``...).

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> compiled = compile_arr(derive_arrs(rlc_circuit())[0])
    >>> compiled.points, compiled.derivatives
    ([V, i, v_C, d1_i], {d1_i: ('i', 1)})
    >>> compiled.nominal
    V - 0.1*d1_i - 10.0*i - v_C
    """
    replace: dict = {}
    signals = sorted({f.func.__name__ for f in (arr.nominal + arr.uncertain).atoms(AppliedUndef)})
    signal_symbols = {name: sp.Symbol(name) for name in signals}
    for name in signals:
        replace[sp.Function(name)(sp.Symbol("t"))] = signal_symbols[name]
    derivatives, integrals = {}, {}
    # a signal may be called d1_x or int0 too: point names must not merge two different quantities
    taken = set(signals) | {str(s) for s in (arr.nominal + arr.uncertain).free_symbols}

    def fresh(name: str) -> sp.Symbol:
        while name in taken:
            name += "_"
        taken.add(name)
        return sp.Symbol(name)

    # the atoms of each part: in the sum, an integral of r_n may cancel against its copy in Psi_2
    def atoms(kind):
        return arr.nominal.atoms(kind) | arr.uncertain.atoms(kind)

    for d in sorted(atoms(sp.Derivative), key=str):
        (variable, order), = d.variable_count
        if not isinstance(d.expr, AppliedUndef) or str(variable) != "t":
            raise ARRError(f"{arr.name}: cannot evaluate {d}: only time derivatives of signals are estimated "
                           "from a record")
        symbol = fresh(f"d{order}_{d.expr.func.__name__}")
        derivatives[symbol] = (d.expr.func.__name__, int(order))
        replace[d] = symbol
    k = 0
    for integral in sorted(atoms(sp.Integral), key=lambda i: (_depth(i), str(i))):
        # inner integrals first, so that an outer integrand is written in the inner one's point
        integrand = integral.function.xreplace(replace)
        for limits in integral.limits:  # Integral(g, L, L) is the integral of the integral of g
            if tuple(limits) != (T, 0, T):
                raise ARRError(f"{arr.name}: cannot evaluate {integral}: only integrals from the start of the "
                               "record, (t, 0, t), are computed")
            symbol = fresh(f"int{k}")
            k += 1
            integrals[symbol] = integrand
            integrand = symbol
        replace[integral] = integrand
    values = {sp.Symbol(p): v for p, v in arr.values.items()}
    points = [signal_symbols[n] for n in signals] + list(derivatives) + list(integrals)
    _check_numeric(arr.name, arr.nominal.xreplace(replace), arr.uncertain.xreplace(replace), integrals)
    return CompiledARR(
        arr=arr,
        points=points,
        signals=signals,
        derivatives=derivatives,
        integrals={s: g.xreplace(values) for s, g in integrals.items()},
        nominal=arr.nominal.xreplace(replace).xreplace(values),
        uncertain=arr.uncertain.xreplace(replace).xreplace(values),
        terms={p: w.xreplace(replace).xreplace(values) for p, w in arr.terms.items()},
        symbols=replace,
    )


def read_record(arr, data, name: str = "record", extra: tuple = ()) -> Record:
    """Validate a record for an ARR: a ``t`` column and one column per signal it uses (and ``extra``)."""
    try:
        return as_record(data, [*arr.compiled.signals, *extra], name=name)
    except RecordError as exc:
        raise RecordError(f"{arr.name}: {exc}") from None
