"""Simulation of bond graph state equations with ``scipy.integrate.solve_ivp``.

Inputs are given per signal name as

* a number (constant input),
* a callable ``u(t)``,
* a callable ``u(t, y)`` of time and the measured signals ``y`` (a dict), so a
  feedback law can close around the model, or
* a controller object with states (see :mod:`bondgraph.control`).

Parameters may be overridden by numbers or by callables of time (a degrading
parameter, say).  The result holds every effort, flow, state and signal.

Limits
------
:func:`simulate` refuses, with a :class:`~bondgraph.errors.SimulationError` naming the argument,
what would hang, exhaust memory or silently give a wrong answer:

* ``t_span`` must be a pair of finite numbers with ``t_end > t_start`` and a span of at least
  :data:`MIN_SPAN` seconds and at least :data:`SPAN_RTOL` times ``max(|t_start|, |t_end|)``: below
  that the solver cannot advance the time in floating point (LSODA then calls the model forever)
  and the output times are no longer distinct.
* ``t_eval`` must hold finite, strictly increasing times within ``t_span``, at most
  :data:`MAX_SAMPLES` of them (:func:`check_sample_count`, which a caller can use before it builds
  the time grid).
* An input or parameter given as a constant must be a finite real number, not a string.
* The integration stops with an error when a derivative is NaN or infinite (a zero inertia,
  capacitance or inductance divides by zero), when :data:`STALL_EVALUATIONS` evaluations in a row
  are at the same time (the solver's step has collapsed below the spacing of floats: LSODA then
  retries forever), and after ``max_evaluations`` (default :data:`MAX_EVALUATIONS`) evaluations of
  the model in all (a step so small that the time crawls), or earlier, from :data:`PACE_START`
  evaluations on, when the pace so far projects more than :data:`PACE_MARGIN` times
  ``max_evaluations`` to reach ``t_end`` (an undamped oscillator over a million periods).
* When LSODA (the default method) gives up (repeated convergence failures on a very stiff model,
  an open circuit ``R = 1e12`` say), the integration is done again with the implicit ``Radau``
  method, with a :class:`SimulationWarning`; when that fails too, the error names both failures.
"""

from __future__ import annotations

import inspect
import math
import numbers
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from .optional import pandas_for
from .equations import StateEquations
from .errors import PHMWarning, SimulationError
from .model import BondGraph
from .structure import T, signal_function

__all__ = [
    "DEFAULT_T_END", "FALLBACK_METHOD", "MAX_EVALUATIONS", "MAX_SAMPLES", "MIN_SPAN", "OUTPUT_SAMPLES", "PACE_MARGIN",
    "PACE_START", "SPAN_RTOL",
    "STALL_EVALUATIONS", "SimulationResult", "SimulationWarning", "check_sample_count", "simulate",
]


