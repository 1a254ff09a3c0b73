"""A flywheel with windage (quadratic aerodynamic) drag, spun up by a proportional speed loop.

Physics: Genta, *Kinetic Energy Storage* (1985), ch. 8 (aerodynamic drag torque c_a omega |omega|
and bearing losses); the motor torque command is T_m = k_p (omega_ref - omega), a closed loop.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

J_F, C_A, B_F = 0.5, 2e-5, 1e-3     # kg m^2, N m s^2, N m s
K_P = 0.05                           # N m s, controller gain (not a model parameter)


def build() -> BondGraph:
    bg = BondGraph(name="flywheel speed loop")
    bg.add("T_m", "MSe", unit="N*m")                       # torque command of the speed controller
    bg.add("1_f", "1")
    bg.add("J_f", "I", value=J_F, uncertainty=(-0.02, 0.02), unit="kg*m^2")
    bg.add("c_a", "R", value=C_A, law="e - c_a*f*Abs(f)", uncertainty=(-0.1, 0.1), unit="N*m*s^2/rad^2")  # windage
    bg.add("b_f", "R", value=B_F, uncertainty=(0.0, 0.3), unit="N*m*s/rad")           # bearings
    bg.add("omega", "Df", unit="rad/s")
    for tail, head in [("T_m", "1_f"), ("1_f", "J_f"), ("1_f", "c_a"), ("1_f", "b_f"), ("1_f", "omega")]:
        bg.bond(tail, head)
    return bg


p = sp.Symbol("p")
T_m, J_f, c_a, b_f, omega, t = sp.symbols("T_m J_f c_a b_f omega t")
w = p / J_f
CASE = ZooCase(
    name="flywheel_speed_loop",
    domain="rotational",
    source="Genta (1985), Kinetic Energy Storage, ch. 8: windage c_a w|w| + bearing loss; P speed loop",
    build=build,
    states=(p,),
    rhs=(T_m - c_a * w * sp.sqrt(w**2) - b_f * w,),   # w |w|, written so that it differentiates cleanly
    outputs={"omega": w},
    # the loop: the torque is the controller's law in the measured speed
    smooth_inputs={"T_m": K_P * (300 * (1 - sp.exp(-t / 20)) - omega)},
    step_inputs={"T_m": ((0.0, 0.0), (10.0, K_P * (300 - omega)), (120.0, K_P * (200 - omega)))},
    t_end=200.0,
    dt=0.1,
    noise={"omega": 0.3},
    faults=("J_f", "c_a"),
)
