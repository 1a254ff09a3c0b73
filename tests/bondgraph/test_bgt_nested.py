"""Nested BondGraphTools models (bondgraph.bgt_format): a file of sub-models, one of them reused, reads to
the state equations derived by hand, every name the path of its instance (``a.sub.R1``) as
bondgraph.composition names a part's; errors name the model, its instance and the line; a composed model
is written nested and reads back to the same names and equations.  (BondGraphTools' own nested models:
tests/interop/test_bondgraphtools.py.)"""

from __future__ import annotations

import pytest
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph import BondGraph, ModelError, compose
from bondgraph.bgt_format import BGTFileError, model_from_bgt, read_bgt, write_bgt

pytestmark = pytest.mark.extras   # .bg files are YAML: PyYAML, the bgt extra

# BondGraphTools' layout (its modular models): the top model drives, through R1, the sub-model a, which
# holds a capacitor on a 0-junction and two instances of the series RC cell /cell.  a is bonded at its
# port B by name, a.sub by its only port, a.sub2 by name.
LADDER = """\
version: '0.1'
root: ladder
models:
  /:
    components:
    - Se base/Se
    - K base/1
    - R1 base/R r=7
    - a /a
    netlist:
    - Se K.non_inverting
    - K.inverting R1
    - K.inverting a.B
  /a:
    components:
    - P base/SS
    - z base/0
    - C0 base/C C=5
    - sub /cell
    - sub2 /cell
    netlist:
    - P z
    - z C0
    - z sub
    - z sub2.A
    ports:
    - P B
  /cell:
    components:
    - SS1 base/SS
    - J base/1
    - R1 base/R r=2
    - C1 base/C C=3
    netlist:
    - SS1 J.non_inverting
    - J.inverting R1
    - J.inverting C1
    ports:
    - SS1 A
"""


def plain(expression) -> sp.Expr:
    """``expression`` with each function of time (a state, an input ``Se(t)``) as a plain symbol."""
    return sp.sympify(expression).replace(lambda e: isinstance(e, AppliedUndef), lambda e: sp.Symbol(e.func.__name__))


def rhs_by_state(bg) -> dict:
    eqs = bg.state_equations()
    return {str(plain(x)): plain(rhs) for x, rhs in zip(eqs.states, eqs.rhs)}


def test_a_nested_file_reads_to_the_ladder_physics_under_instance_paths():
    bg = read_bgt("ladder.bg", text=LADDER)
    cells = ("a.sub", "a.sub2")
    assert set(bg.graph) == {"Se", "K", "R1", "a.z", "a.C0", *(f"{c}.{n}" for c in cells for n in ("J", "R1", "C1"))}
    assert bg.parameters == {"a.sub.R1": 2.0, "a.sub.C1": 3.0, "a.sub2.R1": 2.0, "a.sub2.C1": 3.0, "a.C0": 5.0,
                             "R1": 7.0}
    # by hand: the 0-junction's effort is the capacitor's, e = q_C0/C0; the loop current (Se - e)/R1 feeds
    # it and leaves through the cells, each carrying (e - q_k/C_k)/r_k into its own capacitor
    se, r1, c0, q0 = sp.symbols("Se R1 a.C0 q_a.C0")
    e = q0 / c0
    current = {c: (e - sp.Symbol(f"q_{c}.C1") / sp.Symbol(f"{c}.C1")) / sp.Symbol(f"{c}.R1") for c in cells}
    expected = {"q_a.C0": (se - e) / r1 - sum(current.values()), **{f"q_{c}.C1": current[c] for c in cells}}
    ours = rhs_by_state(bg)
    assert set(ours) == set(expected)
    for state, rhs in expected.items():
        assert sp.simplify(ours[state] - rhs) == 0, state


def test_two_sub_models_bonded_port_to_port_are_one_loop():
    cell = {"components": ["SS1 base/SS", "J base/1", "R1 base/R 2", "C1 base/C 3"],
            "netlist": ["SS1 J.non_inverting", "J.inverting R1", "J.inverting C1"], "ports": ["SS1 A"]}
    cap = {"components": ["SS1 base/SS", "J base/1", "C1 base/C 4"],
           "netlist": ["SS1 J.non_inverting", "J.inverting C1"], "ports": ["SS1 A"]}
    data = {"version": "0.1", "root": "pair", "models": {
        "/": {"components": ["a /cell", "b /cap"], "netlist": ["a.A b.A"]}, "/cell": cell, "/cap": cap}}
    bg = model_from_bgt(data, where="pair.bg")
    assert set(bg.graph) == {"a.J", "a.R1", "a.C1", "b.J", "b.C1"}
    # both ports take power in, so one loop current i leaves a's capacitor and enters b's:
    # i = (q_b/C_b - q_a/C_a) / R_a, dq_a/dt = i, dq_b/dt = -i
    qa, qb, ca, cb, ra = sp.symbols("q_a.C1 q_b.C1 a.C1 b.C1 a.R1")
    i = (qb / cb - qa / ca) / ra
    ours = rhs_by_state(bg)
    assert set(ours) == {"q_a.C1", "q_b.C1"}
    assert sp.simplify(ours["q_a.C1"] - i) == 0 and sp.simplify(ours["q_b.C1"] + i) == 0


