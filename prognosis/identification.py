"""Linear Gaussian state-space identification by EM, for fault-trend detection and prediction (seed 004).

Model (seed 004 eqs. 2-3)::

    x_{t+1} = A x_t + B u_t + w_t,        [w_t]      (    [Q    S])
    y_t     = C x_t + D u_t + v_t,        [v_t]  ~ N (0,  [S^T  R]),     x_1 ~ N(mu1, P1),

with ``n`` states, ``r`` known inputs (operating conditions: torque, temperature) and ``m`` outputs (the
vibration feature).  Time runs ``t = 1..T`` in the formulas and rows ``0..T-1`` in the arrays.

* :func:`kalman_smoother` is the E-step: Kalman filter and Rauch-Tung-Striebel smoother, with the
  cross-covariance ``S`` handled exactly, and the log-likelihood of eq. (10) from the innovations.
* :func:`em_step` is one EM iteration (eqs. 14-23, Gibson and Ninness 2005); :func:`fit_em` iterates it.
* :class:`OnlineEM` re-identifies the model on a sliding window (section 3.4).
* :func:`fault_trend` and :func:`detect_trend` read the fault trend off the spectral radius of ``A``
  (section 5.1); :func:`predict_feature` predicts the feature under a known future load (section 5.2).

Example
-------
>>> truth = LinearGaussianModel(A=[[0.9]], B=[[0.5]], C=[[1.0]], D=[[0.2]], Q=[[0.05]], R=[[0.1]])
>>> u = np.random.default_rng(0).standard_normal((500, 1))
>>> _, y = truth.simulate(u, rng=0)
>>> fit = fit_em(y, u, n_states=1, cross_covariance=False)
>>> bool(np.all(np.diff(fit.log_likelihood) >= -1e-9 * np.abs(fit.log_likelihood[1:])))
True
>>> bool(abs(fit.model.eigenvalues[0] - 0.9) < 0.05)
True
>>> bool(fault_trend(fit.model))   # stable: no fault progression
False
"""

from __future__ import annotations

import warnings
from collections import deque
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike
from scipy.stats import norm

__all__ = [
    "EMResult", "FeaturePrediction", "IdentificationWarning", "LinearGaussianModel", "OnlineEM", "SmootherResult",
    "WindowIdentification", "detect_trend", "em_step", "fault_trend", "fit_em", "initial_model",
    "kalman_smoother", "log_likelihood", "predict_feature",
]

#: Eigenvalues of Q, R (with S: of Q - S R^-1 S^T) and P1 are floored at this fraction of the largest one
#: after an M-step, and never below EIGENVALUE_FLOOR_ABSOLUTE.
EIGENVALUE_FLOOR = 1e-10
EIGENVALUE_FLOOR_ABSOLUTE = 1e-150
_LOG_2PI = float(np.log(2.0 * np.pi))


class IdentificationWarning(RuntimeWarning):
    """An M-step had to floor the eigenvalues of a noise covariance (the model is close to degenerate)."""


# ----------------------------------------------------------------------------------------------- model

