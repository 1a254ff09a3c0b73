"""Quarter-car suspension: sprung and unsprung masses, suspension spring and damper, tyre spring.

Physics: Gillespie, *Fundamentals of Vehicle Dynamics* (1992), ch. 5, the two-mass ride model with
a road-velocity input; values of a passenger car corner.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

M_S, M_U, K_S, K_T, C_S = 300.0, 40.0, 2.0e4, 2.0e5, 1500.0


def build() -> BondGraph:
    bg = BondGraph(name="quarter car")
    bg.add("v_r", "Sf", unit="m/s")                       # road vertical velocity
    bg.add("0_t", "0")
    bg.add("C_t", "C", value=1 / K_T, uncertainty=(-0.05, 0.05), unit="m/N")  # tyre compliance
    bg.add("1_u", "1")
    bg.add("m_u", "I", value=M_U, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("v_u", "Df", unit="m/s")
    bg.add("0_s", "0")
    bg.add("1_d", "1")
    bg.add("C_s", "C", value=1 / K_S, uncertainty=(-0.05, 0.05), unit="m/N")  # suspension compliance
    bg.add("c_s", "R", value=C_S, uncertainty=(-0.1, 0.1), unit="N*s/m")
    bg.add("1_s", "1")
    bg.add("m_s", "I", value=M_S, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("v_s", "Df", unit="m/s")
    for tail, head in [("v_r", "0_t"), ("0_t", "C_t"), ("0_t", "1_u"), ("1_u", "m_u"), ("1_u", "v_u"),
                       ("1_u", "0_s"), ("0_s", "1_d"), ("1_d", "C_s"), ("1_d", "c_s"), ("0_s", "1_s"),
                       ("1_s", "m_s"), ("1_s", "v_s")]:
        bg.bond(tail, head)
    return bg


# states: tyre deflection z_t, suspension deflection z_s, unsprung and sprung momenta
z_t, z_s, p_u, p_s = sp.symbols("z_t z_s p_u p_s")
v_r, C_t, C_s, c_s, m_u, m_s, t = sp.symbols("v_r C_t C_s c_s m_u m_s t")
F_t = z_t / C_t                       # tyre force pushing the wheel up
F_s = z_s / C_s + c_s * (p_u / m_u - p_s / m_s)   # suspension force between wheel and body
CASE = ZooCase(
    name="quarter_car",
    domain="translational",
    source="Gillespie (1992), ch. 5: two-mass quarter-car ride model",
    build=build,
    states=(z_t, z_s, p_u, p_s),
    rhs=(v_r - p_u / m_u, p_u / m_u - p_s / m_s, F_t - F_s, F_s),
    outputs={"v_u": p_u / m_u, "v_s": p_s / m_s},
    smooth_inputs={"v_r": 0.05 * sp.sin(2 * sp.pi * 1.5 * t) * (1 - sp.exp(-t))},
    step_inputs={"v_r": ((0.0, 0.0), (1.0, 0.02), (1.2, 0.0), (3.0, -0.02), (3.2, 0.0))},
    t_end=5.0,
    dt=1e-3,
    noise={"v_u": 1e-3, "v_s": 5e-4},
)
