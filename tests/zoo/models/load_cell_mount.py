"""A mass on a viscoelastic (Maxwell) mount, the mount force read by a load cell.

Physics: Harris & Piersol, *Shock and Vibration Handbook* (5th ed., 2002), ch. 32 (viscoelastic
isolators, the Maxwell element: spring in series with a damper); the load cell measures the spring force.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

M, B_M, K, B_D = 2.0, 5.0, 5.0e3, 200.0   # kg, N s/m, N/m, N s/m


def build() -> BondGraph:
    bg = BondGraph(name="mass on a Maxwell mount")
    bg.add("F", "Se", unit="N")                           # actuator force on the mass
    bg.add("1_m", "1")
    bg.add("m", "I", value=M, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("b_m", "R", value=B_M, uncertainty=(0.0, 0.3), unit="N*s/m")  # guide friction
    bg.add("0_k", "0")
    bg.add("C_k", "C", value=1 / K, uncertainty=(-0.05, 0.05), unit="m/N")
    bg.add("F_k", "De", unit="N")                         # load cell: the spring force
    bg.add("1_d", "1")
    bg.add("b_d", "R", value=B_D, uncertainty=(-0.1, 0.1), unit="N*s/m")
    for tail, head in [("F", "1_m"), ("1_m", "m"), ("1_m", "b_m"), ("1_m", "0_k"), ("0_k", "C_k"),
                       ("0_k", "F_k"), ("0_k", "1_d"), ("1_d", "b_d")]:
        bg.bond(tail, head)
    return bg


# states: mass momentum p, spring deflection x
p, x = sp.symbols("p x")
F, m, b_m, C_k, b_d, t = sp.symbols("F m b_m C_k b_d t")
v = p / m
F_spring = x / C_k
CASE = ZooCase(
    name="load_cell_mount",
    domain="translational",
    source="Harris & Piersol (2002), Shock and Vibration Handbook, ch. 32: Maxwell isolator",
    build=build,
    states=(p, x),
    # the damper carries the spring force, so the spring stretches at v - F_spring / b_d
    rhs=(F - b_m * v - F_spring, v - F_spring / b_d),
    outputs={"F_k": F_spring},
    smooth_inputs={"F": 100 * sp.sin(2 * sp.pi * 3 * t) * (1 - sp.exp(-t / 0.2))},
    step_inputs={"F": ((0.0, 0.0), (0.3, 80.0), (1.2, 0.0))},
    t_end=2.0,
    dt=5e-4,
    noise={"F_k": 0.3},
    faults=("m", "C_k", "b_d"),
)
