"""Observation equation from an ARR's nominal part (Jha et al. (2016), section 3.2).

With the prognostic candidate theta^d free and every other parameter at its
nominal value, the balance of the junction holds for the true system:
``R(theta) = 0``, where ``R`` is the nominal part written with ``theta`` in
place of ``theta_n``, so that ``r_n = R(theta_n)``.  Hence (eqs. 24-26)

    y = -r_n = R(theta) - R(theta_n) = A^T (phi(theta) - phi(theta_n)),

and when ``R`` is linear in theta, ``y = a_1 (theta - theta_n)`` with
``a_1 = d r_n / d theta`` (eq. 27).  For the torsion bar's b_Md this is
eq. (52), ``y = (b_Md - b_Md,n)(-omega_m / k_belt^2)``.

The expression is compiled once into a numpy function of the particles and of
the point values (signals, derivative estimates, integrals) at step k, using
the same point symbols as :mod:`diagnosis.residuals`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from .errors import PrognosisError

__all__ = ["SENSOR", "ObservationModel", "observation_model", "sensor_model"]

#: the prefix of a sensor's fault candidate, ``"sensor <signal>"``, as in the signature matrix
SENSOR = "sensor "


@dataclass
class ObservationModel:
    """``y = h(theta, signals)``: the measurement ``-r_n`` a particle ``theta`` predicts.

    Attributes
    ----------
    candidate : str
        The prognostic candidate (a parameter of the ARR).
    nominal : float
        Its nominal value theta_n.
    expression : sympy.Expr
        ``h`` in the ARR's signals and the symbol of the candidate.
    coefficient : sympy.Expr or None
        ``a_1 = d r_n / d theta`` when ``h`` is linear in theta, else None.
    rate_coefficient : sympy.Expr or None
        For an ARR written as the time derivative of a balance (``form`` ``"differentiated ..."``),
        the balance's own coefficient ``x`` with ``dx/dt = a_1``: there a drifting theta adds
        ``theta' x`` to ``y``, since ``d(theta x)/dt = theta x' + theta' x`` while the ARR assumed
        theta constant.  None for an ARR not differentiated, or when ``x`` is not among the ARR's
        point values (the rate's term is then left out, a first-order model of a slow drift).

    Examples
    --------
    Returned by :func:`observation_model`.  The loop ARR of the RLC circuit with
    the resistance as candidate: ``y = -(R - R_n) i``.

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arr = derive_arrs(rlc_circuit(), complete=False, integrals="keep")[0]
    >>> h = observation_model(arr, "R")
    >>> h.candidate, h.nominal, h.expression, h.coefficient
    ('R', 10.0, -(R - 10.0)*i(t), -i(t))
    >>> arr.compiled.points   # the order of the point values
    [V, i, v_C, d1_i]

    Called on particles (here three values of R, with i = 0.5 A), and inverted:

    >>> h(np.array([9.0, 11.0, 12.0]), [1.0, 0.5, 0.0, 0.0]).tolist()
    [0.5, -0.5, -1.0]
    >>> points = [np.ones(2), np.full(2, 0.5), np.zeros(2), np.zeros(2)]   # two samples
    >>> h.invert(np.array([-0.5, -1.0]), points).tolist()   # linear in R: no bracket needed
    [11.0, 12.0]
    """

    arr: object
    candidate: str
    nominal: float
    expression: sp.Expr
    coefficient: sp.Expr | None
    rate_coefficient: sp.Expr | None = None
    _function: object = field(default=None, init=False, repr=False)
    _rate_function: object = field(default=None, init=False, repr=False)

    def __getstate__(self) -> dict:
        """The state without the lambdified ``h`` (generated code does not pickle); :meth:`function` rebuilds it."""
        return {**self.__dict__, "_function": None, "_rate_function": None}

    @property
    def symbol(self) -> sp.Symbol:
        """The sympy symbol of the candidate, the variable theta of ``expression``."""
        return sp.Symbol(self.candidate)

    def function(self):
        """``h(theta, *points)``, vectorized; ``points`` in the order of the compiled ARR."""
        if self._function is None:
            compiled = self.arr.compiled
            values = {sp.Symbol(p): v for p, v in self.arr.values.items() if p != self.candidate}
            numeric = self.expression.xreplace(compiled.symbols).xreplace(values)
            self._function = sp.lambdify([self.symbol, *compiled.points], numeric, modules="numpy", cse=True)
        return self._function

    def points_used(self) -> list[int]:
        """The positions, in the compiled ARR's point order, of the point values ``h`` reads (the others do
        not change its value: a caller that keeps many samples may drop them)."""
        compiled = self.arr.compiled
        values = {sp.Symbol(p): v for p, v in self.arr.values.items() if p != self.candidate}
        used = self.expression.xreplace(compiled.symbols).xreplace(values).free_symbols
        return [i for i, point in enumerate(compiled.points) if point in used]

    def rate_function(self):
        """``x(*points)``, the factor of theta's rate (see ``rate_coefficient``), vectorized."""
        if self._rate_function is None:
            compiled = self.arr.compiled
            values = {sp.Symbol(p): v for p, v in self.arr.values.items()}
            numeric = self.rate_coefficient.xreplace(compiled.symbols).xreplace(values)
            self._rate_function = sp.lambdify(compiled.points, numeric, modules="numpy")
        return self._rate_function

    def __call__(self, theta: np.ndarray, points, rate: np.ndarray | None = None) -> np.ndarray:
        """Predicted measurement for particles ``theta`` (..., N) with point values (...,) per asset.

        ``rate``: theta's rate of change (like ``theta``), for an ARR with a ``rate_coefficient``.
        """
        values = [np.asarray(p, float)[..., None] for p in points]
        y = np.asarray(self.function()(theta, *values), float)
        if y.shape != np.shape(theta):  # an expression free of theta, or of the points: one value per row
            y = np.broadcast_to(y, np.shape(theta))
        if rate is not None and self.rate_coefficient is not None:
            y = y + rate * np.asarray(self.rate_function()(*values), float)
        return y


    def invert(self, y: np.ndarray, points, bracket: tuple[float, float] | None = None) -> np.ndarray:
        """The theta that explains each measurement ``y`` (K,) at its point values (K,) each.

        Linear ``h``: ``theta = theta_n + y / a_1``, exact, and ``bracket`` is not needed.  Otherwise a
        bracketed root search per sample (:func:`scipy.optimize.brentq` on ``h(theta) - y`` over
        ``bracket``, then required); NaN where ``h - y`` does not change sign on the bracket.
        """
        y = np.asarray(y, float)
        if self.coefficient is None and bracket is None:
            raise PrognosisError(f"the observation equation of {self.candidate!r} is not linear in it: "
                                 f"invert needs a bracket (lo, hi) for the root search")
        values = [np.asarray(p, float)[:, None] for p in points]
        if self.coefficient is not None:
            slope = np.asarray(self.function()(np.full((y.size, 1), self.nominal + 1.0), *values), float)
            with np.errstate(divide="ignore", invalid="ignore"):
                return self.nominal + y / np.broadcast_to(slope, (y.size, 1))[:, 0]
        from scipy.optimize import brentq

        def root(k):
            def gap(theta):
                return float(np.squeeze(self.function()(theta, *(v[k] for v in values)))) - y[k]
            lo, hi = bracket
            return brentq(gap, lo, hi) if np.sign(gap(lo)) != np.sign(gap(hi)) else np.nan
        return np.array([root(k) for k in range(y.size)])


