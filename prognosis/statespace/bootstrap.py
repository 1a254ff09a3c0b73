"""Bootstrap (SIR) particle filter on a discrete state-space model.

The particle filter of Jha et al. (2016) (:mod:`prognosis.particle_filter`) runs on an ARR's
residual; this one runs on the augmented state-space model of
:mod:`prognosis.statespace` (Du et al. (n.d.), eqs. 3-4, 62-63), with the interface of
the Kalman filters in :mod:`prognosis.statespace.gaussian` so that the two families can be
compared on the same data (Gordon, Salmond and Smith 1993):

1. predict: every particle (a column of ``X``, shape ``(n, N)``) goes through
   the model, ``x_k = f(x_{k-1}, u) + w``, ``w ~ N(0, Q)``, in one vectorized call;
2. update: ``log w_i += log N(z_k; h(x_k^i), R)``, normalized with log-sum-exp;
3. resample (systematic by default) when the effective sample size falls
   below ``resample_below * N``.

Weights stay in the log domain, so likelihoods far below the float range
still rank the particles; a step where no particle has a finite
log-likelihood (NaN or -inf measurement model) resets the weights to
uniform and is counted in ``degenerate_steps``.

Example
-------
>>> import sympy as sp
>>> from types import SimpleNamespace
>>> from prognosis.statespace import discretize
>>> x, a = sp.symbols("x a")
>>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
>>> model = discretize(decay, dt=1.0, augment=["a"])
>>> pf = BootstrapParticleFilter(model, [1.0, 0.2], np.diag([1e-4, 1e-2]), np.diag([1e-8, 1e-6]), [[1e-6]],
...                              n_particles=2000, seed=1)
>>> truth = 1.0
>>> for k in range(60):
...     truth *= 0.9
...     _ = pf.step([truth])
>>> abs(float(pf.mean[1]) - 0.1) < 0.01
True
"""

from __future__ import annotations

import copy as _copy

import numpy as np

from .. import _linalg as linalg
from .gaussian import Innovation, innovation, measured_rows, noises
from ..resampling import effective_sample_size, get_scheme, normalize_log_weights
from ..errors import PrognosisError

__all__ = ["BootstrapParticleFilter"]


