"""The extended Kalman filter: linearization by the model's sympy Jacobians, Joseph-form update.
"""

from __future__ import annotations

import numpy as np

from .. import _linalg as linalg
from .gaussian import GaussianFilter
from .strong_tracking import StrongTracking

__all__ = ["ExtendedKalmanFilter"]


class ExtendedKalmanFilter(GaussianFilter):
    """EKF with the model's sympy Jacobians (no finite differences).

    Parameters
    ----------
    model : DiscreteModel
    mean, covariance : initial estimate ``x_0|0`` (n,) and ``P_0|0`` (n, n)
    process_noise, measurement_noise : Q (n, n) and R (m, m)
    fading : StrongTracking, optional
        Strong tracking EKF (Zhou et al. 1990; Du et al. (n.d.), eqs. 7-12).

    Examples
    --------
    Estimate the resistance of the RLC circuit (true 12 ohm, nominal 10) from its
    current and capacitor voltage, the bond graph's state equations discretized
    with ``R`` augmented as a state:

    >>> from bondgraph import simulate
    >>> from bondgraph.library import rlc_circuit
    >>> from prognosis.statespace import discretize
    >>> bg = rlc_circuit()
    >>> model = discretize(bg.state_equations(), dt=1e-3, augment=["R"], method="rk4")
    >>> model.states, model.outputs
    (('p_L', 'q_C', 'R'), ('i', 'v_C'))
    >>> data = simulate(bg, (0.0, 0.1), {"V": 1.0}, parameters={"R": 12.0}, t_eval=np.linspace(0.0, 0.1, 101))
    >>> ekf = ExtendedKalmanFilter(model, [0.0, 0.0, 10.0], np.diag([0.0, 0.0, 4.0]),
    ...                            np.diag([1e-10, 1e-12, 1e-6]), np.diag([1e-6, 1e-6]))
    >>> for k in range(1, 101):
    ...     _ = ekf.step([data["i"][k], data["v_C"][k]], {"V": 1.0})
    >>> round(float(ekf.mean[2]), 1), bool(np.sqrt(ekf.covariance[2, 2]) < 0.1)
    (12.0, True)
    """

    def __init__(self, model, mean, covariance, process_noise, measurement_noise, *,
                 fading: StrongTracking | None = None):
        super().__init__(model, mean, covariance, process_noise, measurement_noise, fading)

    def predict(self, u=None) -> None:
        """Time update: ``x = f(x, u)`` and ``P = F P F^T + Q``, ``F = df/dx`` at the previous estimate.

        ``u``: the inputs over the step (see :meth:`~prognosis.statespace.DiscreteModel.input_vector`).
        """
        self._x, f = self.model.transition_with_jacobian(self._x, u)
        self._spread = linalg.symmetric(f @ self._p @ f.T)
        self._p = self._spread + self.process_noise
        self._predicted = True

    def _update(self, z, rows, u):
        r = linalg.block(self.measurement_noise, rows)
        h = self.model.measurement_jacobian(self._x, u)[rows]
        predicted = self.model.measure(self._x, u)[rows]
        residual = z - predicted
        fading = 1.0
        if self._predicted and self.fading is not None:
            fading = self._fade(residual, self._p, self._p @ h.T, h @ self._p @ h.T + r, r)
            self._p = fading * self._spread + self.process_noise
        pzz = linalg.symmetric(h @ self._p @ h.T + r)
        gain = linalg.solve(pzz, h @ self._p).T
        self._x = self._x + gain @ residual
        joseph = np.eye(self.model.n_states) - gain @ h
        self._p = linalg.symmetric(joseph @ self._p @ joseph.T + gain @ r @ gain.T)
        return residual, pzz, fading
