"""A hardening (cubic) spring oscillator, the Duffing equation.

Physics: Kovacic & Brennan (eds.), *The Duffing Equation* (2011), ch. 1: m x'' + b x' + k x + k_3 x^3 = F;
a leaf-spring rig whose stiffness hardens at a few centimetres.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase

M, B, K, K3 = 1.0, 0.8, 100.0, 1.0e5   # kg, N s/m, N/m, N/m^3


def build() -> BondGraph:
    bg = BondGraph(name="Duffing oscillator")
    bg.add("F", "Se", unit="N")
    bg.add("1_m", "1")
    bg.add("m", "I", value=M, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("b", "R", value=B, uncertainty=(0.0, 0.3), unit="N*s/m")
    bg.add("k", "C", value=K, law="e - k*q - k_3*q**3", params={"k_3": K3},
           uncertainties={"k_3": (-0.1, 0.1)}, domains={"k_3": "positive"}, uncertainty=(-0.05, 0.05),
           unit="N/m", units={"k_3": "N/m^3"})
    bg.add("v", "Df", unit="m/s")
    for tail, head in [("F", "1_m"), ("1_m", "m"), ("1_m", "b"), ("1_m", "k"), ("1_m", "v")]:
        bg.bond(tail, head)
    return bg


x, p = sp.symbols("x p")
F, m, b, k, k_3, t = sp.symbols("F m b k k_3 t")
CASE = ZooCase(
    name="duffing_oscillator",
    domain="translational",
    source="Kovacic & Brennan (2011), The Duffing Equation, ch. 1: hardening cubic spring",
    build=build,
    states=(x, p),
    rhs=(p / m, F - b * p / m - k * x - k_3 * x**3),
    outputs={"v": p / m},
    smooth_inputs={"F": 12 * sp.sin(2 * sp.pi * 1.8 * t) * (1 - sp.exp(-t / 0.5))},
    step_inputs={"F": ((0.0, 0.0), (0.5, 10.0), (3.0, -6.0))},
    t_end=5.0,
    dt=1e-3,
    noise={"v": 3e-3},
    faults=("k", "k_3", "b"),
)
