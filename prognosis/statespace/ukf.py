"""The unscented Kalman filter: scaled unscented transform (alpha, beta, kappa), covariance form.
"""

from __future__ import annotations

import numpy as np

from .. import _linalg as linalg
from .gaussian import GaussianFilter, cholesky_or_repair
from .strong_tracking import StrongTracking
from ..errors import PrognosisError

__all__ = ["UnscentedKalmanFilter"]


class UnscentedKalmanFilter(GaussianFilter):
    """UKF with the scaled unscented transform (Julier 2002; Wan and van der Merwe 2000).

    ``2n + 1`` sigma points ``x, x +- sqrt(n + l) S_i`` with ``l = alpha^2 (n + kappa) - n``,
    mean weights ``l / (n + l)`` and ``1 / (2 (n + l))``, covariance weight of the centre
    ``l / (n + l) + 1 - alpha^2 + beta``.  Defaults are Wan and van der Merwe's
    ``alpha = 1e-3, beta = 2, kappa = 0``.  The covariance is carried in full form: when
    rounding leaves it indefinite, it is repaired by clipping its eigenvalues and a
    :class:`FilterWarning` says so.

    Parameters
    ----------
    model : DiscreteModel
    mean, covariance : initial estimate ``x_0|0`` (n,) and ``P_0|0`` (n, n)
    process_noise, measurement_noise : Q (n, n) and R (m, m)
    alpha, beta, kappa : float
        Parameters of the scaled unscented transform.
    fading : StrongTracking, optional

    Examples
    --------
    Estimate the rate ``a`` of ``dx/dt = -a x`` (true 0.1, initial guess 0.2):

    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import discretize
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> model = discretize(decay, dt=1.0, augment=["a"])
    >>> ukf = UnscentedKalmanFilter(model, [1.0, 0.2], np.diag([1e-4, 1e-2]), np.diag([1e-8, 1e-6]), [[1e-6]])
    >>> for k in range(1, 31):
    ...     innovation = ukf.step([0.9 ** k])
    >>> round(float(ukf.mean[1]), 3), ukf.covariance.shape, bool(innovation.nis < 9.0)
    (0.1, (2, 2), True)
    """

    def __init__(self, model, mean, covariance, process_noise, measurement_noise, *,
                 alpha: float = 1e-3, beta: float = 2.0, kappa: float = 0.0,
                 fading: StrongTracking | None = None):
        n = model.n_states
        if not alpha > 0:
            raise PrognosisError(f"alpha must be positive, got {alpha}")
        spread = alpha ** 2 * (n + kappa) - n
        if not n + spread > 0:
            raise PrognosisError(f"n + lambda = alpha^2 (n + kappa) must be positive, got {n + spread}")
        self._scale = np.sqrt(n + spread)
        self._wm = np.full(2 * n + 1, 0.5 / (n + spread))
        self._wm[0] = spread / (n + spread)
        self._wc = self._wm.copy()
        self._wc[0] += 1.0 - alpha ** 2 + beta
        super().__init__(model, mean, covariance, process_noise, measurement_noise, fading)

    def _sigma_points(self, p: np.ndarray) -> np.ndarray:
        root = cholesky_or_repair(p, "UKF covariance")
        offsets = self._scale * root
        return self._x[:, None] + np.hstack([np.zeros((len(self._x), 1)), offsets, -offsets])

    def _moments(self, points: np.ndarray):
        mean = points @ self._wm
        deviation = points - mean[:, None]
        return mean, deviation

    def predict(self, u=None) -> None:
        """Time update: the ``2n + 1`` sigma points of the estimate go through ``f``.

        ``x`` becomes their weighted mean and ``P`` their weighted spread plus ``Q``.

        ``u``: the inputs over the step (see :meth:`~prognosis.statespace.DiscreteModel.input_vector`).
        """
        propagated = self.model.transition(self._sigma_points(self._p), u)
        self._x, deviation = self._moments(propagated)
        self._spread = linalg.symmetric((deviation * self._wc) @ deviation.T)
        self._p = self._spread + self.process_noise
        self._predicted = True

    def _transform(self, rows, u, r):
        points = self._sigma_points(self._p)
        z_points = self._measure(points, rows, u)
        z_mean, z_dev = self._moments(z_points)
        x_dev = points - self._x[:, None]
        pzz = linalg.symmetric((z_dev * self._wc) @ z_dev.T + r)
        pxz = (x_dev * self._wc) @ z_dev.T
        return z_mean, pzz, pxz

    def _update(self, z, rows, u):
        r = linalg.block(self.measurement_noise, rows)
        z_mean, pzz, pxz = self._transform(rows, u, r)
        fading = 1.0
        if self._predicted and self.fading is not None:
            fading = self._fade(z - z_mean, self._p, pxz, pzz, r)
            if fading > 1.0:
                self._p = fading * self._spread + self.process_noise
                z_mean, pzz, pxz = self._transform(rows, u, r)
        residual = z - z_mean
        gain = linalg.solve(pzz, pxz.T).T
        self._x = self._x + gain @ residual
        self._p = linalg.symmetric(self._p - gain @ pzz @ gain.T)
        return residual, pzz, fading
