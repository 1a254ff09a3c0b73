"""The square-root cubature Kalman filter (Arasaratnam and Haykin 2009; Du et al. (n.d.), eqs. 21-26, 37-46).

``2n`` points ``x + S xi_i``, ``xi_i = +-sqrt(n) e_i``, equal weights, and the covariance carried as a
lower-triangular factor ``S`` (``P = S S^T``) updated by QR triangularization only, so that it stays
positive semi-definite by construction.

Example
-------
>>> import numpy as np, sympy as sp
>>> from types import SimpleNamespace
>>> from prognosis.statespace import discretize
>>> x, a = sp.symbols("x a")
>>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
>>> model = discretize(decay, dt=1.0, augment=["a"])
>>> ckf = CubatureKalmanFilter(model, [1.0, 0.2], np.diag([1e-4, 1e-2]), np.diag([1e-8, 1e-6]), [[1e-6]],
...                            fading=StrongTracking())
>>> truth = 1.0
>>> for k in range(60):
...     truth *= 0.9
...     _ = ckf.step([truth])
>>> round(float(ckf.mean[1]), 3)
0.1
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import cho_solve

from .. import _linalg as linalg
from .gaussian import GaussianFilter
from .strong_tracking import StrongTracking

__all__ = ["CubatureKalmanFilter"]


class CubatureKalmanFilter(GaussianFilter):
    """Square-root cubature Kalman filter (Du et al. (n.d.), eqs. 21-46); with ``fading``, the STSCKF.

    The estimate's covariance is held as ``S`` (lower triangular, non-negative
    diagonal, ``P = S S^T``) and only ever rebuilt by :func:`tria`, so it stays
    symmetric positive semi-definite whatever the rounding.

    Parameters
    ----------
    model : DiscreteModel
    mean, covariance : initial estimate ``x_0|0`` (n,) and ``P_0|0`` (n, n)
    process_noise, measurement_noise : Q (n, n) and R (m, m)
    fading : StrongTracking, optional
        Strong tracking SCKF (STSCKF, Du et al. (n.d.)).

    Examples
    --------
    Estimate the rate ``a`` of ``dx/dt = -a x`` (true 0.1, initial guess 0.2):

    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import discretize
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> model = discretize(decay, dt=1.0, augment=["a"])
    >>> ckf = CubatureKalmanFilter(model, [1.0, 0.2], np.diag([1e-4, 1e-2]), np.diag([1e-8, 1e-6]), [[1e-6]])
    >>> for k in range(1, 31):
    ...     _ = ckf.step([0.9 ** k])
    >>> round(float(ckf.mean[1]), 3)
    0.1
    >>> s = ckf.sqrt_covariance   # lower triangular, P = S S^T
    >>> bool(np.allclose(s @ s.T, ckf.covariance)), bool(s[0, 1] == 0.0), bool(np.all(np.diag(s) >= 0))
    (True, True, True)
    """

    def __init__(self, model, mean, covariance, process_noise, measurement_noise, *,
                 fading: StrongTracking | None = None):
        n = model.n_states
        self._xi = np.sqrt(n) * np.hstack([np.eye(n), -np.eye(n)])  # eq. 22 (m = 2n points)
        super().__init__(model, mean, covariance, process_noise, measurement_noise, fading)
        self._sqrt_r = np.linalg.cholesky(self.measurement_noise)

    @property
    def covariance(self) -> np.ndarray:
        """Estimate covariance ``P = S S^T``, shape (n, n), from the square-root factor ``S``."""
        return self._s @ self._s.T

    @property
    def sqrt_covariance(self) -> np.ndarray:
        """The lower-triangular factor ``S`` of ``P = S S^T``."""
        return self._s.copy()

    def _set_covariance(self, p: np.ndarray) -> None:
        self._s = linalg.tria(linalg.psd_sqrt(p))

    def _points(self, s: np.ndarray) -> np.ndarray:
        return self._x[:, None] + s @ self._xi  # eq. 21, 27, 37

    def predict(self, u=None) -> None:
        """Time update (eqs. 23-26): the ``2n`` cubature points ``x + S xi_i`` go through ``f``.

        ``x`` becomes their mean and ``S = linalg.tria([chi, sqrt(Q)])``, with ``chi`` their deviations from that mean
        divided by ``sqrt(2n)``.

        ``u``: the inputs over the step (see :meth:`~prognosis.statespace.DiscreteModel.input_vector`).
        """
        propagated = self.model.transition(self._points(self._s), u)  # eq. 23
        self._x = propagated.mean(axis=1)  # eq. 24
        self._chi = (propagated - self._x[:, None]) / np.sqrt(propagated.shape[1])  # eq. 26
        self._s = linalg.tria(np.hstack([self._chi, self._sqrt_q]))  # eq. 25
        self._predicted = True

    def _transform(self, rows, u):
        points = self._points(self._s)
        eta = self._measure(points, rows, u)  # eq. 28, 38
        z_mean = eta.mean(axis=1)  # eq. 29, 39
        scale = np.sqrt(points.shape[1])
        z_dev = (eta - z_mean[:, None]) / scale  # eq. 34, 41
        x_dev = (points - self._x[:, None]) / scale  # eq. 33, 43
        return z_mean, z_dev, x_dev

    def _update(self, z, rows, u):
        sqrt_r = np.linalg.cholesky(linalg.block(self.measurement_noise, rows)) if not rows.all() else self._sqrt_r
        z_mean, z_dev, x_dev = self._transform(rows, u)
        fading = 1.0
        if self._predicted and self.fading is not None:
            r = sqrt_r @ sqrt_r.T
            p_star = self._s @ self._s.T  # eq. 30
            fading = self._fade(z - z_mean, p_star, x_dev @ z_dev.T, z_dev @ z_dev.T + r, r)  # eqs. 31-35
            if fading > 1.0:
                self._s = linalg.tria(np.hstack([np.sqrt(fading) * self._chi, self._sqrt_q]))  # eq. 36
                z_mean, z_dev, x_dev = self._transform(rows, u)
        s_zz = linalg.tria(np.hstack([z_dev, sqrt_r]))  # eq. 40
        pxz = x_dev @ z_dev.T  # eq. 42
        # eq. 44: K = P_xz S_zz^-T S_zz^-1 by the two triangular solves of LAPACK potrs (scipy's solve_triangular
        # costs milliseconds per 3 x 3 call when other processes load the cores; this does not)
        gain = cho_solve((s_zz, True), pxz.T).T
        residual = z - z_mean
        self._x = self._x + gain @ residual  # eq. 45
        self._s = linalg.tria(np.hstack([x_dev - gain @ z_dev, gain @ sqrt_r]))  # eq. 46
        return residual, s_zz @ s_zz.T, fading
