"""Two carts joined by a spring, the second one held by a spring to the frame (a rectilinear plant).

Physics: ECP *Model 210 Rectilinear Control System* manual (1999), ch. 6, the two-mass configuration;
sensors: cart 1 velocity (encoder) and the coupling spring force (a load cell in series).
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

M1, M2, B1, B2, K_C, K2 = 2.4, 1.8, 3.0, 4.0, 800.0, 450.0


def build() -> BondGraph:
    bg = BondGraph(name="two-mass rectilinear plant")
    bg.add("F", "MSe", unit="N")                           # voice-coil force, from the amplifier command
    bg.add("1_1", "1")
    bg.add("m1", "I", value=M1, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("b1", "R", value=B1, uncertainty=(0.0, 0.3), unit="N*s/m")
    bg.add("v1", "Df", unit="m/s")
    bg.add("0_c", "0")
    bg.add("c_c", "C", value=1 / K_C, uncertainty=(-0.05, 0.05), unit="m/N")
    bg.add("F_c", "De", unit="N")
    bg.add("1_2", "1")
    bg.add("m2", "I", value=M2, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("b2", "R", value=B2, uncertainty=(0.0, 0.3), unit="N*s/m")
    bg.add("k2", "C", value=K2, law="e - k2*q", uncertainty=(-0.05, 0.05), unit="N/m")
    for tail, head in [("F", "1_1"), ("1_1", "m1"), ("1_1", "b1"), ("1_1", "v1"), ("1_1", "0_c"),
                       ("0_c", "c_c"), ("0_c", "F_c"), ("0_c", "1_2"), ("1_2", "m2"), ("1_2", "b2"),
                       ("1_2", "k2")]:
        bg.bond(tail, head)
    return bg


# states: coupling spring deflection x_c, frame spring deflection x2, momenta p1, p2
x_c, x2, p1, p2 = sp.symbols("x_c x2 p1 p2")
F, m1, m2, b1, b2, c_c, k2, t = sp.symbols("F m1 m2 b1 b2 c_c k2 t")
v1, v2 = p1 / m1, p2 / m2
CASE = ZooCase(
    name="two_mass_drive",
    domain="translational",
    source="ECP Model 210 Rectilinear Control System manual (1999), ch. 6: two-mass plant",
    build=build,
    states=(x_c, x2, p1, p2),
    rhs=(v1 - v2, v2, F - b1 * v1 - x_c / c_c, x_c / c_c - b2 * v2 - k2 * x2),
    outputs={"v1": v1, "F_c": x_c / c_c},
    smooth_inputs={"F": 5 * sp.sin(2 * sp.pi * 1.2 * t) * (1 - sp.exp(-t / 0.5))},
    step_inputs={"F": ((0.0, 0.0), (0.5, 4.0), (2.5, -2.0))},
    t_end=4.0,
    dt=1e-3,
    noise={"v1": 1e-3, "F_c": 0.02},
    faults=("m1", "c_c", "k2", "b2"),
)
