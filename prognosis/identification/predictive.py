"""Long-term feature prediction with the uncertainty of the identified parameters (Gasperin et al. (2011), section 5.2).

:func:`~prognosis.identification.predict_feature` propagates the noises of one identified model.  Over a
horizon of a few window lengths the error of the parameters dominates: a pole error of 0.005 grows to a
factor ``exp(0.005 * 504) = 12`` over 504 steps.  This module samples the window's posterior over the
model and predicts with the posterior predictive distribution.

Model (one output, ``n`` states, ``r`` inputs): the steady-state innovations form in observer canonical
coordinates, one parameter vector per input-output behaviour::

    x_{t+1} = A x_t + B u_t + K e_t,    y_t = x_t[0] + D u_t + e_t,    e_t ~ N(0, sigma^2),
    A = companion(a):  A[:, 0] = a,  A[i, i+1] = 1   (characteristic polynomial z^n - a_1 z^(n-1) - ... - a_n),
    F = A - K e_1^T = companion(f)                  (the one-step predictor; f = a - K).

Given the two polynomials ``theta = (a, f)`` the predictor output is *linear* in
``beta = (x_1, B, D)`` (``n + n r + r`` entries)::

    y_t = g_t(theta) + phi_t(theta)^T beta + e_t,

so ``beta`` and ``sigma`` are integrated out in closed form and only ``2 n`` parameters are sampled.
An input declared *direct* (``direct_inputs``) has no column in ``B``: it acts on the output through ``D``
only, which shortens ``beta`` by ``n`` entries per such input.

Prior
    ``p(sigma) ~ 1/sigma``; for ``beta`` given ``theta``, Jeffreys' ``|Phi^T Phi|^(1/2)`` (``Phi`` stacks the
    ``phi_t``): it makes the result independent of how ``beta`` is parametrized (``x_1`` and ``B`` of a
    pole near 1 have no natural scale).  ``theta`` is uniform over ``rho(A) <= max_radius`` and a stable
    predictor ``rho(F) < 1``.  Then, with ``nu = N - dim(beta)``::

        p(theta | y) ~ RSS(theta)^(-nu / 2),
        y_{T+h} | theta, y ~ Student t_nu(g_h + G_h beta_hat,
                                          s^2 (1 + sum_{i<h-1} (e_1^T A^i K)^2 + G_h (Phi^T Phi)^-1 G_h^T)),

    ``RSS`` the least-squares residual, ``beta_hat`` the estimate, ``s^2 = RSS / nu``, ``G_h`` the sensitivity
    of the future mean to ``beta``.

Sampler
    Tempering sequential Monte Carlo (Del Moral, Doucet and Jasra 2006): particles from the prior, the
    exponent of the likelihood raised from 0 to 1 in steps that keep the effective sample size at
    ``target_ess``, systematic resampling, and random-walk Metropolis moves scaled by the particles'
    covariance.  All in log-weights, vectorized over particles.

Example
-------
>>> rng = np.random.default_rng(0)
>>> u = rng.uniform(0.0, 2.0, (150, 1))
>>> x, y = 0.0, np.empty(150)
>>> for t in range(150):                       # x_{t+1} = 0.9 x_t + 0.2 u_t + w, y = x + v
...     y[t] = x + 0.05 * rng.standard_normal()
...     x = 0.9 * x + 0.2 * u[t, 0] + 0.02 * rng.standard_normal()
>>> post = sample_posterior(y, u, n_states=1, particles=400, seed=1)
>>> bool(0.85 < np.median(post.spectral_radii) < 0.95)
True
>>> p = post.predict(np.ones((30, 1)))       # a constant load: towards 0.2 / (1 - 0.9) = 2
>>> bool(np.all(p.lower < p.mean) and np.all(p.mean < p.upper)), bool(1.8 < p.mean[-1] < 2.2)
(True, True)
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from math import comb

import numpy as np
from numpy.typing import ArrayLike
from scipy import special

from bondgraph.errors import PHMWarning

from ..resampling import systematic
from .data import check_data, check_future_inputs
from ..errors import PrognosisError

__all__ = ["PosteriorPrediction", "SamplerWarning", "WindowPosterior", "sample_posterior", "window_log_posterior"]


class SamplerWarning(PHMWarning, RuntimeWarning):
    """The tempering sampler degenerated (few distinct particles or moves rarely accepted)."""


# ------------------------------------------------------------------------------------- the regression

@dataclass(frozen=True)
class _Regression:
    """Per particle: the window regression ``z = Phi beta + e`` in QR form and the predictor state."""

    log_posterior: np.ndarray  # (M,) -nu/2 log RSS, -inf outside the prior
    R: np.ndarray  # (M, p, p) upper triangular, Phi = Q R
    qz: np.ndarray  # (M, p) Q^T z
    rss: np.ndarray  # (M,)
    state: np.ndarray  # (M, n, 1 + p) x_{T+1|T} = state[..., 0] + state[..., 1:] @ beta
    nu: int


def _companion_radius(c: np.ndarray) -> np.ndarray:
    """Spectral radius of companion(c) for each row of ``c`` (M, n)."""
    m, n = c.shape
    comp = np.zeros((m, n, n))
    comp[:, :, 0] = c
    comp[:, np.arange(n - 1), np.arange(1, n)] = 1.0
    with np.errstate(all="ignore"):
        return np.abs(np.linalg.eigvals(np.nan_to_num(comp, nan=np.inf))).max(axis=1) if m else np.zeros(0)


@dataclass(frozen=True)
class _Layout:
    """Where ``beta = (x_1, B, D)`` sits in the ``1 + p`` columns of a regression row (column 0 the known part).

    Only the inputs in ``dynamic`` drive the state: ``B`` is (n, len(dynamic)), ``D`` is (r,).
    """

    direct: tuple[int, ...]  # the inputs that act through D only
    dynamic: np.ndarray
    cB: np.ndarray  # (n, len(dynamic)) column of each entry of B
    cD: np.ndarray  # (r,) column of each entry of D
    p: int  # n + n len(dynamic) + r entries of beta


def _layout(n: int, r: int, direct_inputs: Sequence[int]) -> _Layout:
    """The regression's layout for ``n`` states and ``r`` inputs, ``direct_inputs`` checked (named when bad)."""
    direct = tuple(int(j) for j in direct_inputs)
    for j in direct:
        if not 0 <= j < r:
            raise PrognosisError(f"direct_inputs names input column {j}, but u has {r} columns")
    if len(set(direct)) != len(direct):
        raise PrognosisError(f"direct_inputs repeats an input column: {list(direct_inputs)}")
    dynamic = np.array([j for j in range(r) if j not in direct], dtype=int)
    rd = dynamic.size
    return _Layout(direct, dynamic, 1 + n + np.arange(n * rd).reshape(n, rd), 1 + n + n * rd + np.arange(r),
                   n + n * rd + r)


