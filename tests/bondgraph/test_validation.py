"""Validation of bond graph models (docs/design.md, "Model contract").

Every check is exercised on a graph built with networkx and wrapped by
``BondGraph(G)`` and, where it makes sense, on the same graph built with the
DSL (``add``/``bond``/``validate``).  Each test asserts the exception type and
that the message names the node, bond, parameter or signal at fault.
"""

from __future__ import annotations

import copy
import math
import re

import networkx as nx
import numpy as np
import pytest
import sympy as sp

from bondgraph import BondGraph, LawError, ModelError


# ---------------------------------------------------------------------------
# A small valid model and the two ways of building it
# ---------------------------------------------------------------------------
def base_graph() -> nx.DiGraph:
    """Valid model: Se -> 1(R, I, TF -> 0(C, R)), Df on the 1, De on the 0.

    ::

        V --> J1 --> R1            J1 --> D1 (Df, signal "i")
              J1 --> L1            J0 --> D2 (De, signal "v")
              J1 --> T1 --> J0 --> C1
                            J0 --> R2
    """
    G = nx.DiGraph(name="test circuit")
    G.add_node("V", kind="Se", signal="u")
    G.add_node("J1", kind="1")
    G.add_node("R1", kind="R", value=2.0, uncertainty=(-0.1, 0.1))
    G.add_node("L1", kind="I", value=0.5, uncertainty=(0.0, 0.2))
    G.add_node("T1", kind="TF", value=2.0)
    G.add_node("J0", kind="0")
    G.add_node("C1", kind="C", value=1e-3)
    G.add_node("R2", kind="R", value=10.0, colour="red")  # extra attribute: kept and ignored
    G.add_node("D1", kind="Df", signal="i")
    G.add_node("D2", kind="De", signal="v")
    G.add_edges_from(
        [("V", "J1"), ("J1", "R1"), ("J1", "L1"), ("J1", "T1"), ("T1", "J0"), ("J0", "C1"), ("J0", "R2")]
    )
    G.add_edge("J1", "D1")
    G.add_edge("J0", "D2")
    return G


def build(G: nx.DiGraph, path: str) -> BondGraph:
    """Build the model of ``G`` with networkx + ``BondGraph(G)`` or with the DSL."""
    if path == "networkx":
        return BondGraph(G)
    bg = BondGraph()
    for name, data in G.nodes(data=True):
        data = dict(data)
        kind = data.pop("kind")
        data.pop("colour", None)  # the DSL refuses what the contract does not know; networkx keeps it
        bg.add(name, kind, **data)
    for tail, head, data in G.edges(data=True):
        bg.bond(tail, head, **data)
    bg.validate()
    return bg


@pytest.fixture(params=["networkx", "dsl"])
def path(request):
    return request.param


def names(*items: str) -> str:
    """A regex requiring every quoted name in the message (in any order)."""
    return "".join(f"(?=.*{re.escape(repr(item))})" for item in items)


def assert_node_local_rejected(G: nx.DiGraph, node: str, *mentions: str, error=ModelError):
    """A node-local fault is caught by BondGraph(G) and at once by the DSL's ``add``."""
    pattern = names(node, *mentions)
    with pytest.raises(error, match=pattern):
        BondGraph(G)
    bg = BondGraph()
    data = dict(G.nodes[node])
    kind = data.pop("kind")
    with pytest.raises(error, match=pattern):
        bg.add(node, kind, **data)  # no bonds yet: the node's own attributes are at fault
    assert node not in bg.graph, "a rejected node must not be added to the graph"


def test_base_graph_is_valid(path):
    bg = build(base_graph(), path)
    assert bg.parameters == {"R1": 2.0, "L1": 0.5, "T1": 2.0, "C1": 1e-3, "R2": 10.0}
    assert bg.inputs == ["u"]
    assert sorted(bg.outputs) == ["i", "v"]
    assert bg.uncertainties == {"R1": (-0.1, 0.1), "L1": (0.0, 0.2)}


