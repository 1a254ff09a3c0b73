"""Simulation residuals: the ARR of a minimal set that only an ODE of its own closes.

Some minimal overdetermined sets have no closed form by differentiation: the middle tanks of a cascade
measured at its ends sit in a loop through their orifice laws, and eliminating their levels would need the
inverse of a law applied to derivatives.  Such a set is still an analytical redundancy relation once its
states are integrated from the record, in integral causality: the set less one equation is an ODE
``dx/dt = f(x, u, theta)`` with explicit algebra, and the equation left over, ``r_n = g(x_hat, u, theta)``,
compares its solution with the measurements.  :func:`diagnosis.derive_arrs` adds these with
``simulated=True`` for the gaps no closed form fills; :func:`diagnosis.elimination.arr_from_set` makes one
for a given set.

The residual
    ``x_hat`` is integrated by Heun's scheme (explicit trapezoid) on the record's samples, the signals read
    at both ends of each step; ``r_n`` is ``g`` at the simulated states (the signals' derivatives, if ``g``
    needs any, estimated as for any ARR).

The band
    The same simulation runs at every corner of the parameters' box (all at once, vectorized): the band on
    ``-r_n`` is the range of ``g`` over those trajectories, less ``r_n``.  It is the exact range when the
    residual moves monotonically with each parameter, as in cooperative dynamics (tanks, thermal and
    pneumatic networks: every state raises the others' rates); otherwise an interior parameter can reach
    past it, so :data:`INTERIOR_SAMPLES` interior points are simulated too, their range joins the band, and
    a :class:`SimulationWarning` says when they reach past the corners: the band is then a sample's hull,
    not a guaranteed range.  Past :data:`MAX_CORNERS` corners a fixed sample of them is simulated, and a
    warning says so.  Heun's discretization error (second order in the step) is not in the band: the noise
    margin of :func:`diagnosis.detect` covers it, as it covers a derivative estimate's.

The initial state
    ``initial="rest"`` (default): every trajectory starts at rest for its own parameters (the rates vanish
    for the first usable sample's signals: the nominal rest by following the dynamics, each corner's by
    Newton steps from it); or ``initial={"q_T2": (lo, hi), ...}``, the corners of that box with each corner
    of the parameters'.  A record that does not start at rest needs the second.

A gap in a signal the simulation reads stops it: the samples after it are undecided.  Streaming, generated
code, parameter boxes and the prognoser need a closed form and refuse these residuals
(:func:`~diagnosis.detection.check_closed_form`).

Examples
--------
Three tanks in a row with the first and last levels measured: the middle volume ``q_T2`` is simulated.

>>> import numpy as np
>>> from bondgraph import simulate
>>> from bondgraph.library import tank_cascade
>>> from diagnosis import structural_model
>>> from diagnosis.elimination import arr_from_set
>>> bg = tank_cascade(3, every=2)
>>> model = structural_model(bg)
>>> arr = arr_from_set(bg, model.mso_sets()[2], model=model, simulated=True)
>>> arr.form, arr.states, arr.signals
('simulation', ('q_T2', 'q_T3'), ['h1', 'h3'])
>>> rest = {"T1": 0.05 * 0.0075, "T2": 0.05 * 0.005, "T3": 0.05 * 0.0025}   # volumes at rest, q_in = 1e-4
>>> t = np.linspace(0.0, 120.0, 1201)
>>> record = simulate(bg, (0.0, 120.0), {"q_in": 1e-4}, x0=rest, t_eval=t).record()
>>> result = arr.evaluate(record)
>>> result.detection_time is None, bool(np.nanmax(np.abs(result.residual)) < 1e-9)
(True, True)
>>> arr.evaluate(record, initial={"q_T2": 2.5e-4})   # doctest: +ELLIPSIS
Traceback (most recent call last):
...
diagnosis.simulation_residuals.SimulationError: ARR_MSO: initial: state 'q_T3' not given; its states are [...]
"""

from __future__ import annotations

import itertools
import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import scipy.integrate
import scipy.optimize
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph.calculus import T
from bondgraph.errors import PHMError, PHMWarning

