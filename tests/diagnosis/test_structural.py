"""diagnosis.structural: overdetermined parts, MSO sets and fault signatures from a bond graph's equations."""

import warnings

import networkx as nx
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from bondgraph import BondGraph
from bondgraph import library as lib
from bondgraph.equations import ModelEquation, labelled_equations, model_equations
from diagnosis.structural import StructuralLimitError, StructuralModel, structural_model


def without(bg: BondGraph, node: str) -> BondGraph:
    graph = bg.graph.copy()
    graph.remove_node(node)
    return BondGraph(graph)


MODELS = {
    "dc motor": lib.dc_motor,
    "dc motor, speed sensor only": lambda: without(lib.dc_motor(), "i"),
    "three-tank": lib.three_tank,
    "torsion bar, monitorable part": lib.torsion_bar_monitorable,
    "torsion bar": lib.torsion_bar,
}


@pytest.fixture(scope="module", params=list(MODELS))
def model(request):
    return structural_model(MODELS[request.param]())


# ------------------------------------------------------------------------------------ the equations

def test_labelled_equations_are_the_model_equations_with_their_node_and_role():
    motor = lib.dc_motor()
    labelled = labelled_equations(motor)
    assert [m.equation for m in labelled] == model_equations(motor)
    roles = [m.role for m in labelled]
    assert roles.count("sensor") == 2 and roles.count("balance") == 2 and roles.count("storage") == 2
    assert {m.node for m in labelled if m.role == "law"} == {"R_a", "L_a", "J", "b"}


def test_unknowns_are_bond_variables_and_states_never_signals_or_parameters():
    model = structural_model(lib.dc_motor())
    law_of_l = next(i for i, m in enumerate(model.equations) if m.node == "L_a" and m.role == "law")
    storage_of_l = next(i for i, m in enumerate(model.equations) if m.node == "L_a" and m.role == "storage")
    assert model.unknowns[law_of_l] == {"f_3", "state L_a"}
    assert model.unknowns[storage_of_l] == {"e_3", "state L_a"}   # dp/dt counts as the state
    sensor = next(iter(model.faults["sensor i"]))
    assert model.unknowns[sensor] == {"f_1"}


# -------------------------------------------------- detectability and isolability on whole models

def test_dc_motor_with_its_speed_sensor_only_has_one_relation_that_sees_every_parameter():
    model = structural_model(MODELS["dc motor, speed sensor only"]())
    assert model.redundancy() == 1
    assert len(model.mso_sets()) == 1
    assert {"R_a", "L_a", "k_m", "J", "b"} <= model.detectable()


def test_every_parameter_of_the_full_torsion_bar_is_detectable_and_k_belt_isolable():
    model = structural_model(lib.torsion_bar())
    parameters = {f for f in model.faults if not f.startswith("sensor")}
    assert len(parameters) == 12 and parameters <= model.detectable()
    assert model.isolability()["k_belt"] == set(model.faults) - {"k_belt"}


@pytest.mark.parametrize("bg, faults", [(lib.three_tank, ["az1", "az3"]), (lib.dc_motor, ["k_m"])])
def test_with_sensor_faults_the_full_structure_still_isolates(bg, faults):
    model = structural_model(bg())
    assert any(f.startswith("sensor") for f in model.faults)
    isolability = model.isolability()
    for fault in faults:
        assert isolability[fault] == set(model.faults) - {fault}


def test_healthy_sensors_switch_removes_the_sensor_faults():
    model = structural_model(lib.three_tank(), sensor_faults=False)
    assert model.faults and not any(f.startswith("sensor") for f in model.faults)


# --------------------------------------------------------------- two routes to the same signatures

def test_mso_sets_give_the_detectability_and_isolability_of_the_whole_structure(model):
    msos = model.mso_sets()
    assert msos and all(model.redundancy(m) == 1 and model.overdetermined(m) == m for m in msos)
    assert len(set(msos)) == len(msos)
    detectable = {f for f, rows in model.faults.items() if any(rows & m for m in msos)}
    assert detectable == model.detectable()
    isolability = {a: {b for b in model.faults if b != a and any(model.faults[a] & m and not model.faults[b] & m
                                                                 for m in msos)}
                   for a in model.faults}
    assert isolability == model.isolability()


def test_each_mso_set_is_minimal(model):
    for mso in model.mso_sets():
        assert all(model.redundancy(mso - {i}) == 0 for i in mso)


def test_describe_names_the_junctions_and_elements_a_set_uses():
    model = structural_model(MODELS["dc motor, speed sensor only"]())
    (mso,) = model.mso_sets()
    used = model.describe(mso)
    assert "1_e balance" in used and "1_m balance" in used and "omega sensor" in used and "GY transformer" in used


def test_the_search_stops_with_a_clear_error_over_its_limit():
    with pytest.raises(StructuralLimitError, match="more than 2 overdetermined subsets"):
        structural_model(lib.three_tank()).mso_sets(limit=2)


# ------------------------------------------- the overdetermined part against its definition

def _matching_size(model: StructuralModel, rows) -> int:
    graph = nx.Graph()
    top = [("e", i) for i in rows]
    graph.add_nodes_from(top)
    graph.add_edges_from((("e", i), ("x", x)) for i in rows for x in model.unknowns[i])
    return len(nx.bipartite.hopcroft_karp_matching(graph, top_nodes=top)) // 2


def _synthetic(incidence) -> StructuralModel:
    equations = tuple(ModelEquation(sp.Eq(sp.Symbol(f"r{i}"), 0), f"n{i}", "law") for i in range(len(incidence)))
    return StructuralModel(equations, tuple(frozenset(row) for row in incidence), {})


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(st.lists(st.sets(st.integers(0, 6), min_size=1, max_size=3), min_size=1, max_size=9))
def test_overdetermined_part_is_where_removing_an_equation_lowers_the_redundancy(incidence):
    """phi(M) = |M| - (maximum matching of M); M+ holds exactly the equations whose removal lowers phi."""
    model = _synthetic(incidence)
    everything = model.all
    phi = len(everything) - _matching_size(model, everything)
    expected = {i for i in everything if len(everything) - 1 - _matching_size(model, everything - {i}) < phi}
    assert model.overdetermined() == expected
    assert model.redundancy() == phi


@pytest.mark.slow
def test_current_arrs_are_no_more_than_the_structure_allows():
    """Every fault our ARRs see, the structure sees too (the structural route is the upper bound)."""
    from diagnosis import derive_arrs, signature_matrix

    for bg in (lib.dc_motor(), lib.three_tank(), lib.torsion_bar_monitorable()):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            signatures = signature_matrix(derive_arrs(bg))
        seen = {row for row, detectable in zip(signatures.rows, signatures.detectable) if detectable}
        assert seen <= structural_model(bg).detectable()
