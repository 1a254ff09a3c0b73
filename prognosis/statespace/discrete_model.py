"""Discrete-time state-space models for joint state-parameter estimation.

A model comes from explicit state equations ``dx/dt = F(x, u, theta)`` with
outputs ``z = G(x, u, theta)`` given as sympy expressions (the bond graph's
``state_equations()`` in integral causality, or any object with ``states``,
``rhs``, ``inputs``, ``outputs`` and ``parameters``).  Parameters listed in
``augment`` become states with the "assistant" dynamics of Du et al. (n.d.), eqs. (3)
and (62): ``theta_k = theta_{k-1}`` (plus the filter's process noise), so a
filter estimates a drifting parameter whose law is unknown.

Discretization over a step ``dt`` with the input held (zero-order hold):

* ``"euler"`` (Du et al. (n.d.), eq. 59): ``x_k = x_{k-1} + dt F(x_{k-1}, u_{k-1})``;
* ``"rk4"``: the classical Runge-Kutta step.

Jacobians for the EKF are derived with sympy (``dF/dx``, ``dG/dx``) and
chained through the discretization exactly (``I + dt J`` for Euler, the stage
rule for RK4), with no finite differences.  ``d|e|/de = sign(e)`` and
``d sign(e)/de = 0`` away from ``e = 0``.

Points are columns: ``transition(X, u)`` takes ``X`` of shape ``(n,)`` or
``(n, M)`` (M sigma points, cubature points or particles) and returns the same
shape, evaluated in one vectorized call.

Example
-------
>>> import sympy as sp
>>> from types import SimpleNamespace
>>> q, a = sp.symbols("q a")
>>> tank = SimpleNamespace(states=[q], rhs=[sp.Function("Q")(sp.Symbol("t")) - a * q],
...                        inputs=["Q"], outputs={"h": q / 2}, parameters={"a": 0.5})
>>> model = discretize(tank, dt=0.1, augment=["a"])
>>> model.states, model.outputs
(('q', 'a'), ('h',))
>>> model.transition([1.0, 0.5], {"Q": 1.0}).tolist()
[1.05, 0.5]
>>> model.transition_jacobian([1.0, 0.5], {"Q": 1.0}).tolist()
[[0.95, -0.1], [0.0, 1.0]]
"""

from __future__ import annotations

import copy as _copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from ..errors import PrognosisError

__all__ = ["DiscreteModel", "discretize"]

_TIME = sp.Symbol("t")
METHODS = ("euler", "rk4")
_RK4_NODES = (0.0, 0.5, 0.5, 1.0)  # where each RK4 stage is taken, in steps of dt


