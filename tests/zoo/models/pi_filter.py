"""C-L-C (pi) low-pass filter between a source with internal resistance and a resistive load; only the
output voltage is measured.

Physics: Horowitz & Hill, *The Art of Electronics* (3rd ed.), sec. 1.7 and 9.5 (LC power-supply filters);
220 uF capacitors, 100 uH choke with 50 mOhm winding resistance, 8 Ohm load.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="pi filter")
    bg.add("V_in", "Se", unit="V")
    bg.add("1_s", "1")
    bg.add("R_s", "R", value=0.5, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("0_1", "0")
    bg.add("C_1", "C", value=220e-6, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("1_L", "1")
    bg.add("L_f", "I", value=100e-6, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("R_w", "R", value=0.05, uncertainty=(0.0, 0.2), unit="Ohm")
    bg.add("0_2", "0")
    bg.add("C_2", "C", value=220e-6, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("R_o", "R", value=8.0, uncertainty=(-0.02, 0.02), unit="Ohm")
    bg.add("v_o", "De", unit="V")
    for tail, head in [("V_in", "1_s"), ("1_s", "R_s"), ("1_s", "0_1"), ("0_1", "C_1"), ("0_1", "1_L"),
                       ("1_L", "L_f"), ("1_L", "R_w"), ("1_L", "0_2"), ("0_2", "C_2"), ("0_2", "R_o"),
                       ("0_2", "v_o")]:
        bg.bond(tail, head)
    return bg


q_1, p_L, q_2 = sp.symbols("q_1 p_L q_2")
V_in, R_s, C_1, L_f, R_w, C_2, R_o, t = sp.symbols("V_in R_s C_1 L_f R_w C_2 R_o t")
v_1, i_L, v_2 = q_1 / C_1, p_L / L_f, q_2 / C_2
CASE = ZooCase(
    name="pi_filter",
    domain="electrical",
    source="Horowitz & Hill, The Art of Electronics (3rd ed.), sec. 1.7/9.5: C-L-C supply filter with load",
    build=build,
    states=(q_1, p_L, q_2),
    rhs=((V_in - v_1) / R_s - i_L, v_1 - R_w * i_L - v_2, i_L - v_2 / R_o),
    outputs={"v_o": v_2},
    smooth_inputs={"V_in": 12 * (1 - sp.exp(-t / 2e-3)) + 1.5 * sp.sin(2 * sp.pi * 600 * t) * (1 - sp.exp(-t / 2e-3))},
    step_inputs={"V_in": ((0.0, 0.0), (1e-3, 12.0), (10e-3, 9.0))},
    t_end=20e-3,
    dt=5e-6,
    noise={"v_o": 0.03},
    faults=("C_2", "R_o", "L_f"),
)
