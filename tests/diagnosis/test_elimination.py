"""diagnosis.elimination: ARRs from minimal overdetermined sets complete what derive_arrs misses."""

import warnings

import numpy as np
import pytest
import sympy as sp

from bondgraph import BondGraph, simulate
from bondgraph import library as lib
from diagnosis import ARRWarning, derive_arrs, signature_matrix
from diagnosis.deltas import delta
from diagnosis.elimination import structural_arrs


def speed_only_motor() -> BondGraph:
    graph = lib.dc_motor().graph.copy()
    graph.remove_node("i")
    return BondGraph(graph)


def quiet_derive(bg):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        return derive_arrs(bg)


def quiet_structural(bg, existing):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        return structural_arrs(bg, existing=existing)


def test_the_speed_only_motor_gets_one_arr_that_sees_every_parameter():
    bg = speed_only_motor()
    assert quiet_derive(bg) == []
    (arr,) = structural_arrs(bg, existing=[])
    assert arr.parameters == {"R_a", "L_a", "k_m", "J", "b"}
    assert arr.signals == ["U", "omega"]
    assert "GY transformer" in arr.origin and "omega sensor" in arr.origin


@pytest.mark.parametrize("bg", [speed_only_motor, pytest.param(lib.torsion_bar, marks=pytest.mark.slow)],
                         ids=["speed-only motor", "torsion bar"])
def test_psi_2_is_exactly_the_change_of_r_n_under_the_multiplicative_uncertainties(bg):
    model = bg()
    for arr in quiet_structural(model, quiet_derive(model)):
        perturbed = arr.nominal.xreplace({sp.Symbol(p): sp.Symbol(p) * (1 + delta(p)) for p in arr.uncertainties})
        assert sp.simplify(perturbed - arr.nominal - arr.uncertain) == 0, arr.name


@pytest.mark.slow
def test_the_full_torsion_bar_detects_all_twelve_parameters_and_isolates_k_belt():
    bg = lib.torsion_bar()
    base = quiet_derive(bg)
    before = signature_matrix(base)
    assert not all(before.detectable)   # the junction ARRs miss most parameters
    after = signature_matrix(base + quiet_structural(bg, base))
    assert len(after.rows) == 12 and all(after.detectable)
    assert after.isolable[after.rows.index("k_belt")]


@pytest.mark.parametrize("bg", [lib.dc_motor, pytest.param(lib.three_tank, marks=pytest.mark.slow),
                                pytest.param(lib.torsion_bar, marks=pytest.mark.slow)],
                         ids=["dc motor", "three-tank", "torsion bar"])
def test_every_added_arr_holds_only_signals_and_parameters(bg):
    model = bg()
    signals = {e.signal for e in model.structure().elements.values() if e.signal is not None}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        added = structural_arrs(model)
    assert added
    for arr in added:
        assert set(arr.signals) <= signals, arr.name
        names = {str(s) for s in arr.nominal.free_symbols} - {"t"}
        assert names <= set(model.parameters), (arr.name, names - set(model.parameters))


def test_the_residual_is_zero_on_the_healthy_motor_and_not_under_a_fault():
    bg = speed_only_motor()
    (arr,) = structural_arrs(bg, existing=[])
    t = np.linspace(0.0, 4.0, 4001)
    drive = {"U": lambda s: 6.0 + 3.0 * np.sin(2.0 * s)}

    def rms(parameters):
        record = simulate(bg, (0.0, 4.0), drive, parameters=parameters, t_eval=t, rtol=1e-10, atol=1e-12).record()
        residual = arr.evaluate(record, window=31).residual[200:-200]
        return float(np.sqrt(np.mean(residual ** 2)))

    healthy, faulty = rms({}), rms({"R_a": 1.23 * 1.5})
    assert faulty > 100 * healthy


@pytest.mark.slow
def test_sets_that_cannot_be_eliminated_are_named_in_one_warning():
    bg = lib.three_tank()
    with pytest.warns(ARRWarning, match=r"overdetermined set\(s\) could not be eliminated .*ARR_MSO_"):
        added = structural_arrs(bg, existing=quiet_derive(bg))
    assert added   # the sets that can be eliminated still are
