"""SIR particle filter for joint estimation of theta and gamma (Jha et al. (2016), Table II).

State arrays are batched over independent assets: ``theta`` (A, N),
``gamma`` (A, N, G), log-weights (A, N); one asset is a batch of one.  A step:

1. predict: ``gamma_k = gamma_{k-1} + xi``, ``xi ~ N(0, var_xi)`` (random
   walk), ``theta_k = g(theta_{k-1}, gamma_{k-1}) + v``;
2. update: ``log w += -(y - h(theta_k))^2 / (2 c sigma_w^2)``, with ``c`` the
   inflation of the residual noise variance (the paper uses 4 and 9);
   a missing measurement (NaN) skips the update;
3. normalize in log space (log-sum-exp) and resample (systematic by default)
   every step or when the effective sample size falls below a fraction of N;
   if every weight of an asset is zero or NaN, the weights are reset to
   uniform and the step's diagnostics say so;
4. adapt the random-walk variance (:class:`VarianceAdaptation`, Table III).

Initialisation at detection (eq. 39): theta uniform over the candidate's
uncertainty interval ``theta_n (1 + [delta_lo, delta_hi])``, gamma at a given
start value (0 in the paper).
"""

from __future__ import annotations

import copy
import math
import numbers
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .metrics import rmad
from .weighted import weighted_quantiles
from .resampling import effective_sample_size, get_scheme, normalize_log_weights
from .seeds import check_seed
from .errors import PrognosisError

__all__ = [
    "COLLAPSE_BELOW", "KernelSmoothing", "ParticleFilter", "StepDiagnostics", "VarianceAdaptation",
    "check_particles", "check_positive", "cloud_estimate",
]


@dataclass
class VarianceAdaptation:
    """Random-walk variance adaptation (Jha et al. (2016), section 4.1.1, Table III).

    For each progression parameter j, the moving average of the estimated
    mean of gamma_j over the last ``window + 1`` steps (eq. 36) decides:

    * inside ``band = [gamma_l*, gamma_u*]``: proportional control of the
      random-walk variance from the spread ``v = RMAD(gamma_j particles)``
      (eq. 35) against the reference ``v*``::

          var_xi <- var_xi * (1 - P (v - v*) / v*)

      kept within ``[floor * var_xi,0, var_xi,0]``.  Table III as printed
      multiplies by ``1 + P (v - v*)/v*``, which grows the noise when the
      spread is too large; the intent (section 4.1.1, after Daigle and Goebel)
      is to shrink it, hence the minus sign (see docs/design.md).  Table III also
      writes the spread and the variance with the same symbol; here the
      spread steers the variance of the previous step.
    * outside the band: reset to the initial variance ``var_xi,0``.

    Examples
    --------
    Particles of gamma at 0.4, 0.5, 0.6 have the spread ``v = 0.1 / 0.5 = 0.2``,
    twice the reference 0.1; with gain 0.5 the variance is halved:

    >>> adapt = VarianceAdaptation(band=(0.0, 1.0), reference=0.1, gain=0.5)
    >>> gamma, weights = np.array([[[0.4], [0.5], [0.6]]]), np.full((1, 3), 1 / 3)   # (A, N, G), (A, N)
    >>> (adapt(gamma, weights, np.array([[1e-4]]), np.array([1e-4])) / 1e-4).round(6).tolist()
    [[0.5]]

    Outside the band the variance goes back to its initial value:

    >>> adapt.reset()
    >>> (adapt(gamma + 2.0, weights, np.array([[5e-5]]), np.array([1e-4])) / 1e-4).round(6).tolist()
    [[1.0]]
    """

    band: tuple
    reference: float = 0.10
    gain: float = 0.001
    window: int = 10
    floor: float = 1e-6
    _means: deque = field(default=None, init=False, repr=False)

    def reset(self) -> None:
        """Forget the stored means of gamma, so that the moving average (eq. 36) starts afresh."""
        self._means = deque(maxlen=self.window + 1)

    def shrink(self, gamma: np.ndarray) -> np.ndarray:
        """``gamma`` unchanged: the random walk of Table III moves no particle toward the mean."""
        return gamma

    def __call__(self, gamma: np.ndarray, weights: np.ndarray, variance: np.ndarray,
                 initial: np.ndarray) -> np.ndarray:
        """New variance (A, G) from particles ``gamma`` (A, N, G) and their weights (A, N)."""
        if self._means is None:
            self.reset()
        mean = np.einsum("an,ang->ag", weights, gamma)
        self._means.append(mean)
        average = np.mean(np.stack(self._means), axis=0)  # eq. 36 (all available steps when k < L)
        lo, hi = (np.broadcast_to(np.asarray(b, float), mean.shape) for b in self.band)
        inside = (average >= lo) & (average <= hi)
        spread = _spread(np.moveaxis(gamma, -1, 1), weights)  # (A, G)
        factor = 1.0 - self.gain * (spread - self.reference) / self.reference
        adapted = np.clip(variance * np.nan_to_num(factor, nan=1.0), self.floor * initial, initial)
        return np.where(inside, adapted, initial)


