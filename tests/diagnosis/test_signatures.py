"""Fault signature matrix against the structure of the bond graph: the three tanks of Du et al."""

import networkx as nx

from bondgraph.library import three_tank
from diagnosis import derive_arrs, signature_matrix


def test_signature_matrix_matches_the_structure_of_the_bond_graph():
    """Structural result: a tank's balance (0-junction) sees its C and every valve (R on a 1-junction) it touches."""
    bg = three_tank()
    graph = bg.graph.to_undirected()
    kinds = nx.get_node_attributes(bg.graph, "kind")
    structural = {}
    for junction in (n for n, k in kinds.items() if str(k) == "0"):
        seen = {n for n in graph[junction] if kinds[n] == "C"}
        for one in (n for n in graph[junction] if str(kinds[n]) == "1"):
            seen |= {n for n in graph[one] if kinds[n] == "R"}
        for valve in (n for n in graph[junction] if kinds[n] == "R"):
            seen.add(valve)
        structural[f"ARR_{junction}"] = seen
    fsm = signature_matrix(derive_arrs(bg, complete=False), sensor_faults=False)
    for row in fsm.rows:
        assert [int(row in structural[c]) for c in fsm.columns] == list(fsm.row(row).values()), row
    valves = signature_matrix(derive_arrs(bg, complete=False), rows=["az1", "az2", "az3"])
    signatures = {tuple(valves.row(v).values()) for v in valves.rows}
    assert len(signatures) == 3 and all(any(s) for s in signatures)  # detectable, and pairwise distinct
    assert valves.detectable.tolist() == [1, 1, 1] and valves.isolable.tolist() == [1, 1, 1]


def test_isolability_is_a_signature_no_other_detectable_row_shares():
    """Ib by definition (a detectable row whose signature is unique), written out pairwise, against the
    matrix's own grouping on random matrices of every shape, the empty ones too."""
    import numpy as np

    from diagnosis.signatures import SignatureMatrix

    rng = np.random.default_rng(36)
    for rows, columns in [(0, 3), (4, 0), (1, 1), *[(int(r), int(c)) for r, c in rng.integers(1, 12, (40, 2))]]:
        matrix = (rng.random((rows, columns)) < rng.uniform(0.1, 0.6)).astype(int)
        expected = [int(matrix[i].any() and not any(np.array_equal(matrix[i], matrix[j])
                                                       for j in range(rows) if j != i)) for i in range(rows)]
        signatures = SignatureMatrix(tuple(f"f{i}" for i in range(rows)), tuple(f"a{j}" for j in range(columns)),
                                     matrix)
        assert signatures.isolable.tolist() == expected, (rows, columns)
