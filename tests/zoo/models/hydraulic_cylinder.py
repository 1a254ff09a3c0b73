"""A pump-fed single-acting hydraulic cylinder pushing a spring-loaded mass: piston area as a transformer.

Physics: Merritt (1967), Hydraulic Control Systems, sec. 5.2 (chamber compliance V / beta, leakage,
piston force A p); Esposito, Fluid Power, ch. 6 (a 50 mm bore cylinder).
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

C_H = 0.5e-3 / 1.4e9        # m^3/Pa: 0.5 l of oil, bulk modulus 1.4 GPa
R_L = 1.0e12                # Pa s/m^3, internal leakage
A_P = 1.96e-3               # m^2, 50 mm bore
M_P, B_P, K_L = 50.0, 2000.0, 1.0e5


def build() -> BondGraph:
    bg = BondGraph(name="hydraulic cylinder")
    bg.add("Q_p", "MSf", unit="m^3/s")                     # servo-pump flow command
    bg.add("0_c", "0")
    bg.add("C_h", "C", value=C_H, uncertainty=(-0.1, 0.1), unit="m^3/Pa")
    bg.add("R_l", "R", value=R_L, uncertainty=(-0.2, 0.0), unit="Pa*s/m^3")
    bg.add("p_c", "De", unit="Pa")
    bg.add("piston", "TF", param="A_p", value=A_P, modulus="1/A_p", domain="positive", unit="m^2")  # p = F / A_p
    bg.add("1_p", "1")
    bg.add("m_p", "I", value=M_P, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("b_p", "R", value=B_P, uncertainty=(0.0, 0.2), unit="N*s/m")
    bg.add("k_L", "C", value=K_L, law="e - k_L*q", uncertainty=(-0.05, 0.05), unit="N/m")
    bg.add("v_p", "Df", unit="m/s")
    for tail, head in [("Q_p", "0_c"), ("0_c", "C_h"), ("0_c", "R_l"), ("0_c", "p_c"), ("0_c", "piston"),
                       ("piston", "1_p"), ("1_p", "m_p"), ("1_p", "b_p"), ("1_p", "k_L"), ("1_p", "v_p")]:
        bg.bond(tail, head)
    return bg


V, p, x = sp.symbols("V p x")    # compressed oil volume, piston momentum, spring deflection
Q_p, C_h, R_l, A_p, m_p, b_p, k_L, t = sp.symbols("Q_p C_h R_l A_p m_p b_p k_L t")
P, v = V / C_h, p / m_p
CASE = ZooCase(
    name="hydraulic_cylinder",
    domain="mixed",
    source="Merritt (1967), Hydraulic Control Systems, sec. 5.2: cylinder with compliance and leakage",
    build=build,
    states=(V, p, x),
    rhs=(Q_p - P / R_l - A_p * v, A_p * P - b_p * v - k_L * x, v),
    outputs={"p_c": P, "v_p": v},
    smooth_inputs={"Q_p": 1e-4 * (1 - sp.exp(-t / 0.02)) * (1 + 0.3 * sp.sin(2 * sp.pi * 5 * t))},
    step_inputs={"Q_p": ((0.0, 0.0), (0.05, 1e-4), (0.3, -0.5e-4))},
    t_end=0.5,
    dt=1e-4,
    noise={"p_c": 5e3, "v_p": 2e-4},
    faults=("C_h", "m_p", "b_p", "k_L"),
)
