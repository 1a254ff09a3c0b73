"""Three-section RLC ladder (a lumped transmission line) into a resistive load: input current and two
node voltages measured.

Physics: Nilsson & Riedel, *Electric Circuits* (10th ed.), ch. 8 (second-order RLC circuits) cascaded as
in Pozar, *Microwave Engineering* (4th ed.), sec. 2.1 (lumped-element line model); 1 mH / 10 uF sections
with 2 Ohm series resistance, 10 Ohm load.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

L_SEC, C_SEC, R_SEC, R_LOAD = 1e-3, 10e-6, 2.0, 10.0


def build() -> BondGraph:
    bg = BondGraph(name="three-section RLC ladder")
    bg.add("V", "Se", unit="V")
    bonds = []
    previous = "V"
    for k in (1, 2, 3):
        bg.add(f"1_{k}", "1")
        bg.add(f"R_{k}", "R", value=R_SEC, uncertainty=(-0.05, 0.05), unit="Ohm")
        bg.add(f"L_{k}", "I", value=L_SEC, uncertainty=(-0.03, 0.03), unit="H")
        bg.add(f"0_{k}", "0")
        bg.add(f"C_{k}", "C", value=C_SEC, uncertainty=(-0.1, 0.1), unit="F")
        bonds += [(previous, f"1_{k}"), (f"1_{k}", f"R_{k}"), (f"1_{k}", f"L_{k}"), (f"1_{k}", f"0_{k}"),
                  (f"0_{k}", f"C_{k}")]
        previous = f"0_{k}"
    bg.add("R_L", "R", value=R_LOAD, uncertainty=(-0.02, 0.02), unit="Ohm")
    bg.add("i_1", "Df", unit="A")
    bg.add("v_2", "De", unit="V")
    bg.add("v_3", "De", unit="V")
    bonds += [("0_3", "R_L"), ("1_1", "i_1"), ("0_2", "v_2"), ("0_3", "v_3")]
    for tail, head in bonds:
        bg.bond(tail, head)
    return bg


# states: inductor fluxes p_k and capacitor charges q_k
p_1, q_1, p_2, q_2, p_3, q_3 = sp.symbols("p_1 q_1 p_2 q_2 p_3 q_3")
V, t = sp.symbols("V t")
R_1, R_2, R_3, L_1, L_2, L_3, C_1, C_2, C_3, R_L = sp.symbols("R_1 R_2 R_3 L_1 L_2 L_3 C_1 C_2 C_3 R_L")
i1, i2, i3 = p_1 / L_1, p_2 / L_2, p_3 / L_3
v1, v2, v3 = q_1 / C_1, q_2 / C_2, q_3 / C_3
CASE = ZooCase(
    name="rlc_ladder3",
    domain="electrical",
    source="Nilsson & Riedel (10th ed.) ch. 8; Pozar (4th ed.) sec. 2.1: lumped RLC line sections, resistive load",
    build=build,
    states=(p_1, q_1, p_2, q_2, p_3, q_3),
    rhs=(V - R_1 * i1 - v1, i1 - i2, v1 - R_2 * i2 - v2, i2 - i3, v2 - R_3 * i3 - v3, i3 - v3 / R_L),
    outputs={"i_1": i1, "v_2": v2, "v_3": v3},
    smooth_inputs={"V": 10 * sp.sin(2 * sp.pi * 300 * t) * (1 - sp.exp(-t / 1e-3))},
    step_inputs={"V": ((0.0, 0.0), (1e-3, 10.0), (5e-3, 0.0))},
    t_end=10e-3,
    dt=2.5e-6,
    noise={"i_1": 5e-3, "v_2": 0.03, "v_3": 0.03},
    faults=("R_1", "L_1", "C_2", "R_L"),
)
