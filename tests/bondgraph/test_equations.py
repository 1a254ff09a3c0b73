"""Equations: DSL and networkx give the same model; state equations against hand derivations."""

import networkx as nx
import pytest
import sympy as sp

from bondgraph import BondGraph, CausalityError, EquationError
from bondgraph.equations import causal_equations, model_equations
from bondgraph.library import rlc_circuit, three_tank, torsion_bar, torsion_bar_monitorable

t = sp.Symbol("t")


def motor_nodes():
    return [
        ("U", {"kind": "Se"}),
        ("1_e", {"kind": "1"}),
        ("R_a", {"kind": "R", "value": 1.2, "uncertainty": (-0.05, 0.05)}),
        ("L_a", {"kind": "I", "value": 1e-3}),
        ("GY", {"kind": "GY", "param": "k_m", "value": 0.04}),
        ("1_m", {"kind": 1}),  # an integer junction kind is accepted
        ("J", {"kind": "I", "value": 1e-4}),
        ("b", {"kind": "R", "law": "e - b*f - c3*f**3", "value": 1e-4, "params": {"c3": 1e-7}}),
        ("omega", {"kind": "Df"}),
    ]


MOTOR_BONDS = [("U", "1_e"), ("1_e", "R_a"), ("1_e", "L_a"), ("1_e", "GY"), ("GY", "1_m"),
               ("1_m", "J"), ("1_m", "b"), ("1_m", "omega")]


def test_dsl_and_networkx_give_identical_equations():
    graph = nx.DiGraph()
    graph.add_nodes_from(motor_nodes())
    graph.add_edges_from(MOTOR_BONDS)
    from_networkx = BondGraph(graph)

    from_dsl = BondGraph()
    for name, attrs in motor_nodes():
        attrs = dict(attrs)
        from_dsl.add(name, attrs.pop("kind"), **attrs)
    for tail, head in MOTOR_BONDS:
        from_dsl.bond(tail, head)

    assert model_equations(from_dsl) == model_equations(from_networkx)
    a, b = from_dsl.state_equations(), from_networkx.state_equations()
    assert a.states == b.states and a.rhs == b.rhs and a.outputs == b.outputs
    assert nx.utils.graphs_equal(from_dsl.graph, from_networkx.graph)
    # and the nonlinear friction law made it into the equations
    p_J, J, bb, c3 = sp.symbols("p_J J b c3")
    omega = p_J / J
    expected = sp.Symbol("k_m") * sp.Symbol("p_L_a") / sp.Symbol("L_a") - bb * omega - c3 * omega**3
    assert sp.simplify(a.rhs[1] - expected) == 0


def test_rlc_state_equations_by_hand():
    eqs = rlc_circuit().state_equations()
    p, q, R, L, C = sp.symbols("p_L q_C R L C")
    V = sp.Function("V")(t)
    assert eqs.states == [p, q]
    assert sp.simplify(eqs.rhs[0] - (V - R * p / L - q / C)) == 0
    assert sp.simplify(eqs.rhs[1] - p / L) == 0
    assert eqs.outputs == {"i": p / L, "v_C": q / C}


def test_torsion_bar_dependent_inertia_is_reflected_through_the_belt():
    eqs = torsion_bar().state_equations()
    s = {n: sp.Symbol(n) for n in ["p_L_a", "p_J_m", "q_k_s", "p_J_Ld", "J_m", "J_Md", "J_Ld", "k_belt", "k_m",
                                   "L_a", "f_m", "b_Md", "b_s", "k_s", "b_Ld"]}
    omega_m, omega_Ld = s["p_J_m"] / s["J_m"], s["p_J_Ld"] / s["J_Ld"]
    omega_Md = omega_m / s["k_belt"]
    shaft_torque = s["k_s"] * s["q_k_s"] + s["b_s"] * (omega_Md - omega_Ld)
    motor_torque = s["k_m"] * s["p_L_a"] / s["L_a"]
    inertia = s["J_m"] + s["J_Md"] / s["k_belt"] ** 2
    # d(omega_m)/dt * (J_m + J_Md/k^2) = tau - f_m w_m - (b_Md w_Md + shaft torque)/k
    domega = (motor_torque - s["f_m"] * omega_m - (s["b_Md"] * omega_Md + shaft_torque) / s["k_belt"]) / inertia
    index = [str(x) for x in eqs.states].index("p_J_m")
    assert sp.simplify(eqs.rhs[index] - s["J_m"] * domega) == 0
    assert eqs.dependent_storage == ["J_Md"]
    # the effort of the dependent inertia, J_Md d(omega_Md)/dt, is expressed through the state equations
    bond = next(b for b in torsion_bar().bonds if b.key == ("1_Md", "J_Md"))
    assert not eqs.efforts[bond.label].has(sp.Derivative)
    assert sp.simplify(eqs.efforts[bond.label] - s["J_Md"] * domega / s["k_belt"]) == 0


