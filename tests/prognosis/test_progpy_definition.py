"""The ProgPy definition of a degrading bond graph (prognosis.progpy_export) without ProgPy: names, the numeric
derivative against the sympy state equations, events, errors, and the one-line ImportError without ProgPy."""

import sys

import numpy as np
import pytest
import sympy as sp

from bondgraph import Degradation
from bondgraph.library import rlc_circuit
from bondgraph.structure import signal_function
from prognosis import PrognosisError, progpy_definition, to_progpy, to_progpy_samples
from prognosis.progpy_export import resampled_times


def test_the_definition_names_states_inputs_outputs_and_events():
    definition = progpy_definition(rlc_circuit(), degradation={"R": Degradation("linear", 2.0, onset=1.0)},
                                   failures={"R": 20.0})
    assert definition.states == ["p_L", "q_C", "R", "R_rate", "clock"]
    assert (definition.inputs, definition.outputs, definition.events) == (["V"], ["i", "v_C"], ["R failure"])
    assert definition.parameters["x0"] == {"p_L": 0.0, "q_C": 0.0, "R": 10.0, "R_rate": 2.0, "clock": 0.0}
    assert definition.parameters["integration_method"] == "rk4"


def test_the_numeric_derivative_is_the_sympy_state_equations_at_a_point():
    bg = rlc_circuit()
    equations = bg.state_equations()
    definition = progpy_definition(bg, degradation={"R": "exponential"}, failures={"R": 5.0},
                                   parameters={"C": 2e-3})
    point = {"p_L": 0.03, "q_C": 4e-3, "R": 7.5, "R_rate": -0.2}
    x = np.array([[point[s], point[s] * 1.1] for s in definition.states])      # two samples, vectorized
    dx = definition.derivative(x, [3.0], definition.parameters)
    for column in range(2):
        values = {sp.Symbol(s): x[j, column] for j, s in enumerate(definition.states)}
        values.update({sp.Symbol("L"): 0.1, sp.Symbol("C"): 2e-3, signal_function("V"): 3.0})
        expected = [float(r.subs(values)) for r in equations.rhs]
        assert np.allclose(dx[:2, column], expected, rtol=1e-12)
        assert dx[2, column] == pytest.approx(x[3, column] * x[2, column], rel=1e-12)   # dR/dt = rate R
    assert np.all(dx[3] == 0.0)
    z = definition.output(x, [3.0], definition.parameters)
    assert np.allclose(z[:, 0], [0.03 / 0.1, 4e-3 / 2e-3])


def test_events_fall_from_nominal_to_failure_on_either_side():
    definition = progpy_definition(rlc_circuit(), degradation={"R": "linear"}, failures={"R": 5.0})
    x = np.zeros((4, 4))
    x[2] = [10.0, 7.5, 5.0, 4.0]                                               # nominal 10, falling to 5
    assert definition.event_state(x, definition.parameters).ravel().tolist() == [1.0, 0.5, 0.0, 0.0]
    assert definition.threshold_met(x, definition.parameters).ravel().tolist() == [False, False, True, True]


def test_a_clock_drives_onsets_and_power_laws():
    definition = progpy_definition(rlc_circuit(), degradation={"R": Degradation("power", 2.0, 1.0, 3.0)},
                                   failures={"R": 20.0})
    x = np.zeros((5, 3))
    x[2], x[3], x[4] = 10.0, 2.0, [0.5, 1.0, 3.0]                         # R, R_rate, clock
    assert definition.derivative(x, [0.0], definition.parameters)[2].tolist() == [0.0, 0.0, 2.0 * 3.0 * 2.0 ** 2]


@pytest.mark.parametrize("kwargs, message", [
    ({"degradation": {"R_x": "linear"}, "failures": {}}, "degradation: 'R_x' is not a parameter of the model"),
    ({"degradation": {"R": "linear"}, "failures": {"Q": 1.0}}, "failures: 'Q' is not a parameter"),
    ({"degradation": {"R": "linear"}, "failures": {"R": 20.0}, "parameters": {"X": 1.0}},
     "parameters: 'X' is not a parameter"),
    ({"degradation": {"R": "linear"}, "failures": {"C": 1.0}}, "failures: 'C' does not degrade"),
    ({"degradation": {"R": Degradation("step", 5.0)}, "failures": {}}, "degradation['R']: a step law has no rate"),
    ({"degradation": {"R": "quadratic"}, "failures": {}}, "degradation['R']: the law name 'quadratic'"),
    ({"degradation": {"R": "linear"}, "failures": {"R": 10.0}}, "its nominal value"),
    ({"degradation": {"R": "linear"}, "failures": {}, "process_noise": {"q_X": 1.0}},
     "process_noise: 'q_X' is not a state"),
    ({"degradation": {"R": "linear"}, "failures": {}, "measurement_noise": {"w": 1.0}},
     "measurement_noise: 'w' is not an output"),
])
def test_bad_input_is_one_line_naming_what_is_at_fault(kwargs, message):
    with pytest.raises(PrognosisError) as error:
        progpy_definition(rlc_circuit(), **kwargs)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_without_progpy_the_export_says_which_extra_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "progpy", None)
    with pytest.raises(ImportError, match=r"^to_progpy needs NASA's ProgPy: pip install 'bondgraph-phm\[progpy\]'$"):
        to_progpy(rlc_circuit(), degradation={"R": "linear"}, failures={"R": 20.0})
    from prognosis import RULDistribution
    with pytest.raises(ImportError, match=r"bondgraph-phm\[progpy\]"):
        to_progpy_samples(RULDistribution(samples=np.array([1.0])), "R failure")


def test_weighted_samples_are_resampled_to_their_quantiles():
    from prognosis import RULDistribution
    rng = np.random.default_rng(3)
    samples = rng.gamma(4.0, 1.0, 50)
    samples[[3, 7]] = np.inf
    rul = RULDistribution(samples=samples[None], weights=rng.dirichlet(np.ones(50))[None], origin=2.0)
    times = np.sort(resampled_times(rul, size=40, relative=True))
    levels = (np.arange(40) + 0.5) / 40
    assert np.array_equal(times, rul.quantile(levels)[0])
    assert np.array_equal(np.sort(resampled_times(rul, size=40)), 2.0 + times)        # times of event: origin + RUL
    equal = RULDistribution(samples=samples, weights=np.full(50, 0.02))
    assert np.array_equal(resampled_times(equal, relative=True), samples)     # equal weights: kept as they are
