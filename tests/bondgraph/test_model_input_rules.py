"""What a model may hold: names not markup, physical domains, a strict DSL, bounded model files.

Each rule is checked where the model reads its elements and bonds, so the DSL, a graph built with
networkx and a JSON file obey it alike; each error names the node and the field at fault.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import networkx as nx
import pytest

from bondgraph import BondGraph, ModelError, assign_causality, io, state_equations, to_json, to_svg
from bondgraph.domains import bounds
from bondgraph.io import MAX_FILE_BYTES, MAX_LINKS, MAX_NODES, ModelFileError, load_model, model_from_json
from bondgraph.library import (dc_motor, friction_drive, mass_spring_chain, rlc_circuit, three_tank, torsion_bar,
                               torsion_bar_with_load)
from bondgraph.names import MAX_NAME_LENGTH, NAME_PATTERN, NODE_ID_PATTERN
from bondgraph.structure import NODE_ATTRIBUTES

INJECTIONS = ["<img src=x onerror=alert(1)>", "}\\input{/etc/passwd}", "a b", "x\x01y", "é", "R-1", ""]


def rc(**resistor) -> BondGraph:
    """Se -> 1 (R, Df:i); the R node takes ``resistor`` as attributes."""
    bg = BondGraph(name="rc")
    bg.add("V", "Se")
    bg.add("J", "1")
    bg.add("R", "R", **{"value": 2.0, **resistor})
    bg.add("i", "Df")
    for tail, head in [("V", "J"), ("J", "R"), ("J", "i")]:
        bg.bond(tail, head)
    return bg


def graph_with(node, **attributes) -> nx.DiGraph:
    """The networkx graph of :func:`rc` with the R node replaced by ``node`` carrying ``attributes``."""
    G = nx.DiGraph()
    G.add_node("V", kind="Se")
    G.add_node("J", kind="1")
    G.add_node(node, **attributes)
    G.add_edges_from([("V", "J"), ("J", node)])
    return G


def json_model(**resistor) -> str:
    data = json.loads(to_json(rc()))
    for node in data["nodes"]:
        if node["id"] == "R":
            node.update(resistor)
    return json.dumps(data)


# ------------------------------------------------------------------------------------------- names

@pytest.mark.parametrize("node", INJECTIONS + ["n" * (MAX_NAME_LENGTH + 1), -3, 2.5, ("a", 1)])
def test_a_node_id_that_is_not_a_name_is_refused_by_every_path(node):
    with pytest.raises(ModelError, match="node id .* is not a name"):
        BondGraph().add(node, "0")
    with pytest.raises(ModelError, match="is not a name"):
        BondGraph(graph_with(node, kind="R", value=1.0))


@pytest.mark.parametrize("node", INJECTIONS[:5])
def test_a_json_node_id_that_is_not_a_name_is_refused_with_the_file_and_position(node):
    data = json.loads(to_json(rc()))
    data["nodes"][2]["id"] = node
    data["links"][1]["target"] = node
    with pytest.raises(ModelFileError) as error:
        model_from_json(json.dumps(data), where="m.json")
    message = str(error.value)
    assert message.startswith("m.json: nodes[2]") and "'id'" in message and "ASCII letters, digits and _" in message
    assert "\n" not in message


@pytest.mark.parametrize("node", ["a.", ".a", "a..b", "a.<b>", "a. b"])
def test_a_path_has_no_empty_part(node):
    with pytest.raises(ModelError, match="node id .* is not a name"):
        BondGraph().add(node, "0")


def test_paths_name_nodes_parameters_and_signals_and_laws_read_them():
    bg = BondGraph()
    bg.add("motor.V", "Se")
    bg.add("motor.1_e", "1")
    bg.add("motor.R", "R", value=2.0, law="e - motor.R*f**3")
    bg.bond("motor.V", "motor.1_e")
    bg.bond("motor.1_e", "motor.R", label="motor.2")
    assert bg.parameters == {"motor.R": 2.0} and bg.inputs == ["motor.V"]
    with pytest.raises(ModelError, match="R 'R': parameter name 'motor.1R' is not an identifier"):
        rc(param="motor.1R")


def test_names_at_the_limits_are_accepted():
    bg = BondGraph()
    bg.add("n" * MAX_NAME_LENGTH, "0")
    bg.add(7, "1")  # integer ids print as their digits
    bg.add("1_2", "0")
    assert list(bg.graph) == ["n" * MAX_NAME_LENGTH, 7, "1_2"]


def test_a_parametric_node_whose_id_is_not_an_identifier_needs_a_param():
    with pytest.raises(ModelError, match=r"R '1R': parameter name '1R' is not an identifier.*give the node a 'param'"):
        BondGraph().add("1R", "R", value=1.0)
    assert BondGraph(graph_with("1R", kind="R", param="R_1", value=1.0)).parameters == {"R_1": 1.0}
    with pytest.raises(ModelError, match="Se 7: signal name '7' is not an identifier.*'signal'"):
        BondGraph().add(7, "Se")


@pytest.mark.parametrize("field, value, what", [
    ("param", "<b>", "parameter name"),
    ("param", "R" * (MAX_NAME_LENGTH + 1), "parameter name"),
    ("params", {"a b": 1.0}, "constant name"),
    ("params", {3: 1.0}, "constant name"),
])
def test_parameter_and_constant_names_are_identifiers(field, value, what):
    with pytest.raises(ModelError, match=f"R 'R': {what} .* is not an identifier"):
        rc(**{field: value})


def test_reserved_names_stay_reserved():
    with pytest.raises(ModelError, match="R 'R': parameter name 'e' is reserved"):
        rc(param="e")
    with pytest.raises(ModelError, match="R 'R': constant name 'q' is reserved"):
        rc(params={"q": 1.0})
    with pytest.raises(ModelError, match="Se 'V': signal name 't' is reserved"):
        BondGraph().add("V", "Se", signal="t")


def test_signal_names_are_identifiers():
    bg = BondGraph()
    with pytest.raises(ModelError, match=r"Se 'V': signal name 'u\(t\)' is not an identifier"):
        bg.add("V", "Se", signal="u(t)")
    with pytest.raises(ModelError, match="Df 'i': signal name"):
        bg.add("i", "Df", signal="$i$")


def test_bond_labels_are_names():
    bg = BondGraph()
    bg.add("V", "Se")
    bg.add("R", "R", value=1.0)
    with pytest.raises(ModelError, match=r"bond \('V' -> 'R'\): label '<1>' is not a name"):
        bg.bond("V", "R", label="<1>")
    G = graph_with("R", kind="R", value=1.0)
    G.edges["J", "R"]["label"] = "}\\write18"
    with pytest.raises(ModelError, match=r"bond \('J' -> 'R'\): label"):
        BondGraph(G)
    data = json.loads(to_json(rc()))
    data["links"][0]["label"] = "a b"
    with pytest.raises(ModelFileError, match=r"links\[0\].*'label' 'a b' is not a name"):
        model_from_json(json.dumps(data), where="m.json")
    assert bg.bond("V", "R", label=12) == ("V", "R")


def test_the_patterns_are_what_the_documentation_says():
    identifier = "[A-Za-z_][A-Za-z0-9_]*"
    assert NODE_ID_PATTERN == r"[A-Za-z0-9_]+(?:\.[A-Za-z0-9_]+)*" and MAX_NAME_LENGTH == 64
    assert NAME_PATTERN == identifier + r"(?:\." + identifier + ")*"
    text = (Path(__file__).resolve().parents[2] / "docs" / "model.md").read_text(encoding="utf-8")
    assert NODE_ID_PATTERN in text and NAME_PATTERN in text and "64" in text


def test_the_display_name_stays_free_text():
    bg = rc()
    bg.name = "<b>motor</b> $1 & {2}"
    assert bg.validate() is None and "<b>motor</b>" in repr(bg)


# ------------------------------------------------------------------------------------------- domains

@pytest.mark.parametrize("kind", ["R", "C", "I"])
def test_zero_is_refused_for_r_c_and_i_naming_node_parameter_and_domain(kind):
    pattern = rf"{kind} 'X': parameter 'X' = 0 is not allowed: its linear law divides by it .*; domain positive"
    with pytest.raises(ModelError, match=pattern):
        BondGraph().add("X", kind, value=0.0)
    with pytest.raises(ModelError, match=pattern):
        BondGraph(graph_with("X", kind=kind, value=0))
    with pytest.raises(ModelError, match=r"m.json: R 'R': parameter 'R' = 0 is not allowed: .*\(f = e/R\)"):
        model_from_json(json_model(value=0), where="m.json")


def test_a_negative_capacitance_is_refused_unless_declared():
    with pytest.raises(ModelError, match=r"C 'C1': parameter 'C1' = -0.001 is outside its domain positive.*'domain'"):
        BondGraph().add("C1", "C", value=-1e-3)
    bg = BondGraph(graph_with("C1", kind="C", value=-1e-3, domain="negative", uncertainty=(-0.1, 0.1)))
    assert bg.elements["C1"].domain == "negative" and bg.domains == {"C1": (-math.inf, 0.0)}
    # a linear C, I or R divides by its parameter: zero stays refused whatever the domain
    with pytest.raises(ModelError, match=r"= 0 is not allowed: its linear law divides by it \(e = q/C\); domain real"):
        BondGraph().add("C2", "C", value=0.0, domain="real")


def test_a_law_keeps_the_positive_default_of_its_element():
    with pytest.raises(ModelError, match="parameter 'a' = -0.3 is outside its domain positive"):
        BondGraph().add("valve", "R", param="a", value=-0.3, law="f - a*sqrt(Abs(e))")
    bg = BondGraph(graph_with("valve", kind="R", param="a", value=0.0, law="f - a*sqrt(Abs(e))", domain="real"))
    assert bg.parameters == {"a": 0.0}  # a closed valve, declared


def test_two_ports_and_sources_default_to_real():
    bg = BondGraph()
    bg.add("S", "Se", value=-5.0)
    bg.add("T", "TF", value=-2.0)
    bg.add("X", "R", value=1.0)
    bg.bond("S", "T")
    bg.bond("T", "X")
    assert (bg.elements["T"].domain, bg.elements["S"].domain) == ("real", "real")
    assert bg.domains == {"T": (-math.inf, math.inf), "X": (0.0, math.inf)}
    with pytest.raises(ModelError, match=r"Se 'P': value = -5 is outside its domain positive"):
        bg.add("P", "Se", value=-5.0, domain="positive")


def test_an_uncertainty_box_may_not_leave_the_domain():
    with pytest.raises(ModelError, match=r"uncertainty \(-1.5, 0.1\) of parameter 'R' lets it reach -1, "
                                         r"outside its domain positive"):
        rc(uncertainty=(-1.5, 0.1))
    with pytest.raises(ModelError, match=r"lets parameter 'T' reach zero or change sign \(need lo > -1"):
        BondGraph().add("T", "TF", value=2.0, uncertainty=(-1.0, 0.0))  # real: the multiplicative form is the limit
    assert rc(uncertainty=(-0.99, 0.5)).uncertainties == {"R": (-0.99, 0.5)}


def test_nonzero_reports_the_half_line_of_its_value():
    bg = BondGraph()
    bg.add("T", "TF", value=-2.0, domain="nonzero")
    bg.add("G", "GY", value=3.0)
    bg.add("J", "1")
    bg.add("X", "R", value=5.0, domain="nonzero")
    bg.add("S", "Se")
    for tail, head in [("S", "T"), ("T", "G"), ("G", "J"), ("J", "X")]:
        bg.bond(tail, head)
    assert bg.domains == {"T": (-math.inf, 0.0), "G": (-math.inf, math.inf), "X": (0.0, math.inf)}
    with pytest.raises(ModelError, match="= 0 is outside its domain nonzero"):
        BondGraph().add("T", "TF", value=0.0, domain="nonzero")


@pytest.mark.parametrize("attributes, message", [
    ({"kind": "0", "domain": "positive"}, "0 'X': has a domain but no parameter or value"),
    ({"kind": "R", "value": 1.0, "domain": "postive"},
     "domain 'postive' is not one of positive, negative, nonzero, real"),
    ({"kind": "R", "value": 1.0, "domain": 1}, "domain 1 is not one of"),
    ({"kind": "R", "value": 1.0, "domains": {"g": "positive"}},
     r"'domains' names \['g'\], which are not law constants"),
    ({"kind": "R", "value": 1.0, "domains": ["positive"]}, "'domains' must map law constants"),
])
def test_bad_domains_are_named(attributes, message):
    kind = attributes.pop("kind")
    with pytest.raises(ModelError, match=message):
        BondGraph().add("X", kind, **attributes)


def test_law_constants_are_real_unless_declared():
    law = "e - b*f - mu*sign(f)"
    # real by default: the sign of a constant is the law's business
    assert BondGraph(graph_with("b", kind="R", value=1.0, params={"mu": -0.2}, law=law)).domains["mu"] == (
        -math.inf, math.inf)
    bg = BondGraph()
    with pytest.raises(ModelError, match=r"R 'c': constant 'mu' = -0.2 is outside its domain positive \(0, inf\)$"):
        bg.add("c", "R", param="b2", value=1.0, params={"mu": -0.2}, domains={"mu": "positive"},
               law="e - b2*f - mu*sign(f)")
    with pytest.raises(ModelError, match=r"uncertainty \(-1.0, 0.0\) lets constant 'mu' reach zero"):
        bg.add("d", "R", param="b3", value=1.0, params={"mu": 0.2}, uncertainties={"mu": (-1.0, 0.0)},
               law="e - b3*f - mu*sign(f)")


def test_a_shared_constant_lies_in_every_domain_given_to_it():
    def model(first: str, second: str) -> BondGraph:
        bg = BondGraph()
        bg.add("S", "Sf")
        bg.add("J", "0")
        for name, domain in (("a1", first), ("a2", second)):
            bg.add(name, "R", value=1.0, params={"g": 9.81}, domains={"g": domain},
                   law=f"f - {name}*sqrt(g*Abs(e))")
        for tail, head in [("S", "J"), ("J", "a1"), ("J", "a2")]:
            bg.bond(tail, head)
        return bg

    assert model("nonzero", "real").domains["g"] == (0.0, math.inf)
    assert model("positive", "nonzero").domains["g"] == (0.0, math.inf)
    assert model("real", "real").domains["g"] == (-math.inf, math.inf)
    with pytest.raises(ModelError, match="R 'a2': constant 'g' = 9.81 is outside its domain negative"):
        model("positive", "negative")


def test_library_models_expose_their_domains():
    assert dc_motor().domains == {"R_a": (0.0, math.inf), "L_a": (0.0, math.inf), "k_m": (0.0, math.inf),
                                  "J": (0.0, math.inf), "b": (0.0, math.inf)}
    assert friction_drive().domains["r2"] == torsion_bar().domains["k_belt"] == (0.0, math.inf)
    tanks = three_tank().domains
    assert tanks["az1"] == tanks["A_1"] == tanks["S_n"] == tanks["g"] == (0.0, math.inf)
    load = torsion_bar_with_load().domains
    assert all(load[p] == (0.0, math.inf) for p in ("M", "mu", "g", "r_Md", "b_Md"))
    for bg in (dc_motor(), three_tank(), torsion_bar_with_load(), friction_drive(), torsion_bar()):
        assert set(bg.domains) == set(bg.parameters)
        assert all(lo < bg.parameters[p] < hi for p, (lo, hi) in bg.domains.items())
    assert bounds("positive") == (0.0, math.inf)


def test_json_carries_the_domains():
    bg = rc(domain="nonzero", value=-2.0, params={"k": 1.0}, domains={"k": "positive"}, law="e - R*f - k*sign(f)")
    text = to_json(bg)
    node = next(n for n in json.loads(text)["nodes"] if n["id"] == "R")
    assert node["domain"] == "nonzero" and node["domains"] == {"k": "positive"}
    back = model_from_json(text).model
    assert back.elements["R"].domain == "nonzero" and back.domains == {"R": (-math.inf, 0.0), "k": (0.0, math.inf)}
    with pytest.raises(ModelFileError, match="'domain' must be a string"):
        model_from_json(json_model(domain=["positive"]), where="m.json")


# ------------------------------------------------------------------------------------------- DSL strictness

def test_the_dsl_refuses_an_unknown_keyword_naming_the_nearest():
    with pytest.raises(ModelError, match=re.escape("R 'R': unknown attribute 'uncertanty' "
                                                   "(did you mean 'uncertainty'?)")):
        BondGraph().add("R", "R", value=10, uncertanty=(-0.05, 0.05))
    with pytest.raises(ModelError, match=r"R 'R': unknown attribute 'colour' \(known: description, domain, "):
        BondGraph().add("R", "R", value=10, colour="red")
    bg = BondGraph()
    bg.add("V", "Se")
    bg.add("R", "R", value=1.0)
    with pytest.raises(ModelError, match=re.escape("bond ('V' -> 'R'): unknown attribute 'lable' "
                                                   "(did you mean 'label'?)")):
        bg.bond("V", "R", lable=3)
    assert bg.graph.number_of_edges() == 0


def test_a_networkx_graph_keeps_foreign_attributes_but_not_misspelt_ones():
    G = graph_with("R", kind="R", value=1.0, colour="red", pos=(0, 1), name="resistor")
    assert BondGraph(G).parameters == {"R": 1.0} and G.nodes["R"]["colour"] == "red"
    G.nodes["R"]["uncertanty"] = (-0.1, 0.1)
    with pytest.raises(ModelError, match=r"R 'R': unknown attribute 'uncertanty' \(did you mean 'uncertainty'\?\)"):
        BondGraph(G)
    del G.nodes["R"]["uncertanty"]
    G.edges["J", "R"]["weight"] = 2.0  # foreign: kept
    BondGraph(G)
    G.edges["J", "R"]["lable"] = "b1"
    with pytest.raises(ModelError, match=r"bond \('J' -> 'R'\): unknown attribute 'lable'"):
        BondGraph(G)


def test_the_dsl_and_the_json_loader_share_one_list_of_node_fields():
    assert io.NODE_FIELDS == NODE_ATTRIBUTES | {"id"}
    assert {"domain", "domains", "uncertainty", "uncertainties"} <= NODE_ATTRIBUTES
    bg = rc(uncertainty=(-0.05, 0.05), description="the load")
    again = model_from_json(to_json(bg)).model
    assert again.uncertainties == {"R": (-0.05, 0.05)}


# ------------------------------------------------------------------------------------------- model size

def test_a_file_over_the_size_limit_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "big.json"
    with open(path, "wb") as file:
        file.truncate(MAX_FILE_BYTES + 1)  # sparse: nothing written, nothing read
    with pytest.raises(ModelFileError, match=rf"big.json: {MAX_FILE_BYTES + 1} bytes, larger than the limit of "
                                             rf"{MAX_FILE_BYTES} bytes"):
        load_model(path)
    with pytest.raises(ModelFileError, match="characters, longer than the limit"):
        model_from_json(" " * (MAX_FILE_BYTES + 1))


@pytest.mark.parametrize("key, limit", [("nodes", MAX_NODES), ("links", MAX_LINKS)])
def test_too_many_nodes_or_links_are_refused_before_anything_is_built(key, limit, monkeypatch):
    def never(*args):
        raise AssertionError("a node or link was built")

    monkeypatch.setattr(io, "_add_node", never)
    monkeypatch.setattr(io, "_add_link", never)
    data = {"nodes": [], "links": []}
    data[key] = [{}] * (limit + 1)
    with pytest.raises(ModelFileError, match=rf"m.json: {limit + 1} {key}, more than the limit of {limit} "
                                             rf"\(bondgraph.io.MAX_{key.upper()}\)"):
        model_from_json(json.dumps(data), where="m.json")


@pytest.mark.slow
def test_a_model_at_the_node_limit_loads():
    stages = (MAX_NODES - 1) // 6  # a chain stage has 6 nodes
    text = to_json(mass_spring_chain(stages))
    assert len(text) < MAX_FILE_BYTES / 4
    model = model_from_json(text).model
    assert MAX_NODES - 6 < model.graph.number_of_nodes() <= MAX_NODES


# ------------------------------------------------------------------------------------------- API misuse

@pytest.mark.parametrize("call, name", [
    (lambda: assign_causality("dc-motor"), "assign_causality"),
    (lambda: state_equations("dc-motor"), "state_equations"),
    (lambda: to_svg("dc-motor"), "layout"),
    (lambda: to_json("dc-motor"), "to_json"),
])
def test_a_model_name_in_place_of_a_model_is_a_type_error_naming_the_argument(call, name):
    with pytest.raises(TypeError, match=re.escape(f"{name}: bg must be a BondGraph, got str 'dc-motor' "
                                                  "(use bondgraph.load_model('dc-motor').model)")):
        call()


def test_other_objects_in_place_of_a_model_are_named_too():
    with pytest.raises(TypeError, match=r"assign_causality: bg must be a BondGraph, got NoneType None$"):
        assign_causality(None)
    with pytest.raises(TypeError, match=r"got PosixPath\('m.json'\) \(use bondgraph.load_model\('m.json'\).model\)"):
        assign_causality(Path("m.json"))
    assert assign_causality(rlc_circuit()).is_valid


def test_an_empty_model_is_refused_in_one_line():
    from diagnosis.report import arr_report

    with pytest.raises(ModelFileError, match="'nodes' is empty"):
        model_from_json('{"nodes": [], "links": []}')
    with pytest.raises(ModelError, match="an empty bond graph has nothing to draw"):
        arr_report(BondGraph())
