"""Isolation at any size: sets of one shape eliminated once, the work counted, every gap explained."""

from __future__ import annotations

import warnings

import pytest
import sympy as sp

from bondgraph.library import dc_motor, mass_spring_chain
from diagnosis import ARRWarning, derive_arrs
from diagnosis.elimination import structural_arrs, unreached
from diagnosis.report import arr_report
from diagnosis.structural import structural_model
from diagnosis import elimination


def _shared(bg):
    return elimination._Shared(bg, structural_model(bg), True)   # the derivation's own cache, to compare with


def _near_sets(model, n: int) -> list:
    """The minimal sets near each mass of an ``n``-stage chain, in stage order."""
    return [rows for i in range(1, n + 1) for rows in model.msos_through(model.faults[f"m{i}"])]


@pytest.mark.slow   # a second of CPU: the fast tier stays under a minute
def test_a_set_of_the_shape_of_one_eliminated_takes_its_arr_renamed_and_that_is_the_sets_own_arr():
    bg = mass_spring_chain(9)
    shared = _shared(bg)
    renamed = []
    for rows in _near_sets(shared.model, 9):
        arr = shared.cached(rows, set())
        if shared.reused.get(rows) and arr is not None:
            renamed.append((rows, arr))
    assert len(renamed) >= 2
    for rows, arr in renamed[:2]:
        fresh = shared.arr(rows, arr.name)
        assert sp.simplify(arr.nominal - fresh.nominal) == 0
        assert sp.simplify(arr.uncertain - fresh.uncertain) == 0
        assert (arr.junction, arr.parameters, arr.values, arr.uncertainties) == \
            (fresh.junction, fresh.parameters, fresh.values, fresh.uncertainties)


def test_shapes_tell_a_shifted_stage_from_another_set():
    shared = _shared(mass_spring_chain(6))
    model, shapes = shared.model, shared.shapes
    by_key: dict = {}
    for rows in _near_sets(model, 6):
        shape = shapes.shape(rows)
        if shape is not None:
            by_key.setdefault(shape.key, []).append(rows)
    alike = [sets for sets in by_key.values() if len(sets) > 1]
    assert alike and len(by_key) > 1
    for sets in alike:   # the same roles and elements in the same numbers: the same equations, renamed
        kinds = [sorted(f"{m.role}" for m in (model.equations[i] for i in rows)) for rows in sets]
        assert all(k == kinds[0] for k in kinds)


@pytest.mark.slow
def test_every_isolable_pair_of_a_chain_is_reached_within_the_counted_budget():
    bg = mass_spring_chain(12)
    spent: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("error", ARRWarning)   # no budget runs out
        added = structural_arrs(bg, max_order=None, spent=spent)
    model = structural_model(bg)
    pairs = sum(len(v) for v in model.isolability().values())
    assert pairs > 1500
    assert unreached(bg, derive_arrs(bg, complete=False) + added) == {"detect": [], "isolate": []}
    # most sets are another stage's, renamed: the elimination work does not grow with the chain
    assert spent["reused_sets"] > spent["eliminated_sets"]
    assert set(spent) == {"searches", "search_equations", "eliminated_sets", "eliminated_equations", "reused_sets"}


def test_each_gap_left_is_explained_and_the_report_groups_them_by_reason():
    bg = dc_motor()
    left = unreached(bg, derive_arrs(bg), explain=True)
    assert left["isolate"] and set(left["reasons"]) == set(left["isolate"])
    assert all("order 2" in reason for reason in left["reasons"].values())
    text = arr_report(bg, "md")
    assert f"({len(left['isolate'])} ordered pairs; the minimal sets that would tell them apart need derivatives " \
           "of order 2" in text


@pytest.mark.slow
def test_isolation_is_on_at_any_size_and_off_when_asked():
    bg = mass_spring_chain(16)   # 64 fault candidates: isolation used to stop at 60
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        detection_only = structural_arrs(bg, isolation=False)
    assert detection_only == []   # the junction ARRs detect every fault
    spent: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        added = structural_arrs(bg, spent=spent)
    assert added and spent["searches"] > 0
