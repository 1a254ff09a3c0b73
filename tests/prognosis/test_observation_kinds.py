"""Observation models for every kind of parameter: R, C (compliance and stiffness), I, TF and GY moduli, law constants.

Each is checked against the ARR itself: ``h(theta)`` must be what the ARR's own compiled residual gives
when the parameter is moved to ``theta`` (``R(theta) - R(theta_n)`` at the same point values), zero at
nominal, and, for a linear one, its coefficient the slope of that residual.
"""

import dataclasses
import re

import numpy as np
import pytest
import sympy as sp

from bondgraph import BondGraph
from bondgraph.library import dc_motor, friction_drive, three_tank, torsion_bar_monitorable
from diagnosis import derive_arrs
from prognosis import PrognosisError, observation_model
from tests.zoo.models import quarter_car as qc


def loudspeaker() -> BondGraph:
    """A moving-coil driver: coil (R_e, L_e) through the force factor Bl (GY) to a cone on a suspension (m, c, k)."""
    bg = BondGraph(name="loudspeaker")
    bg.add("U", "Se")
    bg.add("1_e", "1")
    bg.add("R_e", "R", value=6.0, uncertainty=(-0.05, 0.05))
    bg.add("L_e", "I", value=4e-4, uncertainty=(-0.05, 0.05))
    bg.add("i", "Df")
    bg.add("Bl", "GY", value=7.5, uncertainty=(-0.03, 0.03))
    bg.add("1_m", "1")
    bg.add("m", "I", value=0.02, uncertainty=(-0.02, 0.02))
    bg.add("c", "R", value=1.5, uncertainty=(-0.1, 0.1))
    bg.add("k", "C", stiffness=2.5e3, uncertainty=(-0.1, 0.1))
    bg.add("v", "Df")
    for tail, head in [("U", "1_e"), ("1_e", "R_e"), ("1_e", "L_e"), ("1_e", "i"), ("1_e", "Bl"), ("Bl", "1_m"),
                       ("1_m", "m"), ("1_m", "c"), ("1_m", "k"), ("1_m", "v")]:
        bg.bond(tail, head)
    return bg


def gear_pair() -> BondGraph:
    """Two inertias through a gear of ratio n (TF), the output braked by a viscous friction."""
    bg = BondGraph(name="gear pair")
    bg.add("T", "Se")
    bg.add("1_a", "1")
    bg.add("J1", "I", value=2e-3, uncertainty=(-0.02, 0.02))
    bg.add("w1", "Df")
    bg.add("n", "TF", value=3.0, uncertainty=(-0.01, 0.01))
    bg.add("1_b", "1")
    bg.add("J2", "I", value=5e-2, uncertainty=(-0.02, 0.02))
    bg.add("b2", "R", value=0.1, uncertainty=(-0.1, 0.1))
    bg.add("w2", "Df")
    for tail, head in [("T", "1_a"), ("1_a", "J1"), ("1_a", "w1"), ("1_a", "n"), ("n", "1_b"), ("1_b", "J2"),
                       ("1_b", "b2"), ("1_b", "w2")]:
        bg.bond(tail, head)
    return bg


def quarter_car_with_a_stiffness() -> BondGraph:
    bg = qc.build()
    bg.graph.remove_node("C_s")
    bg.add("k_s", "C", stiffness=qc.K_S, uncertainty=(-0.05, 0.05))
    bg.bond("1_d", "k_s")
    return bg


MODELS = {"quarter car": qc.build, "quarter car k_s": quarter_car_with_a_stiffness, "loudspeaker": loudspeaker,
          "gear pair": gear_pair, "dc motor": dc_motor, "three tank": three_tank, "friction drive": friction_drive,
          "torsion bar": torsion_bar_monitorable}
_ARRS: dict = {}

