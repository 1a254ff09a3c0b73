"""Electrodynamic loudspeaker (moving-coil woofer) with a progressive (hardening) suspension: voice-coil
current and cone velocity (laser vibrometer) measured, driven by the amplifier voltage.

Physics: Beranek & Mellow, *Acoustics: Sound Fields and Transducers* (2012), ch. 4 (Thiele-Small
lumped model, force factor Bl as a gyrator) with the suspension nonlinearity K(x) = K_ms + k_3 x^2 of
Klippel, "Tutorial: loudspeaker nonlinearities", JAES 54(10), 2006; a 6.5" woofer: R_e 3.3 Ohm,
L_e 0.9 mH, Bl 7 T m, M_ms 15 g, K_ms 1250 N/m, R_ms 1.2 kg/s.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="loudspeaker")
    bg.add("u", "MSe", unit="V")
    bg.add("1_e", "1")
    bg.add("R_e", "R", value=3.3, uncertainty=(-0.05, 0.1), unit="Ohm")  # voice coil heats up: mostly up
    bg.add("L_e", "I", value=0.9e-3, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("i", "Df", unit="A")
    # GY: e1 = Bl f2 (back emf), e2 = Bl f1 (Lorentz force)
    bg.add("M", "GY", param="Bl", value=7.0, uncertainty=(-0.03, 0.03), domain="positive", unit="T*m")
    bg.add("1_m", "1")
    bg.add("M_ms", "I", value=0.015, uncertainty=(-0.03, 0.03), unit="kg")
    bg.add("R_ms", "R", value=1.2, uncertainty=(-0.1, 0.1), unit="N*s/m")
    bg.add("K_ms", "C", value=1250.0, uncertainty=(-0.05, 0.05), law="e - K_ms*q - k_3*q**3",
           params={"k_3": 1.0e7}, uncertainties={"k_3": (-0.1, 0.1)}, domains={"k_3": "positive"},
           unit="N/m", units={"k_3": "N/m^3"})
    bg.add("v_c", "Df", unit="m/s")
    for tail, head in [("u", "1_e"), ("1_e", "R_e"), ("1_e", "L_e"), ("1_e", "i"), ("1_e", "M"), ("M", "1_m"),
                       ("1_m", "M_ms"), ("1_m", "R_ms"), ("1_m", "K_ms"), ("1_m", "v_c")]:
        bg.bond(tail, head)
    return bg


lam, p, x = sp.symbols("lambda_e p_m x")     # coil flux linkage, cone momentum, cone excursion
u, R_e, L_e, Bl, M_ms, R_ms, K_ms, k_3, t = sp.symbols("u R_e L_e Bl M_ms R_ms K_ms k_3 t")
current, velocity = lam / L_e, p / M_ms
CASE = ZooCase(
    name="loudspeaker",
    domain="mixed",
    source="Beranek & Mellow (2012) ch. 4 Thiele-Small model; Klippel, JAES 54(10) 2006: hardening suspension",
    build=build,
    states=(lam, p, x),
    rhs=(u - R_e * current - Bl * velocity,
         Bl * current - R_ms * velocity - (K_ms * x + k_3 * x**3),
         velocity),
    outputs={"i": current, "v_c": velocity},
    smooth_inputs={"u": 4 * sp.sin(2 * sp.pi * 60 * t) * (1 - sp.exp(-t / 0.01))},
    step_inputs={"u": ((0.0, 0.0), (0.005, 4.0), (0.03, -4.0))},
    t_end=0.05,
    dt=1e-5,
    noise={"i": 2e-3, "v_c": 1e-3},
    faults=("R_e", "Bl", "K_ms", "M_ms"),
)
