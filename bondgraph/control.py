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

__all__ = ["PIController"]


@dataclass
class PIController:
    """Proportional-integral controller with output saturation.

    ``v = kp * err + ki * z``, ``u = clip(v, lo, hi)`` with
    ``err = setpoint(t) - y[measured]``, and back-calculation anti-windup::

        dz/dt = err + (u - v) / (ki * tracking_time)

    which bleeds the integral while the output is saturated.  The tracking
    time defaults to the integral time ``kp / ki``.  Unlike freezing the
    integral (conditional integration), this right-hand side is continuous in
    the state, so adaptive ODE solvers do not chatter on the saturation edge.

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
    tracking_time: float | None = None
    n_states: int = 1

    def initial_state(self) -> np.ndarray:
        """Initial controller state: the integral ``z = 0``, shape (1,)."""
        return np.zeros(1)

    def error(self, t: float, y: dict) -> float:
        """Control error ``err = setpoint(t) - y[measured]`` at time ``t`` (a constant ``setpoint`` is used as is).

        ``y`` maps measured signal names (detector outputs) to their values.
        """
        reference = self.setpoint(t) if callable(self.setpoint) else self.setpoint
        return reference - y[self.measured]

    def _unsaturated(self, t, z, y) -> float:
        return self.kp * self.error(t, y) + self.ki * z[0]

    def output(self, t: float, z, y: dict) -> float:
        """The control signal; also vectorized over samples (``z`` of shape (1, n), ``y`` of arrays)."""
        u = self._unsaturated(t, z, y)
        if self.limits is not None:
            u = np.clip(u, self.limits[0], self.limits[1])
        return float(u) if np.ndim(u) == 0 else np.asarray(u, float)

    def derivative(self, t: float, z, y: dict) -> np.ndarray:
        """State derivative ``dz/dt``, shape (1,), at time ``t`` from the controller state ``z`` and measurements ``y``.

        ``err`` without ``limits`` or without integral action (``ki = 0``: nothing to bleed); otherwise
        ``err + (u - v) / (ki * tracking_time)`` (back-calculation anti-windup, ``v`` the unsaturated and ``u``
        the clipped output).  Vectorized over samples as :meth:`output` (then shape (1, n)).

        >>> pi = PIController("omega", setpoint=10.0, kp=0.5, ki=2.0, limits=(-1.0, 1.0))
        >>> pi.derivative(0.0, np.zeros((1, 2)), {"omega": np.array([9.5, 0.0])}).tolist()   # 2nd saturated
        [[0.5, 2.0]]
        """
        err = self.error(t, y)
        if self.limits is None or self.ki == 0:
            return np.array([err], dtype=float)
        v = self._unsaturated(t, z, y)
        u = np.clip(v, self.limits[0], self.limits[1])
        tracking = self.tracking_time if self.tracking_time is not None else self.kp / self.ki
        return np.array([err + (u - v) / (self.ki * tracking)], dtype=float)

    def __post_init__(self) -> None:
        if self.limits is not None and not self.limits[0] < self.limits[1]:
            raise ValueError(f"PIController on {self.measured!r}: limits must be (lo, hi) with lo < hi, "
                             f"got {self.limits}")
        if self.tracking_time is not None and not self.tracking_time > 0:
            raise ValueError(f"PIController on {self.measured!r}: tracking_time must be positive, "
                             f"got {self.tracking_time}")
