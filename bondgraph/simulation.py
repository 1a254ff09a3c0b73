"""Simulation of bond graph state equations with ``scipy.integrate.solve_ivp``.

Inputs are given per signal name as

* a number (constant input),
* a callable ``u(t)``,
* a callable ``u(t, y)`` of time and the measured signals ``y`` (a dict), so a
  feedback law can close around the model, or
* a controller object with states (see :mod:`bondgraph.control`).

Parameters may be overridden by numbers or by callables of time (a degrading
parameter, say).  The result holds every effort, flow, state and signal.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from ._optional import pandas_for
from .equations import StateEquations
from .errors import SimulationError
from .model import BondGraph
from .structure import T, signal_function


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
) -> SimulationResult:
    """Simulate a bond graph from its state equations.

    Parameters
    ----------
    model : BondGraph or StateEquations
    t_span : (t0, t1)
    inputs : mapping, optional
        Signal name -> number, ``u(t)``, ``u(t, y)`` or controller.  Sources
        with a constant ``value`` need no entry.
    x0 : mapping, optional
        Initial state by state name (``q_C``) or element name (``C``); default 0.
    parameters : mapping, optional
        Parameter name -> value or callable of t, overriding nominal values.
    t_eval : array, optional
        Output times; default 501 points over ``t_span``.
    method, rtol, atol, max_step
        Passed to :func:`scipy.integrate.solve_ivp`.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> result = simulate(rlc_circuit(), (0.0, 0.5), {"V": 1.0})
    >>> round(float(result["v_C"][-1]), 3)
    1.0
    """
    equations = model.state_equations() if isinstance(model, BondGraph) else model
    sources = model.elements if isinstance(model, BondGraph) else {}
    plan = _Plan(equations, inputs or {}, parameters or {}, sources)
    x0_vector = _initial_state(equations, x0 or {})
    z0 = np.concatenate([x0_vector] + [np.asarray(c.initial_state(), float) for c in plan.controllers.values()])
    if t_eval is None:
        t_eval = np.linspace(t_span[0], t_span[1], 501)
    with np.errstate(invalid="ignore", divide="ignore"):  # Piecewise laws evaluate unselected branches too
        solution = solve_ivp(plan.derivative, t_span, z0, method=method, t_eval=t_eval,
                             rtol=rtol, atol=atol, max_step=max_step)
    if not solution.success:
        failed_at = solution.t[-1] if solution.t.size else t_span[0]
        raise SimulationError(f"integration failed at t = {failed_at}: {solution.message}")
    if not np.all(np.isfinite(solution.y)):
        k = int(np.argmax(~np.all(np.isfinite(solution.y), axis=0)))
        raise SimulationError(f"the state became NaN or infinite at t = {solution.t[k]:g}; "
                              "check the laws and parameters")
    return plan.result(solution)


def _initial_state(equations: StateEquations, x0: Mapping) -> np.ndarray:
    names = [str(s) for s in equations.states]
    by_element = {str(e): i for i, e in enumerate(equations.elements)}
    vector = np.zeros(len(names))
    for key, value in x0.items():
        index = names.index(str(key)) if str(key) in names else by_element.get(str(key))
        if index is None:
            raise SimulationError(f"x0: {key!r} is not a state; states are {names} (or elements {list(by_element)})")
        vector[index] = float(value)
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
                try:
                    value = float(spec)
                except (TypeError, ValueError):
                    raise SimulationError(f"input {name!r}: {spec!r} is not a number, a callable "
                                          "or a controller") from None
                self.open_loop[name] = lambda t, v=value: v
        unknown = set(parameters) - set(equations.parameters)
        if unknown:
            raise SimulationError(f"parameters {sorted(unknown)} are not in the model; "
                                  f"it has {sorted(equations.parameters)}")
        self.parameter_names = list(equations.parameters)
        self.parameter_values = {**equations.parameters, **parameters}
        self.input_names = names
        self._compile()

    def _compile(self) -> None:
        eq = self.equations
        u_symbols = [sp.Symbol(f"_u_{name}") for name in self.input_names]
        to_symbol = {signal_function(name): s for name, s in zip(self.input_names, u_symbols)}
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

        self.f_rhs, _ = compile_list(eq.rhs, [f"d{x}/dt" for x in eq.states])
        self.output_names = list(eq.outputs)
        self.f_outputs, outputs = compile_list(eq.outputs.values(), [f"signal {n!r}" for n in eq.outputs])
        closed = {to_symbol[signal_function(n)] for n in (*self.feedback, *self.controllers)}
        for name, expression in zip(self.output_names, outputs):
            if expression.free_symbols & closed:
                raise SimulationError(
                    f"measured signal {name!r} depends directly on a feedback input; the loop is algebraic"
                )
        self.labels = list(eq.efforts)
        what = [f"effort of bond {k}" for k in eq.efforts] + [f"flow of bond {k}" for k in eq.flows]
        self.f_bonds, _ = compile_list([*eq.efforts.values(), *eq.flows.values()], what)

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
