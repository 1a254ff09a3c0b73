"""Controllers that close a loop around a simulated bond graph.

A controller is an input with its own states.  It follows a small protocol
used by :func:`bondgraph.simulate`:

``n_states``
    number of internal states;
``initial_state()``
    their initial values;
``output(t, z, y)`` and ``derivative(t, z, y)``
    the input value and the state derivative, given the controller states
    ``z`` and the measured signals ``y`` (a dict of detector outputs).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass
class PIController:
    """Proportional-integral controller with output saturation.

    ``u = clip(kp * err + ki * z, lo, hi)``, ``dz/dt = err`` with
    ``err = setpoint(t) - y[measured]``.  Anti-windup by conditional
    integration: while the output is saturated and the error would push it
    further, the integral is frozen.

    Examples
    --------
    >>> pi = PIController("omega", setpoint=10.0, kp=0.5, ki=2.0, limits=(-12.0, 12.0))
    >>> pi.output(0.0, pi.initial_state(), {"omega": 0.0})
    5.0
    """

    measured: str
    setpoint: float | Callable[[float], float]
    kp: float
    ki: float
    limits: tuple[float, float] | None = None
    n_states: int = 1

    def initial_state(self) -> np.ndarray:
        return np.zeros(1)

    def error(self, t: float, y: dict) -> float:
        reference = self.setpoint(t) if callable(self.setpoint) else self.setpoint
        return reference - y[self.measured]

    def _unsaturated(self, t, z, y) -> float:
        return self.kp * self.error(t, y) + self.ki * z[0]

    def output(self, t: float, z, y: dict) -> float:
        u = self._unsaturated(t, z, y)
        if self.limits is not None:
            u = min(max(u, self.limits[0]), self.limits[1])
        return u

    def derivative(self, t: float, z, y: dict) -> np.ndarray:
        err = self.error(t, y)
        if self.limits is not None:
            u = self._unsaturated(t, z, y)
            if (u >= self.limits[1] and err > 0) or (u <= self.limits[0] and err < 0):
                return np.zeros(1)
        return np.array([err])
