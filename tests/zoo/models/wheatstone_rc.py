"""An RC bridge (Wheatstone topology, two arms with capacitors to ground, a bridge resistor between the
mid-points): both mid-point voltages and the bridge current measured.

Physics: Nilsson & Riedel, *Electric Circuits* (10th ed.), sec. 3.6 (the Wheatstone bridge) and ch. 4
(node-voltage method); a non-series-parallel network written as one 0-junction per node and one
1-junction per branch.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="RC bridge")
    bg.add("V_s", "Se", unit="V")
    bg.add("0_A", "0")
    bg.add("1_AB", "1")
    bg.add("R_1", "R", value=1.0e3, uncertainty=(-0.02, 0.02), unit="Ohm")
    bg.add("1_AC", "1")
    bg.add("R_2", "R", value=2.2e3, uncertainty=(-0.02, 0.02), unit="Ohm")
    bg.add("0_B", "0")
    bg.add("C_3", "C", value=1e-6, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("0_C", "0")
    bg.add("C_4", "C", value=2.2e-6, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("R_4", "R", value=3.3e3, uncertainty=(-0.02, 0.02), unit="Ohm")
    bg.add("1_BC", "1")
    bg.add("R_5", "R", value=4.7e3, uncertainty=(-0.02, 0.02), unit="Ohm")
    bg.add("v_B", "De", unit="V")
    bg.add("v_C", "De", unit="V")
    bg.add("i_5", "Df", unit="A")
    for tail, head in [("V_s", "0_A"), ("0_A", "1_AB"), ("1_AB", "R_1"), ("1_AB", "0_B"), ("0_A", "1_AC"),
                       ("1_AC", "R_2"), ("1_AC", "0_C"), ("0_B", "C_3"), ("0_C", "C_4"), ("0_C", "R_4"),
                       ("0_B", "1_BC"), ("1_BC", "R_5"), ("1_BC", "0_C"), ("0_B", "v_B"), ("0_C", "v_C"),
                       ("1_BC", "i_5")]:
        bg.bond(tail, head)
    return bg


q_3, q_4 = sp.symbols("q_3 q_4")
V_s, R_1, R_2, C_3, C_4, R_4, R_5, t = sp.symbols("V_s R_1 R_2 C_3 C_4 R_4 R_5 t")
v_b, v_c = q_3 / C_3, q_4 / C_4
i_bc = (v_b - v_c) / R_5
CASE = ZooCase(
    name="wheatstone_rc",
    domain="electrical",
    source="Nilsson & Riedel, Electric Circuits (10th ed.), sec. 3.6 and ch. 4: bridge by node voltages",
    build=build,
    states=(q_3, q_4),
    rhs=((V_s - v_b) / R_1 - i_bc, (V_s - v_c) / R_2 + i_bc - v_c / R_4),
    outputs={"v_B": v_b, "v_C": v_c, "i_5": i_bc},
    smooth_inputs={"V_s": 10 * sp.sin(2 * sp.pi * 50 * t) * (1 - sp.exp(-t / 5e-3))},
    step_inputs={"V_s": ((0.0, 0.0), (5e-3, 10.0), (25e-3, 0.0), (40e-3, 5.0))},
    t_end=0.05,
    dt=2e-5,
    noise={"v_B": 0.01, "v_C": 0.01, "i_5": 2e-6},
    faults=("R_1", "C_3", "C_4", "R_4"),
)
