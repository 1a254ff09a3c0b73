"""A bond graph with a degrading parameter as a ProgPy prognostics model, and our RUL as ProgPy samples.

NASA's ProgPy (Teubert et al. (2025), ``pip install progpy``, the optional extra ``progpy``) writes a
prognostics model as states, inputs, outputs and events with ``dx``, ``output``, ``event_state`` and
``threshold_met``; its state estimators, predictors and metrics work on any such model.
:func:`to_progpy` writes one from a bond graph:

* **states**: the bond graph's states (``q_C``, ``p_I`` of :func:`bondgraph.state_equations`), then per
  degrading parameter ``p`` the parameter itself and its rate ``p_rate`` (so that ProgPy's estimators
  estimate them, as our particle filter estimates ``(theta, gamma)``), and a clock ``clock`` (s) when a
  law needs the time: an onset after 0 or a power law;
* **inputs**: the model's source signals; **outputs**: its detector signals;
* **events**: ``"<p> failure"`` per entry of ``failures``: met when ``p`` reaches its failure value from
  the nominal side, ``event_state`` falling from 1 at the nominal value to 0 there.

Each degradation is a :class:`bondgraph.Degradation` or a law name:

* ``Degradation(law, rate, onset, exponent)``: the truth of :func:`bondgraph.scenarios.drift` as a
  differential equation, ``dp/dt = rate`` (linear), ``rate p`` (exponential) or ``rate n tau^(n-1)`` (power,
  ``tau = clock - onset``), zero before the onset; the rate starts at ``rate``.  A step has no rate and is
  refused;
* ``"linear"`` or ``"exponential"`` (or ``"lin"``, ``"exp"``): the same law from the start with an unknown
  rate, which starts at 0: what an estimator is given, the rate among the particles' states.

The rate has no dynamics of its own (``d rate/dt = 0``): ProgPy's process noise on ``p_rate`` makes it the
random walk of Jha et al. (2016).  ProgPy applies process noise as ``x += dt N(0, sigma)``: give it as a rate,
a per-step standard deviation divided by the step.

ProgPy's ``output(x)`` takes no input.  An output that depends on an input (a heat flow through a wall whose
outer temperature is a source, say) uses the input last given to ``dx``/``next_state``, which the model
keeps in ``held_input`` (initially each source's constant ``value``, else 0): right for a state estimator,
which steps the model and then reads its outputs.  ``simulate_to`` computes its saved outputs after the run,
with the last input: for such an output and an input that varies, step the model yourself.

Examples
--------
The definition needs no ProgPy; :func:`to_progpy` hands it to ProgPy
(``tests/interop/test_progpy.py`` simulates, estimates and predicts with it):

>>> from bondgraph import Degradation
>>> from bondgraph.library import dc_motor
>>> definition = progpy_definition(dc_motor(), degradation={"b": Degradation("exponential", 0.8, onset=1.0)},
...                                failures={"b": 2e-3})
>>> definition.states, definition.inputs, definition.outputs, definition.events
(['p_L_a', 'p_J', 'b', 'b_rate', 'clock'], ['U'], ['i', 'omega'], ['b failure'])
>>> definition.parameters["x0"]["b_rate"], definition.parameters["failures"]
(0.8, {'b': 0.002})
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import sympy as sp

from bondgraph.optional import import_optional
from bondgraph.scenarios import DEGRADATION_LAWS, LAW_NAMES, Degradation
from bondgraph.structure import require_model, signal_function

from .errors import PrognosisError

__all__ = ["CLOCK", "PROGPY_INSTALL", "ProgPyDefinition", "progpy_definition", "to_progpy", "to_progpy_samples"]

#: The name of the clock state, present when a law needs the time.
CLOCK = "clock"
#: What to install for :func:`to_progpy`.
PROGPY_INSTALL = "pip install 'bondgraph-phm[progpy]'"
#: ProgPy's own parameter names, which a model parameter may not take.
RESERVED = ("x0", "process_noise", "process_noise_dist", "measurement_noise", "measurement_noise_dist",
            "integration_method", "failures")
#: The integration ProgPy's ``next_state`` uses by default: the bond graph's states are often stiff for Euler.
INTEGRATION = "rk4"


@dataclass(frozen=True)
class _Law:
    """One degrading parameter's law: ``law`` in linear/exponential/power, from ``onset``, power ``exponent``."""

    law: str
    onset: float
    exponent: float
    rate: float   # the rate's initial value


