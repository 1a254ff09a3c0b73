"""A law sympy turns into an infinity (``e/0 - f``) is diagnosed by the ARR derivation, never an AttributeError.

Reading such a law may be refused earlier (bondgraph); the derivation must hold on its own for a model
built from a graph whatever its laws.
"""

import networkx as nx
import pytest

from bondgraph import BondGraph, LawError


def series_circuit(law: str) -> BondGraph:
    """A voltage source, a resistor with ``law``, an inductor and a capacitor in series; current and voltage sensed."""
    g = nx.DiGraph()
    g.add_node("u", kind="Se")
    g.add_node("loop", kind="1")
    g.add_node("R", kind="R", value=4.0, law=law)
    g.add_node("L", kind="I", value=0.2, uncertainty=(-0.05, 0.05))
    g.add_node("cap", kind="0")
    g.add_node("C", kind="C", value=1e-3, uncertainty=(-0.1, 0.1))
    g.add_node("i", kind="Df")
    g.add_node("v", kind="De")
    g.add_edges_from([("u", "loop"), ("loop", "R"), ("loop", "L"), ("loop", "i"), ("loop", "cap"), ("cap", "C"),
                      ("cap", "v")])
    return BondGraph(g)


@pytest.mark.parametrize("law", ["e/0 - f", "f - e/0", "e - R*f/0"])
def test_a_law_dividing_by_zero_is_refused_naming_the_element(law):
    # reading the law refuses it (bondgraph.laws); the derivation's own guard stays behind it
    with pytest.raises(LawError, match=r"R 'R' law: division by zero"):
        series_circuit(law)
