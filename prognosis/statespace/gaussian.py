"""Kalman filters for joint state-parameter estimation, with strong tracking.

Every filter here, and :class:`prognosis.statespace.bootstrap.BootstrapParticleFilter`,
has one interface on a :class:`prognosis.statespace.DiscreteModel`:

* ``predict(u)``: time update with the inputs of the step;
* ``update(z, u=None)``: measurement update, returns an :class:`Innovation`
  (NaN entries of ``z`` are skipped, an all-NaN ``z`` skips the update);
* ``step(z, u)``: both; ``mean`` and ``covariance``: the current estimate;
* ``copy()``: an independent filter, for look-ahead runs.

This module holds what they share: the base class :class:`GaussianFilter`, the
:class:`Innovation` an update returns, and the :class:`FilterWarning` a repaired covariance raises.
"""

from __future__ import annotations

import copy as _copy
import warnings
from dataclasses import dataclass

import numpy as np

from bondgraph.errors import PHMWarning

from .. import _linalg as linalg
from .strong_tracking import StrongTracking
from ..errors import PrognosisError

__all__ = [
    "FilterWarning", "GaussianFilter", "Innovation", "cholesky_or_repair", "innovation", "measured_rows",
    "noises",
]


class FilterWarning(PHMWarning, RuntimeWarning):
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
    >>> from prognosis.statespace import ExtendedKalmanFilter, discretize
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

class GaussianFilter:
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

def noises(model, process_noise, measurement_noise) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validated ``Q`` (n, n) and ``R`` (m, m) of ``model`` (R positive definite), and a square root of Q."""
    q = linalg.covariance_matrix(process_noise, model.n_states, "process_noise (Q)", model.states)
    r = linalg.covariance_matrix(measurement_noise, model.n_outputs, "measurement_noise (R)", model.outputs)
    if np.any(np.linalg.eigvalsh(r) <= 0):
        raise PrognosisError("measurement_noise (R) must be positive definite")
    return q, r, linalg.psd_sqrt(q)

def measured_rows(z, model) -> tuple[np.ndarray, np.ndarray]:
    """``z`` as a vector of the model's outputs, and the mask of its finite (measured) entries."""
    z = np.asarray(z, float).reshape(-1)
    if z.shape != (model.n_outputs,):
        raise PrognosisError(f"z: expected {model.n_outputs} values for {list(model.outputs)}, got shape {z.shape}")
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

def cholesky_or_repair(p: np.ndarray, what: str) -> np.ndarray:
    """The Cholesky factor of ``p``, or of ``p`` with its eigenvalues clipped at 1e-12 of the largest, with a
    :class:`FilterWarning` naming ``what`` (a covariance that round-off made indefinite)."""
    try:
        return np.linalg.cholesky(p)
    except np.linalg.LinAlgError:
        values, vectors = np.linalg.eigh(p)
        floor = max(float(values.max()), 1e-300) * 1e-12
        warnings.warn(f"{what} was not positive definite (smallest eigenvalue {values.min():.3g}); "
                      f"eigenvalues clipped at {floor:.3g}", FilterWarning, stacklevel=4)
        return np.linalg.cholesky((vectors * np.maximum(values, floor)) @ vectors.T)