@dataclass(frozen=True, eq=False, repr=False)
class LinearGaussianModel:
    """``x_{t+1} = A x_t + B u_t + w_t``, ``y_t = C x_t + D u_t + v_t`` (seed 004 eqs. 2-3).

    ``[w_t; v_t] ~ N(0, [[Q, S], [S^T, R]])`` independently over ``t`` and of ``x_1 ~ N(mu1, P1)``.

    Parameters
    ----------
    A : array (n, n)
    B : array (n, r), or None for a model without inputs (``r = 0``)
    C : array (m, n)
    D : array (m, r), or None (zeros; ``r`` is taken from ``B``)
    Q : array (n, n), symmetric positive semi-definite
    R : array (m, m), symmetric positive definite
    S : array (n, m), or None for ``S = 0``.  ``[[Q, S], [S^T, R]]`` must be positive semi-definite.
    mu1 : array (n,), or None for zeros
    P1 : array (n, n), symmetric positive semi-definite, or None for the identity

    Arrays are stored as read-only float arrays; a bad shape, a non-finite entry, an asymmetric or
    indefinite covariance raises a ``ValueError`` that names the matrix.

    Example
    -------
    >>> m = LinearGaussianModel(A=[[0.5, 0.1], [0.0, 1.02]], B=None, C=[[1.0, 1.0]], D=None,
    ...                         Q=0.01 * np.eye(2), R=[[0.1]])
    >>> (m.n_states, m.n_inputs, m.n_outputs), round(m.spectral_radius, 2), m.is_stable
    ((2, 0, 1), 1.02, False)
    >>> x, y = m.simulate(steps=5, rng=1)
    >>> x.shape, y.shape
    ((5, 2), (5, 1))
    """

    A: np.ndarray
    B: np.ndarray | None
    C: np.ndarray
    D: np.ndarray | None
    Q: np.ndarray
    R: np.ndarray
    S: np.ndarray | None = None
    mu1: np.ndarray | None = None
    P1: np.ndarray | None = None

    def __post_init__(self):
        a = _matrix("A", self.A)
        n = a.shape[0]
        if a.shape != (n, n):
            raise ValueError(f"A must be square (n, n), got shape {a.shape}")
        c = _matrix("C", self.C)
        if c.shape[1] != n:
            raise ValueError(f"C must have shape (m, {n}) for {n} states, got {c.shape}")
        m = c.shape[0]
        if self.B is None:
            r = 0 if self.D is None else _matrix("D", self.D).shape[1]
            b = np.zeros((n, r))
        else:
            b = _matrix("B", self.B, rows=n)
            r = b.shape[1]
        d = np.zeros((m, r)) if self.D is None else _matrix("D", self.D, rows=m)
        if b.shape != (n, r):
            raise ValueError(f"B must have shape ({n}, {r}) to match D, got {b.shape}")
        if d.shape != (m, r):
            raise ValueError(f"D must have shape ({m}, {r}) for {m} outputs and {r} inputs, got {d.shape}")
        q = _covariance("Q", self.Q, n)
        rr = _covariance("R", self.R, m)
        s = np.zeros((n, m)) if self.S is None else _matrix("S", self.S)
        if s.shape != (n, m):
            raise ValueError(f"S must have shape ({n}, {m}), got {s.shape}")
        mu1 = np.zeros(n) if self.mu1 is None else np.asarray(self.mu1, dtype=float).reshape(-1)
        if mu1.shape != (n,) or not np.all(np.isfinite(mu1)):
            raise ValueError(f"mu1 must be a finite vector of {n} entries, got shape {np.shape(self.mu1)}")
        p1 = np.eye(n) if self.P1 is None else _covariance("P1", self.P1, n)
        if np.linalg.eigvalsh(rr)[0] <= 0.0:
            raise ValueError("R must be positive definite (the innovations need it)")
        if np.any(s):
            joint = np.block([[q, s], [s.T, rr]])
            if np.linalg.eigvalsh(joint)[0] < -1e-10 * max(1.0, np.abs(joint).max()):
                raise ValueError("[[Q, S], [S^T, R]] must be positive semi-definite: S is too large for Q and R")
        for name, value in (("A", a), ("B", b), ("C", c), ("D", d), ("Q", q), ("R", rr), ("S", s),
                            ("mu1", mu1), ("P1", p1)):
            value = np.array(value, dtype=float)
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def n_states(self) -> int:
        """``n``, the dimension of ``x``."""
        return self.A.shape[0]

    @property
    def n_inputs(self) -> int:
        """``r``, the dimension of ``u`` (0 without inputs)."""
        return self.B.shape[1]

    @property
    def n_outputs(self) -> int:
        """``m``, the dimension of ``y``."""
        return self.C.shape[0]

    @property
    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of ``A``, by decreasing modulus (the modes of the fault dynamics)."""
        values = np.linalg.eigvals(self.A)
        return values[np.argsort(-np.abs(values), kind="stable")]

    @property
    def spectral_radius(self) -> float:
        """``rho(A) = max |lambda_i(A)|``: above 1 the state (the fault) grows without input."""
        return float(np.max(np.abs(np.linalg.eigvals(self.A)))) if self.n_states else 0.0

    @property
    def is_stable(self) -> bool:
        """``rho(A) < 1``."""
        return self.spectral_radius < 1.0

    def simulate(self, u: ArrayLike | None = None, rng=None, *, steps: int | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Draw states ``x`` (T, n) and outputs ``y`` (T, m) for the inputs ``u`` (T, r).

        ``x_1 ~ N(mu1, P1)``, then eqs. (2)-(3) with ``[w_t; v_t] ~ N(0, [[Q, S], [S^T, R]])``.  Without
        inputs pass ``steps`` instead of ``u``.  ``rng`` is a ``numpy.random.Generator``, a seed or None.

        Example
        -------
        >>> m = LinearGaussianModel(A=[[0.8]], B=[[1.0]], C=[[2.0]], D=[[0.0]], Q=[[0.0]], R=[[1e-12]],
        ...                         mu1=[0.0], P1=[[0.0]])
        >>> x, y = m.simulate(np.ones((3, 1)), rng=0)
        >>> np.round(x[:, 0], 6).tolist()
        [0.0, 1.0, 1.8]
        """
        if u is None:
            if steps is None:
                raise ValueError("simulate needs the inputs u (T, r) or, for a model without inputs, steps")
            u = np.zeros((int(steps), 0))
        u = _inputs(u, None, self.n_inputs)
        if steps is not None and steps != u.shape[0]:
            raise ValueError(f"steps ({steps}) disagrees with the {u.shape[0]} rows of u")
        rng = np.random.default_rng(rng)
        steps, n = u.shape[0], self.n_states
        noise = rng.standard_normal((steps, n + self.n_outputs)) @ _psd_root(self.noise_covariance).T
        x = np.empty((steps, n))
        if steps:
            x[0] = self.mu1 + _psd_root(self.P1) @ rng.standard_normal(n)
        drive = u @ self.B.T + noise[:, :n]
        for t in range(steps - 1):
            x[t + 1] = self.A @ x[t] + drive[t]
        y = x @ self.C.T + u @ self.D.T + noise[:, n:]
        return x, y

    def transformed(self, T: ArrayLike) -> "LinearGaussianModel":
        """The same model in the state basis ``x' = T x`` (``T`` invertible): same outputs, same likelihood.

        ``A' = T A T^-1``, ``B' = T B``, ``C' = C T^-1``, ``Q' = T Q T^T``, ``S' = T S``, ``mu1' = T mu1``,
        ``P1' = T P1 T^T``; ``D``, ``R`` and the eigenvalues are unchanged.  EM cannot tell these models
        apart, so the basis it lands in is arbitrary; :class:`OnlineEM` uses this to keep it well scaled.

        Example
        -------
        >>> m = LinearGaussianModel(A=[[0.5, 1.0], [0.0, 0.9]], B=None, C=[[1.0, 0.0]], D=None,
        ...                         Q=np.eye(2), R=[[1.0]])
        >>> m2 = m.transformed(np.diag([2.0, 0.5]))
        >>> m2.A.tolist(), m2.C.tolist(), bool(np.allclose(m2.eigenvalues, m.eigenvalues))
        ([[0.5, 4.0], [0.0, 0.9]], [[0.5, 0.0]], True)
        """
        t = _matrix("T", T)
        if t.shape != (self.n_states, self.n_states):
            raise ValueError(f"T must have shape ({self.n_states}, {self.n_states}), got {t.shape}")
        t_inv = np.linalg.inv(t)  # raises LinAlgError if T is singular
        return LinearGaussianModel(A=t @ self.A @ t_inv, B=t @ self.B, C=self.C @ t_inv, D=self.D,
                                   Q=_symmetric(t @ self.Q @ t.T), R=self.R, S=t @ self.S if np.any(self.S) else None,
                                   mu1=t @ self.mu1, P1=_symmetric(t @ self.P1 @ t.T))

    @property
    def noise_covariance(self) -> np.ndarray:
        """``[[Q, S], [S^T, R]]``, the covariance of ``[w_t; v_t]``."""
        return np.block([[self.Q, self.S], [self.S.T, self.R]])

    def __repr__(self) -> str:
        def show(a):
            return np.array2string(np.asarray(a), precision=4, suppress_small=True, separator=", ").replace("\n", "")

        eig = ", ".join(f"{v:.4g}" for v in self.eigenvalues)
        body = ", ".join(f"{name}={show(getattr(self, name))}" for name in ("A", "B", "C", "D", "Q", "R"))
        extra = f", S={show(self.S)}" if np.any(self.S) else ""
        return (f"LinearGaussianModel(n_states={self.n_states}, n_inputs={self.n_inputs}, "
                f"n_outputs={self.n_outputs}, spectral_radius={self.spectral_radius:.4g}, eigenvalues=[{eig}], "
                f"{body}{extra}, mu1={show(self.mu1)}, P1={show(self.P1)})")


# ------------------------------------------------------------------------------------------ smoother

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
    y, u = _data(model, y, u)
    return _smooth(model, y, u)