# ---------------------------------------------------------------------------
# Kinds
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["X", "r", "Resistor", "2", 2, None, True, ""])
def test_unknown_kind(kind):
    G = base_graph()
    G.nodes["R2"]["kind"] = kind
    assert_node_local_rejected(G, "R2")
    with pytest.raises(ModelError, match=r"(?i)kind"):
        BondGraph(G)


def test_missing_kind():
    G = base_graph()
    del G.nodes["R2"]["kind"]
    with pytest.raises(ModelError, match=names("R2")):
        BondGraph(G)


# ---------------------------------------------------------------------------
# Bonds per element
# ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "node, edit",
    [
        ("R1", lambda G: G.remove_edge("J1", "R1")),  # R with 0 bonds
        ("L1", lambda G: G.remove_edge("J1", "L1")),  # I with 0 bonds
        ("C1", lambda G: G.remove_edge("J0", "C1")),  # C with 0 bonds
        ("R1", lambda G: G.add_edge("J0", "R1")),  # R with 2 bonds
        ("C1", lambda G: G.add_edge("C1", "J1")),  # C with 2 bonds
        ("V", lambda G: G.add_edge("V", "J0")),  # Se with 2 bonds
    ],
    ids=["R-0", "I-0", "C-0", "R-2", "C-2", "Se-2"],
)
def test_one_port_needs_exactly_one_bond(path, node, edit):
    G = base_graph()
    edit(G)
    with pytest.raises(ModelError, match=names(node)):
        build(G, path)


def test_isolated_one_port_is_rejected(path):
    G = base_graph()
    G.add_node("R9", kind="R", value=1.0)
    with pytest.raises(ModelError, match=names("R9")):
        build(G, path)


def _tf_two_entering(G):
    G.remove_edge("T1", "J0")
    G.add_edge("J0", "T1")


def _tf_two_leaving(G):
    G.remove_edge("J1", "T1")
    G.add_edge("T1", "J1")


@pytest.mark.parametrize("kind", ["TF", "GY"])
@pytest.mark.parametrize(
    "edit",
    [_tf_two_entering, _tf_two_leaving, lambda G: G.remove_edge("T1", "J0")],
    ids=["two-entering", "two-leaving", "one-bond"],
)
def test_two_port_needs_one_entering_and_one_leaving_bond(path, kind, edit):
    G = base_graph()
    G.nodes["T1"]["kind"] = kind
    edit(G)
    with pytest.raises(ModelError, match=names("T1")):
        build(G, path)


@pytest.mark.parametrize("junction", ["0", "1"])
@pytest.mark.parametrize("n_bonds", [0, 1])
def test_junction_needs_two_power_bonds(path, junction, n_bonds):
    G = base_graph()
    G.add_node("J9", kind=junction)
    if n_bonds:
        G.add_node("R9", kind="R", value=1.0)
        G.add_edge("J9", "R9")
    with pytest.raises(ModelError, match=names("J9")):
        build(G, path)


def test_junction_signal_bond_does_not_count_as_power_bond(path):
    G = base_graph()
    G.add_node("J9", kind="0")
    G.add_node("R9", kind="R", value=1.0)
    G.add_node("D9", kind="De", signal="y9")
    G.add_edge("J9", "R9")
    G.add_edge("J9", "D9")  # sensor on the junction: no power
    with pytest.raises(ModelError, match=names("J9")):
        build(G, path)


@pytest.mark.parametrize("kinds", [("Se", "Sf"), ("Se", "Se"), ("MSf", "Se")])
def test_bond_between_two_sources(path, kinds):
    G = base_graph()
    G.add_node("S1", kind=kinds[0], signal="s1")
    G.add_node("S2", kind=kinds[1], signal="s2")
    G.add_edge("S1", "S2")
    with pytest.raises(ModelError, match=re.escape("'S1' -> 'S2'")):
        build(G, path)


# ---------------------------------------------------------------------------
# Detectors
# ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "detector, host",
    [("Df", "L1"), ("De", "C1"), ("De", "R1"), ("Df", "V"), ("De", "T1")],
)
def test_detector_on_a_non_junction(path, detector, host):
    G = base_graph()
    G.add_node("D9", kind=detector, signal="y9")
    G.add_edge(host, "D9")
    with pytest.raises(ModelError, match=names("D9", host)):
        build(G, path)


