"""Units: the unit texts, and the dimensional check of a model (``unit``/``units`` on its elements)."""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bondgraph import BondGraph, ModelError
from bondgraph.io import model_from_json, to_json
from bondgraph.library import (dc_motor, friction_drive, mass_spring_chain, rlc_circuit, three_tank, torsion_bar,
                               torsion_bar_monitorable, torsion_bar_with_load)
from bondgraph.units import ATOMS, DIMENSIONLESS, Unit, parse_unit

LIBRARY = [rlc_circuit, dc_motor, torsion_bar, torsion_bar_monitorable, torsion_bar_with_load, three_tank,
           friction_drive, lambda: mass_spring_chain(3)]


# ------------------------------------------------------------------------------------------ unit texts

@pytest.mark.parametrize("text, same_as", [
    ("V/A", "Ohm"), ("N*m", "J"), ("W*s", "J"), ("kg*m^2/s^2", "N*m"), ("C/V", "F"), ("V*s/A", "H"),
    ("Pa*m^3", "J"), ("N/m^2", "Pa"), ("1/s", "Hz"), ("rad/s", "Hz"), ("(m/s)^2", "m^2/s^2"), ("m^(1/2)*m^(1/2)", "m"),
    ("kg.m.s^-2", "N"), ("V**2/Ohm", "W"), ("Ω", "Ohm"), ("N*m*s/rad", "kg*m^2/s"), ("1", "rad"),
])
def test_units_of_the_same_dimension(text, same_as):
    assert parse_unit(text).same_dimension(parse_unit(same_as))


@pytest.mark.parametrize("text, other", [("V", "A"), ("N*m", "N"), ("m^3/s", "m^3"), ("kg*m^2", "kg*m")])
def test_units_of_other_dimensions(text, other):
    assert not parse_unit(text).same_dimension(parse_unit(other))


@pytest.mark.parametrize("text, message", [
    ("mH", "'mH' is not a coherent SI unit (no prefixes: give the value in H"),
    ("kPa", "no prefixes: give the value in Pa"),
    ("L/min", "'L' is not a coherent SI unit"),
    ("furlong", "unknown unit symbol 'furlong'"),
    ("N*m/", "a unit symbol is missing at the end"),
    ("(N*m", "a ')' is missing"),
    ("m^x", "exponent"),
    ("N m", "unexpected 'm'"),
    ("2*m", "unexpected '2'"),
    ("__import__('os')", "is not part of a unit"),
    ("", "is not a unit text"),
])
def test_bad_unit_texts_are_refused_naming_the_owner(text, message):
    with pytest.raises(ModelError) as error:
        parse_unit(text, where="R 'b'")
    assert str(error.value).startswith(f"R 'b': unit {text!r}")
    assert message in str(error.value)


def test_a_unit_that_is_not_text_is_refused():
    with pytest.raises(ModelError, match="unit 5 is not a unit text"):
        parse_unit(5, where="R 'b'")


units = st.dictionaries(st.sampled_from(sorted(ATOMS)), st.integers(-3, 3).filter(bool), max_size=4).map(Unit.of)


@settings(derandomize=True, max_examples=200)
@given(units, units)
def test_a_unit_reads_back_from_its_text_and_multiplies_as_powers_add(a, b):
    assert parse_unit(str(a)) == a
    assert (a * b) / b == a
    assert (a * b).same_dimension(parse_unit(f"({a})*({b})"))
    assert (a ** 2).same_dimension(a * a)
    assert str(a / a) == str(DIMENSIONLESS) == "1"


# ------------------------------------------------------------------------------------------ models

@pytest.mark.parametrize("build", LIBRARY)
def test_every_library_model_declares_a_unit_for_each_parameter_and_signal_and_passes(build):
    bg = build()
    units = bg.units
    assert units.declared
    assert set(units.parameters) == set(bg.parameters)
    assert set(units.signals) == set(bg.inputs) | set(bg.outputs)
    assert all(units.efforts.values()) and all(units.flows.values())  # every bond's unit is known


def _heater(**overrides) -> BondGraph:
    """A thermal pseudo bond graph written here: heat flow (W) into a mass (J/K) losing heat through a wall (K/W)."""
    units = {"P": "W", "C_h": "J/K", "R_h": "K/W", "T_h": "K", **overrides}
    bg = BondGraph(name="heater")
    bg.add("P", "Sf", unit=units["P"])
    bg.add("0_h", "0")
    bg.add("C_h", "C", value=500.0, unit=units["C_h"])
    bg.add("R_h", "R", value=2.0, unit=units["R_h"])
    bg.add("T_h", "De", unit=units["T_h"])
    for tail, head in [("P", "0_h"), ("0_h", "C_h"), ("0_h", "R_h"), ("0_h", "T_h")]:
        bg.bond(tail, head)
    return bg