@dataclass(frozen=True)
class DiscreteModel:
    """``x_k = f(x_{k-1}, u_{k-1})``, ``z_k = h(x_k, u_k)``, compiled to numpy.

    Attributes
    ----------
    states : tuple of str
        State names; augmented parameters come last.
    outputs : tuple of str
        Measured signal names, the rows of ``z``.
    inputs : tuple of str
    parameters : dict
        Values of the parameters that stay constant.
    augmented : tuple of str
        Parameters estimated as states.
    dt : float
        Sampling interval: one ``transition`` spans ``dt``.
    method : str
    substeps : int
        Integration steps per sample (``dt / substeps`` each), for dynamics
        faster than the sampling (an explicit step must stay stable).
    rhs, measurement : tuple of sympy.Expr
        ``F`` and ``G`` in the state symbols ``states`` and input symbols ``inputs``.

    Examples
    --------
    Returned by :func:`discretize`; the RLC circuit of the library with its
    resistance estimated as a state:

    >>> from bondgraph.library import rlc_circuit
    >>> model = discretize(rlc_circuit().state_equations(), dt=1e-3, augment=["R"])
    >>> model.states, model.outputs, model.inputs, model.parameters
    (('p_L', 'q_C', 'R'), ('i', 'v_C'), ('V',), {'L': 0.1, 'C': 0.001})
    >>> model.n_states, model.n_outputs, model.index("R"), model.method, model.dt
    (3, 2, 2, 'euler', 0.001)
    >>> model.rates([0.0, 0.0, 10.0], {"V": 1.0}).tolist()   # dp_L/dt = V at rest
    [1.0, 0.0, 0.0]
    >>> np.round(model.transition([0.0, 0.0, 10.0], {"V": 1.0}), 6).tolist()   # one Euler step
    [0.001, 0.0, 10.0]
    >>> model.measure([0.01, 5e-4, 10.0]).tolist()   # i = p_L / L, v_C = q_C / C
    [0.1, 0.5]
    >>> model.measurement_jacobian([0.01, 5e-4, 10.0]).tolist()
    [[10.0, 0.0, 0.0], [0.0, 1000.0, 0.0]]
    >>> particles = np.zeros((3, 4))   # columns are points: one vectorized call
    >>> model.transition(particles, [1.0]).shape
    (3, 4)
    """

    states: tuple
    outputs: tuple
    inputs: tuple
    parameters: dict
    augmented: tuple
    dt: float
    method: str
    rhs: tuple = field(repr=False)
    measurement: tuple = field(repr=False)
    _functions: dict = field(repr=False, compare=False)
    substeps: int = 1

    def __getstate__(self) -> dict:
        """The state without the lambdified functions (generated code does not pickle).

        They are rebuilt from ``rhs`` and ``measurement`` on first use, so a model sent to a worker
        process computes exactly as the original:

        >>> import pickle
        >>> from bondgraph.library import rlc_circuit
        >>> model = discretize(rlc_circuit().state_equations(), dt=1e-3, augment=["R"])
        >>> copy = pickle.loads(pickle.dumps(model))
        >>> x = [0.01, 5e-4, 10.0]
        >>> bool(np.array_equal(copy.transition(x, [1.0]), model.transition(x, [1.0])))
        True
        """
        return {**self.__dict__, "_functions": {}}

    def __deepcopy__(self, memo: dict) -> DiscreteModel:
        """A copy that shares the compiled functions: they hold no state, and a filter's look-ahead copies
        the filter, model included, at every step (recompiling cost 0.2 s a copy on the three-tank model)."""
        fields = {k: _copy.deepcopy(v, memo) for k, v in self.__dict__.items() if k != "_functions"}
        return DiscreteModel(**fields, _functions=self._functions)

    def _numeric(self, key: str):
        """The compiled function (or flag) ``key``, rebuilt after unpickling."""
        if key not in self._functions:
            self._functions.update(_compile_functions(self.states, self.inputs, self.rhs, self.measurement))
        return self._functions[key]

    @property
    def n_states(self) -> int:
        """Length ``n`` of the state vector, augmented parameters included."""
        return len(self.states)

    @property
    def n_outputs(self) -> int:
        """Number ``m`` of measured outputs, the rows of ``z``."""
        return len(self.outputs)

    def index(self, name: str) -> int:
        """Position of state ``name`` in the state vector."""
        try:
            return self.states.index(name)
        except ValueError:
            raise KeyError(f"{name!r} is not a state; states are {list(self.states)}") from None

    def input_vector(self, u=None, required: bool = True) -> np.ndarray:
        """Inputs as a vector in the order of ``inputs`` from a mapping, a sequence or None.

        ``None`` is accepted for a model without inputs, or (``required=False``) where the
        expression does not use them; they are then NaN.
        """
        if u is None and not required:
            return np.full(len(self.inputs), np.nan)
        if isinstance(u, Mapping):
            missing = [n for n in self.inputs if n not in u]
            unknown = sorted(set(u) - set(self.inputs))
            if missing or unknown:
                raise PrognosisError(f"inputs: missing {missing}, unknown {unknown}; the model's inputs are "
                                     f"{list(self.inputs)}")
            return np.array([float(u[n]) for n in self.inputs])
        vector = np.zeros(0) if u is None else np.atleast_1d(np.asarray(u, float))
        if vector.shape != (len(self.inputs),):
            raise PrognosisError(f"inputs: expected {len(self.inputs)} values for {list(self.inputs)}, "
                                 f"got shape {vector.shape}")
        return vector

    def rates(self, x, u=None) -> np.ndarray:
        """Continuous-time derivative ``F(x, u)``, shape of ``x``."""
        x, squeeze = _columns(x, self.n_states, "x")
        out = _evaluate(self._numeric("rhs"), x, self.input_vector(u), self.n_states)
        return out[:, 0] if squeeze else out

    @property
    def substep(self) -> float:
        """The integration step, ``dt / substeps``."""
        return self.dt / self.substeps

    def transition(self, x, u=None) -> np.ndarray:
        """One step of the discretized dynamics, vectorized over the columns of ``x``."""
        x, squeeze = _columns(x, self.n_states, "x")
        u = self.input_vector(u)
        with np.errstate(invalid="ignore", divide="ignore"):
            for _ in range(self.substeps):
                x = self._substep(x, u)
        return x[:, 0] if squeeze else x

    def _substep(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        h = self.substep
        if self.method == "euler":
            return x + h * _evaluate(self._numeric("rhs"), x, u, self.n_states)
        k1, k2, k3, k4 = (slope for _, slope in self._rk4_stages(x, u))
        return x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)

    def _rk4_stages(self, x: np.ndarray, u: np.ndarray) -> list:
        """The four (point, slope) pairs of the RK4 step from columns ``x`` (n, M)."""
        f, n, dt = self._numeric("rhs"), self.n_states, self.substep
        stages, slope = [], None
        for weight in _RK4_NODES:
            point = x if slope is None else x + weight * dt * slope
            slope = _evaluate(f, point, u, n)
            stages.append((point, slope))
        return stages

    def measure(self, x, u=None) -> np.ndarray:
        """Predicted measurement ``h(x, u)``, shape ``(m,)`` or ``(m, M)``."""
        x, squeeze = _columns(x, self.n_states, "x")
        with np.errstate(invalid="ignore", divide="ignore"):
            out = _evaluate(self._numeric("measurement"), x, self._measurement_inputs(u), self.n_outputs)
        return out[:, 0] if squeeze else out

    def transition_jacobian(self, x, u=None) -> np.ndarray:
        """``df/dx`` of the discrete step at one point ``x`` (n,), from the sympy Jacobian of ``F``."""
        return self.transition_with_jacobian(x, u)[1]

    def transition_with_jacobian(self, x, u=None) -> tuple[np.ndarray, np.ndarray]:
        """``f(x, u)`` and ``df/dx`` at one point ``x`` (n,) in one pass over the substeps (the EKF's predict)."""
        x = _point(x, self.n_states)
        u = self.input_vector(u)
        jac = self._jacobian("rhs_jacobian", u, self.n_states)
        point, out = x[:, None], None
        with np.errstate(invalid="ignore", divide="ignore"):
            for _ in range(self.substeps):  # chain rule over the substeps
                point, step = self._substep_with_jacobian(point, u, jac)
                out = step if out is None else step @ out
        return point[:, 0], _finite(out, "transition Jacobian", x, self.states)

    def _substep_with_jacobian(self, point: np.ndarray, u: np.ndarray, jac) -> tuple[np.ndarray, np.ndarray]:
        """One substep from ``point`` (n, 1) and its Jacobian, the RK4 stages evaluated once for both."""
        eye, h = np.eye(self.n_states), self.substep
        if self.method == "euler":
            return self._substep(point, u), eye + h * jac(point[:, 0])
        # chain rule through the stages: d k_i/dx = J(x_i) (I + c_i h d k_{i-1}/dx)
        stages, derivatives = self._rk4_stages(point, u), []
        for (stage_point, _), weight in zip(stages, _RK4_NODES):
            stage = jac(stage_point[:, 0])
            derivatives.append(stage @ (eye + weight * h * derivatives[-1]) if derivatives else stage)
        k1, k2, k3, k4 = (slope for _, slope in stages)
        d1, d2, d3, d4 = derivatives
        return point + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4), eye + h / 6.0 * (d1 + 2 * d2 + 2 * d3 + d4)

    def measurement_jacobian(self, x, u=None) -> np.ndarray:
        """``dh/dx`` at one point ``x`` (n,), shape ``(m, n)``."""
        x = _point(x, self.n_states)
        jac = self._jacobian("measurement_jacobian", self._measurement_inputs(u), self.n_outputs)
        return _finite(jac(x), "measurement Jacobian", x, self.states)

    def _measurement_inputs(self, u) -> np.ndarray:
        return self.input_vector(u, required=self._numeric("measurement_uses_inputs"))

    def _jacobian(self, key: str, u: np.ndarray, rows: int):
        function = self._numeric(key)

        u = u.tolist()

        def jac(x):
            with np.errstate(invalid="ignore", divide="ignore"):
                values = function(*x.tolist(), *u)
            try:
                return np.array(values, dtype=float).reshape(rows, self.n_states)
            except ValueError:  # an entry came back as a length-1 array
                return np.array([[float(np.asarray(v)) for v in row] for row in values]).reshape(rows, self.n_states)
        return jac


