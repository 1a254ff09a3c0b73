"""Input signals written as data (bondgraph.inputs): expressions of t, tables, and JSON model files that hold them."""

import json
import pickle

import numpy as np
import pytest

from bondgraph import InputExpression, LawError, ModelError, SimulationError, TabulatedInput, simulate
from bondgraph.io import ModelFileError, load_model, model_from_json, to_json
from bondgraph.laws import parse_expression
from bondgraph.library import rlc_circuit

T = np.array([0.0, 0.25, 0.5, 0.75, 1.0])


@pytest.mark.parametrize("text, formula", [
    ("12*step(t - 0.5)", lambda t: np.where(t >= 0.5, 12.0, 0.0)),
    ("5 + sin(7*t)", lambda t: 5 + np.sin(7 * t)),
    ("Min(24*t, 12)", lambda t: np.minimum(24 * t, 12.0)),
    ("Max(0, 2 - 4*t)", lambda t: np.maximum(0.0, 2 - 4 * t)),
    ("exp(-t/0.2)*cos(2*pi*t)", lambda t: np.exp(-t / 0.2) * np.cos(2 * np.pi * t)),
    ("sign(t - 0.6)*sqrt(Abs(t - 0.6))", lambda t: np.sign(t - 0.6) * np.sqrt(np.abs(t - 0.6))),
    ("3.5", lambda t: np.full_like(t, 3.5)),
])
def test_an_expression_gives_its_formula_at_a_time_and_over_an_array(text, formula):
    u = InputExpression(text)
    np.testing.assert_allclose(u(T), formula(T), rtol=1e-14, atol=1e-15)
    value = u(0.75)
    assert isinstance(value, float) and value == pytest.approx(float(formula(np.array(0.75))), rel=1e-14)
    assert u(T).shape == T.shape and str(u) == text


def test_step_is_one_from_zero_on():
    u = InputExpression("step(t - 0.5)")
    assert (u(np.nextafter(0.5, 0.0)), u(0.5)) == (0.0, 1.0)


def test_an_expression_survives_pickling_and_compares_by_its_expression():
    u = InputExpression("5 + sin(7*t)", where="V")
    again = pickle.loads(pickle.dumps(u))
    assert again == u and again == InputExpression("sin(7*t)+5") and again != InputExpression("5 + sin(6*t)")
    assert again.where == "V" and again(0.3) == u(0.3)


@pytest.mark.parametrize("text, message", [
    ("__import__('os').system('echo pwned')", "call to \"__import__('os').system\" not allowed"),
    ("t.__class__", "unknown name 't.__class__'"),
    ("(lambda: 1)()", "call to 'lambda: 1' not allowed"),
    ("[1, 2][0]*t", "Subscript not allowed"),
    ("eval('1')", "call to 'eval' not allowed"),
    ("12*x", "unknown name 'x' (allowed: t)"),
    ("t if t else 0", "IfExp not allowed"),
    ("9**9**9", "exponent"),
    ("t > 1", "Compare not allowed"),
    ("step(t, 2)", "step(t, 2)"),
    ("Heaviside(t)", "call to 'Heaviside' not allowed"),
    ("1/0", "division by zero"),
    ("", "not a valid expression"),
])
def test_hostile_or_bad_expressions_are_refused_naming_the_input(text, message):
    with pytest.raises(LawError) as error:
        InputExpression(text, where="m.json: graph.inputs['V']")
    assert str(error.value).startswith("m.json: graph.inputs['V']: ") and message in str(error.value)


def test_step_is_for_inputs_only_not_for_laws():
    import sympy as sp

    e = sp.Symbol("e")
    with pytest.raises(LawError, match="call to 'step' not allowed"):
        parse_expression("step(e)", {"e": e})


def test_a_value_that_is_not_finite_is_an_error_at_its_time():
    u = InputExpression("log(t)", where="--input V")
    assert u(1.0) == 0.0
    with pytest.raises(SimulationError, match=r"^--input V: log\(t\) is not finite at t = 0$"):
        u(T)


def test_a_table_interpolates_linearly_and_holds_its_ends():
    u = TabulatedInput([1.0, 2.0, 4.0], [0.0, 10.0, 6.0], where="u.csv: column 'V'")
    t = np.array([0.0, 1.0, 1.5, 3.0, 4.0, 9.0])
    assert u(t).tolist() == [0.0, 0.0, 5.0, 8.0, 6.0, 6.0]
    assert isinstance(u(1.5), float) and u(1.5) == 5.0


