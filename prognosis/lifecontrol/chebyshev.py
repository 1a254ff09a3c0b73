"""Distribution-free interval bounds from a mean and a covariance (Rodriguez Obando et al. (2021), eqs. 37-44).

The multivariate Chebyshev inequality (Stellato et al. 2017) holds for any
distribution of the estimation error ``x~`` with zero mean and covariance ``P``
in ``R^n``::

    Pr(x~^T P^{-1} x~ > c^2) <= n / c^2                                 (37)

The ellipsoid ``x~^T P^{-1} x~ <= c^2`` lies inside the box
``|x~_i| <= c sqrt(P_ii)`` (its bounding box), so every state lies in

    x^_i - xbar_i <= x_i <= x^_i + xbar_i,   xbar = c sqrt(diag P)      (38)-(43)

jointly, with probability at least ``1 - n/c^2``: ``c = 10`` gives 95 % for
``n = 5``.  (The paper's ``diag(P^{1/2})`` with an elementwise root is
``sqrt(diag P)``.)  Read backwards, bounds ``xbar_0`` on the initial state give
a diagonal initial covariance ``P_0 = diag((xbar_0 / c)^2)`` (eq. 44); with the
paper's ``xbar_0 = (23, 2, 5, 1e-6, 5e5)`` and ``c = 10`` the ``D`` entry is
``(5e5/10)^2 = 2.5e9`` (eq. 58 prints 2.5e-9).

The box is conservative: one component alone satisfies the univariate bound
``Pr(|x~_i| > c sqrt(P_ii)) <= 1/c^2``.

Example
-------
>>> bounds = [23.0, 2.0, 5.0, 1e-6, 5e5]
>>> p0 = covariance_from_bounds(bounds, c=10.0)
>>> [float(f"{v:.3g}") for v in np.diag(p0)]
[5.29, 0.04, 0.25, 1e-14, 2500000000.0]
>>> chebyshev_level(5, 10.0)
0.95
>>> np.allclose(chebyshev_bounds(p0, 10.0), bounds)
True
"""

from __future__ import annotations

import numpy as np

from ..errors import PrognosisError

__all__ = ["chebyshev_bounds", "chebyshev_intervals", "chebyshev_level", "chebyshev_scale", "covariance_from_bounds"]


def chebyshev_level(n: int, c: float) -> float:
    """Lower bound ``1 - n / c^2`` (clipped at 0) on the probability that the state lies in the box.

    Parameters
    ----------
    n : int
        Dimension of the state.
    c : float
        Scale of the box ``|x~_i| <= c sqrt(P_ii)``.

    Returns
    -------
    float

    Examples
    --------
    >>> chebyshev_level(5, 10.0), chebyshev_level(1, 2.0)
    (0.95, 0.75)
    >>> chebyshev_level(5, 2.0)   # a box this small guarantees nothing
    0.0
    """
    if n < 1 or not c > 0:
        raise PrognosisError(f"need n >= 1 and c > 0, got n={n!r}, c={c!r}")
    return max(0.0, 1.0 - n / c ** 2)


def chebyshev_scale(n: int, level: float) -> float:
    """The ``c`` with ``1 - n / c^2 = level``: ``c = sqrt(n / (1 - level))``.

    >>> round(chebyshev_scale(5, 0.95), 6)
    10.0
    """
    if n < 1 or not 0.0 <= level < 1.0:
        raise PrognosisError(f"need n >= 1 and 0 <= level < 1, got n={n!r}, level={level!r}")
    return float(np.sqrt(n / (1.0 - level)))


def chebyshev_bounds(covariance, c: float) -> np.ndarray:
    """Half-widths ``xbar = c sqrt(diag P)`` (eq. 38), for one ``P`` (n, n) or a stack (..., n, n).

    Parameters
    ----------
    covariance : array (n, n) or (..., n, n)
    c : float
        Positive scale (see :func:`chebyshev_level` for the probability it gives).

    Returns
    -------
    ndarray (n,) or (..., n)

    Examples
    --------
    >>> p = np.diag([4.0, 0.25])
    >>> chebyshev_bounds(p, 3.0).tolist()
    [6.0, 1.5]
    >>> chebyshev_bounds(np.stack([p, 4 * p]), 2.0).tolist()   # one row per estimate
    [[4.0, 1.0], [8.0, 2.0]]
    """
    p = np.asarray(covariance, float)
    if p.ndim < 2 or p.shape[-1] != p.shape[-2]:
        raise PrognosisError(f"covariance: expected (n, n) or (..., n, n), got shape {p.shape}")
    if not c > 0:
        raise PrognosisError(f"c must be positive, got {c!r}")
    variances = np.diagonal(p, axis1=-2, axis2=-1)
    if np.any(variances < 0):
        raise PrognosisError("covariance: negative variance on the diagonal")
    return c * np.sqrt(variances)


def chebyshev_intervals(mean, covariance, c: float) -> tuple[np.ndarray, np.ndarray]:
    """``(x^ - xbar, x^ + xbar)`` (eqs. 39-43), broadcast over a stack of estimates.

    Parameters
    ----------
    mean : array (n,) or (..., n)
        Estimates ``x^``.
    covariance : array (n, n) or (..., n, n)
        Their covariances ``P``.
    c : float

    Returns
    -------
    lower, upper : ndarray, the shape of ``mean``

    Examples
    --------
    >>> lower, upper = chebyshev_intervals([1.0, 0.0], np.diag([4.0, 0.25]), 3.0)
    >>> lower.tolist(), upper.tolist()
    ([-5.0, -1.5], [7.0, 1.5])
    """
    half = chebyshev_bounds(covariance, c)
    mean = np.asarray(mean, float)
    if mean.shape != half.shape:
        raise PrognosisError(f"mean shape {mean.shape} does not match the covariance diagonal {half.shape}")
    return mean - half, mean + half


def covariance_from_bounds(bounds, c: float) -> np.ndarray:
    """Diagonal ``P_0`` whose Chebyshev box (eq. 38) is ``bounds``: ``P_0 = diag((xbar_0 / c)^2)`` (eq. 44).

    Parameters
    ----------
    bounds : array (n,)
        Half-widths ``xbar_0`` (finite, non-negative).
    c : float

    Returns
    -------
    ndarray (n, n)

    Examples
    --------
    >>> p0 = covariance_from_bounds([6.0, 1.5], 3.0)
    >>> p0.tolist()
    [[4.0, 0.0], [0.0, 0.25]]
    >>> chebyshev_bounds(p0, 3.0).tolist()   # the inverse of chebyshev_bounds
    [6.0, 1.5]
    """
    bounds = np.asarray(bounds, float).reshape(-1)
    if not c > 0:
        raise PrognosisError(f"c must be positive, got {c!r}")
    if not np.all(np.isfinite(bounds)) or np.any(bounds < 0):
        raise PrognosisError(f"bounds must be finite and non-negative, got {bounds.tolist()}")
    return np.diag((bounds / c) ** 2)
