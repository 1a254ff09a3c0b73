"""Averaged (state-space averaged, continuous-conduction) buck converter: the switch is a modulated
transformer of ratio d (duty cycle), then an LC output filter into a resistive load.

Physics: Erickson & Maksimovic, *Fundamentals of Power Electronics* (2nd ed.), ch. 2 and 7 (the averaged
switch model: v_L = d V_in - v_o, i_in = d i_L); 24 V input, 100 uH / 50 mOhm, 470 uF, 5 Ohm load.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="averaged buck converter")
    bg.add("V_in", "Se", unit="V")
    # MTF: e1 = (1/d) e2, i.e. the switch-node voltage is d V_in; f2 = f1/d, i.e. i_in = d i_L
    # the modulus is the duty cycle alone, a pure number: S has no parameter, so no `unit`
    bg.add("S", "MTF", signal="d", modulus="1/d", units={"d": "1"})
    bg.add("1_L", "1")
    bg.add("L", "I", value=100e-6, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("R_L", "R", value=0.05, uncertainty=(0.0, 0.2), unit="Ohm")
    bg.add("i_L", "Df", unit="A")
    bg.add("0_o", "0")
    bg.add("C", "C", value=470e-6, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("R_o", "R", value=5.0, uncertainty=(-0.02, 0.02), unit="Ohm")
    bg.add("v_o", "De", unit="V")
    for tail, head in [("V_in", "S"), ("S", "1_L"), ("1_L", "L"), ("1_L", "R_L"), ("1_L", "i_L"), ("1_L", "0_o"),
                       ("0_o", "C"), ("0_o", "R_o"), ("0_o", "v_o")]:
        bg.bond(tail, head)
    return bg


p_L, q_C = sp.symbols("p_L q_C")
V_in, d, L, R_L, C, R_o, t = sp.symbols("V_in d L R_L C R_o t")
i, v = p_L / L, q_C / C
CASE = ZooCase(
    name="buck_averaged",
    domain="electrical",
    source="Erickson & Maksimovic, Fundamentals of Power Electronics (2nd ed.), ch. 2/7: averaged buck",
    build=build,
    states=(p_L, q_C),
    rhs=(d * V_in - R_L * i - v, i - v / R_o),
    outputs={"i_L": i, "v_o": v},
    smooth_inputs={"V_in": 24 * (1 - sp.exp(-t / 2e-3)),
                   "d": 0.5 + 0.1 * sp.sin(2 * sp.pi * 100 * t) * (1 - sp.exp(-t / 5e-3))},
    step_inputs={"V_in": ((0.0, 24.0),), "d": ((0.0, 0.4), (0.015, 0.6), (0.03, 0.5))},
    t_end=0.04,
    dt=1e-5,
    noise={"i_L": 0.01, "v_o": 0.03},
    faults=("L", "C", "R_o"),
)
