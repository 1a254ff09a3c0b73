"""Three masses in a chain, coupled by spring-damper pairs, the last one tied to the frame.

Physics: Inman, *Engineering Vibration* (4th ed., 2014), sec. 4.1 and 4.6: the damped three-degree-
of-freedom chain driven by a force on the first mass; values of a small laboratory rig.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

M1, M2, M3 = 10.0, 8.0, 12.0          # kg
K12, K23, K3 = 4.0e3, 3.0e3, 5.0e3    # N/m
B12, B23, B3 = 20.0, 15.0, 10.0       # N s/m


def build() -> BondGraph:
    bg = BondGraph(name="three-mass chain")
    bg.add("F", "Se", unit="N")                                  # shaker force on mass 1
    for i, m in ((1, M1), (2, M2), (3, M3)):
        bg.add(f"1_{i}", "1")
        bg.add(f"m{i}", "I", value=m, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("v1", "Df", unit="m/s")
    bg.add("v3", "Df", unit="m/s")
    for pair, k, b in (("12", K12, B12), ("23", K23, B23)):
        bg.add(f"0_{pair}", "0")
        bg.add(f"1_{pair}", "1")
        bg.add(f"c{pair}", "C", value=1 / k, uncertainty=(-0.05, 0.05), unit="m/N")  # compliance
        bg.add(f"b{pair}", "R", value=b, uncertainty=(0.0, 0.2), unit="N*s/m")
    bg.add("k3", "C", value=K3, law="e - k3*q", uncertainty=(-0.05, 0.05), unit="N/m")  # frame spring as a stiffness
    bg.add("b3", "R", value=B3, uncertainty=(0.0, 0.2), unit="N*s/m")
    for tail, head in [("F", "1_1"), ("1_1", "m1"), ("1_1", "v1"), ("1_1", "0_12"), ("0_12", "1_12"),
                       ("1_12", "c12"), ("1_12", "b12"), ("0_12", "1_2"), ("1_2", "m2"), ("1_2", "0_23"),
                       ("0_23", "1_23"), ("1_23", "c23"), ("1_23", "b23"), ("0_23", "1_3"), ("1_3", "m3"),
                       ("1_3", "k3"), ("1_3", "b3"), ("1_3", "v3")]:
        bg.bond(tail, head)
    return bg


# states: spring deflections x12, x23, x3 and the three momenta
x12, x23, x3, p1, p2, p3 = sp.symbols("x12 x23 x3 p1 p2 p3")
F, m1, m2, m3, c12, c23, k3, b12, b23, b3, t = sp.symbols("F m1 m2 m3 c12 c23 k3 b12 b23 b3 t")
v1, v2, v3 = p1 / m1, p2 / m2, p3 / m3
F12 = x12 / c12 + b12 * (v1 - v2)     # force of the first coupling, pulling mass 1 back
F23 = x23 / c23 + b23 * (v2 - v3)
F3 = k3 * x3 + b3 * v3
CASE = ZooCase(
    name="three_mass_chain",
    domain="translational",
    source="Inman (2014), Engineering Vibration, sec. 4.1/4.6: damped three-mass chain",
    build=build,
    states=(x12, x23, x3, p1, p2, p3),
    rhs=(v1 - v2, v2 - v3, v3, F - F12, F12 - F23, F23 - F3),
    outputs={"v1": v1, "v3": v3},
    smooth_inputs={"F": 50 * sp.sin(2 * sp.pi * 2 * t) * (1 - sp.exp(-t / 0.3))},
    step_inputs={"F": ((0.0, 0.0), (0.5, 40.0), (2.5, -20.0))},
    t_end=4.0,
    dt=1e-3,
    noise={"v1": 2e-3, "v3": 1e-3},
    faults=("c12", "c23", "k3", "b12"),
)
