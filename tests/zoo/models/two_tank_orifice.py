"""Two tanks in cascade, each draining through a sharp-edged orifice, two pressure (level) transmitters.

Physics: Merritt, *Hydraulic Control Systems* (1967), sec. 2.4 (orifice flow Q = C_d A sqrt(2 dp/rho));
tank capacitance A / (rho g) (Esposito, *Fluid Power*, ch. 3).  Efforts are gauge pressures at the tank
bottoms, flows volumetric; the orifice constant a = C_d A_o sqrt(2/rho).
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

RHO_G = 1000.0 * 9.81
C_T1, C_T2 = 0.02 / RHO_G, 0.015 / RHO_G     # m^3/Pa: tanks of 0.02 and 0.015 m^2
A_1, A_2 = 1.34e-6, 1.1e-6                   # m^3/(s Pa^0.5): 8 mm and 7 mm orifices, C_d = 0.6
# the square-root law is singular at zero flow: the records start at the steady state of Q_0, where
# every flow is positive and stays so (Q_in > 0)
Q_0 = 2e-5
P2_0 = (Q_0 / A_2) ** 2
P1_0 = P2_0 + (Q_0 / A_1) ** 2


def build() -> BondGraph:
    bg = BondGraph(name="two-tank cascade")
    bg.add("Q_in", "Sf", unit="m^3/s")                     # pump flow into tank 1
    bg.add("0_1", "0")
    bg.add("C_t1", "C", value=C_T1, uncertainty=(-0.02, 0.02), unit="m^3/Pa")
    bg.add("p_1", "De", unit="Pa")
    bg.add("1_12", "1")
    bg.add("a_1", "R", value=A_1, law="f - a_1*sign(e)*sqrt(Abs(e))", uncertainty=(-0.05, 0.05),
           unit="m^3/(s*Pa^(1/2))")
    bg.add("0_2", "0")
    bg.add("C_t2", "C", value=C_T2, uncertainty=(-0.02, 0.02), unit="m^3/Pa")
    bg.add("p_2", "De", unit="Pa")
    bg.add("a_2", "R", value=A_2, law="f - a_2*sign(e)*sqrt(Abs(e))", uncertainty=(-0.05, 0.05),
           unit="m^3/(s*Pa^(1/2))")
    for tail, head in [("Q_in", "0_1"), ("0_1", "C_t1"), ("0_1", "p_1"), ("0_1", "1_12"), ("1_12", "a_1"),
                       ("1_12", "0_2"), ("0_2", "C_t2"), ("0_2", "p_2"), ("0_2", "a_2")]:
        bg.bond(tail, head)
    return bg


V1, V2 = sp.symbols("q_C_t1 q_C_t2")   # stored volumes, named as the library names its states
Q_in, C_t1, C_t2, a_1, a_2, t = sp.symbols("Q_in C_t1 C_t2 a_1 a_2 t")
P1, P2 = V1 / C_t1, V2 / C_t2


def orifice(a, dp):
    """``a sign(dp) sqrt|dp|``, written as ``a dp / (dp^2)^(1/4)`` to differentiate without sign or DiracDelta."""
    return a * dp / (dp**2) ** sp.Rational(1, 4)


Q12 = orifice(a_1, P1 - P2)
Q2 = orifice(a_2, P2)
CASE = ZooCase(
    name="two_tank_orifice",
    domain="hydraulic",
    source="Merritt (1967), Hydraulic Control Systems, sec. 2.4: orifice flow; tanks A/(rho g)",
    build=build,
    states=(V1, V2),
    rhs=(Q_in - Q12, Q12 - Q2),
    outputs={"p_1": P1, "p_2": P2},
    smooth_inputs={"Q_in": Q_0 + (3e-5 + 1e-5 * sp.sin(2 * sp.pi * t / 100)) * (1 - sp.exp(-t / 30))},
    step_inputs={"Q_in": ((0.0, Q_0), (20.0, 5e-5), (350.0, 3e-5))},
    t_end=600.0,
    dt=0.2,
    noise={"p_1": 10.0, "p_2": 10.0},
    x0={V1: C_T1 * P1_0, V2: C_T2 * P2_0},
    faults=("a_1", "a_2"),
)
