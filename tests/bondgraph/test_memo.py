"""Derivations remembered by content (bondgraph.memo): never a stale answer, never a shared mutable one."""

import numpy as np
import pytest

from bondgraph import simulate, state_equations
from bondgraph.library import dc_motor, rlc_circuit, torsion_bar
from bondgraph.memo import ContentCache, content_key
from diagnosis import ARRWarning, derive_arrs


def test_a_model_edited_after_a_derivation_gets_its_own_arrs():
    bg = rlc_circuit()
    before = derive_arrs(bg)
    bg.graph.nodes["R"]["value"] = 20.0   # edited through networkx, after the first derivation
    after = derive_arrs(bg)
    assert before[0].values["R"] == 10.0 and after[0].values["R"] == 20.0
    assert derive_arrs(rlc_circuit(R=20.0))[0].values["R"] == 20.0


@pytest.mark.slow
def test_options_and_budgets_are_part_of_the_key(monkeypatch):
    from diagnosis import elimination
    assert len(derive_arrs(dc_motor())) == 2 and len(derive_arrs(dc_motor(), max_order=2)) == 4
    monkeypatch.setattr(elimination, "MAX_ELIMINATIONS", 0)
    with pytest.warns(ARRWarning, match="MAX_ELIMINATIONS"):
        derive_arrs(rlc_circuit(L=0.2), max_order=None, isolation=True)


def test_a_remembered_derivation_warns_again_and_hands_out_copies():
    for _ in range(2):
        with pytest.warns(ARRWarning, match=r"ARR_1_1.*R 'R_a'"):
            arrs = derive_arrs(torsion_bar(), complete=False, integrals="keep")
        arrs[0].values.clear()
        arrs[0].name = "changed by the caller"
    with pytest.warns(ARRWarning):
        again = derive_arrs(torsion_bar(), complete=False, integrals="keep")
    assert again[0].values and again[0].name == "ARR_1_2"


def test_state_equations_follow_an_edit_and_a_copy_can_be_changed():
    bg = rlc_circuit()
    first = state_equations(bg)
    first.rhs[0] = 0
    assert state_equations(bg).rhs[0] != 0
    bg.graph.nodes["C"]["value"] = 2e-3
    assert state_equations(bg).parameters["C"] == 2e-3


def test_simulate_compiles_equations_edited_in_place_afresh():
    equations = rlc_circuit().state_equations()
    t = np.linspace(0.0, 0.05, 11)
    moving = simulate(equations, (0.0, 0.05), {"V": 1.0}, t_eval=t)
    equations.rhs = [0 * x for x in equations.rhs]   # nothing moves any more
    frozen = simulate(equations, (0.0, 0.05), {"V": 1.0}, t_eval=t)
    assert np.ptp(moving["i"]) > 0 and np.ptp(frozen["i"]) == 0


def test_the_cache_forgets_the_oldest_and_never_remembers_a_failure():
    cache = ContentCache(2)
    calls = []
    for key in ("a", "b", "a", "c", "b"):
        cache.get(content_key(key), lambda k=key: calls.append(k) or k)
    assert calls == ["a", "b", "c", "b"] and len(cache) == 2

    def failing():
        calls.append("boom")
        raise ValueError("boom")
    for _ in range(2):
        with pytest.raises(ValueError):
            cache.get(content_key("d"), failing)
    assert calls.count("boom") == 2


def test_unhashable_content_is_computed_every_time():
    assert content_key({"x": np.zeros(2)}) is None
    calls = []
    cache = ContentCache(4)
    for _ in range(2):
        cache.get(None, lambda: calls.append(1))
    assert len(calls) == 2
