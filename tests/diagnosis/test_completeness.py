"""Cross-check: the ARRs reach every detection and isolation the closed-form minimal overdetermined sets reach.

An independent structural analysis, written here over the equations the bond graph gives: its own
maximum matchings (networkx), its own overdetermined parts and minimal sets.  A minimal set counts
when it has a closed form (``arr_from_set``): a set whose only residual needs an ODE solved (a
Kelvin-Voigt shaft driven by its torque) or a relation of more than ``MAX_OPERATIONS`` is not an ARR.
"""

import warnings

import networkx as nx
import pytest

from bondgraph import BondGraph
from bondgraph import library as lib
from diagnosis import ARRWarning, derive_arrs, structural_model
from diagnosis.elimination import arr_from_set, faults_of_arr


def _overdetermined(unknowns: list, rows: frozenset) -> frozenset:
    """Equations whose removal lowers |rows| - (maximum matching): the definition of M+, by brute force."""
    def excess(subset):
        graph = nx.Graph()
        graph.add_nodes_from(("e", i) for i in subset)
        graph.add_edges_from((("e", i), ("x", x)) for i in subset for x in unknowns[i])
        return len(subset) - len(nx.bipartite.maximum_matching(graph, top_nodes=[("e", i) for i in subset])) // 2
    total = excess(rows)
    return frozenset(i for i in rows if excess(rows - {i}) < total)


def _minimal_sets(unknowns: list) -> set:
    """Every minimal overdetermined set: M+ of the whole, then of each one-smaller subset, down to redundancy 1."""
    found, seen, stack = set(), set(), [_overdetermined(unknowns, frozenset(range(len(unknowns))))]
    while stack:
        current = stack.pop()
        if not current or current in seen:
            continue
        seen.add(current)
        smaller = [_overdetermined(unknowns, current - {i}) for i in current]
        if not any(smaller):
            found.add(current)
        stack.extend(smaller)
    return found


def _signatures(faults: dict, supports: list) -> tuple[set, set]:
    detected = set().union(*supports) if supports else set()
    isolated = {(a, b) for a in faults for b in faults if a != b and any(a in s and b not in s for s in supports)}
    return detected, isolated


def speed_only_motor() -> BondGraph:
    graph = lib.dc_motor().graph.copy()
    graph.remove_node("i")
    return BondGraph(graph)


@pytest.mark.slow
@pytest.mark.parametrize("bg", [lib.three_tank, lib.dc_motor, speed_only_motor, lib.torsion_bar_monitorable,
                                lib.torsion_bar],
                         ids=["three-tank", "dc motor", "dc motor, speed sensor only", "torsion bar, monitorable",
                              "torsion bar"])
def test_detectability_and_isolability_equal_those_of_the_closed_form_minimal_sets(bg):
    model_bg = bg()
    model = structural_model(model_bg)
    sets = _minimal_sets(list(model.unknowns))
    assert set(model.mso_sets()) == sets   # the library's search finds the same sets
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        closed = []
        for rows in sets:
            try:
                closed.append(faults_of_arr(model, arr_from_set(model_bg, rows, model=model)))
            except ValueError:
                continue
        arrs = derive_arrs(model_bg, max_order=None, isolation=True)
    ours = _signatures(model.faults, [faults_of_arr(model, arr) for arr in arrs])
    assert ours == _signatures(model.faults, closed)