def discretize(equations, *, dt: float, augment: Sequence[str] = (), parameters: Mapping | None = None,
               outputs: Sequence[str] | None = None, method: str = "euler", substeps: int = 1) -> DiscreteModel:
    """Discrete-time model of ``equations`` with the parameters ``augment`` as extra states.

    Parameters
    ----------
    equations : StateEquations-like
        ``states`` (sympy symbols), ``rhs``, ``inputs``, ``outputs`` (signal -> expression),
        ``parameters`` (name -> nominal value).
    dt : float
        Sampling interval.
    augment : sequence of str
        Parameters to estimate as states, ``theta_k = theta_{k-1}`` (Du et al. (n.d.), eq. 3).
    parameters : mapping, optional
        Values overriding the nominal ones for the parameters kept constant.
    outputs : sequence of str, optional
        Measured signals, in the order of ``z`` (default: all outputs).
    method : ``"euler"`` or ``"rk4"``
    substeps : int
        Integration steps of ``dt / substeps`` per sample; the Jacobian is chained
        through them (``F = F_s ... F_2 F_1``).

    Returns
    -------
    DiscreteModel

    Examples
    --------
    ``dx/dt = -a x`` over one step of 1 s from ``x = 1``, ``a = 0.1`` (exactly ``exp(-0.1) = 0.904837``):

    >>> from types import SimpleNamespace
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> discretize(decay, dt=1.0).transition([1.0]).tolist()   # Euler: 1 - 0.1
    [0.9]
    >>> round(float(discretize(decay, dt=1.0, method="rk4").transition([1.0])[0]), 5)
    0.90484
    >>> round(float(discretize(decay, dt=1.0, substeps=4).transition([1.0])[0]), 6)   # 0.975 ** 4
    0.903688

    An augmented parameter becomes the last state, constant over a step, and
    enters the Jacobian:

    >>> model = discretize(decay, dt=1.0, augment=["a"])
    >>> model.states, model.transition([1.0, 0.2]).tolist()
    (('x', 'a'), [0.8, 0.2])
    >>> model.transition_jacobian([1.0, 0.2]).tolist()
    [[0.8, -1.0], [0.0, 1.0]]
    """
    if not dt > 0 or not np.isfinite(dt):
        raise PrognosisError(f"dt must be a positive number, got {dt!r}")
    if method not in METHODS:
        raise PrognosisError(f"method must be one of {METHODS}, got {method!r}")
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise PrognosisError(f"substeps must be a positive integer, got {substeps!r}")
    nominal = {str(k): v for k, v in equations.parameters.items()}
    parameters = dict(parameters or {})
    for name in [*augment, *parameters]:
        if name not in nominal:
            raise PrognosisError(f"parameter {name!r} is not in the model; it has {sorted(nominal)}")
    if len(set(augment)) != len(augment):
        raise PrognosisError(f"augment lists a parameter twice: {list(augment)}")
    values = {**nominal, **parameters}
    for name, value in values.items():
        if name not in augment and (value is None or callable(value) or not np.isfinite(float(value))):
            raise PrognosisError(f"parameter {name!r} needs a finite number, got {value!r}")
    available = list(equations.outputs)
    outputs = list(available if outputs is None else outputs)
    for name in outputs:
        if name not in available:
            raise PrognosisError(f"output {name!r} is not a measured signal of the model; it has {available}")

    # real symbols so that sympy differentiates Abs and sign (d|e|/de = sign(e))
    state_names = [str(s) for s in equations.states] + list(augment)
    x = [sp.Symbol(name, real=True) for name in state_names]
    u = [sp.Symbol(f"_u_{name}", real=True) for name in equations.inputs]
    replace = {sp.Symbol(str(s)): xi for s, xi in zip(equations.states, x)}
    replace.update({sp.Symbol(name): xi for name, xi in zip(augment, x[len(equations.states):])})
    replace.update({sp.Function(name)(_TIME): ui for name, ui in zip(equations.inputs, u)})
    replace.update({sp.Symbol(name): float(values[name]) for name in values if name not in augment})

    def prepare(expression, where):
        expression = sp.sympify(expression).xreplace(replace)
        expression = expression.xreplace({s: sp.Symbol(str(s), real=True) for s in expression.free_symbols
                                          if isinstance(s, sp.Symbol) and s not in x and s not in u})
        leftover = sorted(map(str, expression.free_symbols - set(x) - set(u)))
        if leftover or expression.has(sp.Derivative, sp.Integral):
            raise PrognosisError(f"{where} depends on {leftover or 'derivatives or integrals'}: "
                                 "a state-space model needs explicit state equations")
        return expression

    rhs = [prepare(r, f"d{name}/dt") for r, name in zip(equations.rhs, state_names)] + [sp.S.Zero] * len(augment)
    measurement = [prepare(equations.outputs[name], f"output {name!r}") for name in outputs]

    return DiscreteModel(
        states=tuple(state_names), outputs=tuple(outputs), inputs=tuple(equations.inputs),
        parameters={k: float(v) for k, v in values.items() if k not in augment}, augmented=tuple(augment),
        dt=float(dt), method=method, rhs=tuple(rhs), measurement=tuple(measurement),
        _functions=_compile_functions(state_names, equations.inputs, rhs, measurement), substeps=int(substeps),
    )