def log_likelihood(model: LinearGaussianModel, y: ArrayLike, u: ArrayLike | None = None) -> float:
    """``log p(y_1..y_T | theta)`` from the innovations of the Kalman filter (seed 004 eq. 10).

    ``sum_t -1/2 (m log 2 pi + log det S_t + e_t^T S_t^-1 e_t)`` over the observed rows (see
    :func:`kalman_smoother` for ``e_t``, ``S_t`` and missing rows).

    Example
    -------
    >>> m = LinearGaussianModel(A=[[0.0]], B=None, C=[[1.0]], D=None, Q=[[1.0]], R=[[1.0]], P1=[[1.0]])
    >>> from scipy.stats import norm
    >>> bool(np.isclose(log_likelihood(m, [0.3, -1.2]), norm.logpdf([0.3, -1.2], scale=np.sqrt(2)).sum()))
    True
    """
    y, u = _data(model, y, u)
    return _filter(model, y, u).log_likelihood


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


def _filter(model: LinearGaussianModel, y: np.ndarray, u: np.ndarray) -> _Filtered:
    a, c, q, r = model.A, model.C, model.Q, model.R
    steps, n, m = y.shape[0], model.n_states, model.n_outputs
    observed = ~np.isnan(y).any(axis=1)
    y0 = np.where(observed[:, None], y, 0.0)
    drive = u @ model.B.T  # B u_t
    feed = u @ model.D.T  # D u_t
    if np.any(model.S):
        decorrelate = _solve_psd(r, model.S.T).T  # S R^-1
        a_dec = a - decorrelate @ c
        q_dec = _symmetric(q - decorrelate @ model.S.T)
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


def _smooth(model: LinearGaussianModel, y: np.ndarray, u: np.ndarray) -> SmootherResult:
    fl = _filter(model, y, u)
    steps, n = y.shape[0], model.n_states
    pf, pp, xf, xp = fl.filtered_covariances, fl.predicted_covariances, fl.filtered_means, fl.predicted_means
    xs = xf.copy()
    ps = pf.copy()
    if steps > 1:
        # J_t^T = P_{t+1|t}^-1 F_t P_{t|t}, all t at once (Cholesky solves, a pseudo-inverse if singular)
        gains_t = _solve_psd_stack(pp[1:], fl.transitions[:-1] @ pf[:-1])
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


# ------------------------------------------------------------------------------------------------ EM

def em_step(model: LinearGaussianModel, y: ArrayLike, u: ArrayLike | None = None, *, cross_covariance: bool = True,
            estimate_initial: bool = True) -> tuple[LinearGaussianModel, float]:
    """One EM iteration (seed 004 eqs. 14-23): returns ``(new_model, log p(Y | model))``.

    E-step: :func:`kalman_smoother` gives ``x_t = E[x_t | Y]``, ``P_t = Cov(x_t | Y)``,
    ``M_t = Cov(x_{t+1}, x_t | Y)``, hence ``E[x_t x_t^T] = P_t + x_t x_t^T`` and
    ``E[x_{t+1} x_t^T] = M_t + x_{t+1} x_t^T``.

    M-step.  Eqs. (19)-(23) maximize ``sum_t E log N([x_{t+1}; y_t]; Gamma [x_t; u_t], Pi)`` with
    ``Gamma = [[A, B], [C, D]] = Psi Sigma^-1`` and ``Pi = [[Q, S], [S^T, R]] = Phi - Psi Sigma^-1 Psi^T``.
    ``x_{t+1}`` exists for ``t = 1..T-1`` but ``y_t`` for ``t = 1..T``, so the complete-data likelihood
    (eq. 17) has ``T - 1`` joint terms and one more output term ``N(y_T; C x_T + D u_T, R)``.  We
    maximize it exactly by factorizing each joint term into ``p(y_t | x_t)`` and
    ``p(x_{t+1} | x_t, y_t)``, whose parameters ``(C, D, R)`` and ``(F, K, Q~)`` vary independently:

    1. output regression over the observed ``t = 1..T`` (``xi_t = [x_t; u_t]``)::

           [C, D] = Psi_y Sigma_y^-1,   R = Phi_y - Psi_y Sigma_y^-1 Psi_y^T,
           Phi_y = avg y_t y_t^T,  Psi_y = avg E[y_t xi_t^T],  Sigma_y = avg E[xi_t xi_t^T];

    2. state regression over ``t = 1..T-1`` on ``zeta_t = [x_t; u_t; y_t]``::

           [F_x, F_u, K] = Psi_x Sigma_x^-1,   Q~ = Phi_x - Psi_x Sigma_x^-1 Psi_x^T,
           Phi_x = avg E[x_{t+1} x_{t+1}^T],  Psi_x = avg E[x_{t+1} zeta_t^T],  Sigma_x = avg E[zeta_t zeta_t^T];

    3. back to the model: ``S = K R``, ``[A, B] = [F_x, F_u] + K [C, D]``, ``Q = Q~ + K R K^T``.

    Over the same pairs ``t = 1..T-1`` for both regressions this is exactly eqs. (19)-(20) (the Gaussian
    regression of ``[x_{t+1}; y_t]`` on ``xi_t`` factorizes this way); using the extra ``y_T`` is the
    exact maximizer of eq. (17) as written.  With ``cross_covariance=False``, ``S = 0`` is imposed: the
    state regression drops ``y_t`` and ``Q = Q~`` (still an exact M-step for that model).  With
    ``estimate_initial``, ``mu1 = x_{1|T}`` and ``P1 = P_{1|T}`` (exact); otherwise they are kept.

    ``Q~`` (``Q`` when ``S = 0``), ``R`` and ``P1`` are symmetrized and their eigenvalues floored at
    ``EIGENVALUE_FLOOR`` times the largest; an :class:`IdentificationWarning` says when a floor was hit.
    A singular ``Sigma`` (inputs that are not persistently exciting) falls back to the minimum-norm
    least-squares solution, which is still a maximizer.

    Missing outputs (NaN rows) are supported with ``cross_covariance=False`` only: the output regression
    then runs over the observed rows; with ``S`` free the M-step of an incomplete record has no closed
    form, and a ``ValueError`` says so.

    Example
    -------
    >>> truth = LinearGaussianModel(A=[[0.7]], B=None, C=[[1.0]], D=None, Q=[[1.0]], R=[[0.5]])
    >>> _, y = truth.simulate(steps=300, rng=2)
    >>> start = LinearGaussianModel(A=[[0.2]], B=None, C=[[1.0]], D=None, Q=[[0.3]], R=[[0.3]])
    >>> new, before = em_step(start, y)
    >>> bool(log_likelihood(new, y) > before)
    True
    """
    y, u = _data(model, y, u)
    if y.shape[0] < 2:
        raise ValueError(f"y: EM needs at least 2 samples, got {y.shape[0]}")
    new, smoothed = _em(model, y, u, cross_covariance, estimate_initial)
    return new, smoothed.log_likelihood


