"""Piezoelectric stack actuator driving a payload mass, fed by an amplifier with output resistance: the
stack's electrical capacitance and its electromechanical coupling (force n V, current n x_dot) as a
transformer; stack voltage and payload velocity measured.

Physics: Preumont, *Mechatronics: Dynamics of Electromechanical and Piezoelectric Systems* (2006),
ch. 4 (discrete piezoelectric transducer, eqs. 4.15-4.18) with stack values of a PI P-888.51-like
actuator: C_p 2 uF, stiffness 20 N/um, coupling 2 N/V; 50 g payload, 20 Ohm amplifier output.
"""

import sympy as sp

from bondgraph import BondGraph
from tests.zoo.case import ZooCase


def build() -> BondGraph:
    bg = BondGraph(name="piezo stack actuator")
    bg.add("v_a", "MSe", unit="V")                              # amplifier voltage
    bg.add("1_s", "1")
    bg.add("R_s", "R", value=20.0, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("0_p", "0")
    bg.add("C_p", "C", value=2e-6, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("v_p", "De", unit="V")
    # TF: e1 = e2 / n_p (stack voltage = force / n_p), f2 = f1 / n_p (velocity = coupling current / n_p)
    bg.add("X", "TF", param="n_p", value=2.0, modulus="1/n_p", uncertainty=(-0.05, 0.05), domain="positive", unit="N/V")
    bg.add("1_m", "1")
    bg.add("m", "I", value=0.05, uncertainty=(-0.02, 0.02), unit="kg")
    bg.add("k_p", "C", value=2e7, uncertainty=(-0.05, 0.05), law="e - k_p*q", unit="N/m")  # a stiffness (N/m)
    bg.add("c_p", "R", value=100.0, uncertainty=(-0.2, 0.2), unit="N*s/m")
    bg.add("v_m", "Df", unit="m/s")
    for tail, head in [("v_a", "1_s"), ("1_s", "R_s"), ("1_s", "0_p"), ("0_p", "C_p"), ("0_p", "v_p"), ("0_p", "X"),
                       ("X", "1_m"), ("1_m", "m"), ("1_m", "k_p"), ("1_m", "c_p"), ("1_m", "v_m")]:
        bg.bond(tail, head)
    return bg


q, p, x = sp.symbols("q_p p_m x")          # stack charge, payload momentum, stack extension
v_a, R_s, C_p, n_p, m, k_p, c_p, t = sp.symbols("v_a R_s C_p n_p m k_p c_p t")
voltage, velocity = q / C_p, p / m
CASE = ZooCase(
    name="piezo_stack",
    domain="mixed",
    source="Preumont, Mechatronics (2006), ch. 4: discrete piezoelectric transducer driving a mass",
    build=build,
    states=(q, p, x),
    rhs=((v_a - voltage) / R_s - n_p * velocity, n_p * voltage - k_p * x - c_p * velocity, velocity),
    outputs={"v_p": voltage, "v_m": velocity},
    smooth_inputs={"v_a": 50 * sp.sin(2 * sp.pi * 1000 * t) * (1 - sp.exp(-t / 5e-4))},
    step_inputs={"v_a": ((0.0, 0.0), (5e-4, 100.0), (3e-3, 0.0))},
    t_end=6e-3,
    dt=2e-6,
    noise={"v_p": 0.2, "v_m": 2e-4},
    faults=("C_p", "n_p", "k_p", "m"),
)
