"""RLC ladders: the structural completion stays within its work budget, keeps the junction ARRs, and its
warning names only faults that no returned ARR sees."""

import re
import warnings

import pytest

import diagnosis.elimination as elimination
from diagnosis import ARRWarning, derive_arrs
from diagnosis.elimination import faults_of_arr
from diagnosis.structural import structural_model
from tests.diagnosis.ladders import rlc_ladder

ADJACENT = ("v_1", "i_2", "v_2")   # the second section's loop is measured on all sides: a junction ARR


def derive(bg, **options):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        arrs = derive_arrs(bg, **options)
    return arrs, [str(w.message) for w in caught if issubclass(w.category, ARRWarning)]


def named_missing(messages) -> set:
    """The faults a warning says no ARR detects."""
    found = set()
    for message in messages:
        match = re.search(r"have no closed-form ARR: (.*?)(;|$)", message)
        if match:
            found |= {name.strip() for name in match.group(1).split(",")}
    return found


@pytest.mark.slow
@pytest.mark.parametrize("sections, sensors", [(4, ("i_1", "v_mid", "v_end")), (4, ADJACENT)])
def test_the_warning_names_only_faults_no_returned_arr_sees(sections, sensors):
    bg = rlc_ladder(sections, sensors)
    arrs, messages = derive(bg)
    model = structural_model(bg)
    seen = set().union(*(faults_of_arr(model, arr) for arr in arrs))
    missing = named_missing(messages)
    assert not missing & seen
    # and every detectable fault is either seen or named
    assert model.detectable() <= seen | missing


def test_a_spent_budget_keeps_the_junction_arrs_and_says_why(monkeypatch):
    monkeypatch.setattr(elimination, "MAX_ELIMINATIONS", 0)
    arrs, messages = derive(rlc_ladder(3, ADJACENT))
    assert [arr.name for arr in arrs] == ["ARR_s2"]
    assert any("stopped" in m and "MAX_ELIMINATIONS" in m for m in messages), messages


def test_a_spent_search_budget_stops_without_an_exception(monkeypatch):
    monkeypatch.setattr(elimination, "MAX_SEARCH_EQUATIONS", 10)
    arrs, messages = derive(rlc_ladder(3, ADJACENT))
    assert "ARR_s2" in [arr.name for arr in arrs]
    assert any("MAX_SEARCH_EQUATIONS" in m for m in messages), messages


@pytest.mark.slow
# the longest ladder with the spread sensors; the adjacent sensors at 8 sections only (at 15 they
# cost 35 s of CPU, the most of any test in the suite)
@pytest.mark.parametrize("sections, sensors", [(8, ("i_1", "v_mid", "v_end")), (15, ("i_1", "v_mid", "v_end")),
                                               (8, ADJACENT)])
def test_long_ladders_return_their_junction_arrs_and_a_warning(sections, sensors):
    bg = rlc_ladder(sections, sensors)
    arrs, messages = derive(bg)
    junction = [arr.name for arr in derive_arrs(bg, complete=False)] if sensors == ADJACENT else []
    assert [arr.name for arr in arrs][:len(junction)] == junction
    model = structural_model(bg)
    seen = set().union(set(), *(faults_of_arr(model, arr) for arr in arrs))
    assert not named_missing(messages) & seen
    assert model.detectable() <= seen | named_missing(messages)
