"""Parallel resonant (tank) circuit driven by a modulated current source: capacitor, damping resistor and
an inductor with winding resistance; tank voltage and inductor current measured.

Physics: Hayt, Kemmerly & Durbin, *Engineering Circuit Analysis* (8th ed.), sec. 16.1 (parallel
resonance) with the Norton source of a transconductance amplifier; 10 mH / 1 Ohm coil, 10 uF, 1 kOhm.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="parallel tank circuit")
    bg.add("i_s", "MSf", unit="A")
    bg.add("0_t", "0")
    bg.add("C", "C", value=10e-6, uncertainty=(-0.05, 0.05), unit="F")
    bg.add("R_p", "R", value=1.0e3, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("v", "De", unit="V")
    bg.add("1_L", "1")
    bg.add("L", "I", value=10e-3, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("R_L", "R", value=1.0, uncertainty=(0.0, 0.3), unit="Ohm")
    bg.add("i_L", "Df", unit="A")
    for tail, head in [("i_s", "0_t"), ("0_t", "C"), ("0_t", "R_p"), ("0_t", "v"), ("0_t", "1_L"),
                       ("1_L", "L"), ("1_L", "R_L"), ("1_L", "i_L")]:
        bg.bond(tail, head)
    return bg


q, p = sp.symbols("q p")
i_s, C, R_p, L, R_L, t = sp.symbols("i_s C R_p L R_L t")
vt, iL = q / C, p / L
CASE = ZooCase(
    name="tank_circuit",
    domain="electrical",
    source="Hayt, Kemmerly & Durbin (8th ed.), sec. 16.1: parallel resonance fed by a Norton current source",
    build=build,
    states=(q, p),
    rhs=(i_s - vt / R_p - iL, vt - R_L * iL),
    outputs={"v": vt, "i_L": iL},
    smooth_inputs={"i_s": 0.01 * sp.sin(2 * sp.pi * 400 * t) * (1 - sp.exp(-t / 2e-3))},
    step_inputs={"i_s": ((0.0, 0.0), (5e-3, 0.01), (30e-3, 0.0))},
    t_end=0.05,
    dt=1.25e-5,
    noise={"v": 5e-3, "i_L": 5e-5},
    faults=("C", "L", "R_p"),
)