# (model, ARR, parameter, kind, linear in it)
CASES = [
    ("quarter car", "ARR_1_s", "c_s", "R", True),
    ("quarter car", "ARR_1_s", "C_s", "C compliance under an integral", False),
    ("quarter car", "ARR_1_u", "C_t", "C compliance under an integral", False),
    ("quarter car", "ARR_1_s", "m_s", "I", True),
    ("quarter car k_s", "ARR_1_s", "k_s", "C stiffness under an integral", True),
    ("quarter car k_s", "ARR_1_u", "k_s", "C stiffness under an integral", True),
    ("loudspeaker", "ARR_1_m", "k", "C stiffness under an integral", True),
    ("loudspeaker", "ARR_1_m", "Bl", "GY modulus", True),
    ("loudspeaker", "ARR_1_e", "Bl", "GY modulus", True),
    ("loudspeaker", "ARR_1_e", "L_e", "I", True),
    ("loudspeaker", "ARR_1_e", "R_e", "R", True),
    ("gear pair", "ARR_1_a", "n", "TF modulus (reflected inertia n**2 J2)", False),
    ("dc motor", "ARR_1_m", "k_m", "GY modulus", True),
    ("friction drive", "ARR_1_1", "r1", "TF modulus (quadratic)", False),
    ("torsion bar", "ARR_1_1", "b_Md", "R behind the TF modulus 1/k_belt", True),
    ("three tank", "ARR_0_2", "S_n", "law constant", True),
    ("three tank", "ARR_0_2", "g", "law constant under a square root", False),
    ("three tank", "ARR_0_2", "az2", "R with a nonlinear law", True),
]


def junction_arr(model: str, name: str):
    if model not in _ARRS:
        _ARRS[model] = {a.name: a for a in derive_arrs(MODELS[model](), complete=False, integrals="keep")}
    return _ARRS[model][name]


def residual(arr, points):
    """The ARR's own compiled r_n at the point values."""
    compiled = arr.compiled
    return np.asarray(compiled.function("nominal", compiled.nominal)(*points), float)


@pytest.mark.parametrize("model, name, candidate, kind, linear", CASES,
                         ids=[f"{c[0]}-{c[2]}-{c[3]}" for c in CASES])
def test_observation_model_is_the_arr_with_the_parameter_moved(model, name, candidate, kind, linear):
    arr = junction_arr(model, name)
    h = observation_model(arr, candidate)
    rng = np.random.default_rng(7)
    points = [rng.uniform(0.5, 2.0, 6) for _ in arr.compiled.points]
    nominal = arr.values[candidate]
    assert h.nominal == nominal
    at = [nominal, 1.25 * nominal, 0.7 * nominal]
    # six assets (one per point sample), one particle each
    values = [np.asarray(h(np.full((6, 1), theta), points))[:, 0] for theta in at]
    assert np.max(np.abs(values[0])) <= 1e-12 * np.max(np.abs(values[1]))   # zero up to rounding of 1/C
    for theta, y in zip(at[1:], values[1:]):
        moved = dataclasses.replace(arr, values={**arr.values, candidate: theta})
        # y = R(theta) - R(theta_n): the ARR's residual written with theta, less the nominal one
        expected = residual(moved, points) - residual(arr, points)
        assert np.allclose(y, expected, rtol=1e-9, atol=1e-12 * np.max(np.abs(expected))), kind
        assert np.max(np.abs(expected)) > 0
    assert (h.coefficient is not None) == linear, kind
    if linear:
        symbols = {p: sp.Symbol(p) for p in arr.values if p != candidate}
        coefficient = h.coefficient.xreplace(arr.compiled.symbols).xreplace(
            {s: arr.values[p] for p, s in symbols.items()})
        slope = sp.lambdify(arr.compiled.points, coefficient, modules="numpy")(*points)
        assert np.allclose(np.broadcast_to(slope, (6,)) * (0.25 * nominal), values[1], rtol=1e-9)


@pytest.mark.parametrize("arr", [
    # (an uncertain parameter is moved out of its integral when the ARR is written: diagnosis.integral_forms)
    # the torsion bar's belt ratio scales the twist rate the shaft's spring integrates
    pytest.param(lambda: junction_arr("torsion bar", "ARR_1_1"), id="torsion-bar-k_belt"),
])
def test_a_parameter_inside_an_integral_is_named(arr):
    """No point value of the ARR carries an integral with the parameter moved: a PrognosisError says so."""
    arr = arr()
    inside = [p for p in sorted(arr.parameters)
              if any(sp.Symbol(p) in i.function.free_symbols for i in arr.nominal.atoms(sp.Integral))]
    assert inside
    with pytest.raises(PrognosisError, match=re.escape(f"{arr.name}: {inside[0]!r} sits inside Integral(")):
        observation_model(arr, inside[0])


def test_the_expression_keeps_the_arrs_integrals_whole():
    """Integral(v_u - v_s)/C_s is not expanded into Integral(v_u) - Integral(v_s), which no point value carries."""
    arr = junction_arr("quarter car", "ARR_1_s")
    h = observation_model(arr, "C_s")
    assert h.expression.atoms(sp.Integral) == arr.nominal.atoms(sp.Integral)
    assert set(h.expression.xreplace(arr.compiled.symbols).free_symbols) <= set(arr.compiled.points) | {h.symbol}
