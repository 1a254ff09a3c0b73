"""Innovation consistency of a Kalman filter (Rodriguez Obando et al. (2021), section 4.3; Bar-Shalom et al. 2001).

A filter whose model and noise covariances are right produces innovations
``e_k = y_k - C x^_{k|k-1}`` that are zero-mean, white, with covariance
``S_k``.  Whitened by ``S_k = L_k L_k^T``, ``nu_k = L_k^{-1} e_k`` is then
standard normal in every channel, so over ``K`` samples:

* variance: ``var(e_i) / mean(S_ii) <= 1`` (the tuning rule of Rodriguez Obando et al. (2021) for Q);
* unbiasedness: ``z_i = sqrt(K) mean(nu_i)`` is N(0, 1);
* NIS: ``sum_k e_k^T S_k^{-1} e_k`` is chi-square with ``m K`` degrees of freedom;
* whiteness: the sample autocorrelations of ``nu_i`` at lags 1..L lie within
  ``+-z_{(1+level)/2} / sqrt(K)``.

:func:`innovation_consistency` runs these checks on a record;
:class:`InnovationMonitor` runs the bias and NIS checks online over a sliding
window, the supervisor that decides when a filter's model no longer holds and
the filter must be restarted (Rodriguez Obando et al. (2021), section 6.1, "Re-starting the EKF").

Example
-------
>>> rng = np.random.default_rng(0)
>>> s = np.array([[2.0, 0.3], [0.3, 0.5]])
>>> e = rng.multivariate_normal([0.0, 0.0], s, size=2000)
>>> report = innovation_consistency(e, np.broadcast_to(s, (2000, 2, 2)))
>>> report.consistent
True
>>> innovation_consistency(e + [1.0, 0.0], np.broadcast_to(s, (2000, 2, 2))).unbiased
False
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..errors import PrognosisError

__all__ = ["ConsistencyReport", "InnovationMonitor", "innovation_consistency", "whiten"]


def whiten(residuals, covariances) -> np.ndarray:
    """``nu_k = L_k^{-1} e_k`` with ``S_k = L_k L_k^T``, vectorized over k; rows with NaN stay NaN.

    Parameters
    ----------
    residuals : array (K, m)
    covariances : array (K, m, m)

    Returns
    -------
    ndarray (K, m)

    Examples
    --------
    ``S = [[4, 2], [2, 2]] = L L^T`` with ``L = [[2, 0], [1, 1]]``:

    >>> s = [[4.0, 2.0], [2.0, 2.0]]
    >>> whiten([[2.0, 3.0], [np.nan, 1.0]], [s, s]).tolist()
    [[1.0, 2.0], [nan, nan]]
    """
    e = np.asarray(residuals, float)
    s = np.asarray(covariances, float)
    if e.ndim == 1:
        e = e[:, None]
    if s.ndim == 1:
        s = s[:, None, None]
    if s.shape != (*e.shape, e.shape[1]):
        raise PrognosisError(f"covariances: expected shape {(*e.shape, e.shape[1])} for residuals {e.shape}, "
                             f"got {s.shape}")
    ok = np.isfinite(e).all(axis=1) & np.isfinite(s).all(axis=(1, 2))
    out = np.full(e.shape, np.nan)
    if ok.any():
        lower = np.linalg.cholesky(s[ok])
        out[ok] = np.linalg.solve(lower, e[ok][..., None])[..., 0]
    return out


@dataclass(frozen=True)
class ConsistencyReport:
    """Outcome of :func:`innovation_consistency`.

    Attributes
    ----------
    samples : int
    variance_ratio : ndarray (m,)
        ``var(e_i) / mean(S_ii)``; at most 1 for a consistent (or cautious) filter.
    bias_z : ndarray (m,)
        ``sqrt(K) mean(nu_i)``.
    nis_mean : float
        Mean normalized innovation squared (``m`` for a consistent filter).
    nis_interval : (float, float)
        Two-sided ``level`` interval of the mean NIS under chi-square(m K) / K.
    autocorrelation : ndarray (lags, m)
        Sample autocorrelation of ``nu`` at lags 1..L.
    white_bound : float
        ``z_{(1+level)/2} / sqrt(K)``.
    level : float

    Examples
    --------
    Returned by :func:`innovation_consistency`; unit-variance innovations
    checked against ``S = 1``:

    >>> e = np.random.default_rng(0).standard_normal(500)
    >>> report = innovation_consistency(e, np.ones((500, 1, 1)))
    >>> report.samples, np.round(report.variance_ratio, 2).tolist(), round(report.nis_mean, 2)
    (500, [1.03], 1.03)
    >>> [round(v, 2) for v in report.nis_interval], report.autocorrelation.shape, round(report.white_bound, 3)
    ([0.88, 1.13], (10, 1), 0.088)
    >>> report.variance_consistent, report.unbiased, report.nis_consistent, report.white, report.consistent
    (True, True, True, True, True)
    """

    samples: int
    variance_ratio: np.ndarray
    bias_z: np.ndarray
    nis_mean: float
    nis_interval: tuple
    autocorrelation: np.ndarray
    white_bound: float
    level: float

    @property
    def variance_consistent(self) -> bool:
        """The rule of Rodriguez Obando et al. (2021): no channel varies more than ``S`` says."""
        return bool(np.all(self.variance_ratio <= 1.0 + self._slack))

    @property
    def _slack(self) -> float:  # sampling error of a variance estimate at this level
        return stats.norm.ppf(0.5 + self.level / 2) * np.sqrt(2.0 / max(self.samples - 1, 1))

    @property
    def unbiased(self) -> bool:
        """Zero-mean test: every channel's ``|bias_z|`` is at most ``z_{(1+level)/2}`` (two-sided, at ``level``)."""
        return bool(np.all(np.abs(self.bias_z) <= stats.norm.ppf(0.5 + self.level / 2)))

    @property
    def nis_consistent(self) -> bool:
        """NIS test: ``nis_mean`` lies in ``nis_interval`` (chi-square(m K) / K at ``level``)."""
        return bool(self.nis_interval[0] <= self.nis_mean <= self.nis_interval[1])

    @property
    def white(self) -> bool:
        """At most the expected share ``1 - level`` of autocorrelations outside the bound (plus one)."""
        outside = int(np.sum(np.abs(self.autocorrelation) > self.white_bound))
        return outside <= (1.0 - self.level) * self.autocorrelation.size + 1

    @property
    def consistent(self) -> bool:
        """``variance_consistent``, ``unbiased`` and ``white`` together (``nis_consistent`` is not part of it)."""
        return self.variance_consistent and self.unbiased and self.white


