"""Estimation, prediction and prognostic metrics (Jha et al. (2016), section 5; Saxena et al. 2010).

Jha et al. (2016) evaluate a particle-filter prognoser with

* estimation: relative RMSE (eq. 40) and the spread RMAD (eqs. 35, 41) of the
  estimated state and degradation parameters;
* prediction: relative accuracy RA of the mean RUL (eqs. 42-43) and the RMAD
  of the RUL distribution;
* prognostics: the alpha-lambda metric with a probability-mass threshold
  beta (section 5.3),

all taken from Saxena, Celaya, Saha, Saha and Goebel (2010), "Metrics for
offline evaluation of prognostic performance", Int. J. Prognostics and Health
Management 1(1), which also defines the prognostic horizon, the cumulative
relative accuracy and the convergence of a metric, given here too.

The weighted medians and quantiles they use are in :mod:`prognosis.weighted`; ranking methods by a
score is :mod:`prognosis.ranking`.

Conventions: the last axis of a sample array holds the particles (or the
time steps ``k`` for a sequence); every leading axis (assets, prediction
points) is a batch axis, so ``(assets, points, particles)`` arrays are
evaluated at once.  1-D input gives a scalar.  Particle weights default to
uniform; NaN, infinite or negative weights raise ``PrognosisError`` (a ``ValueError``).

Example
-------
>>> import numpy as np
>>> rul = np.array([[9.0, 10.0, 11.0, np.inf], [4.0, 5.0, 6.0, 7.0]])  # 2 prediction points, 4 particles
>>> mass, passed = alpha_lambda(rul, None, np.array([10.0, 8.0]), alpha=0.2, beta=0.5)
>>> mass.tolist(), passed.tolist()
([0.75, 0.25], [True, False])
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import ArrayLike

from bondgraph.errors import PHMWarning

from .errors import PrognosisError
from .weighted import last_axis, median_along_last, moved_weights, weights_like

__all__ = [
    "MetricWarning", "alpha_lambda", "convergence", "cumulative_relative_accuracy", "mean_relative_accuracy",
    "mean_rmad", "pooled_scores", "prognostic_horizon", "relative_accuracy", "relative_rmse", "rmad",
    "scores_against_truth",
]


class MetricWarning(PHMWarning):
    """A metric undefined at some points (set to NaN there)."""


def rmad(samples: ArrayLike, weights: ArrayLike | None = None, axis: int = -1) -> np.ndarray | float:
    """Relative median absolute deviation, the robust spread of Jha et al. (2016), eq. (35).

    ``RMAD(X) = Median_i |X_i - Median_j X_j| / Median_j X_j``

    With particle weights both medians are the weighted medians of
    :func:`~prognosis.weighted.weighted_median` (midpoint of the lower and upper weighted medians)
    with the same weights.  A zero median gives ``inf`` (or NaN if the
    deviation is also zero); a negative median gives a negative RMAD.

    Parameters
    ----------
    samples : array_like
        E.g. particles ``(assets, N)`` of a parameter, or RUL samples.
    weights : array_like, optional
        Particle weights: a 1-D vector along ``axis``, or broadcastable to ``samples``.
    axis : int
        Axis of the samples (default: last).

    Returns
    -------
    ndarray or float
        The input's shape without ``axis``.

    Examples
    --------
    >>> float(rmad([1.0, 2.0, 3.0, 4.0, 10.0]))  # median 3, deviations 2 1 0 1 7, their median 1
    0.3333333333333333
    """
    x = last_axis(samples, axis)
    w = moved_weights(weights, np.shape(samples), axis)
    w = None if w is None else weights_like(x, w)
    median = median_along_last(x, w)
    with np.errstate(invalid="ignore"):
        deviation = median_along_last(np.abs(x - median[..., None]), w)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (deviation / median)[()]


def mean_rmad(rmads: ArrayLike, axis: int = -1) -> np.ndarray | float:
    """Mean spread over time, Jha et al. (2016), eq. (41): ``mean RMAD = Mean_k RMAD_k``.

    NaN entries (e.g. time steps without an estimate) are ignored; an
    all-NaN slice gives NaN.

    Examples
    --------
    >>> round(float(mean_rmad([0.1, 0.2, np.nan, 0.3])), 12)
    0.2
    """
    values = last_axis(rmads, axis)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN slice -> NaN, documented
        return np.nanmean(values, axis=-1)[()]


def relative_rmse(estimates: ArrayLike, truth: ArrayLike, axis: int = -1) -> np.ndarray | float:
    """Relative root mean square error, Jha et al. (2016), eq. (40).

    ``RMSE_X = sqrt( Mean_k ((X_k - X*_k) / X*_k)^2 )``

    over the time steps ``k`` along ``axis``.  ``X*_k`` must be non-zero
    (zero gives ``inf``); NaN propagates.

    Parameters
    ----------
    estimates : array_like
        Estimates ``X_k`` (e.g. particle means), shape ``(..., K)``.
    truth : array_like
        True values ``X*_k``, broadcastable to ``estimates``.
    axis : int
        Time axis (default: last).

    Examples
    --------
    >>> round(float(relative_rmse([3.0, 3.0], [2.0, 4.0])), 12)  # errors +50 % and -25 %: sqrt((0.25 + 0.0625) / 2)
    0.395284707521
    """
    x, x_true = np.broadcast_arrays(np.asarray(estimates, dtype=float), np.asarray(truth, dtype=float))
    x, x_true = last_axis(x, axis), np.moveaxis(x_true, axis, -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(np.mean(((x - x_true) / x_true) ** 2, axis=-1))[()]


def relative_accuracy(rul_true: ArrayLike, rul_predicted_mean: ArrayLike) -> np.ndarray | float:
    """Relative accuracy at each prediction point, Jha et al. (2016), eq. (42).

    ``RA_kp = 1 - |RUL*_kp - Mean(RUL_kp)| / RUL*_kp``

    Elementwise over broadcast prediction points (and assets).  RA is 1 for
    a perfect mean and may be negative for a mean off by more than RUL*.
    Where ``RUL* <= 0`` (at or after the true end of life) RA is undefined:
    it is set to NaN and a :class:`MetricWarning` is issued.  A mean of
    ``+inf`` (censored particles averaged in) gives ``-inf``.

    Examples
    --------
    >>> relative_accuracy([10.0, 5.0], [8.0, 6.0]).tolist()  # 1 - 2/10, 1 - 1/5
    [0.8, 0.8]
    """
    true, mean = np.broadcast_arrays(np.asarray(rul_true, dtype=float), np.asarray(rul_predicted_mean, dtype=float))
    undefined = true <= 0
    if undefined.any():
        warnings.warn(f"true RUL <= 0 at {int(undefined.sum())} prediction point(s): relative accuracy set to NaN",
                      MetricWarning, stacklevel=2)
    safe = np.where(undefined, 1.0, true)
    with np.errstate(invalid="ignore"):
        ra = 1.0 - np.abs(safe - mean) / safe
    return np.where(undefined, np.nan, ra)[()]


def mean_relative_accuracy(ra: ArrayLike, axis: int = -1) -> np.ndarray | float:
    """Overall accuracy, Jha et al. (2016), eq. (43): ``mean RA = Mean_kp RA_kp``.

    NaN entries (points where RA is undefined) are ignored.

    Examples
    --------
    >>> float(mean_relative_accuracy([0.8, 1.0, np.nan]))
    0.9
    """
    return mean_rmad(ra, axis=axis)


def alpha_lambda(rul_samples: ArrayLike, weights: ArrayLike | None, rul_true: ArrayLike, alpha: float,
                 beta: float) -> tuple[np.ndarray, np.ndarray]:
    """Alpha-lambda accuracy with a probability-mass threshold (Jha et al. (2016), section 5.3).

    At each prediction point the probability mass of the predicted RUL
    distribution inside the cone ``[(1 - alpha) RUL*, (1 + alpha) RUL*]``
    (closed interval) is

    ``pi = sum_i w_i [ (1 - alpha) RUL* <= RUL_i <= (1 + alpha) RUL* ] / sum_i w_i``

    and the prediction is acceptable when ``pi >= beta`` (Saxena et al.
    2010).  Jha et al. (2016) use ``beta = 0.5`` at every prediction point (all
    lambda): pass the prediction points of interest.

    Censoring: a particle whose RUL is ``+inf`` or NaN (it never crossed the
    failure threshold within the prediction horizon) counts as *outside* the
    cone; its weight stays in the denominator, so it lowers the mass.

    Parameters
    ----------
    rul_samples : array_like, shape (..., N)
        RUL particles at each prediction point (leading axes: assets, points).
    weights : array_like or None
        Particle weights broadcastable to ``rul_samples``; None for uniform.
    rul_true : array_like, shape (...)
        True RUL at each prediction point, broadcastable to ``rul_samples[..., 0]``.
    alpha : float
        Relative half-width of the cone, ``alpha >= 0``.
    beta : float
        Required mass, in ``[0, 1]``.

    Returns
    -------
    mass : ndarray, shape (...)
        Probability mass inside the cone.
    passed : ndarray of bool, shape (...)
        ``mass >= beta``.

    Examples
    --------
    >>> mass, passed = alpha_lambda([7.0, 8.0, 9.0, np.inf], [0.1, 0.2, 0.3, 0.4], 10.0, alpha=0.2, beta=0.5)
    >>> round(float(mass), 12), bool(passed)  # 8 and 9 inside [8, 12]: 0.2 + 0.3
    (0.5, True)
    """
    if not (np.isfinite(alpha) and alpha >= 0):
        raise PrognosisError(f"alpha must be a finite number >= 0, got {alpha}")
    if not 0 <= beta <= 1:
        raise PrognosisError(f"beta must lie in [0, 1], got {beta}")
    true = np.asarray(rul_true, dtype=float)
    mass = mass_within(rul_samples, weights, (1 - alpha) * true, (1 + alpha) * true)
    return mass, np.asarray(mass >= beta)[()]


def mass_within(rul_samples: ArrayLike, weights: ArrayLike | None, lower: ArrayLike, upper: ArrayLike) -> np.ndarray:
    """Probability mass of the RUL distribution in ``[lower, upper]`` (closed), per prediction point.

    ``pi = sum_i w_i [lower <= RUL_i <= upper] / sum_i w_i``; censored (inf or NaN) samples count as
    outside.  The alpha-lambda cone is ``[(1 - alpha) RUL*, (1 + alpha) RUL*]``; the prognostic
    horizon's fixed-width bounds are ``RUL* -+ alpha EOL`` (Saxena et al. 2010).

    >>> float(mass_within([1.0, 2.0, 3.0, np.inf], None, 1.5, 3.0))
    0.5
    """
    x = last_axis(rul_samples, -1)
    lo, hi = np.asarray(lower, dtype=float)[..., None], np.asarray(upper, dtype=float)[..., None]
    x = np.broadcast_to(x, np.broadcast_shapes(x.shape, lo.shape, hi.shape))
    w = weights_like(x, weights)
    return np.sum(w * ((x >= lo) & (x <= hi)), axis=-1)[()]


def prognostic_horizon(times: ArrayLike, passed: ArrayLike, eol: ArrayLike) -> np.ndarray | float:
    """Prognostic horizon ``PH = EOL - t_j`` (Saxena et al. 2010).

    ``t_j`` is the first prediction time from which *all* later predictions
    pass the accuracy criterion (e.g. ``passed`` of :func:`alpha_lambda`):

    ``j = min { j : passed_k for every k >= j }``.

    A prediction that passes and later fails does not start the horizon.
    When the last prediction fails, no such ``j`` exists and PH is NaN.

    Parameters
    ----------
    times : array_like, shape (K,) or broadcastable to ``passed``
        Prediction times, increasing along the last axis.
    passed : array_like of bool, shape (..., K)
    eol : array_like
        True end of life, broadcastable to ``passed[..., 0]``.

    Returns
    -------
    ndarray or float, shape (...)

    Examples
    --------
    >>> float(prognostic_horizon([10, 20, 30, 40], [True, False, True, True], eol=50))  # from t = 30
    20.0
    >>> float(prognostic_horizon([10, 20, 30, 40], [True, True, True, False], eol=50))
    nan
    """
    ok = np.asarray(passed, dtype=bool)
    if ok.ndim == 0 or ok.shape[-1] == 0:
        raise PrognosisError(f"passed must have shape (..., K) with K >= 1, got shape {ok.shape}")
    t = np.broadcast_to(np.asarray(times, dtype=float), ok.shape)
    if (np.diff(t, axis=-1) < 0).any():
        raise PrognosisError("prediction times must be increasing")
    suffix = np.flip(np.logical_and.accumulate(np.flip(ok, axis=-1), axis=-1), axis=-1)
    start = np.take_along_axis(t, np.argmax(suffix, axis=-1)[..., None], axis=-1)[..., 0]
    return np.where(suffix[..., -1], np.asarray(eol, dtype=float) - start, np.nan)[()]


def cumulative_relative_accuracy(ra: ArrayLike, weights: ArrayLike | None = None, axis: int = -1) -> np.ndarray | float:
    """Cumulative relative accuracy (Saxena et al. 2010).

    ``CRA = sum_l w_l RA_l / sum_l w_l``

    over the prediction points ``l`` along ``axis``: a normalized weighted
    sum, equal to mean RA (Jha et al. (2016), eq. 43) for the default uniform weights.
    Saxena et al. suggest weights growing as the RUL shrinks, so late
    predictions, closer to failure, count more.  Points where RA is NaN are
    dropped together with their weights.

    Parameters
    ----------
    ra : array_like, shape (..., K)
        Relative accuracy at the prediction points (:func:`relative_accuracy`).
    weights : array_like, optional
        Non-negative; a 1-D vector lies along ``axis``, otherwise broadcastable to ``ra``.
    axis : int
        Axis of the prediction points (default: last).

    Examples
    --------
    >>> round(float(cumulative_relative_accuracy([0.5, 0.9, 1.0], [1, 2, 3])), 12)  # (0.5 + 1.8 + 3) / 6
    0.883333333333
    """
    values = last_axis(ra, axis)
    w = weights_like(values, moved_weights(weights, np.shape(ra), axis))
    known = ~np.isnan(values)
    w = np.where(known, w, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return (np.sum(w * np.where(known, values, 0.0), axis=-1) / np.sum(w, axis=-1))[()]


def convergence(times: ArrayLike, metric_values: ArrayLike, t_start: ArrayLike | None = None) -> np.ndarray | float:
    """Convergence of a metric (Saxena et al. 2010): distance to the centroid of its area.

    The metric ``M`` (non-negative, an error or a spread, smaller is better)
    is taken piecewise constant, ``M_i`` on ``[t_i, t_{i+1})``, ``i = 0..K-2``;
    the last value ``M_{K-1}`` only closes the curve and does not enter.
    The centroid of the area under this step curve is

    ``x_c = (1/2) sum_i (t_{i+1}^2 - t_i^2) M_i / sum_i (t_{i+1} - t_i) M_i``,

    ``y_c = (1/2) sum_i (t_{i+1} - t_i) M_i^2 / sum_i (t_{i+1} - t_i) M_i``,

    exactly the sums printed by Saxena et al. (each interval is a rectangle
    of area ``(t_{i+1} - t_i) M_i`` centred on ``((t_i + t_{i+1})/2, M_i/2)``),
    and the convergence is

    ``C = sqrt((x_c - t_start)^2 + y_c^2)``.

    A smaller ``C`` means faster convergence.  A zero area (``M_i = 0`` on
    every interval) leaves the centroid undefined: NaN.

    Parameters
    ----------
    times : array_like, shape (K,) or broadcastable to ``metric_values``
        Increasing prediction times, ``K >= 2``.
    metric_values : array_like, shape (..., K)
        The metric at each time (leading axes: assets).
    t_start : array_like, optional
        Reference start time (Saxena's ``t_P``); default ``times[..., 0]``.

    Examples
    --------
    >>> round(float(convergence([0.0, 1.0, 2.0], [2.0, 1.0, 5.0])), 12)  # centroid (5/6, 5/6)
    1.178511301978
    """
    m = np.asarray(metric_values, dtype=float)
    if m.ndim == 0 or m.shape[-1] < 2:
        raise PrognosisError(f"need at least 2 prediction times along the last axis, got shape {m.shape}")
    t = np.broadcast_to(np.asarray(times, dtype=float), m.shape)
    dt = np.diff(t, axis=-1)
    if (dt < 0).any():
        raise PrognosisError("prediction times must be increasing")
    left = m[..., :-1]
    area = np.sum(dt * left, axis=-1)
    start = t[..., 0] if t_start is None else np.asarray(t_start, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        x_c = 0.5 * np.sum(np.diff(t**2, axis=-1) * left, axis=-1) / area
        y_c = 0.5 * np.sum(dt * left**2, axis=-1) / area
    return np.hypot(x_c - start, y_c)[()]




def scores_against_truth(times: ArrayLike, percentiles: ArrayLike, rul_mean: ArrayLike, eol: float,
                         alpha: float = 0.2) -> dict:
    """How the RUL predictions of one run compare with a known end of life: what ``--truth`` reports.

    Parameters
    ----------
    times : array_like, shape (K,)
        Prediction times (s); NaN rows of ``percentiles`` (withheld predictions) are left out.
    percentiles : array_like, shape (K, 5)
        The 5th, 25th, 50th, 75th and 95th percentiles of each predicted RUL (``inf`` beyond the horizon; NaN
        quartiles when they are not known: ``coverage_50`` is then None).
    rul_mean : array_like, shape (K,)
        The mean RUL of each prediction.
    eol : float
        The true end of life (s).
    alpha : float
        Half-width of the accuracy cone, relative to the true RUL: a median within ``alpha`` of it passes.

    Returns
    -------
    dict
        ``predictions`` (made before the end of life), ``true_rul`` and per prediction
        ``relative_accuracy`` (eq. 42, of the mean), ``within_alpha`` (the median) and ``inside_90``
        (the 5-95 % band); over them ``mean_relative_accuracy`` and ``worst_relative_accuracy``,
        ``coverage_90`` and ``coverage_50`` (the share of predictions whose 5-95 % and 25-75 % bands
        hold the true RUL, the bands' claims), ``within_alpha_share`` and the ``prognostic_horizon``
        (s) of the alpha criterion.  NaN (no prediction) becomes None.

    Examples
    --------
    >>> q = np.array([[8.0, 9.0, 10.0, 11.0, 12.0], [3.0, 3.5, 4.0, 4.4, 5.0]])
    >>> s = scores_against_truth([0.0, 6.0], q, [10.0, 4.0], eol=10.5)
    >>> s["true_rul"], s["coverage_90"], s["coverage_50"], s["within_alpha"]
    ([10.5, 4.5], 1.0, 0.5, [True, True])
    >>> round(s["mean_relative_accuracy"], 4), s["prognostic_horizon"]
    (0.9206, 10.5)
    """
    t = np.asarray(times, dtype=float)
    q = np.asarray(percentiles, dtype=float).reshape(t.size, 5)
    mean = np.asarray(rul_mean, dtype=float).reshape(t.size)
    true = float(eol) - t
    kept = (true > 0) & np.isfinite(q[:, 2])  # before the end of life, and a prediction made (not withheld)
    t, q, mean, true = t[kept], q[kept], mean[kept], true[kept]
    ra = relative_accuracy(true, mean) if t.size else np.empty(0)
    within = np.abs(q[:, 2] - true) <= alpha * true
    inside_90 = (q[:, 0] <= true) & (true <= q[:, 4])
    scores = {"predictions": int(t.size), "alpha": alpha, "true_rul": true.tolist(),
              "relative_accuracy": np.atleast_1d(ra).tolist(), "within_alpha": within.tolist(),
              "inside_90": inside_90.tolist()}
    if not t.size:
        return {**scores, **dict.fromkeys(("mean_relative_accuracy", "worst_relative_accuracy", "coverage_90",
                                            "coverage_50", "within_alpha_share", "prognostic_horizon"))}

    def finite(value) -> float | None:
        return float(value) if np.isfinite(value) else None

    quartiles = ~np.isnan(q[:, 1]) & ~np.isnan(q[:, 3])  # NaN: not given (a fleet's table keeps 5, 50, 95 %)
    inner = (q[:, 1] <= true) & (true <= q[:, 3])
    return {**scores, "mean_relative_accuracy": finite(np.mean(ra)), "worst_relative_accuracy": finite(np.min(ra)),
            "coverage_90": float(np.mean(inside_90)),
            "coverage_50": float(np.mean(inner[quartiles])) if quartiles.any() else None,
            "within_alpha_share": float(np.mean(within)),
            "prognostic_horizon": finite(prognostic_horizon(t, within, eol))}


def pooled_scores(scores: dict) -> dict:
    """Many runs' :func:`scores_against_truth` (one per asset) pooled prediction by prediction: each prediction
    weighs the same, whichever asset made it.

    Returns the number of ``assets`` and ``predictions``, the ``mean_relative_accuracy`` over every prediction
    and the ``worst_relative_accuracy``, the mean and worst of the assets' own mean accuracies
    (``asset_mean_relative_accuracy``, ``asset_worst_mean_relative_accuracy``), ``coverage_90`` and
    ``within_alpha_share`` (None without a prediction).

    >>> one = scores_against_truth([0.0], [[8.0, 9.0, 10.0, 11.0, 12.0]], [10.0], eol=10.5)
    >>> two = scores_against_truth([0.0, 1.0], [[1.0, 2.0, 3.0, 4.0, 5.0]] * 2, [3.0, 3.0], eol=7.0)
    >>> pooled = pooled_scores({"a": one, "b": two})
    >>> pooled["assets"], pooled["predictions"], round(pooled["coverage_90"], 4)
    (2, 3, 0.3333)
    """
    used = [s for s in scores.values() if s.get("predictions")]
    ra = np.concatenate([np.asarray(s["relative_accuracy"], float) for s in used]) if used else np.empty(0)
    inside = np.concatenate([np.asarray(s["inside_90"], bool) for s in used]) if used else np.empty(0, bool)
    within = np.concatenate([np.asarray(s["within_alpha"], bool) for s in used]) if used else np.empty(0, bool)
    means = np.array([s["mean_relative_accuracy"] if s["mean_relative_accuracy"] is not None else -np.inf
                      for s in used])

    def finite(value) -> float | None:
        return float(value) if np.isfinite(value) else None

    if not ra.size:
        return {"assets": len(used), "predictions": 0, **dict.fromkeys((
            "mean_relative_accuracy", "worst_relative_accuracy", "asset_mean_relative_accuracy",
            "asset_worst_mean_relative_accuracy", "coverage_90", "within_alpha_share"))}
    return {"assets": len(used), "predictions": int(ra.size), "mean_relative_accuracy": finite(np.mean(ra)),
            "worst_relative_accuracy": finite(np.min(ra)), "asset_mean_relative_accuracy": finite(np.mean(means)),
            "asset_worst_mean_relative_accuracy": finite(np.min(means)), "coverage_90": float(np.mean(inside)),
            "within_alpha_share": float(np.mean(within))}
