"""Library models against independently hand-written ODEs.

Every example model shipped in :mod:`bondgraph.library` is simulated with
:func:`bondgraph.simulate` and compared with an ODE written here by hand from
the physics of the system (Kirchhoff / Newton / mass balance), integrated with
``scipy.integrate.solve_ivp`` on the same time grid, with the same method and
tight tolerances.  The hand ODEs deliberately use nothing from the toolkit's
symbolic machinery: only the nominal parameter values are read from the
library (so the two sides describe the same physical system).

For each state the error is measured relative to the largest absolute value
of the hand-written trajectory, and must stay below ``REL_TOL``.  Each test
also checks a physical property of the response (steady state, tracking,
saturation...) so that a model that is wrong but self-consistent would fail.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bondgraph import PIController, simulate
from bondgraph.library import (
    OMEGA_M_REF,
    THREE_TANK,
    TORSION_BAR,
    U_MAX,
    dc_motor,
    rlc_circuit,
    three_tank,
    torsion_bar,
    torsion_bar_controller,
)

REL_TOL = 1e-6
RTOL = 1e-11
ATOL = 1e-13
METHOD = "LSODA"


def _hand(rhs, t_span, y0, t_eval, max_step=np.inf, method=METHOD):
    solution = solve_ivp(rhs, t_span, np.asarray(y0, float), method=method, t_eval=t_eval,
                         rtol=RTOL, atol=ATOL, max_step=max_step)
    assert solution.success, solution.message
    return solution.y


def _relative_errors(result, expected: dict) -> dict:
    """max |toolkit - hand| / max |hand| for every state (and signal) in ``expected``."""
    errors = {}
    for name, reference in expected.items():
        reference = np.asarray(reference, float)
        scale = np.max(np.abs(reference))
        assert scale > 0.0, f"{name}: hand trajectory is identically zero, comparison is meaningless"
        errors[name] = float(np.max(np.abs(np.asarray(result[name], float) - reference)) / scale)
    return errors


def _assert_close(result, expected: dict) -> dict:
    errors = _relative_errors(result, expected)
    bad = {k: v for k, v in errors.items() if not v < REL_TOL}
    assert not bad, f"relative errors above {REL_TOL:g}: {bad} (all: {errors})"
    return errors


# ---------------------------------------------------------------------------
# Series RLC circuit: L di/dt = V - R i - q/C, dq/dt = i
# ---------------------------------------------------------------------------

def test_rlc_circuit_matches_hand_ode():
    R, L, C, V = 10.0, 0.1, 1e-3, 1.0
    t_eval = np.linspace(0.0, 0.5, 1001)
    q0 = 2e-4  # some initial charge: v_C(0) = 0.2 V

    def rhs(t, y):
        i, q = y  # current through the loop, capacitor charge
        return [(V - R * i - q / C) / L, i]

    i_h, q_h = _hand(rhs, (0.0, 0.5), [0.0, q0], t_eval)

    result = simulate(rlc_circuit(R=R, L=L, C=C), (0.0, 0.5), {"V": V}, x0={"C": q0},
                      t_eval=t_eval, method=METHOD, rtol=RTOL, atol=ATOL)
    assert set(result.states) == {"p_L", "q_C"}
    _assert_close(result, {"p_L": L * i_h, "q_C": q_h, "i": i_h, "v_C": q_h / C})

    # Physics: underdamped (zeta = R/2 sqrt(C/L) = 0.5) step response.  The
    # capacitor charges to the source voltage, the current dies out, and it
    # overshoots by exp(-pi zeta / sqrt(1 - zeta^2)) of the step.
    v_C = result["v_C"]
    assert v_C[-1] == pytest.approx(V, abs=1e-9)
    assert abs(result["i"][-1]) < 1e-9
    zeta = R / 2.0 * np.sqrt(C / L)
    overshoot = (np.max(v_C) - V) / (V - q0 / C)
    assert overshoot == pytest.approx(np.exp(-np.pi * zeta / np.sqrt(1.0 - zeta**2)), rel=1e-3)


# ---------------------------------------------------------------------------
# DC motor: L_a di/dt = U - R_a i - k_m w,  J dw/dt = k_m i - b w
# ---------------------------------------------------------------------------

def test_dc_motor_matches_hand_ode():
    R_a, L_a, k_m, J, b = 1.23, 1.34e-3, 3.89e-2, 1e-4, 1e-4
    U = 12.0
    t_eval = np.linspace(0.0, 1.0, 1001)

    def rhs(t, y):
        i, w = y
        return [(U - R_a * i - k_m * w) / L_a, (k_m * i - b * w) / J]

    i_h, w_h = _hand(rhs, (0.0, 1.0), [0.0, 0.0], t_eval)

    result = simulate(dc_motor(R_a=R_a, L_a=L_a, k_m=k_m, J=J, b=b), (0.0, 1.0), {"U": U},
                      t_eval=t_eval, method=METHOD, rtol=RTOL, atol=ATOL)
    assert set(result.states) == {"p_L_a", "p_J"}
    _assert_close(result, {"p_L_a": L_a * i_h, "p_J": J * w_h, "i": i_h, "omega": w_h})

    # Physics: steady speed and current from k_m i = b w, U = R_a i + k_m w.
    w_ss = U * k_m / (k_m**2 + R_a * b)
    i_ss = b * w_ss / k_m
    assert result["omega"][-1] == pytest.approx(w_ss, rel=1e-5)
    assert result["i"][-1] == pytest.approx(i_ss, rel=1e-4)
    # Inrush: the current peaks close to U/R_a before the back-emf builds up.
    assert 0.8 * U / R_a < np.max(result["i"]) <= U / R_a


# ---------------------------------------------------------------------------
# Torsion bar under the saturated PI speed loop
# ---------------------------------------------------------------------------

def _torsion_hand(t_span, t_eval, b_Md, kp, ki, setpoint=OMEGA_M_REF, u_max=U_MAX, max_step=np.inf,
                  method=METHOD):
    """Hand ODE of the torsion bar with its own PI controller.

    Hand states: i (armature current), w_m (motor shaft speed), q (shaft twist
    angle), w_L (load disk speed), z (PI integral).  The motor disk is rigidly
    tied to the motor shaft by the belt: w_Md = w_m / k_belt, and a torque T at
    the disk is T / k_belt at the motor shaft, so the disk inertia appears at
    the motor shaft as J_Md / k_belt^2.

    PI: v = kp e + ki z, U = clip(v, -12, 12), e = setpoint - w_m, with the
    back-calculation anti-windup documented in bondgraph.control:
    dz/dt = e + (U - v) / (ki T_t), tracking time T_t = kp / ki (its default).
    """
    T_t = kp / ki
    P = {k: v for k, (v, _) in TORSION_BAR.items()}
    R_a, L_a, k_m = P["R_a"], P["L_a"], P["k_m"]
    J_m, f_m, k_belt = P["J_m"], P["f_m"], P["k_belt"]
    J_Md, k_s, b_s = P["J_Md"], P["k_s"], P["b_s"]
    J_Ld, b_Ld = P["J_Ld"], P["b_Ld"]
    J_eq = J_m + J_Md / k_belt**2
    b_Md_t = b_Md if callable(b_Md) else (lambda t, v=b_Md: v)

    def pi(t, w_m, z):
        err = setpoint - w_m
        v = kp * err + ki * z
        u = min(max(v, -u_max), u_max)
        return u, err + (u - v) / (ki * T_t)

    def rhs(t, y):
        i, w_m, q, w_L, z = y
        U, dz = pi(t, w_m, z)
        w_Md = w_m / k_belt
        tau_shaft = k_s * q + b_s * (w_Md - w_L)  # spring || damper, acting from disk on load
        tau_disk = b_Md_t(t) * w_Md + tau_shaft  # torque the motor disk must supply
        di = (U - R_a * i - k_m * w_m) / L_a
        dw_m = (k_m * i - f_m * w_m - tau_disk / k_belt) / J_eq
        dq = w_Md - w_L
        dw_L = (tau_shaft - b_Ld * w_L) / J_Ld
        return [di, dw_m, dq, dw_L, dz]

    y = _hand(rhs, t_span, np.zeros(5), t_eval, max_step=max_step, method=method)
    i, w_m, q, w_L, z = y
    U = np.array([pi(t, a, c)[0] for t, a, c in zip(t_eval, w_m, z)])
    expected = {"p_L_a": L_a * i, "p_J_m": J_m * w_m, "q_k_s": q, "p_J_Ld": J_Ld * w_L,
                "omega_m": w_m, "omega_Ld": w_L, "U": U}
    return expected, z


def _default_gains():
    controller = torsion_bar_controller()
    assert isinstance(controller, PIController)
    assert controller.limits == (-U_MAX, U_MAX) and U_MAX == 12.0
    assert controller.measured == "omega_m"
    assert controller.tracking_time is None  # default tracking time kp / ki, as the hand PI uses
    return controller.kp, controller.ki


@pytest.mark.slow
def test_torsion_bar_pi_loop_matches_hand_ode():
    kp, ki = _default_gains()
    t_span = (0.0, 10.0)
    t_eval = np.linspace(*t_span, 1001)
    expected, z_h = _torsion_hand(t_span, t_eval, TORSION_BAR["b_Md"][0], kp, ki, max_step=1e-2)
    assert np.max(expected["U"]) < U_MAX  # the nominal run never saturates

    result = simulate(torsion_bar(), t_span, {"U": torsion_bar_controller()}, t_eval=t_eval,
                      method=METHOD, rtol=RTOL, atol=ATOL, max_step=1e-2)
    assert set(result.states) == {"p_L_a", "p_J_m", "q_k_s", "p_J_Ld"}
    _assert_close(result, expected)
    z = result.controller_states["U"][:, 0]
    assert np.max(np.abs(z - z_h)) / np.max(np.abs(z_h)) < REL_TOL

    # Physics: the PI loop tracks the 112.5 rad/s set point, the load disk
    # turns at the motor-disk speed 112.5 / k_belt = 30 rad/s, and the shaft
    # twist carries the load friction: k_s q = b_Ld w_L (b_s term vanishes).
    k_belt, k_s, b_Ld = TORSION_BAR["k_belt"][0], TORSION_BAR["k_s"][0], TORSION_BAR["b_Ld"][0]
    assert result["omega_m"][-1] == pytest.approx(OMEGA_M_REF, rel=1e-3)
    assert result["omega_Ld"][-1] == pytest.approx(OMEGA_M_REF / k_belt, rel=1e-2)
    assert result.states["q_k_s"][-1] == pytest.approx(b_Ld * OMEGA_M_REF / k_belt / k_s, rel=5e-2)
    # Nominal friction needs ~5.7 V: the loop settles well inside the actuator range.
    assert np.all(np.abs(result["U"][t_eval > 5.0]) < U_MAX - 1.0)


@pytest.mark.slow
def test_torsion_bar_saturated_actuator_matches_hand_ode():
    """Motor-disk bearing degradation drives the actuator into saturation.

    b_Md stays nominal up to t = 4 s (the loop settles at 112.5 rad/s, ~5.7 V),
    then grows as b0 exp(0.5 (t - 4)) up to a cap of 0.05 (reached at t ~ 8.6 s).
    Holding 112.5 rad/s needs 12 V once b_Md ~ 0.030: the output saturates while
    the speed falls, back-calculation keeps the integral from winding up, and
    the speed settles where the 12 V motor balances the friction.
    """
    kp, ki = _default_gains()
    b0 = TORSION_BAR["b_Md"][0]
    b_cap = 0.05

    def b_Md(t):
        return b0 if t <= 4.0 else min(b0 * np.exp(0.5 * (t - 4.0)), b_cap)

    t_span = (0.0, 10.0)
    t_eval = np.linspace(*t_span, 1001)
    expected, z_h = _torsion_hand(t_span, t_eval, b_Md, kp, ki, max_step=1e-2)

    result = simulate(torsion_bar(), t_span, {"U": torsion_bar_controller()}, t_eval=t_eval,
                      parameters={"b_Md": b_Md}, method=METHOD, rtol=RTOL, atol=ATOL, max_step=1e-2)
    _assert_close(result, expected)
    z = result.controller_states["U"][:, 0]
    assert np.max(np.abs(z - z_h)) / np.max(np.abs(z_h)) < REL_TOL

    # Before the degradation the loop tracks the set point inside the actuator range.
    before = (t_eval > 3.0) & (t_eval <= 4.0)
    assert np.all(np.abs(result["omega_m"][before] - OMEGA_M_REF) < 1e-3)
    assert np.all(result["U"][before] < U_MAX - 5.0)
    # Saturation really happened, in both models, and holds to the end.
    U = result["U"]
    assert np.max(U) == pytest.approx(U_MAX, abs=1e-12)
    assert np.max(expected["U"]) == pytest.approx(U_MAX, abs=1e-12)
    saturated = U >= U_MAX - 1e-12
    first = int(np.argmax(saturated))
    assert 6.0 < t_eval[first] < 9.0
    assert np.all(saturated[first:])
    # Anti-windup (back-calculation, T_t = kp/ki): while saturated, dz/dt =
    # (U_max - ki z)/kp, so ki z relaxes to U_max instead of winding up with the
    # growing error; the unclipped output stays at U_max + kp e > U_max.
    assert np.max(z) < 1.01 * U_MAX / ki
    assert z[-1] == pytest.approx(U_MAX / ki, rel=1e-6)

    # Physics: at 12 V the loop is open and the speed settles where the motor
    # torque balances all friction reflected to the motor shaft:
    # k_m (U - k_m w)/R_a = f_m w + (b_Md + b_Ld) w / k_belt^2.
    P = {k: v for k, (v, _) in TORSION_BAR.items()}
    w_sat = (P["k_m"] * U_MAX / P["R_a"]) / (
        P["k_m"] ** 2 / P["R_a"] + P["f_m"] + (b_cap + P["b_Ld"]) / P["k_belt"] ** 2)
    assert w_sat < OMEGA_M_REF - 25.0
    assert result["omega_m"][-1] == pytest.approx(w_sat, rel=1e-3)
    assert result["omega_Ld"][-1] == pytest.approx(w_sat / P["k_belt"], rel=1e-2)


# ---------------------------------------------------------------------------
# Three-tank DTS200: mass balance with Torricelli valves
# ---------------------------------------------------------------------------

def test_three_tank_matches_hand_ode():
    A_s, S_n, g = THREE_TANK["A_s"], THREE_TANK["S_n"], THREE_TANK["g"]
    az1, az2, az3 = THREE_TANK["az1"], THREE_TANK["az2"], THREE_TANK["az3"]
    Q1, Q2 = THREE_TANK["Q1"], THREE_TANK["Q2"]
    h0 = (0.5, 0.3, 0.4)
    t_span = (0.0, 6000.0)  # slowest linearised time constant ~ 690 s
    t_eval = np.linspace(*t_span, 1201)

    def valve(az, dh):
        return az * S_n * np.sign(dh) * np.sqrt(2.0 * g * abs(dh))

    def rhs(t, h):
        h1, h2, h3 = h
        Q13 = valve(az1, h1 - h3)
        Q32 = valve(az3, h3 - h2)
        Q20 = valve(az2, h2)
        return [(Q1 - Q13) / A_s, (Q2 + Q32 - Q20) / A_s, (Q13 - Q32) / A_s]

    h1, h2, h3 = _hand(rhs, t_span, h0, t_eval)

    result = simulate(three_tank(), t_span, {"Q1": Q1, "Q2": Q2},
                      x0={"A_1": A_s * h0[0], "A_2": A_s * h0[1], "A_3": A_s * h0[2]},
                      t_eval=t_eval, method=METHOD, rtol=RTOL, atol=ATOL)
    assert set(result.states) == {"q_A_1", "q_A_2", "q_A_3"}
    _assert_close(result, {"q_A_1": A_s * h1, "q_A_2": A_s * h2, "q_A_3": A_s * h3,
                           "h1": h1, "h2": h2, "h3": h3})
    # The levels stay clear of the sqrt singularities (dh = 0, h2 = 0).
    assert np.min(h1 - h3) > 0.05 and np.min(h3 - h2) > 0.05 and np.min(h2) > 0.1

    # Physics: steady state where inflow equals outflow.  Q13 = Q32 = Q1 and
    # Q20 = Q1 + Q2, i.e. h2 = ((Q1+Q2)/(az2 S_n))^2 / 2g, h3 - h2 = (Q1/(az3 S_n))^2 / 2g,
    # h1 - h3 = (Q1/(az1 S_n))^2 / 2g.
    h2_ss = ((Q1 + Q2) / (az2 * S_n)) ** 2 / (2 * g)
    h3_ss = h2_ss + (Q1 / (az3 * S_n)) ** 2 / (2 * g)
    h1_ss = h3_ss + (Q1 / (az1 * S_n)) ** 2 / (2 * g)
    assert result["h1"][-1] == pytest.approx(h1_ss, rel=1e-3)
    assert result["h2"][-1] == pytest.approx(h2_ss, rel=1e-3)
    assert result["h3"][-1] == pytest.approx(h3_ss, rel=1e-3)
    # Mass balance along the way: total volume changes by (Q1 + Q2 - Q20) dt.
    volume = result.states["q_A_1"] + result.states["q_A_2"] + result.states["q_A_3"]
    outflow = az2 * S_n * np.sqrt(2 * g * result["h2"])
    dt = np.diff(t_eval)
    integrated = np.concatenate([[0.0], np.cumsum(0.5 * (outflow[1:] + outflow[:-1]) * dt)])
    assert volume - volume[0] == pytest.approx((Q1 + Q2) * t_eval - integrated, abs=1e-6)
