"""Units of the zoo: every model declares the SI unit of each parameter, signal and bond, and passes the
dimensional check (:mod:`bondgraph.dimensions`); a unit made wrong is refused naming its element."""

import pytest

from bondgraph import ModelError
from bondgraph.elements import JUNCTIONS
from tests.zoo.check import load_case, model_names

MODELS = model_names()


def test_the_zoo_is_all_here():
    assert len(MODELS) >= 32


@pytest.mark.parametrize("name", MODELS)
def test_every_zoo_model_declares_its_units_and_passes_the_check(name):
    bg = load_case(name).build()
    bg.validate()
    units = bg.units
    assert units.declared
    undeclared = [str(e) for e in bg.elements.values() if e.kind not in JUNCTIONS and e.unit is None and not e.units]
    assert undeclared == []
    assert set(units.parameters) == set(bg.parameters)             # law constants included, nothing more
    assert set(units.signals) == set(bg.inputs) | set(bg.outputs)  # sources, modulating signals and sensors
    unknown = [b.key for b in bg.bonds if units.efforts[b.key] is None or units.flows[b.key] is None]
    assert unknown == []


# (model, element, attributes made wrong): the mistakes a user makes, one at a time
WRONG = [
    ("rc_ladder2", "R_2", {"unit": "F"}),                       # a resistance given the unit of a capacitance
    ("heat_exchanger", "C_h", {"unit": "K/W"}),                 # a heat capacity given a thermal resistance's
    ("pipe_tank", "L_f", {"unit": "Pa*s/m^3"}),                 # an inertance given a resistance's
    ("dc_generator", "G", {"unit": "N*m"}),                     # a motor constant given a torque's
    ("hydraulic_cylinder", "piston", {"unit": "1/m^2"}),        # the unit of the modulus 1/A_p, not of A_p
    ("duffing_oscillator", "k", {"units": {"k_3": "N/m"}}),     # the cubic constant given a linear stiffness's
    ("flywheel_speed_loop", "c_a", {"unit": "N*m*s/rad"}),      # quadratic drag given a viscous friction's
    ("wall_two_layer", "T_o", {"unit": "W"}),                   # a temperature source given a heat flow's
    ("loudspeaker", "v_c", {"unit": "rad/s"}),                  # a cone velocity read as an angular one
]


@pytest.mark.parametrize("name, node, wrong", WRONG, ids=[f"{m}-{n}" for m, n, _ in WRONG])
def test_a_wrong_unit_in_a_zoo_model_is_refused_naming_its_element(name, node, wrong):
    bg = load_case(name).build()
    bg.graph.nodes[node].update(wrong)
    with pytest.raises(ModelError) as error:
        bg.validate()
    message = str(error.value)
    element = f"{bg.graph.nodes[node]['kind']} '{node}'"
    assert message.startswith(f"{element}:") or f"(from {element})" in message, message
