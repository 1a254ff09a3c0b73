"""Two gravity-drained tanks in cascade, coupled and drained through sharp-edged orifices (Torricelli).

Physics: Åström and Murray, *Feedback Systems* (2008), the coupled-tank example, with the orifice law
``q = a sign(dh) sqrt(|dh|)`` (``a = c_d A_o sqrt(2 g)``); the C elements take the tank areas, so their
effort is the level.  Values of a laboratory rig of 0.05 m² tanks; levels read by two level sensors.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

A_1, A_2, A_12, A_OUT = 0.05, 0.04, 2.0e-3, 1.5e-3
ORIFICE = "f - {a}*sign(e)*sqrt(Abs(e))"


def build() -> BondGraph:
    bg = BondGraph(name="orifice tanks")
    bg.add("q_in", "Sf", unit="m^3/s")                     # pump inflow, m³/s
    bg.add("0_1", "0")
    bg.add("T1", "C", param="A1", value=A_1, uncertainty=(-0.02, 0.02), unit="m^2")  # upper tank area
    bg.add("h1", "De", unit="m")
    bg.add("1_12", "1")
    bg.add("O12", "R", param="a12", value=A_12, uncertainty=(-0.1, 0.1), law=ORIFICE.format(a="a12"),
           unit="m^(5/2)/s")
    bg.add("0_2", "0")
    bg.add("T2", "C", param="A2", value=A_2, uncertainty=(-0.02, 0.02), unit="m^2")  # lower tank area
    bg.add("h2", "De", unit="m")
    bg.add("1_out", "1")
    bg.add("O_out", "R", param="a_out", value=A_OUT, uncertainty=(-0.1, 0.1), law=ORIFICE.format(a="a_out"),
           unit="m^(5/2)/s")
    for tail, head in [("q_in", "0_1"), ("0_1", "T1"), ("0_1", "h1"), ("0_1", "1_12"), ("1_12", "O12"),
                       ("1_12", "0_2"), ("0_2", "T2"), ("0_2", "h2"), ("0_2", "1_out"), ("1_out", "O_out")]:
        bg.bond(tail, head)
    return bg


# states: the volumes of water in the two tanks
V_1, V_2 = sp.symbols("V_1 V_2")
q_in, A1, A2, a12, a_out, t = sp.symbols("q_in A1 A2 a12 a_out t")
h_1, h_2 = V_1 / A1, V_2 / A2
# Torricelli: the records keep h1 > h2 > 0 (a positive inflow from levels set apart), where the orifice
# law is sqrt of the head; written so, the reference's exact derivatives need no sign or Abs
q_12 = a12 * sp.sqrt(h_1 - h_2)
q_out = a_out * sp.sqrt(h_2)
CASE = ZooCase(
    name="orifice_tanks",
    domain="hydraulic",
    source="Åström and Murray (2008), coupled tanks with Torricelli orifices",
    build=build,
    states=(V_1, V_2),
    rhs=(q_in - q_12, q_12 - q_out),
    outputs={"h1": h_1, "h2": h_2},
    # the inflow stays positive, so the levels stay apart and above zero (the orifice law is smooth there)
    smooth_inputs={"q_in": 1.0e-3 * (1 + 0.4 * sp.sin(0.3 * t))},
    step_inputs={"q_in": ((0.0, 1.0e-3), (20.0, 1.4e-3), (50.0, 0.8e-3))},
    t_end=80.0,
    dt=0.02,
    noise={"h1": 1e-3, "h2": 1e-3},
    x0={V_1: A_1 * 0.45, V_2: A_2 * 0.2},
)