@pytest.mark.parametrize("detector, junction", [("De", "J1"), ("Df", "J0")])
def test_detector_on_the_wrong_junction(path, detector, junction):
    """De must sit on a 0-junction, Df on a 1-junction."""
    G = base_graph()
    G.add_node("D9", kind=detector, signal="y9")
    G.add_edge(junction, "D9")
    with pytest.raises(ModelError, match=names("D9", junction)):
        build(G, path)


# ---------------------------------------------------------------------------
# Values
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("node", ["R1", "C1", "L1", "T1"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, np.nan, np.float64("inf")], ids=str)
def test_non_finite_value(node, value):
    G = base_graph()
    G.nodes[node]["value"] = value
    assert_node_local_rejected(G, node)


@pytest.mark.parametrize("node", ["R1", "C1", "L1", "T1"])
@pytest.mark.parametrize("how", ["absent", "None"])
def test_missing_value(node, how):
    G = base_graph()
    if how == "absent":
        del G.nodes[node]["value"]
    else:
        G.nodes[node]["value"] = None
    assert_node_local_rejected(G, node)
    with pytest.raises(ModelError, match=r"(?i)value"):
        BondGraph(G)


def _value_id(value) -> str:
    """A test id that is the same in every process (xdist compares them): an object()'s repr holds its address."""
    return type(value).__name__ if type(value) is object else repr(value)


@pytest.mark.parametrize("value", ["abc", "1,5", [1.0], (1.0, 2.0), {"R": 1.0}, object(), 1j], ids=_value_id)
def test_non_numeric_value(value):
    G = base_graph()
    G.nodes["R1"]["value"] = value
    assert_node_local_rejected(G, "R1")


# ---------------------------------------------------------------------------
# Uncertainties
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("interval", [(0.2, -0.1), (0.1, -0.1), (0.0, -0.05)])
def test_uncertainty_lo_greater_than_hi(interval):
    G = base_graph()
    G.nodes["R1"]["uncertainty"] = interval
    assert_node_local_rejected(G, "R1")


@pytest.mark.parametrize("interval", [(0.1, 0.2), (-0.2, -0.1), (0.05, 0.05)])
def test_uncertainty_must_contain_zero(interval):
    G = base_graph()
    G.nodes["C1"]["uncertainty"] = interval
    assert_node_local_rejected(G, "C1")


@pytest.mark.parametrize("interval", [(-1.0, 0.1), (-1.5, 0.0), (-2.0, 0.5)])
def test_uncertainty_lower_bound_above_minus_one(interval):
    G = base_graph()
    G.nodes["L1"]["uncertainty"] = interval
    assert_node_local_rejected(G, "L1")


@pytest.mark.parametrize("node", ["J1", "J0", "V", "D1", "D2"])
def test_uncertainty_on_junction_source_or_detector(node):
    G = base_graph()
    G.nodes[node]["uncertainty"] = (-0.1, 0.1)
    assert_node_local_rejected(G, node)


def test_valid_uncertainties_are_accepted():
    G = base_graph()
    G.nodes["R2"]["uncertainty"] = (-0.999, 0.0)
    G.nodes["C1"]["uncertainty"] = (0.0, 0.0)
    bg = BondGraph(G)
    assert bg.uncertainties["R2"] == (-0.999, 0.0)
    assert bg.uncertainties["C1"] == (0.0, 0.0)


# ---------------------------------------------------------------------------
# Shared parameters and signals
# ---------------------------------------------------------------------------
def test_same_parameter_with_conflicting_values(path):
    G = base_graph()
    G.nodes["R1"].update(param="b", value=2.0)
    G.nodes["R2"].update(param="b", value=3.0)
    with pytest.raises(ModelError, match=names("b")) as info:
        build(G, path)
    # and the elements that disagree are named too
    assert "'R1'" in str(info.value) and "'R2'" in str(info.value)


def test_same_parameter_with_equal_values_is_shared(path):
    G = base_graph()
    G.nodes["R1"].update(param="b", value=2.0)
    G.nodes["R2"].update(param="b", value=2.0)
    bg = build(G, path)
    assert bg.parameters == {"b": 2.0, "L1": 0.5, "T1": 2.0, "C1": 1e-3}
    assert bg.elements["R1"].param == bg.elements["R2"].param == "b"


