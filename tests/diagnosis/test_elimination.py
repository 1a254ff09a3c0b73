"""diagnosis.elimination: ARRs from minimal overdetermined sets complete what the junction ARRs miss."""

import warnings

import numpy as np
import pytest
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph import BondGraph, simulate
from bondgraph import library as lib
from diagnosis import ARRWarning, derive_arrs, signature_matrix
from diagnosis.deltas import delta
from diagnosis.elimination import structural_arrs, unreached
from diagnosis.junctions import junction_arrs


def speed_only_motor() -> BondGraph:
    graph = lib.dc_motor().graph.copy()
    graph.remove_node("i")
    return BondGraph(graph)


def quiet(function, *args, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        return function(*args, **options)


def test_the_speed_only_motor_gets_one_arr_that_sees_every_parameter():
    bg = speed_only_motor()
    assert quiet(junction_arrs, bg) == []
    (arr,) = derive_arrs(bg)
    assert arr.parameters == {"R_a", "L_a", "k_m", "J", "b"}
    assert arr.signals == ["U", "omega"] and arr.derivatives == {"U": 0, "omega": 2} and arr.integrals == []
    assert "GY transformer" in arr.origin and "omega sensor" in arr.origin and arr.form == "elimination"


@pytest.mark.slow
def test_the_full_torsion_bar_detects_all_twelve_parameters_and_isolates_k_belt():
    bg = lib.torsion_bar()
    before = signature_matrix(quiet(junction_arrs, bg))
    assert not all(before.detectable)   # the junction ARRs miss most parameters
    after = signature_matrix(derive_arrs(bg))
    parameters = [r for r in after.rows if not r.startswith("sensor ")]
    assert len(parameters) == 12 and all(after.detectable)
    # k_belt, with healthy sensors, through a set that avoids the shaft: a third derivative, or an integral
    for options in ({"max_order": None}, {"integrals": "keep"}):
        arrs = derive_arrs(bg, sensor_faults=False, **options)
        isolated = signature_matrix(arrs, sensor_faults=False)
        assert isolated.isolable[isolated.rows.index("k_belt")], options
    assert ("k_belt", "J_Ld") in unreached(bg, derive_arrs(bg, sensor_faults=False), sensor_faults=False)["isolate"]


def _numeric_identity_error(arr, rng) -> float:
    """|r_n(theta (1 + delta)) - r_n(theta) - Psi_2| at random signal values and deltas in the box, relative."""
    atoms = sorted(arr.nominal.atoms(sp.Derivative, sp.Integral) | arr.uncertain.atoms(sp.Derivative, sp.Integral),
                   key=sp.default_sort_key, reverse=True)
    points = {a: sp.Float(rng.uniform(0.5, 2.0)) for a in atoms}
    functions = arr.nominal.atoms(AppliedUndef) | arr.uncertain.atoms(AppliedUndef)
    signals = {f: sp.Float(rng.uniform(0.5, 2.0)) for f in functions}
    deltas = {delta(p): sp.Float(rng.uniform(*box)) for p, box in arr.uncertainties.items()}
    values = {sp.Symbol(p): v for p, v in arr.values.items()}
    perturbed = arr.nominal.xreplace({sp.Symbol(p): sp.Symbol(p) * (1 + delta(p)) for p in arr.uncertainties})

    def at(expression):
        return complex(expression.xreplace(points).xreplace(signals).xreplace(deltas).xreplace(values).evalf())

    nominal, difference = at(arr.nominal), at(perturbed) - at(arr.nominal) - at(arr.uncertain)
    return abs(difference) / max(1.0, abs(nominal), abs(at(perturbed)))


@pytest.mark.parametrize("bg", [speed_only_motor, lib.dc_motor, pytest.param(lib.three_tank, marks=pytest.mark.slow),
                                pytest.param(lib.torsion_bar_monitorable, marks=pytest.mark.slow),
                                pytest.param(lib.torsion_bar, marks=pytest.mark.slow)],
                         ids=["speed-only motor", "dc motor", "three-tank", "torsion bar, monitorable", "torsion bar"])
def test_psi_2_is_exactly_the_change_of_r_n_under_the_multiplicative_uncertainties(bg):
    """r_n + Psi_2 = 0 for the true system: Psi_2 is r_n at theta (1 + delta) minus r_n, for every ARR."""
    rng = np.random.default_rng(7)
    arrs = quiet(derive_arrs, bg(), max_order=None)
    assert any(arr.form != "balance" for arr in arrs)
    for arr in arrs:
        assert max(_numeric_identity_error(arr, rng) for _ in range(3)) < 1e-9, arr.name


@pytest.mark.parametrize("bg", [lib.dc_motor, pytest.param(lib.three_tank, marks=pytest.mark.slow),
                                pytest.param(lib.torsion_bar, marks=pytest.mark.slow)],
                         ids=["dc motor", "three-tank", "torsion bar"])
def test_every_added_arr_holds_only_signals_and_parameters(bg):
    model = bg()
    signals = {e.signal for e in model.structure().elements.values() if e.signal is not None}
    added = quiet(structural_arrs, model, max_order=2)
    assert added
    for arr in added:
        assert set(arr.signals) <= signals, arr.name
        names = {str(s) for s in arr.nominal.free_symbols} - {"t"}
        assert names <= set(model.parameters), (arr.name, names - set(model.parameters))
        assert arr.order <= 2 and arr.origin and arr.form in ("elimination", "differentiated elimination")


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
def test_isolation_asks_no_higher_derivative_than_detection_unless_told():
    motor = lib.dc_motor()
    default = derive_arrs(motor)
    assert [a.name for a in default] == ["ARR_1_e", "ARR_1_m"]   # first order: k_m shares its signature
    left = unreached(motor, default)
    assert left["detect"] == [] and ("k_m", "sensor i") in left["isolate"]
    second = derive_arrs(motor, max_order=2)
    assert unreached(motor, second) == {"detect": [], "isolate": []}
    assert all(a.order == 2 for a in second[2:]) and signature_matrix(second).isolable[2] == 1   # k_m
    assert unreached(motor, default, sensor_faults=False) == {"detect": [], "isolate": []}


def test_healthy_sensors_switch_removes_the_sensor_rows_and_the_arrs_only_they_need():
    motor = lib.dc_motor()
    assert [a.name for a in derive_arrs(motor, sensor_faults=False, max_order=2)] == ["ARR_1_e", "ARR_1_m"]
    rows = signature_matrix(derive_arrs(motor), sensor_faults=False).rows
    assert rows == ("R_a", "L_a", "k_m", "J", "b")
    assert signature_matrix(derive_arrs(motor)).rows[-2:] == ("sensor i", "sensor omega")


def test_integrals_of_measured_signals_are_differentiated_away_unless_kept():
    bg = lib.torsion_bar_monitorable()
    kept = junction_arrs(bg, integrals="keep")
    assert all(a.form == "balance with integral" and a.integrals for a in kept)
    avoided = junction_arrs(bg)
    assert all(a.form == "differentiated balance" and not a.integrals for a in avoided)
    for before, after in zip(kept, avoided):   # the same relation, one derivative higher
        assert sp.simplify(sp.diff(before.nominal, sp.Symbol("t")) - after.nominal) == 0
        assert after.order == before.order + 1


@pytest.mark.parametrize("option, value, match", [("integrals", "drop", "option integrals: 'drop'"),
                                                   ("max_order", -1, "option max_order: -1")])
def test_bad_options_are_named(option, value, match):
    with pytest.raises(ValueError, match=match):
        derive_arrs(lib.dc_motor(), **{option: value})


@pytest.mark.slow  # isolation search on the three-tank with sensor faults: about 3 s
def test_with_sensor_faults_the_three_tank_still_isolates_az1_and_az3():
    signatures = signature_matrix(quiet(derive_arrs, lib.three_tank()))
    assert {"sensor h1", "sensor h2", "sensor h3"} <= set(signatures.rows)
    junction_only = signature_matrix(junction_arrs(lib.three_tank()))
    for valve in ("az1", "az3"):
        assert not junction_only.isolable[junction_only.rows.index(valve)]   # a sensor fault shares its signature
        assert signatures.isolable[signatures.rows.index(valve)]