@dataclass(frozen=True)
class ProgPyDefinition:
    """What :func:`to_progpy` hands to ProgPy, without ProgPy: names, default parameters and numeric functions.

    The functions take the states as rows, ``x`` of shape ``(n_states, k)`` for ``k`` samples (ProgPy's
    vectorized containers), ``u`` a list of the inputs' values and ``parameters`` a mapping with every model
    parameter and ``failures``; they return arrays of shape ``(n, k)``.

    Attributes
    ----------
    name : str
    states, inputs, outputs, events : list of str
    parameters : dict
        ProgPy's default parameters: the model's parameters (nominal values), ``failures`` (parameter ->
        failure value), ``x0`` (state -> initial value: 0 for the bond graph's states, as
        :func:`bondgraph.simulate`), ``process_noise``, ``measurement_noise`` and ``integration_method``.
    derivative : callable ``(x, u, parameters) -> dx``
    output : callable ``(x, u, parameters) -> z``
    event_state, threshold_met : callable ``(x, parameters) -> array``
        One row per event; ``threshold_met`` is boolean.
    held_input : dict
        Input -> the value an output uses before any input is given: its source's constant ``value``, else 0.
    """

    name: str
    states: list
    inputs: list
    outputs: list
    events: list
    parameters: dict
    derivative: Callable
    output: Callable
    event_state: Callable
    threshold_met: Callable
    held_input: dict


def to_progpy(bg, *, degradation: Mapping, failures: Mapping, parameters: Mapping | None = None,
              process_noise=None, measurement_noise=None):
    """The ProgPy ``PrognosticsModel`` of a bond graph whose parameters degrade (see the module).

    Parameters
    ----------
    bg : BondGraph
    degradation : mapping
        Parameter -> :class:`bondgraph.Degradation` or law name (``"linear"``, ``"exponential"``).
    failures : mapping
        Degrading parameter -> its failure value: one event each.
    parameters : mapping, optional
        Parameter -> value overriding the nominal value (of a degrading one: its value at the start).
    process_noise, measurement_noise : float or mapping, optional
        ProgPy's: one standard deviation for every state (output), or state (output) -> standard deviation;
        the process noise is a rate (per second).  Default 0.

    Returns
    -------
    progpy.PrognosticsModel
        A vectorized, continuous model (``dx``) integrated with ``rk4`` unless told otherwise
        (``integration_method``); ``held_input`` holds the input last given to ``dx``.

    Raises
    ------
    ImportError
        Without ProgPy: one line naming the extra to install.
    PrognosisError
        Naming the parameter, state, output or law at fault.
    """
    definition = progpy_definition(bg, degradation=degradation, failures=failures, parameters=parameters,
                                   process_noise=process_noise, measurement_noise=measurement_noise)
    progpy = import_optional("progpy", f"to_progpy needs NASA's ProgPy: {PROGPY_INSTALL}")
    return _model_class(progpy.PrognosticsModel, definition)()