def test_same_signal_on_two_detectors(path):
    G = base_graph()
    G.nodes["D1"]["signal"] = "y"
    G.nodes["D2"]["signal"] = "y"
    with pytest.raises(ModelError, match=names("y")) as info:
        build(G, path)
    assert "'D1'" in str(info.value) or "'D2'" in str(info.value)


def test_default_detector_signals_are_distinct():
    """Without `signal`, a detector measures the signal named after its node."""
    G = base_graph()
    del G.nodes["D1"]["signal"], G.nodes["D2"]["signal"]
    assert sorted(BondGraph(G).outputs) == ["D1", "D2"]


@pytest.mark.parametrize("input_node", ["V", "T1"], ids=["source", "MTF-modulation"])
def test_signal_both_input_and_measurement(path, input_node):
    G = base_graph()
    if input_node == "T1":
        G.nodes["T1"].update(kind="MTF", signal="w")
        del G.nodes["T1"]["value"]
        signal = "w"
    else:
        signal = "u"
    G.nodes["D2"]["signal"] = signal
    with pytest.raises(ModelError, match=names(signal)) as info:
        build(G, path)
    assert "'D2'" in str(info.value) or f"'{input_node}'" in str(info.value)


# ---------------------------------------------------------------------------
# Laws that do not mention their port variables
# ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "node, law, missing",
    [
        ("R1", "e - 5", "f"),
        ("R1", "f - 5", "e"),
        ("R1", "R1*f**2 - 1", "e"),
        ("C1", "e - 1/C1", "q"),
        ("C1", "C1*e**3 - 2", "q"),
        ("C1", "q - C1", "e"),
        ("L1", "f - 1/L1", "p"),
        ("L1", "p - L1", "f"),
        ("R1", sp.Symbol("e") - 5, "f"),
        ("C1", sp.Symbol("e") - 1 / sp.Symbol("C1"), "q"),
    ],
    ids=str,
)
def test_law_must_mention_port_variables(node, law, missing):
    G = base_graph()
    G.nodes[node]["law"] = law
    assert_node_local_rejected(G, node, error=LawError)
    with pytest.raises(LawError, match=re.escape(repr(missing))):
        BondGraph(G)


def test_law_mentioning_port_variables_is_accepted():
    G = base_graph()
    G.nodes["R1"]["law"] = "e - R1*f"
    G.nodes["C1"]["law"] = "e - q/C1"
    G.nodes["L1"]["law"] = "f - p/L1"
    elements = BondGraph(G).elements
    e, f, q, p = sp.symbols("e f q p")
    assert elements["R1"].law == e - sp.Symbol("R1") * f
    assert elements["C1"].law == e - q / sp.Symbol("C1")
    assert elements["L1"].law == f - p / sp.Symbol("L1")


# ---------------------------------------------------------------------------
# Bond labels
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("labels", [(1, 1), ("b3", "b3"), (7, "7")], ids=str)
def test_duplicate_bond_labels(path, labels):
    G = base_graph()
    G.edges["J1", "R1"]["label"] = labels[0]
    G.edges["J1", "L1"]["label"] = labels[1]
    with pytest.raises(ModelError, match=r"'J1' -> '(R1|L1)'"):
        build(G, path)


def test_distinct_bond_labels_are_kept(path):
    G = base_graph()
    G.edges["J1", "R1"]["label"] = 2
    G.edges["V", "J1"]["label"] = 1
    bonds = {bond.key: bond.label for bond in build(G, path).bonds if not bond.is_signal}
    assert bonds[("V", "J1")] == 1 and bonds[("J1", "R1")] == 2
    assert len(set(map(str, bonds.values()))) == len(bonds) == 7


# ---------------------------------------------------------------------------
# DSL
# ---------------------------------------------------------------------------
def test_dsl_add_existing_node_name():
    bg = BondGraph()
    bg.add("R1", "R", value=2.0)
    with pytest.raises(ModelError, match=names("R1")):
        bg.add("R1", "C", value=1e-3)
    assert bg.graph.nodes["R1"] == {"kind": "R", "value": 2.0}, "the existing node must be left alone"


