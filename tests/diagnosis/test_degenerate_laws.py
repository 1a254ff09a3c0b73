"""A law sympy turns into an infinity (``e/0 - f``) is diagnosed by the ARR derivation, never an AttributeError.

Reading such a law may be refused earlier (bondgraph); the derivation must hold on its own for a model
built from a graph whatever its laws.
"""

import warnings

import networkx as nx
import pytest
import sympy as sp

from bondgraph import BondGraph
from diagnosis import ARRWarning, derive_arrs
from diagnosis.junctions import junction_arrs


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
def test_a_law_dividing_by_zero_leaves_only_finite_arrs_and_says_which_element(law):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        arrs = derive_arrs(series_circuit(law), max_order=None, isolation=True)
    for arr in arrs:
        assert not arr.nominal.has(sp.zoo, sp.oo, sp.nan), arr.name
        assert not arr.uncertain.has(sp.zoo, sp.oo, sp.nan), arr.name
    # the capacitor's balance needs no resistor: it stays
    assert any(set(arr.signals) == {"i", "v"} and "C" in arr.parameters for arr in arrs)
    messages = [str(w.message) for w in caught if issubclass(w.category, ARRWarning)]
    assert any("R law" in m and "not finite" in m for m in messages), messages


def test_the_junction_route_skips_a_non_finite_balance_naming_the_law():
    with pytest.warns(ARRWarning, match=r"ARR_loop: left out.*R 'R'.*divides by zero"):
        arrs = junction_arrs(series_circuit("e/0 - f"))
    assert [arr.name for arr in arrs] == ["ARR_cap"]