def _compile_functions(states: Sequence[str], inputs: Sequence[str], rhs: Sequence, measurement: Sequence) -> dict:
    """The numpy functions of ``F``, ``G`` and their Jacobians, in the symbols :func:`discretize` writes them in."""
    x = [sp.Symbol(name, real=True) for name in states]
    u = [sp.Symbol(f"_u_{name}", real=True) for name in inputs]

    def jacobian(expressions):
        return sp.Matrix(expressions).jacobian(x).replace(sp.DiracDelta, lambda *a: sp.S.Zero)

    return {
        "rhs": sp.lambdify((*x, *u), list(rhs), modules="numpy", cse=True),
        "measurement": sp.lambdify((*x, *u), list(measurement), modules="numpy", cse=True),
        "rhs_jacobian": sp.lambdify((*x, *u), jacobian(rhs).tolist(), modules="numpy", cse=True),
        "measurement_jacobian": sp.lambdify((*x, *u), jacobian(measurement).tolist(), modules="numpy", cse=True),
        "measurement_uses_inputs": any(e.has(*u) for e in measurement) if u else False,
    }


def _columns(x, n: int, name: str) -> tuple[np.ndarray, bool]:
    array = np.asarray(x, float)
    if array.ndim == 1 and array.shape[0] == n:
        return array[:, None], True
    if array.ndim == 2 and array.shape[0] == n:
        return array, False
    raise PrognosisError(f"{name}: expected shape ({n},) or ({n}, M), got {array.shape}")


