"""Resampling schemes for particle filters, vectorized over a batch of assets.

Jha et al. (2016) use sampling importance resampling (SIR): after the weights are
updated with the likelihood of the new residual, particles are drawn again
from their weighted empirical distribution (eq. 37 before propagation).  Each
scheme here returns *ancestor indices*: ``particles[..., indices]`` (with
``numpy.take_along_axis`` for a batch) is the resampled cloud, with uniform
weights ``1/N`` afterwards.

Every scheme is unbiased: the expected number of copies (offspring count) of
particle ``i`` is ``N w_i``.  They differ in variance (Douc and Cappe 2005,
"Comparison of resampling schemes for particle filtering"):

* multinomial: ``N`` i.i.d. ``U[0, 1)`` per row, sorted; offspring
  ``Multinomial(N, w)``;
* stratified: ``u_j = (j + U_j) / N``, one uniform per particle; offspring
  between ``floor(N w_i) - 1`` and ``ceil(N w_i) + 1``;
* systematic: ``u_j = (j + U) / N``, one uniform per row; offspring
  ``floor(N w_i)`` or ``ceil(N w_i)``;
* residual: ``floor(N w_i)`` copies, then a systematic draw of the remainder;
  offspring ``floor(N w_i)`` or ``ceil(N w_i)``.

Weights have shape ``(..., N)``: one row of ``N`` particles per asset (a single
asset may be passed as a 1-D array).  Rows are normalized defensively; a row
containing NaN, infinite or negative weights, or summing to zero, raises
``PrognosisError`` (a ``ValueError``).  Indices come back with the weights' shape, each row sorted
ascending.

Weights are usually computed in the log domain: :func:`normalize_log_weights`
turns log weights into normalized weights with a stable log-sum-exp and flags
degenerate rows instead of producing NaN.

Example
-------
>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> systematic(np.array([0.1, 0.6, 0.3]), rng).tolist()
[1, 1, 2]
>>> weights, log_z, degenerate = normalize_log_weights(np.array([[-1e4, -1e4], [-np.inf, -np.inf]]))
>>> weights.tolist(), degenerate.tolist()
([[0.5, 0.5], [0.5, 0.5]], [False, True])
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .errors import PrognosisError

__all__ = [
    "SCHEMES", "effective_sample_size", "get_scheme", "multinomial", "normalize_log_weights", "residual",
    "stratified", "systematic", "systematic_indices",
]

Scheme = Callable[[np.ndarray, np.random.Generator], np.ndarray]

# Largest double below 1: uniforms are clipped to it so that, with the last
# cumulative weight set to exactly 1, no index can reach N.
_BELOW_ONE = float(np.nextafter(1.0, 0.0))


def _as_rows(weights: ArrayLike) -> np.ndarray:
    """Validated, normalized weights reshaped to ``(rows, N)``."""
    w = np.asarray(weights, dtype=float)
    if w.ndim == 0 or w.shape[-1] == 0:
        raise PrognosisError(f"weights must have shape (..., N) with N >= 1 particles, got shape {w.shape}")
    rows = w.reshape(-1, w.shape[-1])
    if np.isnan(rows).any():
        raise PrognosisError("weights contain NaN")
    if np.isinf(rows).any():
        raise PrognosisError("weights contain infinite values")
    if (rows < 0).any():
        raise PrognosisError("weights contain negative values")
    total = rows.sum(axis=-1, keepdims=True)
    if (total == 0).any():
        bad = np.flatnonzero(total[:, 0] == 0)
        raise PrognosisError(f"weights of row(s) {bad.tolist()} sum to 0: nothing to resample from")
    return rows / total


def _cdf(rows: np.ndarray) -> np.ndarray:
    """Cumulative weights along the last axis, clipped to 1, last element exactly 1."""
    cdf = np.minimum(np.cumsum(rows, axis=-1), 1.0)
    cdf[:, -1] = 1.0
    return cdf


def _inverse_cdf(cdf: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Index of the particle each sorted uniform falls on, row by row.

    For every row, ``index_j = #{i : cdf_i <= u_j}``, the particle ``i`` with
    ``cdf_{i-1} <= u_j < cdf_i`` (zero-weight particles are never chosen).
    ``cdf`` is ``(rows, N)``, non-decreasing; ``u`` is ``(rows, M)``, sorted
    ascending along each row.  All rows are merged at once: a stable argsort of
    ``[cdf, u]`` puts each ``u_j`` after every ``cdf_i <= u_j``, so the count of
    cdf entries before it is its index.  (Unlike offsetting row ``r`` by ``r``
    and calling one ``searchsorted``, this loses no precision for many rows.)
    """
    n = cdf.shape[-1]
    order = np.argsort(np.concatenate([cdf, u], axis=-1), axis=-1, kind="stable")
    from_cdf = order < n
    before = np.cumsum(from_cdf, axis=-1)
    return before[~from_cdf].reshape(u.shape)


