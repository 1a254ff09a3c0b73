"""Modulated elements (MTF, MGY, MSf) against hand-written ODEs."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from bondgraph import BondGraph, simulate

L, B = 0.5, 2.0


def two_port_model(kind, **attrs):
    bg = BondGraph()
    bg.add("u", "Se")
    bg.add("1_a", "1")
    bg.add("L", "I", value=L)
    bg.add("M", kind, **attrs)
    bg.add("1_b", "1")
    bg.add("b", "R", value=B)
    for tail, head in [("u", "1_a"), ("1_a", "L"), ("1_a", "M"), ("M", "1_b"), ("1_b", "b")]:
        bg.bond(tail, head)
    return bg


def modulation(t):
    return 1.0 + 0.5 * np.sin(3.0 * t)


def compare(bg, inputs, hand_rhs):
    t_eval = np.linspace(0.0, 4.0, 201)
    ours = simulate(bg, (0.0, 4.0), inputs, t_eval=t_eval, rtol=1e-11, atol=1e-13)
    hand = solve_ivp(hand_rhs, (0.0, 4.0), [0.0], t_eval=t_eval, rtol=1e-11, atol=1e-13, method="LSODA")
    p = ours.states["p_L"]
    assert np.max(np.abs(p - hand.y[0])) / np.max(np.abs(hand.y[0])) < 1e-6
    return ours


def test_mtf_modulated_by_an_input_signal():
    bg = two_port_model("MTF", signal="r")
    eqs = bg.state_equations()
    r = sp.Function("r")(sp.Symbol("t"))
    expected = sp.Function("u")(sp.Symbol("t")) - r**2 * sp.Symbol("b") * sp.Symbol("p_L") / sp.Symbol("L")
    assert sp.simplify(eqs.rhs[0] - expected) == 0
    # e1 = r e2, f2 = r f1, e2 = b f2  =>  L dp/dt... dp/dt = u - r^2 b p / L
    result = compare(bg, {"u": 1.0, "r": modulation}, lambda t, x: [1.0 - modulation(t) ** 2 * B * x[0] / L])
    assert np.allclose(result.flows[4], modulation(result.t) * result.flows[3])  # f2 = r f1


def test_mgy_with_a_parameter_and_a_signal_in_its_modulus():
    k = 0.8
    bg = two_port_model("MGY", param="k", value=k, signal="s", modulus="k*s")
    assert bg.inputs == ["u", "s"]
    # e1 = m f2, e2 = m f1 with m = k s; R in conductance: f2 = e2 / b  =>  dp/dt = u - m^2 p / (L b)
    result = compare(bg, {"u": 2.0, "s": modulation}, lambda t, x: [2.0 - (k * modulation(t)) ** 2 * x[0] / (L * B)])
    m = k * modulation(result.t)
    assert np.allclose(result.efforts[3], m * result.flows[4])


def test_modulated_flow_source_with_feedback():
    bg = BondGraph()
    bg.add("q", "MSf")
    bg.add("0", "0")
    bg.add("C", "C", value=2.0)
    bg.add("R", "R", value=5.0)
    bg.add("v", "De")
    for tail, head in [("q", "0"), ("0", "C"), ("0", "R"), ("0", "v")]:
        bg.bond(tail, head)
    # flow source driven by the measured voltage: q = 1 - 0.1 v  =>  C dv/dt = 1 - 0.1 v - v/R
    result = simulate(bg, (0.0, 150.0), {"q": lambda t, y: 1.0 - 0.1 * y["v"]})  # 22 time constants
    assert result["v"][-1] == pytest.approx(1.0 / (0.1 + 1.0 / 5.0), rel=1e-4)
