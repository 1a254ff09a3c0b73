"""Monte Carlo RUL from a Gaussian state estimate (Rodriguez Obando et al. (2021), section 5.1, eq. 46).

At the prediction time ``t_0`` the deterioration states (e.g. ``alpha, m, D``)
are drawn from the estimate ``N(x^, P)`` -- optionally kept inside bounds such
as the Chebyshev box of :mod:`prognosis.lifecontrol.chebyshev` -- and each draw is
propagated with the deterioration dynamics under the planned operation (the
decision ``theta``) until it fails.  A failure margin ``g(x)`` is positive while
the system works; the failure time of a draw is the first zero of ``g`` along
its trajectory, located by linear interpolation inside the integration step.
The failure times form the predicted RUL distribution (Fig. 3, 9, 11, 13).

All draws are integrated together (classical RK4, vectorized over samples).

Example
-------
A coefficient decaying as ``da/dt = -m`` from ``a = 1`` with ``m ~ N(0.1, 0.01^2)``
fails at ``a = 0.5`` after ``0.5 / m``:

>>> rul = monte_carlo_rul(lambda x, t: np.vstack([-x[1], 0 * x[1]]), [1.0, 0.1], np.diag([0.0, 1e-4]),
...                       lambda x: x[0] - 0.5, horizon=20.0, dt=0.1, n_samples=2000, seed=1)
>>> abs(rul.median - 5.0) < 0.05, rul.probability_before(5.0) > 0.45
(True, True)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..rul import RULDistribution
from ..errors import PrognosisError

__all__ = ["monte_carlo_rul", "sample_gaussian"]


def sample_gaussian(mean, covariance, n: int, rng: np.random.Generator, lower=None, upper=None,
                    max_rounds: int = 100) -> np.ndarray:
    """``n`` draws (d, n) of ``N(mean, covariance)`` kept inside ``[lower, upper]`` by redrawing.

    A zero-variance direction is allowed (the factor comes from ``eigh``).

    Parameters
    ----------
    mean : array (d,)
    covariance : array (d, d), symmetric positive semi-definite
    n : int
        Number of draws.
    rng : numpy.random.Generator
    lower, upper : array (d,), optional
        Bounds every draw must respect (``-inf``/``inf`` for none); the mean must lie inside.
    max_rounds : int
        Redraw rounds before giving up with a ``RuntimeError``.

    Returns
    -------
    ndarray (d, n)

    Examples
    --------
    >>> x = sample_gaussian([0.0, 1.0], np.diag([1.0, 0.0]), 1000, np.random.default_rng(0), lower=[0.0, -np.inf])
    >>> x.shape, bool(x[0].min() >= 0.0), bool(np.all(x[1] == 1.0))
    ((2, 1000), True, True)
    """
    mean = np.asarray(mean, float).reshape(-1)
    d = mean.size
    p = np.asarray(covariance, float).reshape(d, d)
    # factor the correlation matrix: variances spanning 1e-14 to 1e9 (m and D) would drown the
    # small ones in the round-off of a factorization of P itself
    std = np.sqrt(np.clip(np.diag(p), 0.0, None))
    scale = np.where(std > 0, std, 1.0)
    correlation = 0.5 * (p + p.T) / np.outer(scale, scale)
    values, vectors = np.linalg.eigh(correlation)
    if values.min() < -1e-9 * max(values.max(), 1e-300):
        raise PrognosisError("covariance is not positive semi-definite")
    factor = scale[:, None] * vectors * np.sqrt(np.clip(values, 0.0, None))
    lo = np.full(d, -np.inf) if lower is None else np.asarray(lower, float).reshape(d)
    hi = np.full(d, np.inf) if upper is None else np.asarray(upper, float).reshape(d)
    if np.any(mean < lo) or np.any(mean > hi):
        raise PrognosisError(f"the mean {mean.tolist()} is outside the bounds [{lo.tolist()}, {hi.tolist()}]")
    out = np.empty((d, n))
    missing = np.arange(n)
    for _ in range(max_rounds):
        draws = mean[:, None] + factor @ rng.standard_normal((d, missing.size))
        inside = np.all((draws >= lo[:, None]) & (draws <= hi[:, None]), axis=0)
        out[:, missing[inside]] = draws[:, inside]
        missing = missing[~inside]
        if missing.size == 0:
            return out
    raise RuntimeError(f"{missing.size} of {n} draws still outside the bounds after {max_rounds} rounds")


def monte_carlo_rul(rates: Callable, mean, covariance, margin: Callable, *, horizon: float, dt: float,
                    origin: float = 0.0, n_samples: int = 1000, lower=None, upper=None, seed=None,
                    keep: int = 0) -> RULDistribution:
    """Predict the RUL distribution by propagating draws of the estimate (eq. 46).

    Parameters
    ----------
    rates : callable ``rates(x, t) -> dx/dt``
        Deterioration dynamics on columns ``x`` (d, N) at absolute time ``t``.
    mean, covariance : the estimate of the deterioration states at ``origin``.
    margin : callable ``margin(x) -> (N,)``
        Positive while working; failure at its first zero.
    horizon : float
        Longest RUL looked for; draws still working get ``inf``.
    dt : float
        Integration step.
    n_samples : int
    lower, upper : array (d,), optional
        Bounds the draws must respect (e.g. the Chebyshev box, ``alpha >= 0``).
    seed : int or Generator
        The same seed gives the same draws (common random numbers across decisions).
    keep : int
        Number of trajectories to return (for plots).

    Returns
    -------
    RULDistribution

    Examples
    --------
    ``da/dt = -m`` from ``a = 1`` with ``m ~ N(0.1, 0.01^2)`` kept positive;
    failure at ``a = 0.5``, that is after ``0.5 / m``:

    >>> rul = monte_carlo_rul(lambda x, t: np.vstack([-x[1], 0 * x[1]]), [1.0, 0.1], np.diag([0.0, 1e-4]),
    ...                       lambda x: x[0] - 0.5, horizon=20.0, dt=0.1, n_samples=200, seed=1,
    ...                       lower=[-np.inf, 0.0], keep=3)
    >>> rul.samples.shape, rul.initial.shape, rul.trajectories.shape[1:]
    ((200,), (2, 200), (2, 3))
    >>> bool(4.5 < rul.median < 5.5), bool(np.all(np.isfinite(rul.samples)))
    (True, True)
    >>> bool(np.allclose(rul.samples, 0.5 / rul.initial[1]))   # exact but for the interpolated crossing
    True
    """
    if not dt > 0 or not horizon > 0:
        raise PrognosisError(f"dt and horizon must be positive, got dt={dt!r}, horizon={horizon!r}")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    x = sample_gaussian(mean, covariance, n_samples, rng, lower, upper)
    initial = x.copy()
    rul = np.full(n_samples, np.inf)
    g = np.asarray(margin(x), float)
    rul[g <= 0] = 0.0
    alive = g > 0
    steps = int(np.ceil(horizon / dt))
    times, kept = [origin], [x[:, :keep].copy()]
    t = origin
    for _ in range(steps):
        if not alive.any():
            break
        x = _rk4(rates, x, t, dt)
        t += dt
        g_next = np.asarray(margin(x), float)
        crossed = alive & ~(g_next > 0)  # NaN counts as failed
        if crossed.any():
            fraction = np.where(np.isfinite(g_next[crossed]), g[crossed] / (g[crossed] - g_next[crossed]), 1.0)
            rul[crossed] = t - dt - origin + np.clip(fraction, 0.0, 1.0) * dt
        alive &= ~crossed
        g = g_next
        if keep:
            times.append(t)
            kept.append(x[:, :keep].copy())
    return RULDistribution(samples=rul, horizon=float(horizon), origin=float(origin), initial=initial,
                           times=np.array(times) if keep else np.zeros(0),
                           trajectories=np.array(kept) if keep else np.zeros((0, 0, 0)))


def _rk4(rates: Callable, x: np.ndarray, t: float, dt: float) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        k1 = rates(x, t)
        k2 = rates(x + 0.5 * dt * k1, t + 0.5 * dt)
        k3 = rates(x + 0.5 * dt * k2, t + 0.5 * dt)
        k4 = rates(x + dt * k3, t + dt)
        return x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