def _em(model: LinearGaussianModel, y: np.ndarray, u: np.ndarray, cross_covariance: bool, estimate_initial: bool
        ) -> tuple[LinearGaussianModel, SmootherResult]:
    observed = ~np.isnan(y).any(axis=1)
    if cross_covariance and not observed.all():
        raise ValueError("y has missing rows (NaN): EM with a free cross-covariance S needs a complete record; "
                         "use cross_covariance=False")
    if not observed.any():
        raise ValueError("y: every row is missing (NaN)")
    res = _smooth(model, y, u)
    new = _m_step(model, res, y, u, cross_covariance, estimate_initial)
    return new, res


def _m_step(model: LinearGaussianModel, res: SmootherResult, y: np.ndarray, u: np.ndarray,
            cross_covariance: bool, estimate_initial: bool) -> LinearGaussianModel:
    n, r = model.n_states, u.shape[1]
    xs, ps, obs = res.smoothed_means, res.smoothed_covariances, res.observed
    floored = []

    # 1. output regression, observed t = 1..T: y_t on xi_t = [x_t; u_t]
    xo, uo, yo = xs[obs], u[obs], y[obs]
    count = xo.shape[0]
    sigma_y = np.block([[ps[obs].sum(axis=0) + xo.T @ xo, xo.T @ uo], [uo.T @ xo, uo.T @ uo]]) / count
    psi_y = np.hstack([yo.T @ xo, yo.T @ uo]) / count
    phi_y = yo.T @ yo / count
    gamma_y = _solve_psd(sigma_y, psi_y.T).T
    c, d = gamma_y[:, :n], gamma_y[:, n:]
    rr = _floor_psd(phi_y - psi_y @ gamma_y.T, "R", floored)

    # 2. state regression, t = 1..T-1: x_{t+1} on zeta_t = [x_t; u_t] (+ y_t with S free)
    x0, x1, u0 = xs[:-1], xs[1:], u[:-1]
    pairs = x0.shape[0]
    blocks = [[ps[:-1].sum(axis=0) + x0.T @ x0, x0.T @ u0], [u0.T @ x0, u0.T @ u0]]
    psi_x = [res.lag_one_covariances.sum(axis=0) + x1.T @ x0, x1.T @ u0]
    if cross_covariance:
        y0 = y[:-1]
        blocks = [blocks[0] + [x0.T @ y0], blocks[1] + [u0.T @ y0], [y0.T @ x0, y0.T @ u0, y0.T @ y0]]
        psi_x.append(x1.T @ y0)
    sigma_x = np.block(blocks) / pairs
    psi_x = np.hstack(psi_x) / pairs
    phi_x = (ps[1:].sum(axis=0) + x1.T @ x1) / pairs
    gamma_x = _solve_psd(sigma_x, psi_x.T).T
    residual = phi_x - psi_x @ gamma_x.T
    if cross_covariance:
        gain = gamma_x[:, n + r:]  # K = S R^-1
        q_cond = _floor_psd(residual, "Q - S R^-1 S^T", floored)
        a = gamma_x[:, :n] + gain @ c
        b = gamma_x[:, n:n + r] + gain @ d
        s = gain @ rr
        q = _symmetric(q_cond + gain @ rr @ gain.T)
    else:
        a, b, s = gamma_x[:, :n], gamma_x[:, n:], None
        q = _floor_psd(residual, "Q", floored)

    if estimate_initial:
        mu1, p1 = xs[0], _floor_psd(ps[0], "P1", floored)
    else:
        mu1, p1 = model.mu1, model.P1
    if floored:
        warnings.warn(f"EM M-step floored the eigenvalues of {', '.join(floored)} at {EIGENVALUE_FLOOR:g} times "
                      f"the largest: the identified model is close to degenerate", IdentificationWarning,
                      stacklevel=4)
    return LinearGaussianModel(A=a, B=b, C=c, D=d, Q=q, R=rr, S=s, mu1=mu1, P1=p1)


@dataclass(frozen=True, eq=False)
class EMResult:
    """Output of :func:`fit_em`.

    Attributes
    ----------
    model : LinearGaussianModel
        The model after the last EM step.
    log_likelihood : ndarray (iterations + 1,)
        ``log p(Y | theta_k)`` of the start (``k = 0``) and after each EM step; the last entry is the
        returned model's.  EM never decreases it (up to round-off).
    iterations : int
        Number of EM steps taken.
    converged : bool
        Whether the relative change of the log-likelihood fell below ``tol`` before ``max_iter``.

    Example
    -------
    >>> y = np.random.default_rng(0).standard_normal(50)
    >>> fit = fit_em(y, None, 1, max_iter=5, tol=0.0)
    >>> fit.iterations, fit.converged, fit.log_likelihood.shape
    (5, False, (6,))
    """

    model: LinearGaussianModel
    log_likelihood: np.ndarray
    iterations: int
    converged: bool