def _model_class(base: type, definition: ProgPyDefinition) -> type:
    """A subclass of ProgPy's ``PrognosticsModel`` that evaluates ``definition``'s functions."""

    def dx(self, x, u):
        self.held_input = [_value(u, name) for name in self.inputs]
        return self.StateContainer(definition.derivative(_rows(x), self.held_input, self.parameters))

    def output(self, x):
        return self.OutputContainer(definition.output(_rows(x), self.held_input, self.parameters))

    def event_state(self, x):
        rows = definition.event_state(_rows(x), self.parameters)
        return {event: _squeezed(row) for event, row in zip(self.events, rows)}

    def threshold_met(self, x):
        rows = definition.threshold_met(_rows(x), self.parameters)
        return {event: _squeezed(row, bool) for event, row in zip(self.events, rows)}

    namespace = {"__doc__": f"The bond graph {definition.name!r} with degrading parameters, from to_progpy.",
                 "states": list(definition.states), "inputs": list(definition.inputs),
                 "outputs": list(definition.outputs), "events": list(definition.events), "is_vectorized": True,
                 "default_parameters": definition.parameters,
                 "held_input": [definition.held_input[name] for name in definition.inputs],
                 "dx": dx, "output": output, "event_state": event_state, "threshold_met": threshold_met}
    return type(_class_name(definition.name), (base,), namespace)


def progpy_definition(bg, *, degradation: Mapping, failures: Mapping, parameters: Mapping | None = None,
                      process_noise=None, measurement_noise=None) -> ProgPyDefinition:
    """The definition :func:`to_progpy` hands to ProgPy, without needing ProgPy (arguments as there).

    The derivative of the bond graph's states is its state equations lambdified, the degrading parameters
    read from the states:

    >>> from bondgraph.library import rlc_circuit
    >>> definition = progpy_definition(rlc_circuit(), degradation={"R": "linear"}, failures={"R": 20.0})
    >>> definition.states, definition.events
    (['p_L', 'q_C', 'R', 'R_rate'], ['R failure'])
    >>> x = np.array([[0.1], [1e-3], [12.0], [2.0]])                  # p_L, q_C, R, R_rate
    >>> definition.derivative(x, [5.0], definition.parameters).ravel().round(3).tolist()   # V - R p_L/L - q_C/C
    [-8.0, 1.0, 2.0, 0.0]
    >>> definition.event_state(x, definition.parameters).ravel().tolist()              # (20 - 12) / (20 - 10)
    [0.8]
    """
    require_model(bg, "to_progpy")
    equations = bg.state_equations()
    names = list(equations.parameters)
    laws = {name: _law(name, spec) for name, spec in _known(degradation, names, "degradation").items()}
    failure_values = {name: _number(value, f"failures[{name!r}]")
                      for name, value in _known(failures, names, "failures").items()}
    overrides = {name: _number(value, f"parameters[{name!r}]")
                 for name, value in _known(parameters or {}, names, "parameters").items()}
    _check_reserved(names)
    values = {**equations.parameters, **overrides}
    for name, failure in failure_values.items():
        if name not in laws:
            raise PrognosisError(f"failures: {name!r} does not degrade; give its law in degradation={{{name!r}: ...}}")
        if failure == values[name]:
            raise PrognosisError(f"failures: the failure value of {name!r} is its nominal value {failure:g}")
    physical = [str(x) for x in equations.states]
    degrading = [name for name in names if name in laws]      # in the model's order
    states = [*physical, *(s for name in degrading for s in (name, f"{name}_rate"))]
    clocked = any(law.law == "power" or law.onset > 0 for law in laws.values())
    states += [CLOCK] if clocked else []
    clash = sorted({s for s in states if states.count(s) > 1})
    if clash:
        raise PrognosisError(f"to_progpy: the state name {clash[0]!r} is taken twice (a parameter named like a "
                             "state, or like another's rate or the clock); rename the parameter")
    inputs, outputs = list(equations.inputs), list(equations.outputs)
    rhs, out = _compiled(equations, names, inputs)
    index = {name: states.index(name) for name in degrading}
    events = [f"{name} failure" for name in failure_values]

    def theta(x: np.ndarray, parameters: Mapping) -> list:
        """The parameters' values: from the states for the degrading ones."""
        return [x[index[name]] if name in index else parameters[name] for name in names]

    def derivative(x, u, parameters):
        x = np.asarray(x, float)
        k = x.shape[1]
        with np.errstate(invalid="ignore", divide="ignore"):
            dx = [*_rows_of(rhs(list(x[:len(physical)]), list(u), theta(x, parameters)), k)]
        clock = x[states.index(CLOCK)] if clocked else None
        for name in degrading:
            dx += [_law_rate(laws[name], x[index[name]], x[index[name] + 1], clock), np.zeros(k)]
        dx += [np.ones(k)] if clocked else []
        return np.array(dx, float).reshape(len(states), k)

    def output(x, u, parameters):
        x = np.asarray(x, float)
        with np.errstate(invalid="ignore", divide="ignore"):
            z = _rows_of(out(list(x[:len(physical)]), list(u), theta(x, parameters)), x.shape[1])
        return np.array(z, float).reshape(len(outputs), x.shape[1])

    def progress(x, parameters):
        """Per event, how far from nominal (0) towards failure (1) the parameter is."""
        x = np.asarray(x, float)
        rows = []
        for name, failure in parameters["failures"].items():
            nominal = parameters[name]
            rows.append((x[index[name]] - nominal) / (failure - nominal))
        return np.array(rows, float).reshape(len(events), x.shape[1])

    def event_state(x, parameters):
        return np.clip(1.0 - progress(x, parameters), 0.0, 1.0)

    def threshold_met(x, parameters):
        return progress(x, parameters) >= 1.0

    x0 = {**{s: 0.0 for s in physical}, **{s: 0.0 for s in states[len(physical):]}}
    for name in degrading:
        x0[name], x0[f"{name}_rate"] = values[name], laws[name].rate
    defaults = {**values, "failures": failure_values, "x0": x0,
                "process_noise": _noise(process_noise, states, "process_noise", "state"),
                "measurement_noise": _noise(measurement_noise, outputs, "measurement_noise", "output"),
                "integration_method": INTEGRATION}
    return ProgPyDefinition(name=bg.name or "bond graph", states=states, inputs=inputs, outputs=outputs,
                            events=events, parameters=defaults, derivative=derivative, output=output,
                            event_state=event_state, threshold_met=threshold_met,
                            held_input=_inputs_at_start(bg, inputs))