@pytest.mark.parametrize("tail, head, missing", [("J1", "nope", "nope"), ("nope", "J1", "nope")])
def test_dsl_bond_to_missing_node(tail, head, missing):
    bg = BondGraph()
    bg.add("J1", "1")
    with pytest.raises(ModelError, match=names(missing)):
        bg.bond(tail, head)
    assert list(bg.graph.nodes) == ["J1"], "networkx must not create the missing node"
    assert bg.graph.number_of_edges() == 0


def test_dsl_checks_node_attributes_at_once():
    bg = BondGraph()
    with pytest.raises(ModelError, match=names("R1")):
        bg.add("R1", "R", value=math.nan)
    with pytest.raises(ModelError, match=names("J1")):
        bg.add("J1", "1", uncertainty=(-0.1, 0.1))
    assert bg.graph.number_of_nodes() == 0


def test_dsl_and_networkx_give_the_same_model():
    G = base_graph()
    from_nx = BondGraph(G)
    from_dsl = build(base_graph(), "dsl")
    contract = {n: {k: v for k, v in d.items() if k != "colour"} for n, d in G.nodes(data=True)}
    assert dict(from_dsl.graph.nodes(data=True)) == contract  # the DSL refuses the foreign 'colour'
    assert G.nodes["R2"]["colour"] == "red"  # networkx keeps it
    assert list(from_dsl.graph.edges(data=True)) == list(G.edges(data=True))
    assert from_dsl.elements == from_nx.elements
    assert from_dsl.bonds == from_nx.bonds
    assert from_dsl.parameters == from_nx.parameters


# ---------------------------------------------------------------------------
# The user's graph is kept as given
# ---------------------------------------------------------------------------
def test_valid_networkx_graph_is_kept_unmodified():
    G = base_graph()
    G.edges["J1", "R1"]["label"] = 5
    nodes_before = copy.deepcopy(list(G.nodes(data=True)))
    edges_before = copy.deepcopy(list(G.edges(data=True)))
    graph_before = copy.deepcopy(dict(G.graph))

    bg = BondGraph(G)
    assert bg.graph is G
    # use the model: none of this may write into the user's graph
    bg.validate()
    assert set(bg.elements) == set(G.nodes)
    assert len(bg.bonds) == 9 and sum(b.is_signal for b in bg.bonds) == 2
    assert bg.parameters["R1"] == 2.0
    _ = bg.uncertainties, bg.inputs, bg.outputs, repr(bg)

    assert bg.graph is G
    assert list(G.nodes(data=True)) == nodes_before
    assert list(G.edges(data=True)) == edges_before
    assert dict(G.graph) == graph_before
    assert G.nodes["R2"]["colour"] == "red"  # other attributes kept
    assert "label" not in G.edges["V", "J1"]  # automatic numbering is not written back


def test_invalid_graph_is_not_modified():
    G = base_graph()
    G.nodes["R1"]["value"] = math.nan
    nodes_before = copy.deepcopy(list(G.nodes(data=True)))
    edges_before = copy.deepcopy(list(G.edges(data=True)))
    with pytest.raises(ModelError):
        BondGraph(G)
    # nan != nan: compare the repr of the attribute dicts
    assert repr(list(G.nodes(data=True))) == repr(nodes_before)
    assert list(G.edges(data=True)) == edges_before


def test_shared_parameter_with_conflicting_uncertainty_is_rejected():
    bg = BondGraph()
    bg.add("u", "Se"), bg.add("j", "1")
    bg.add("R1", "R", param="b", value=1.0, uncertainty=(-0.1, 0.1))
    bg.add("R2", "R", param="b", value=1.0, uncertainty=(-0.5, 0.5))
    for tail, head in [("u", "j"), ("j", "R1"), ("j", "R2")]:
        bg.bond(tail, head)
    with pytest.raises(ModelError, match=r"'b'.*conflicting uncertainty.*R 'R1'.*R 'R2'"):
        bg.validate()