@dataclass
class SimulationResult:
    """Trajectories of a simulation.

    Attributes
    ----------
    t : ndarray, shape (n,)
    states : dict
        State name (``q_C``, ``p_L``) -> trajectory.
    efforts, flows : dict
        Bond label -> trajectory.
    signals : dict
        Input and measured signal name -> trajectory.
    controller_states : dict
        Input name -> array (n, n_states) of controller states.
    solver : object
        The ``solve_ivp`` result (``nfev``, ``message``...).

    Examples
    --------
    Returned by :func:`simulate`:

    >>> from bondgraph.library import rlc_circuit
    >>> result = simulate(rlc_circuit(), (0.0, 0.1), {"V": 1.0}, t_eval=np.linspace(0.0, 0.1, 6))
    >>> np.round(result.t, 3).tolist()
    [0.0, 0.02, 0.04, 0.06, 0.08, 0.1]
    >>> list(result.signals), list(result.states), list(result.efforts)
    (['V', 'i', 'v_C'], ['p_L', 'q_C'], [1, 2, 3, 4, 5])
    >>> np.round(result["v_C"], 3).tolist()   # underdamped: overshoots, settles at the source voltage
    [0.0, 0.849, 1.153, 1.002, 0.979, 1.002]
    >>> bool(np.allclose(result.flows[5], result["i"])), result.solver.success
    (True, True)
    >>> sorted(result.record())
    ['V', 'i', 't', 'v_C']
    """

    t: np.ndarray
    states: dict
    efforts: dict
    flows: dict
    signals: dict
    controller_states: dict = field(default_factory=dict)
    solver: object = None

    def __getitem__(self, name: str) -> np.ndarray:
        """A signal or state trajectory by name."""
        for table in (self.signals, self.states):
            if name in table:
                return table[name]
        raise KeyError(f"no signal or state {name!r}; signals: {sorted(self.signals)}, states: {sorted(self.states)}")

    def record(self) -> dict[str, np.ndarray]:
        """The measured and input signals with the time column ``t``, as data files hold them."""
        return {"t": self.t, **self.signals}

    def to_frame(self):
        """The time, every signal and every state as a pandas DataFrame (pandas imported on demand).

        Columns: ``t`` (a column, with the default integer index, as in :meth:`record`), then the
        signals (inputs and measured outputs) in the result's order, then the states; a state named
        like a signal is left out, as ``result[name]`` gives the signal.  Bond efforts and flows are
        in :attr:`efforts` and :attr:`flows`.

        >>> from bondgraph.library import rlc_circuit
        >>> frame = simulate(rlc_circuit(), (0.0, 0.5), {"V": 1.0}, t_eval=np.linspace(0, 0.5, 11)).to_frame()
        >>> list(frame.columns)
        ['t', 'V', 'i', 'v_C', 'p_L', 'q_C']
        >>> frame.shape
        (11, 6)
        """
        pd = pandas_for("to_frame")
        columns = {"t": self.t, **self.signals}
        columns.update((name, values) for name, values in self.states.items() if name not in columns)
        return pd.DataFrame(columns)


#: The shortest simulated span (s): nothing a bond graph in seconds models happens faster than a picosecond.
MIN_SPAN = 1e-12
#: The shortest span relative to ``max(|t_start|, |t_end|)``: about 4.5e6 floating-point steps, so the
#: solver can advance and 501 default output times stay distinct.
SPAN_RTOL = 1e-9
#: The most output times (``t_eval``) of one simulation: each trajectory (one per state, bond effort,
#: bond flow and signal) of that many samples takes 80 MB.
#: a written simulation's samples by default (``bgphm simulate``), and its horizon (s) when the model has none
OUTPUT_SAMPLES, DEFAULT_T_END = 501, 1.0
MAX_SAMPLES = 10_000_000
#: Evaluations of the model in a row at the same time (within 4 units in the last place) before the
#: integration is declared stalled: a Jacobian estimate takes one per state and Newton iterations a
#: handful, while a solver whose step no longer moves the time in floating point calls forever.
STALL_EVALUATIONS = 10_000
#: The default most evaluations of the model in one simulation (``max_evaluations``): about 20 s of
#: work for a small model; the examples and tests need at most about 25 000.
MAX_EVALUATIONS = 1_000_000
#: Evaluations after which the pace of the integration is judged (see :data:`PACE_MARGIN`).
PACE_START = 20_000
#: An integration is stopped early when, at its pace so far, reaching ``t_end`` would take more than this
#: many times ``max_evaluations``: a hopeless run then ends in about a second, not at the limit.  The margin
#: leaves room for a solver that is slow at first (a fast transient) and speeds up later.
PACE_MARGIN = 2.0
#: The method tried again when LSODA gives up: implicit and L-stable, it integrates the very stiff models
#: (an open circuit, a tiny capacitance) on which LSODA's switching fails.
FALLBACK_METHOD = "Radau"


class SimulationWarning(PHMWarning):
    """A simulation that succeeded differently than asked (another solver method, say)."""


