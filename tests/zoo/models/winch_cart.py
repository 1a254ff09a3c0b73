"""A winch drum pulling a cart through an elastic rope: rotation to translation through the drum radius.

Physics: Rubin, *Materials Handling Handbook* / Shigley (2015) sec. 17-7 (wire rope stiffness
k = A E / L); drum inertia and radius of a small electric winch, a 200 kg cart with rolling resistance.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

J_D, B_D, R_D, K_R, M_C, B_C = 0.5, 0.05, 0.1, 2.0e5, 200.0, 50.0


def build() -> BondGraph:
    bg = BondGraph(name="winch and cart")
    bg.add("T_m", "MSe", unit="N*m")
    bg.add("1_d", "1")
    bg.add("J_d", "I", value=J_D, uncertainty=(-0.02, 0.02), unit="kg*m^2")
    bg.add("b_d", "R", value=B_D, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    bg.add("omega_d", "Df", unit="rad/s")
    bg.add("drum", "TF", param="r_d", value=R_D, uncertainty=(-0.01, 0.01), domain="positive",
           unit="m")  # v = r_d omega
    bg.add("0_r", "0")
    bg.add("c_r", "C", value=1 / K_R, uncertainty=(-0.1, 0.1), unit="m/N")  # rope compliance
    bg.add("F_r", "De", unit="N")                                   # rope tension (load pin)
    bg.add("1_c", "1")
    bg.add("m_c", "I", value=M_C, uncertainty=(-0.05, 0.05), unit="kg")
    bg.add("b_c", "R", value=B_C, uncertainty=(0.0, 0.3), unit="N*s/m")
    bg.add("v_c", "Df", unit="m/s")
    for tail, head in [("T_m", "1_d"), ("1_d", "J_d"), ("1_d", "b_d"), ("1_d", "omega_d"), ("1_d", "drum"),
                       ("drum", "0_r"), ("0_r", "c_r"), ("0_r", "F_r"), ("0_r", "1_c"), ("1_c", "m_c"),
                       ("1_c", "b_c"), ("1_c", "v_c")]:
        bg.bond(tail, head)
    return bg


p_d, x_r, p_c = sp.symbols("p_d x_r p_c")
T_m, J_d, b_d, r_d, c_r, m_c, b_c, t = sp.symbols("T_m J_d b_d r_d c_r m_c b_c t")
w_d, v_c, F = p_d / J_d, p_c / m_c, x_r / c_r
CASE = ZooCase(
    name="winch_cart",
    domain="mixed",
    source="Shigley (2015) sec. 17-7 (wire-rope stiffness AE/L): winch drum pulling a cart",
    build=build,
    states=(p_d, x_r, p_c),
    rhs=(T_m - b_d * w_d - r_d * F, r_d * w_d - v_c, F - b_c * v_c),
    outputs={"omega_d": w_d, "F_r": F, "v_c": v_c},
    smooth_inputs={"T_m": 20 * (1 - sp.exp(-t / 0.5)) + 5 * sp.sin(2 * sp.pi * 4 * t) * (1 - sp.exp(-t / 0.5))},
    step_inputs={"T_m": ((0.0, 0.0), (0.2, 20.0), (2.5, 10.0))},
    t_end=4.0,
    dt=1e-3,
    noise={"omega_d": 0.2, "F_r": 1.0, "v_c": 0.005},
    faults=("m_c", "b_c", "c_r"),
)