def _shift(poly: np.ndarray, state: np.ndarray) -> np.ndarray:
    """``companion(poly) @ state`` for each particle: (M, n), (M, n, c) -> (M, n, c)."""
    out = np.empty_like(state)
    out[:, :-1] = poly[:, :-1, None] * state[:, :1] + state[:, 1:]
    out[:, -1] = poly[:, -1, None] * state[:, 0]
    return out


def _regression(theta: np.ndarray, y: np.ndarray, u: np.ndarray, max_radius: float,
                layout: _Layout) -> _Regression:
    """Run the predictor of every particle over the window and solve its regression."""
    m, n2 = theta.shape
    n, N, p = n2 // 2, y.size, layout.p
    a, f = theta[:, :n], theta[:, n:]
    k = a - f
    cB, cD = layout.cB, layout.cD
    # per-step inputs of the recursion x_{t+1} = F x_t + (B - K D) u_t + K y_t, in the 1 + p layout
    known = np.zeros((N, 1 + p))  # multiplied by K: [y_t, 0 (x_1, B), -u_t (D)]
    known[:, 0], known[:, cD] = y, -u
    drive = np.zeros((N, n, 1 + p))  # B u_t: row i gets u_t in the columns of B[i]
    for i in range(n):
        drive[:, i, cB[i]] = u[:, layout.dynamic]
    output = np.zeros((N, 1 + p))  # y_hat_t = x_t[0] + D u_t
    output[:, cD] = u

    state = np.zeros((m, n, 1 + p))
    state[:, :, 1:1 + n] = np.eye(n)
    rows = np.empty((m, N, 1 + p))
    with np.errstate(all="ignore"):
        for t in range(N):
            rows[:, t] = state[:, 0] + output[t]
            state = _shift(f, state) + k[:, :, None] * known[t] + drive[t]
        z = y - rows[:, :, 0]
        phi = rows[:, :, 1:]
        finite = np.isfinite(phi).all(axis=(1, 2)) & np.isfinite(z).all(axis=1)
        phi = np.where(finite[:, None, None], phi, 0.0)
        z = np.where(finite[:, None], z, 0.0)
        Q, R = np.linalg.qr(phi)
        qz = (z[:, None, :] @ Q)[:, 0]
        residual = z - (Q @ qz[..., None])[..., 0]
        rss = np.einsum("mt,mt->m", residual, residual)
        d = np.abs(np.diagonal(R, axis1=1, axis2=2))
        full_rank = d.min(axis=1) > 1e-13 * d.max(axis=1)
        log_post = -0.5 * (N - p) * np.log(rss)
    inside = (_companion_radius(a) <= max_radius) & (_companion_radius(f) < 1.0)
    ok = finite & full_rank & inside & np.isfinite(log_post) & (rss > 0)
    return _Regression(np.where(ok, log_post, -np.inf), R, qz, rss, state, N - p)


