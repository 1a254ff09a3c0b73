"""An air receiver filled from a compressed-air line through an orifice, with a leak to atmosphere.

Physics: Beater, *Pneumatic Drives* (2007), sec. 3.2 (isothermal vessel: dp/dt = R T / V * mass flow,
capacitance V / (R T)) and sec. 4.2 (orifice, subsonic, the square-root law of an incompressible
approximation with the density of the line air, a = C_d A sqrt(2 rho)); a 50 l receiver, 2 mm nozzle.
Efforts are gauge pressures, flows mass flows.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

C_V = 0.05 / (287.0 * 293.0)     # kg/Pa
A_O = 7.0e-6                     # kg/(s Pa^0.5)
R_LK = 2.0e9                     # Pa s/kg, leak


def build() -> BondGraph:
    bg = BondGraph(name="pressure vessel filling")
    bg.add("p_l", "MSe", unit="Pa")                         # line pressure after the regulator
    bg.add("1_o", "1")
    bg.add("a_o", "R", value=A_O, law="f - a_o*sign(e)*sqrt(Abs(e))", uncertainty=(-0.05, 0.05), unit="kg/(s*Pa^(1/2))")
    bg.add("m_dot", "Df", unit="kg/s")                      # thermal mass-flow meter
    bg.add("0_v", "0")
    bg.add("C_v", "C", value=C_V, uncertainty=(-0.02, 0.02), unit="kg/Pa")
    bg.add("R_lk", "R", value=R_LK, uncertainty=(-0.3, 0.0), unit="Pa*s/kg")  # a leak only grows: R only falls
    bg.add("p_v", "De", unit="Pa")
    for tail, head in [("p_l", "1_o"), ("1_o", "a_o"), ("1_o", "m_dot"), ("1_o", "0_v"), ("0_v", "C_v"),
                       ("0_v", "R_lk"), ("0_v", "p_v")]:
        bg.bond(tail, head)
    return bg


m = sp.Symbol("m")    # stored air mass above atmospheric
p_l, a_o, C_v, R_lk, t = sp.symbols("p_l a_o C_v R_lk t")
P = m / C_v
flow = a_o * (p_l - P) / ((p_l - P) ** 2) ** sp.Rational(1, 4)   # a sign(dp) sqrt|dp|, differentiable form
CASE = ZooCase(
    name="pressure_vessel_fill",
    domain="pneumatic",
    source="Beater (2007), Pneumatic Drives, sec. 3.2/4.2: isothermal receiver filled through an orifice",
    build=build,
    states=(m,),
    rhs=(flow - P / R_lk,),
    outputs={"p_v": P, "m_dot": flow},
    # the square-root law is singular at zero flow: the line is already at 3 bar when the valve opens at t = 0,
    # and it only rises, so the air flows into the vessel throughout
    smooth_inputs={"p_l": 3e5 + 2e5 * (1 - sp.exp(-t / 20)) + 2e4 * (t / 50) ** 2 * sp.exp(-t / 50)},
    step_inputs={"p_l": ((0.0, 3e5), (100.0, 5e5))},
    t_end=200.0,
    dt=0.1,
    noise={"p_v": 1e3, "m_dot": 2e-5},
    faults=("a_o", "C_v"),
)
