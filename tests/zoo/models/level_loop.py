"""A tank level held by a proportional controller driving a pump, the tank draining through an orifice.

Physics: Seborg, Edgar & Mellichamp, *Process Dynamics and Control* (2nd ed., 2004), sec. 2.4 and 11.3
(liquid-level process with a square-root outflow valve; proportional feedback Q_p = K_c (p_ref - p_t));
the pump is a modulated flow source driven by the measured bottom pressure.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

C_T = 0.05 / (1000.0 * 9.81)    # m^3/Pa, 0.05 m^2 tank
A_O = 2.0e-6                    # m^3/(s Pa^0.5)
K_C = 1.0e-7                    # m^3/(s Pa), controller gain (not a model parameter)
# the square-root law is singular at zero flow: the loop starts settled at P_0 with set-point SP_0
P_0 = 1000.0
SP_0 = P_0 + A_O * P_0**0.5 / K_C


def build() -> BondGraph:
    bg = BondGraph(name="level loop")
    bg.add("Q_p", "MSf", unit="m^3/s")                      # pump flow, set by the level controller
    bg.add("0_t", "0")
    bg.add("C_t", "C", value=C_T, uncertainty=(-0.02, 0.02), unit="m^3/Pa")
    bg.add("p_t", "De", unit="Pa")                          # bottom-pressure level transmitter
    bg.add("1_o", "1")
    bg.add("a_o", "R", value=A_O, law="f - a_o*sign(e)*sqrt(Abs(e))", uncertainty=(-0.05, 0.05),
           unit="m^3/(s*Pa^(1/2))")
    bg.add("Q_o", "Df", unit="m^3/s")                       # outflow meter
    for tail, head in [("Q_p", "0_t"), ("0_t", "C_t"), ("0_t", "p_t"), ("0_t", "1_o"), ("1_o", "a_o"),
                       ("1_o", "Q_o")]:
        bg.bond(tail, head)
    return bg


V = sp.Symbol("q_C_t")   # stored volume, named as the library names its state (x0 is shared)
Q_p, C_t, a_o, p_t, t = sp.symbols("Q_p C_t a_o p_t t")
P = V / C_t
Q_out = a_o * P / (P**2) ** sp.Rational(1, 4)   # a sign(p) sqrt|p|, differentiable form
CASE = ZooCase(
    name="level_loop",
    domain="hydraulic",
    source="Seborg et al. (2004), Process Dynamics and Control, sec. 2.4/11.3: P level loop, orifice outflow",
    build=build,
    states=(V,),
    rhs=(Q_p - Q_out,),
    outputs={"p_t": P, "Q_o": Q_out},
    # the loop: the pump's flow is the controller's law in the measured pressure
    smooth_inputs={"Q_p": K_C * (SP_0 + 1500 * (1 - sp.exp(-t / 40)) - p_t)},
    step_inputs={"Q_p": ((0.0, K_C * (SP_0 - p_t)), (20.0, K_C * (SP_0 + 1500 - p_t)),
                         (250.0, K_C * (SP_0 + 500 - p_t)))},
    t_end=500.0,
    dt=0.2,
    noise={"p_t": 10.0, "Q_o": 5e-7},
    x0={V: C_T * P_0},
    faults=("C_t", "a_o"),
)
