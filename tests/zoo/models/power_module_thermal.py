"""Thermal network of a power semiconductor on a heatsink (Cauer ladder: chip, baseplate/case, heatsink
to ambient), heated by the modulated loss power; case and heatsink temperatures measured (NTCs).
Pseudo bond graph: temperature rises above ambient, heat flows.

Physics: Infineon AN2008-03 "Thermal equivalent circuit models" (Cauer network from the datasheet's
Z_th); values of a 50 A IGBT module (R_jc 0.3 K/W, R_ch 0.1 K/W with grease) on a 0.5 K/W heatsink.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="power module on heatsink")
    bg.add("P", "MSf", unit="W")                             # loss power injected at the junction
    bg.add("0_j", "0")
    bg.add("C_j", "C", value=5.0, uncertainty=(-0.1, 0.1), unit="J/K")
    bg.add("1_jc", "1")
    bg.add("R_jc", "R", value=0.3, uncertainty=(-0.05, 0.05), unit="K/W")
    bg.add("0_c", "0")
    bg.add("C_c", "C", value=50.0, uncertainty=(-0.1, 0.1), unit="J/K")
    bg.add("T_c", "De", unit="K")
    bg.add("1_ch", "1")
    bg.add("R_ch", "R", value=0.1, uncertainty=(0.0, 0.2), unit="K/W")  # grease dries out: only up
    bg.add("0_h", "0")
    bg.add("C_h", "C", value=500.0, uncertainty=(-0.05, 0.05), unit="J/K")
    bg.add("R_ha", "R", value=0.5, uncertainty=(-0.05, 0.1), unit="K/W")
    bg.add("T_h", "De", unit="K")
    for tail, head in [("P", "0_j"), ("0_j", "C_j"), ("0_j", "1_jc"), ("1_jc", "R_jc"), ("1_jc", "0_c"),
                       ("0_c", "C_c"), ("0_c", "T_c"), ("0_c", "1_ch"), ("1_ch", "R_ch"), ("1_ch", "0_h"),
                       ("0_h", "C_h"), ("0_h", "R_ha"), ("0_h", "T_h")]:
        bg.bond(tail, head)
    return bg


Q_j, Q_c, Q_h = sp.symbols("Q_j Q_c Q_h")
P, C_j, R_jc, C_c, R_ch, C_h, R_ha, t = sp.symbols("P C_j R_jc C_c R_ch C_h R_ha t")
Tj, Tc, Th = Q_j / C_j, Q_c / C_c, Q_h / C_h
jc, ch = (Tj - Tc) / R_jc, (Tc - Th) / R_ch
CASE = ZooCase(
    name="power_module_thermal",
    domain="thermal",
    source="Infineon AN2008-03, thermal equivalent circuits: Cauer ladder chip-case-heatsink-ambient",
    build=build,
    states=(Q_j, Q_c, Q_h),
    rhs=(P - jc, jc - ch, ch - Th / R_ha),
    outputs={"T_c": Tc, "T_h": Th},
    smooth_inputs={"P": (100 + 30 * sp.sin(2 * sp.pi * t / 20)) * (1 - sp.exp(-t / 5))},
    step_inputs={"P": ((0.0, 0.0), (5.0, 100.0), (100.0, 40.0))},
    t_end=200.0,
    dt=0.05,
    noise={"T_c": 0.05, "T_h": 0.05},
    faults=("R_ch", "R_ha", "C_h"),
)