from .arr import ARR
from .deltas import delta_parameter, latex
from .records import Record, as_record
from .residuals import signal_derivative

__all__ = ["INTERIOR_SAMPLES", "MAX_CORNERS", "NEWTON_STEPS", "SimulationARR", "SimulationError", "SimulationWarning"]


class SimulationWarning(PHMWarning):
    """A simulation residual's band that is a sample's hull: more corners than simulated, or an interior point
    of the parameters' box reaching past the corners."""


class SimulationError(PHMError, ValueError):
    """A simulation residual that cannot start: no rest state to enclose, or an initial state not given right."""


@dataclass
class SimulationARR(ARR):
    """The ARR of a set closed by simulating its states: ``r_n = g(x_hat, u)`` with ``dx_hat/dt = f(x_hat, u)``.

    Attributes (besides those of :class:`~diagnosis.arr.ARR`)
    ----------
    states : tuple of str
        The simulated states, by their energy variable (``q_T2``); ``nominal`` holds them as functions of
        time, read from the simulation.
    rates : tuple of sympy.Expr
        ``f``, the nominal rate of each state, in states, signals (and their derivatives) and parameters.
    rates_true : tuple of sympy.Expr
        The same with theta (1 + delta_theta), for the band.
    """

    states: tuple = ()
    rates: tuple = ()
    rates_true: tuple = ()
    form: str = "simulation"
    _simulator: object = field(default=None, init=False, repr=False, compare=False)

    simulation = True

    @property
    def signals(self) -> list[str]:
        """The measured and input signals the relation and the simulation read (the states are simulated)."""
        functions = {f.func.__name__ for e in (self.nominal, *self.rates) for f in e.atoms(AppliedUndef)}
        return sorted(functions - set(self.states))

    @property
    def derivatives(self) -> dict:
        """Signal -> the highest time derivative of it the relation or the simulation needs."""
        orders = dict.fromkeys(self.signals, 0)
        for d in set().union(*(e.atoms(sp.Derivative) for e in (self.nominal, *self.rates))):
            name = d.expr.func.__name__
            orders[name] = max(orders.get(name, 0), d.derivative_count)
        return orders

    def __str__(self) -> str:
        rates = "".join(f"\n  d{x}/dt = {f}" for x, f in zip(self.states, self.rates))
        return f"{self.name}: r_n = {self.nominal}{rates}\n  band: r_n over simulations at the parameters' box corners"

    def latex(self) -> str:
        """LaTeX of ``r_n`` and of each simulated state's rate."""
        rates = ", \\quad ".join(f"\\dot{{{sp.latex(sp.Symbol(x))}}} = {latex(f)}"
                                  for x, f in zip(self.states, self.rates))
        return f"r_{{n}} = {latex(self.nominal)}, \\quad {rates}"

    def __getstate__(self) -> dict:
        """Pickled without its numerics (numpy functions made by sympy), rebuilt on first use."""
        return {**self.__dict__, "_simulator": None}

    def prepared(self, record, *, extra: tuple = (), method: str = "savgol", window: int | None = None,
                 polyorder: int = 3, exact: Mapping | None = None, initial="rest"):
        """The record with the simulated states added as columns, and the band ``(lower, upper)`` on ``-r_n``
        as a function of ``r_n`` (see the module)."""
        data = as_record(record, [*self.signals, *extra], name=getattr(record, "name", "record"))
        clash = [x for x in self.states if x in data.columns]
        if clash:
            raise SimulationError(f"{self.name}: the record has a column {clash[0]!r}, the name of a simulated state")
        if self._simulator is None:
            self._simulator = _Simulator(self)
        states, band = self._simulator.run(data, method=method, window=window, polyorder=polyorder, exact=exact,
                                           initial=initial)
        return Record(data.t, {**data.columns, **states}, data.name), band


#: The most corners of the parameters' box simulated together; past it, a fixed sample of them (the band is then
#: the hull of that sample, and says so in a warning).
MAX_CORNERS = 1024
#: The Newton steps that move the nominal rest state to each corner's.
NEWTON_STEPS = 50
#: Interior points of the parameters' box simulated beside the corners (a fixed sample), to tell a residual
#: that is not monotone in its parameters.
INTERIOR_SAMPLES = 32