def innovation_consistency(residuals, covariances, *, level: float = 0.95, lags: int = 10) -> ConsistencyReport:
    """Check that innovations agree with their covariances, are unbiased and white (section 4.3).

    Parameters
    ----------
    residuals : array (K, m)
        Innovations ``e_k`` (rows with NaN are skipped).
    covariances : array (K, m, m)
        Their predicted covariances ``S_k`` (eq. 32).
    level : float
        Confidence level of every test.
    lags : int
        Autocorrelation lags for the whiteness test.

    Returns
    -------
    ConsistencyReport

    Examples
    --------
    Innovations twice as large as the filter believes fail the variance and NIS
    tests (the filter's ``Q`` or ``R`` is too small), yet remain unbiased and white:

    >>> e = 2.0 * np.random.default_rng(0).standard_normal(500)
    >>> report = innovation_consistency(e, np.ones((500, 1, 1)))
    >>> report.variance_consistent, report.nis_consistent, report.unbiased, report.white
    (False, False, True, True)
    >>> round(report.nis_mean, 1)
    4.1
    """
    e = np.asarray(residuals, float)
    e = e[:, None] if e.ndim == 1 else e
    s = np.asarray(covariances, float)
    nu = whiten(e, s)
    ok = np.isfinite(nu).all(axis=1)
    k = int(ok.sum())
    if k < max(lags + 2, 3):
        raise PrognosisError(f"innovation_consistency needs more than {max(lags + 1, 2)} complete samples, got {k}")
    e, s, nu = e[ok], s.reshape(-1, e.shape[1], e.shape[1])[ok], nu[ok]
    m = e.shape[1]
    variance_ratio = e.var(axis=0, ddof=1) / np.diagonal(s, axis1=1, axis2=2).mean(axis=0)
    nis = np.sum(nu ** 2, axis=1)
    tail = (1.0 - level) / 2
    interval = (stats.chi2.ppf(tail, m * k) / k, stats.chi2.ppf(1.0 - tail, m * k) / k)
    centred = nu - nu.mean(axis=0)
    denominator = np.sum(centred ** 2, axis=0)
    autocorrelation = np.array([np.sum(centred[j:] * centred[:-j], axis=0) / denominator for j in range(1, lags + 1)])
    return ConsistencyReport(
        samples=k, variance_ratio=variance_ratio, bias_z=np.sqrt(k) * nu.mean(axis=0), nis_mean=float(nis.mean()),
        nis_interval=(float(interval[0]), float(interval[1])), autocorrelation=autocorrelation,
        white_bound=float(stats.norm.ppf(1.0 - tail) / np.sqrt(k)), level=level,
    )