def _point(x, n: int) -> np.ndarray:
    array = np.asarray(x, float)
    if array.shape != (n,):
        raise PrognosisError(f"x: a Jacobian is taken at one point of shape ({n},), got {array.shape}")
    return array


def _evaluate(function, x: np.ndarray, u: np.ndarray, rows: int) -> np.ndarray:
    """Call a lambdified list of ``rows`` expressions on columns ``x`` (n, M); constants are broadcast."""
    if x.shape[1] == 1:  # one point: Python floats are several times faster than (n, 1) arrays
        try:
            return np.array(function(*x[:, 0].tolist(), *u.tolist()), dtype=float).reshape(rows, 1)
        except (ValueError, TypeError):
            pass
    values = function(*x, *u)
    out = np.empty((rows, x.shape[1]))
    for i, v in enumerate(values):
        out[i] = v
    return out


def _finite(matrix: np.ndarray, what: str, x: np.ndarray, states: Sequence[str]) -> np.ndarray:
    if not np.all(np.isfinite(matrix)):
        columns = sorted({states[j] for j in np.nonzero(~np.isfinite(matrix))[1]})
        raise FloatingPointError(f"the {what} is not finite at x = {x.tolist()} (columns {columns}): "
                                 "the model is not differentiable there (e.g. sqrt(|e|) at e = 0)")
    return matrix