def fit_em(y: ArrayLike, u: ArrayLike | None, n_states: int, *, initial: LinearGaussianModel | None = None,
           max_iter: int = 200, tol: float = 1e-8, cross_covariance: bool = True, estimate_initial: bool = True,
           seed: int | None = None) -> EMResult:
    """Maximum-likelihood ``A, B, C, D, Q, R`` (and ``S``, ``mu1``, ``P1``) by EM (seed 004 section 3.3).

    Iterates :func:`em_step` until ``(L_k - L_{k-1}) <= tol |L_{k-1}|`` (relative change of the
    log-likelihood ``L``) or ``max_iter`` steps.

    Start.  The seed sets every entry of every matrix to 1 and argues the likelihood is unimodal.  It is
    not (any change of state basis gives the same likelihood, and there are genuine local maxima), and
    the all-ones start is a trap: with identical rows and columns the states are exchangeable, EM keeps
    that symmetry at every step, and the model stays of order 1 for ever.  The default start is
    deterministic and breaks the symmetry (``initial_model``):

    * ``D`` = least-squares regression of ``y`` on ``u`` (zero without inputs), ``e = y - D u``;
    * ``A = diag(linspace(0.9, 0.5, n))`` (distinct stable modes), ``B = 0``, ``C`` = ones (m, n);
    * ``R = Cov(e)``, ``Q = 0.1 tr(R) / m I``, ``mu1 = 0``, ``P1 = tr(R) / m I``.

    With ``seed``, ``A``'s off-diagonal entries and ``C`` get small random perturbations (N(0, 0.1^2)
    relative) for restarts.

    Parameters
    ----------
    y : array (T,) or (T, m), rows with NaN missing (only with ``cross_covariance=False``)
    u : array (T, r), or None without inputs
    n_states : int
    initial : LinearGaussianModel, optional
        Start model (``n_states`` must match); overrides the default start.
    max_iter, tol : stopping rule (``max_iter`` EM steps at most).
    cross_covariance : bool
        Estimate ``S`` (True) or impose ``S = 0`` (the seed's eq. 24 lists ``A, B, C, D, Q, R`` only).
    estimate_initial : bool
        Estimate ``mu1`` and ``P1`` (True) or keep the start's.

    Example
    -------
    >>> truth = LinearGaussianModel(A=[[0.9, 0.2], [0.0, 0.5]], B=[[1.0], [0.5]], C=[[1.0, 0.0]], D=[[0.0]],
    ...                             Q=0.01 * np.eye(2), R=[[0.01]])
    >>> u = np.random.default_rng(0).standard_normal((500, 1))
    >>> _, y = truth.simulate(u, rng=0)
    >>> fit = fit_em(y, u, 2, cross_covariance=False)
    >>> bool(np.allclose(np.sort(fit.model.eigenvalues.real), [0.5, 0.9], atol=0.1))
    True
    >>> fit.log_likelihood.shape == (fit.iterations + 1,)
    True
    """
    if isinstance(n_states, bool) or not isinstance(n_states, (int, np.integer)) or n_states < 1:
        raise ValueError(f"n_states must be a positive integer, got {n_states!r}")
    if max_iter < 0:
        raise ValueError(f"max_iter must be >= 0, got {max_iter}")
    if not tol >= 0.0:
        raise ValueError(f"tol must be >= 0, got {tol}")
    y_arr, u_arr = _raw_data(y, u)
    model = initial_model(y_arr, u_arr, n_states, seed=seed) if initial is None else initial
    if model.n_states != n_states:
        raise ValueError(f"initial has {model.n_states} states but n_states is {n_states}")
    y_arr, u_arr = _data(model, y_arr, u_arr)
    if y_arr.shape[0] < 2:
        raise ValueError(f"y: EM needs at least 2 samples, got {y_arr.shape[0]}")
    history: list[float] = []
    converged = False
    iterations = 0
    for iterations in range(1, max_iter + 1):
        new, res = _em(model, y_arr, u_arr, cross_covariance, estimate_initial)
        history.append(res.log_likelihood)
        model = new
        if len(history) > 1 and history[-1] - history[-2] <= tol * abs(history[-2]):
            converged = True
            break
    history.append(_filter(model, y_arr, u_arr).log_likelihood)
    return EMResult(model, np.array(history), iterations, converged)


def initial_model(y: ArrayLike, u: ArrayLike | None, n_states: int, *, seed: int | None = None
                  ) -> LinearGaussianModel:
    """The default EM start of :func:`fit_em` (deterministic without ``seed``; see there).

    Example
    -------
    >>> m = initial_model(np.arange(10.0), None, 3)
    >>> np.diag(m.A).tolist(), m.C.tolist()
    ([0.9, 0.7, 0.5], [[1.0, 1.0, 1.0]])
    """
    y, u = _raw_data(y, u)
    m, r = y.shape[1], u.shape[1]
    rows = ~np.isnan(y).any(axis=1)
    if rows.sum() < 2:
        raise ValueError("y: need at least 2 observed rows to initialize EM")
    yo, uo = y[rows], u[rows]
    d = np.linalg.lstsq(uo, yo, rcond=None)[0].T if r else np.zeros((m, 0))
    e = yo - uo @ d.T
    cov = np.atleast_2d(np.cov(e, rowvar=False))
    scale = max(float(np.trace(cov)) / m, 1e-12 * max(float(np.mean(yo ** 2)), 1.0))
    rr = _floor_psd(cov + 1e-9 * scale * np.eye(m), "R", [])
    a = np.diag(np.linspace(0.9, 0.5, n_states)) if n_states > 1 else np.array([[0.9]])
    c = np.ones((m, n_states))
    if seed is not None:
        rng = np.random.default_rng(seed)
        a = a + 0.1 * rng.standard_normal(a.shape) * (1.0 - np.eye(n_states))
        c = c * (1.0 + 0.1 * rng.standard_normal(c.shape))
    return LinearGaussianModel(A=a, B=np.zeros((n_states, r)), C=c, D=d, Q=0.1 * scale * np.eye(n_states), R=rr,
                               mu1=np.zeros(n_states), P1=scale * np.eye(n_states))


# ------------------------------------------------------------------------------------------ online EM

@dataclass(frozen=True, eq=False)
class WindowIdentification:
    """One entry of :attr:`OnlineEM.history`: the model identified on the window ending at sample ``time``.

    Attributes
    ----------
    time : int
        Index (0-based, in samples given to :meth:`OnlineEM.update`) of the newest sample in the window.
    spectral_radius : float
        ``rho(A)`` of ``model``.
    eigenvalues : ndarray
        Eigenvalues of ``model.A`` by decreasing modulus.
    log_likelihood : float
        ``log p(window | theta)`` for the model *before* the last EM step of this identification (the
        E-step computes it for free); EM guarantees the returned model's is at least as large.
    model : LinearGaussianModel

    Examples
    --------
    One entry per identification of an :class:`OnlineEM`:

    >>> truth = LinearGaussianModel(A=[[0.8]], B=[[1.0]], C=[[1.0]], D=[[0.0]], Q=[[0.01]], R=[[0.01]])
    >>> u = np.random.default_rng(1).standard_normal((60, 1))
    >>> _, y = truth.simulate(u, rng=1)
    >>> online = OnlineEM(n_states=1, window=40, every=10, initial_iterations=20)
    >>> for t in range(60):
    ...     _ = online.update(y[t], u[t])
    >>> [entry.time for entry in online.history]
    [39, 49, 59]
    >>> entry = online.history[-1]
    >>> entry.model is online.model, entry.spectral_radius == entry.model.spectral_radius
    (True, True)
    >>> bool(abs(entry.eigenvalues[0] - 0.8) < 0.05), bool(np.isfinite(entry.log_likelihood))
    (True, True)
    """

    time: int
    spectral_radius: float
    eigenvalues: np.ndarray
    log_likelihood: float
    model: LinearGaussianModel = field(repr=False)


