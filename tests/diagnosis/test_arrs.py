"""ARR derivation: Jha et al. (2016), eqs. (48)-(49), the tank balances of Du et al., signatures, implicit relations."""

import networkx as nx
import pytest
import sympy as sp

from bondgraph import BondGraph
from bondgraph.library import dc_motor, three_tank, torsion_bar, torsion_bar_monitorable
from diagnosis import ARRWarning, derive_arrs, signature_matrix

t = sp.Symbol("t")
S = sp.Symbol


def fn(name):
    return sp.Function(name)(t)


def test_torsion_bar_arr_at_1_1_is_eq_48_and_49():
    arrs = {arr.junction: arr for arr in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")}
    assert set(arrs) == {"1_1", "1_2"}
    arr = arrs["1_1"]
    w_m, w_L, tau = fn("omega_m"), fn("omega_Ld"), fn("tau_m")
    J_m, f_m, J_Md, b_Md, k_s, b_s, k = (S(n) for n in ["J_m", "f_m", "J_Md", "b_Md", "k_s", "b_s", "k_belt"])
    dw = sp.Derivative(w_m, t)
    twist = sp.Integral(w_m / k - w_L, (t, 0, t))
    eq48 = tau - J_m * dw - f_m * w_m - (J_Md * dw / k + b_Md * w_m / k + k_s * twist + b_s * (w_m / k - w_L)) / k
    assert sp.simplify(arr.nominal - eq48) == 0
    d = {n: S(f"delta_{n}") for n in ["J_m", "f_m", "J_Md", "b_Md", "k_s", "b_s"]}
    # eq. (49) with its sign misprint corrected so that r_n + Psi_2 = 0 (eq. 45):
    eq49 = -(d["J_m"] * J_m * dw + d["f_m"] * f_m * w_m
             + (d["J_Md"] * J_Md * dw / k + d["b_Md"] * b_Md * w_m / k + d["k_s"] * k_s * twist
                + d["b_s"] * b_s * (w_m / k - w_L)) / k)
    assert sp.simplify(arr.uncertain - eq49) == 0
    assert arr.parameters == {"J_m", "f_m", "J_Md", "b_Md", "k_s", "b_s", "k_belt"}
    assert arr.uncertainties["b_Md"] == (0.0, 0.2) and arr.uncertainties["f_m"] == (0.0, 0.3)
    assert set(arr.terms) == set(d)
    assert "\\frac" in arr.latex() and "r_n = " in str(arr)


def test_torsion_bar_arr_at_1_2_is_the_load_disk_balance():
    arr = {a.junction: a for a in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")}["1_2"]
    w_m, w_L = fn("omega_m"), fn("omega_Ld")
    J_Ld, b_Ld, k_s, b_s, k = (S(n) for n in ["J_Ld", "b_Ld", "k_s", "b_s", "k_belt"])
    expected = (k_s * sp.Integral(w_m / k - w_L, (t, 0, t)) + b_s * (w_m / k - w_L)
                - J_Ld * sp.Derivative(w_L, t) - b_Ld * w_L)
    assert sp.simplify(arr.nominal - expected) == 0


def test_three_tank_arrs_are_the_mass_balances_of_du_et_al():
    arrs = {arr.junction: arr for arr in derive_arrs(three_tank(), complete=False, integrals="keep")}
    assert set(arrs) == {"0_1", "0_2", "0_3"}
    h1, h2, h3, Q1, Q2 = (fn(n) for n in ["h1", "h2", "h3", "Q1", "Q2"])
    S_n, g = S("S_n"), S("g")

    def Q(az, dh):
        return S(az) * S_n * sp.sign(dh) * sp.sqrt(2 * g * sp.Abs(dh))

    Q13, Q32, Q20 = Q("az1", h1 - h3), Q("az3", h3 - h2), Q("az2", h2)
    expected = {
        "0_1": Q1 - S("A_1") * sp.Derivative(h1, t) - Q13,
        "0_2": Q2 + Q32 - Q20 - S("A_2") * sp.Derivative(h2, t),
        "0_3": Q13 - Q32 - S("A_3") * sp.Derivative(h3, t),
    }
    for junction, balance in expected.items():
        assert sp.simplify(arrs[junction].nominal - balance) == 0, junction
    # the valve law was given as a string: its uncertain term is -delta * (nominal valve flow)
    assert sp.simplify(arrs["0_1"].terms["az1"] + S("delta_az1") * Q13) == 0


def test_three_tank_signature_matrix_by_hand():
    fsm = signature_matrix(derive_arrs(three_tank(), complete=False, integrals="keep"), sensor_faults=False)
    expected = {"A_1": [1, 0, 0], "A_2": [0, 1, 0], "A_3": [0, 0, 1],
                "az1": [1, 0, 1], "az2": [0, 1, 0], "az3": [0, 1, 1]}
    assert fsm.columns == ("ARR_0_1", "ARR_0_2", "ARR_0_3")
    for row, signature in expected.items():
        assert list(fsm.row(row).values()) == signature
    assert fsm.detectable.tolist() == [1] * 6
    isolable = dict(zip(fsm.rows, fsm.isolable.tolist()))
    assert isolable == {"A_1": 1, "A_2": 0, "A_3": 1, "az1": 1, "az2": 0, "az3": 1}  # A_2 and az2 look alike
    valves = signature_matrix(derive_arrs(three_tank(), complete=False, integrals="keep"), rows=["az1", "az2", "az3"])
    assert valves.isolable.tolist() == [1, 1, 1]  # three level sensors isolate the three valves


def test_torsion_bar_signature_matrix_by_hand():
    fsm = signature_matrix(derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep"),
                           sensor_faults=False)
    both = {"k_belt", "k_s", "b_s"}
    motor_side = {"J_m", "f_m", "J_Md", "b_Md"}
    load_side = {"J_Ld", "b_Ld"}
    assert set(fsm.rows) == both | motor_side | load_side
    for row in fsm.rows:
        expected = [int(row in both | motor_side), int(row in both | load_side)]
        assert list(fsm.row(row).values()) == expected, row
    assert fsm.isolable.sum() == 0  # two ARRs cannot isolate nine parameters
    assert fsm.detectable.sum() == len(fsm.rows)


def test_full_torsion_bar_needs_the_current_for_arr_1_1():
    with pytest.warns(ARRWarning, match=r"ARR_1_1.*R 'R_a'"):
        arrs = derive_arrs(torsion_bar(), complete=False, integrals="keep")
    assert [arr.junction for arr in arrs] == ["1_2"]


def test_arrs_from_a_plain_networkx_graph_with_string_laws():
    G = nx.DiGraph()
    G.add_node("Q", kind="Sf")
    G.add_node("tank", kind=0)
    G.add_node("A", kind="C", value=2.0, uncertainty=(-0.1, 0.1))
    G.add_node("valve", kind="R", value=0.3, uncertainty=(-0.05, 0.05), law="f - valve*sqrt(Abs(e))")
    G.add_node("h", kind="De")
    G.add_edges_from([("Q", "tank"), ("tank", "A"), ("tank", "valve"), ("tank", "h")])
    [arr] = derive_arrs(BondGraph(G), complete=False, integrals="keep")
    h = fn("h")
    assert sp.simplify(arr.nominal - (fn("Q") - S("A") * sp.Derivative(h, t) - S("valve") * sp.sqrt(sp.Abs(h)))) == 0
    assert arr.parameters == {"A", "valve"}


@pytest.mark.slow
def test_non_invertible_law_gives_an_implicit_arr():
    # a flow sensor on a pipe whose valve law cannot be solved for the pressure drop
    bg = BondGraph()
    bg.add("P", "Se")
    bg.add("pipe", "1")
    bg.add("valve", "R", value=0.5, law="f - valve*(e + e**3/3 + exp(e) - 1)")
    bg.add("q", "Df")
    for tail, head in [("P", "pipe"), ("pipe", "valve"), ("pipe", "q")]:
        bg.bond(tail, head)
    [arr] = derive_arrs(bg, complete=False, integrals="keep")
    assert arr.implicit and arr.blocked_by == ("valve",)
    P, q, a = fn("P"), fn("q"), S("valve")
    assert sp.simplify(arr.nominal - (q - a * (P + P**3 / 3 + sp.exp(P) - 1))) == 0


def test_two_sensors_on_one_junction_give_a_measurement_arr():
    bg = dc_motor()
    bg.add("omega2", "Df")
    bg.bond("1_m", "omega2")
    arrs = derive_arrs(bg, complete=False, integrals="keep")
    redundant = [arr for arr in arrs if arr.detector is not None]
    assert [arr.name for arr in redundant] == ["ARR_omega2"]  # the first sensor is dualized, the second measured
    assert sp.simplify(redundant[0].nominal - (fn("omega2") - fn("omega"))) == 0


def test_signature_matrix_lists_parameters_no_arr_can_see():
    """Default rows are every element parameter, so an unmonitorable fault shows as Mb = 0.

    As in Jha et al. (2016), table 2.
    """
    import warnings

    from bondgraph.library import torsion_bar
    from diagnosis import signature_matrix

    bg = torsion_bar()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ARR_1_1 cannot be expressed without the current sensor
        sm = signature_matrix(derive_arrs(bg, complete=False, integrals="keep"))
    assert set(bg.uncertainties) <= set(sm.rows)
    mb = dict(zip(sm.rows, sm.detectable.tolist()))
    assert mb["J_m"] == 0 and mb["f_m"] == 0 and mb["b_Md"] == 0
    assert mb["b_Ld"] == 1 and mb["k_s"] == 1