class BootstrapParticleFilter:
    """SIR particle filter with the Kalman filters' interface.

    Parameters
    ----------
    model : DiscreteModel
    mean, covariance : initial Gaussian ``N(x_0, P_0)`` the particles are drawn from
    process_noise, measurement_noise : Q (n, n) and R (m, m)
    n_particles : int
    resampling : str
        ``"systematic"``, ``"stratified"``, ``"residual"`` or ``"multinomial"``.
    resample_below : float
        Resample when ESS < resample_below * N (1.0: every step).
    seed : int

    Examples
    --------
    Estimate the rate ``a`` of ``dx/dt = -a x`` (true 0.1, prior N(0.2, 0.1^2)):

    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import discretize
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> model = discretize(decay, dt=1.0, augment=["a"])
    >>> pf = BootstrapParticleFilter(model, [1.0, 0.2], np.diag([1e-4, 1e-2]), np.diag([1e-8, 1e-6]), [[1e-6]],
    ...                              n_particles=500, seed=1)
    >>> pf.particles.shape, pf.n_particles
    ((2, 500), 500)
    >>> for k in range(1, 31):
    ...     innovation = pf.step([0.9 ** k])
    >>> round(float(pf.mean[1]), 2), bool(np.isclose(pf.weights.sum(), 1.0)), pf.degenerate_steps
    (0.1, True, 0)
    >>> pf.update([np.nan]).nis   # a missing measurement leaves the weights alone
    nan
    """

    def __init__(self, model, mean, covariance, process_noise, measurement_noise, *, n_particles: int = 1000,
                 resampling: str = "systematic", resample_below: float = 0.5, seed: int = 0):
        if n_particles < 2:
            raise PrognosisError(f"n_particles must be at least 2, got {n_particles}")
        n = model.n_states
        self.model = model
        self.process_noise, self.measurement_noise, self._sqrt_q = noises(model, process_noise, measurement_noise)
        self.resample = get_scheme(resampling)
        self.resample_below = resample_below
        self.rng = np.random.default_rng(seed)
        x0 = linalg.state_vector(mean, n, "mean", model.states)
        root = linalg.psd_sqrt(linalg.covariance_matrix(covariance, n, "covariance (P0)", model.states))
        self.particles = x0[:, None] + root @ self.rng.standard_normal((n, n_particles))
        self.log_weights = np.full(n_particles, -np.log(n_particles))
        self.degenerate_steps = 0

    @property
    def n_particles(self) -> int:
        """Number of particles ``N``, the columns of ``particles``."""
        return self.particles.shape[1]

    @property
    def weights(self) -> np.ndarray:
        """Normalised particle weights, shape (N,)."""
        return normalize_log_weights(self.log_weights)[0]

    @property
    def mean(self) -> np.ndarray:
        """Weighted particle mean, the state estimate, shape (n,)."""
        return self.particles @ self.weights

    @property
    def covariance(self) -> np.ndarray:
        """Weighted particle covariance ``sum_i w_i (x_i - mean)(x_i - mean)^T``, shape (n, n)."""
        deviation = self.particles - self.mean[:, None]
        return (deviation * self.weights) @ deviation.T

    def predict(self, u=None) -> None:
        """Move every particle through the model: ``x_i = f(x_i, u) + w_i``, ``w_i ~ N(0, Q)``.

        ``u``: the inputs over the step (see :meth:`~prognosis.statespace.DiscreteModel.input_vector`).
        """
        noise = self._sqrt_q @ self.rng.standard_normal(self.particles.shape)
        self.particles = self.model.transition(self.particles, u) + noise

    def update(self, z, u=None) -> Innovation:
        """Weight the particles by the likelihood of the measurement ``z`` (m,), then resample if needed.

        ``log w_i += -(z - h(x_i))^T R^-1 (z - h(x_i)) / 2`` over the finite entries of ``z`` (NaN entries are
        skipped; an all-NaN ``z`` leaves the weights alone).  The particles are resampled when the effective
        sample size falls below ``resample_below * N`` or when no particle has a non-zero likelihood.  ``u`` are
        the inputs at the measurement, as in :meth:`predict`.

        Returns
        -------
        Innovation
            ``z`` minus the weighted mean of ``h(x_i)`` (weights before this update), with covariance the
            weighted spread of ``h(x_i)`` plus ``R``.
        """
        z, rows = measured_rows(z, self.model)
        if not rows.any():
            return innovation(rows)
        r = linalg.block(self.measurement_noise, rows)
        predicted = self.model.measure(self.particles, u)[rows]  # (m', N)
        weights = self.weights
        z_mean = predicted @ weights
        deviation = predicted - z_mean[:, None]
        pzz = (deviation * weights) @ deviation.T + r
        error = z[rows][:, None] - predicted
        log_likelihood = -0.5 * np.sum(error * linalg.solve(r, error), axis=0)
        log_likelihood = np.where(np.isfinite(log_likelihood), log_likelihood, -np.inf)
        weights, _, degenerate = normalize_log_weights(self.log_weights + log_likelihood)
        if degenerate:
            self.degenerate_steps += 1
        if effective_sample_size(weights) < self.resample_below * self.n_particles or degenerate:
            self.particles = self.particles[:, self.resample(weights, self.rng)]
            weights = np.full(self.n_particles, 1.0 / self.n_particles)
        self.log_weights = np.log(np.maximum(weights, np.finfo(float).tiny))
        return innovation(rows, z[rows] - z_mean, pzz)

    def step(self, z, u=None) -> Innovation:
        """``predict(u)`` then ``update(z, u)``."""
        self.predict(u)
        return self.update(z, u)

    def copy(self) -> "BootstrapParticleFilter":
        """An independent copy (its random stream continues from the same state)."""
        return _copy.deepcopy(self)
