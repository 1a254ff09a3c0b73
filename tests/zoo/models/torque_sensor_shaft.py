"""Two inertias on an elastic shaft with an in-line torque transducer, a dynamometer test bench.

Physics: Den Hartog, *Mechanical Vibrations* (1956), sec. 5.2 (two-disc torsional system); the
transducer reads the shaft torque k_s * twist (e.g. HBM T40B datasheet, 1 kN m class scaled down);
the load motor applies a braking torque T_L.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

J_DRIVE, J_LOAD, B_DRIVE, B_LOAD, K_S = 0.02, 0.05, 2e-3, 1e-2, 400.0


def build() -> BondGraph:
    bg = BondGraph(name="two-inertia shaft with torque transducer")
    bg.add("T_d", "MSe", unit="N*m")                       # drive motor torque
    bg.add("T_L", "MSe", unit="N*m")                       # load (brake) torque, against the motion
    bg.add("1_1", "1")
    bg.add("J_1", "I", value=J_DRIVE, uncertainty=(-0.02, 0.02), unit="kg*m^2")
    bg.add("b_1", "R", value=B_DRIVE, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    bg.add("0_s", "0")
    bg.add("k_s", "C", value=K_S, law="e - k_s*q", uncertainty=(-0.05, 0.05), unit="N*m/rad")  # shaft stiffness
    bg.add("T_s", "De", unit="N*m")
    bg.add("1_2", "1")
    bg.add("J_2", "I", value=J_LOAD, uncertainty=(-0.02, 0.02), unit="kg*m^2")
    bg.add("b_2", "R", value=B_LOAD, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    bg.add("omega_2", "Df", unit="rad/s")
    # the brake's bond points into the load shaft: its torque T_L drives it, so a brake is T_L < 0
    for tail, head in [("T_d", "1_1"), ("1_1", "J_1"), ("1_1", "b_1"), ("1_1", "0_s"), ("0_s", "k_s"),
                       ("0_s", "T_s"), ("0_s", "1_2"), ("1_2", "J_2"), ("1_2", "b_2"), ("1_2", "omega_2"),
                       ("T_L", "1_2")]:
        bg.bond(tail, head)
    return bg


th, p1, p2 = sp.symbols("th p1 p2")
T_d, T_L, J_1, J_2, b_1, b_2, k_s, t = sp.symbols("T_d T_L J_1 J_2 b_1 b_2 k_s t")
w1, w2 = p1 / J_1, p2 / J_2
CASE = ZooCase(
    name="torque_sensor_shaft",
    domain="rotational",
    source="Den Hartog (1956), Mechanical Vibrations, sec. 5.2: two-disc torsional system, torque transducer",
    build=build,
    states=(th, p1, p2),
    rhs=(w1 - w2, T_d - b_1 * w1 - k_s * th, k_s * th - b_2 * w2 + T_L),
    outputs={"T_s": k_s * th, "omega_2": w2},
    smooth_inputs={"T_d": 2 * (1 - sp.exp(-t / 0.1)) + 0.5 * sp.sin(2 * sp.pi * 8 * t) * (1 - sp.exp(-t / 0.1)),
                   "T_L": -1.0 * (1 - sp.exp(-t / 0.2))},
    step_inputs={"T_d": ((0.0, 0.0), (0.1, 2.0), (0.5, 1.0)), "T_L": ((0.0, 0.0), (0.3, -0.8))},
    t_end=0.8,
    dt=2e-4,
    noise={"T_s": 0.01, "omega_2": 0.02},
    faults=("k_s", "J_2", "b_2"),
)
