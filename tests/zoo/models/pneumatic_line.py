"""A pneumatic transmission line (10 m, 4 mm tube) to an actuator chamber, in two lumped sections.

Physics: Doebelin, *System Dynamics* (1998), ch. 5, and Andersen, *The Analysis and Design of Pneumatic
Systems* (1967), ch. 6: the line linearised about its mean state, per section a laminar resistance
128 mu l / (pi d^4 rho), an inertance l / A and an isothermal capacitance V / (R T); efforts gauge
pressures, flows mass flows.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

R_SEC = 6.0e6          # Pa s/kg per 5 m section
I_SEC = 3.97e5         # 1/m, l / A
C_SEC1 = 7.5e-10          # kg/Pa, the first section's volume
C_SEC2 = 3.1e-9           # kg/Pa, the second section's and the 0.2 l chamber's


def build() -> BondGraph:
    bg = BondGraph(name="pneumatic line")
    bg.add("p_in", "MSe", unit="Pa")                       # valve-controlled inlet pressure
    bg.add("1_1", "1")
    bg.add("R_1", "R", value=R_SEC, uncertainty=(-0.1, 0.1), unit="Pa*s/kg")
    bg.add("I_1", "I", value=I_SEC, uncertainty=(-0.05, 0.05), unit="1/m")
    bg.add("0_1", "0")
    bg.add("C_1", "C", value=C_SEC1, uncertainty=(-0.05, 0.05), unit="kg/Pa")
    bg.add("p_1", "De", unit="Pa")                         # mid-line pressure tap
    bg.add("1_2", "1")
    bg.add("R_2", "R", value=R_SEC, uncertainty=(-0.1, 0.1), unit="Pa*s/kg")
    bg.add("I_2", "I", value=I_SEC, uncertainty=(-0.05, 0.05), unit="1/m")
    bg.add("0_2", "0")
    bg.add("C_2", "C", value=C_SEC2, uncertainty=(-0.05, 0.05), unit="kg/Pa")
    bg.add("p_2", "De", unit="Pa")                         # chamber pressure
    for tail, head in [("p_in", "1_1"), ("1_1", "R_1"), ("1_1", "I_1"), ("1_1", "0_1"), ("0_1", "C_1"),
                       ("0_1", "p_1"), ("0_1", "1_2"), ("1_2", "R_2"), ("1_2", "I_2"), ("1_2", "0_2"),
                       ("0_2", "C_2"), ("0_2", "p_2")]:
        bg.bond(tail, head)
    return bg


G1, m1, G2, m2 = sp.symbols("G1 m1 G2 m2")   # section momenta, stored masses
p_in, R_1, I_1, C_1, R_2, I_2, C_2, t = sp.symbols("p_in R_1 I_1 C_1 R_2 I_2 C_2 t")
w1, w2, P1, P2 = G1 / I_1, G2 / I_2, m1 / C_1, m2 / C_2
CASE = ZooCase(
    name="pneumatic_line",
    domain="pneumatic",
    source="Doebelin (1998) ch. 5; Andersen (1967) ch. 6: linearised lumped pneumatic line",
    build=build,
    states=(G1, m1, G2, m2),
    rhs=(p_in - R_1 * w1 - P1, w1 - w2, P1 - R_2 * w2 - P2, w2),
    outputs={"p_1": P1, "p_2": P2},
    smooth_inputs={"p_in": 1e5 * (1 - sp.exp(-t / 0.05)) * (1 + 0.2 * sp.sin(2 * sp.pi * 3 * t))},
    step_inputs={"p_in": ((0.0, 0.0), (0.1, 1e5), (1.0, 5e4))},
    t_end=2.0,
    dt=4e-4,
    noise={"p_1": 200.0, "p_2": 200.0},
    faults=("R_2", "C_2", "C_1"),
)
