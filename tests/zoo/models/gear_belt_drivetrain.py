"""A servo drivetrain: motor shaft, spur-gear reduction, intermediate shaft, elastic belt, load pulley.

Physics: Shigley's *Mechanical Engineering Design* (10th ed., 2015), ch. 13 and 17 (gear and belt
ratios, belt stretch); inertia reflected through a gear (Ogata, *System Dynamics*, 4th ed., sec. 5-5).
The rigid gear makes the intermediate inertia dependent on the motor's: the physics has one speed state
for both, and the belt's twist and the load momentum.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

J_M, B_M, N_G, J_I, B_I, R_B, K_B, J_LOAD, B_LOAD = 2e-4, 1e-4, 5.0, 1e-3, 5e-4, 0.5, 50.0, 0.05, 0.01


def build() -> BondGraph:
    bg = BondGraph(name="gear and belt drivetrain")
    bg.add("T_m", "MSe", unit="N*m")                       # motor torque from the current loop
    bg.add("1_m", "1")
    bg.add("J_m", "I", value=J_M, uncertainty=(-0.02, 0.02), unit="kg*m^2")
    bg.add("b_m", "R", value=B_M, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    bg.add("omega_m", "Df", unit="rad/s")
    bg.add("gear", "TF", param="n_g", value=N_G, modulus="1/n_g", domain="positive",
           unit="1")  # omega_i = omega_m / n_g
    bg.add("1_i", "1")
    bg.add("J_i", "I", value=J_I, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    bg.add("b_i", "R", value=B_I, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    bg.add("belt", "TF", param="r_b", value=R_B, domain="positive", unit="1")  # pulley ratio: omega_p = r_b omega_i
    bg.add("0_b", "0")
    bg.add("c_b", "C", value=1 / K_B, uncertainty=(-0.1, 0.1), unit="rad/(N*m)")  # belt compliance at the load
    bg.add("1_L", "1")
    bg.add("J_L", "I", value=J_LOAD, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    bg.add("b_L", "R", value=B_LOAD, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    bg.add("omega_L", "Df", unit="rad/s")
    for tail, head in [("T_m", "1_m"), ("1_m", "J_m"), ("1_m", "b_m"), ("1_m", "omega_m"), ("1_m", "gear"),
                       ("gear", "1_i"), ("1_i", "J_i"), ("1_i", "b_i"), ("1_i", "belt"), ("belt", "0_b"),
                       ("0_b", "c_b"), ("0_b", "1_L"), ("1_L", "J_L"), ("1_L", "b_L"), ("1_L", "omega_L")]:
        bg.bond(tail, head)
    return bg


# states: motor speed w_m (the intermediate shaft turns at w_m / n_g), belt twist th_b, load momentum p_L
w_m, th_b, p_L = sp.symbols("w_m th_b p_L")
T_m, J_m, b_m, n_g, J_i, b_i, r_b, c_b, J_L, b_L, t = sp.symbols("T_m J_m b_m n_g J_i b_i r_b c_b J_L b_L t")
T_b = th_b / c_b                          # belt torque at the load pulley
w_L = p_L / J_L
# motor shaft with the intermediate inertia reflected through the gear: J_m + J_i / n_g^2
w_m_dot = (T_m - b_m * w_m - (b_i * w_m / n_g + r_b * T_b) / n_g) / (J_m + J_i / n_g**2)
CASE = ZooCase(
    name="gear_belt_drivetrain",
    domain="rotational",
    source="Shigley (2015) ch. 13/17 and Ogata, System Dynamics, sec. 5-5: gear + elastic belt drive",
    build=build,
    states=(w_m, th_b, p_L),
    rhs=(w_m_dot, r_b * w_m / n_g - w_L, T_b - b_L * w_L),
    outputs={"omega_m": w_m, "omega_L": w_L},
    smooth_inputs={"T_m": 0.08 * sp.sin(2 * sp.pi * 2 * t) * (1 - sp.exp(-t / 0.3)) + 0.02 * (1 - sp.exp(-t))},
    step_inputs={"T_m": ((0.0, 0.0), (0.3, 0.1), (1.3, -0.05))},
    t_end=2.0,
    dt=5e-4,
    noise={"omega_m": 0.05, "omega_L": 0.01},
    faults=("J_L", "c_b", "b_L"),
)