class OnlineEM:
    """Sliding-window EM identification (seed 004 section 3.4).

    Keeps the last ``window`` samples ``(y_t, u_t)``.  When the window first fills, :func:`fit_em` runs
    from the default start (up to ``initial_iterations`` steps).  Afterwards, every ``every`` new samples,
    ``iterations`` EM steps run on the current window, warm-started from the previous model with its
    initial state moved to the new window's first sample (``mu1``, ``P1`` = the last E-step's smoothed
    state at that sample).  Between re-identifications :meth:`update` returns the last model.

    Defaults (the seed re-identifies at every sample and does not say how many iterations): ``window=200``
    (the seed's N, 16.7 h at 5 min), ``every=12`` (hourly at 5 min), ``iterations=5``,
    ``initial_iterations=200``, ``cross_covariance=False`` (the seed's parameter vector, eq. 24, has no S;
    this also allows missing samples).  Successive windows overlap by ``window - every`` samples, so the
    EM steps accumulate along the record: each identification continues the previous one's ascent.
    One identification costs ``iterations`` Kalman smoother passes over the window.

    Example
    -------
    >>> truth = LinearGaussianModel(A=[[0.8]], B=[[1.0]], C=[[1.0]], D=[[0.0]], Q=[[0.01]], R=[[0.01]])
    >>> u = np.random.default_rng(1).standard_normal((260, 1))
    >>> _, y = truth.simulate(u, rng=1)
    >>> online = OnlineEM(n_states=1, window=200, every=20)
    >>> models = [online.update(y[t], u[t]) for t in range(260)]
    >>> models[198] is None, models[199] is not None, [h.time for h in online.history]
    (True, True, [199, 219, 239, 259])
    >>> bool(abs(online.model.eigenvalues[0] - 0.8) < 0.1)
    True
    """

    def __init__(self, n_states: int, window: int = 200, iterations: int = 5, every: int = 12, *,
                 initial_iterations: int = 200, tol: float = 1e-8, cross_covariance: bool = False,
                 initial: LinearGaussianModel | None = None):
        if isinstance(n_states, bool) or not isinstance(n_states, (int, np.integer)) or n_states < 1:
            raise ValueError(f"n_states must be a positive integer, got {n_states!r}")
        if window < 2:
            raise ValueError(f"window must be at least 2 samples, got {window}")
        if iterations < 1 or every < 1 or initial_iterations < 1:
            raise ValueError("iterations, every and initial_iterations must be >= 1")
        if every >= window:
            raise ValueError(f"every ({every}) must be smaller than window ({window}) for the warm start")
        self.n_states, self.window, self.iterations, self.every = int(n_states), int(window), iterations, every
        self.initial_iterations, self.tol, self.cross_covariance = initial_iterations, tol, cross_covariance
        self.initial = initial
        self.model: LinearGaussianModel | None = None
        self.history: list[WindowIdentification] = []
        self._y: deque = deque(maxlen=self.window)
        self._u: deque = deque(maxlen=self.window)
        self._time = -1
        self._since = 0
        self._smoothed: SmootherResult | None = None  # last E-step, for the next warm start

    @property
    def samples(self) -> int:
        """Number of samples seen."""
        return self._time + 1

    def window_data(self) -> tuple[np.ndarray, np.ndarray]:
        """The current window as ``y`` (N, m) and ``u`` (N, r)."""
        return np.array(self._y), np.array(self._u).reshape(len(self._u), -1)

    def smoother(self) -> SmootherResult:
        """:func:`kalman_smoother` of the current model over the current window.

        Its ``filtered_means[-1]`` is the state at the newest sample and ``next_mean``, ``next_covariance``
        start a :func:`predict_feature` from the next one.
        """
        if self.model is None:
            raise RuntimeError(f"no model yet: the window needs {self.window} samples, got {self.samples}")
        y, u = self.window_data()
        return _smooth(self._at_window_start(), y, u)

    def _at_window_start(self) -> LinearGaussianModel:
        """The current model with ``mu1``, ``P1`` at the current window's first sample.

        ``mu1``, ``P1`` of the identified model describe the first sample of the window it was identified on;
        the window has since moved by ``_since`` samples, so take the last E-step's smoothed state there.
        """
        if self._since == 0:
            return self.model
        return replace(self.model, mu1=self._smoothed.smoothed_means[self._since],
                       P1=self._smoothed.smoothed_covariances[self._since])

    def update(self, y_t: ArrayLike, u_t: ArrayLike | None = None) -> LinearGaussianModel | None:
        """Add one sample (``y_t`` with NaN = missing); return the current model (None until the window is full)."""
        y_t = np.atleast_1d(np.asarray(y_t, dtype=float)).reshape(-1)
        u_t = np.zeros(0) if u_t is None else np.atleast_1d(np.asarray(u_t, dtype=float)).reshape(-1)
        if self._y and (y_t.shape != self._y[0].shape or u_t.shape != self._u[0].shape):
            raise ValueError(f"y_t, u_t: expected shapes {self._y[0].shape}, {self._u[0].shape}, got "
                             f"{y_t.shape}, {u_t.shape}")
        if not np.all(np.isfinite(u_t)):
            raise ValueError("u_t must be finite (inputs are known)")
        if np.any(np.isinf(y_t)):
            raise ValueError("y_t must be finite or NaN (missing)")
        self._y.append(y_t)
        self._u.append(u_t)
        self._time += 1
        self._since += 1
        if len(self._y) < self.window:
            return None
        if self.model is None:
            self._identify(first=True)
        elif self._since >= self.every:
            self._identify(first=False)
        return self.model

    def _identify(self, first: bool) -> None:
        y, u = self.window_data()
        if first:
            model = self.initial if self.initial is not None else initial_model(y, u, self.n_states)
            steps = self.initial_iterations
        else:
            model = _whitened(self._at_window_start(), self._smoothed, self._since)
            steps = self.iterations
        previous = None
        for _ in range(steps):
            model, res = _em(model, y, u, self.cross_covariance, True)
            if first and previous is not None and res.log_likelihood - previous <= self.tol * abs(previous):
                break
            previous = res.log_likelihood
        self.model, self._smoothed, self._since = model, res, 0
        self.history.append(WindowIdentification(self._time, model.spectral_radius, model.eigenvalues,
                                           res.log_likelihood, model))

    def radii(self) -> tuple[np.ndarray, np.ndarray]:
        """Sample index and spectral radius of every identification so far."""
        return (np.array([h.time for h in self.history], dtype=int),
                np.array([h.spectral_radius for h in self.history]))


def _whitened(model: LinearGaussianModel, res: SmootherResult, start: int) -> LinearGaussianModel:
    """``model`` in the state basis where the smoothed states from ``start`` on have unit second moment.

    EM leaves the state basis free; along a long record a slowly growing mode lets it drift until ``mu1``
    is 1e7 and ``C`` 1e-2, or two states nearly coincide with ``C`` = 1e6 [1, -1], and the filter then
    loses the definiteness of ``P`` to round-off.  With ``M = avg E[x_t x_t^T] = L L^T``, ``T = L^-1``.
    """
    means, covs = res.smoothed_means[start:], res.smoothed_covariances[start:]
    if means.shape[0] == 0:
        return model
    second = _symmetric(means.T @ means / means.shape[0] + covs.mean(axis=0))
    try:
        root = np.linalg.cholesky(second)
    except np.linalg.LinAlgError:
        return model
    if not np.all(np.isfinite(root)) or np.linalg.cond(root) > 1e8:
        return model
    return model.transformed(np.linalg.inv(root))


# ------------------------------------------------------------------------------------- trend, prediction

