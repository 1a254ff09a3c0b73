"""Example bond graphs that ship with the toolkit.

========================  =====================================================
:func:`rlc_circuit`       series RLC circuit, current and capacitor-voltage sensors
:func:`dc_motor`          DC motor: Se, R_a, L_a, GY k_m, rotor J, friction b
:func:`torsion_bar`       Jha et al. (2016), Figs. 5-6: the complete torsion-bar system
:func:`torsion_bar_monitorable`  Jha et al. (2016), Fig. 7: its monitorable mechanical part
:func:`three_tank`        Du et al. (n.d.): the DTS200 three-tank system
:func:`friction_drive`    Rodriguez Obando et al. (2021): roller-on-tire friction drive
:func:`mass_spring_chain` n mass-spring-damper stages (benchmarks)
========================  =====================================================

Each builder returns a :class:`~bondgraph.model.BondGraph`; :func:`example`
returns a model with the inputs and horizon of its demonstration run.  Every element declares its unit
(:mod:`bondgraph.dimensions` checks them).  Every physical parameter of
these models is positive: the C, I, R parameters by default, the two-port moduli (motor constant,
belt ratio, radii) and the law constants declared so (:mod:`bondgraph.domains`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from .control import PIController
from .model import BondGraph

__all__ = [
    "MASS_LOAD", "MU_UNCERTAINTY", "OMEGA_M_REF", "ORIFICE", "TANK_AREA", "THREE_TANK", "TORSION_BAR",
    "TORSION_BAR_UNITS", "U_MAX", "Example", "dc_motor", "example", "friction_drive", "mass_spring_chain",
    "rlc_circuit", "tank_cascade", "three_tank", "torsion_bar", "torsion_bar_controller", "torsion_bar_monitorable",
    "torsion_bar_with_load", "with_suspended_load",
]


def rlc_circuit(R: float = 10.0, L: float = 0.1, C: float = 1e-3) -> BondGraph:
    """Series RLC circuit driven by a voltage source ``V``.

    ``Se:V -> 1 (R, I:L, Df:i) -> 0 (C, De:v_C)``.
    """
    bg = BondGraph(name="series RLC circuit")
    bg.add("V", "Se", signal="V", unit="V")
    bg.add("J1", "1")
    bg.add("R", "R", value=R, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("L", "I", value=L, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("J0", "0")
    bg.add("C", "C", value=C, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("i", "Df", unit="A")
    bg.add("v_C", "De", unit="V")
    for tail, head in [("V", "J1"), ("J1", "R"), ("J1", "L"), ("J1", "J0"), ("J0", "C"), ("J1", "i"), ("J0", "v_C")]:
        bg.bond(tail, head)
    return bg


def dc_motor(R_a: float = 1.23, L_a: float = 1.34e-3, k_m: float = 3.89e-2, J: float = 1e-4,
             b: float = 1e-4) -> BondGraph:
    """Permanent-magnet DC motor with current and speed sensors.

    ``Se:U -> 1_e (R:R_a, I:L_a, Df:i) -> GY:k_m -> 1_m (I:J, R:b, Df:omega)``.
    """
    bg = BondGraph(name="DC motor")
    bg.add("U", "Se", unit="V")
    bg.add("1_e", "1")
    bg.add("R_a", "R", value=R_a, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("L_a", "I", value=L_a, uncertainty=(-0.05, 0.05), unit="H")
    bg.add("GY", "GY", param="k_m", value=k_m, uncertainty=(-0.02, 0.02), domain="positive", unit="N*m/A")
    bg.add("1_m", "1")
    bg.add("J", "I", value=J, uncertainty=(-0.1, 0.1), unit="kg*m^2")
    bg.add("b", "R", value=b, uncertainty=(0.0, 0.2), unit="N*m*s/rad")
    bg.add("i", "Df", unit="A")
    bg.add("omega", "Df", unit="rad/s")
    for tail, head in [("U", "1_e"), ("1_e", "R_a"), ("1_e", "L_a"), ("1_e", "GY"), ("GY", "1_m"),
                       ("1_m", "J"), ("1_m", "b"), ("1_e", "i"), ("1_m", "omega")]:
        bg.bond(tail, head)
    return bg


# Jha et al. (2016), Table VI, with k_m = 3.89e-2 N.m/A (the table's 3.89e-4 cannot hold the
# nominal speed; see docs/design.md).  b_s is Table VI's "R_s".
TORSION_BAR = {
    "J_m": (6.76e-6, (-0.02, 0.02)),
    "f_m": (2e-6, (0.0, 0.3)),
    "J_Md": (9.07e-4, (-0.1, 0.1)),
    "b_Md": (5.025e-3, (0.0, 0.2)),
    "J_Ld": (1.37e-3, (-0.1, 0.1)),
    "b_Ld": (2.5e-5, (0.0, 0.2)),
    "k_s": (1.786, (-0.1, 0.1)),
    "b_s": (5.11e-4, (-0.1, 0.1)),
    "k_m": (3.89e-2, None),
    "k_belt": (3.75, None),
    "L_a": (1.34e-3, None),
    "R_a": (1.23, None),
}
#: The unit of each torsion-bar parameter (a rotational bond carries a torque in N*m and a speed in rad/s).
TORSION_BAR_UNITS = {"J_m": "kg*m^2", "f_m": "N*m*s/rad", "J_Md": "kg*m^2", "b_Md": "N*m*s/rad", "J_Ld": "kg*m^2",
                     "b_Ld": "N*m*s/rad", "k_s": "N*m/rad", "b_s": "N*m*s/rad", "k_m": "N*m/A", "k_belt": "1",
                     "L_a": "H", "R_a": "Ohm"}
OMEGA_M_REF = 112.5  # rad/s, motor speed set-point (omega_Md = 30 rad/s)
U_MAX = 12.0  # V, actuator saturation


def _mechanical_part(bg: BondGraph, values: dict) -> None:
    """Motor shaft 1_1, belt TF, motor disk 1_Md, shaft 0_s/1_s, load disk 1_2."""

    def element(name, kind, **extra):
        value, uncertainty = values[name]
        bg.add(name, kind, value=value, uncertainty=uncertainty, unit=TORSION_BAR_UNITS[name], **extra)

    bg.add("1_1", "1")
    element("J_m", "I")
    element("f_m", "R")
    bg.add("omega_m", "Df", unit="rad/s")
    value, _ = values["k_belt"]
    bg.add("TF", "TF", param="k_belt", value=value, modulus="1/k_belt", domain="positive", unit="1")
    bg.add("1_Md", "1")
    element("J_Md", "I")
    element("b_Md", "R")
    bg.add("0_s", "0")
    bg.add("1_s", "1")
    element("k_s", "C", law="e - k_s*q")  # spring: torque = k_s * twist angle
    element("b_s", "R")
    bg.add("1_2", "1")
    element("J_Ld", "I")
    element("b_Ld", "R")
    bg.add("omega_Ld", "Df", unit="rad/s")
    for tail, head in [("1_1", "J_m"), ("1_1", "f_m"), ("1_1", "TF"), ("TF", "1_Md"), ("1_Md", "J_Md"),
                       ("1_Md", "b_Md"), ("1_Md", "0_s"), ("0_s", "1_s"), ("1_s", "k_s"), ("1_s", "b_s"),
                       ("0_s", "1_2"), ("1_2", "J_Ld"), ("1_2", "b_Ld"), ("1_1", "omega_m"), ("1_2", "omega_Ld")]:
        bg.bond(tail, head)


def torsion_bar(**overrides: float) -> BondGraph:
    """The complete torsion-bar system of Jha et al. (2016), Figs. 5-6 and Table VI.

    ``MSe:U -> 1_e (R:R_a, I:L_a) -> GY:k_m -> 1_1 (I:J_m, R:f_m, Df:omega_m)
    -> TF:1/k_belt -> 1_Md (I:J_Md, R:b_Md) -> 0_s -> [1_s (C:k_s, R:b_s)]
    -> 1_2 (I:J_Ld, R:b_Ld, Df:omega_Ld)``.

    The voltage ``U`` comes from the PI speed loop (:func:`torsion_bar_controller`).
    With the rigid belt, J_Md is dependent storage in integral causality.
    Keyword arguments override nominal values, e.g. ``torsion_bar(b_Md=0.01)``.
    """
    values = _values(overrides)
    bg = BondGraph(name="torsion bar")
    bg.add("U", "MSe", unit="V")
    bg.add("1_e", "1")
    bg.add("R_a", "R", value=values["R_a"][0], unit="Ohm")
    bg.add("L_a", "I", value=values["L_a"][0], unit="H")
    bg.add("GY", "GY", param="k_m", value=values["k_m"][0], domain="positive", unit="N*m/A")
    for tail, head in [("U", "1_e"), ("1_e", "R_a"), ("1_e", "L_a"), ("1_e", "GY")]:
        bg.bond(tail, head)
    _mechanical_part(bg, values)
    bg.bond("GY", "1_1")
    return bg


def torsion_bar_monitorable(**overrides: float) -> BondGraph:
    """Jha et al. (2016), Fig. 7: the monitorable mechanical part, driven by the motor torque ``tau_m``."""
    values = _values(overrides)
    bg = BondGraph(name="torsion bar (monitorable part)")
    bg.add("tau_m", "MSe", unit="N*m")
    _mechanical_part(bg, values)
    bg.bond("tau_m", "1_1")
    return bg


# Jha et al. (2016), section 7: a suspended load of mass M presses a lever on the motor disk
# (Coulomb friction mu M g r_Md sgn(omega_Md), eqs. 54-56).  r_Md is not given in the
# paper; 0.05 m is our assumption.
MASS_LOAD = {"M": 0.1, "mu": 0.27, "g": 9.81, "r_Md": 0.05}
MU_UNCERTAINTY = (-0.1, 0.1)


def torsion_bar_with_load(M: float = MASS_LOAD["M"], mu: float = MASS_LOAD["mu"], r_Md: float = MASS_LOAD["r_Md"],
                          **overrides: float) -> BondGraph:
    """Jha et al. (2016), section 7: the monitorable part with the suspended-mass friction on the motor disk.

    The motor-disk R element gets the law ``e = b_Md f + mu M g r_Md sign(f)``
    (eq. 56), with M (kg), mu and r_Md as law constants and mu uncertain as in
    Table VI; the prognostic candidate of section 7 is M (eqs. 61-62).
    """
    bg = with_suspended_load(torsion_bar_monitorable(**overrides), M=M, mu=mu, r_Md=r_Md)
    bg.name = "torsion bar with suspended load"
    return bg


def with_suspended_load(bg: BondGraph, M: float = MASS_LOAD["M"], mu: float = MASS_LOAD["mu"],
                        r_Md: float = MASS_LOAD["r_Md"]) -> BondGraph:
    """Add the suspended-load Coulomb friction (eqs. 54-56) to the R element ``b_Md`` of a torsion bar.

    Works on :func:`torsion_bar` (to simulate the experiments of section 7) and on
    :func:`torsion_bar_monitorable` (to derive their I-ARR, eq. 57).  Modifies and returns ``bg``.
    """
    node = bg.graph.nodes["b_Md"]
    node["law"] = "e - b_Md*f - mu*M*g*r_Md*sign(f)"
    node["params"] = {"M": M, "mu": mu, "g": MASS_LOAD["g"], "r_Md": r_Md}
    node["uncertainties"] = {"mu": MU_UNCERTAINTY}  # Table VI
    node["domains"] = {"M": "positive", "mu": "positive", "g": "positive", "r_Md": "positive"}
    node["units"] = {"M": "kg", "mu": "1", "g": "m/s^2", "r_Md": "m"}
    bg.validate()
    return bg


def _values(overrides: dict) -> dict:
    unknown = set(overrides) - set(TORSION_BAR)
    if unknown:
        raise KeyError(f"unknown torsion-bar parameter(s) {sorted(unknown)}; known: {sorted(TORSION_BAR)}")
    return {k: (overrides.get(k, v), u) for k, (v, u) in TORSION_BAR.items()}


def torsion_bar_controller(kp: float = 0.05, ki: float = 0.5, setpoint: float | Callable = OMEGA_M_REF) -> PIController:
    """PI speed loop on ``omega_m`` with the 12 V actuator saturation (gains are ours; the paper gives none)."""
    return PIController("omega_m", setpoint=setpoint, kp=kp, ki=ki, limits=(-U_MAX, U_MAX))


# Du et al. (n.d.), section 6.1 (DTS200).  Levels h are efforts, volumetric flows are flows.
THREE_TANK = {"A_s": 0.0154, "S_n": 5e-5, "g": 9.81, "az1": 0.5, "az2": 0.6, "az3": 0.5, "Q1": 4.5e-5, "Q2": 4.5e-5}


def three_tank(az1: float = 0.5, az2: float = 0.6, az3: float = 0.5, A_s: float = 0.0154,
               uncertainty: float = 0.05, area_uncertainty: float | None = None) -> BondGraph:
    """The DTS200 three-tank system of Du et al. (n.d.), eqs. 57-58.

    Tanks 1, 3, 2 in series: ``Q1 -> tank 1 -> valve az1 -> tank 3 -> valve az3
    -> tank 2 -> valve az2 -> out``, ``Q2 -> tank 2``.  Tanks are C elements
    (``h = V / A``), valves nonlinear R elements with the law of eq. 58,
    ``Q = az S_n sign(dh) sqrt(2 g |dh|)``; levels are measured by De:h1..h3.
    Parameter uncertainty: ``(-uncertainty, +uncertainty)`` on every az, and
    ``+-area_uncertainty`` on the areas (default: the same as the valves).
    """
    box = (-uncertainty, uncertainty)
    area_box = box if area_uncertainty is None else (-area_uncertainty, area_uncertainty)
    constants = {"S_n": THREE_TANK["S_n"], "g": THREE_TANK["g"]}
    bg = BondGraph(name="three-tank DTS200")
    bg.add("Q1", "Sf", unit="m^3/s")
    bg.add("Q2", "Sf", unit="m^3/s")
    for tank in ("1", "2", "3"):
        bg.add(f"0_{tank}", "0")
        bg.add(f"A_{tank}", "C", value=A_s, uncertainty=area_box, unit="m^2")
        bg.add(f"h{tank}", "De", unit="m")
        bg.bond(f"0_{tank}", f"A_{tank}")
        bg.bond(f"0_{tank}", f"h{tank}")
    for valve, value in (("az1", az1), ("az2", az2), ("az3", az3)):
        bg.add(valve, "R", value=value, uncertainty=box, params=constants,
               domains={"S_n": "positive", "g": "positive"}, law=f"f - {valve}*S_n*sign(e)*sqrt(2*g*Abs(e))",
               unit="1", units={"S_n": "m^2", "g": "m/s^2"})
    bg.add("1_13", "1")
    bg.add("1_32", "1")
    for tail, head in [("Q1", "0_1"), ("Q2", "0_2"), ("0_1", "1_13"), ("1_13", "az1"), ("1_13", "0_3"),
                       ("0_3", "1_32"), ("1_32", "az3"), ("1_32", "0_2"), ("0_2", "az2")]:
        bg.bond(tail, head)
    return bg


def friction_drive(J1: float = 9.9225e-4, B1: float = 6.36e-3, r1: float = 0.0315, alpha: float = 11.0,
                   r2: float = 0.35, J2: float = 12.25, B2: float = 0.625) -> BondGraph:
    """Roller-on-tire friction drive, Rodriguez Obando et al. (2021), eqs. 1-5 (defaults: Table 1 in SI, alpha: eq. 57).

    ``MSe:T_m -> 1_1 (I:J1, R:B1, Df:omega1) -> TF:r1 -> 0_c (R:alpha)
    -> TF:1/r2 -> 1_2 (I:J2, R:B2, Df:omega2)``.  The 0-junction carries the
    contact force ``F_c`` (common effort) and balances the tangential speeds,
    so the contact R element sees ``v = r1 omega1 - r2 omega2`` and
    ``F_c = alpha v`` (eq. 1); the power it dissipates, ``alpha v^2``, is the
    deterioration rate of eq. (9).  The state equations are eq. (13).

    >>> friction_drive().state_equations().coenergy_states({"J1": "omega1", "J2": "omega2"}).rhs[1]
    (-B2*omega2 + alpha*r2*(omega1*r1 - omega2*r2))/J2
    """
    bg = BondGraph(name="friction drive")
    bg.add("T_m", "MSe", unit="N*m")
    bg.add("1_1", "1")
    bg.add("J1", "I", value=J1, unit="kg*m^2")
    bg.add("B1", "R", value=B1, unit="N*m*s/rad")
    bg.add("TF_1", "TF", param="r1", value=r1, domain="positive", unit="m")
    bg.add("0_c", "0")
    bg.add("alpha", "R", value=alpha, unit="N*s/m")
    bg.add("TF_2", "TF", param="r2", value=r2, modulus="1/r2", domain="positive", unit="m")
    bg.add("1_2", "1")
    bg.add("J2", "I", value=J2, unit="kg*m^2")
    bg.add("B2", "R", value=B2, unit="N*m*s/rad")
    bg.add("omega1", "Df", unit="rad/s")
    bg.add("omega2", "Df", unit="rad/s")
    for tail, head in [("T_m", "1_1"), ("1_1", "J1"), ("1_1", "B1"), ("1_1", "TF_1"), ("TF_1", "0_c"),
                       ("0_c", "alpha"), ("0_c", "TF_2"), ("TF_2", "1_2"), ("1_2", "J2"), ("1_2", "B2"),
                       ("1_1", "omega1"), ("1_2", "omega2")]:
        bg.bond(tail, head)
    return bg


def mass_spring_chain(n: int, mass: float = 1.0, stiffness: float = 100.0, damping: float = 0.5) -> BondGraph:
    """``n`` mass-spring-damper stages in a chain, a velocity sensor on every mass.

    ``Se:F -> 1_1 (I:m1, R:b1, Df:v1) -> 0_1 (C:c1) -> 1_2 ... -> 0_n (C:cn)``;
    the last spring is tied to the wall.  2n states.
    """
    bg = BondGraph(name=f"{n}-stage mass-spring-damper chain")
    bg.add("F", "Se", unit="N")
    previous = "F"
    for i in range(1, n + 1):
        bg.add(f"1_{i}", "1")
        bg.add(f"m{i}", "I", value=mass, uncertainty=(-0.05, 0.05), unit="kg")
        bg.add(f"b{i}", "R", value=damping, uncertainty=(0.0, 0.2), unit="N*s/m")
        bg.add(f"v{i}", "Df", unit="m/s")
        bg.add(f"0_{i}", "0")
        bg.add(f"c{i}", "C", value=1.0 / stiffness, uncertainty=(-0.1, 0.1), unit="m/N")
        bg.bond(previous, f"1_{i}")
        for tail, head in [(f"1_{i}", f"m{i}"), (f"1_{i}", f"b{i}"), (f"1_{i}", f"v{i}"),
                           (f"1_{i}", f"0_{i}"), (f"0_{i}", f"c{i}")]:
            bg.bond(tail, head)
        previous = f"0_{i}"
    return bg


#: Tank areas (m^2) and orifice constants a = c_d A_o sqrt(2 g) (m^(5/2)/s) of :func:`tank_cascade`: a laboratory
#: rig's values.
TANK_AREA, ORIFICE = 0.05, 2.0e-3


def tank_cascade(n: int, *, every: int = 1, area: float = TANK_AREA, orifice: float = ORIFICE) -> BondGraph:
    """``n`` gravity-drained tanks in series: ``q_in -> 0_1 (C:T1, De h1) -> 1_12 (R:O1) -> 0_2 ... -> 0_n (R:On)``.

    Each tank is a C element of its area (effort: the level, state: the volume ``q_Ti``), each orifice a
    non-linear R element with the signed square-root (Torricelli) law ``q = a sign(dh) sqrt|dh|``; tank ``i``
    drains into tank ``i + 1``, the last to the atmosphere.  A level sensor on every ``every``-th tank, from
    the first, and always on the last: with ``every=2`` the levels between two sensors are known only through
    the orifice laws, and some redundancy only through the tanks' dynamics.

    >>> bg = tank_cascade(3, every=2)
    >>> sorted(name for name, e in bg.structure().elements.items() if e.kind == "De")
    ['h1', 'h3']
    """
    bg = BondGraph(name=f"{n}-tank cascade" + ("" if every == 1 else f", a level sensor every {every} tanks"))
    bg.add("q_in", "Sf", unit="m^3/s")
    previous = "q_in"
    for i in range(1, n + 1):
        bg.add(f"0_{i}", "0")
        bg.add(f"T{i}", "C", param=f"A{i}", value=area, uncertainty=(-0.02, 0.02), unit="m^2")
        bg.add(f"O{i}", "R", param=f"a{i}", value=orifice, uncertainty=(-0.1, 0.1),
               law=f"f - a{i}*sign(e)*sqrt(Abs(e))", unit="m^(5/2)/s")
        bonds = [(previous, f"0_{i}"), (f"0_{i}", f"T{i}")]
        if (i - 1) % every == 0 or i == n:
            bg.add(f"h{i}", "De", unit="m")
            bonds.append((f"0_{i}", f"h{i}"))
        if i < n:   # the orifice between tank i and tank i + 1 sees the difference of their levels
            bg.add(f"1_{i}{i + 1}", "1")
            bonds += [(f"0_{i}", f"1_{i}{i + 1}"), (f"1_{i}{i + 1}", f"O{i}")]
            previous = f"1_{i}{i + 1}"
        else:        # the last drains to the atmosphere: its level is the head across the orifice
            bonds.append((f"0_{i}", f"O{i}"))
        for tail, head in bonds:
            bg.bond(tail, head)
    return bg


@dataclass
class Example:
    """A model with the inputs and horizon of its demonstration run."""

    name: str
    model: BondGraph
    inputs: dict = field(default_factory=dict)
    t_end: float = 1.0
    x0: dict = field(default_factory=dict)
    description: str = ""


def example(name: str) -> Example:
    """A built-in example by name: ``rlc``, ``dc-motor``, ``torsion-bar``, ``three-tank``."""
    builders = {
        "rlc": lambda: Example("rlc", rlc_circuit(), {"V": 1.0}, 0.5,
                               description="step response of a series RLC circuit"),
        "dc-motor": lambda: Example("dc-motor", dc_motor(), {"U": 12.0}, 1.0, description="DC motor speed-up at 12 V"),
        "torsion-bar": lambda: Example("torsion-bar", torsion_bar(), {"U": torsion_bar_controller()}, 10.0,
                                       description="torsion bar under the PI speed loop (omega_m -> 112.5 rad/s)"),
        "three-tank": lambda: Example("three-tank", three_tank(), {"Q1": THREE_TANK["Q1"], "Q2": THREE_TANK["Q2"]},
                                      200.0, {"A_1": 0.0154 * 0.5, "A_2": 0.0154 * 0.3, "A_3": 0.0154 * 0.4},
                                      "DTS200 three tanks filling from h = (0.5, 0.3, 0.4) m"),
    }
    if name not in builders:
        raise KeyError(f"unknown example {name!r}; choose from {sorted(builders)}")
    return builders[name]()