def error(text: str) -> str:
    with pytest.raises(BGTFileError) as caught:
        read_bgt("ladder.bg", text=text)
    message = str(caught.value)
    assert "\n" not in message and message.startswith("ladder.bg: ")
    return message


@pytest.mark.parametrize("change, expected", [
    (("    - J.inverting C1", "    - J.inverting C9"),
     "model '/cell' (as 'a.sub') bond 'J.inverting C9' (line 37): no component 'C9'"),
    (("    - K.inverting a.B", "    - K.inverting a.X"),
     "model '/' bond 'K.inverting a.X' (line 13): sub-model 'a' has no port 'X' (its ports: ['B'])"),
    (("    - P B", "    - z B"), "model '/a' (as 'a') port 'z B' (line 27): 'z' is not a source-sensor"),
    (("    - sub2 /cell", "    - sub2 /cel"), "model '/a' (as 'a') component 'sub2 /cel' (line 20): '/cel' is "),
    (("    - sub /cell", "    - sub /a"), "model '/a' (as 'a.sub'): contains itself (through / -> /a -> /a)"),
])
def test_errors_in_nested_models_name_the_model_its_instance_and_the_line(change, expected):
    text = LADDER.replace(*change)
    assert text != LADDER
    assert expected in error(text)


def rc_stage() -> BondGraph:
    """A source with its resistance feeding an RC load with a voltage sensor, composed, its load's
    terminal a port of its own."""
    source = BondGraph(name="source")
    source.add("U", "Se"), source.add("out", "1"), source.add("R_s", "R", value=1.0)
    source.bond("U", "out"), source.bond("out", "R_s"), source.port("terminal", "out")
    load = BondGraph(name="load")
    load.add("in", "0"), load.add("C", "C", value=1e-3), load.add("R", "R", value=50.0), load.add("v", "De")
    load.bond("in", "C"), load.bond("in", "R"), load.bond("in", "v"), load.port("terminal", "in")
    return compose({"supply": source, "rc": load}, [("supply.terminal", "rc.terminal")],
                   ports={"out": "rc.terminal"}, name="stage")


def test_write_bgt_nests_a_composed_model_and_reads_it_back_with_its_names():
    tail = BondGraph(name="tail")
    tail.add("in", "1"), tail.add("L", "I", value=0.2), tail.add("R", "R", value=3.0), tail.add("i", "Df")
    tail.bond("in", "L"), tail.bond("in", "R"), tail.bond("in", "i"), tail.port("in", "in")
    # the bond stage.rc.in -> tail.in leaves two models on one side and one on the other
    composed = compose({"stage": rc_stage(), "tail": tail}, [("stage.out", "tail.in")], name="two stages")
    text = write_bgt(composed)
    keys = [line.strip()[:-1] for line in text.splitlines() if line.startswith("  /")]
    assert keys == ["/", "/stage", "/stage/supply", "/stage/rc", "/tail"]
    assert "    - stage.in tail.SS_in\n" not in text and "    - stage.in tail.in\n" in text
    back = read_bgt("stages.bg", text=text)
    assert set(back.graph) == set(composed.graph)
    assert back.parameters == composed.parameters
    assert (back.inputs, back.outputs) == (composed.inputs, composed.outputs) == (["stage.supply.U"],
                                                                                 ["stage.rc.v", "tail.i"])
    ours, theirs = rhs_by_state(composed), rhs_by_state(back)
    assert set(ours) == set(theirs) == {"q_stage.rc.C", "p_tail.L"}
    for state in ours:
        assert sp.simplify(ours[state] - theirs[state]) == 0, state


def test_write_bgt_refuses_a_node_named_like_a_part():
    composed = rc_stage()
    graph = composed.graph.copy()
    graph.add_node("rc", kind="R", value=1.0)
    graph.add_edge("supply.out", "rc")
    with pytest.raises(ModelError, match="node 'rc' and the sub-model '/rc' would both be 'rc'"):
        write_bgt(BondGraph(graph))