def window_log_posterior(theta: ArrayLike, y: ArrayLike, u: ArrayLike | None, *, max_radius: float = 1.05,
                         direct_inputs: Sequence[int] = ()) -> np.ndarray:
    """Log posterior density (up to a constant) of ``theta = (a, f)`` for a population of particles.

    ``theta`` is (M, 2 n): the coefficients of the characteristic polynomials of ``A`` and of the
    predictor ``F = A - K C`` (``z^n - c_1 z^(n-1) - ... - c_n``).  The value is ``-nu/2 log RSS(theta)``
    inside the prior's support and ``-inf`` outside it (see the module docstring).  The input columns in
    ``direct_inputs`` act on the output through ``D`` only (their column of ``B`` is zero).

    Example
    -------
    >>> rng = np.random.default_rng(0)
    >>> y = np.cumsum(rng.standard_normal(100)) * 0.1      # a random walk: A = 1, F = 0
    >>> lp = window_log_posterior([[1.0, 0.0], [0.5, 0.0], [1.0, 1.0]], y, None)
    >>> bool(lp[0] > lp[1]), float(lp[2])                   # rho(F) = 1 is outside the prior
    (True, -inf)
    """
    y, u = check_data(y, u)
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    if y.shape[1] != 1:
        raise PrognosisError(f"the window posterior handles one output; y has {y.shape[1]} columns")
    if theta.shape[1] % 2 or theta.shape[1] == 0:
        raise PrognosisError(f"theta must have 2 n columns (a and f), got {theta.shape[1]}")
    layout = _layout(theta.shape[1] // 2, u.shape[1], direct_inputs)
    return _regression(theta, y[:, 0], u, max_radius, layout).log_posterior


# -------------------------------------------------------------------------------------- the sampler

@dataclass(frozen=True)
class PosteriorPrediction:
    """Posterior predictive of the feature ``y_{T+1..T+H}``: a mixture of Student t over the particles.

    Attributes
    ----------
    mean, median, lower, upper : ndarray (H,)
        Mixture mean, median and the equal-tailed ``level`` interval.
    level : float

    Example
    -------
    Returned by :meth:`WindowPosterior.predict`; :meth:`coverage` counts the later values inside:

    >>> p = PosteriorPrediction(np.zeros(3), np.zeros(3), -np.ones(3), np.ones(3), 0.95)
    >>> p.coverage([0.5, 2.0, np.nan])
    0.5
    """

    mean: np.ndarray
    median: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    level: float

    def coverage(self, y: ArrayLike) -> float:
        """Fraction of the observed ``y`` (the first ``len(y)`` leads; NaN ignored) inside the interval."""
        y = np.asarray(y, dtype=float).ravel()
        lo, hi = self.lower[:y.size], self.upper[:y.size]
        seen = ~np.isnan(y)
        return float(np.mean((y[seen] >= lo[seen]) & (y[seen] <= hi[seen])))


@dataclass(frozen=True)
class WindowPosterior:
    """Equally weighted particles ``theta = (a, f)`` from the window posterior, and the window data.

    Attributes
    ----------
    theta : ndarray (M, 2 n)
    log_posterior : ndarray (M,)
    log_evidence : float
        Sum over the tempering stages of the log mean incremental weight (up to the prior's constant).
    stages : int
    acceptance : ndarray
        Acceptance rate of every Metropolis move.
    direct_inputs : tuple of int
        Input columns that act on the output only through ``D``.

    Example
    -------
    Returned by :func:`sample_posterior`; white noise around a level set by the input:

    >>> rng = np.random.default_rng(2)
    >>> u = rng.uniform(1.0, 3.0, (100, 1))
    >>> post = sample_posterior(2.0 * u[:, 0] + 0.1 * rng.standard_normal(100), u, 1, particles=200, seed=0)
    >>> post.theta.shape, post.n_states, bool(np.isfinite(post.log_evidence))
    ((200, 2), 1, True)
    """

    theta: np.ndarray
    log_posterior: np.ndarray
    log_evidence: float
    stages: int
    acceptance: np.ndarray
    max_radius: float
    y: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)
    scale: np.ndarray = field(repr=False)  # the inputs are divided by it (per column)
    direct_inputs: tuple[int, ...] = ()

    @property
    def n_states(self) -> int:
        """Model order ``n``: half the columns of ``theta = (a, f)``."""
        return self.theta.shape[1] // 2

    @property
    def spectral_radii(self) -> np.ndarray:
        """``rho(A)`` of every particle."""
        return _companion_radius(self.theta[:, :self.n_states])

    def predict(self, u_future: ArrayLike | None, level: float = 0.95, *, steps: int | None = None,
                draws: int | None = 500, seed: int = 0) -> PosteriorPrediction:
        """Posterior predictive of ``y_{T+1..T+H}`` under the known future inputs (row ``h - 1`` = ``u_{T+h}``).

        ``draws`` particles (all if None) are used; the interval solves the mixture's CDF by bisection.

        Example
        -------
        >>> rng = np.random.default_rng(0)
        >>> u = rng.uniform(1.0, 2.0, (120, 1))
        >>> y = 0.5 * u[:, 0] + 0.1 * rng.standard_normal(120)    # y = D u + e, no dynamics
        >>> post = sample_posterior(y, u, n_states=1, particles=300, seed=0)
        >>> p = post.predict(np.ones((5, 1)))
        >>> bool(np.all(np.abs(p.median - 0.5) < 0.05)), bool(np.all(p.upper - p.lower > 0.3))
        (True, True)
        """
        if not 0.0 < level < 1.0:
            raise PrognosisError(f"level must be in (0, 1), got {level}")
        r = self.u.shape[1]
        uf = check_future_inputs(u_future, steps, r, "predict") / self.scale
        theta = self.theta
        if draws is not None and draws < theta.shape[0]:
            theta = theta[np.random.default_rng(seed).choice(theta.shape[0], draws, replace=False)]
        layout = _layout(self.n_states, r, self.direct_inputs)
        reg = _regression(theta, self.y, self.u, self.max_radius, layout)
        loc, scale = _future(theta, reg, uf, layout)
        lower, median, upper = (_mixture_quantile(q, loc, scale, reg.nu) for q in
                                (0.5 * (1.0 - level), 0.5, 0.5 * (1.0 + level)))
        return PosteriorPrediction(loc.mean(axis=1), median, lower, upper, level)


