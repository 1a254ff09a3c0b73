"""A long pipe (fluid inertance and friction) feeding a standpipe tank that drains through a valve.

Physics: Doebelin, *System Dynamics* (1998), ch. 5: fluid inertance rho l / A, laminar resistance,
tank capacitance A_t / (rho g); a 10 m, 25 mm pipe from a constant-head supply.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

L_F = 1000.0 * 10.0 / 4.9e-4     # kg/m^4
R_F, R_O = 2.0e7, 4.0e7          # Pa s/m^3
C_T = 0.005 / (1000.0 * 9.81)    # m^3/Pa


def build() -> BondGraph:
    bg = BondGraph(name="pipe feeding a tank")
    bg.add("P_s", "Se", unit="Pa")                          # supply pressure (gauge)
    bg.add("1_p", "1")
    bg.add("L_f", "I", value=L_F, uncertainty=(-0.05, 0.05), unit="kg/m^4")
    bg.add("R_f", "R", value=R_F, uncertainty=(-0.1, 0.1), unit="Pa*s/m^3")
    bg.add("Q", "Df", unit="m^3/s")                         # flow meter in the pipe
    bg.add("0_t", "0")
    bg.add("C_t", "C", value=C_T, uncertainty=(-0.02, 0.02), unit="m^3/Pa")
    bg.add("R_o", "R", value=R_O, uncertainty=(-0.1, 0.1), unit="Pa*s/m^3")
    bg.add("p_t", "De", unit="Pa")
    for tail, head in [("P_s", "1_p"), ("1_p", "L_f"), ("1_p", "R_f"), ("1_p", "Q"), ("1_p", "0_t"),
                       ("0_t", "C_t"), ("0_t", "R_o"), ("0_t", "p_t")]:
        bg.bond(tail, head)
    return bg


G, V = sp.symbols("G V")      # pipe momentum (pressure momentum), tank volume
P_s, L_f, R_f, C_t, R_o, t = sp.symbols("P_s L_f R_f C_t R_o t")
Qp, P = G / L_f, V / C_t
CASE = ZooCase(
    name="pipe_tank",
    domain="hydraulic",
    source="Doebelin (1998), System Dynamics, ch. 5: pipe inertance and resistance feeding a tank",
    build=build,
    states=(G, V),
    rhs=(P_s - R_f * Qp - P, Qp - P / R_o),
    outputs={"Q": Qp, "p_t": P},
    smooth_inputs={"P_s": 2e4 * (1 - sp.exp(-t / 5)) + 4e3 * sp.sin(2 * sp.pi * t / 15) * (1 - sp.exp(-t / 5))},
    step_inputs={"P_s": ((0.0, 0.0), (5.0, 2e4), (60.0, 1e4))},
    t_end=100.0,
    dt=0.05,
    noise={"Q": 1e-6, "p_t": 20.0},
    faults=("L_f", "R_f", "C_t", "R_o"),
)