def simulate(
    model: BondGraph | StateEquations,
    t_span: tuple[float, float],
    inputs: Mapping | None = None,
    *,
    x0: Mapping | None = None,
    parameters: Mapping | None = None,
    t_eval: np.ndarray | None = None,
    method: str = "LSODA",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    max_step: float = np.inf,
    max_evaluations: int = MAX_EVALUATIONS,
) -> SimulationResult:
    """Simulate a bond graph from its state equations.

    Parameters
    ----------
    model : BondGraph or StateEquations
    t_span : (t0, t1)
        Finite, ``t1 > t0``, a span of at least :data:`MIN_SPAN` and :data:`SPAN_RTOL` times
        ``max(|t0|, |t1|)``.
    inputs : mapping, optional
        Signal name -> number, ``u(t)``, ``u(t, y)`` or controller.  Sources
        with a constant ``value`` need no entry.
    x0 : mapping, optional
        Initial state by state name (``q_C``) or element name (``C``); default 0.
    parameters : mapping, optional
        Parameter name -> value or callable of t, overriding nominal values.
    t_eval : array, optional
        Output times, strictly increasing within ``t_span``, at most :data:`MAX_SAMPLES`;
        default 501 points over ``t_span``.
    method, rtol, atol, max_step
        Passed to :func:`scipy.integrate.solve_ivp`.
    max_evaluations : int, optional
        The most evaluations of the model's derivatives before the integration is stopped.

    Raises
    ------
    SimulationError
        Naming the argument at fault (see the module's Limits), or when the integration fails, stalls,
        meets a NaN or infinite derivative or exceeds ``max_evaluations``.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> result = simulate(rlc_circuit(), (0.0, 0.5), {"V": 1.0})
    >>> round(float(result["v_C"][-1]), 3)
    1.0
    >>> simulate(rlc_circuit(), (0.5, 0.0), {"V": 1.0})
    Traceback (most recent call last):
    ...
    bondgraph.errors.SimulationError: t_span: t_end = 0.0 is not after t_start = 0.5
    """
    t0, t1 = _checked_span(t_span)
    equations = model.state_equations() if isinstance(model, BondGraph) else model
    sources = model.elements if isinstance(model, BondGraph) else {}
    plan = _Plan(equations, inputs or {}, parameters or {}, sources)
    x0_vector = _initial_state(equations, x0 or {})
    z0 = np.concatenate([x0_vector] + [np.asarray(c.initial_state(), float) for c in plan.controllers.values()])
    t_eval = np.linspace(t0, t1, 501) if t_eval is None else _checked_times(t_eval, t0, t1)
    limit = _checked_count(max_evaluations, "max_evaluations")
    _check_max_step(max_step, t1 - t0, limit)
    solution = _integrate(plan, (t0, t1), z0, t_eval, limit, method=method, rtol=rtol, atol=atol,
                          max_step=max_step)
    if not np.all(np.isfinite(solution.y)):
        k = int(np.argmax(~np.all(np.isfinite(solution.y), axis=0)))
        raise SimulationError(f"the state became NaN or infinite at t = {solution.t[k]:g}; "
                              "check the laws and parameters")
    return plan.result(solution)


def _integrate(plan: "_Plan", span: tuple[float, float], z0: np.ndarray, t_eval: np.ndarray, limit: int,
               *, method: str, **options) -> object:
    """``solve_ivp`` under a :class:`_Guard`; LSODA's failure is retried with :data:`FALLBACK_METHOD`.

    Raises a SimulationError naming the method(s), the time reached and the solver's message when the
    integration fails; the retry gets the evaluations the first attempt left.
    """
    guard = _Guard(plan, limit, span)
    solution = _solve(guard, span, z0, t_eval, method, options)
    if solution.success:
        return solution
    failure = f"{method} failed at t = {guard.furthest:g} of {span[1]:g}: {solution.message}"
    if method != "LSODA" or guard.evaluations >= limit:
        raise SimulationError(f"the integration {failure} (a very stiff model? check the parameters, or try "
                              f"method={FALLBACK_METHOD!r})")
    retry = _Guard(plan, limit - guard.evaluations, span)
    solution = _solve(retry, span, z0, t_eval, FALLBACK_METHOD, options)
    if not solution.success:
        raise SimulationError(f"the integration {failure}, and {FALLBACK_METHOD} failed at t = {retry.furthest:g}: "
                              f"{solution.message} (check the parameters: a value that makes the model extremely "
                              "stiff or singular?)")
    warnings.warn(f"{failure}; integrated with {FALLBACK_METHOD} instead", SimulationWarning, stacklevel=3)
    return solution


