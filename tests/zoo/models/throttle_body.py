"""Electronic throttle body: DC motor, two-stage reduction gear, throttle plate with viscous friction and
a return spring; motor current and return-spring torque (the position sensor's reading scaled by the
spring rate) measured.  Motor and plate inertias both kept: through the rigid gear, one of them is
dependent storage.

Physics: Pavkovic, Deur, Jansz & Peric, "Adaptive control of automotive electronic throttle", Control
Engineering Practice 14 (2006), sec. 2 (motor, gear ratio 20, return spring about the limp-home
position); R_a 1.6 Ohm, L_a 2.5 mH, k_m 0.0183 N m/A, J_m 4e-6, J_t 2e-4 kg m^2, k_sp 0.4 N m/rad.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="electronic throttle")
    bg.add("u", "MSe", unit="V")                           # H-bridge voltage (averaged PWM)
    bg.add("1_e", "1")
    bg.add("R_a", "R", value=1.6, uncertainty=(-0.05, 0.1), unit="Ohm")
    bg.add("L_a", "I", value=2.5e-3, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("i", "Df", unit="A")
    bg.add("K", "GY", param="k_m", value=0.0183, uncertainty=(-0.03, 0.03), domain="positive", unit="N*m/A")
    bg.add("1_m", "1")
    bg.add("J_m", "I", value=4e-6, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    # TF: e1 = r_g e2 (motor torque = plate torque / 20), f2 = r_g f1 (plate speed = motor speed / 20)
    bg.add("gear", "TF", param="r_g", value=0.05, domain="positive", unit="1")
    bg.add("1_t", "1")
    bg.add("J_t", "I", value=2e-4, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    bg.add("b_t", "R", value=4e-3, uncertainty=(0.0, 0.3), unit="N*m*s/rad")  # friction grows with deposits
    bg.add("0_sp", "0")
    bg.add("k_sp", "C", value=0.4, uncertainty=(-0.05, 0.05), law="e - k_sp*q", unit="N*m/rad")  # stiffness (N m/rad)
    bg.add("tau_sp", "De", unit="N*m")
    for tail, head in [("u", "1_e"), ("1_e", "R_a"), ("1_e", "L_a"), ("1_e", "i"), ("1_e", "K"), ("K", "1_m"),
                       ("1_m", "J_m"), ("1_m", "gear"), ("gear", "1_t"), ("1_t", "J_t"), ("1_t", "b_t"),
                       ("1_t", "0_sp"), ("0_sp", "k_sp"), ("0_sp", "tau_sp")]:
        bg.bond(tail, head)
    return bg


lam, h, theta = sp.symbols("lambda_a h_t theta")   # coil flux, plate-side angular momentum of both inertias, angle
u, R_a, L_a, k_m, J_m, r_g, J_t, b_t, k_sp, t = sp.symbols("u R_a L_a k_m J_m r_g J_t b_t k_sp t")
J_eq = J_t + J_m / r_g**2                           # both inertias seen at the plate
current, w_t = lam / L_a, h / J_eq
CASE = ZooCase(
    name="throttle_body",
    domain="mixed",
    source="Pavkovic et al., Control Engineering Practice 14 (2006), sec. 2: electronic throttle model",
    build=build,
    states=(lam, h, theta),
    rhs=(u - R_a * current - k_m * w_t / r_g,
         k_m * current / r_g - b_t * w_t - k_sp * theta,
         w_t),
    outputs={"i": current, "tau_sp": k_sp * theta},
    smooth_inputs={"u": (4 + 2 * sp.sin(2 * sp.pi * 5 * t)) * (1 - sp.exp(-t / 0.01))},
    step_inputs={"u": ((0.0, 0.0), (0.02, 5.0), (0.15, 2.0))},
    t_end=0.3,
    dt=7.5e-5,
    noise={"i": 0.01, "tau_sp": 2e-3},
    faults=("R_a", "k_sp", "k_m"),
)