def _counts_to_indices(counts: np.ndarray) -> np.ndarray:
    """Sorted ancestor indices from offspring counts ``(rows, N)`` summing to ``N`` per row."""
    rows, n = counts.shape
    flat = np.repeat(np.arange(rows * n), counts.ravel())
    return flat.reshape(rows, n) - (n * np.arange(rows))[:, None]


def _offspring(indices: np.ndarray, n: int, valid: np.ndarray | None = None) -> np.ndarray:
    """Offspring counts ``(rows, n)`` of row-wise indices, counting only ``valid`` entries."""
    rows = indices.shape[0]
    flat = (indices + n * np.arange(rows)[:, None]).ravel()
    if valid is not None:
        flat = flat[valid.ravel()]
    return np.bincount(flat, minlength=rows * n).reshape(rows, n)


def _resample(weights: ArrayLike, rng: np.random.Generator, uniforms: Callable) -> np.ndarray:
    """Shared driver: validate, draw sorted uniforms ``(rows, N)``, invert the cdf, reshape."""
    shape = np.shape(weights)
    rows = _as_rows(weights)
    u = np.minimum(uniforms(np.random.default_rng(rng), rows.shape), _BELOW_ONE)
    return _inverse_cdf(_cdf(rows), u).reshape(shape)


def systematic(weights: ArrayLike, rng: np.random.Generator) -> np.ndarray:
    """Systematic resampling: one uniform per row.

    ``u_j = (j + U) / N`` for ``j = 0..N-1`` with a single ``U ~ U[0, 1)`` per
    row; particle ``i`` is chosen for every ``u_j`` in
    ``[C_{i-1}, C_i)``, ``C_i = w_0 + ... + w_i``.  The offspring count of
    particle ``i`` is ``floor(N w_i)`` or ``ceil(N w_i)``.  The indices are
    :func:`systematic_indices`' (the fleet's filter calls it with its own uniforms).

    Parameters
    ----------
    weights : array_like, shape (..., N)
        Non-negative particle weights, normalized along the last axis (they
        are normalized again here).
    rng : numpy.random.Generator
        Source of randomness (a seed is passed to ``numpy.random.default_rng``).

    Returns
    -------
    ndarray of int, shape (..., N)
        Ancestor indices, sorted ascending in each row.

    Raises
    ------
    PrognosisError
        If a row has NaN, infinite or negative weights or sums to zero.

    Examples
    --------
    >>> import numpy as np
    >>> systematic(np.array([[0.5, 0.0, 0.5], [0.0, 0.0, 1.0]]), np.random.default_rng(1)).tolist()
    [[0, 2, 2], [2, 2, 2]]
    """
    shape = np.shape(weights)
    rows = _as_rows(weights)
    u = np.random.default_rng(rng).random(rows.shape[0])
    return systematic_indices(rows, np.ones(rows.shape[0]), u).reshape(shape)


