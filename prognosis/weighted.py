"""Weighted statistics of samples (particle clouds, RUL samples): medians and quantiles along an axis, and
the checks and reshaping of their weights, which the metrics (:mod:`prognosis.metrics`) build on.

The last axis of a sample array holds the samples; every leading axis is a batch axis.  Weights default to
uniform; NaN, infinite or negative weights raise ``PrognosisError``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .errors import PrognosisError

__all__ = ["last_axis", "median_along_last", "moved_weights", "weighted_median", "weighted_quantiles", "weights_like"]


def weights_like(samples: np.ndarray, weights: ArrayLike | None) -> np.ndarray:
    """Weights broadcast to ``samples``, checked, each slice along the last axis summing to 1."""
    if weights is None:
        return np.full(samples.shape, 1.0 / samples.shape[-1])
    w = np.broadcast_to(np.asarray(weights, dtype=float), samples.shape)
    if not np.isfinite(w).all():
        raise PrognosisError("weights contain NaN or infinite values")
    if (w < 0).any():
        raise PrognosisError("weights contain negative values")
    total = w.sum(axis=-1, keepdims=True)
    if (total == 0).any():
        raise PrognosisError("weights sum to 0 along the particle axis")
    return w / total


def moved_weights(weights: ArrayLike | None, shape: tuple[int, ...], axis: int) -> np.ndarray | None:
    """Weights broadcast to ``shape`` with ``axis`` moved last; a 1-D vector lies along ``axis``."""
    if weights is None:
        return None
    w = np.asarray(weights, dtype=float)
    if w.ndim == 1 and len(shape) > 1:
        w = np.expand_dims(w, tuple(range(1, len(shape) - axis % len(shape))))
    return np.moveaxis(np.broadcast_to(w, shape), axis, -1)


def last_axis(values: ArrayLike, axis: int) -> np.ndarray:
    x = np.asarray(values, dtype=float)
    if x.ndim == 0 or x.shape[axis] == 0:
        raise PrognosisError(f"need at least one value along axis {axis}, got shape {x.shape}")
    return np.moveaxis(x, axis, -1)


def median_along_last(x: np.ndarray, w: np.ndarray | None) -> np.ndarray:
    """Weighted median along the last axis (``w`` normalized, or None for ``np.median``)."""
    if w is None:
        return np.median(x, axis=-1)
    n = x.shape[-1]
    order = np.argsort(x, axis=-1)
    xs = np.take_along_axis(x, order, axis=-1)
    cw = np.cumsum(np.take_along_axis(w, order, axis=-1), axis=-1)
    tol = 4 * n * np.finfo(float).eps
    lower = np.argmax(cw >= 0.5 - tol, axis=-1)[..., None]
    upper = np.argmax(cw > 0.5 + tol, axis=-1)[..., None]
    median = 0.5 * (np.take_along_axis(xs, lower, axis=-1) + np.take_along_axis(xs, upper, axis=-1))[..., 0]
    return np.where(np.isnan(x).any(axis=-1), np.nan, median)


def weighted_median(samples: ArrayLike, weights: ArrayLike | None = None, axis: int = -1) -> np.ndarray | float:
    """Median of a weighted sample along ``axis``.

    With the samples sorted, ``x_(1) <= ... <= x_(n)``, and ``C_k`` the
    cumulative normalized weight of the first ``k``:

    ``lower = x_(k)`` for the smallest ``k`` with ``C_k >= 1/2``,
    ``upper = x_(k)`` for the smallest ``k`` with ``C_k > 1/2``,
    ``median = (lower + upper) / 2``.

    ``C_k`` within ``4 n eps`` of one half counts as exactly one half, so
    uniform weights give ``numpy.median`` (the mean of the two middle values
    for even ``n``) despite rounding in the cumulative sum.  Zero-weight
    samples are never picked.  Without weights this *is* ``numpy.median``.
    A slice containing NaN gives NaN.

    Parameters
    ----------
    samples : array_like
    weights : array_like, optional
        Non-negative; a 1-D vector lies along ``axis``, otherwise broadcastable
        to ``samples``.  Normalized along ``axis``.
    axis : int
        Axis of the samples (default: last).

    Returns
    -------
    ndarray or float
        The input's shape without ``axis``.

    Examples
    --------
    >>> float(weighted_median([1.0, 2.0, 3.0, 4.0]))
    2.5
    >>> float(weighted_median([1.0, 2.0, 3.0, 4.0], [1, 1, 1, 1]))
    2.5
    >>> float(weighted_median([1.0, 2.0, 3.0, 4.0], [1, 1, 3, 1]))
    3.0
    """
    x = last_axis(samples, axis)
    w = moved_weights(weights, np.shape(samples), axis)
    return median_along_last(x, None if w is None else weights_like(x, w))[()]


def weighted_quantiles(values: np.ndarray, weights: np.ndarray, levels) -> np.ndarray:
    """Quantiles along the last axis: the smallest value whose cumulative weight reaches each level.

    ``levels`` in [0, 1]; the output has the shape of ``values`` without its
    last axis, plus one axis of ``len(levels)``.  ``+inf`` samples (censored
    RULs) sort last.

    >>> import numpy as np
    >>> weighted_quantiles(np.array([3.0, 1.0, 2.0]), np.array([0.2, 0.5, 0.3]), (0.5, 0.9)).tolist()
    [1.0, 3.0]
    """
    order = np.argsort(values, axis=-1)
    sorted_values = np.take_along_axis(values, order, axis=-1)
    cumulative = np.cumsum(np.take_along_axis(np.broadcast_to(weights, values.shape), order, axis=-1), axis=-1)
    cumulative = cumulative / cumulative[..., -1:]
    index = np.stack([np.argmax(cumulative >= level - 1e-12, axis=-1) for level in levels], axis=-1)
    return np.take_along_axis(sorted_values, index, axis=-1)
