"""The residuals' noise as the likelihood sees it: correlated between ARRs, growing with the parameter.

A hypothesis predicts ``y = h(theta, s)`` from the measured signals ``s``.  The gap ``y - h`` is the
residual evaluated at the hypothesis' value of theta, so its noise is what the sensors' noise makes
of it *at that value*: for an ARR linear in theta, ``r(theta) = r(theta_n) + (theta - theta_n) S(s)``
with ``S = dh/dtheta`` read on noisy signals, hence

    Cov(y - h) = C + D (X + X^T) + D^2 G,      D = theta - theta_n,

with ``C`` the covariance of the residuals on a healthy stretch, ``G`` that of the sensitivities'
noise and ``X`` their cross-covariance (:func:`healthy_noise` estimates all three from the healthy
stretch).  A viscous friction seen through a noisy speed is the usual case: ten times the friction,
ten times the speed noise in the residual.  ARRs that share a signal share its noise, hence the full
matrices: weighing them as independent counts the same evidence twice.  For an ARR that is not
linear in theta the same form holds to first order.

:class:`ResidualNoise` evaluates the Gaussian log-density of the gaps, normalizing constant included
(the covariance depends on theta, so the constant differs between particles and belongs in the
weights).  A missing measurement (NaN) is left out of the density (its marginal over the others).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .errors import PrognosisError
from .wander import innovations, steady_state

__all__ = ["ResidualNoise", "healthy_noise", "information_excess", "integral_walk"]

_LOG_2PI = float(np.log(2 * np.pi))
DIFFERENCES = 4  # order of the differences the sensitivities' noise is read from
MIN_STEPS = 8  # standardized gaps below which their long-run variance is not estimated (taken as 1)
BATCHES = 8  # the fewest batches the long-run variance is read from (the longest batches, K / BATCHES steps)


@dataclass(frozen=True)
class ResidualNoise:
    """Gaussian noise of M residuals per asset, its covariance growing with ``theta - nominal``.

    Parameters
    ----------
    covariance : array (A, M, M) or (M, M)
        ``C``: the residuals' covariance at the nominal value.
    cross, growth : array (A, M, M C) and (A, M C, M C), optional
        ``X`` and ``G``: cross-covariance of residual and sensitivity noise, covariance of the
        sensitivities' noise, of each of C parameters per row (C = 1: like ``covariance``; C > 1, a
        joint hypothesis: the sensitivities of the C parameters side by side, ``Cov(y - h) = C +
        sum_c D_c (X_c + X_c^T) + sum_cd D_c D_d G_cd``).  Without them the noise does not depend on theta.
    nominal : array (A,), (A, C) or float
        ``theta_n`` of each asset (row), of each of its C parameters.
    inflation : float
        Multiplier of the whole covariance (1: the noise as measured).
    walk : array (A, M) or (M,), optional
        Variance per step of a random-walk offset on each residual (the drift an integral of noisy
        signals adds: :func:`integral_walk`), in the residual's units squared; None: no offset.
        The likelihood of a history then follows it (:mod:`prognosis.wander`).

    Examples
    --------
    One residual of std 0.1 whose sensitivity carries noise of std 0.01: at ``theta - theta_n = 10``
    the std is ``sqrt(0.01 + 100 * 1e-4) = 0.141``.

    >>> noise = ResidualNoise(covariance=[[0.01]], growth=[[1e-4]], nominal=1.0)
    >>> round(float(np.sqrt(noise.covariance_at(np.array([[11.0]]))[0, 0, 0, 0])), 3)
    0.141
    >>> log_p = noise.log_density(np.array([[[0.0], [0.0]]]), np.array([[1.0, 11.0]]))
    >>> bool(log_p[0, 0] > log_p[0, 1])   # the same gap is less likely where the noise is wider... at 0
    True
    """

    covariance: np.ndarray
    cross: np.ndarray | None = None
    growth: np.ndarray | None = None
    nominal: np.ndarray | float = 0.0
    inflation: float = 1.0
    walk: np.ndarray | None = None

    def __post_init__(self):
        c = np.asarray(self.covariance, float)
        c = c if c.ndim == 3 else c[None]
        if c.shape[-1] != c.shape[-2]:
            raise PrognosisError(f"covariance must be square (M, M) per asset, got shape {c.shape}")
        diagonal = np.diagonal(c, axis1=-2, axis2=-1)
        if not (np.all(np.isfinite(c)) and np.all(diagonal > 0)):
            raise PrognosisError("covariance must be finite with a positive diagonal (each residual's noise "
                                 "variance)")
        if not self.inflation > 0:
            raise PrognosisError(f"inflation must be positive, got {self.inflation!r}")
        object.__setattr__(self, "covariance", c)
        for name in ("cross", "growth"):
            value = getattr(self, name)
            if value is not None:
                value = np.asarray(value, float)
                value = value if value.ndim == 3 else value[None]
                object.__setattr__(self, name, np.broadcast_to(value, (c.shape[0], *value.shape[1:])))
        object.__setattr__(self, "nominal", np.atleast_1d(np.asarray(self.nominal, float)))
        if self.walk is not None:
            walk = np.broadcast_to(np.asarray(self.walk, float), (c.shape[0], c.shape[-1]))
            if not (np.all(np.isfinite(walk)) and np.all(walk >= 0)):
                raise PrognosisError("walk must hold finite variances >= 0, one per residual")
            object.__setattr__(self, "walk", walk)
        if self.cross is not None or self.growth is not None:
            self._make_joint_positive()

    def _make_joint_positive(self) -> None:
        """Make ``[[C, X], [X^T, G]]`` positive semi-definite by raising G alone.

        ``Sigma(theta) = [I, D I] J [I, D I]^T`` is a covariance for every D only if the joint ``J`` of
        the residual and sensitivity noise is one; C, X and G come from different estimators (a
        robust std, fourth differences), so their joint may not be.  With C positive definite, J is
        positive semi-definite exactly when the Schur complement ``G - X^T C^-1 X`` is: its negative
        eigenvalues are set to zero, which raises G (more noise, never less) and keeps C and X.
        """
        width = self.size * self.components
        x = np.zeros((*self.covariance.shape[:2], width)) if self.cross is None else self.cross
        g = np.zeros((self.covariance.shape[0], width, width)) if self.growth is None else self.growth
        explained = np.swapaxes(x, -1, -2) @ np.linalg.solve(self.covariance, x)
        schur = g - explained
        values, vectors = np.linalg.eigh(0.5 * (schur + np.swapaxes(schur, -1, -2)))
        schur = np.einsum("aij,aj,akj->aik", vectors, np.maximum(values, 0.0), vectors)
        object.__setattr__(self, "cross", np.array(x))
        object.__setattr__(self, "growth", explained + schur)

    @classmethod
    def independent(cls, std, inflation: float = 1.0) -> "ResidualNoise":
        """Independent residuals of standard deviation ``std`` (M,) or (A, M), not growing with theta.

        >>> ResidualNoise.independent([0.1, 0.2]).covariance.round(4).tolist()
        [[[0.01, 0.0], [0.0, 0.04]]]
        """
        std = np.atleast_1d(np.asarray(std, float))
        return cls(np.einsum("...m,mn->...mn", np.square(std), np.eye(std.shape[-1])), inflation=inflation)

    def rows(self, index: np.ndarray) -> "ResidualNoise":
        """The noise of the rows ``index`` alone: per-row arrays sliced, shared ones kept.

        >>> noise = ResidualNoise.independent([[0.1], [0.2], [0.3]])
        >>> noise.rows(np.array([2])).covariance.round(4).tolist()
        [[[0.09]]]
        """
        view = object.__new__(ResidualNoise)
        for name in ("covariance", "cross", "growth", "nominal", "walk"):
            value = getattr(self, name)
            object.__setattr__(view, name, value if value is None or value.shape[0] == 1 else value[index])
        object.__setattr__(view, "inflation", self.inflation)
        return view

    @cached_property
    def walk_ratio(self) -> np.ndarray:
        """Each whitened residual's offset walk per step over its noise (A, M), 0 without a walk.

        The walk of residual m over the variance residual m keeps given the earlier ones (the square
        of the Cholesky factor's diagonal at the nominal value): what the walk is in the whitened
        component it enters first.  A walk of one residual also leaks into later whitened
        components; that share is left out (the walks are small beside the noise).

        >>> ResidualNoise.independent([0.1], inflation=4.0).walk_ratio.tolist()
        [[0.0]]
        >>> noise = ResidualNoise(covariance=[[0.01]], walk=[1e-4])
        >>> noise.walk_ratio.round(6).tolist()
        [[0.01]]
        """
        if self.walk is None:
            return np.zeros(self.covariance.shape[:2])
        conditional = np.square(np.diagonal(_cholesky(self.covariance), axis1=-2, axis2=-1))
        return self.walk / conditional

    @property
    def size(self) -> int:
        """M, the number of residuals."""
        return self.covariance.shape[-1]

    @property
    def components(self) -> int:
        """C, the parameters per row the noise grows with (theta then carries them on a last axis when C > 1)."""
        given = self.cross if self.cross is not None else self.growth
        return 1 if given is None else given.shape[-1] // self.size

    def covariance_at(self, theta: np.ndarray) -> np.ndarray:
        """``Sigma(theta)`` (A, N, ..., M, M) for ``theta`` (A, N, ...), or (A, N, ..., C) with C > 1
        :attr:`components`, kept positive definite."""
        theta = np.asarray(theta, float)
        c, m = self.components, self.size
        batch = theta.shape if c == 1 else theta.shape[:-1]
        extra = (slice(None),) + (None,) * (len(batch) - 1) + (Ellipsis,)
        sigma = np.broadcast_to(self.covariance[extra], (*batch, m, m))
        if self.cross is None and self.growth is None:
            return self.inflation * sigma
        d = (theta.reshape(*batch, c) - self.nominal.reshape((-1,) + (1,) * (len(batch) - 1) + (c,)))
        with np.errstate(over="ignore", invalid="ignore"):  # a theta far out overflows: no density there
            if c == 1:
                d = d[..., None]
                if self.cross is not None:
                    sigma = sigma + d * (self.cross + np.swapaxes(self.cross, -1, -2))[extra]
                if self.growth is not None:
                    sigma = sigma + np.square(d) * self.growth[extra]
            else:  # a loop over the C parameters (a few): elementwise products broadcast fast, einsum does not
                d = d[..., None, None]
                for i in range(c):
                    if self.cross is not None:  # d_i (X_i + X_i^T), X_i the i-th M x M block of X
                        block = self.cross[:, :, i * m:(i + 1) * m]
                        sigma = sigma + d[..., i, :, :] * (block + np.swapaxes(block, -1, -2))[extra]
                    if self.growth is not None:  # d_i d_j G_ij
                        for j in range(c):
                            block = self.growth[:, i * m:(i + 1) * m, j * m:(j + 1) * m][extra]
                            sigma = sigma + (d[..., i, :, :] * d[..., j, :, :]) * block
        # the cross term can only lower the variance as far as the correlation allows; estimates from
        # a short stretch may overshoot, so the diagonal stays at least at the healthy one's share
        healthy = np.diagonal(self.covariance, axis1=-2, axis2=-1)[extra]
        diagonal = np.diagonal(sigma, axis1=-2, axis2=-1)
        # plus a millionth of the healthy variance: a positive semi-definite sum stays invertible
        lift = np.maximum(0.25 * healthy - diagonal, 0.0) + 1e-6 * healthy
        sigma = sigma + np.einsum("...m,mn->...mn", lift, np.eye(self.size))
        return self.inflation * sigma

    def log_density(self, gap: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """``log N(gap; 0, Sigma(theta))`` (A, N, ...) for ``gap`` (A, N, ..., M); NaN entries marginalized."""
        white, log_variance, measured = self.whiten(gap, theta)
        used = np.sum(measured, axis=-1)
        with np.errstate(invalid="ignore"):  # an infinite variance (no density) gives -inf
            return -0.5 * (np.sum(np.square(white) + log_variance, axis=-1) + used * _LOG_2PI)

    def history_density(self, gap: np.ndarray, theta: np.ndarray,
                        level: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Log-densities per whitened residual (A, N, K, M) of the gaps (A, N, K, M) of K successive steps.

        Each step's density is that of its innovation given the earlier gaps when the residuals'
        offsets walk (:attr:`walk_ratio`, :mod:`prognosis.wander`), of the gap itself otherwise (the
        terms then sum to :meth:`log_density`).  ``theta`` (A, N, K) or (A, N, K, C); ``level`` (A, N, M):
        the offsets predicted for the first step (None: zero).  Returns the terms (0 where not
        measured), the offsets predicted after the last step and the standardized innovations (NaN
        where not measured), which are white N(0, 1) when the noise model holds.

        >>> noise = ResidualNoise(covariance=[[1.0]], walk=[0.25])
        >>> terms, level, standardized = noise.history_density(np.ones((1, 1, 3, 1)), np.zeros((1, 1, 3)))
        >>> level.round(3).tolist(), standardized[0, 0, :, 0].round(3).tolist()   # the offset follows the gaps
        ([[[0.773]]], [0.781, 0.476, 0.29])
        """
        white, log_variance, measured = self.whiten(gap, theta)
        gain, spread = steady_state(self.walk_ratio[:, None, :])  # (A, 1, M)
        level = np.zeros(white.shape[:2] + white.shape[-1:]) if level is None else level
        v, level = innovations(white, measured, gain, level)
        spread = spread[:, :, None, :]  # (A, 1, 1, M)
        with np.errstate(invalid="ignore", over="ignore"):  # an infinite variance: no density, -inf
            terms = -0.5 * (np.square(v) / spread + np.log(spread) + _LOG_2PI + log_variance)
        terms = np.where(np.isfinite(terms), terms, -np.inf)
        return np.where(measured, terms, 0.0), level, np.where(measured, v / np.sqrt(spread), np.nan)

    def whiten(self, gap: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``L^-1 gap`` with ``L L^T = Sigma(theta)``, ``log L_mm^2`` and which entries were measured.

        The whitened gaps (A, N, ..., M) are independent N(0, 1) under the noise model (0 where not
        measured: the marginal of the measured ones); the log-variances ``log L_mm^2`` (A, N, ..., M),
        each residual's variance given the earlier ones, sum to ``log det Sigma``, and are ``inf``
        where a particle's theta is so far out that its covariance overflows (no density there).
        """
        gap = np.asarray(gap, float)
        missing = ~np.isfinite(gap)
        sigma = self.covariance_at(theta)
        if self.size == 1:
            variance = sigma[..., 0, 0]
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                white = gap / np.sqrt(variance)[..., None]
                log_variance = np.log(variance)[..., None]
            # an overflowing covariance (or gap) has no density, as with several residuals, never NaN
            bad = ~(np.isfinite(log_variance) & (np.isfinite(white) | missing))
            return (np.where(missing | bad, 0.0, white), np.where(bad, np.inf, np.where(missing, 0.0, log_variance)),
                    ~missing)
        if missing.any():  # the marginal of the measured ones: their rows and columns alone
            keep = ~missing
            sigma = np.where(keep[..., :, None] & keep[..., None, :], sigma,
                             np.where(np.eye(self.size, dtype=bool), 1.0, 0.0))
            gap = np.where(keep, gap, 0.0)
        # a particle whose theta is so far out that its covariance overflows has no density
        bad = ~np.all(np.isfinite(sigma), axis=(-2, -1)) | ~np.all(np.isfinite(np.where(missing, 0.0, gap)), axis=-1)
        sigma = np.where(bad[..., None, None], np.eye(self.size), sigma)
        chol = _cholesky(sigma)
        white = _forward(chol, np.where(bad[..., None], 0.0, gap))
        log_variance = 2 * np.log(np.diagonal(chol, axis1=-2, axis2=-1))
        return np.where(bad[..., None], 0.0, white), np.where(bad[..., None], np.inf, log_variance), ~missing


#: Up to this many residuals, the Cholesky factor and the forward substitution are written out over the
#: matrix entries, each step vectorized over the particles: numpy's batched LAPACK calls cost microseconds
#: per (tiny) matrix, which made them three quarters of a resample-move run.
SMALL = 5


def _factor(sigma: np.ndarray) -> np.ndarray | None:
    """Lower Cholesky factors of covariances (..., M, M), or None if one is not positive definite."""
    m = sigma.shape[-1]
    if m > SMALL:
        try:
            return np.linalg.cholesky(sigma)
        except np.linalg.LinAlgError:
            return None
    chol = np.zeros_like(sigma)
    for j in range(m):
        pivot = sigma[..., j, j] - np.sum(np.square(chol[..., j, :j]), axis=-1)
        if not np.all(pivot > 0):  # NaN included
            return None
        chol[..., j, j] = root = np.sqrt(pivot)
        for i in range(j + 1, m):
            chol[..., i, j] = (sigma[..., i, j] - np.sum(chol[..., i, :j] * chol[..., j, :j], axis=-1)) / root
    return chol


def _forward(chol: np.ndarray, gap: np.ndarray) -> np.ndarray:
    """``L^-1 gap`` (..., M) for lower-triangular ``chol`` (..., M, M)."""
    m = chol.shape[-1]
    if m > SMALL:
        return np.linalg.solve(chol, gap[..., None])[..., 0]
    z = np.empty(np.broadcast_shapes(gap.shape, chol.shape[:-1]))
    for i in range(m):
        z[..., i] = (gap[..., i] - np.sum(chol[..., i, :i] * z[..., :i], axis=-1)) / chol[..., i, i]
    return z


def _cholesky(sigma: np.ndarray) -> np.ndarray:
    """Cholesky factors of covariances (..., M, M); rounding that leaves one not quite positive
    definite is met with a ridge of a growing share of its trace."""
    for ridge in (0.0, 1e-12, 1e-9, 1e-6):
        lifted = sigma if ridge == 0.0 else (sigma + ridge * np.trace(sigma, axis1=-2, axis2=-1)[..., None, None]
                                             * np.eye(sigma.shape[-1]))
        chol = _factor(lifted)
        if chol is not None:
            return chol
    raise PrognosisError("a residual covariance is not positive definite even with a ridge of 1e-6 of its trace")


INDEPENDENT = 0.01  # least share of a combination of residuals' noise taken as its own (eigenvalue floor)


def _independent_share(correlation: np.ndarray) -> np.ndarray:
    """The correlation matrix with every eigenvalue at least :data:`INDEPENDENT`, back to a unit diagonal.

    More ARRs than sensors make some combination of the residuals noise-free on the healthy
    stretch (six ARRs over four sensors: a singular correlation).  Taken as exact, that combination
    would weigh any model error infinitely; at least a hundredth of its variance is its own.
    """
    np.fill_diagonal(correlation, 1.0)
    values, vectors = np.linalg.eigh(0.5 * (correlation + correlation.T))
    if values.min() >= INDEPENDENT:
        return correlation
    lifted = np.einsum("ij,j,kj->ik", vectors, np.maximum(values, INDEPENDENT), vectors)
    scale = np.sqrt(np.diagonal(lifted))
    return lifted / np.outer(scale, scale)


def healthy_noise(residuals: np.ndarray, sensitivities: np.ndarray | None = None) -> dict:
    """``C``, ``X`` and ``G`` of :class:`ResidualNoise` from a healthy stretch at the filter's step.

    ``residuals`` (K, M): the residuals on the healthy stretch, sampled every filter step;
    ``sensitivities`` (K, M): ``dh/dtheta`` of each ARR there (zero for an ARR blind to the candidate).
    The residuals are noise about zero: ``C`` is their covariance, with each variance the square of
    a robust std (a start-up spike does not inflate it).  A sensitivity follows the signals (a
    speed's set-point swing): its noise is read from fourth differences, in which a signal smooth
    over a few steps cancels while white noise keeps 70 times its variance; ``X`` alike, from the
    differences of both.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> e = rng.normal(0, 0.01, 4000)                      # a speed sensor's noise
    >>> speed = 30 + np.sin(np.arange(4000) / 300) + e     # a speed seen by it
    >>> r = 0.5 * e + rng.normal(0, 0.002, 4000)          # the residual, through the same sensor
    >>> noise = healthy_noise(r[:, None], speed[:, None])
    >>> [round(float(np.sqrt(noise[k][0, 0])), 4) for k in ("covariance", "growth")]
    [0.0054, 0.0098]
    >>> correlation = noise["cross"][0, 0] / np.sqrt(noise["covariance"][0, 0] * noise["growth"][0, 0])
    >>> round(float(correlation), 1)   # the residual's share of the speed noise, 0.005, over its std 0.0054
    0.9
    """
    residuals = np.asarray(residuals, float)
    keep = np.all(np.isfinite(residuals), axis=1)
    r = residuals[keep]
    if r.shape[0] < 3:
        raise PrognosisError(f"the healthy stretch has {r.shape[0]} usable filter steps; at least 3 are needed "
                             "to estimate the residuals' noise")
    centred = r - np.median(r, axis=0)
    robust = 1.4826 * np.median(np.abs(centred), axis=0)
    plain = np.std(centred, axis=0)
    std = np.where(robust > 0, robust, plain)
    std = np.where(std > 0, std, 1e-300)
    clipped = np.clip(centred, -5 * std, 5 * std)
    correlation = np.corrcoef(clipped, rowvar=False) if r.shape[1] > 1 else np.ones((1, 1))
    correlation = _independent_share(np.nan_to_num(np.atleast_2d(correlation), nan=0.0))
    out = {"covariance": correlation * np.outer(std, std)}
    if sensitivities is None:
        return out
    s = np.asarray(sensitivities, float)[keep]
    # fourth differences: a smooth signal (a set-point swing) nearly cancels, white noise keeps a
    # variance of C(8, 4) = 70 times its own
    order = min(DIFFERENCES, r.shape[0] - 1)
    differences = np.hstack([np.diff(r, order, axis=0), np.diff(s, order, axis=0)])
    # robust, as C is: a start-up transient (a circuit's ring as its source switches on) is no noise,
    # and its few large differences would make the sensitivity's noise a thousand times too large
    covariance = _robust_covariance(differences) / float(math.comb(2 * order, order))
    m = r.shape[1]
    out["growth"] = covariance[m:, m:]
    out["cross"] = covariance[:m, m:]
    return out


def _robust_covariance(x: np.ndarray) -> np.ndarray:
    """Covariance of the columns of ``x`` (K, P) about zero: each variance the square of a robust std (the
    median absolute value), the correlations those of the values clipped at 5 such stds.  A column
    that is all zero (an ARR blind to the candidate) has no variance and no correlation."""
    scale = 1.4826 * np.median(np.abs(x), axis=0)
    scale = np.where(scale > 0, scale, np.sqrt(np.mean(np.square(x), axis=0)))
    safe = np.where(scale > 0, scale, 1.0)
    clipped = np.clip(x / safe, -5.0, 5.0)
    second = clipped.T @ clipped / x.shape[0]
    norm = np.sqrt(np.diagonal(second))
    with np.errstate(invalid="ignore", divide="ignore"):
        correlation = np.nan_to_num(second / np.outer(norm, norm), nan=0.0)
    return correlation * np.outer(scale, scale)


WALK_DIFFERENCES = 4  # order of the differences an integral's walk is read from


def integral_walk(increments: np.ndarray) -> float:
    """The variance per filter step of the random walk that integrals of noisy signals add to a residual.

    ``increments`` (K,): the residual's change over each of K successive filter steps of a healthy
    stretch through its integrals alone, ``sum_i (dr/dI_i) (I_i(t_k+1) - I_i(t_k))``.  An integral of a
    signal carrying white noise of sd ``s`` at sample interval ``h`` drifts as a random walk of
    variance ``s^2 h Delta`` per filter step ``Delta``: its increments are the integrand's smooth part
    times ``Delta`` plus the walk's independent steps.  In fourth differences of the increments a
    smooth integrand nearly cancels while the walk's steps keep ``C(8, 4) = 70`` times their
    variance; their sd is taken robustly (a set-point step is one outlier, not a drift).  0 with
    fewer than six increments.

    Examples
    --------
    The integral of a speed that swings smoothly, read through noise of sd 0.01 at 1 kHz, every
    0.1 s: a walk of sd ``0.01 sqrt(1e-3 0.1) = 1e-4`` per step (read from 100 s to about 10 %).

    >>> rng = np.random.default_rng(0)
    >>> t = np.arange(0, 100, 1e-3)
    >>> speed = 3 + np.sin(t) + rng.normal(0, 0.01, t.size)
    >>> integral = np.cumsum(speed) * 1e-3
    >>> round(float(np.sqrt(integral_walk(np.diff(integral[::100])))), 5)
    0.00011
    """
    increments = np.asarray(increments, float)
    increments = increments[np.isfinite(increments)]
    if increments.size < WALK_DIFFERENCES + 2:
        return 0.0
    d = np.diff(increments, WALK_DIFFERENCES)
    robust = 1.4826 * np.median(np.abs(d - np.median(d)))
    return float(robust ** 2 / math.comb(2 * WALK_DIFFERENCES, WALK_DIFFERENCES))


def _batch_variance(gaps: np.ndarray, size: int) -> np.ndarray:
    """``n mean^2`` averaged over the most recent whole batches of ``size`` steps (A, M): 1 for white gaps."""
    assets, steps, m = gaps.shape
    count = steps // size
    batches = gaps[:, steps - count * size:].reshape(assets, count, size, m)
    seen = np.sum(np.isfinite(batches), axis=2)
    means = np.nansum(batches, axis=2) / np.maximum(seen, 1)
    # a batch's mean over n measured steps has variance 1 / n for white gaps: n mean^2 is 1 on average
    return np.nanmean(np.where(seen > 0, seen * np.square(means), np.nan), axis=1)


def information_excess(gaps: np.ndarray) -> np.ndarray:
    """How many times the likelihood overstates what the residuals know: their long-run variance, at least 1.

    ``gaps`` (A, K, M): the residuals' gaps to a hypothesis' prediction at its best estimate,
    standardized by the noise's sd, over K filter steps (NaN where not measured).  If the noise model
    were right they would be white N(0, 1) and every step would add its full information.  A model
    error that the noise model does not know of (a derivative's lag, a friction law's shape, a law
    that bends away) leaves gaps that are too large or that persist over many steps; the posterior
    from a likelihood taken as white is then too narrow by the factor returned here, the long-run
    variance ``lim K Var(mean of K gaps)``, read by batch means about zero (not about their own mean:
    a persistent offset is part of the excess), of ``ceil(sqrt(K))`` steps and, once that is shorter,
    of ``K / BATCHES`` steps (an offset that wanders over tens of steps, as an integral's drift does,
    averages out of short batches), or their mean square if larger (it has more degrees of freedom).
    White gaps come out at about 1.1-1.25 on average (the largest of several noisy estimates).  Dividing the
    log-likelihood by it is the sandwich correction of a misspecified likelihood.  One per residual
    and asset (A, M): whitened residuals carry independent information, so each is corrected by its
    own; 1 with fewer than :data:`MIN_STEPS` steps.

    Examples
    --------
    White gaps know what they say; an offset of one sd that persists, or gaps of twice the sd, do not:

    >>> rng = np.random.default_rng(0)
    >>> white = rng.standard_normal((1, 400, 1))
    >>> information_excess(np.concatenate([white, white + 1.0, 2.0 * white])).round(1).tolist()
    [[1.1], [46.8], [4.6]]
    """
    gaps = np.asarray(gaps, float)
    assets, steps, m = gaps.shape
    if steps < MIN_STEPS:
        return np.ones((assets, m))
    with np.errstate(invalid="ignore"):
        # batch means see persistence but have few degrees of freedom; the plain mean square has many:
        # the larger of them, so that gaps merely too wide are not missed by a lucky draw of batches.
        # Batches of sqrt(K) steps, and of K / BATCHES steps once those are longer: an offset that
        # wanders over tens of steps (an integral's drift) averages out of short batches
        variance = np.nanmean(np.square(gaps), axis=1)
        short = math.ceil(math.sqrt(steps))
        for size in (short, *((steps // BATCHES,) if steps // BATCHES > short else ())):
            variance = np.fmax(variance, _batch_variance(gaps, size))
    # an ARR never measured in the history says nothing: 1, as does every variance below it
    return np.fmax(np.where(np.isfinite(variance), variance, 1.0), 1.0)