def systematic_indices(weights: np.ndarray, total: np.ndarray, u: np.ndarray, flat: bool = False) -> np.ndarray:
    """Systematic resampling of each row from its unnormalized ``weights`` (R, N), sums ``total`` and uniform ``u``.

    Particle ``i`` gets ``ceil(N C_i - u) - ceil(N C_{i-1} - u)`` copies, ``C`` the normalized
    cumulative weights: the number of points ``(j + u) / N`` in ``[C_{i-1}, C_i)``.  Returns the
    ancestors' indices per row (R, N), or with ``flat`` their indices into the flattened (R * N) array.
    A single row (a stream's tick) finds the same ancestors by binary search: point ``j`` descends
    from the number of edges ``N C_i - u`` at or below ``j``, two calls where the counts take ten.

    >>> systematic_indices(np.array([[1.0, 0.0, 1.0]]), np.array([2.0]), np.array([0.5])).tolist()
    [[0, 2, 2]]
    """
    rows, n = weights.shape
    edges = np.add.accumulate(weights, axis=1)  # cumsum's values, with fewer layers of calls
    edges *= (n / total)[:, None]
    edges -= u[:, None]
    # the last particle with weight (and the weightless ones after it) ends at N: a u rounding N - u down
    # to N - 1 would otherwise hand the last point to a particle without weight
    if rows == 1:  # a stream's tick: point j's ancestor is the number of edges <= j (ceil(e) > j iff e > j)
        edges[0, np.searchsorted(edges[0], edges[0, -1]):] = n  # the edges do not decrease: a binary search
        ancestors = np.searchsorted(edges[0], _points(n), side="right")
        return ancestors if flat else ancestors[None, :]
    tail = np.flatnonzero(edges[:, -2] == edges[:, -1]) if n > 1 else np.empty(0, int)
    edges[:, -1] = n
    if tail.size:  # the rare rows whose last particles have no weight: their run of equal edges ends at N
        part = edges[tail]
        np.copyto(part, n, where=part >= part[:, -2:-1])
        edges[tail] = part
    np.ceil(edges, out=edges)
    np.minimum(edges, n, out=edges)
    np.maximum(edges, 0, out=edges)
    counts = edges.astype(np.int64)
    counts[:, 1:] -= counts[:, :-1].copy()
    ancestors = np.repeat(np.arange(rows * n), counts.reshape(-1))
    return ancestors if flat else ancestors.reshape(rows, n) - (n * np.arange(rows))[:, None]



