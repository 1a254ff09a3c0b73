"""DC motor driving a centrifugal pump through a reduction gear: the pump's load torque follows the
affinity law tau = c_p omega |omega|.  Motor current and pump speed measured.

Physics: Krishnan, *Electric Motor Drives* (2001), ch. 3 (DC motor) with the centrifugal-pump load of
Gulich, *Centrifugal Pumps* (3rd ed.), sec. 3.4 (affinity laws: torque ~ speed^2); 24 V motor
(R_a 0.5 Ohm, L_a 2 mH, k_m 0.05 N m/A), gear ratio 0.5, c_p 2.2e-5 N m s^2 (0.5 N m at 150 rad/s).
The pump impeller's inertia is referred to the motor shaft (rigid gear).
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="pump drive")
    bg.add("u", "MSe", unit="V")
    bg.add("1_e", "1")
    bg.add("R_a", "R", value=0.5, uncertainty=(-0.05, 0.1), unit="Ohm")
    bg.add("L_a", "I", value=2e-3, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("i", "Df", unit="A")
    bg.add("K", "GY", param="k_m", value=0.05, uncertainty=(-0.02, 0.02), domain="positive", unit="N*m/A")
    bg.add("1_m", "1")
    bg.add("J", "I", value=2e-4, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    bg.add("b_m", "R", value=1e-4, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    # TF: e1 = r_g e2 (motor torque = r_g pump torque), f2 = r_g f1 (pump speed = r_g motor speed)
    bg.add("gear", "TF", param="r_g", value=0.5, domain="positive", unit="1")
    bg.add("1_p", "1")
    bg.add("c_p", "R", value=2.2e-5, uncertainty=(-0.05, 0.05), law="e - c_p*f*Abs(f)", unit="N*m*s^2/rad^2")
    bg.add("omega_p", "Df", unit="rad/s")
    for tail, head in [("u", "1_e"), ("1_e", "R_a"), ("1_e", "L_a"), ("1_e", "i"), ("1_e", "K"), ("K", "1_m"),
                       ("1_m", "J"), ("1_m", "b_m"), ("1_m", "gear"), ("gear", "1_p"), ("1_p", "c_p"),
                       ("1_p", "omega_p")]:
        bg.bond(tail, head)
    return bg


lam, h = sp.symbols("lambda_a h_J")
u, R_a, L_a, k_m, J, b_m, r_g, c_p, t = sp.symbols("u R_a L_a k_m J b_m r_g c_p t")
current, w = lam / L_a, h / J
w_p = r_g * w
CASE = ZooCase(
    name="pump_drive",
    domain="mixed",
    source="Krishnan, Electric Motor Drives (2001) ch. 3; Gulich, Centrifugal Pumps (3rd ed.) sec. 3.4",
    build=build,
    states=(lam, h),
    # u >= 0 in both input sets, so the pump never turns backwards: omega |omega| = omega^2 here (a smooth
    # form the reference can differentiate three times)
    rhs=(u - R_a * current - k_m * w, k_m * current - b_m * w - r_g * c_p * w_p**2),
    outputs={"i": current, "omega_p": w_p},
    smooth_inputs={"u": (18 + 2 * sp.sin(2 * sp.pi * 3 * t)) * (1 - sp.exp(-t / 0.05))},
    step_inputs={"u": ((0.0, 0.0), (0.05, 18.0), (0.45, 12.0))},
    t_end=0.8,
    dt=2e-4,
    noise={"i": 0.03, "omega_p": 0.3},
    faults=("R_a", "c_p", "J"),
)