def _solve(guard: "_Guard", span, z0, t_eval, method: str, options: dict) -> object:
    """One ``solve_ivp`` run; LSODA's warning on a failure goes into the result's message, not to the user.

    LSODA says why it failed only in a warning ("Repeated convergence failures..."); its result's
    message is a bare "Unexpected istate in LSODA."  Other warnings (from an input callable, say) are
    issued again as they came.
    """
    with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # Piecewise laws evaluate unselected branches too: hence the errstate
        solution = solve_ivp(guard, span, z0, method=method, t_eval=t_eval, **options)
    reasons, others = [], {}
    for w in caught:
        if str(w.message).startswith("lsoda:"):
            reasons.append(str(w.message).removeprefix("lsoda:").strip().rstrip("."))
        else:  # once each, as the default filter would have shown them: an input may warn at every call
            others.setdefault((w.category, str(w.message), w.filename, w.lineno), w)
    for w in others.values():
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)
    if reasons and not solution.success:
        solution.message = "; ".join(dict.fromkeys(reasons))
    return solution


def check_sample_count(count: object, option: str = "t_eval", least: int = 1) -> int:
    """The number of output samples ``count`` as an int, or a SimulationError naming ``option``.

    At least ``least`` (a written trajectory wants 3: a start, an end and a point between) and at
    most :data:`MAX_SAMPLES`; a caller that builds the time grid (a command line's
    ``--samples``, say) checks the count first, so a typo does not allocate gigabytes.

    Examples
    --------
    >>> check_sample_count(1001)
    1001
    >>> check_sample_count(10**8, "--samples")
    Traceback (most recent call last):
    ...
    bondgraph.errors.SimulationError: --samples: 100000000 samples is more than the limit of 10000000 (MAX_SAMPLES)
    """
    if isinstance(count, bool) or not isinstance(count, numbers.Real) or count != int(count) or count < least:
        raise SimulationError(f"{option}: the number of samples must be a whole number >= {least}, got {count!r}")
    if count > MAX_SAMPLES:
        raise SimulationError(f"{option}: {int(count)} samples is more than the limit of {MAX_SAMPLES} (MAX_SAMPLES)")
    return int(count)


def _checked_span(t_span: object) -> tuple[float, float]:
    """``(t0, t1)`` as floats: a pair of finite numbers, long enough for the solver to advance."""
    if isinstance(t_span, (str, bytes)) or not hasattr(t_span, "__len__") or len(t_span) != 2:
        raise SimulationError(f"t_span: expected a pair (t_start, t_end) of numbers, got {t_span!r}")
    t0, t1 = (_real(value, f"t_span[{i}]") for i, value in enumerate(t_span))
    if t1 <= t0:
        raise SimulationError(f"t_span: t_end = {t1!r} is not after t_start = {t0!r}")
    shortest = max(MIN_SPAN, SPAN_RTOL * max(abs(t0), abs(t1)))
    if t1 - t0 < shortest:
        raise SimulationError(f"t_span: the span {t1 - t0:g} s from t = {t0:g} is shorter than {shortest:g} s "
                              f"(MIN_SPAN = {MIN_SPAN:g} s, SPAN_RTOL = {SPAN_RTOL:g} of |t|): the solver "
                              "cannot advance the time in floating point")
    return t0, t1


