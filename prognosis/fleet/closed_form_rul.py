"""RUL at fleet scale: closed-form crossing times per particle and per-asset mixture summaries.

A fleet predicts the RUL of every particle with its rate held at its estimate (the random walk and
the process noise are estimation devices of the filter, not models of the future: the ``named``
setting of :class:`~prognosis.health_monitor.HealthMonitor`, ``prediction_walk=0``).  The path of a
particle is then deterministic and, for the built-in laws, its crossing of the failure value has a
closed form:

* linear ``theta + gamma t``: ``t = (theta_fail - theta) / gamma``;
* exponential ``theta exp(gamma t)``: ``t = log(theta_fail / theta) / gamma``;

a particle at or beyond the failure value has RUL 0, one whose path never reaches it (a rate of
the wrong sign) or reaches it after the horizon is censored (``+inf``).  This costs a few
operations per particle instead of a path over the horizon, and needs no random numbers at all.
Other laws are propagated with :class:`~prognosis.rul.RULPredictor` (keyed by asset and step).

A summary reduces each asset's samples (its hypotheses' particles, weighted by the hypotheses'
posterior probabilities) to the mean over the particles that fail within the horizon, the 5, 50
and 95 % quantiles (censored particles counted as ``+inf``) and the censored weight, as
:class:`~prognosis.rul.RULDistribution` does.
"""

from __future__ import annotations

import numpy as np

from ..degradation import ExponentialDegradation, LinearDegradation

__all__ = ["LEVELS", "crossing_times", "has_closed_form", "summarize"]

LEVELS = (0.05, 0.5, 0.95)


def has_closed_form(law) -> bool:
    """Whether :func:`crossing_times` handles the law (linear and exponential)."""
    return isinstance(law, (LinearDegradation, ExponentialDegradation))


def crossing_times(law, theta: np.ndarray, rate: np.ndarray, theta_fail: np.ndarray, up: np.ndarray,
                   horizon: float) -> np.ndarray:
    """Time (s) for each particle to reach ``theta_fail`` with its rate held; ``inf`` beyond ``horizon``.

    ``theta``, ``rate`` (R, N); ``theta_fail`` and ``up`` (R,), ``up`` true where failure lies above.

    >>> crossing_times(LinearDegradation(), np.array([[1.0, 1.0, 3.0]]), np.array([[0.5, -0.5, 0.1]]),
    ...                np.array([2.0]), np.array([True]), horizon=10.0).tolist()
    [[2.0, inf, 0.0]]
    >>> crossing_times(ExponentialDegradation(), np.array([[1.0]]), np.array([[np.log(2.0)]]), np.array([4.0]),
    ...                np.array([True]), horizon=10.0).round(12).tolist()
    [[2.0]]
    """
    fail = np.asarray(theta_fail, float)[:, None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if isinstance(law, LinearDegradation):
            t = (fail - theta) / rate
        elif isinstance(law, ExponentialDegradation):
            t = np.log(fail / theta) / rate
        else:
            raise TypeError(f"no closed-form crossing time for {type(law).__name__}")
    t = np.where(np.isfinite(t) & (t > 0) & (t <= horizon), t, np.inf)
    failed = np.where(np.asarray(up)[:, None], theta >= fail, theta <= fail)
    t[failed] = 0.0
    return t


def summarize(samples: np.ndarray, weights: np.ndarray, equal: bool = False) -> dict:
    """Mean (over crossed samples), 5/50/95 % quantiles (censored as ``+inf``) and censored weight per row.

    ``samples``, ``weights`` (A, S); weights need not be normalized.  ``equal``: every row's weights
    are one positive value (one hypothesis per asset), so the quantiles are order statistics, found by
    a partial sort instead of a sort and a cumulative sum.

    >>> s = summarize(np.array([[1.0, 2.0, 4.0, np.inf]]), np.full((1, 4), 0.25))
    >>> np.round(s["mean"], 4).tolist(), s["p50"].tolist(), s["p95"].tolist(), s["censored"].tolist()
    ([2.3333], [2.0], [inf], [0.25])
    """
    out = _order_statistics(samples) if equal else _weighted_quantiles(samples, weights)
    # the total as the sorted path sums it (a running sum, not numpy's pairwise one): the same last bit
    total = np.add.accumulate(weights, axis=1)[:, -1] if equal else out.pop("total")
    finite = np.isfinite(samples)
    crossed = np.where(finite, weights, 0.0)
    mass = np.sum(crossed, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["mean"] = np.where(mass > 0, np.sum(crossed * np.where(finite, samples, 0.0), axis=1) / mass, np.nan)
        out["censored"] = np.where(total > 0, 1.0 - mass / total, 1.0)
    return out


def _weighted_quantiles(samples: np.ndarray, weights: np.ndarray) -> dict:
    """The first sample, in sorted order, whose cumulative weight reaches each level; with the weights' totals."""
    order = np.argsort(samples, axis=1, kind="stable")
    row = np.arange(samples.shape[0])[:, None]
    ordered = samples[row, order]
    cumulative = np.cumsum(weights[row, order], axis=1)
    total = cumulative[:, -1:]
    cumulative = cumulative / np.where(total > 0, total, 1.0)
    out = {"total": total[:, 0]}
    for level, name in zip(LEVELS, ("p5", "p50", "p95")):
        index = np.argmax(cumulative >= level - 1e-12, axis=1)
        out[name] = ordered[row[:, 0], index]
    return out


def _order_statistics(samples: np.ndarray) -> dict:
    """:func:`_weighted_quantiles` under equal weights: the sample of rank ``ceil(S (level - 1e-12)) - 1``."""
    size = samples.shape[1]
    ranks = [max(int(np.ceil(size * (level - 1e-12))) - 1, 0) for level in LEVELS]
    chosen = np.partition(samples, ranks, axis=1)[:, ranks]
    return {name: chosen[:, i] for i, name in enumerate(("p5", "p50", "p95"))}