def fault_trend(model: LinearGaussianModel, margin: float = 0.0) -> bool:
    """Whether the fault is progressing: ``rho(A) > 1 + margin`` (seed 004 section 5.1).

    A stable ``A`` means the feature settles for a constant load (the fault stays the same size); an
    eigenvalue outside the unit circle means it grows even at constant load.

    Example
    -------
    >>> grow = LinearGaussianModel(A=[[1.01]], B=None, C=[[1.0]], D=None, Q=[[0.1]], R=[[0.1]])
    >>> fault_trend(grow), fault_trend(grow, margin=0.02)
    (True, False)
    """
    return bool(model.spectral_radius > 1.0 + margin)


def detect_trend(radii: ArrayLike, threshold: float = 1.0, persistence: int = 3) -> int | None:
    """Index of the first alarm: the radius has been above ``threshold`` for ``persistence`` identifications.

    Returns the index (into ``radii``) of the identification that completes the first run of
    ``persistence`` consecutive values ``> threshold``, i.e. the earliest point at which an online
    monitor can raise the alarm (the run starts ``persistence - 1`` entries earlier), or None.

    Example
    -------
    >>> detect_trend([0.9, 1.02, 0.95, 1.01, 1.03, 1.02, 1.04], persistence=3)
    5
    >>> detect_trend([0.9, 1.02, 0.95], persistence=2) is None
    True
    """
    radii = np.asarray(radii, dtype=float).reshape(-1)
    if isinstance(persistence, bool) or int(persistence) != persistence or persistence < 1:
        raise ValueError(f"persistence must be a positive integer, got {persistence!r}")
    persistence = int(persistence)
    above = np.concatenate([[0], (radii > threshold).astype(int)])
    run = np.cumsum(above)
    hits = np.flatnonzero(run[persistence:] - run[:-persistence] == persistence) if radii.size >= persistence else []
    return int(hits[0] + persistence - 1) if len(hits) else None


@dataclass(frozen=True, eq=False)
class FeaturePrediction:
    """Predicted feature ``y_{T+1..T+H}`` with a two-sided normal interval.

    Attributes
    ----------
    mean, std, lower, upper : ndarray (H, m)
    level : float
    state_means, state_covariances : ndarray (H, n), (H, n, n)

    Examples
    --------
    Returned by :func:`predict_feature`; a decaying state without load, 90 % intervals:

    >>> m = LinearGaussianModel(A=[[0.9]], B=[[1.0]], C=[[1.0]], D=[[0.0]], Q=[[0.01]], R=[[0.04]])
    >>> p = predict_feature(m, [1.0], [[0.0]], np.zeros((3, 1)), level=0.9)
    >>> np.round(p.mean[:, 0], 4).tolist(), np.round(p.std[:, 0], 4).tolist()
    ([1.0, 0.9, 0.81], [0.2, 0.2236, 0.241])
    >>> np.round(p.lower[:, 0], 3).tolist(), np.round(p.upper[:, 0], 3).tolist(), p.level
    ([0.671, 0.532, 0.414], [1.329, 1.268, 1.206], 0.9)
    >>> p.state_means.shape, p.state_covariances.shape
    ((3, 1), (3, 1, 1))
    """

    mean: np.ndarray
    std: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    level: float
    state_means: np.ndarray
    state_covariances: np.ndarray

    def coverage(self, y: ArrayLike) -> float:
        """Fraction of the observed entries of ``y`` (H, m) inside ``[lower, upper]`` (NaN entries ignored).

        Example
        -------
        >>> m = LinearGaussianModel(A=[[0.0]], B=None, C=[[1.0]], D=None, Q=[[0.0]], R=[[1.0]])
        >>> p = predict_feature(m, [0.0], [[0.0]], None, steps=4)   # y ~ N(0, 1): interval +-1.96
        >>> p.coverage([0.5, -1.0, 2.5, np.nan])
        0.6666666666666666
        """
        y = np.asarray(y, dtype=float).reshape(self.mean.shape)
        seen = ~np.isnan(y)
        return float(np.mean((y[seen] >= self.lower[seen]) & (y[seen] <= self.upper[seen])))


def predict_feature(model: LinearGaussianModel, mean: ArrayLike, covariance: ArrayLike, u_future: ArrayLike | None,
                    level: float = 0.95, *, steps: int | None = None) -> FeaturePrediction:
    """Long-term prediction of the feature under a known future load profile (seed 004 section 5.2).

    ``mean``, ``covariance`` describe the state at the first predicted time, ``x_{T+1} | y_1..y_T``: the
    filtered state at the prediction time ``T`` pushed one step through the model
    (:attr:`SmootherResult.next_mean`, :attr:`SmootherResult.next_covariance`; exact with ``S != 0``).
    Then, for ``h = 1..H`` with ``u_future`` row ``h - 1`` = ``u_{T+h}``::

        y mean = C x_h + D u_{T+h},    y var = C P_h C^T + R,
        x_{h+1} = A x_h + B u_{T+h},   P_{h+1} = A P_h A^T + Q

    (no more measurements, so ``w`` and ``v`` are uncorrelated with the past).  The interval is
    ``mean +- z std`` with ``z = Phi^-1((1 + level) / 2)`` per output.  It reflects the model's noises, not
    the uncertainty of the identified parameters.  Without inputs pass ``u_future=None`` and ``steps``.

    Example
    -------
    >>> m = LinearGaussianModel(A=[[1.0]], B=[[1.0]], C=[[1.0]], D=[[0.0]], Q=[[1.0]], R=[[0.0001]])
    >>> p = predict_feature(m, [0.0], [[0.0]], np.ones((3, 1)))
    >>> p.mean[:, 0].tolist(), np.round(p.std[:, 0] ** 2, 4).tolist()
    ([0.0, 1.0, 2.0], [0.0001, 1.0001, 2.0001])
    >>> bool(np.allclose(p.upper - p.mean, 1.959964 * p.std))
    True
    """
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    n = model.n_states
    x = np.asarray(mean, dtype=float).reshape(-1)
    p = np.asarray(covariance, dtype=float)
    if x.shape != (n,) or not np.all(np.isfinite(x)):
        raise ValueError(f"mean must be a finite vector of {n} entries, got shape {np.shape(mean)}")
    if p.shape != (n, n) or not np.all(np.isfinite(p)):
        raise ValueError(f"covariance must be a finite ({n}, {n}) matrix, got shape {p.shape}")
    u = _future_inputs(u_future, steps, model.n_inputs, "predict_feature")
    horizon = u.shape[0]
    xs = np.empty((horizon, n))
    ps = np.empty((horizon, n, n))
    drive = u @ model.B.T
    for h in range(horizon):
        xs[h], ps[h] = x, p
        x = model.A @ x + drive[h]
        p = model.A @ p @ model.A.T + model.Q
        p = 0.5 * (p + p.T)
    y_mean = xs @ model.C.T + u @ model.D.T
    y_var = np.einsum("ij,hjk,ik->hi", model.C, ps, model.C) + np.diag(model.R)
    std = np.sqrt(np.maximum(y_var, 0.0))
    z = float(norm.ppf(0.5 * (1.0 + level)))
    return FeaturePrediction(y_mean, std, y_mean - z * std, y_mean + z * std, level, xs, ps)