class InnovationMonitor:
    """Online bias and NIS test over a sliding window of whitened innovations.

    After each innovation the statistic is the largest of

    * ``|sqrt(W) mean(nu_i)|`` over the channels (a bias: the model drifts), and
    * ``(sum NIS - m W) / sqrt(2 m W)`` (innovations larger than ``S`` says),

    both N(0, 1)-like for a consistent filter.  An alarm is raised when the
    statistic stays above ``threshold`` for ``persistence`` consecutive samples
    with a full window.  Sums are kept running, O(m^2) per sample.

    Parameters
    ----------
    window : int
        ``W`` samples.
    threshold : float
        Alarm level of the statistic (default 5: about 3e-7 per test under N(0, 1)).
    persistence : int

    Example
    -------
    >>> monitor = InnovationMonitor(window=100, threshold=4.0, persistence=5)
    >>> rng = np.random.default_rng(1)
    >>> alarms = [monitor.update(rng.normal(size=2) + (0.0 if k < 300 else 0.8), np.eye(2)) for k in range(600)]
    >>> alarms.index(True) > 300, any(alarms[:300])
    (True, False)
    """

    def __init__(self, window: int = 600, threshold: float = 5.0, persistence: int = 10):
        if window < 2 or persistence < 1 or not threshold > 0:
            raise PrognosisError(f"need window >= 2, persistence >= 1 and threshold > 0, got {window}, "
                                 f"{persistence}, {threshold}")
        self.window, self.threshold, self.persistence = int(window), float(threshold), int(persistence)
        self.reset()

    def reset(self) -> None:
        """Forget the window (after a restart of the filter)."""
        self._buffer: deque = deque()
        self._sum = None
        self._nis = 0.0
        self._above = 0
        self.statistic = np.nan

    def update(self, residual, covariance) -> bool:
        """Add one innovation ``e_k`` with covariance ``S_k``; True when the alarm is raised."""
        e = np.atleast_1d(np.asarray(residual, float))
        if not np.all(np.isfinite(e)):
            return False
        nu = np.linalg.solve(np.linalg.cholesky(np.atleast_2d(np.asarray(covariance, float))), e)
        nis = float(nu @ nu)
        if self._sum is None:
            self._sum = np.zeros_like(nu)
        self._buffer.append((nu, nis))
        self._sum += nu
        self._nis += nis
        if len(self._buffer) > self.window:
            old, old_nis = self._buffer.popleft()
            self._sum -= old
            self._nis -= old_nis
        if len(self._buffer) < self.window:
            return False
        w, m = self.window, nu.size
        bias = float(np.max(np.abs(self._sum)) / np.sqrt(w))
        spread = (self._nis - m * w) / np.sqrt(2.0 * m * w)
        self.statistic = max(bias, spread)
        self._above = self._above + 1 if self.statistic > self.threshold else 0
        return self._above >= self.persistence