def _future(theta: np.ndarray, reg: _Regression, uf: np.ndarray, layout: _Layout
            ) -> tuple[np.ndarray, np.ndarray]:
    """Student t location and scale (H, M) of ``y_{T+h}`` for each particle."""
    n = theta.shape[1] // 2
    a, k = theta[:, :n], theta[:, :n] - theta[:, n:]
    cB, cD = layout.cB, layout.cD
    beta = np.linalg.solve(reg.R, reg.qz[..., None])[..., 0]
    s2 = reg.rss / reg.nu
    R_inv = np.linalg.inv(reg.R)  # (Phi^T Phi)^-1 = R^-1 R^-T
    state, impulse, noise = reg.state, k.copy(), np.ones(theta.shape[0])
    H = uf.shape[0]
    loc, var = np.empty((H, theta.shape[0])), np.empty((H, theta.shape[0]))
    for h in range(H):
        row = state[:, 0].copy()
        row[:, cD] += uf[h]
        G = row[:, 1:]
        loc[h] = row[:, 0] + np.einsum("mi,mi->m", G, beta)
        w = (G[:, None, :] @ R_inv)[:, 0]  # G (Phi^T Phi)^-1 G^T = |G R^-1|^2
        var[h] = s2 * (noise + np.einsum("mi,mi->m", w, w))
        noise = noise + impulse[:, 0] ** 2  # e_1^T A^i K, i = 0..h-1
        impulse = _shift(a, impulse[..., None])[..., 0]
        state = _shift(a, state)
        for i in range(n):
            state[:, i, cB[i]] += uf[h, layout.dynamic]
    return loc, np.sqrt(var)