def test_three_tank_state_equations_match_du_et_al():
    eqs = three_tank().state_equations()
    q1, q2, q3, A1, A2, A3, a1, a2, a3, S, g = sp.symbols("q_A_1 q_A_2 q_A_3 A_1 A_2 A_3 az1 az2 az3 S_n g")
    h1, h2, h3 = q1 / A1, q2 / A2, q3 / A3

    def valve(a, dh):
        return a * S * sp.sign(dh) * sp.sqrt(2 * g * sp.Abs(dh))

    Q1, Q2 = sp.Function("Q1")(t), sp.Function("Q2")(t)
    expected = {"q_A_1": Q1 - valve(a1, h1 - h3), "q_A_2": Q2 + valve(a3, h3 - h2) - valve(a2, h2),
                "q_A_3": valve(a1, h1 - h3) - valve(a3, h3 - h2)}
    values = {q1: 0.01, q2: 0.004, q3: 0.006, A1: 0.0154, A2: 0.0154, A3: 0.0154, a1: 0.5, a2: 0.6, a3: 0.5,
              S: 5e-5, g: 9.81, Q1: 1e-5, Q2: 2e-5}
    for x, rhs in zip(eqs.states, eqs.rhs):
        assert float(rhs.xreplace(values)) == pytest.approx(float(expected[str(x)].xreplace(values)), rel=1e-12)


def test_algebraic_loop_solved_symbolically():
    bg = _loop_model()
    eqs = bg.state_equations()
    p, u = sp.Symbol("p_L"), sp.Function("u")(t)
    R1, R2, R3, L = sp.symbols("R1 R2 R3 L")
    expected = R2 * (u - R1 * p / L) / (R1 + R2) - R3 * p / L
    assert sp.simplify(eqs.rhs[0] - expected) == 0
    assert len(eqs.algebraic_loops) == 1


def test_unsolvable_algebraic_loop_names_its_elements():
    bg = _loop_model(law="f - R2*sign(e)*sqrt(Abs(e))")
    with pytest.raises(EquationError, match=r"algebraic loop.*R 'R2'"):
        bg.state_equations()


def test_equations_refuse_a_conflicting_causality():
    bg = BondGraph()
    bg.add("a", "Se"), bg.add("b", "Se"), bg.add("j", "0"), bg.add("C", "C", value=1.0)
    for tail, head in [("a", "j"), ("b", "j"), ("j", "C")]:
        bg.bond(tail, head)
    with pytest.raises(CausalityError, match="Se 'b'"):
        bg.state_equations()


def test_derivative_causality_gives_junction_balances_in_measured_signals():
    bg = torsion_bar_monitorable()
    oriented = causal_equations(bg, bg.assign_causality("derivative"))
    assert set(oriented.balances) == {"1_1", "1_2"}  # junctions carrying the two encoders
    balance = oriented.express(oriented.balances["1_1"])
    omega_m = sp.Function("omega_m")(t)
    assert balance.has(sp.Derivative(omega_m, t))  # J_m in derivative causality
    assert balance.has(sp.Function("tau_m")(t))


def _loop_model(law=None):
    bg = BondGraph()
    bg.add("u", "Se")
    bg.add("1a", "1")
    bg.add("R1", "R", value=1.0)
    bg.add("0b", "0")
    bg.add("R2", "R", value=2.0, **({"law": law} if law else {}))
    bg.add("1c", "1")
    bg.add("R3", "R", value=3.0)
    bg.add("L", "I", value=0.5)
    for tail, head in [("u", "1a"), ("1a", "R1"), ("1a", "0b"), ("0b", "R2"), ("0b", "1c"), ("1c", "R3"), ("1c", "L")]:
        bg.bond(tail, head)
    return bg
