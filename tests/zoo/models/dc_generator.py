"""Separately excited DC generator (constant field) driven by a prime-mover torque, feeding a resistive
load: shaft speed (tachometer) and load voltage measured.

Physics: Chapman, *Electric Machinery Fundamentals* (5th ed.), ch. 9 (DC generators: E_A = K phi omega,
torque K phi I_A) and Fitzgerald & Kingsley (6th ed.), sec. 7.7 (armature dynamics); a 2 kW machine:
K phi 1 V s/rad, R_a 1 Ohm, L_a 50 mH, J 0.01 kg m^2, 20 Ohm load.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="DC generator with resistive load")
    bg.add("tau_d", "MSe", unit="N*m")                           # prime-mover torque
    bg.add("1_m", "1")
    bg.add("J", "I", value=0.01, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    bg.add("b", "R", value=5e-3, uncertainty=(0.0, 0.3), unit="N*m*s/rad")  # bearing friction wears up
    bg.add("omega", "Df", unit="rad/s")
    bg.add("G", "GY", param="K_e", value=1.0, uncertainty=(-0.02, 0.02), domain="positive", unit="V*s/rad")
    bg.add("1_a", "1")
    bg.add("R_a", "R", value=1.0, uncertainty=(-0.05, 0.1), unit="Ohm")
    bg.add("L_a", "I", value=50e-3, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("0_L", "0")
    bg.add("R_Ld", "R", value=20.0, uncertainty=(-0.02, 0.02), unit="Ohm")
    bg.add("v_L", "De", unit="V")
    for tail, head in [("tau_d", "1_m"), ("1_m", "J"), ("1_m", "b"), ("1_m", "omega"), ("1_m", "G"), ("G", "1_a"),
                       ("1_a", "R_a"), ("1_a", "L_a"), ("1_a", "0_L"), ("0_L", "R_Ld"), ("0_L", "v_L")]:
        bg.bond(tail, head)
    return bg


h, lam = sp.symbols("h_J lambda_a")      # shaft angular momentum, armature flux linkage
tau_d, J, b, K_e, R_a, L_a, R_Ld, t = sp.symbols("tau_d J b K_e R_a L_a R_Ld t")
w, i_a = h / J, lam / L_a
CASE = ZooCase(
    name="dc_generator",
    domain="mixed",
    source="Chapman, Electric Machinery Fundamentals (5th ed.), ch. 9: separately excited DC generator",
    build=build,
    states=(h, lam),
    rhs=(tau_d - b * w - K_e * i_a, K_e * w - (R_a + R_Ld) * i_a),
    outputs={"omega": w, "v_L": R_Ld * i_a},
    smooth_inputs={"tau_d": (5 + sp.sin(2 * sp.pi * 2 * t)) * (1 - sp.exp(-t / 0.05))},
    step_inputs={"tau_d": ((0.0, 0.0), (0.02, 5.0), (0.3, 3.0))},
    t_end=0.5,
    dt=1e-4,
    noise={"omega": 0.2, "v_L": 0.2},
    faults=("J", "R_Ld", "K_e"),
)