def observation_model(arr, candidate: str) -> ObservationModel:
    """The observation equation of ``arr`` for the prognostic candidate ``candidate``.

    The ARR's signals, derivatives and integrals are kept whole while the equation is expanded, so
    that ``h`` is a function of the ARR's own point values (a spring's ``Integral(v_u - v_s)/C_s``
    stays one integral).  A candidate inside an integral or a derivative would need point values the
    ARR does not compute: a :class:`~prognosis.errors.PrognosisError` names the ARR and the integral.

    Examples
    --------
    >>> from bondgraph.library import torsion_bar_monitorable
    >>> from diagnosis import derive_arrs
    >>> arr = derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")[0]
    >>> observation_model(arr, "b_Md").expression
    -(b_Md - 0.005025)*omega_m(t)/k_belt**2
    """
    if candidate not in arr.parameters:
        raise PrognosisError(
            f"{arr.name} is not sensitive to {candidate!r}; it is sensitive to {sorted(arr.parameters)}"
        )
    theta = sp.Symbol(candidate)
    nominal = float(arr.values[candidate])
    balance, back = _opaque(arr.nominal)  # R(theta): the nominal part with theta free
    inside = [atom for atom in back.values() if not isinstance(atom, AppliedUndef) and theta in atom.free_symbols]
    if inside:
        raise PrognosisError(f"{arr.name}: {candidate!r} sits inside {inside[0]}, so its observation model needs "
                             f"integrals or derivatives the ARR does not compute; use an ARR in which {candidate!r} "
                             "multiplies the signals, their derivatives and integrals")
    h = sp.factor_terms(sp.expand(balance - balance.xreplace({theta: nominal})))
    slope = sp.diff(h, theta)
    coefficient = sp.factor_terms(slope) if not slope.has(theta) else None  # no simplify: keep sign() as is
    if coefficient is not None:
        h = (theta - nominal) * coefficient
        coefficient = coefficient.xreplace(back)
    rate = _antiderivative(coefficient, arr) if str(getattr(arr, "form", "")).startswith("differentiated ") else None
    return ObservationModel(arr, candidate, nominal, h.xreplace(back), coefficient, rate)


