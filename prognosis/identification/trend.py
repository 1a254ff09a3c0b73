"""Fault trend from an identified model and prediction of the feature under a known future load.

A fault progresses when the spectral radius of ``A`` stays above one (Gasperin et al. (2011),
section 5.1); the feature is then predicted with the identified model (section 5.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.stats import norm

from .data import check_future_inputs
from .linear_gaussian import LinearGaussianModel
from ..errors import PrognosisError

__all__ = ["FeaturePrediction", "detect_trend", "fault_trend", "predict_feature"]


def fault_trend(model: LinearGaussianModel, margin: float = 0.0) -> bool:
    """Whether the fault is progressing: ``rho(A) > 1 + margin`` (Gasperin et al. (2011), section 5.1).

    A stable ``A`` means the feature settles for a constant load (the fault stays the same size); an
    eigenvalue outside the unit circle means it grows even at constant load.

    Example
    -------
    >>> grow = LinearGaussianModel(A=[[1.01]], B=None, C=[[1.0]], D=None, Q=[[0.1]], R=[[0.1]])
    >>> fault_trend(grow), fault_trend(grow, margin=0.02)
    (True, False)
    """
    return bool(model.spectral_radius > 1.0 + margin)


def detect_trend(radii: ArrayLike, threshold: float = 1.0, persistence: int = 3) -> int | None:
    """Index of the first alarm: the radius has been above ``threshold`` for ``persistence`` identifications.

    Returns the index (into ``radii``) of the identification that completes the first run of
    ``persistence`` consecutive values ``> threshold``, i.e. the earliest point at which an online
    monitor can raise the alarm (the run starts ``persistence - 1`` entries earlier), or None.

    Example
    -------
    >>> detect_trend([0.9, 1.02, 0.95, 1.01, 1.03, 1.02, 1.04], persistence=3)
    5
    >>> detect_trend([0.9, 1.02, 0.95], persistence=2) is None
    True
    """
    radii = np.asarray(radii, dtype=float).reshape(-1)
    if isinstance(persistence, bool) or int(persistence) != persistence or persistence < 1:
        raise PrognosisError(f"persistence must be a positive integer, got {persistence!r}")
    persistence = int(persistence)
    above = np.concatenate([[0], (radii > threshold).astype(int)])
    run = np.cumsum(above)
    hits = np.flatnonzero(run[persistence:] - run[:-persistence] == persistence) if radii.size >= persistence else []
    return int(hits[0] + persistence - 1) if len(hits) else None


@dataclass(frozen=True, eq=False)
class FeaturePrediction:
    """Predicted feature ``y_{T+1..T+H}`` with a two-sided normal interval.

    Attributes
    ----------
    mean, std, lower, upper : ndarray (H, m)
    level : float
    state_means, state_covariances : ndarray (H, n), (H, n, n)

    Examples
    --------
    Returned by :func:`predict_feature`; a decaying state without load, 90 % intervals:

    >>> m = LinearGaussianModel(A=[[0.9]], B=[[1.0]], C=[[1.0]], D=[[0.0]], Q=[[0.01]], R=[[0.04]])
    >>> p = predict_feature(m, [1.0], [[0.0]], np.zeros((3, 1)), level=0.9)
    >>> np.round(p.mean[:, 0], 4).tolist(), np.round(p.std[:, 0], 4).tolist()
    ([1.0, 0.9, 0.81], [0.2, 0.2236, 0.241])
    >>> np.round(p.lower[:, 0], 3).tolist(), np.round(p.upper[:, 0], 3).tolist(), p.level
    ([0.671, 0.532, 0.414], [1.329, 1.268, 1.206], 0.9)
    >>> p.state_means.shape, p.state_covariances.shape
    ((3, 1), (3, 1, 1))
    """

    mean: np.ndarray
    std: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    level: float
    state_means: np.ndarray
    state_covariances: np.ndarray

    def coverage(self, y: ArrayLike) -> float:
        """Fraction of the observed entries of ``y`` (H, m) inside ``[lower, upper]`` (NaN entries ignored).

        Example
        -------
        >>> m = LinearGaussianModel(A=[[0.0]], B=None, C=[[1.0]], D=None, Q=[[0.0]], R=[[1.0]])
        >>> p = predict_feature(m, [0.0], [[0.0]], None, steps=4)   # y ~ N(0, 1): interval +-1.96
        >>> p.coverage([0.5, -1.0, 2.5, np.nan])
        0.6666666666666666
        """
        y = np.asarray(y, dtype=float).reshape(self.mean.shape)
        seen = ~np.isnan(y)
        return float(np.mean((y[seen] >= self.lower[seen]) & (y[seen] <= self.upper[seen])))


def predict_feature(model: LinearGaussianModel, mean: ArrayLike, covariance: ArrayLike, u_future: ArrayLike | None,
                    level: float = 0.95, *, steps: int | None = None) -> FeaturePrediction:
    """Long-term prediction of the feature under a known future load profile (Gasperin et al. (2011), section 5.2).

    ``mean``, ``covariance`` describe the state at the first predicted time, ``x_{T+1} | y_1..y_T``: the
    filtered state at the prediction time ``T`` pushed one step through the model
    (:attr:`SmootherResult.next_mean`, :attr:`SmootherResult.next_covariance`; exact with ``S != 0``).
    Then, for ``h = 1..H`` with ``u_future`` row ``h - 1`` = ``u_{T+h}``::

        y mean = C x_h + D u_{T+h},    y var = C P_h C^T + R,
        x_{h+1} = A x_h + B u_{T+h},   P_{h+1} = A P_h A^T + Q

    (no more measurements, so ``w`` and ``v`` are uncorrelated with the past).  The interval is
    ``mean +- z std`` with ``z = Phi^-1((1 + level) / 2)`` per output.  It reflects the model's noises, not
    the uncertainty of the identified parameters.  Without inputs pass ``u_future=None`` and ``steps``.

    Example
    -------
    >>> m = LinearGaussianModel(A=[[1.0]], B=[[1.0]], C=[[1.0]], D=[[0.0]], Q=[[1.0]], R=[[0.0001]])
    >>> p = predict_feature(m, [0.0], [[0.0]], np.ones((3, 1)))
    >>> p.mean[:, 0].tolist(), np.round(p.std[:, 0] ** 2, 4).tolist()
    ([0.0, 1.0, 2.0], [0.0001, 1.0001, 2.0001])
    >>> bool(np.allclose(p.upper - p.mean, 1.959964 * p.std))
    True
    """
    if not 0.0 < level < 1.0:
        raise PrognosisError(f"level must be in (0, 1), got {level}")
    n = model.n_states
    x = np.asarray(mean, dtype=float).reshape(-1)
    p = np.asarray(covariance, dtype=float)
    if x.shape != (n,) or not np.all(np.isfinite(x)):
        raise PrognosisError(f"mean must be a finite vector of {n} entries, got shape {np.shape(mean)}")
    if p.shape != (n, n) or not np.all(np.isfinite(p)):
        raise PrognosisError(f"covariance must be a finite ({n}, {n}) matrix, got shape {p.shape}")
    u = check_future_inputs(u_future, steps, model.n_inputs, "predict_feature")
    horizon = u.shape[0]
    xs = np.empty((horizon, n))
    ps = np.empty((horizon, n, n))
    drive = u @ model.B.T
    for h in range(horizon):
        xs[h], ps[h] = x, p
        x = model.A @ x + drive[h]
        p = model.A @ p @ model.A.T + model.Q
        p = 0.5 * (p + p.T)
    y_mean = xs @ model.C.T + u @ model.D.T
    y_var = np.einsum("ij,hjk,ik->hi", model.C, ps, model.C) + np.diag(model.R)
    std = np.sqrt(np.maximum(y_var, 0.0))
    z = float(norm.ppf(0.5 * (1.0 + level)))
    return FeaturePrediction(y_mean, std, y_mean - z * std, y_mean + z * std, level, xs, ps)
