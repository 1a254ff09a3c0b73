"""Single-phase transformer (ideal TF with winding resistances and primary-referred leakage inductance)
feeding a capacitor-smoothed resistive load, driven by a square-wave inverter.

Physics: Hughes, *Electrical and Electronic Technology* (10th ed.), ch. 35 (transformer equivalent circuit
referred to the primary); 10:1 ratio, 2 Ohm / 20 mH primary, 50 mOhm secondary, 1000 uF || 2 Ohm load.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="transformer with load")
    bg.add("V_1", "Se", unit="V")
    bg.add("1_p", "1")
    bg.add("R_1", "R", value=2.0, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("L_1", "I", value=20e-3, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("i_1", "Df", unit="A")
    # TF: e1 = n e2 (primary voltage = n secondary voltage), f2 = n f1 (secondary current = n primary)
    bg.add("T", "TF", param="n", value=10.0, uncertainty=(-0.01, 0.01), domain="positive", unit="1")
    bg.add("1_s", "1")
    bg.add("R_2", "R", value=0.05, uncertainty=(0.0, 0.2), unit="Ohm")
    bg.add("0_o", "0")
    bg.add("C_o", "C", value=1000e-6, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("R_L", "R", value=2.0, uncertainty=(-0.03, 0.03), unit="Ohm")
    bg.add("v_2", "De", unit="V")
    for tail, head in [("V_1", "1_p"), ("1_p", "R_1"), ("1_p", "L_1"), ("1_p", "i_1"), ("1_p", "T"),
                       ("T", "1_s"), ("1_s", "R_2"), ("1_s", "0_o"), ("0_o", "C_o"), ("0_o", "R_L"),
                       ("0_o", "v_2")]:
        bg.bond(tail, head)
    return bg


p_1, q_o = sp.symbols("p_1 q_o")
V_1, R_1, L_1, n, R_2, C_o, R_L, t = sp.symbols("V_1 R_1 L_1 n R_2 C_o R_L t")
i_p = p_1 / L_1          # primary current
i_s = n * i_p            # secondary current
v_o = q_o / C_o          # load voltage
CASE = ZooCase(
    name="transformer_load",
    domain="electrical",
    source="Hughes, Electrical and Electronic Technology (10th ed.), ch. 35: referred equivalent circuit",
    build=build,
    states=(p_1, q_o),
    # primary loop: V_1 = R_1 i_p + L_1 di_p/dt + n (R_2 i_s + v_o)
    rhs=(V_1 - R_1 * i_p - n * (R_2 * i_s + v_o), i_s - v_o / R_L),
    outputs={"i_1": i_p, "v_2": v_o},
    smooth_inputs={"V_1": 120 * sp.sin(2 * sp.pi * 50 * t) * (1 - sp.exp(-t / 0.01))},
    step_inputs={"V_1": ((0.0, 0.0), (0.005, 120.0), (0.015, -120.0), (0.025, 120.0), (0.035, -120.0),
                         (0.045, 120.0), (0.055, -120.0), (0.065, 0.0))},
    t_end=0.08,
    dt=2e-5,
    noise={"i_1": 5e-3, "v_2": 0.03},
    faults=("R_1", "L_1", "C_o", "R_L"),
)