def test_a_consistent_pseudo_bond_graph_passes_and_its_bonds_carry_kelvin_and_watt():
    units = _heater().units
    assert {str(u) for u in units.efforts.values()} == {"K"} and {str(u) for u in units.flows.values()} == {"W"}


@pytest.mark.parametrize("overrides, element, words", [
    ({"R_h": "W/K"}, "R 'R_h'", ["effort of bond '0_h' -> 'R_h' is K", "flow", "is W", "they make K/W"]),
    ({"C_h": "K/W"}, "C 'C_h'", ["they make W*s/K"]),
    # a wrong sensor: the conflict shows where an element meets it, and the message names the sensor
    ({"T_h": "W"}, "R 'R_h'", ["effort of bond '0_h' -> 'R_h' is W (from De 'T_h')"]),
])
def test_an_inconsistent_model_is_refused_naming_the_element(overrides, element, words):
    bg = _heater(**overrides)
    with pytest.raises(ModelError) as error:
        bg.validate()
    message = str(error.value)
    assert message.startswith(f"{element}: unit") and "does not fit its bonds" in message
    for word in words:
        assert word in message


def test_a_wrong_motor_constant_is_refused_naming_the_gyrator_and_the_units_around_it():
    bg = dc_motor()
    bg.graph.nodes["GY"]["unit"] = "N*m"
    with pytest.raises(ModelError, match=r"^GY 'GY': modulus unit N\*m does not fit its bonds: the effort of bond "
                                         r"'1_e' -> 'GY' is V \(from Se 'U'\)"):
        bg.validate()


def test_a_law_whose_terms_differ_in_units_is_refused_naming_the_valve():
    bg = three_tank()
    bg.graph.nodes["az2"]["units"] = {"S_n": "m^2", "g": "m/s"}  # g in m/s: sqrt(2 g |e|) is not a speed
    with pytest.raises(ModelError, match=r"^R 'az2': law .* does not hold in units: the terms .* have units m\^3/s "
                                         r"and m\^3/s\^\(1/2\)"):
        bg.validate()


def test_a_modulus_function_of_a_quantity_with_units_is_refused():
    bg = BondGraph(name="modulated")
    bg.add("U", "Se", unit="V")
    bg.add("S", "MTF", signal="d", modulus="exp(d)", units={"d": "s"})
    bg.add("1_o", "1")
    bg.add("R", "R", value=1.0, unit="Ohm")
    for tail, head in [("U", "S"), ("S", "1_o"), ("1_o", "R")]:
        bg.bond(tail, head)
    with pytest.raises(ModelError, match=r"^MTF 'S': modulus exp\(d\(t\)\): d\(t\) must be a pure number, its unit "
                                         r"is s"):
        bg.validate()


@pytest.mark.parametrize("attributes, message", [
    ({"kind": "0", "unit": "V"}, "a junction has no unit"),
    ({"kind": "R", "value": 1.0, "units": {"x": "m"}}, "'units' names 'x', which is not a law constant"),
    ({"kind": "R", "value": 1.0, "units": "m"}, "'units' must map law constants"),
    ({"kind": "R", "value": 1.0, "unit": "mOhm"}, "not a coherent SI unit"),
])
def test_bad_unit_attributes_are_refused_when_added(attributes, message):
    with pytest.raises(ModelError, match=message):
        BondGraph().add("n", **attributes)


def test_units_are_found_where_only_the_sources_and_sensors_declare_them():
    bg = rlc_circuit()
    for name in ("R", "L", "C"):
        del bg.graph.nodes[name]["unit"]
    units = bg.units
    assert {name: str(units.parameters[name]) for name in ("R", "L", "C")} == {"R": "V/A", "L": "V*s/A", "C": "A*s/V"}
    assert all(units.parameters[name].same_dimension(parse_unit(text))
               for name, text in {"R": "Ohm", "L": "H", "C": "F"}.items())


def test_a_model_without_units_is_not_checked():
    bg = rlc_circuit()
    for _, data in bg.graph.nodes(data=True):
        data.pop("unit", None)
    assert not bg.units.declared and bg.units.text("R", "?") == "?"


def test_units_survive_the_json_model_file():
    bg = torsion_bar_with_load()
    nodes = {node["id"]: node for node in json.loads(to_json(bg))["nodes"]}
    assert nodes["b_Md"]["unit"] == "N*m*s/rad" and nodes["b_Md"]["units"]["g"] == "m/s^2"
    back = model_from_json(to_json(bg)).model
    assert {k: str(v) for k, v in back.units.parameters.items()} == {k: str(v) for k, v in bg.units.parameters.items()}


def test_json_model_with_an_inconsistent_unit_names_the_element():
    data = json.loads(to_json(dc_motor()))
    next(node for node in data["nodes"] if node["id"] == "J")["unit"] = "kg"
    with pytest.raises(ModelError, match=r"^JSON model: I 'J': unit 'kg' does not fit its bonds"):
        model_from_json(json.dumps(data)).model.validate()
