"""A pump charging a gas-loaded (bladder) accumulator through a restrictor, with a load valve.

Physics: Esposito, *Fluid Power with Applications* (7th ed.), sec. 5.9 (isothermal bladder accumulator,
p V = const): with the gas at its precharge p_0 in V_a at rest, the pressure rise for q m^3 of oil is
p_0 q / (V_a - q); Merritt (1967) sec. 2.3 for the laminar restrictor and valve.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

V_A, P_0 = 1.0e-3, 5.0e6          # m^3 gas volume, Pa precharge
R_A, R_V = 1.0e9, 1.0e11          # Pa s/m^3: accumulator restrictor, load valve


def build() -> BondGraph:
    bg = BondGraph(name="gas accumulator")
    bg.add("Q_p", "MSf", unit="m^3/s")                      # pump flow (displacement x speed command)
    bg.add("0_s", "0")
    bg.add("R_v", "R", value=R_V, uncertainty=(-0.1, 0.1), unit="Pa*s/m^3")
    bg.add("p_s", "De", unit="Pa")                          # supply-line pressure
    bg.add("1_a", "1")
    bg.add("R_a", "R", value=R_A, uncertainty=(-0.1, 0.1), unit="Pa*s/m^3")
    bg.add("Q_a", "Df", unit="m^3/s")                       # flow into the accumulator
    bg.add("V_a", "C", value=V_A, law="e - p_0*q/(V_a - q)", params={"p_0": P_0},
           uncertainties={"p_0": (-0.05, 0.05)}, domains={"p_0": "positive"}, uncertainty=(-0.05, 0.05),
           unit="m^3", units={"p_0": "Pa"})
    for tail, head in [("Q_p", "0_s"), ("0_s", "R_v"), ("0_s", "p_s"), ("0_s", "1_a"), ("1_a", "R_a"),
                       ("1_a", "Q_a"), ("1_a", "V_a")]:
        bg.bond(tail, head)
    return bg


q = sp.Symbol("q")            # oil volume in the accumulator
Q_p, R_v, R_a, V_a, p_0, t = sp.symbols("Q_p R_v R_a V_a p_0 t")
p_acc = p_0 * q / (V_a - q)
# the supply node: Q_p = p_s / R_v + (p_s - p_acc) / R_a
p_s = (Q_p + p_acc / R_a) / (1 / R_v + 1 / R_a)
Q_a = (p_s - p_acc) / R_a
CASE = ZooCase(
    name="gas_accumulator",
    domain="hydraulic",
    source="Esposito, Fluid Power, sec. 5.9: isothermal bladder accumulator; Merritt (1967) sec. 2.3",
    build=build,
    states=(q,),
    rhs=(Q_a,),
    outputs={"p_s": p_s, "Q_a": Q_a},
    smooth_inputs={"Q_p": 1e-4 * (1 - sp.exp(-t / 2)) * (1 + 0.3 * sp.sin(2 * sp.pi * t / 10))},
    step_inputs={"Q_p": ((0.0, 0.0), (2.0, 1e-4), (30.0, 4e-5))},
    t_end=60.0,
    dt=0.02,
    noise={"p_s": 2e4, "Q_a": 2e-7},
    faults=("R_a", "V_a", "p_0", "R_v"),
)
