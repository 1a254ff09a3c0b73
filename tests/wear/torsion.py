"""The torsion bar's mechanical part under a PI speed loop, written from the physics (not the library's simulate).

Motor shaft (J_m, friction f_m) -> belt of ratio k_belt -> motor disk (J_Md, friction b_Md, rigidly on the
belt) -> torsion spring (k_s, damping b_s) -> load disk (J_Ld, friction b_Ld):

    (J_m + J_Md / k^2) dw_m/dt = tau - f_m w_m - (b_Md w_m / k + T_s) / k
    J_Ld dw_Ld/dt = T_s - b_Ld w_Ld,       T_s = k_s phi + b_s (w_m / k - w_Ld)
    dphi/dt = w_m / k - w_Ld

with the motor torque tau from a digital PI loop on w_m (anti-windup: the integral stops while the
torque is saturated).  The parameters may move with time (a wear law); the record holds the measured torque and
speeds with Gaussian noise, and the true parameter trajectory.  Values: Jha et al. (2016), Table VI.

>>> run = simulate({}, t_end=2.0, dt=0.01, noise={}, seed=0)
>>> sorted(run), bool(abs(run["omega_m"][-1] - setpoint(2.0)) < 0.5)   # the loop tracks the set-point
(['omega_Ld', 'omega_m', 't', 'tau_m'], True)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from scipy.linalg import expm

from bondgraph.library import TORSION_BAR

NOMINAL = {name: value for name, (value, _) in TORSION_BAR.items()}
SETPOINT = 112.5              # rad/s on the motor shaft (30 rad/s on the disk)
WAVE = 0.1                    # the set-point swings by this share, so that the inertias show
PERIOD = 8.0                  # s, period of the swing
KP, KI = 2e-3, 2e-2           # N.m/(rad/s), N.m/rad: ours (the paper gives none)
TAU_MAX = NOMINAL["k_m"] * 12.0 / NOMINAL["R_a"]   # N.m: 12 V across the armature at stall
NOISE = {"omega_m": 0.01, "omega_Ld": 0.01, "tau_m": 0.01}   # rad/s, rad/s, N.m (Jha et al. (2016), 6.3)


def setpoint(t):
    return SETPOINT * (1.0 + WAVE * np.sin(2 * np.pi * np.asarray(t, float) / PERIOD))


def simulate(parameters: Mapping[str, float | Callable], *, t_end: float, dt: float, noise: Mapping,
             seed: int) -> dict:
    """Columns ``t``, ``tau_m``, ``omega_m``, ``omega_Ld``; ``parameters``: name -> value or ``theta(t)``.

    The loop is digital, as on a real drive: the torque is computed from the speed at each sample and
    held until the next (zero-order hold); between samples the mechanics is linear, so each interval is
    integrated exactly by the matrix exponential, with the parameters at the interval's middle (they
    move by a few millionths of their value in one sample).
    """
    value = {name: parameters.get(name, NOMINAL[name]) for name in NOMINAL}

    def at(name, t):
        v = value[name]
        return float(v(t)) if callable(v) else float(v)

    t = np.round(np.arange(0.0, t_end + dt / 2, dt) / dt) * dt
    x = _steady_state()
    z = x[3]
    x = x[:3]
    states, torques = np.empty((t.size, 3)), np.empty(t.size)
    for k, tk in enumerate(t):
        error = float(setpoint(tk)) - x[0]
        demand = KP * error + KI * z
        tau = float(np.clip(demand, -TAU_MAX, TAU_MAX))
        if abs(demand) < TAU_MAX or np.sign(error) != np.sign(demand):   # anti-windup
            z += error * dt
        states[k], torques[k] = x, tau
        x = _step(x, tau, {name: at(name, tk + dt / 2) for name in NOMINAL}, dt)
    rng = np.random.default_rng(seed)
    columns = {"t": t, "tau_m": torques, "omega_m": states[:, 0], "omega_Ld": states[:, 1]}
    for name, std in noise.items():
        columns[name] = columns[name] + rng.normal(0.0, std, t.size)
    return columns


def _step(x: np.ndarray, tau: float, p: Mapping, dt: float) -> np.ndarray:
    """The state ``(w_m, w_Ld, phi)`` one sample later under the held torque ``tau`` (exact for the interval)."""
    k = p["k_belt"]
    inertia = p["J_m"] + p["J_Md"] / k**2
    a = np.array([[-(p["f_m"] + (p["b_Md"] + p["b_s"]) / k**2) / inertia, p["b_s"] / (k * inertia),
                   -p["k_s"] / (k * inertia), 1.0 / inertia],
                  [p["b_s"] / (k * p["J_Ld"]), -(p["b_s"] + p["b_Ld"]) / p["J_Ld"], p["k_s"] / p["J_Ld"], 0.0],
                  [1.0 / k, -1.0, 0.0, 0.0],
                  [0.0, 0.0, 0.0, 0.0]])
    return (expm(a * dt) @ np.append(x, tau))[:3]


def _steady_state() -> np.ndarray:
    """``(w_m, w_Ld, phi, PI integral)`` at the set-point with nominal parameters: the record starts settled."""
    w0 = SETPOINT
    k = NOMINAL["k_belt"]
    losses = NOMINAL["f_m"] * w0 + (NOMINAL["b_Md"] + NOMINAL["b_Ld"]) * w0 / k**2
    return np.array([w0, w0 / k, NOMINAL["b_Ld"] * w0 / k / NOMINAL["k_s"], losses / KI])