def to_progpy_samples(rul, event: str, *, asset: int = 0, size: int | None = None, relative: bool = False):
    """Our RUL prediction as ProgPy's ``UnweightedSamples`` of the time of ``event``, for ProgPy's metrics.

    A censored sample (no failure within the horizon, ``inf``) becomes ``None``, ProgPy's "no event".  ProgPy's
    times of event are times (``origin + RUL``, as its predictors give them) unless ``relative``.  Weighted
    samples are resampled deterministically to ``size`` samples (default: as many as there are): the systematic
    scheme with the offset 1/2 over the sorted samples, so sample ``i`` is repeated about ``size w_i`` times and the
    ``j``-th smallest draw is the weighted quantile (:meth:`RULDistribution.quantile`) at ``(j + 1/2) / size``;
    equal weights keep the samples as they are.

    Parameters
    ----------
    rul : prognosis.RULDistribution
        One row of samples, or a batch of which ``asset`` is taken.
    event : str
        The event's name, e.g. ``"b failure"`` (:func:`to_progpy`'s events).

    Returns
    -------
    progpy.uncertain_data.UnweightedSamples

    Raises
    ------
    ImportError
        Without ProgPy: one line naming the extra to install.
    PrognosisError
        When ``asset`` or ``size`` does not fit.
    """
    uncertain = import_optional("progpy.uncertain_data", f"to_progpy_samples needs NASA's ProgPy: {PROGPY_INSTALL}")
    times = resampled_times(rul, asset=asset, size=size, relative=relative)
    return uncertain.UnweightedSamples([{event: None if math.isinf(t) else float(t)} for t in times])