def _mixture_quantile(q: float, loc: np.ndarray, scale: np.ndarray, nu: int, tol: float = 1e-10) -> np.ndarray:
    """Per row ``h``, the ``q`` quantile of the equal-weight mixture of ``t_nu(loc[h, j], scale[h, j])``.

    Newton's method on the mixture CDF, safeguarded by bisection inside the bracket of the components'
    own quantiles (the mixture quantile lies between them).
    """
    single = loc + special.stdtrit(nu, q) * scale
    lo, hi = single.min(axis=1), single.max(axis=1)
    x = np.median(single, axis=1)
    log_norm = special.gammaln(0.5 * (nu + 1)) - special.gammaln(0.5 * nu) - 0.5 * np.log(nu * np.pi)
    active = np.arange(x.size)  # rows not yet solved
    for _ in range(200):
        z = (x[active, None] - loc[active]) / scale[active]
        gap = special.stdtr(nu, z).mean(axis=1) - q
        done = np.abs(gap) <= tol
        active, z, gap = active[~done], z[~done], gap[~done]
        if not active.size:
            break
        density = (np.exp(log_norm - 0.5 * (nu + 1) * np.log1p(z * z / nu)) / scale[active]).mean(axis=1)
        lo[active] = np.where(gap < 0, x[active], lo[active])
        hi[active] = np.where(gap > 0, x[active], hi[active])
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = x[active] - gap / density
        inside = (newton > lo[active]) & (newton < hi[active])
        x[active] = np.where(inside, newton, 0.5 * (lo[active] + hi[active]))
    return x


def _prior_draws(rng: np.random.Generator, count: int, n: int, max_radius: float) -> np.ndarray:
    """Uniform draws of ``(a, f)`` over the prior's support, by rejection from the bounding box."""
    # |c_i| <= binom(n, i) rho^i for a polynomial with roots inside radius rho
    box_a = np.array([comb(n, i) * max_radius ** i for i in range(1, n + 1)])
    box_f = np.array([comb(n, i) for i in range(1, n + 1)], dtype=float)
    kept, total = [], 0
    for _ in range(1000):
        a = rng.uniform(-box_a, box_a, (4 * count, n))
        f = rng.uniform(-box_f, box_f, (4 * count, n))
        ok = (_companion_radius(a) <= max_radius) & (_companion_radius(f) < 1.0)
        kept.append(np.hstack([a, f])[ok])
        total += int(ok.sum())
        if total >= count:
            return np.vstack(kept)[:count]
    raise RuntimeError("could not draw from the prior")  # pragma: no cover - the support is not small