# ---------------------------------------------------------------------------------------------- helpers

def _matrix(name: str, value, rows: int | None = None) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric matrix: {exc}") from None
    if a.ndim == 1 and rows is not None and a.size == rows:
        a = a[:, None]
    if a.ndim != 2:
        raise ValueError(f"{name} must be a 2-D matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} has non-finite entries")
    if rows is not None and a.shape[0] != rows:
        raise ValueError(f"{name} must have {rows} rows, got shape {a.shape}")
    return a


def _covariance(name: str, value, size: int) -> np.ndarray:
    a = _matrix(name, value)
    if a.shape != (size, size):
        raise ValueError(f"{name} must have shape ({size}, {size}), got {a.shape}")
    scale = max(1.0, float(np.abs(a).max())) if a.size else 1.0
    if not np.allclose(a, a.T, rtol=0.0, atol=1e-9 * scale):
        raise ValueError(f"{name} must be symmetric")
    a = 0.5 * (a + a.T)
    if size and np.linalg.eigvalsh(a)[0] < -1e-10 * scale:
        raise ValueError(f"{name} must be positive semi-definite (smallest eigenvalue "
                         f"{np.linalg.eigvalsh(a)[0]:.3g})")
    return a


def _columns(value, name: str) -> np.ndarray:
    """``value`` as a float array, a 1-D series as one column; a clear error naming it if not numeric."""
    try:
        value = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric: {exc}") from None
    return value[:, None] if value.ndim == 1 else value


def _raw_data(y, u) -> tuple[np.ndarray, np.ndarray]:
    """``y`` as (T, m) with NaN allowed, ``u`` as (T, r) finite (r = 0 for None)."""
    y = _columns(y, "y")
    if y.ndim != 2 or y.shape[0] == 0 or y.shape[1] == 0:
        raise ValueError(f"y must have shape (T,) or (T, m) with T, m >= 1, got {y.shape}")
    if np.any(np.isinf(y)):
        raise ValueError("y has infinite entries (use NaN for a missing measurement)")
    return y, _inputs(u, y.shape[0], None)


def _inputs(u, steps: int | None, width: int | None, name: str = "u") -> np.ndarray:
    if u is None:
        if width:
            raise ValueError(f"{name} is required: the model has {width} inputs")
        if steps is None:
            raise ValueError(f"{name} is required")
        return np.zeros((steps, 0))
    u = _columns(u, name)
    if u.ndim != 2:
        raise ValueError(f"{name} must have shape (T, r), got {u.shape}")
    if steps is not None and u.shape[0] != steps:
        raise ValueError(f"{name} has {u.shape[0]} rows but y has {steps}")
    if width is not None and u.shape[1] != width:
        raise ValueError(f"{name} has {u.shape[1]} columns but the model has {width} inputs")
    if not np.all(np.isfinite(u)):
        raise ValueError(f"{name} has non-finite entries (inputs must be known)")
    return u


def _future_inputs(u_future, steps: int | None, width: int, caller: str) -> np.ndarray:
    """The known future inputs as (H, r); without inputs, ``steps`` gives the horizon H."""
    if u_future is None:
        if steps is None:
            raise ValueError(f"{caller} needs u_future (H, r) or, for a model without inputs, steps")
        u_future = np.zeros((int(steps), 0))
    return _inputs(u_future, None, width, name="u_future")


def _data(model: LinearGaussianModel, y, u) -> tuple[np.ndarray, np.ndarray]:
    if u is None and model.n_inputs:
        raise ValueError(f"u is required: the model has {model.n_inputs} inputs")
    y, u = _raw_data(y, u)
    if y.shape[1] != model.n_outputs:
        raise ValueError(f"y has {y.shape[1]} columns but the model has {model.n_outputs} outputs")
    if u.shape[1] != model.n_inputs:
        raise ValueError(f"u has {u.shape[1]} columns but the model has {model.n_inputs} inputs")
    return y, u


def _scatter(values: np.ndarray, mask: np.ndarray, shape: tuple) -> np.ndarray:
    out = np.zeros(shape)
    out[mask] = values
    return out


def _symmetric(a: np.ndarray) -> np.ndarray:
    return 0.5 * (a + a.T)


def _floor_psd(a: np.ndarray, name: str, floored: list) -> np.ndarray:
    """Symmetrize and lift the eigenvalues of ``a`` to at least the floor; note ``name`` if it was needed."""
    a = _symmetric(a)
    values, vectors = np.linalg.eigh(a)
    floor = max(EIGENVALUE_FLOOR * max(values[-1], 0.0), EIGENVALUE_FLOOR_ABSOLUTE)
    if values[0] >= floor:
        return a
    floored.append(name)
    return _symmetric((vectors * np.maximum(values, floor)) @ vectors.T)


def _psd_root(a: np.ndarray) -> np.ndarray:
    """``L`` with ``L L^T = a`` for a symmetric positive semi-definite ``a`` (eigen-decomposition)."""
    if a.size == 0:
        return a.copy()
    values, vectors = np.linalg.eigh(_symmetric(a))
    return vectors * np.sqrt(np.maximum(values, 0.0))


def _solve_psd(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a^-1 b`` for a symmetric positive semi-definite ``a``: Cholesky, minimum-norm least squares if singular."""
    if a.size == 0:
        return np.zeros((0,) + b.shape[1:])
    try:
        root = np.linalg.cholesky(a)
        if np.min(np.diag(root)) <= 1e-13 * np.sqrt(np.max(np.diag(a))):
            raise np.linalg.LinAlgError("numerically singular")
        return np.linalg.solve(root.T, np.linalg.solve(root, b))
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(a, b, rcond=None)[0]


def _solve_psd_stack(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a_k^-1 b_k`` for a stack of symmetric positive semi-definite ``a_k`` (pseudo-inverse if singular)."""
    try:
        root = np.linalg.cholesky(a)
        diag = np.diagonal(root, axis1=1, axis2=2)
        scale = np.sqrt(np.max(np.diagonal(a, axis1=1, axis2=2), axis=1, keepdims=True))
        if np.any(diag <= 1e-13 * scale):
            raise np.linalg.LinAlgError("numerically singular")
        return np.linalg.solve(np.swapaxes(root, 1, 2), np.linalg.solve(root, b))
    except np.linalg.LinAlgError:
        return np.linalg.pinv(a, hermitian=True) @ b
