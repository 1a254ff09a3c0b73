"""Two-layer building wall (brick and insulation with render), 1 m^2, as a pseudo bond graph: efforts are
temperatures (K, deviations from the initial steady state), flows heat flows (W), C heat capacities (J/K),
R thermal resistances (K/W).  A heat-flux plate on the inner surface and a thermocouple in the brick.

Physics: Incropera et al., *Fundamentals of Heat and Mass Transfer* (7th ed.), sec. 3.1 and 5.9 (thermal
circuits, lumped layers); 0.2 m brick (k = 0.7 W/m K, rho c = 1.6 MJ/m^3 K), 0.1 m mineral wool
(k = 0.04), 20 mm render, surface films 0.13 and 0.04 m^2 K/W (ISO 6946).
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="two-layer wall")
    bg.add("T_i", "MSe", unit="K")    # indoor air temperature (heating schedule)
    bg.add("1_i", "1")
    bg.add("R_i", "R", value=0.273, uncertainty=(-0.05, 0.05), unit="K/W")  # inner film + half brick
    bg.add("q_i", "Df", unit="W")
    bg.add("0_b", "0")
    bg.add("C_b", "C", value=3.2e5, uncertainty=(-0.05, 0.05), unit="J/K")  # brick
    bg.add("T_b", "De", unit="K")
    bg.add("1_m", "1")
    bg.add("R_m", "R", value=1.393, uncertainty=(-0.1, 0.1), unit="K/W")  # half brick + half insulation
    bg.add("0_n", "0")
    bg.add("C_n", "C", value=4.0e4, uncertainty=(-0.1, 0.1), unit="J/K")  # insulation + render
    bg.add("1_o", "1")
    bg.add("R_o", "R", value=1.29, uncertainty=(-0.1, 0.1), unit="K/W")  # half insulation + outer film
    bg.add("T_o", "Se", unit="K")                          # outdoor air temperature
    # heat through R_o flows from outside in: its effort is T_o - T_n
    for tail, head in [("T_i", "1_i"), ("1_i", "R_i"), ("1_i", "q_i"), ("1_i", "0_b"), ("0_b", "C_b"),
                       ("0_b", "T_b"), ("0_b", "1_m"), ("1_m", "R_m"), ("1_m", "0_n"), ("0_n", "C_n"),
                       ("T_o", "1_o"), ("1_o", "R_o"), ("1_o", "0_n")]:
        bg.bond(tail, head)
    return bg


Q_b, Q_n = sp.symbols("Q_b Q_n")     # heat stored in the brick and in the insulation node
T_i, T_o, R_i, C_b, R_m, C_n, R_o, t = sp.symbols("T_i T_o R_i C_b R_m C_n R_o t")
T_brick, T_ins = Q_b / C_b, Q_n / C_n
q_in = (T_i - T_brick) / R_i
q_mid = (T_brick - T_ins) / R_m
DAY = 86400.0
CASE = ZooCase(
    name="wall_two_layer",
    domain="thermal",
    source="Incropera et al. (7th ed.), sec. 3.1/5.9: lumped thermal circuit of a brick + insulation wall",
    build=build,
    states=(Q_b, Q_n),
    rhs=(q_in - q_mid, q_mid + (T_o - T_ins) / R_o),
    outputs={"q_i": q_in, "T_b": T_brick},
    smooth_inputs={"T_i": 5 * (1 - sp.exp(-t / 3600)),
                   "T_o": -8 * sp.sin(2 * sp.pi * t / DAY) * (1 - sp.exp(-t / 7200))},
    step_inputs={"T_i": ((0.0, 0.0), (21600.0, 4.0), (151200.0, 0.0)), "T_o": ((0.0, 0.0), (43200.0, -6.0))},
    t_end=3 * DAY,
    dt=120.0,
    noise={"q_i": 0.05, "T_b": 0.01},
    faults=("R_i", "C_b", "R_m"),
)