@dataclass
class KernelSmoothing:
    """Kernel shrinkage of the constant rate gamma (Liu and West (2001)), the default adaptation.

    A degradation law with a constant rate makes gamma a static parameter; a plain random walk on it
    widens its posterior at every step, and Table III's band control resets the walk to its initial
    variance whenever the mean of gamma leaves the band, so it can oscillate (a true rate on or
    beyond the band's edge).  Kernel smoothing keeps the particles' mean and variance instead:
    before each move, every particle is pulled toward the weighted mean, then jittered,

        gamma_i <- a gamma_i + (1 - a) mean + N(0, (1 - a^2) var),   a = (3 delta - 1) / (2 delta),

    so the cloud's variance is unchanged by the move (no artificial growth, no reset, nothing to
    oscillate), while the jitter keeps the resampled particles distinct.  ``discount`` (delta,
    0.95-0.99 in Liu and West (2001)) sets how much of the spread is renewed per step.  ``floor``
    keeps the jitter's standard deviation at least that fraction of ``|mean|``, so that a
    collapsed cloud can still move.

    Examples
    --------
    The move keeps the mean (0.5) and shrinks each particle a tenth of the way toward it
    (discount 0.9 gives a = 0.944):

    >>> smoothing = KernelSmoothing(discount=0.9)
    >>> gamma, weights = np.array([[[0.4], [0.5], [0.6]]]), np.full((1, 3), 1 / 3)
    >>> variance = smoothing(gamma, weights, None, None)   # after a filter step: the jitter's variance
    >>> smoothing.shrink(gamma).round(4).ravel().tolist()
    [0.4056, 0.5, 0.5944]
    >>> bool(np.isclose(variance[0, 0], (1 - smoothing.shrinkage**2) * np.var(gamma)))
    True
    """

    discount: float = 0.98
    floor: float = 1e-3
    _mean: np.ndarray = field(default=None, init=False, repr=False)

    def __post_init__(self):
        if not 1 / 3 < self.discount <= 1:
            raise PrognosisError(f"discount must lie in (1/3, 1], got {self.discount}")

    @property
    def shrinkage(self) -> float:
        """``a = (3 delta - 1) / (2 delta)``."""
        return (3 * self.discount - 1) / (2 * self.discount)

    def reset(self) -> None:
        """Forget the stored mean (the first move uses the initial particles' plain mean)."""
        self._mean = None

    def shrink(self, gamma: np.ndarray) -> np.ndarray:
        """Particles ``gamma`` (A, N, G) pulled toward the mean of the last :meth:`__call__`."""
        mean = np.mean(gamma, axis=1) if self._mean is None else self._mean
        a = self.shrinkage
        return a * gamma + (1 - a) * mean[:, None, :]

    def __call__(self, gamma: np.ndarray, weights: np.ndarray, variance, initial) -> np.ndarray:
        """The jitter's variance (A, G) for the next move; ``variance`` and ``initial`` are not used."""
        self._mean = np.einsum("an,ang->ag", weights, gamma)
        spread = np.einsum("an,ang->ag", weights, np.square(gamma - self._mean[:, None, :]))
        return np.maximum((1 - self.shrinkage**2) * spread, np.square(self.floor * self._mean))