def resampled_times(rul, *, asset: int = 0, size: int | None = None, relative: bool = False) -> np.ndarray:
    """The times of event (or RULs if ``relative``) :func:`to_progpy_samples` gives ProgPy, ``inf`` if censored.

    >>> from prognosis import RULDistribution
    >>> rul = RULDistribution(samples=np.array([1.0, 2.0, np.inf]), weights=np.array([0.5, 0.25, 0.25]), origin=10.0)
    >>> resampled_times(rul, size=4).tolist()
    [11.0, 11.0, 12.0, inf]
    """
    samples = np.asarray(rul.samples, float)
    weights = None if rul.weights is None else np.broadcast_to(np.asarray(rul.weights, float), samples.shape)
    if samples.ndim == 2:
        if not 0 <= asset < samples.shape[0]:
            raise PrognosisError(f"asset: {asset} is not a row of the {samples.shape[0]} rows of samples")
        samples, weights = samples[asset], None if weights is None else weights[asset]
    elif samples.ndim != 1:
        raise PrognosisError(f"rul: samples of shape {samples.shape}; expected (N,) or (assets, N)")
    n = samples.size if size is None else int(size)
    if n < 1:
        raise PrognosisError(f"size: need at least one sample, got {size!r}")
    if weights is not None and not np.allclose(weights, weights[0], rtol=1e-12, atol=0) or n != samples.size:
        w = np.ones(samples.size) if weights is None else weights
        order = np.argsort(samples, kind="stable")   # sorted, the j-th draw is the quantile at (j + 1/2) / n
        cumulative = np.cumsum(w[order]) / np.sum(w)
        picks = np.minimum(np.searchsorted(cumulative, (np.arange(n) + 0.5) / n), samples.size - 1)
        samples = samples[order][picks]
    return samples if relative else rul.origin + samples


def _known(spec: Mapping, names: list, argument: str) -> dict:
    """``spec`` as a dict, or a PrognosisError naming the keys that are not parameters of the model."""
    if not isinstance(spec, Mapping):
        raise PrognosisError(f"{argument}: expected a mapping of parameter names, got {type(spec).__name__}")
    unknown = sorted(map(str, set(spec) - set(names)))
    if unknown:
        raise PrognosisError(f"{argument}: {', '.join(map(repr, unknown))} "
                             f"{'is not a parameter' if len(unknown) == 1 else 'are not parameters'} of the model; "
                             f"its parameters are {names}")
    return dict(spec)


def _law(name: str, spec: object) -> _Law:
    """The law of parameter ``name`` from a Degradation or a law name."""
    if isinstance(spec, str):
        law = LAW_NAMES.get(spec.strip().lower(), spec.strip().lower())
        if law not in ("linear", "exponential"):
            raise PrognosisError(f"degradation[{name!r}]: the law name {spec!r} is not 'linear' or 'exponential' "
                                 "(give a Degradation for a power law)")
        return _Law(law, 0.0, 1.0, 0.0)
    if not isinstance(spec, Degradation):
        raise PrognosisError(f"degradation[{name!r}]: expected a Degradation or a law name, got {type(spec).__name__}")
    if spec.law == "step" or spec.law not in DEGRADATION_LAWS:
        raise PrognosisError(f"degradation[{name!r}]: a {spec.law} law has no rate for ProgPy's states to follow; "
                             "use a linear, exponential or power law")
    return _Law(spec.law, _number(spec.onset, f"degradation[{name!r}].onset"), float(spec.exponent),
                _number(spec.rate, f"degradation[{name!r}].rate"))


