"""Kalman filters for joint state-parameter estimation, with strong tracking.

Every filter here, and :class:`prognosis.statespace.bootstrap.BootstrapParticleFilter`,
has one interface on a :class:`prognosis.statespace.DiscreteModel`:

* ``predict(u)``: time update with the inputs of the step;
* ``update(z, u=None)``: measurement update, returns an :class:`Innovation`
  (NaN entries of ``z`` are skipped, an all-NaN ``z`` skips the update);
* ``step(z, u)``: both; ``mean`` and ``covariance``: the current estimate;
* ``copy()``: an independent filter, for look-ahead runs.

Filters
-------
:class:`ExtendedKalmanFilter`
    Linearization by the model's sympy Jacobians; Joseph-form update.
:class:`UnscentedKalmanFilter`
    Scaled unscented transform (alpha, beta, kappa), covariance form.
:class:`CubatureKalmanFilter`
    Square-root cubature Kalman filter (Arasaratnam and Haykin 2009; Du et al. (n.d.),
    eqs. 21-26, 37-46): ``2n`` points ``x + S xi_i``, ``xi_i = +-sqrt(n) e_i``,
    equal weights, and the covariance carried as a lower-triangular factor
    ``S`` (``P = S S^T``) updated by QR triangularization only, so that it
    stays positive semi-definite by construction.

Strong tracking (Du et al. (n.d.), section 3; Zhou et al. 1990)
---------------------------------------------------------------
Pass ``fading=StrongTracking()`` to any of them.  At the measurement update
the predicted covariance's propagated part is inflated by a suboptimal fading
factor ``lambda_k >= 1`` (eq. 7, 36)::

    P_{k|k-1} = lambda_k (P*_{k|k-1} - Q_{k-1}) + Q_{k-1},
    lambda_k = max(1, tr N_k / tr M_k),
    N_k = V_k - H Q H^T - beta R_k,          M_k = H (P* - Q) H^T,
    V_k = eps_1 eps_1^T (k = 1),  (rho V_{k-1} + eps_k eps_k^T) / (1 + rho),

so that the innovation sequence stays orthogonal when the model is wrong
(a drifting parameter whose law is unknown).  The derivative-free form
(eqs. 17-20, 27-35) replaces ``H`` by ``P_xz^T P*^{-1}`` (eq. 17) from the
sigma or cubature points drawn from ``P*``; the EKF uses its Jacobian.

Note on eq. (35): substituting eq. (20) it writes
``M_k = Z Z^T - V_k + N_k``, which drops the ``+ R_k`` that ``P_zz`` carries in
eq. (32); eq. (20) itself gives ``M_k = Z Z^T - H Q H^T = H (P* - Q) H^T``,
which is what is computed here (with the printed form ``M`` can turn negative
when the measurement noise dominates).

Example
-------
>>> import sympy as sp
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

import copy as _copy
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import cho_solve

from .. import _linalg as linalg

__all__ = [
    "CubatureKalmanFilter", "ExtendedKalmanFilter", "FilterWarning", "Innovation", "StrongTracking",
    "UnscentedKalmanFilter",
]


class FilterWarning(RuntimeWarning):
    """A covariance had to be repaired, or a measurement was rejected as non-finite."""


@dataclass
class Innovation:
    """What one measurement update saw.

    Attributes
    ----------
    residual : ndarray (m,)
        ``z_k - z_hat_{k|k-1}`` over the measured entries (NaN where skipped).
    covariance : ndarray (m, m)
        Innovation covariance ``P_zz`` (rows and columns of skipped entries NaN).
    nis : float
        Normalized innovation squared ``eps^T P_zz^{-1} eps`` (chi-square with as
        many degrees of freedom as measured entries when the filter is consistent).
    fading : float
        Strong-tracking factor ``lambda_k`` applied (1 without strong tracking).

    Examples
    --------
    Returned by ``update`` and ``step`` of every filter:

    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import discretize
    >>> x = sp.Symbol("x")
    >>> level = SimpleNamespace(states=[x], rhs=[0 * x], inputs=[], outputs={"y": x}, parameters={})
    >>> ekf = ExtendedKalmanFilter(discretize(level, dt=1.0), [0.0], [[1.0]], [[0.0]], [[1.0]])
    >>> innovation = ekf.update([2.0])   # residual 2, covariance P + R = 2
    >>> innovation.residual.tolist(), innovation.covariance.tolist(), innovation.nis, innovation.fading
    ([2.0], [[2.0]], 2.0, 1.0)
    >>> ekf.update([np.nan]).nis   # a missing measurement: no update
    nan
    """

    residual: np.ndarray
    covariance: np.ndarray
    nis: float
    fading: float = 1.0


@dataclass
class StrongTracking:
    """Suboptimal fading factor of the strong tracking filter (Du et al. (n.d.), eqs. 7-10, 17-20).

    Parameters
    ----------
    forgetting : float
        ``rho`` of eq. (10), in (0, 1]: weight of the past in ``V_k``.  The paper
        does not give it; 0.95 is the value of Zhou et al.
    softening : float
        ``beta >= 1`` multiplying ``R_k`` in ``N_k`` (1 in the paper); a larger value
        makes the filter fade less on measurement noise.
    max_factor : float
        Upper bound on ``lambda_k`` (no bound by default).

    Examples
    --------
    A sudden change of the decay rate ``a`` from 0.1 to 0.2: a filter with a small
    process noise on ``a`` follows slowly, with strong tracking it follows at once.

    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import discretize
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> model = discretize(decay, dt=1.0, augment=["a"])
    >>> def run(fading):
    ...     ekf = ExtendedKalmanFilter(model, [1.0, 0.1], np.diag([1e-6, 1e-6]), np.diag([1e-8, 1e-8]), [[1e-6]],
    ...                                fading=fading)
    ...     truth, factors = 1.0, []
    ...     for k in range(40):
    ...         truth *= 0.9 if k < 20 else 0.8
    ...         factors.append(ekf.step([truth]).fading)
    ...     return round(float(ekf.mean[1]), 2), max(factors) > 1.0
    >>> run(None), run(StrongTracking())
    ((0.12, False), (0.2, True))

    The factor itself, for an innovation of 3 whose predicted variance is 2 (``H = 1``, ``Q = 0``, ``R = 1``):
    ``lambda = (9 - 1) / (2 - 1)``.

    >>> StrongTracking().factor(np.array([3.0]), np.eye(1), np.eye(1), np.array([[2.0]]), np.zeros((1, 1)), np.eye(1))
    8.0
    """

    forgetting: float = 0.95
    softening: float = 1.0
    max_factor: float = np.inf
    _v: np.ndarray = field(default=None, repr=False)

    def __post_init__(self):
        if not 0.0 < self.forgetting <= 1.0:
            raise ValueError(f"forgetting (rho) must be in (0, 1], got {self.forgetting}")
        if self.softening < 1.0:
            raise ValueError(f"softening (beta) must be >= 1, got {self.softening}")
        if not self.max_factor >= 1.0:
            raise ValueError(f"max_factor must be >= 1, got {self.max_factor}")

    def reset(self) -> None:
        """Forget ``V_k`` (eq. 10); the filters call this at their start and in ``reinitialize``."""
        self._v = None

    def factor(self, residual: np.ndarray, predicted: np.ndarray, cross: np.ndarray, innovation: np.ndarray,
               process: np.ndarray, noise: np.ndarray) -> float:
        """``lambda_k`` from the innovation ``eps`` (m,), ``P*`` (n, n), ``P_xz`` (n, m), ``P_zz`` (m, m), Q, R."""
        outer = np.outer(residual, residual)
        rho = self.forgetting
        self._v = outer if self._v is None or self._v.shape != outer.shape else (rho * self._v + outer) / (1 + rho)
        h = linalg.solve(predicted, cross).T  # eq. 17: H = P_xz^T P*^{-1}
        hqh = h @ process @ h.T
        n = self._v - hqh - self.softening * noise
        m = innovation - noise - hqh  # eq. 20: M = H (P* - Q) H^T
        trace_m = float(np.trace(m))
        if not trace_m > 0.0:
            return 1.0
        return float(np.clip(np.trace(n) / trace_m, 1.0, self.max_factor))


class _GaussianFilter:
    """Shared plumbing: validation, NaN handling, the public interface."""

    def __init__(self, model, mean, covariance, process_noise, measurement_noise, fading: StrongTracking | None):
        n = model.n_states
        self.model = model
        self._x = linalg.state_vector(mean, n, "mean", model.states)
        self.process_noise, self.measurement_noise, self._sqrt_q = noises(model, process_noise, measurement_noise)
        self.fading = _copy.deepcopy(fading)
        if self.fading is not None:
            self.fading.reset()
        self._predicted = False
        self._set_covariance(linalg.covariance_matrix(covariance, n, "covariance (P0)", model.states))

    @property
    def mean(self) -> np.ndarray:
        return self._x.copy()

    @property
    def covariance(self) -> np.ndarray:
        return self._p.copy()

    def _set_covariance(self, p: np.ndarray) -> None:
        """Full-form covariance (EKF, UKF); the square-root CKF overrides both."""
        self._p = linalg.symmetric(p)

    def reinitialize(self, mean=None, covariance=None) -> None:
        """Restart from a new estimate and/or covariance ``P_0`` (e.g. wider bounds after a model change).

        Strong tracking, if any, starts afresh.  Rodriguez Obando et al. (2021), section 6.1, restart their EKF
        this way when the estimated ``m`` stops being consistent with ``dm/dt = 0``.
        """
        n = self.model.n_states
        if mean is not None:
            self._x = linalg.state_vector(mean, n, "mean", self.model.states)
        if covariance is not None:
            self._set_covariance(linalg.covariance_matrix(covariance, n, "covariance (P0)", self.model.states))
        if self.fading is not None:
            self.fading.reset()
        self._predicted = False

    def step(self, z, u=None) -> Innovation:
        """``predict(u)`` then ``update(z, u)``."""
        self.predict(u)
        return self.update(z, u)

    def copy(self):
        """An independent copy (for a look-ahead on forecast measurements)."""
        return _copy.deepcopy(self)

    def update(self, z, u=None) -> Innovation:
        z, rows = measured_rows(z, self.model)
        if not rows.any():
            self._predicted = False
            return innovation(rows)
        residual, pzz, fading = self._update(z[rows], rows, u)
        self._predicted = False
        return innovation(rows, residual, pzz, fading)

    def _measure(self, points: np.ndarray, rows: np.ndarray, u) -> np.ndarray:
        return self.model.measure(points, u)[rows]

    def _fade(self, residual, predicted, cross, innovation, noise) -> float:
        if self.fading is None:
            return 1.0
        return self.fading.factor(residual, predicted, cross, innovation, self.process_noise, noise)


class ExtendedKalmanFilter(_GaussianFilter):
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


class UnscentedKalmanFilter(_GaussianFilter):
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
            raise ValueError(f"alpha must be positive, got {alpha}")
        spread = alpha ** 2 * (n + kappa) - n
        if not n + spread > 0:
            raise ValueError(f"n + lambda = alpha^2 (n + kappa) must be positive, got {n + spread}")
        self._scale = np.sqrt(n + spread)
        self._wm = np.full(2 * n + 1, 0.5 / (n + spread))
        self._wm[0] = spread / (n + spread)
        self._wc = self._wm.copy()
        self._wc[0] += 1.0 - alpha ** 2 + beta
        super().__init__(model, mean, covariance, process_noise, measurement_noise, fading)

    def _sigma_points(self, p: np.ndarray) -> np.ndarray:
        root = _cholesky_or_repair(p, "UKF covariance")
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


class CubatureKalmanFilter(_GaussianFilter):
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


def noises(model, process_noise, measurement_noise) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validated ``Q`` (n, n) and ``R`` (m, m) of ``model`` (R positive definite), and a square root of Q."""
    q = linalg.covariance_matrix(process_noise, model.n_states, "process_noise (Q)", model.states)
    r = linalg.covariance_matrix(measurement_noise, model.n_outputs, "measurement_noise (R)", model.outputs)
    if np.any(np.linalg.eigvalsh(r) <= 0):
        raise ValueError("measurement_noise (R) must be positive definite")
    return q, r, linalg.psd_sqrt(q)