def _spread(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """RMAD (eq. 35) along the last axis; after resampling the weights are equal and a plain median does."""
    if np.all(weights == weights[..., :1]):
        median = np.median(values, axis=-1, keepdims=True)
        return np.median(np.abs(values - median), axis=-1) / median[..., 0]
    return rmad(values, weights[:, None, :])


@dataclass
class StepDiagnostics:
    """What one filter step did, per asset.

    Attributes
    ----------
    updated : ndarray of bool (A,)
        A measurement was used (False where it was NaN).
    ess : ndarray (A,)
        Effective sample size after the update, before resampling.
    resampled : ndarray of bool (A,)
    degenerate : ndarray of bool (A,)
        Every weight was zero or NaN and the weights were reset to uniform.
    collapsed : ndarray of bool (A,)
        The cloud collapsed: the effective sample size of an update fell below
        :data:`COLLAPSE_BELOW` N (a resample-move filter: fewer distinct particles than that
        after its move).  Its spread is then not a band.
    innovation : ndarray (A, M) or None
        The measurement's standardized innovation ``(y - E[y]) / sd[y]`` under the one-step
        predictive distribution (the particles before the update and the noise): near N(0, 1) and
        white when the model fits (a resample-move filter gives it).

    Examples
    --------
    Returned by :meth:`ParticleFilter.step`; two assets, the second one unmeasured at this step:

    >>> from prognosis.degradation import LinearDegradation
    >>> pf = ParticleFilter(LinearDegradation(), lambda theta, points: theta, n_particles=200, dt=1.0, noise_std=0.05,
    ...                     resample_below=0.5, seed=0)
    >>> pf.initialize((0.0, 2.0), assets=2)
    >>> step = pf.step([1.0, np.nan])
    >>> step.updated.tolist(), step.resampled.tolist(), step.degenerate.tolist()
    ([True, False], [True, False], [False, False])
    >>> bool(step.ess[0] < 100), round(float(step.ess[1]), 6)   # the unmeasured asset keeps uniform weights
    (True, 200.0)
    """

    updated: np.ndarray
    ess: np.ndarray
    resampled: np.ndarray
    degenerate: np.ndarray
    collapsed: np.ndarray | None = None
    innovation: np.ndarray | None = None


#: An update whose effective sample size falls below this share of the particles has collapsed.
COLLAPSE_BELOW = 0.1


class ParticleFilter:
    """Batched SIR particle filter over (theta, gamma).

    Parameters
    ----------
    model : degradation model (:mod:`prognosis.degradation`)
    observation : callable ``h(theta, points) -> y`` (e.g. an ObservationModel)
    n_particles : int
    dt : float
        Filter step in seconds.
    noise_std : float or array (A,)
        Standard deviation sigma_w of the residual noise.
    inflation : float
        Multiplier of sigma_w^2 in the likelihood (Jha et al. (2016): 4 or 9).
    gamma_std : float or sequence (G,)
        Initial random-walk standard deviation of each gamma.
    adaptation : VarianceAdaptation or KernelSmoothing, optional
        Copied (:func:`copy.deepcopy`): the filter keeps its moving averages in its own copy, so
        one object can configure several filters without mixing their averages.
    resampling : str
        ``"systematic"`` (default), ``"stratified"``, ``"residual"`` or ``"multinomial"``.
    resample_below : float
        Resample when ESS < resample_below * N; 1.0 resamples at every step.
    seed : int or numpy.random.SeedSequence
        Seed of the filter's generator (:func:`numpy.random.default_rng`).

    Examples
    --------
    A quantity growing by 0.1 per step, measured directly: the filter estimates
    its level theta and its rate gamma.

    >>> from prognosis.degradation import LinearDegradation
    >>> pf = ParticleFilter(LinearDegradation(), lambda theta, points: theta, n_particles=500, dt=1.0, noise_std=0.05,
    ...                     inflation=1.0, gamma_std=0.01, seed=0)
    >>> pf.initialize((0.0, 2.0), gamma0=0.0)   # theta ~ U(0, 2), gamma = 0 at detection
    >>> for k in range(1, 31):
    ...     _ = pf.step(0.1 * k)
    >>> estimate = pf.estimate()
    >>> round(float(estimate["theta_mean"][0]), 1), round(float(estimate["gamma_mean"][0, 0]), 2)
    (3.0, 0.1)
    >>> pf.assets, pf.theta.shape, pf.gamma.shape, estimate["theta_quantiles"].shape
    (1, (1, 500), (1, 500, 1), (1, 3))
    """

    def __init__(self, model, observation, *, n_particles: int = 500, dt: float = 0.1, noise_std=0.01,
                 inflation: float = 4.0, gamma_std=0.02, adaptation: VarianceAdaptation | None = None,
                 resampling: str = "systematic", resample_below: float = 1.0, seed: int | np.random.SeedSequence = 0):
        n_particles = check_particles(n_particles)
        if inflation <= 0:
            raise PrognosisError(f"inflation must be positive, got {inflation}")
        _check_noise_std(noise_std)
        dt = check_positive(dt, "dt")
        self.model, self.observation = model, observation
        self.n, self.dt = n_particles, dt
        self.noise_std, self.inflation = noise_std, inflation
        self.initial_variance = np.square(np.atleast_1d(np.asarray(gamma_std, float)))
        if self.initial_variance.size != model.n_gamma:
            raise PrognosisError(f"gamma_std has {self.initial_variance.size} entries; "
                                 f"the model has {model.n_gamma} gammas")
        # a copy of its own: a shared adaptation object would average gamma over every filter using it
        self.adaptation = copy.deepcopy(adaptation)
        self.resample = get_scheme(resampling)
        self.resample_below = resample_below
        self.rng = np.random.default_rng(check_seed(seed))
        self.theta = self.gamma = self.log_weights = self.variance = self.log_evidence = None

    def initialize(self, theta_bounds, gamma0=0.0, assets: int = 1, gamma_bounds=None) -> None:
        """Particles at detection: theta ~ U(lo, hi) per asset (eq. 39), gamma = gamma0.

        ``gamma_bounds = (lo, hi)`` (each a scalar or (G,)) draws gamma uniformly instead, e.g. over
        the band of :class:`VarianceAdaptation`, the prior knowledge of gamma the paper already uses.
        """
        lo, hi = (np.broadcast_to(np.asarray(b, float), (assets,)) for b in theta_bounds)
        if np.any(lo > hi):
            raise PrognosisError(f"theta bounds have lo > hi: {theta_bounds}")
        self.theta = lo[:, None] + (hi - lo)[:, None] * self.rng.random((assets, self.n))
        shape = (assets, self.n, self.model.n_gamma)
        if gamma_bounds is None:  # gamma0: a value per gamma (G,), or the particles themselves (A, N, G)
            self.gamma = np.broadcast_to(np.asarray(gamma0, float), shape).copy()
        else:
            g_lo, g_hi = (np.broadcast_to(np.asarray(b, float), (self.model.n_gamma,)) for b in gamma_bounds)
            if np.any(g_lo > g_hi):
                raise PrognosisError(f"gamma bounds have lo > hi: {gamma_bounds}")
            self.gamma = g_lo + (g_hi - g_lo) * self.rng.random(shape)
        self.log_weights = np.full((assets, self.n), -np.log(self.n))
        self.log_evidence = np.zeros(assets)
        self.variance = np.broadcast_to(self.initial_variance, (assets, self.model.n_gamma)).copy()
        if self.adaptation is not None:
            self.adaptation.reset()

    @property
    def assets(self) -> int:
        """Number of assets ``A``, the first axis of ``theta`` (after :meth:`initialize`)."""
        return self._initialized().shape[0]

    @property
    def weights(self) -> np.ndarray:
        """Normalised particle weights, shape (assets, particles)."""
        self._initialized()
        return normalize_log_weights(self.log_weights)[0]

    def _initialized(self) -> np.ndarray:
        if self.theta is None:
            raise RuntimeError("the particle filter has no particles yet: call initialize() first (at detection time)")
        return self.theta

    def step(self, y, points=()) -> StepDiagnostics:
        """One predict-update-resample-adapt cycle with measurement ``y`` and point values.

        ``y`` is one measurement per asset (A,), or M per asset (A, M) when the observation returns
        (A, N, M) (several residuals; ``noise_std`` then (M,) or (A, M)).  NaN entries are skipped.
        The log of the evidence increment p(y_k | y_1..k-1), summed into :attr:`log_evidence`, is
        the log of the sum of the updated weights (the stored weights are normalized), with the
        Gaussian's normalizing constant.
        """
        self._initialized()
        y = np.asarray(y, float)
        y = y if y.ndim == 2 else np.broadcast_to(y, (self.assets,))
        self._predict()
        finite = np.isfinite(y)
        updated = finite.any(axis=1) if y.ndim == 2 else finite
        if updated.any():
            log_likelihood = self._log_likelihood(y, finite, self.observation(self.theta, points))
            self.log_weights = np.where(updated[:, None], self.log_weights + log_likelihood, self.log_weights)
        weights, log_sum, degenerate = normalize_log_weights(self.log_weights)
        self.log_evidence = self.log_evidence + np.where(updated, log_sum + self._log_constant(y, finite), 0.0)
        ess = effective_sample_size(weights)
        resampled = (ess < self.resample_below * self.n) | (self.resample_below >= 1.0) | degenerate
        if resampled.any():
            self._resample(weights, resampled)
            weights = np.where(resampled[:, None], 1.0 / self.n, weights)
        self.log_weights = np.log(np.maximum(weights, np.finfo(float).tiny))
        if self.adaptation is not None:
            self.variance = self.adaptation(self.gamma, weights, self.variance, self.initial_variance)
        collapsed = updated & (ess < COLLAPSE_BELOW * self.n)
        return StepDiagnostics(updated, ess, resampled, degenerate, collapsed)

    def _log_likelihood(self, y: np.ndarray, finite: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        """Gaussian log-likelihood (A, N) of each particle, with inflated variance c sigma_w^2."""
        variance = self.inflation * np.square(np.broadcast_to(np.asarray(self.noise_std, float), y.shape))
        gap = np.where(finite, y, 0.0)[:, None, ...] - predicted
        terms = -0.5 * np.square(gap) / variance[:, None, ...]
        if y.ndim == 2:
            return np.sum(np.where(finite[:, None, :], terms, 0.0), axis=-1)
        return terms

    def _log_constant(self, y: np.ndarray, finite: np.ndarray) -> np.ndarray:
        """The Gaussian's normalizing constant, log of 1 / sqrt(2 pi c sigma_w^2) per used measurement, (A,).

        Kept out of the weights (it is the same for every particle of an asset), added to the evidence.
        """
        variance = self.inflation * np.square(np.broadcast_to(np.asarray(self.noise_std, float), y.shape))
        constant = np.where(finite, -0.5 * np.log(2 * np.pi * variance), 0.0)
        return constant.sum(axis=1) if y.ndim == 2 else constant

    def _predict(self) -> None:
        noise = self.rng.standard_normal(self.theta.shape) * self.model.process_noise
        theta = self.model.step(self.theta, self.gamma, self.dt) + noise  # uses gamma_{k-1}
        gamma = self.gamma if self.adaptation is None else self.adaptation.shrink(self.gamma)
        self.gamma = gamma + self.rng.standard_normal(self.gamma.shape) * np.sqrt(self.variance)[:, None, :]
        self.theta = theta

    def _resample(self, weights: np.ndarray, rows: np.ndarray) -> None:
        index = self.resample(weights, self.rng)
        index = np.where(rows[:, None], index, np.arange(self.n))
        self.theta = np.take_along_axis(self.theta, index, axis=1)
        self.gamma = np.take_along_axis(self.gamma, index[..., None], axis=1)

    def estimate(self) -> dict:
        """Weighted mean, median and RMAD of theta and each gamma, per asset."""
        return cloud_estimate(self.theta, self.gamma, self.weights)


def cloud_estimate(theta: np.ndarray, gamma: np.ndarray, weights: np.ndarray) -> dict:
    """Weighted mean, RMAD and 5/50/95 % quantiles of ``theta`` (A, N) and each gamma (A, N, G), per asset."""
    gamma = np.moveaxis(gamma, -1, 1)  # (A, G, N)
    return {
        "theta_mean": np.sum(weights * theta, axis=1),
        "theta_rmad": rmad(theta, weights),
        "gamma_mean": np.einsum("an,agn->ag", weights, gamma),
        "gamma_rmad": rmad(gamma, weights[:, None, :]),
        "theta_quantiles": weighted_quantiles(theta, weights, (0.05, 0.5, 0.95)),
        "gamma_quantiles": weighted_quantiles(gamma, weights[:, None, :], (0.05, 0.5, 0.95)),
    }


def check_positive(value: object, option: str) -> float:
    """``value`` as a float; a PrognosisError naming ``option`` unless it is a finite number > 0.

    >>> check_positive(0.01, "noise_std")
    0.01
    >>> check_positive(-1, "noise_std")
    Traceback (most recent call last):
    ...
    prognosis.errors.PrognosisError: noise_std must be a finite number > 0, got -1
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real) or not math.isfinite(value) \
            or value <= 0:
        raise PrognosisError(f"{option} must be a finite number > 0, got {value!r}")
    return float(value)


def check_particles(value: object) -> int:
    """``n_particles`` as an int; a PrognosisError unless it is >= 2 (a weighted cloud needs two)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral) or value < 2:
        raise PrognosisError(f"n_particles must be a whole number >= 2, got {value!r}")
    return int(value)


def _check_noise_std(noise_std: object) -> None:
    """Every entry of ``noise_std`` a finite number > 0: the likelihood divides by its square."""
    try:
        values = np.asarray(noise_std, dtype=float)
    except (TypeError, ValueError):
        raise PrognosisError(f"noise_std must be a number or an array of numbers, got {noise_std!r}") from None
    bad = ~(np.isfinite(values) & (values > 0))
    if bad.any():
        raise PrognosisError(f"noise_std must be finite and > 0, got {float(values[bad].reshape(-1)[0])!r}"
                             + (f" in {values.tolist()}" if values.ndim else ""))
