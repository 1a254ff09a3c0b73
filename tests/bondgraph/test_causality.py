"""Sequential causality assignment: preferred causalities, dualized detectors, reported issues."""

import pytest

from bondgraph import BondGraph
from bondgraph.library import dc_motor, mass_spring_chain, rlc_circuit, three_tank, torsion_bar, torsion_bar_monitorable


def build(nodes, bonds):
    bg = BondGraph()
    for name, kind, attrs in nodes:
        bg.add(name, kind, **attrs)
    for tail, head in bonds:
        bg.bond(tail, head)
    return bg


def test_rlc_integral_strokes():
    causality = rlc_circuit().assign_causality("integral")
    assert causality.is_valid and not causality.issues
    assert causality.storage == {"L": "integral", "C": "integral"}
    assert causality.effort_from[("V", "J1")] == "V"  # Se imposes effort
    assert causality.effort_from[("J1", "L")] == "J1"  # integral I receives effort
    assert causality.effort_from[("J0", "C")] == "C"  # integral C imposes effort
    assert causality.effort_from[("J1", "R")] == "R"  # R receives the common flow of the 1-junction
    assert causality.stroke(("J0", "C")) == "J0"
    assert not causality.dualized  # detectors stay measurements in integral causality


def test_rlc_derivative_dualizes_detectors():
    causality = rlc_circuit().assign_causality("derivative")
    assert causality.storage == {"L": "derivative", "C": "derivative"}
    assert causality.dualized == {"i": "SSf", "v_C": "SSe"}
    assert causality.effort_from[("J0", "v_C")] == "v_C"  # SSe imposes the effort on its 0-junction
    assert causality.effort_from[("J1", "i")] == "J1"  # SSf imposes the flow on its 1-junction
    assert causality.is_valid


def test_dualization_can_be_turned_off():
    causality = rlc_circuit().assign_causality("derivative", dualize_detectors=False)
    assert not causality.dualized
    assert ("J0", "v_C") not in causality.effort_from


def test_gyrator_and_transformer_rules():
    motor = dc_motor().assign_causality("integral")
    gy_in, gy_out = motor.effort_from[("1_e", "GY")], motor.effort_from[("GY", "1_m")]
    assert (gy_in == "GY") == (gy_out == "GY")  # same role on both ports
    bar = torsion_bar().assign_causality("integral")
    tf_in, tf_out = bar.effort_from[("1_1", "TF")], bar.effort_from[("TF", "1_Md")]
    assert (tf_in == "TF") != (tf_out == "TF")  # effort passes through


def test_torsion_bar_dependent_storage_in_integral_causality():
    causality = torsion_bar().assign_causality("integral")
    assert causality.dependent_storage == ["J_Md"]  # rigid belt: J_Md follows J_m
    issue = next(i for i in causality.issues if i.kind == "dependent storage")
    assert "J_Md" in issue.message and "J_m" in issue.message
    assert causality.storage["J_m"] == "integral"


def test_torsion_bar_shaft_spring_stays_integral_for_diagnosis():
    # Jha et al. (2016), section 6.2: the C element remains in integral causality
    causality = torsion_bar_monitorable().assign_causality("derivative")
    assert causality.storage == {"J_m": "derivative", "J_Md": "derivative", "k_s": "integral", "J_Ld": "derivative"}
    assert causality.dependent_storage == ["k_s"]
    assert causality.is_valid


def test_three_tank_valves_in_conductance_causality():
    causality = three_tank().assign_causality("integral")
    assert set(causality.storage.values()) == {"integral"}
    for valve in ("az1", "az2", "az3"):
        bond = next(key for key in causality.effort_from if valve in key)
        assert causality.effort_from[bond] != valve  # valve receives the level difference


def test_conflict_between_two_effort_sources_is_reported_not_raised():
    bg = build([("a", "Se", {}), ("b", "Se", {}), ("j", "0", {}), ("C", "C", {"value": 1.0})],
               [("a", "j"), ("b", "j"), ("j", "C")])
    causality = bg.assign_causality("integral")
    assert not causality.is_valid
    conflict = causality.conflicts[0]
    assert set(conflict.elements) == {"a", "b"}
    assert "'b'" in conflict.message and "'a'" in conflict.message


def test_flow_source_forces_inertia_into_derivative_causality():
    bg = build([("v", "Sf", {}), ("j", "1", {}), ("m", "I", {"value": 2.0}), ("b", "R", {"value": 1.0})],
               [("v", "j"), ("j", "m"), ("j", "b")])
    causality = bg.assign_causality("integral")
    assert causality.storage == {"m": "derivative"}
    assert causality.dependent_storage == ["m"]
    assert "Sf 'v'" in causality.issues[0].message


def test_algebraic_loop_reported_at_the_resistor():
    bg = build(
        [("u", "Se", {}), ("1a", "1", {}), ("R1", "R", {"value": 1.0}), ("0b", "0", {}),
         ("R2", "R", {"value": 2.0}), ("1c", "1", {}), ("R3", "R", {"value": 3.0}), ("L", "I", {"value": 0.5})],
        [("u", "1a"), ("1a", "R1"), ("1a", "0b"), ("0b", "R2"), ("0b", "1c"), ("1c", "R3"), ("1c", "L")],
    )
    causality = bg.assign_causality("integral")
    assert causality.is_valid
    assert [i.elements for i in causality.algebraic_loops] == [("R1",)]


def test_every_bond_of_the_chain_is_assigned_both_ways():
    bg = mass_spring_chain(20)
    for preferred in ("integral", "derivative"):
        causality = bg.assign_causality(preferred)
        assert causality.is_valid
        assert len(causality.effort_from) == len(causality.bonds)
    derivative = bg.assign_causality("derivative")
    # velocity sensors on every mass: each spring's relative velocity is known, so springs stay integral
    assert {n for n, s in derivative.storage.items() if s == "integral"} == {f"c{i}" for i in range(1, 21)}


def test_unknown_preference_is_rejected():
    with pytest.raises(ValueError, match="integral"):
        rlc_circuit().assign_causality("sideways")
