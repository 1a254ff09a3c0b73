"""Two-node counter/co-flow heat exchanger: lumped hot and cold fluid hold-ups, each fed by a stream
(advection as a thermal resistance 1/(m_dot c_p) from its inlet temperature) and coupled through the
wall conductance UA.  Four sensors: both outlet temperatures, the wall heat flow and the cold stream's
heat pick-up.  Pseudo bond graph (temperature deviations, heat flows).

Physics: Incropera et al. (7th ed.), sec. 11.3 (UA, capacity rates) with the lumped (mixing-cell)
dynamics of Stephanopoulos, *Chemical Process Control* (1984), ch. 4; a small water-water plate
exchanger: 0.1 and 0.15 kg/s, 0.5 kg hold-up per side, UA = 500 W/K.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="two-node heat exchanger")
    bg.add("T_hi", "MSe", unit="K")                           # hot inlet temperature
    bg.add("1_h", "1")
    bg.add("R_h", "R", value=1 / 418.6, uncertainty=(-0.05, 0.05), unit="K/W")  # 1/(m_dot_h c_p)
    bg.add("0_h", "0")
    bg.add("C_h", "C", value=2093.0, uncertainty=(-0.05, 0.05), unit="J/K")
    bg.add("T_h", "De", unit="K")
    bg.add("1_w", "1")
    bg.add("R_w", "R", value=2.0e-3, uncertainty=(0.0, 0.15), unit="K/W")  # fouling only raises it
    bg.add("q_w", "Df", unit="W")
    bg.add("0_c", "0")
    bg.add("C_c", "C", value=2093.0, uncertainty=(-0.05, 0.05), unit="J/K")
    bg.add("T_c", "De", unit="K")
    bg.add("T_ci", "Se", unit="K")                            # cold inlet temperature
    bg.add("1_c", "1")
    bg.add("R_c", "R", value=1 / 627.9, uncertainty=(-0.05, 0.05), unit="K/W")
    bg.add("q_c", "Df", unit="W")
    for tail, head in [("T_hi", "1_h"), ("1_h", "R_h"), ("1_h", "0_h"), ("0_h", "C_h"), ("0_h", "T_h"),
                       ("0_h", "1_w"), ("1_w", "R_w"), ("1_w", "q_w"), ("1_w", "0_c"), ("0_c", "C_c"),
                       ("0_c", "T_c"), ("T_ci", "1_c"), ("1_c", "R_c"), ("1_c", "q_c"), ("1_c", "0_c")]:
        bg.bond(tail, head)
    return bg


Q_h, Q_c = sp.symbols("Q_h Q_c")
T_hi, T_ci, R_h, C_h, R_w, C_c, R_c, t = sp.symbols("T_hi T_ci R_h C_h R_w C_c R_c t")
Th, Tc = Q_h / C_h, Q_c / C_c
wall = (Th - Tc) / R_w
pickup = (T_ci - Tc) / R_c          # heat the cold stream brings into the cold node
CASE = ZooCase(
    name="heat_exchanger",
    domain="thermal",
    source="Incropera et al. (7th ed.) sec. 11.3 and Stephanopoulos (1984) ch. 4: two lumped fluid cells, UA",
    build=build,
    states=(Q_h, Q_c),
    rhs=((T_hi - Th) / R_h - wall, wall + pickup),
    outputs={"T_h": Th, "T_c": Tc, "q_w": wall, "q_c": pickup},
    smooth_inputs={"T_hi": (40 + 3 * sp.sin(2 * sp.pi * t / 30)) * (1 - sp.exp(-t / 10)),
                   "T_ci": 2 * sp.sin(2 * sp.pi * t / 45) * (1 - sp.exp(-t / 10))},
    step_inputs={"T_hi": ((0.0, 0.0), (10.0, 40.0), (90.0, 30.0)), "T_ci": ((0.0, 0.0), (50.0, 5.0))},
    t_end=150.0,
    dt=0.05,
    noise={"T_h": 0.05, "T_c": 0.05, "q_w": 20.0, "q_c": 20.0},
    faults=("R_h", "R_w", "C_h", "R_c"),
)