def sensor_model(arr, signal: str, kind: str = "offset") -> ObservationModel:
    """The observation equation of ``arr`` for a fault of the sensor of ``signal``.

    ``kind="offset"``: the sensor reads ``s + beta``; evaluated on the readings, the ARR balances at
    the true signal ``s = reading - beta``, so that

        y = -r_n = R(reading - beta, reading' - beta') - R(reading, reading')

    with ``beta'`` the offset's rate: 0 for a bias, the slope of a drift.  Both are straight lines in
    time, so ``beta''`` and higher derivatives are 0 and the ARR's higher derivatives of the reading
    are the signal's.  ``kind="gain"``: the error is a share ``g`` of the reading, ``s = reading (1 - g)``
    (a gain ``1 / (1 - g)``), so the k-th derivative of the signal is ``reading^(k) (1 - g) - k g'
    reading^(k-1)`` for ``g`` a straight line in time.  Either way the candidate is
    ``"sensor <signal>"``, its nominal value 0, ``y`` linear in it, and its rate enters as a drifting
    parameter's does (``rate_coefficient``; left out when it needs a derivative the ARR does not
    compute).  An ARR that integrates the signal would need the integral of the error since the
    record's start, which no law of the error from its onset gives: a
    :class:`~prognosis.errors.PrognosisError` says so.

    Examples
    --------
    The RLC circuit's loop, ``V - R i - L di/dt - v_C``, with the current's sensor off by beta
    (and drifting at beta'): ``y = R beta + L beta'``; with a share g of the reading in error,
    ``y = g (R i + L di/dt) + L g' i``.

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arr = derive_arrs(rlc_circuit(), complete=False, integrals="keep")[0]
    >>> h = sensor_model(arr, "i")
    >>> h.candidate, h.nominal, h.expression, h.coefficient, h.rate_coefficient
    ('sensor i', 0.0, R*sensor i, R, L)
    >>> h(np.array([0.1]), [1.0, 0.5, 0.0, 0.0], rate=np.array([0.2])).round(9).tolist()   # R = 10, L = 0.1
    [1.02]
    >>> gain = sensor_model(arr, "i", kind="gain")
    >>> gain.coefficient, gain.rate_coefficient
    (L*Derivative(i(t), t) + R*i(t), L*i(t))
    """
    if kind not in ("offset", "gain"):
        raise PrognosisError(f"a sensor's fault is an 'offset' or a 'gain', got {kind!r}")
    if signal not in arr.signals:
        raise PrognosisError(f"{arr.name} does not read {signal!r}; it reads {arr.signals}")
    theta, rate = sp.Symbol(SENSOR + signal), sp.Dummy("rate")
    balance, back = _opaque(arr.nominal)
    shift = {}
    for symbol, atom in back.items():
        order = _order_in(atom, signal, arr.name)
        if order is None:
            continue
        if kind == "offset":
            shift[symbol] = symbol - (theta if order == 0 else rate if order == 1 else 0)
        else:
            lower = 0 if order == 0 else (atom.expr if order == 1 else sp.Derivative(atom.expr, (sp.Symbol("t"),
                                                                                                order - 1)))
            shift[symbol] = symbol * (1 - theta) - order * rate * lower
    change = sp.expand(balance.xreplace(shift) - balance)
    h = sp.factor_terms(change.subs(rate, 0))
    x = sp.factor_terms(sp.diff(change, rate).subs({rate: 0, theta: 0})).xreplace(back)
    if x == 0 or not x.atoms(sp.Integral, sp.Derivative, AppliedUndef) <= set(arr.compiled.symbols):
        x = None
    slope = sp.diff(h, theta)
    coefficient = sp.factor_terms(slope) if not slope.has(theta) else None
    if coefficient is not None:
        h = theta * coefficient
        coefficient = coefficient.xreplace(back)
    return ObservationModel(arr, SENSOR + signal, 0.0, h.xreplace(back), coefficient, x)