def _law_rate(law: _Law, value: np.ndarray, rate: np.ndarray, clock: np.ndarray | None) -> np.ndarray:
    """``d value / dt`` under ``law`` at the rate ``rate``: zero before the onset."""
    if law.law == "exponential":
        slope = rate * value
    elif law.law == "power":
        elapsed = np.maximum(clock - law.onset, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.where(elapsed > 0, rate * law.exponent * elapsed ** (law.exponent - 1.0), 0.0)
    else:
        slope = rate * np.ones_like(value)
    return slope if clock is None else np.where(clock >= law.onset, slope, 0.0)


def _compiled(equations, names: list, inputs: list) -> tuple:
    """The state equations' right-hand sides and outputs as numpy functions of (states, inputs, parameters)."""
    u = [sp.Symbol(f"_u_{name}") for name in inputs]
    to_symbol = {signal_function(name): s for name, s in zip(inputs, u)}
    rhs = [sp.sympify(r) for r in equations.rhs]
    for x, r in zip(equations.states, rhs):
        if r.has(sp.Derivative):
            raise PrognosisError(f"d{x}/dt needs the derivative of an input: a storage element in derivative "
                                 "causality is driven by a source, which ProgPy's dx cannot give")
    outputs = [sp.sympify(z) for z in equations.outputs.values()]
    for signal, z in zip(equations.outputs, outputs):
        if z.has(sp.Derivative):
            raise PrognosisError(f"output {signal!r} needs the derivative of an input, which ProgPy's output "
                                 "cannot give")
    args = (list(equations.states), u, [sp.Symbol(name) for name in names])
    return tuple(sp.lambdify(args, [e.xreplace(to_symbol) for e in group], modules="numpy", cse=True)
                 for group in (rhs, outputs))


def _rows_of(values, k: int) -> list:
    """Each value (a number or an array of ``k``) as a row of ``k``."""
    return [np.broadcast_to(np.asarray(v, float).reshape(-1), (k,)) for v in values]


def _rows(container) -> np.ndarray:
    """The states of a ProgPy container (or a dict) as rows, shape ``(n, k)``."""
    matrix = getattr(container, "matrix", None)
    if matrix is None:
        matrix = np.array([np.ravel(v) for v in container.values()], float)
    matrix = np.asarray(matrix, float)
    return matrix.reshape(matrix.shape[0], -1)


def _value(u, name: str) -> float | np.ndarray:
    """An input's value from a ProgPy input container or a dict."""
    value = np.asarray(u[name], float)
    return float(value) if value.size == 1 else value


def _squeezed(row: np.ndarray, kind=float):
    """A row of one sample as a number (ProgPy's unvectorized form), of several as an array."""
    return kind(row[0]) if row.size == 1 else row


def _number(value: object, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not math.isfinite(value):
        raise PrognosisError(f"{what}: expected a finite number, got {value!r}")
    return float(value)


def _noise(spec, keys: list, argument: str, kind: str):
    """ProgPy's noise parameter: a number for all, or a dict checked against the state or output names."""
    if spec is None:
        return 0.0
    if isinstance(spec, Mapping):
        unknown = sorted(map(str, set(spec) - set(keys)))
        if unknown:
            article = "an" if kind == "output" else "a"
            raise PrognosisError(f"{argument}: {', '.join(map(repr, unknown))} is not {article} {kind} of the model; "
                                 f"its {kind}s are {keys}")
        return {key: _number(value, f"{argument}[{key!r}]") for key, value in spec.items()}
    return _number(spec, argument)


def _check_reserved(names: list) -> None:
    taken = [name for name in names if name in RESERVED]
    if taken:
        raise PrognosisError(f"to_progpy: the parameter {taken[0]!r} has the name of a ProgPy parameter; rename it")


def _inputs_at_start(bg, inputs: list) -> dict:
    """Each input's value before any is given: its source's constant ``value``, else 0."""
    constants = {e.signal: e.value for e in bg.structure().elements.values()
                 if getattr(e, "value", None) is not None and getattr(e, "signal", None)}
    return {name: float(constants.get(name, 0.0)) for name in inputs}


def _class_name(name: str) -> str:
    """A class name from a model's name: its words capitalized, other characters dropped."""
    words = "".join(c if c.isalnum() else " " for c in name).split()
    text = "".join(w[:1].upper() + w[1:] for w in words)
    return text if text[:1].isalpha() else f"Model{text}"