def _checked_times(t_eval: object, t0: float, t1: float) -> np.ndarray:
    """The output times as a float array: finite, strictly increasing, within the span, not too many."""
    try:
        times = np.asarray(t_eval, dtype=float)
    except (TypeError, ValueError):
        raise SimulationError(f"t_eval: expected an array of times, got {type(t_eval).__name__}") from None
    if times.ndim != 1:
        raise SimulationError(f"t_eval: expected a one-dimensional array of times, got shape {times.shape}")
    check_sample_count(times.size, "t_eval")
    bad = np.flatnonzero(~np.isfinite(times))
    if bad.size:
        raise SimulationError(f"t_eval: t_eval[{bad[0]}] = {times[bad[0]]} is not finite")
    outside = np.flatnonzero((times < t0) | (times > t1))
    if outside.size:
        i = int(outside[0])
        raise SimulationError(f"t_eval: t_eval[{i}] = {float(times[i])!r} is outside t_span [{t0!r}, {t1!r}]")
    back = np.flatnonzero(np.diff(times) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise SimulationError(f"t_eval: not strictly increasing: t_eval[{i}] = {float(times[i])!r} follows "
                              f"t_eval[{i - 1}] = {float(times[i - 1])!r}")
    return times


def _checked_count(value: object, option: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise SimulationError(f"{option}: expected a whole number >= 1, got {value!r}")
    return int(value)


def _check_max_step(max_step: object, span: float, limit: int) -> None:
    """A positive ``max_step`` that does not need more steps than ``limit`` evaluations allow."""
    if isinstance(max_step, (bool, np.bool_)) or not isinstance(max_step, numbers.Real) or not max_step > 0:
        raise SimulationError(f"max_step: expected a positive number of seconds (or inf), got {max_step!r}")
    if span / max_step > limit:
        raise SimulationError(f"max_step: {max_step:g} s needs at least {span / max_step:.3g} steps over the span "
                              f"of {span:g} s, more than max_evaluations = {limit}")


def _real(value: object, what: str) -> float:
    """A finite real number (a numpy scalar or 0-d array too, never a string or a bool) as a float."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise SimulationError(f"{what}: expected a number, got {value!r} ({type(value).__name__})")
    number = float(value)
    if not math.isfinite(number):
        raise SimulationError(f"{what}: {number} is not a finite number")
    return number


def _constant(value: object, what: str, expected: str) -> float:
    """A constant given for ``what`` as a float, or a SimulationError saying what was ``expected``."""
    try:
        return _real(value, what)
    except SimulationError as exc:
        if "finite" in str(exc):
            raise
        raise SimulationError(f"{what}: expected {expected}, got {value!r} ({type(value).__name__})") from None


class _Guard:
    """The model's derivatives for ``solve_ivp``, stopping an integration that cannot succeed.

    Counts the evaluations; raises a SimulationError at a NaN or infinite derivative, after
    :data:`STALL_EVALUATIONS` evaluations in a row at the same time, and after ``limit`` evaluations
    in all.  Without it LSODA calls the model forever once its step collapses.
    """

    def __init__(self, plan: "_Plan", limit: int, span: tuple[float, float]):
        self.plan, self.limit = plan, limit
        self.t_start, self.t_end = span
        self.names = [f"d{x}/dt" for x in plan.equations.states]
        for name, controller in plan.controllers.items():
            self.names += [f"the derivative of state {k} of the controller of {name!r}"
                           for k in range(controller.n_states)]
        self.evaluations = 0
        self.furthest = -math.inf
        self.anchor, self.stalled = math.nan, 0  # the time of the current run of evaluations, its length

    def __call__(self, t: float, z: np.ndarray) -> np.ndarray:
        self.evaluations += 1
        self.furthest = max(self.furthest, t)
        if abs(t - self.anchor) <= 4 * math.ulp(self.anchor):
            self.stalled += 1
        else:
            self.anchor, self.stalled = t, 0
        if self.stalled >= STALL_EVALUATIONS:
            raise SimulationError(f"the integration makes no progress at t = {float(t)!r}: {STALL_EVALUATIONS} "
                                  "evaluations of the model in a row at that time (the solver's step has "
                                  "collapsed; a stiff or degenerate model? check the parameters or try "
                                  "method='BDF')")
        if self.evaluations > self.limit:
            raise SimulationError(f"max_evaluations: the integration evaluated the model {self.limit} times and "
                                  f"reached only t = {self.furthest:g} of {self.t_end:g}; pass a larger "
                                  "max_evaluations or check the model for stiffness")
        if self.evaluations >= PACE_START and self.evaluations % 1000 == 0:
            self._check_pace()
        dz = self.plan.derivative(t, z)
        if not np.all(np.isfinite(dz)):
            k = int(np.flatnonzero(~np.isfinite(dz))[0])
            raise SimulationError(f"{self.names[k]} is {dz[k]} at t = {t:g}; check the laws and parameters "
                                  "(a parameter that divides, such as an inertia or a capacitance, set to zero?)")
        return dz


    def _check_pace(self) -> None:
        """Stop a run that, at its pace so far, needs more than PACE_MARGIN times the evaluations allowed."""
        done = (self.furthest - self.t_start) / (self.t_end - self.t_start)
        if done * PACE_MARGIN * self.limit >= self.evaluations:
            return
        needed = self.evaluations / done if done > 0 else math.inf
        raise SimulationError(f"max_evaluations: {self.evaluations} evaluations of the model reached only "
                              f"t = {self.furthest:g} of {self.t_end:g}; at that pace the span needs about "
                              f"{needed:.2g}, more than {PACE_MARGIN:g} times max_evaluations = {self.limit} "
                              "(a long span for the model's fastest motion, or a stiff model: shorten the "
                              "span, pass a larger max_evaluations or check the parameters)")


def _initial_state(equations: StateEquations, x0: Mapping) -> np.ndarray:
    names = [str(s) for s in equations.states]
    by_element = {str(e): i for i, e in enumerate(equations.elements)}
    vector = np.zeros(len(names))
    for key, value in x0.items():
        index = names.index(str(key)) if str(key) in names else by_element.get(str(key))
        if index is None:
            raise SimulationError(f"x0: {key!r} is not a state; states are {names} (or elements {list(by_element)})")
        vector[index] = _constant(value, f"x0[{key!r}]", "a number")
    return vector


def _arity(function: Callable) -> int:
    try:
        params = inspect.signature(function).parameters.values()
    except (TypeError, ValueError):
        return 1
    positional = [p for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.default is p.empty]
    return len(positional)


class _Plan:
    """Compiled numeric functions and the input schedule of one simulation."""

    def __init__(self, equations: StateEquations, inputs: Mapping, parameters: Mapping, sources: Mapping):
        self.equations = equations
        self.n = len(equations.states)
        names = list(equations.inputs)
        unknown = set(inputs) - set(names)
        if unknown:
            raise SimulationError(f"inputs {sorted(unknown)} are not inputs of the model; its inputs are {names}")
        constants = {e.signal: e.value for e in sources.values() if getattr(e, "value", None) is not None and e.signal}
        self.open_loop: dict[str, Callable] = {}
        self.feedback: dict[str, Callable] = {}
        self.controllers: dict[str, object] = {}
        for name in names:
            spec = inputs.get(name, constants.get(name))
            if spec is None:
                raise SimulationError(f"no value for input {name!r}; pass inputs={{{name!r}: ...}}")
            if hasattr(spec, "output") and hasattr(spec, "derivative"):
                self.controllers[name] = spec
            elif callable(spec):
                (self.feedback if _arity(spec) >= 2 else self.open_loop)[name] = spec
            else:
                value = _constant(spec, f"input {name!r}", "a number, a callable u(t) or u(t, y), or a controller")
                self.open_loop[name] = lambda t, v=value: v
        unknown = set(parameters) - set(equations.parameters)
        if unknown:
            raise SimulationError(f"parameters {sorted(unknown)} are not in the model; "
                                  f"it has {sorted(equations.parameters)}")
        self.parameter_names = list(equations.parameters)
        overrides = {k: v if callable(v) else _constant(v, f"parameter {k!r}", "a number or a callable of t")
                     for k, v in parameters.items()}
        self.parameter_values = {**equations.parameters, **overrides}
        self.input_names = names
        self._compile()

    def _compile(self) -> None:
        eq = self.equations
        u_symbols = [sp.Symbol(f"_u_{name}") for name in self.input_names]
        to_symbol = {signal_function(name): s for name, s in zip(self.input_names, u_symbols)}
        # a sweep simulates one model's equations many times: lambdify once (the expressions are in the
        # key, so equations edited in place are compiled afresh)
        key = (tuple(self.input_names), tuple(self.parameter_names), tuple(eq.states), tuple(eq.rhs),
               tuple(eq.outputs.items()), tuple(eq.efforts.items()), tuple(eq.flows.items()))
        if key not in eq.compiled:
            eq.compiled[key] = self._lambdified(to_symbol, u_symbols)
        self.f_rhs, self.f_outputs, outputs, self.f_bonds = eq.compiled[key]
        self.output_names = list(eq.outputs)
        self.labels = list(eq.efforts)
        closed = {to_symbol[signal_function(n)] for n in (*self.feedback, *self.controllers)}
        for name, expression in zip(self.output_names, outputs):
            if expression.free_symbols & closed:
                raise SimulationError(
                    f"measured signal {name!r} depends directly on a feedback input; the loop is algebraic"
                )

    def _lambdified(self, to_symbol: dict, u_symbols: list) -> tuple:
        """The right-hand sides, outputs (with their expressions in plain input symbols) and bond variables."""
        eq = self.equations
        theta = [sp.Symbol(name) for name in self.parameter_names]
        args = (T, eq.states, u_symbols, theta)

        def compile_list(expressions, names):
            expressions = [sp.sympify(x) for x in expressions]
            for name, expression in zip(names, expressions):
                if expression.has(sp.Derivative):
                    derivatives = ", ".join(sorted(map(str, expression.atoms(sp.Derivative))))
                    raise SimulationError(
                        f"{name} needs {derivatives}: a storage element in derivative causality is driven "
                        "directly by an input; simulate with a smooth input model instead"
                    )
            expressions = [x.xreplace(to_symbol) for x in expressions]
            return sp.lambdify(args, expressions, modules="numpy", cse=True), expressions

        f_rhs, _ = compile_list(eq.rhs, [f"d{x}/dt" for x in eq.states])
        f_outputs, outputs = compile_list(eq.outputs.values(), [f"signal {n!r}" for n in eq.outputs])
        what = [f"effort of bond {k}" for k in eq.efforts] + [f"flow of bond {k}" for k in eq.flows]
        f_bonds, _ = compile_list([*eq.efforts.values(), *eq.flows.values()], what)
        return f_rhs, f_outputs, outputs, f_bonds

    def _theta(self, t):
        return [v(t) if callable(v) else v for v in (self.parameter_values[n] for n in self.parameter_names)]

    def _inputs(self, t, x, z_controllers, theta):
        u = {name: 0.0 for name in self.input_names}
        for name, function in self.open_loop.items():
            u[name] = function(t)
        y = {}
        if self.feedback or self.controllers:
            values = self.f_outputs(t, x, [u[n] for n in self.input_names], theta)
            y = dict(zip(self.output_names, values))
            offset = 0
            for name, controller in self.controllers.items():
                k = controller.n_states
                u[name] = controller.output(t, z_controllers[offset:offset + k], y)
                offset += k
            for name, function in self.feedback.items():
                u[name] = function(t, y)
        return [u[n] for n in self.input_names], y

    def derivative(self, t, z):
        x, zc = z[: self.n], z[self.n:]
        theta = self._theta(t)
        u, y = self._inputs(t, x, zc, theta)
        dx = np.asarray(self.f_rhs(t, x, u, theta), dtype=float).reshape(-1)
        parts = [dx]
        offset = 0
        for controller in self.controllers.values():
            k = controller.n_states
            parts.append(np.asarray(controller.derivative(t, zc[offset:offset + k], y), float).reshape(-1))
            offset += k
        return np.concatenate(parts)

    def _history_per_sample(self, t, z, samples) -> tuple[np.ndarray, np.ndarray]:
        """Inputs (m, K) and parameters (p, K) at ``samples``, one call of every callable per sample."""
        u = np.empty((len(self.input_names), len(samples)))
        theta = np.empty((len(self.parameter_names), len(samples)))
        for j, k in enumerate(samples):
            theta[:, j] = self._theta(t[k])
            u[:, j] = self._inputs(t[k], z[: self.n, k], z[self.n:, k], list(theta[:, j]))[0]
        return u, theta

    def _history_vectorized(self, t, z) -> tuple[np.ndarray, np.ndarray]:
        """The same, calling each callable once with all samples (raises if one cannot take arrays)."""
        n_t = t.size

        def column(value):
            out = np.asarray(value, float)
            if out.shape not in ((), (n_t,)):
                raise ValueError("not vectorized")
            return np.broadcast_to(out, (n_t,))

        theta = np.array([column(v(t) if callable(v) else v)
                          for v in (self.parameter_values[n] for n in self.parameter_names)]).reshape(-1, n_t)
        u = {name: np.zeros(n_t) for name in self.input_names}
        for name, function in self.open_loop.items():
            u[name] = column(function(t))
        if self.feedback or self.controllers:
            values = self.f_outputs(t, z[: self.n], [u[n] for n in self.input_names], list(theta))
            y = {name: column(v) for name, v in zip(self.output_names, values)}
            offset = self.n
            for name, controller in self.controllers.items():
                u[name] = column(controller.output(t, z[offset:offset + controller.n_states], y))
                offset += controller.n_states
            for name, function in self.feedback.items():
                u[name] = column(function(t, y))
        return np.array([u[n] for n in self.input_names]).reshape(-1, n_t), theta

    def result(self, solution) -> SimulationResult:
        t, z = solution.t, solution.y
        n_t = t.size
        # inputs and time-varying parameters may be arbitrary Python callables: call them with all
        # samples at once when they accept arrays and agree with per-sample calls on a few samples
        try:
            with np.errstate(all="ignore"):
                u_history, theta_history = self._history_vectorized(t, z)
            spot = sorted({0, n_t // 2, n_t - 1}) if n_t else []
            u_spot, theta_spot = self._history_per_sample(t, z, spot)
            if not (np.allclose(u_history[:, spot], u_spot, rtol=1e-12, atol=0, equal_nan=True)
                    and np.allclose(theta_history[:, spot], theta_spot, rtol=1e-12, atol=0, equal_nan=True)):
                raise ValueError("vectorized and per-sample calls disagree")
        except (TypeError, ValueError, IndexError, AttributeError):
            u_history, theta_history = self._history_per_sample(t, z, range(n_t))
        u_history, theta_history = list(u_history), list(theta_history)

        def evaluate(function):
            with np.errstate(invalid="ignore", divide="ignore"):  # numpy evaluates every Piecewise branch
                values = function(t, z[: self.n], u_history, theta_history)
            return [np.broadcast_to(np.asarray(v, float), (n_t,)).copy() for v in values]

        bonds = evaluate(self.f_bonds)
        m = len(self.labels)
        signals = {name: np.array(values) for name, values in zip(self.input_names, u_history)}
        signals.update(zip(self.output_names, evaluate(self.f_outputs)))
        controller_states, offset = {}, self.n
        for name, controller in self.controllers.items():
            controller_states[name] = z[offset:offset + controller.n_states].T
            offset += controller.n_states
        return SimulationResult(
            t=t,
            states={str(s): z[i] for i, s in enumerate(self.equations.states)},
            efforts=dict(zip(self.labels, bonds[:m])),
            flows=dict(zip(self.labels, bonds[m:])),
            signals=signals,
            controller_states=controller_states,
            solver=solution,
        )
