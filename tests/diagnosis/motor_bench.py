"""Healthy DC-motor bench runs simulated from the motor's two equations with scipy's solve_ivp (never the
library's own simulate), for the tests of calibration and its validation."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from diagnosis import add_noise, as_record

__all__ = ["DATASHEET", "NOISE", "TRUE", "motor_record", "voltage"]

#: The machine's parameters.
TRUE = {"R_a": 1.23, "L_a": 1.34e-3, "k_m": 3.89e-2, "J": 1e-4, "b": 1e-4}
#: A datasheet 30 % off in the mechanical parameters and 20 % in the winding's resistance.
DATASHEET = {**TRUE, "R_a": 1.23 * 0.8, "J": 1e-4 * 1.3, "b": 1e-4 * 0.7}
#: The sensors' noise (standard deviations).
NOISE = {"i": 0.01, "omega": 0.2}


def voltage(t, volts):
    """Steps, then a sine: the electrical and the mechanical dynamics both excited."""
    return volts * ((t >= 0.05) - 0.5 * (t >= 0.6)) + 0.3 * volts * np.sin(9 * t) * (t >= 1.0)


def motor_record(volts: float, seed: int, samples: int = 2001):
    """L di/dt = U - R_a i - k_m w and J dw/dt = k_m i - b w over 2 s, integrated here, with noisy sensors."""
    p = TRUE

    def rhs(t, x):
        i, w = x
        return [(voltage(t, volts) - p["R_a"] * i - p["k_m"] * w) / p["L_a"], (p["k_m"] * i - p["b"] * w) / p["J"]]

    t = np.linspace(0.0, 2.0, samples)
    sol = solve_ivp(rhs, (0.0, 2.0), [0.0, 0.0], t_eval=t, method="LSODA", rtol=1e-10, atol=1e-12, max_step=1e-3)
    return add_noise(as_record({"t": t, "U": voltage(t, volts), "i": sol.y[0], "omega": sol.y[1]}), NOISE, seed=seed)