def _order_in(atom: sp.Expr, signal: str, arr_name: str) -> int | None:
    """The order of ``atom`` as a time derivative of ``signal`` (0: the signal), None when it is not of it;
    an error when the signal is inside it otherwise (an integral)."""
    if isinstance(atom, AppliedUndef):
        return 0 if atom.func.__name__ == signal else None
    if isinstance(atom, sp.Derivative) and isinstance(atom.expr, AppliedUndef):
        return atom.derivative_count if atom.expr.func.__name__ == signal else None
    if any(f.func.__name__ == signal for f in atom.atoms(AppliedUndef)):
        raise PrognosisError(f"{arr_name}: the sensor of {signal!r} is read inside {atom}, so an error of it "
                             "acts through its history since the record's start; use an ARR that reads "
                             f"{signal!r} and its derivatives only")
    return None


def _antiderivative(coefficient: sp.Expr | None, arr) -> sp.Expr | None:
    """``x`` with ``dx/dt = coefficient``, each derivative one order down; None unless that is exact
    and every atom of ``x`` is one of the ARR's point values."""
    if coefficient is None or str(arr.form).count("differentiated") != 1:
        return None
    t = sp.Symbol("t")

    def lower(d):
        count = sum(n for v, n in d.variable_count if v == t)
        return d.expr if count == 1 else sp.Derivative(d.expr, (t, count - 1))
    x = coefficient.replace(lambda e: isinstance(e, sp.Derivative), lower)
    if sp.simplify(sp.diff(x, t) - coefficient) != 0:
        return None
    known = set(arr.compiled.symbols)
    atoms = x.atoms(sp.Integral, sp.Derivative, AppliedUndef)
    return x if atoms <= known else None


def _opaque(expression: sp.Expr) -> tuple[sp.Expr, dict]:
    """``expression`` with each signal, derivative and integral as one plain symbol, and the map back.

    ``sp.expand`` and ``sp.factor_terms`` rewrite inside an integral (``Integral(a - b)`` becomes
    ``Integral(a) - Integral(b)``), but the ARR computes only its own integrals and derivatives (its
    point values): as symbols they stay whole.  The outermost one is replaced (``xreplace`` works top
    down), so an integral nested in another stays inside it.
    """
    atoms = sorted(expression.atoms(sp.Integral, sp.Derivative, AppliedUndef), key=sp.default_sort_key)
    forward = {atom: sp.Dummy(f"point{k}") for k, atom in enumerate(atoms)}
    opaque = expression.xreplace(forward)
    used = opaque.free_symbols
    return opaque, {symbol: atom for atom, symbol in forward.items() if symbol in used}