class _Simulator:
    """The numerics of one simulation residual, built once: its rates and output as numpy functions of the
    states, the deltas and the signals, vectorized over the corners of the parameters' box."""

    def __init__(self, arr: SimulationARR) -> None:
        self.arr = arr
        expressions = (arr.nominal, *arr.rates, *arr.rates_true, _true_output(arr))
        state_atoms = [sp.Function(x)(T) for x in arr.states]
        self.points = sorted({a for e in expressions for a in _point_atoms(e, arr.states)}, key=str)
        self.n = len(arr.states)
        x = [sp.Dummy(f"x{i}", real=True) for i in range(self.n)]
        p = [sp.Dummy(f"u{i}", real=True) for i in range(len(self.points))]
        deltas = sorted({s for e in expressions for s in e.free_symbols if delta_parameter(s) is not None}, key=str)
        d = [sp.Dummy(s.name, real=True) for s in deltas]
        values = {sp.Symbol(name): sp.Float(v) for name, v in arr.values.items()}
        values.update(zip(deltas, d))

        def numeric(expressions):
            plain = [e.xreplace(dict(zip(state_atoms, x))).xreplace(dict(zip(self.points, p))).xreplace(values)
                     for e in expressions]
            return sp.lambdify([*x, *d, *p], plain, modules="numpy", cse=True)

        self.rates = numeric(arr.rates_true)
        self.output = numeric([_true_output(arr)])
        box = [_delta_box(arr, s) for s in deltas]
        self.corners, self.sampled = _corners(box)
        # interior points, a fixed sample: where the residual is not monotone in a parameter they reach past the
        # corners, and the evaluation says so
        lo, hi = np.array(box, dtype=float).reshape(-1, 2).T
        self.interior = lo + (hi - lo) * np.random.default_rng(0).random((INTERIOR_SAMPLES, len(box)))

    def _rates(self, x: np.ndarray, deltas: np.ndarray, at: list) -> np.ndarray:
        """The rates at states ``x`` (corners, n) for the deltas (corners, p) and the signals ``at``."""
        values = self.rates(*x.T, *deltas.T, *at)
        return np.stack([np.broadcast_to(v, x.shape[:1]) for v in values], axis=1)

    def run(self, data: Record, *, method, window, polyorder, exact, initial) -> tuple[dict, Callable]:
        points = [self._values(data, atom, method, window, polyorder, exact) for atom in self.points]
        usable = np.all(np.isfinite(np.array(points)), axis=0) if points else np.ones(len(data), bool)
        start = int(np.argmax(usable)) if usable.any() else len(data)
        nominal = np.full((len(data), self.n), np.nan)
        g_lo, g_hi = np.full(len(data), np.nan), np.full(len(data), np.nan)
        past = 0
        if start < len(data):
            deltas, x, interior = self._initial(initial, [p[start] for p in points])
            past = self._simulate(data.t, points, usable, start, deltas, x, interior, nominal, g_lo, g_hi)
        if self.sampled:
            warnings.warn(f"{self.arr.name}: {len(self.corners)} of the parameters' box's corners simulated (of "
                          f"more than {MAX_CORNERS}): the band is their hull", SimulationWarning, stacklevel=5)
        if past:
            warnings.warn(f"{self.arr.name}: at {past} sample(s) an interior point of the parameters' box reaches past "
                          "the corners (the residual is not monotone in its parameters on this record): the band is "
                          f"the hull of the corners and {INTERIOR_SAMPLES} interior points, not a guaranteed range",
                          SimulationWarning, stacklevel=5)

        def band(residual: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return g_lo - residual, g_hi - residual

        return {x: nominal[:, i] for i, x in enumerate(self.arr.states)}, band

    def _values(self, data: Record, atom, method, window, polyorder, exact) -> np.ndarray:
        if isinstance(atom, sp.Derivative):
            return signal_derivative(data, atom.expr.func.__name__, atom.derivative_count, method=method,
                                     window=window, polyorder=polyorder, exact=exact)
        return data[atom.func.__name__]

    def _simulate(self, t, points, usable, start, deltas, x, interior, nominal, g_lo, g_hi) -> int:
        """Heun's scheme for every trajectory at once (the nominal first); ``g``'s range over them at each sample.
        Returns at how many samples an interior trajectory reached past the corners' range."""
        past = 0
        for k in range(start, len(t)):
            at = [p[k] for p in points]
            if not np.all(np.isfinite(x)):
                return past
            nominal[k] = x[0]
            g = np.broadcast_to(self.output(*x.T, *deltas.T, *at)[0], x.shape[:1])
            g_lo[k], g_hi[k] = np.min(g), np.max(g)
            if interior.any():
                low, high = np.min(g[~interior]), np.max(g[~interior])
                past += bool(g_lo[k] < low - 1e-9 * (high - low) or g_hi[k] > high + 1e-9 * (high - low))
            if k + 1 == len(t) or not usable[k + 1]:
                return past   # the end, or a gap the simulation cannot cross
            h = t[k + 1] - t[k]
            later = [p[k + 1] for p in points]
            k1 = self._rates(x, deltas, at)
            k2 = self._rates(x + h * k1, deltas, later)
            x = x + h / 2 * (k1 + k2)

    def _initial(self, initial, at: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(deltas, states, whether interior) of every trajectory simulated, the nominal first: each corner of
        the parameters' box and each interior point at rest, or the corners of the given initial box with each
        of them."""
        nominal = np.zeros((1, self.corners.shape[1]))
        deltas = np.vstack([nominal, self.corners, self.interior])
        interior = np.arange(len(deltas)) > len(self.corners)
        if isinstance(initial, Mapping):
            lo, hi = self._given(initial)
            starts = np.array(list(itertools.product(*[sorted({a, b}) for a, b in zip(lo, hi)])))
            pairs = np.array(list(itertools.product(range(1, len(deltas)), range(len(starts)))))
            return (np.vstack([nominal, deltas[pairs[:, 0]]]), np.vstack([(lo + hi) / 2, starts[pairs[:, 1]]]),
                    np.concatenate([[False], interior[pairs[:, 0]]]))
        if initial != "rest":
            raise SimulationError(f"{self.arr.name}: initial must be 'rest' or a mapping state -> value or "
                                  f"(lo, hi), got {initial!r}")
        return deltas, self._corner_rests(self._rest(at), deltas, at), interior

    def _given(self, initial: Mapping) -> tuple[np.ndarray, np.ndarray]:
        unknown = [k for k in initial if k not in self.arr.states]
        missing = [x for x in self.arr.states if x not in initial]
        if unknown or missing:
            what = f"no state {unknown[0]!r}" if unknown else f"state {missing[0]!r} not given"
            raise SimulationError(f"{self.arr.name}: initial: {what}; its states are {list(self.arr.states)}")
        bounds = []
        for x in self.arr.states:
            value = initial[x]
            try:
                lo, hi = (value, value) if np.ndim(value) == 0 else (float(value[0]), float(value[1]))
                ok = len(np.atleast_1d(value)) <= 2 and math.isfinite(lo) and math.isfinite(hi) and lo <= hi
            except (TypeError, ValueError, IndexError):
                ok = False
            if not ok:
                raise SimulationError(f"{self.arr.name}: initial[{x!r}] must be a finite value or (lo, hi) with "
                                      f"lo <= hi, got {value!r}")
            bounds.append((float(lo), float(hi)))
        lo, hi = np.array(bounds).T
        return lo, hi

    def _rest(self, at: list) -> np.ndarray:
        """The nominal states at which every rate vanishes for the signals ``at``: the dynamics held at those
        signals followed until they settle (a stable set), then polished by Newton."""
        zero = np.zeros((1, self.corners.shape[1]))

        def rates(x):
            return self._rates(np.asarray(x, dtype=float)[None, :], zero, at)[0]

        guess, elapsed = np.zeros(self.n), 0.0
        for horizon in 10.0 ** np.arange(-2, 9):
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                found = scipy.optimize.root(rates, guess, method="hybr")
                if found.success and np.all(np.isfinite(found.x)) and _settled(rates(found.x), found.x):
                    return found.x
                path = scipy.integrate.solve_ivp(lambda _, x: rates(x), (elapsed, horizon), guess, method="LSODA",
                                                 rtol=1e-8, atol=1e-14)
            if not path.success or not np.all(np.isfinite(path.y[:, -1])):
                break
            guess, elapsed = path.y[:, -1], horizon
        raise SimulationError(f"{self.arr.name}: no rest state of {list(self.arr.states)} for the first sample's "
                              "signals; give initial={state: (lo, hi)}")

    def _corner_rests(self, rest: np.ndarray, deltas: np.ndarray, at: list) -> np.ndarray:
        """Each corner's rest state, by damped Newton steps from the nominal one (finite-difference Jacobians,
        all corners at once)."""
        x = np.repeat(rest[None, :], len(deltas), axis=0)
        scale = np.abs(rest) + 1e-12
        with np.errstate(all="ignore"):
            for _ in range(NEWTON_STEPS):
                f = self._rates(x, deltas, at)
                if np.all(_settled(f, x)):
                    return x
                jacobian = np.empty((len(x), self.n, self.n))
                for j in range(self.n):
                    step = 1e-7 * scale[j]
                    moved = x.copy()
                    moved[:, j] += step
                    jacobian[:, :, j] = (self._rates(moved, deltas, at) - f) / step
                try:
                    move = np.linalg.solve(jacobian, -f[..., None])[..., 0]
                except np.linalg.LinAlgError:
                    break
                size = np.ones(len(x))
                for _ in range(30):   # halve the step of a corner whose rates it does not reduce
                    trial = x + size[:, None] * move
                    worse = ~(np.linalg.norm(self._rates(trial, deltas, at), axis=1) < np.linalg.norm(f, axis=1))
                    if not worse.any():
                        break
                    size = np.where(worse, size / 2, size)
                x = trial
        raise SimulationError(f"{self.arr.name}: the rest state of some corner of the parameters' box was not found "
                              "(no unique rest: an integrator, or an unstable set); give initial={state: (lo, hi)}")


def _settled(rates: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Whether the rates vanish to a relative 1e-12 of the states (per corner)."""
    return np.max(np.abs(rates), axis=-1) <= 1e-12 * (1.0 + np.max(np.abs(x), axis=-1))


def _corners(box: list) -> tuple[np.ndarray, bool]:
    """The corners of the deltas' box (corners, p) and whether they are a sample of them (more than
    :data:`MAX_CORNERS`): then each delta's two ends with the others nominal, the two extreme corners and a
    fixed random sample of the rest."""
    if 2 ** len(box) <= MAX_CORNERS:
        return np.array(list(itertools.product(*box)), dtype=float).reshape(-1, len(box)), False
    p = len(box)
    lo, hi = np.array(box, dtype=float).T
    chosen = [lo, hi]
    for j in range(p):
        for end in (lo[j], hi[j]):
            corner = np.zeros(p)
            corner[j] = end
            chosen.append(corner)
    picks = np.random.default_rng(0).integers(0, 2, size=(MAX_CORNERS - len(chosen), p)).astype(bool)
    chosen.extend(np.where(picks, hi, lo))
    return np.array(chosen), True


def _point_atoms(expression: sp.Expr, states: tuple) -> set:
    """The signals and signal derivatives ``expression`` reads from the record (the states are simulated)."""
    found = {d for d in expression.atoms(sp.Derivative) if d.expr.func.__name__ not in states}
    return found | {f for f in _outside_derivatives(expression) if f.func.__name__ not in states}


def _outside_derivatives(expression: sp.Expr) -> set:
    """The functions of time that appear outside any derivative."""
    if isinstance(expression, sp.Derivative):
        return set()
    if isinstance(expression, AppliedUndef):
        return {expression}
    return set().union(*(_outside_derivatives(a) for a in expression.args))


def _true_output(arr: SimulationARR) -> sp.Expr:
    """``g`` with theta (1 + delta_theta): the nominal residual plus its uncertain part."""
    return arr.nominal + arr.uncertain


def _delta_box(arr: SimulationARR, delta: sp.Symbol) -> tuple[np.float64, np.float64]:
    lo, hi = arr.uncertainties[delta_parameter(delta)]
    return np.float64(lo), np.float64(hi)
