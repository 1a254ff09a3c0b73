"""Two-section RC ladder (a second-order low-pass), driven by a voltage source, both node voltages measured.

Physics: Nilsson & Riedel, *Electric Circuits* (10th ed.), ch. 7 and 13 (nodal analysis of cascaded RC
sections); 1 kOhm / 100 uF and 2.2 kOhm / 47 uF standard parts, 5 V logic-level square wave.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

R1, C1, R2, C2 = 1.0e3, 100e-6, 2.2e3, 47e-6


def build() -> BondGraph:
    bg = BondGraph(name="two-section RC ladder")
    bg.add("V_s", "Se", unit="V")
    bg.add("1_1", "1")
    bg.add("R_1", "R", value=R1, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("0_1", "0")
    bg.add("C_1", "C", value=C1, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("v_1", "De", unit="V")
    bg.add("1_2", "1")
    bg.add("R_2", "R", value=R2, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("0_2", "0")
    bg.add("C_2", "C", value=C2, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("v_2", "De", unit="V")
    for tail, head in [("V_s", "1_1"), ("1_1", "R_1"), ("1_1", "0_1"), ("0_1", "C_1"), ("0_1", "v_1"),
                       ("0_1", "1_2"), ("1_2", "R_2"), ("1_2", "0_2"), ("0_2", "C_2"), ("0_2", "v_2")]:
        bg.bond(tail, head)
    return bg


# states: the two capacitor charges
q_1, q_2 = sp.symbols("q_1 q_2")
V_s, R_1, C_1, R_2, C_2, t = sp.symbols("V_s R_1 C_1 R_2 C_2 t")
i_1 = (V_s - q_1 / C_1) / R_1          # current through R_1 into node 1
i_2 = (q_1 / C_1 - q_2 / C_2) / R_2    # current through R_2 from node 1 to node 2
CASE = ZooCase(
    name="rc_ladder2",
    domain="electrical",
    source="Nilsson & Riedel, Electric Circuits (10th ed.), ch. 7/13: cascaded RC sections, nodal analysis",
    build=build,
    states=(q_1, q_2),
    rhs=(i_1 - i_2, i_2),
    outputs={"v_1": q_1 / C_1, "v_2": q_2 / C_2},
    smooth_inputs={"V_s": 5 * sp.sin(2 * sp.pi * 1.0 * t) * (1 - sp.exp(-t / 0.2))},
    step_inputs={"V_s": ((0.0, 0.0), (0.2, 5.0), (1.0, 0.0), (1.6, 5.0))},
    t_end=2.0,
    dt=1e-3,
    noise={"v_1": 0.01, "v_2": 0.01},
    faults=("R_1", "C_1", "R_2", "C_2"),
)
