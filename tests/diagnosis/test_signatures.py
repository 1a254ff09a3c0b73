"""Fault signature matrix against the structure of the bond graph: the three tanks of Du et al."""

import networkx as nx
import pytest

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


def _keeps(matrix, chosen) -> bool:
    """Whether the columns ``chosen`` see every detectable row and tell apart every two distinct rows."""
    import numpy as np

    sub = matrix[:, list(chosen)]
    rows = range(matrix.shape[0])
    return (all(sub[i].any() for i in rows if matrix[i].any())
            and all(not np.array_equal(sub[i], sub[k]) for i in rows for k in rows
                    if not np.array_equal(matrix[i], matrix[k])))


def test_the_fewest_tests_are_as_few_as_a_brute_force_search_finds_and_keep_everything():
    """Against every subset of columns, smallest first, on random matrices up to 7 ARRs."""
    from itertools import combinations

    import numpy as np

    from diagnosis.signatures import SignatureMatrix

    rng = np.random.default_rng(6)
    for _ in range(60):
        rows, columns = int(rng.integers(1, 9)), int(rng.integers(1, 8))
        matrix = (rng.random((rows, columns)) < rng.uniform(0.2, 0.7)).astype(int)
        full = SignatureMatrix(tuple(f"f{i}" for i in range(rows)), tuple(f"a{j}" for j in range(columns)), matrix)
        fewest = full.fewest_tests()
        chosen = [full.columns.index(c) for c in fewest.columns]
        assert _keeps(matrix, chosen)
        assert fewest.detectable.tolist() == full.detectable.tolist()
        assert fewest.isolable.tolist() == full.isolable.tolist()
        smallest = next(size for size in range(columns + 1)
                        if any(_keeps(matrix, subset) for subset in combinations(range(columns), size)))
        assert len(chosen) == smallest


@pytest.mark.slow
def test_the_fewest_tests_of_the_three_tanks_complete_arrs_keep_their_isolability():
    full = signature_matrix(derive_arrs(three_tank()))
    fewest = full.fewest_tests()
    assert len(fewest.columns) < len(full.columns)
    assert fewest.isolable.tolist() == full.isolable.tolist() and fewest.detectable.tolist() == full.detectable.tolist()
