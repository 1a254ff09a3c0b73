"""Kalman filter and Rauch-Tung-Striebel smoother of a linear Gaussian model: the E-step of EM.

The cross-covariance ``S`` of the process and measurement noises is handled exactly, missing
outputs (NaN) are skipped, and the log-likelihood comes from the innovations (Gasperin et al.
(2011), eq. 10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import _linalg as linalg
from .linear_gaussian import LinearGaussianModel, check_model_data

__all__ = [
    "STATIONARY_TOLERANCE", "SmootherResult", "filter_arrays", "kalman_smoother", "log_likelihood",
    "smooth_arrays",
]


@dataclass(frozen=True, eq=False)
class SmootherResult:
    """Kalman filter and RTS smoother output for ``y_1..y_T`` (row ``t - 1`` is time ``t``).

    Attributes
    ----------
    predicted_means, predicted_covariances : (T, n), (T, n, n)
        ``x_{t|t-1} = E[x_t | y_1..y_{t-1}]`` and its covariance (row 0 is ``mu1``, ``P1``).
    filtered_means, filtered_covariances : (T, n), (T, n, n)
        ``x_{t|t} = E[x_t | y_1..y_t]`` and its covariance.
    smoothed_means, smoothed_covariances : (T, n), (T, n, n)
        ``x_{t|T} = E[x_t | y_1..y_T]`` and ``P_{t|T}``.
    lag_one_covariances : (T - 1, n, n)
        ``M_t = Cov(x_{t+1}, x_t | y_1..y_T)`` for ``t = 1..T-1``.
    next_mean, next_covariance : (n,), (n, n)
        ``x_{T+1|T}`` and its covariance, the start of a prediction beyond the data (uses ``u_T``).
    log_likelihood : float
        ``log p(y_1..y_T)`` (eq. 10) over the observed rows.
    observed : (T,) bool
        False where the row of ``y`` contained NaN (missing: no measurement update).

    Examples
    --------
    Returned by :func:`kalman_smoother`.  A constant seen at times 1 and 3 (time 2 missing):

    >>> m = LinearGaussianModel(A=[[1.0]], B=None, C=[[1.0]], D=None, Q=[[0.0]], R=[[1.0]], P1=[[1e6]])
    >>> res = kalman_smoother(m, [1.0, np.nan, 3.0])
    >>> res.observed.tolist(), res.smoothed_means.shape, res.lag_one_covariances.shape
    ([True, False, True], (3, 1), (2, 1, 1))
    >>> np.round(res.filtered_means[:, 0], 4).tolist(), np.round(res.smoothed_means[:, 0], 4).tolist()
    ([1.0, 1.0, 2.0], [2.0, 2.0, 2.0])
    >>> round(float(res.next_mean[0]), 4), round(float(res.next_covariance[0, 0]), 4)
    (2.0, 0.5)
    >>> bool(np.isclose(res.log_likelihood, log_likelihood(m, [1.0, np.nan, 3.0])))
    True
    """

    predicted_means: np.ndarray
    predicted_covariances: np.ndarray
    filtered_means: np.ndarray
    filtered_covariances: np.ndarray
    smoothed_means: np.ndarray
    smoothed_covariances: np.ndarray
    lag_one_covariances: np.ndarray
    next_mean: np.ndarray
    next_covariance: np.ndarray
    log_likelihood: float
    observed: np.ndarray


def kalman_smoother(model: LinearGaussianModel, y: ArrayLike, u: ArrayLike | None = None) -> SmootherResult:
    """E-step: Kalman filter, Rauch-Tung-Striebel smoother and lag-one covariances, exact with ``S != 0``.

    Filter (``t = 1..T``), from ``x_{1|0} = mu1``, ``P_{1|0} = P1``::

        e_t = y_t - C x_{t|t-1} - D u_t,        S_t = C P_{t|t-1} C^T + R = L_t L_t^T   (Cholesky)
        x_{t|t} = x_{t|t-1} + P_{t|t-1} C^T S_t^-1 e_t,   P_{t|t} = P_{t|t-1} - P_{t|t-1} C^T S_t^-1 C P_{t|t-1}
        log p(Y) = sum_t -1/2 (m log 2 pi + log det S_t + e_t^T S_t^-1 e_t)                          (eq. 10)

    ``w_t`` is correlated with ``v_t`` (and so with ``y_t``); writing ``w_t = S R^-1 v_t + w~_t`` gives
    the equivalent model with uncorrelated noises used for the time update::

        x_{t+1} = (A - S R^-1 C) x_t + (B - S R^-1 D) u_t + S R^-1 y_t + w~_t,   Cov(w~_t) = Q - S R^-1 S^T.

    Smoother (``t = T-1..1``), with ``F_t`` the transition matrix used at ``t`` (the decorrelated one,
    or ``A`` when ``y_t`` is missing)::

        J_t = P_{t|t} F_t^T P_{t+1|t}^-1
        x_{t|T} = x_{t|t} + J_t (x_{t+1|T} - x_{t+1|t}),   P_{t|T} = P_{t|t} + J_t (P_{t+1|T} - P_{t+1|t}) J_t^T
        Cov(x_{t+1}, x_t | Y) = P_{t+1|T} J_t^T.

    Parameters
    ----------
    model : LinearGaussianModel
    y : array (T,) or (T, m)
        Outputs; a row containing NaN is a missing measurement (the whole row is skipped: no update, no
        log-likelihood term, and the time update uses ``A``, ``B``, ``Q`` since ``v_t`` is not seen).
    u : array (T, r), or None when the model has no inputs

    Example
    -------
    >>> m = LinearGaussianModel(A=[[1.0]], B=None, C=[[1.0]], D=None, Q=[[0.0]], R=[[1.0]], P1=[[1e6]])
    >>> res = kalman_smoother(m, [1.0, 2.0, 3.0])   # a constant seen three times: the mean, 2
    >>> round(float(res.smoothed_means[0, 0]), 4), round(float(res.smoothed_covariances[0, 0, 0]), 4)
    (2.0, 0.3333)
    """
    y, u = check_model_data(model, y, u)
    return smooth_arrays(model, y, u)


def log_likelihood(model: LinearGaussianModel, y: ArrayLike, u: ArrayLike | None = None) -> float:
    """``log p(y_1..y_T | theta)`` from the innovations of the Kalman filter (Gasperin et al. (2011), eq. 10).

    ``sum_t -1/2 (m log 2 pi + log det S_t + e_t^T S_t^-1 e_t)`` over the observed rows (see
    :func:`kalman_smoother` for ``e_t``, ``S_t`` and missing rows).

    Example
    -------
    >>> m = LinearGaussianModel(A=[[0.0]], B=None, C=[[1.0]], D=None, Q=[[1.0]], R=[[1.0]], P1=[[1.0]])
    >>> from scipy.stats import norm
    >>> bool(np.isclose(log_likelihood(m, [0.3, -1.2]), norm.logpdf([0.3, -1.2], scale=np.sqrt(2)).sum()))
    True
    """
    y, u = check_model_data(model, y, u)
    return filter_arrays(model, y, u).log_likelihood


#: The covariance recursions stop when the predicted covariance changes by less than this (relative, max-abs)
#: between two observed steps, and copy the stationary values until the next missing row.
STATIONARY_TOLERANCE = 1e-12


@dataclass
class _Filtered:
    predicted_means: np.ndarray
    predicted_covariances: np.ndarray
    filtered_means: np.ndarray
    filtered_covariances: np.ndarray
    transitions: np.ndarray  # (T, n, n): F_t, the matrix that maps x_{t|t} to x_{t+1|t}
    repeated: np.ndarray  # (T,) bool: the covariances, gain and F_t at t are those at t - 1 (stationary)
    next_mean: np.ndarray
    next_covariance: np.ndarray
    log_likelihood: float
    observed: np.ndarray


def filter_arrays(model: LinearGaussianModel, y: np.ndarray, u: np.ndarray) -> _Filtered:
    """The Kalman filter of :func:`kalman_smoother` on checked arrays (``y`` (T, m) with NaN rows, ``u`` (T, r)).

    Returns the filtered and predicted moments and the log-likelihood; the steady state is detected
    (:data:`STATIONARY_TOLERANCE`) so a long window costs no more covariance updates than needed.
    """
    a, c, q, r = model.A, model.C, model.Q, model.R
    steps, n, m = y.shape[0], model.n_states, model.n_outputs
    observed = ~np.isnan(y).any(axis=1)
    y0 = np.where(observed[:, None], y, 0.0)
    drive = u @ model.B.T  # B u_t
    feed = u @ model.D.T  # D u_t
    if np.any(model.S):
        decorrelate = linalg.solve_psd(r, model.S.T).T  # S R^-1
        a_dec = a - decorrelate @ c
        q_dec = linalg.symmetric(q - decorrelate @ model.S.T)
        drive_dec = drive + (y0 - feed) @ decorrelate.T  # (B - S R^-1 D) u_t + S R^-1 y_t
    else:
        a_dec, q_dec, drive_dec = a, q, drive
    # 1. covariances and the factors of S_t = C P_{t|t-1} C^T + R = L_t L_t^T: they do not depend on y
    pp = np.empty((steps, n, n))
    pf = np.empty((steps, n, n))
    whitened = np.zeros((steps, m, n))  # W_t = L_t^-1 C P_{t|t-1}, so P C^T S^-1 C P = W^T W
    roots = np.zeros((steps, m, m))
    repeated = np.zeros(steps, dtype=bool)
    p = model.P1.copy()
    ct, a_dec_t, a_t = c.T, a_dec.T, a.T
    scalar = m == 1
    t = 0
    while t < steps:
        pp[t] = p
        if observed[t]:
            cp = c @ p
            if scalar:  # one output: S_t is a number, no factorization needed
                root = np.sqrt(cp @ ct + r)
                w = cp / root
            else:
                root = np.linalg.cholesky(cp @ ct + r)
                w = np.linalg.solve(root, cp)
            whitened[t], roots[t] = w, root
            pf[t] = pt = p - w.T @ w
            p_next = a_dec @ pt @ a_dec_t + q_dec
        else:
            pf[t] = p
            p_next = a @ p @ a_t + q
        p_next = 0.5 * (p_next + p_next.T)
        if observed[t] and t % 4 == 0 and abs(p_next - p).max() <= STATIONARY_TOLERANCE * abs(p).max():
            stop = t + 1
            while stop < steps and observed[stop]:
                stop += 1
            for array in (pp, pf, whitened, roots):
                array[t + 1:stop] = array[t]
            repeated[t + 1:stop] = True
            t = stop
            p = p_next
            continue
        p = p_next
        t += 1
    pf = 0.5 * (pf + np.swapaxes(pf, 1, 2))
    transitions = np.where(observed[:, None, None], a_dec, a)  # F_t
    if scalar:
        gains = np.swapaxes(whitened, 1, 2) / np.where(observed[:, None, None], roots, 1.0)  # K_t = W^T / L
    else:
        gains = np.swapaxes(np.linalg.solve(np.swapaxes(roots, 1, 2)[observed], whitened[observed]), 1, 2)
        gains = _scatter(gains, observed, (steps, n, m))
    # 2. means: x_{t+1|t} = F_t (I - K_t C) x_{t|t-1} + F_t K_t (y_t - D u_t) + b_t
    closed = transitions - transitions @ gains @ c
    offset = np.einsum("tij,tj->ti", transitions @ gains, y0 - feed) + np.where(observed[:, None], drive_dec, drive)
    xp = np.empty((steps, n))
    x = model.mu1.copy()
    for t, (phi, g) in enumerate(zip(list(closed), list(offset))):
        xp[t] = x
        x = phi @ x + g
    # 3. innovations, filtered means and eq. (10)
    innovations = y0 - xp @ c.T - feed
    xf = xp + np.einsum("tij,tj->ti", gains, innovations)
    seen = np.flatnonzero(observed)
    loglik = 0.0
    if seen.size:
        white = np.linalg.solve(roots[seen], innovations[seen][:, :, None])[:, :, 0]  # L_t^-1 e_t
        logdet = 2.0 * np.log(np.diagonal(roots[seen], axis1=1, axis2=2)).sum()
        loglik = -0.5 * (seen.size * m * _LOG_2PI + logdet + np.sum(white ** 2))
    return _Filtered(xp, pp, xf, pf, transitions, repeated, x, p, float(loglik), observed)


def smooth_arrays(model: LinearGaussianModel, y: np.ndarray, u: np.ndarray) -> SmootherResult:
    """The Rauch-Tung-Striebel smoother of :func:`kalman_smoother` on checked arrays."""
    fl = filter_arrays(model, y, u)
    steps, n = y.shape[0], model.n_states
    pf, pp, xf, xp = fl.filtered_covariances, fl.predicted_covariances, fl.filtered_means, fl.predicted_means
    xs = xf.copy()
    ps = pf.copy()
    if steps > 1:
        # J_t^T = P_{t+1|t}^-1 F_t P_{t|t}, all t at once (Cholesky solves, a pseudo-inverse if singular)
        gains_t = linalg.solve_psd_stack(pp[1:], fl.transitions[:-1] @ pf[:-1])
        gains = np.swapaxes(gains_t, 1, 2)
        gain_list, gain_t_list, pf_list, pp_list = list(gains), list(gains_t), list(pf), list(pp)
        t = steps - 2
        nxt = ps[t + 1]
        while t >= 0:
            nxt = ps[t] = pf_list[t] + gain_list[t] @ (nxt - pp_list[t + 1]) @ gain_t_list[t]
            if t % 4 == 0 and abs(nxt - ps[t + 1]).max() <= STATIONARY_TOLERANCE * abs(nxt).max():
                while t >= 1 and fl.repeated[t] and fl.repeated[t + 1]:  # J_{t-1} = J_t: ps[t-1] = ps[t]
                    ps[t - 1] = nxt
                    t -= 1
            t -= 1
        ps = 0.5 * (ps + np.swapaxes(ps, 1, 2))
        # x_{t|T} = J_t x_{t+1|T} + (x_{t|t} - J_t x_{t+1|t})
        offset = list(xf[:-1] - np.einsum("tij,tj->ti", gains, xp[1:]))
        x = xs[-1]
        for t in range(steps - 2, -1, -1):
            x = xs[t] = gain_list[t] @ x + offset[t]
        lag = ps[1:] @ gains_t
    else:
        lag = np.empty((0, n, n))
    return SmootherResult(xp, pp, xf, pf, xs, ps, lag, fl.next_mean, fl.next_covariance, fl.log_likelihood,
                          fl.observed)


def _scatter(values: np.ndarray, mask: np.ndarray, shape: tuple) -> np.ndarray:
    out = np.zeros(shape)
    out[mask] = values
    return out


_LOG_2PI = float(np.log(2.0 * np.pi))
