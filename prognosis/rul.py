"""Remaining useful life by propagating the particles to the failure threshold (seed 003 Table IV).

Each particle keeps its weight and is propagated with its degradation model
and the random walk of its gamma until theta crosses ``theta_fail`` (upwards or
downwards).  The horizon is processed in chunks of steps: inside a chunk the
path of every particle comes from cumulative sums (:meth:`path` of the
degradation model), so there is no per-particle and no per-step loop for the
linear and exponential models; only particles that have not failed yet are
carried into the next chunk, and chunks grow from 32 steps.  Particles that have not crossed when the
horizon cap is reached are *censored*: their RUL is ``+inf`` and they are
counted, not dropped.  The mean is over crossed particles (renormalized) and
reported with the censored weight; median and percentiles treat censored
particles as ``+inf``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class RULPrediction:
    """RUL distribution per asset: ``samples`` (A, N) in seconds (inf if censored) with ``weights``."""

    samples: np.ndarray
    weights: np.ndarray
    horizon: float

    @property
    def censored(self) -> np.ndarray:
        return ~np.isfinite(self.samples)

    @property
    def censored_weight(self) -> np.ndarray:
        return np.sum(np.where(self.censored, self.weights, 0.0), axis=-1)

    @property
    def mean(self) -> np.ndarray:
        """Weighted mean over particles that cross within the horizon (NaN if none do)."""
        w = np.where(self.censored, 0.0, self.weights)
        total = w.sum(axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(total > 0, np.sum(w * np.where(self.censored, 0.0, self.samples), axis=-1) / total, np.nan)

    def percentile(self, q) -> np.ndarray:
        """Weighted percentiles (q in [0, 100]), censored samples as +inf; shape (A, len(q))."""
        q = np.atleast_1d(np.asarray(q, float)) / 100.0
        order = np.argsort(self.samples, axis=-1)
        values = np.take_along_axis(self.samples, order, axis=-1)
        cumulative = np.cumsum(np.take_along_axis(self.weights, order, axis=-1), axis=-1)
        cumulative /= cumulative[..., -1:]
        index = np.stack([np.argmax(cumulative >= level - 1e-12, axis=-1) for level in q], axis=-1)
        return np.take_along_axis(values, index, axis=-1)

    @property
    def median(self) -> np.ndarray:
        return self.percentile(50.0)[..., 0]


def predict_rul(model, theta: np.ndarray, gamma: np.ndarray, weights: np.ndarray, *, dt: float,
                theta_fail: float, gamma_std, direction: str = "up", horizon: float = 1000.0,
                rng: np.random.Generator, chunk: int = 512) -> RULPrediction:
    """Propagate particles until ``theta`` crosses ``theta_fail``.

    Parameters
    ----------
    model : degradation model with ``path``
    theta : (A, N); gamma : (A, N, G); weights : (A, N)
    dt : float
        Step of the propagation (the filter's step).
    theta_fail : float
        Failure value of theta.
    gamma_std : array (A, G) or scalar
        Random-walk standard deviation of gamma during the prediction.
    direction : {"up", "down"}
        Failure when theta rises above (``up``) or falls below ``theta_fail``.
    horizon : float
        Cap in seconds; particles not failed by then are censored.
    rng : numpy Generator
    chunk : int
        Most steps propagated at once (chunks start at 32 steps and double).

    Examples
    --------
    >>> import numpy as np
    >>> from prognosis.degradation import Linear
    >>> rul = predict_rul(Linear(), np.array([[0.0]]), np.array([[[1.0]]]), np.array([[1.0]]), dt=0.1,
    ...                   theta_fail=2.0, gamma_std=0.0, rng=np.random.default_rng(0))
    >>> float(rul.samples[0, 0])
    2.0
    """
    if direction not in ("up", "down"):
        raise ValueError(f"direction must be 'up' or 'down', got {direction!r}")
    assets, n, g = gamma.shape
    std = np.broadcast_to(np.broadcast_to(np.asarray(gamma_std, float), (assets, g))[:, None, :], (assets, n, g))
    steps_total = int(np.ceil(horizon / dt - 1e-9))
    # flatten assets x particles and carry only the particles that have not failed yet
    theta_now, gamma_now = theta.astype(float).reshape(-1), gamma.astype(float).reshape(-1, g)
    std = std.reshape(-1, g)
    rul = np.full(theta_now.size, np.inf)
    failed = _crossed(theta_now, theta_fail, direction)
    rul[failed] = 0.0
    alive = np.flatnonzero(~failed)
    done, h = 0, min(chunk, 32)
    with np.errstate(over="ignore", invalid="ignore"):
        while done < steps_total and alive.size:
            h = min(h, steps_total - done)
            increments = rng.standard_normal((alive.size, h, g)) * std[alive, None, :]
            walk = np.cumsum(increments, axis=1)
            # gamma used at step l is gamma_{k+l-1}: the current one, then the random walk
            used = gamma_now[alive, None, :] + np.concatenate([np.zeros((alive.size, 1, g)), walk[:, :-1, :]], axis=1)
            noise = (rng.standard_normal((alive.size, h)) * model.process_noise if model.process_noise
                     else np.zeros((alive.size, h)))
            path = model.path(theta_now[alive], used, noise, dt)
            crossed = _crossed(path, theta_fail, direction) | np.isnan(path)  # NaN only after an overflow to inf
            hit = crossed.any(axis=1)
            rul[alive[hit]] = (done + np.argmax(crossed[hit], axis=1) + 1) * dt
            theta_now[alive], gamma_now[alive] = path[:, -1], gamma_now[alive] + walk[:, -1, :]
            alive = alive[~hit]
            done += h
            h = min(2 * h, chunk)  # short first chunks: near-failure particles leave early
    return RULPrediction(rul.reshape(assets, n), weights, horizon)


def _crossed(theta: np.ndarray, theta_fail: float, direction: str) -> np.ndarray:
    return theta >= theta_fail if direction == "up" else theta <= theta_fail