def sample_posterior(y: ArrayLike, u: ArrayLike | None, n_states: int, *, particles: int = 2000,
                     moves: int = 5, target_ess: float = 0.7, max_radius: float = 1.05,
                     direct_inputs: Sequence[int] = (), seed: int | None = 0) -> WindowPosterior:
    """Sample the posterior of the window's model by tempering sequential Monte Carlo.

    Parameters
    ----------
    y : array (N,) or (N, 1)
        The feature over the identification window (finite).
    u : array (N, r) or None
        The known inputs over the window.
    n_states : int
    particles, moves : int
        Population size and Metropolis moves after each tempering step.
    target_ess : float
        Effective sample size, as a fraction of ``particles``, kept at each tempering step.
    max_radius : float
        Prior bound on ``rho(A)``.
    direct_inputs : sequence of int
        Input columns known to act on the output only through the feedthrough ``D`` (their column of ``B``
        is fixed at zero), e.g. a temperature that changes a vibration feature's gain but not the wear.
        Declare them when it is true: a slowly varying input allowed into the state of a mode near the
        unit circle acts as a free drift and biases the mode's growth rate low (as a trend term does in a
        unit-root regression), which is what a long-term prediction depends on.

    Returns
    -------
    WindowPosterior
        ``particles`` equally weighted draws; ``spectral_radii`` gives the posterior of ``rho(A)``.

    Example
    -------
    A first-order response to a random load, ``y_t = 0.8 y_{t-1} + 0.2 u_{t-1}`` plus noise:

    >>> rng = np.random.default_rng(4)
    >>> u = rng.uniform(0.0, 1.0, (200, 1))
    >>> y = np.zeros(200)
    >>> for t in range(1, 200):
    ...     y[t] = 0.8 * y[t - 1] + 0.2 * u[t - 1, 0] + 0.01 * rng.standard_normal()
    >>> post = sample_posterior(y, u, 1, particles=300, seed=0)
    >>> bool(abs(np.median(post.spectral_radii) - 0.8) < 0.05)
    True
    """
    y, u = check_data(y, u)
    if y.shape[1] != 1:
        raise PrognosisError(f"the window posterior handles one output; y has {y.shape[1]} columns")
    if not np.all(np.isfinite(y)) or not np.all(np.isfinite(u)):
        raise PrognosisError("the window posterior needs a complete window: y and u must be finite")
    if n_states < 1:
        raise PrognosisError(f"n_states must be at least 1, got {n_states}")
    if not 0.0 < target_ess < 1.0:
        raise PrognosisError(f"target_ess must be in (0, 1), got {target_ess}")
    if moves < 1 or particles < 10:
        raise PrognosisError(f"need at least 1 move and 10 particles, got moves={moves}, particles={particles}")
    layout = _layout(n_states, u.shape[1], direct_inputs)
    p = layout.p
    if y.shape[0] <= p + 2:
        raise PrognosisError(f"a window of {y.shape[0]} samples is too short for {p} linear parameters")
    scale = np.sqrt(np.mean(u ** 2, axis=0)) if u.shape[1] else np.ones(0)
    scale = np.where(scale > 0, scale, 1.0)  # the inputs are scaled for the conditioning of the regression
    y, u = y[:, 0], u / scale
    rng = np.random.default_rng(seed)
    theta = _prior_draws(rng, particles, n_states, max_radius)
    log_lik = _regression(theta, y, u, max_radius, layout).log_posterior
    if not np.any(np.isfinite(log_lik)):
        raise PrognosisError("the window regression is rank deficient for every prior draw: the inputs do not excite "
                             f"the {p} linear parameters (a constant input column duplicates the initial state?)")
    exponent, log_evidence, stages, acceptance = 0.0, 0.0, 0, []
    step = 2.38 / np.sqrt(theta.shape[1])
    while exponent < 1.0:
        nxt = _next_exponent(log_lik, exponent, target_ess)
        increment = _tempered(log_lik, nxt - exponent)
        top = increment.max()
        log_evidence += top + np.log(np.mean(np.exp(increment - top)))
        weights = np.exp(increment - top)
        index = systematic(weights / weights.sum(), rng)
        theta, log_lik, exponent, stages = theta[index], log_lik[index], nxt, stages + 1
        chol = np.linalg.cholesky(np.cov(theta.T) + 1e-14 * np.eye(theta.shape[1]))
        for _ in range(moves):
            proposal = theta + step * rng.standard_normal(theta.shape) @ chol.T
            log_lik_p = _regression(proposal, y, u, max_radius, layout).log_posterior
            with np.errstate(invalid="ignore"):
                accept = np.log(rng.random(theta.shape[0])) < exponent * (log_lik_p - log_lik)
            theta[accept], log_lik[accept] = proposal[accept], log_lik_p[accept]
            acceptance.append(float(accept.mean()))
            step *= np.exp(acceptance[-1] - 0.25)  # aim at 25 % acceptance
    acceptance = np.array(acceptance)
    distinct = np.unique(theta, axis=0).shape[0]
    if distinct < 0.2 * particles or acceptance[-moves:].mean() < 0.02:
        warnings.warn(f"the window posterior sampler degenerated: {distinct} distinct particles of {particles}, "
                      f"last acceptance {acceptance[-moves:].mean():.3f}", SamplerWarning, stacklevel=2)
    return WindowPosterior(theta, log_lik, float(log_evidence), stages, acceptance, max_radius, y, u, scale,
                          layout.direct)


def _tempered(log_lik: np.ndarray, delta: float) -> np.ndarray:
    """``delta * log_lik`` with ``-inf`` kept (and never ``0 * -inf = nan``)."""
    return np.where(np.isfinite(log_lik), delta * np.where(np.isfinite(log_lik), log_lik, 0.0), -np.inf)


def _next_exponent(log_lik: np.ndarray, exponent: float, target_ess: float) -> float:
    """The largest exponent in ``(exponent, 1]`` whose incremental weights keep ESS >= target (bisection)."""
    def ess(b: float) -> float:
        w = _tempered(log_lik, b - exponent)
        w = np.exp(w - w.max())
        return float(w.sum() ** 2 / (w ** 2).sum() / w.size)

    if ess(1.0) >= target_ess:
        return 1.0
    lo, hi = exponent, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ess(mid) >= target_ess else (lo, mid)
    return max(lo, exponent + 1e-12)