def stratified(weights: ArrayLike, rng: np.random.Generator) -> np.ndarray:
    """Stratified resampling: one uniform per particle.

    ``u_j = (j + U_j) / N`` with independent ``U_j ~ U[0, 1)``: one draw in
    each stratum ``[j/N, (j+1)/N)``; particle ``i`` is chosen for every
    ``u_j`` in ``[C_{i-1}, C_i)``.

    Parameters
    ----------
    weights : array_like, shape (..., N)
        Non-negative particle weights, normalized along the last axis.
    rng : numpy.random.Generator
        Source of randomness.

    Returns
    -------
    ndarray of int, shape (..., N)
        Ancestor indices, sorted ascending in each row.

    Examples
    --------
    >>> import numpy as np
    >>> stratified(np.array([0.0, 1.0, 0.0]), np.random.default_rng(1)).tolist()
    [1, 1, 1]
    """
    def draw(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
        return (np.arange(shape[1]) + rng.random(shape)) / shape[1]

    return _resample(weights, rng, draw)


def multinomial(weights: ArrayLike, rng: np.random.Generator) -> np.ndarray:
    """Multinomial resampling: ``N`` independent draws per row.

    ``N`` i.i.d. ``U[0, 1)`` per row, sorted, mapped through the inverse of the
    cumulative weights ``C_i`` (particle ``i`` for ``u`` in ``[C_{i-1}, C_i)``).
    The offspring counts are ``Multinomial(N, w)``: the highest variance of
    the four schemes.

    Parameters
    ----------
    weights : array_like, shape (..., N)
        Non-negative particle weights, normalized along the last axis.
    rng : numpy.random.Generator
        Source of randomness.

    Returns
    -------
    ndarray of int, shape (..., N)
        Ancestor indices, sorted ascending in each row.

    Examples
    --------
    >>> import numpy as np
    >>> multinomial(np.array([1.0, 0.0]), np.random.default_rng(1)).tolist()
    [0, 0]
    """
    def draw(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
        return np.sort(rng.random(shape), axis=-1)

    return _resample(weights, rng, draw)


def residual(weights: ArrayLike, rng: np.random.Generator) -> np.ndarray:
    """Residual resampling with a systematic draw of the remainder.

    Particle ``i`` first gets ``floor(N w_i)`` copies deterministically.  The
    ``R = N - sum_i floor(N w_i)`` remaining indices are drawn by *systematic*
    resampling (``u_j = (j + U) / R``, ``j = 0..R-1``) from the residual
    weights ``r_i = (N w_i - floor(N w_i)) / R``.  Since ``R r_i < 1`` the
    systematic step adds at most one copy, so the offspring count of ``i`` is
    ``floor(N w_i)`` or ``ceil(N w_i)``, and its mean is
    ``floor(N w_i) + R r_i = N w_i`` (unbiased).  (A multinomial draw of the
    remainder, the textbook variant, would also be unbiased but can give a
    particle several extra copies.)

    Parameters
    ----------
    weights : array_like, shape (..., N)
        Non-negative particle weights, normalized along the last axis.
    rng : numpy.random.Generator
        Source of randomness.

    Returns
    -------
    ndarray of int, shape (..., N)
        Ancestor indices, sorted ascending in each row.

    Examples
    --------
    >>> import numpy as np
    >>> residual(np.array([0.5, 0.25, 0.25, 0.0]), np.random.default_rng(1)).tolist()
    [0, 0, 1, 2]
    """
    shape = np.shape(weights)
    rows = _as_rows(weights)
    n_rows, n = rows.shape
    scaled = n * rows
    copies = np.floor(scaled).astype(int)
    remainder = np.clip(n - copies.sum(axis=-1), 0, n)
    counts = copies + _systematic_counts(scaled - copies, remainder, np.random.default_rng(rng))
    # The floors of rounded N w_i can overshoot N by one: take the excess from the heaviest particle.
    counts[np.arange(n_rows), rows.argmax(axis=-1)] += n - counts.sum(axis=-1)
    return _counts_to_indices(counts).reshape(shape)


def _systematic_counts(fractions: np.ndarray, draws: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Offspring counts of a systematic draw of ``draws[r]`` indices from row ``r`` of ``fractions``.

    Row ``r`` uses ``u_j = (j + U_r) / draws[r]`` for ``j < draws[r]``; the
    unused columns hold ``+inf`` (index ``N``, not counted).
    """
    n_rows, n = fractions.shape
    used = np.arange(n) < draws[:, None]
    u = (np.arange(n) + rng.random((n_rows, 1))) / np.maximum(draws, 1)[:, None]
    u = np.where(used, np.minimum(u, _BELOW_ONE), np.inf)
    indices = np.minimum(_inverse_cdf(_cdf(_residual_weights(fractions)), u), n - 1)
    return _offspring(indices, n, used)


def _residual_weights(fractions: np.ndarray) -> np.ndarray:
    """Normalized fractional parts; uniform for a row with no remainder (it is never drawn from)."""
    total = fractions.sum(axis=-1, keepdims=True)
    safe = np.where(total > 0, fractions, 1.0)
    return safe / safe.sum(axis=-1, keepdims=True)


def effective_sample_size(weights: ArrayLike) -> np.ndarray | float:
    """Effective sample size ``ESS = 1 / sum_i w_i^2`` along the last axis.

    Computed as ``(sum_i w_i)^2 / sum_i w_i^2`` so that unnormalized weights
    give the ESS of their normalized version.  ``ESS = N`` for uniform weights,
    ``1`` when one particle carries all the weight.

    Parameters
    ----------
    weights : array_like, shape (..., N)
        Non-negative weights (same checks as the resampling schemes).

    Returns
    -------
    ndarray, shape (...)
        One value per row (a float for 1-D input).

    Examples
    --------
    >>> import numpy as np
    >>> effective_sample_size(np.array([[0.25, 0.25, 0.25, 0.25], [0.0, 1.0, 0.0, 0.0]])).tolist()
    [4.0, 1.0]
    >>> float(effective_sample_size(np.array([3.0, 1.0])))
    1.6
    """
    rows = _as_rows(weights)
    ess = 1.0 / np.sum(rows**2, axis=-1)
    return ess.reshape(np.shape(weights)[:-1])[()]


def normalize_log_weights(log_weights: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalized weights from log weights, by a stable log-sum-exp.

    With ``m = max_i l_i`` per row,

    ``log Z = m + log sum_i exp(l_i - m)`` and ``w_i = exp(l_i - m) / sum_j exp(l_j - m)``,

    exact when every ``l_i`` is very negative (e.g. ``-1e4``, where
    ``exp(l_i)`` underflows to 0).  ``log Z`` is the log of the *sum* of the
    unnormalized weights (subtract ``log N`` for the usual particle estimate
    of the log-likelihood increment when the previous weights were uniform).

    A row is *degenerate* when all its log weights are ``-inf`` (every
    particle has zero likelihood) or when it contains NaN or ``+inf``.  Such
    rows get uniform weights ``1/N`` and ``log Z = -inf`` and are flagged in
    ``degenerate``; no NaN is produced.

    Parameters
    ----------
    log_weights : array_like, shape (..., N)
        Unnormalized log weights.

    Returns
    -------
    weights : ndarray, shape (..., N)
        Normalized along the last axis.
    log_normalizer : ndarray, shape (...)
        ``log Z`` per row (a float for 1-D input).
    degenerate : ndarray of bool, shape (...)
        Rows that could not be normalized.

    Examples
    --------
    >>> import numpy as np
    >>> w, log_z, bad = normalize_log_weights(np.log([1.0, 3.0]) - 1e4)
    >>> w.round(12).tolist(), round(float(log_z) + 1e4, 6), bool(bad)
    ([0.25, 0.75], 1.386294, False)
    """
    log_w = np.asarray(log_weights, dtype=float)
    if log_w.ndim == 0 or log_w.shape[-1] == 0:
        raise PrognosisError(f"log weights must have shape (..., N) with N >= 1, got shape {log_w.shape}")
    degenerate = (np.isnan(log_w) | (log_w == np.inf)).any(axis=-1) | (log_w == -np.inf).all(axis=-1)
    safe = np.where(degenerate[..., None], 0.0, log_w)
    peak = safe.max(axis=-1, keepdims=True)
    scaled = np.exp(safe - peak)
    total = scaled.sum(axis=-1, keepdims=True)
    weights = np.where(degenerate[..., None], 1.0 / log_w.shape[-1], scaled / total)
    log_z = np.where(degenerate, -np.inf, (peak + np.log(total))[..., 0])
    return weights, log_z[()], degenerate[()]


SCHEMES: dict[str, Scheme] = {
    "systematic": systematic,
    "stratified": stratified,
    "residual": residual,
    "multinomial": multinomial,
}


def get_scheme(name: str) -> Scheme:
    """The resampling function registered under ``name`` in :data:`SCHEMES`.

    Examples
    --------
    >>> get_scheme("systematic") is systematic
    True
    >>> try:
    ...     get_scheme("bootstrap")
    ... except PrognosisError as error:
    ...     print(error)
    unknown resampling scheme 'bootstrap'; choose one of: multinomial, residual, stratified, systematic
    """
    try:
        return SCHEMES[name]
    except (KeyError, TypeError):
        names = ", ".join(sorted(SCHEMES))
        raise PrognosisError(f"unknown resampling scheme {name!r}; choose one of: {names}") from None


@functools.lru_cache(maxsize=8)
def _points(n: int) -> np.ndarray:
    """0, 1, ..., n - 1, read-only: the systematic points of a row, scaled by N and shifted by its uniform."""
    points = np.arange(n, dtype=float)
    points.flags.writeable = False
    return points