@pytest.mark.parametrize("t, values, message", [
    ([0.0, 1.0], [1.0], "1-D arrays of one length"),
    ([0.0], [1.0], "1 sample(s); at least 2"),
    ([0.0, 1.0, 1.0], [1.0, 2.0, 3.0], "strictly increasing"),
    ([0.0, np.inf], [1.0, 2.0], "finite and strictly increasing"),
    ([0.0, 1.0, 2.0], [1.0, np.nan, 3.0], "no value at t = 1 (a gap)"),
])
def test_a_bad_table_is_refused_naming_the_input(t, values, message):
    with pytest.raises(SimulationError) as error:
        TabulatedInput(t, values, where="u.csv: column 'V'")
    assert str(error.value).startswith("u.csv: column 'V': ") and message in str(error.value)


def test_a_simulation_driven_by_an_expression_or_a_table_is_the_one_driven_by_the_function():
    t = np.linspace(0.0, 0.5, 101)
    expected = simulate(rlc_circuit(), (0.0, 0.5), {"V": lambda s: 5 + np.sin(7 * s)}, t_eval=t)
    by_text = simulate(rlc_circuit(), (0.0, 0.5), {"V": InputExpression("5 + sin(7*t)")}, t_eval=t)
    np.testing.assert_allclose(by_text["v_C"], expected["v_C"], rtol=1e-12, atol=1e-14)
    ramp = TabulatedInput([0.0, 0.2, 0.3], [0.0, 2.0, 2.0])
    by_table = simulate(rlc_circuit(), (0.0, 0.5), {"V": ramp}, t_eval=t)
    by_min = simulate(rlc_circuit(), (0.0, 0.5), {"V": InputExpression("Min(10*t, 2)")}, t_eval=t)
    np.testing.assert_allclose(by_table["V"], np.minimum(10 * t, 2.0), rtol=1e-14)
    np.testing.assert_allclose(by_table["v_C"], by_min["v_C"], rtol=1e-6, atol=1e-9)


# ------------------------------------------------------------------------------------------- JSON model files

def rlc_json(inputs) -> str:
    data = json.loads(to_json(rlc_circuit(), t_end=0.5))
    data["graph"]["inputs"] = inputs
    return json.dumps(data)


def test_a_json_input_may_be_an_expression_and_round_trips():
    spec = model_from_json(rlc_json({"V": "5 + sin(7*t)"}), where="m.json")
    assert spec.inputs == {"V": InputExpression("5 + sin(7*t)")}
    assert spec.inputs["V"](0.1) == pytest.approx(5 + np.sin(0.7), rel=1e-14)
    text = to_json(spec.model, inputs=spec.inputs, t_end=spec.t_end)
    assert json.loads(text)["graph"]["inputs"] == {"V": "5 + sin(7*t)"}
    assert model_from_json(text).inputs == spec.inputs
    assert json.loads(to_json(rlc_circuit(), inputs={"V": "12*step(t-1)"}))["graph"]["inputs"] == {"V": "12*step(t-1)"}


@pytest.mark.parametrize("given, error, message", [
    ({"V": "12*x"}, LawError, "m.json: graph.inputs['V']: unknown name 'x' (allowed: t)"),
    ({"V": "__import__('os')"}, LawError, "m.json: graph.inputs['V']: call to '__import__' not allowed"),
    ({"V": [1, 2]}, ModelFileError, "m.json: graph.inputs['V']: expected a number or the text of an expression of t"),
    ({"V": True}, ModelFileError, "m.json: graph.inputs['V']: expected a number or the text"),
    ({"W": "t"}, ModelFileError, "m.json: graph.inputs names ['W'], which are not input signals"),
    ("12", ModelFileError, "m.json: graph.inputs: expected an object of input signal -> number or expression of t"),
])
def test_a_bad_json_input_names_the_file_and_the_input(given, error, message):
    with pytest.raises(error) as caught:
        model_from_json(rlc_json(given), where="m.json")
    assert message in str(caught.value)


def test_to_json_stores_numbers_and_expressions_only():
    with pytest.raises(ModelError, match=r"to_json: inputs\['V'\] is a function; only a number or an expression of t"):
        to_json(rlc_circuit(), inputs={"V": lambda t: 1.0})
    with pytest.raises(ModelError, match=r"inputs\['V'\] is a TabulatedInput"):
        to_json(rlc_circuit(), inputs={"V": TabulatedInput([0.0, 1.0], [0.0, 1.0])})
    with pytest.raises(LawError, match=r"to_json: inputs\['V'\]: unknown name 'x'"):
        to_json(rlc_circuit(), inputs={"V": "x"})


def test_a_python_model_file_may_give_an_input_as_text(tmp_path):
    path = tmp_path / "circuit.py"
    path.write_text("from bondgraph.library import rlc_circuit\nmodel = rlc_circuit()\ninputs = {'V': '2*step(t)'}\n")
    assert load_model(path).inputs == {"V": InputExpression("2*step(t)")}
    path.write_text("from bondgraph.library import rlc_circuit\nmodel = rlc_circuit()\ninputs = {'V': 'import os'}\n")
    with pytest.raises(LawError, match=r"circuit.py: inputs\['V'\]: not a valid expression"):
        load_model(path)
