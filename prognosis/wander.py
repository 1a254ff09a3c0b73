"""A slowly wandering offset on the residuals: the likelihood of a local-level model in closed form.

A residual whose ARR integrates a signal, or reads a derivative through a filter, carries besides
its white noise an offset that wanders over tens of steps (the integral's drift, a lag that follows
the operating point).  A likelihood that takes the gaps as white reads that wander as wear: the
posterior narrows on a biased rate.  Here the whitened gaps ``u_j`` (:meth:`ResidualNoise.whiten
<prognosis.likelihood.ResidualNoise.whiten>`) are, per component, a local level plus white noise,

    u_j = b_j + e_j,    b_j = b_{j-1} + w_j,    e_j ~ N(0, 1),  w_j ~ N(0, lam),

with ``lam`` the walk's variance per step in units of the noise's.  The offset starts from its
steady-state spread, so the Kalman filter's gain ``k`` is the same at every step (Harvey (1989), the
local level model): the predicted offset is an exponential smoothing of the past gaps, the
innovation ``v_j = u_j - b_j|j-1`` has variance ``s = p + 1``, and the log-likelihood is the sum of
``log N(v_j; 0, s)``.  ``lam = 0`` is the white likelihood.  The smoothing runs in closed form over
blocks of steps, vectorized over particles and components, each particle with its own ``lam``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["steady_state", "innovations"]

BLOCK = 32  # steps smoothed in closed form at once: (1 - k)^-BLOCK stays far from overflow for lam <= 1


def steady_state(lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Kalman gain ``k`` and innovation variance ``s`` of the local level with walk variance ``lam``.

    The predicted offset's variance ``p`` solves ``p = p / (p + 1) + lam``: ``p = (lam + sqrt(lam^2
    + 4 lam)) / 2``; then ``k = p / (p + 1)`` and ``s = p + 1``.

    Examples
    --------
    >>> k, s = steady_state(np.array([0.0, 0.01, 1.0]))
    >>> k.round(3).tolist(), s.round(3).tolist()
    ([0.0, 0.095, 0.618], [1.0, 1.105, 2.618])
    """
    lam = np.asarray(lam, float)
    p = 0.5 * (lam + np.sqrt(lam * lam + 4.0 * lam))
    return p / (p + 1.0), p + 1.0


def innovations(white: np.ndarray, measured: np.ndarray, gain: np.ndarray,
                start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Innovations ``v_j = u_j - b_j|j-1`` (..., K, M) of whitened gaps and the offset predicted after them.

    ``white`` (..., K, M); ``measured`` (..., K, M) bool (an unmeasured step leaves the offset as it
    was and has no innovation: 0); ``gain`` broadcastable to (..., M); ``start`` (..., M) the offset
    predicted for the first step.  The prediction is ``b_j+1 = b_j + k v_j``.

    Examples
    --------
    With gain 0.5 the offset follows a step in the gaps halfway each step:

    >>> v, end = innovations(np.ones((1, 4, 1)), np.ones((1, 4, 1), bool), np.array([0.5]), np.zeros((1, 1)))
    >>> v[0, :, 0].tolist(), end.tolist()
    ([1.0, 0.5, 0.25, 0.125], [[0.9375]])
    """
    white = np.asarray(white, float)
    steps = white.shape[-2]
    decay = np.broadcast_to(1.0 - np.asarray(gain, float), start.shape)[..., None, :]  # (..., 1, M)
    gain = 1.0 - decay
    level = np.asarray(start, float)
    if not np.any(gain):  # white residuals (the common case): the innovations are the gaps
        return np.where(measured, white, 0.0), level
    out = np.empty(np.broadcast_shapes(white.shape, start.shape[:-1] + white.shape[-2:]))
    if not np.all(measured):  # rare: step by step, an unmeasured step neither moves nor scores
        for j in range(steps):
            seen = measured[..., j, :]
            v = np.where(seen, white[..., j, :] - level, 0.0)
            out[..., j, :] = v
            level = level + gain[..., 0, :] * v
        return out, level
    for first in range(0, steps, BLOCK):
        block = white[..., first:first + BLOCK, :]
        n = block.shape[-2]
        power = decay ** np.arange(n + 1)[:, None]  # (..., n + 1, M): (1 - k)^j
        # b_j = (1 - k)^j [b_0 + k sum_{i<j} (1 - k)^-(i+1) u_i]: an exclusive cumulative sum
        with np.errstate(divide="ignore", invalid="ignore"):
            scaled = np.where(power[..., 1:, :] > 0, block / power[..., 1:, :], 0.0)
        total = np.cumsum(scaled, axis=-2)
        before = np.concatenate([np.zeros_like(total[..., :1, :]), total], axis=-2)
        levels = power * (level[..., None, :] + gain * before)  # (..., n + 1, M): b_0 .. b_n
        if np.any(decay == 0):  # gain 1 (only lam -> inf): the offset is the last gap
            last = np.concatenate([level[..., None, :] + 0 * block[..., :1, :], block], axis=-2)
            levels = np.where(decay == 0, last, levels)
        out[..., first:first + n, :] = block - levels[..., :-1, :]
        level = levels[..., -1, :]
    return out, level