def measured_rows(z, model) -> tuple[np.ndarray, np.ndarray]:
    """``z`` as a vector of the model's outputs, and the mask of its finite (measured) entries."""
    z = np.asarray(z, float).reshape(-1)
    if z.shape != (model.n_outputs,):
        raise ValueError(f"z: expected {model.n_outputs} values for {list(model.outputs)}, got shape {z.shape}")
    return z, np.isfinite(z)


def innovation(rows: np.ndarray, residual=None, covariance=None, fading: float = 1.0) -> Innovation:
    """An :class:`Innovation` over all outputs from the one over the measured ``rows`` (NaN elsewhere)."""
    m = rows.size
    full_r = np.full(m, np.nan)
    if residual is None:
        return Innovation(full_r, np.full((m, m), np.nan), np.nan)
    full_r[rows] = residual
    if rows.all():
        full_p = np.array(covariance, float)
    else:
        full_p = np.full((m, m), np.nan)
        full_p[np.ix_(rows, rows)] = covariance
    return Innovation(full_r, full_p, float(residual @ linalg.solve(covariance, residual)), fading)


def _cholesky_or_repair(p: np.ndarray, what: str) -> np.ndarray:
    try:
        return np.linalg.cholesky(p)
    except np.linalg.LinAlgError:
        values, vectors = np.linalg.eigh(p)
        floor = max(float(values.max()), 1e-300) * 1e-12
        warnings.warn(f"{what} was not positive definite (smallest eigenvalue {values.min():.3g}); "
                      f"eigenvalues clipped at {floor:.3g}", FilterWarning, stacklevel=4)
        return np.linalg.cholesky((vectors * np.maximum(values, floor)) @ vectors.T)


