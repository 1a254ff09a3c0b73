"""Regularized online sequential extreme learning machine (ROS-ELM), series forecasts (Du et al. (n.d.), sections 4-5).

An extreme learning machine with ``L`` additive hidden nodes maps an input
``mu`` to

    f_L(mu) = sum_i beta^i g(a_i . mu + b_i)                               (eqs. 47-48)

with input weights ``a_i`` and biases ``b_i`` drawn at random once and kept
fixed; only the output weights ``beta`` (L x m) are learned.  Stacking ``N``
samples gives ``H beta = T`` with the hidden-layer output matrix ``H``
(N x L, eqs. 49-51).  ROS-ELM solves the ridge problem (eqs. 52-53)

    beta = (H^T H + lambda I)^-1 H^T T

in two phases:

* initialization (eq. 54): ``K0 = (H0^T H0 + lambda I)^-1``, ``beta0 = K0 H0^T T0``.
  ``lambda > 0`` makes this well defined with fewer samples than nodes
  (Du et al. (n.d.) initialize with N0 = 47 pairs and L = 50);
* online learning (eqs. 55-56), for a new row ``h_k`` or, in the Woodbury form
  of the same recursion, a block of rows ``H_k``:

      K_k    = K_{k-1} - K_{k-1} H_k^T (I + H_k K_{k-1} H_k^T)^-1 H_k K_{k-1}
      beta_k = beta_{k-1} + K_k H_k^T (T_k - H_k beta_{k-1})

  so that ``beta_k`` stays the batch solution (eq. 53) of all rows seen so far.

:class:`SeriesForecaster` runs one ROS-ELM per measured variable (Du et al. (n.d.), section 5,
step 1): network ``i`` learns ``z_{i,t+1}`` from the embedding
``(z_{i,t-p+1}, ..., z_{i,t})``, is initialized on the first ``N0``
measurements (``N0 - p`` pairs) and updated online with each new measurement.
An ``n``-step-ahead forecast iterates the one-step prediction, feeding each
prediction back as the newest input (step 3).

Example
-------
>>> import numpy as np
>>> t = np.arange(60.0)
>>> z = np.column_stack([np.sin(2 * np.pi * t / 40), 1.0 - 0.004 * t])
>>> forecaster = SeriesForecaster(embedding=3).fit(z[:50])
>>> for row in z[50:55]:
...     _ = forecaster.update(row)
>>> bool(np.abs(forecaster.forecast(5) - z[55:60]).max() < 0.01)
True
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy import linalg

from ..errors import PrognosisError

__all__ = ["ACTIVATIONS", "ROSELM", "SeriesForecaster"]


def _sigmoid(x: np.ndarray) -> np.ndarray:
    """``g(x) = 1 / (1 + exp(-x))`` written with ``exp(-|x|)``, which never overflows."""
    e = np.exp(-np.abs(x))
    return np.where(x >= 0, 1.0, e) / (1.0 + e)


_ACTIVATION_FUNCTIONS = {"sigmoid": _sigmoid, "tanh": np.tanh}
ACTIVATIONS = tuple(_ACTIVATION_FUNCTIONS)


def _check_hyperparameters(n_hidden: int, regularization: float, activation: str) -> None:
    if n_hidden < 1:
        raise PrognosisError(f"n_hidden must be >= 1, got {n_hidden}")
    if not regularization >= 0:  # also rejects NaN
        raise PrognosisError(f"regularization must be >= 0, got {regularization}")
    if activation not in _ACTIVATION_FUNCTIONS:
        raise PrognosisError(f"activation must be one of {ACTIVATIONS}, got {activation!r}")


def _check_finite_rows(a: np.ndarray, name: str) -> None:
    """Raise naming the first row of the 2-D array ``a`` holding NaN or inf."""
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        raise PrognosisError(f"{name} row {np.flatnonzero(bad)[0]} contains NaN or inf")


def _ridge_init(H: np.ndarray, T: np.ndarray, regularization: float) -> tuple[np.ndarray, np.ndarray]:
    """``K0 = (H^T H + lambda I)^-1`` and ``beta0 = K0 H^T T`` (eq. 54) from the SVD ``H = U S V^T``.

        K0 = V diag(1 / (s^2 + lambda)) V^T,   beta0 = V diag(s / (s^2 + lambda)) U^T T

    The SVD never forms ``H^T H``, whose condition number is the square of ``H``'s.
    """
    n, L = H.shape
    # zero rows up to L give the full V (L x L) and zero singular values when N0 < L
    padded = H if n >= L else np.vstack([H, np.zeros((L - n, L))])
    U, s, Vt = linalg.svd(padded, full_matrices=False)
    if regularization == 0 and s[-1] <= s[0] * L * np.finfo(float).eps:
        raise PrognosisError("regularization=0 needs the initial hidden-output matrix H0 to have full column rank: "
                             f"use regularization > 0 or more than n_hidden={L} well-spread samples (got {n})")
    denominator = s**2 + regularization
    K = (Vt.T / denominator) @ Vt
    beta = Vt.T @ ((s / denominator)[:, None] * (U[:n].T @ T))
    return 0.5 * (K + K.T), beta


class ROSELM:
    """Regularized online sequential extreme learning machine (Du et al. (n.d.), eqs. 47-56).

    Parameters
    ----------
    n_inputs : int
        Length ``n_mu`` of an input vector.
    n_hidden : int
        Number ``L`` of hidden nodes.
    regularization : float
        Ridge weight ``lambda`` of eq. 52; ``> 0`` allows fewer initial samples than nodes.
    activation : {"sigmoid", "tanh"}
        Hidden-node function ``g``.
    weight_range, bias_range : (float, float)
        Uniform ranges of the input weights ``a_i`` and biases ``b_i`` (the paper's [-1, 1] and [0, 1]).
    seed : int, numpy.random.SeedSequence or None
        Seed of ``numpy.random.default_rng`` drawing ``a_i`` and ``b_i``.

    Notes
    -----
    A 1-D ``X`` or ``x`` is one sample.  Targets given as ``(N,)`` in :meth:`fit` make
    :meth:`predict` return ``(N,)`` and :attr:`beta` ``(L,)``; ``(N, m)`` targets give
    ``(N, m)`` and ``(L, m)``.

    Example
    -------
    Online updates reproduce the batch ridge solution ``(H^T H + lambda I)^-1 H^T T``:

    >>> import numpy as np
    >>> X = np.random.default_rng(1).uniform(-1, 1, size=(40, 2))
    >>> T = np.sin(3 * X[:, 0]) * X[:, 1]
    >>> online = ROSELM(2, n_hidden=10, regularization=1e-3).fit(X[:15], T[:15]).partial_fit(X[15:], T[15:])
    >>> batch = ROSELM(2, n_hidden=10, regularization=1e-3).fit(X, T)
    >>> bool(np.allclose(online.beta, batch.beta, rtol=1e-8, atol=1e-10))
    True
    """

    def __init__(self, n_inputs: int, n_hidden: int = 50, regularization: float = 1e-8,
                 activation: str = "sigmoid", weight_range: tuple[float, float] = (-1.0, 1.0),
                 bias_range: tuple[float, float] = (0.0, 1.0), seed: int | np.random.SeedSequence | None = 0):
        if n_inputs < 1:
            raise PrognosisError(f"n_inputs must be >= 1, got {n_inputs}")
        _check_hyperparameters(n_hidden, regularization, activation)
        for name, (low, high) in (("weight_range", weight_range), ("bias_range", bias_range)):
            if not low <= high:
                raise PrognosisError(f"{name} must be (low, high) with low <= high, got {(low, high)}")
        self.n_inputs = int(n_inputs)
        self.n_hidden = int(n_hidden)
        self.regularization = float(regularization)
        self.activation = activation
        rng = np.random.default_rng(seed)
        self.input_weights = rng.uniform(*weight_range, size=(self.n_hidden, self.n_inputs))  # row i is a_i
        self.biases = rng.uniform(*bias_range, size=self.n_hidden)
        self._g = _ACTIVATION_FUNCTIONS[activation]
        self._K: np.ndarray | None = None
        self._beta: np.ndarray | None = None  # always (L, m); 1-D targets are kept as m = 1
        self._vector_output = False
        self.n_samples_seen = 0

    # -- checks ---------------------------------------------------------------------------------------------------
    def _rows(self, X: ArrayLike, name: str) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        if X.ndim == 1:
            X = X[None, :]
        if X.ndim != 2 or X.shape[1] != self.n_inputs:
            raise PrognosisError(f"{name} must have n_inputs={self.n_inputs} columns (shape (N, {self.n_inputs}) "
                                 f"or ({self.n_inputs},) for one sample), got shape {np.shape(X)}")
        _check_finite_rows(X, name)
        return X

    def _targets(self, T: ArrayLike, n_rows: int, name: str) -> np.ndarray:
        """``T`` as an (n_rows, m) array matching the targets given to :meth:`fit`."""
        T = np.asarray(T, dtype=float)
        if self._vector_output and T.ndim <= 1:
            T = T.reshape(-1, 1)
        elif T.ndim == 1 and n_rows == 1:
            T = T[None, :]
        if T.shape != (n_rows, self.n_outputs):
            expected = (n_rows,) if self._vector_output else (n_rows, self.n_outputs)
            raise PrognosisError(f"{name} must have shape {expected} (one target per input row), got {T.shape}")
        _check_finite_rows(T, name)
        return T

    def _require_fit(self, method: str) -> None:
        if self._beta is None:
            raise PrognosisError(f"{method} called before fit: initialize the network with fit(X, T) first")

    # -- model ----------------------------------------------------------------------------------------------------
    @property
    def n_outputs(self) -> int:
        """Number ``m`` of outputs (1 for 1-D targets); 0 before :meth:`fit`."""
        return 0 if self._beta is None else self._beta.shape[1]

    @property
    def beta(self) -> np.ndarray:
        """Copy of the output weights, ``(L,)`` for 1-D targets else ``(L, m)``."""
        self._require_fit("beta")
        return self._beta[:, 0].copy() if self._vector_output else self._beta.copy()

    @property
    def K(self) -> np.ndarray:
        """Copy of ``K_k = (H^T H + lambda I)^-1`` over all rows seen so far, ``(L, L)``."""
        self._require_fit("K")
        return self._K.copy()

    def hidden(self, X: ArrayLike) -> np.ndarray:
        """Hidden-layer output matrix ``H`` (N, L), ``H[j, i] = g(a_i . x_j + b_i)`` (eqs. 48, 51)."""
        return self._g(self._rows(X, "X") @ self.input_weights.T + self.biases)

    def fit(self, X: ArrayLike, T: ArrayLike) -> ROSELM:
        """Initialization phase (eq. 54): ``K0 = (H0^T H0 + lambda I)^-1``, ``beta0 = K0 H0^T T0``.

        ``X`` is (N0, n_inputs), ``T`` is (N0,) or (N0, m).  Refitting discards earlier updates.
        """
        H = self.hidden(X)
        T = np.asarray(T, dtype=float)
        if T.ndim not in (1, 2) or len(T) != len(H):
            raise PrognosisError(f"T must have shape ({len(H)},) or ({len(H)}, m), one target per row of X, "
                                 f"got {T.shape}")
        if len(H) == 0:
            raise PrognosisError("X has no rows: fit needs at least one sample")
        self._vector_output = T.ndim == 1
        T = T.reshape(len(H), -1)
        _check_finite_rows(T, "T")
        self._K, self._beta = _ridge_init(H, T, self.regularization)
        self.n_samples_seen = len(H)
        return self

    def partial_fit(self, x: ArrayLike, t: ArrayLike) -> ROSELM:
        """Online phase (eqs. 55-56) for one sample or a block of rows, Woodbury form.

            G      = K_{k-1} H^T (I + H K_{k-1} H^T)^-1      (= K_k H^T)
            beta_k = beta_{k-1} + G (T - H beta_{k-1})
            K_k    = K_{k-1} - G H K_{k-1}
        """
        self._require_fit("partial_fit")
        H = self._g(self._rows(x, "x") @ self.input_weights.T + self.biases)
        T = self._targets(t, len(H), "t")
        if len(H) == 0:
            return self
        P = self._K @ H.T  # K_{k-1} H^T, (L, n)
        S = np.eye(len(H)) + H @ P  # >= I, so the solve is well posed
        G = linalg.solve(S, P.T, assume_a="pos").T
        self._beta = self._beta + G @ (T - H @ self._beta)
        K = self._K - G @ P.T
        self._K = 0.5 * (K + K.T)  # rounding drift would otherwise make K asymmetric over many updates
        self.n_samples_seen += len(H)
        return self

    def predict(self, X: ArrayLike) -> np.ndarray:
        """``f_L(x) = H beta`` (eq. 50): (N,) for 1-D training targets, else (N, m)."""
        self._require_fit("predict")
        Y = self.hidden(X) @ self._beta
        return Y[:, 0] if self._vector_output else Y


class SeriesForecaster:
    """One ROS-ELM per measured variable with iterated multi-step forecasts (Du et al. (n.d.), section 5, steps 1, 3).

    Network ``i`` maps the embedding ``(z_{i,t-p+1}, ..., z_{i,t})`` to ``z_{i,t+1}``.

    Parameters
    ----------
    embedding : int
        Embedding dimension ``p`` (the paper uses 3).
    n_hidden, regularization, activation
        Passed to every :class:`ROSELM` (the paper uses L = 50, lambda = 1e-8, sigmoid).
    scale : bool
        Standardize variable ``i`` (its network's inputs and output) with the mean and
        standard deviation of the initial window given to :meth:`fit` (a numerically
        constant variable gets standard deviation 1); the statistics stay frozen online.
        Off by default, as in Du et al. (n.d.), who train on raw levels: raw tank levels (about
        1 m, changing by about 1e-3 per step) sit on one spot of each sigmoid, so the
        network acts as a nearly linear autoregression, which extrapolates trends.  Scaled
        inputs of a trending series leave the initial window's range (a 1 - 0.004 t ramp
        reaches -12 standard deviations after 150 steps) and saturate the sigmoids: on that
        ramp with N(0, 2e-4^2) noise scaling raised the 5-step RMSE from about 3e-4 to
        0.7-1.7e-3, on the paper's three-tank case (section 6.1) up to 0.66 m.  Scaling helps
        data far from unit magnitude and stationary series seen whole in the initial window.
    seed : int or None
        Root seed; variable ``i``'s network gets child ``i`` of ``numpy.random.SeedSequence(seed)``.
    names : sequence of str, optional
        Variable names used in error messages.

    Notes
    -----
    A 1-D history (one variable) makes :meth:`forecast` return ``(steps,)`` and lets
    :meth:`update` take a scalar.

    Examples
    --------
    One variable, a slow linear decay: initialize on 30 samples, learn 5 more online,
    forecast 3 steps by iterating the one-step prediction.

    >>> z = 1.0 - 0.01 * np.arange(40.0)
    >>> forecaster = SeriesForecaster(embedding=3, seed=0).fit(z[:30])
    >>> for value in z[30:35]:
    ...     _ = forecaster.update(value)
    >>> forecast = forecaster.forecast(3)
    >>> forecast.shape, forecaster.n_variables, forecaster.history.shape
    ((3,), 1, (35, 1))
    >>> bool(np.abs(forecast - z[35:38]).max() < 1e-3)
    True
    """

    def __init__(self, embedding: int = 3, n_hidden: int = 50, regularization: float = 1e-8,
                 activation: str = "sigmoid", scale: bool = False, seed: int | None = 0,
                 names: Sequence[str] | None = None):
        if embedding < 1:
            raise PrognosisError(f"embedding must be >= 1, got {embedding}")
        _check_hyperparameters(n_hidden, regularization, activation)
        self.embedding = int(embedding)
        self.n_hidden = int(n_hidden)
        self.regularization = float(regularization)
        self.activation = activation
        self.scale = scale
        self.seed = seed
        self.names = None if names is None else list(names)
        self.models: list[ROSELM] = []
        self.mean = self.std = None
        self._history: np.ndarray | None = None
        self._vector = False

    def _variable(self, i: int) -> str:
        return f"variable {self.names[i]!r}" if self.names is not None else f"column {i}"

    def _require_fit(self, method: str) -> None:
        if self._history is None:
            raise PrognosisError(f"{method} called before fit: initialize with fit(history) first")

    def _scaled(self, Z: np.ndarray) -> np.ndarray:
        return (Z - self.mean) / self.std

    @property
    def history(self) -> np.ndarray:
        """Copy of every measurement received so far, (N, m)."""
        self._require_fit("history")
        return self._history.copy()

    @property
    def n_variables(self) -> int:
        """Number of measured variables ``m``, one ROS-ELM each (0 before :meth:`fit`)."""
        return len(self.models)

    def fit(self, history: ArrayLike) -> SeriesForecaster:
        """Initialize one ROS-ELM per variable on the ``N0 - p`` pairs of the first ``N0`` measurements.

        Pair ``j`` of variable ``i`` is ``(z_{i,j}, ..., z_{i,j+p-1}) -> z_{i,j+p}``; ``history``
        is (N0, m), or (N0,) for one variable.
        """
        Z = np.asarray(history, dtype=float)
        if Z.ndim not in (1, 2):
            raise PrognosisError(f"history must have shape (N0,) or (N0, m), got {Z.shape}")
        vector = Z.ndim == 1
        Z = Z.reshape(len(Z), -1)
        m, p = Z.shape[1], self.embedding
        if self.names is not None and len(self.names) != m:
            raise PrognosisError(f"names has {len(self.names)} entries but history has {m} variables")
        if len(Z) < p + 1:
            raise PrognosisError(f"history needs at least embedding + 1 = {p + 1} rows (one training pair), "
                                 f"got {len(Z)}")
        for i in range(m):
            bad = np.flatnonzero(~np.isfinite(Z[:, i]))
            if bad.size:
                raise PrognosisError(f"history {self._variable(i)} row {bad[0]} is NaN or inf")
        if self.scale:
            mean, std = Z.mean(axis=0), Z.std(axis=0)
            std = np.where(std <= 1e-12 * np.abs(mean), 1.0, std)  # constant up to rounding
        else:
            mean, std = np.zeros(m), np.ones(m)
        self.mean, self.std, self._vector = mean, std, vector
        U = self._scaled(Z)
        windows = np.lib.stride_tricks.sliding_window_view(U[:-1], p, axis=0)  # (N0 - p, m, p)
        seeds = np.random.SeedSequence(self.seed).spawn(m)
        self.models = [ROSELM(p, self.n_hidden, self.regularization, self.activation, seed=s)
                       .fit(windows[:, i], U[p:, i]) for i, s in enumerate(seeds)]
        self._history = Z.copy()
        return self

    def update(self, z: ArrayLike) -> SeriesForecaster:
        """Append measurement ``z`` (m,) and update every network once (eqs. 55-56) with its newest pair."""
        self._require_fit("update")
        z = np.atleast_1d(np.asarray(z, dtype=float))
        if z.shape != (self.n_variables,):
            raise PrognosisError(f"z must have length {self.n_variables} (one value per variable), got shape {z.shape}")
        bad = np.flatnonzero(~np.isfinite(z))
        if bad.size:
            raise PrognosisError(f"z {self._variable(bad[0])} is NaN or inf")
        window = self._scaled(self._history[-self.embedding:])  # (p, m)
        target = self._scaled(z)
        for i, model in enumerate(self.models):
            model.partial_fit(window[:, i], target[i])
        self._history = np.vstack([self._history, z])
        return self

    def forecast(self, steps: int) -> np.ndarray:
        """Forecasts ``z_{k+1}, ..., z_{k+steps}`` (steps, m) by iterating one-step predictions.

        Each prediction becomes the newest input of the next step (Du et al. (n.d.), section 5, step 3);
        the stored history and the networks are left unchanged.
        """
        self._require_fit("forecast")
        if steps < 1:
            raise PrognosisError(f"steps must be >= 1, got {steps}")
        window = self._scaled(self._history[-self.embedding:])  # (p, m), a new array
        out = np.empty((steps, self.n_variables))
        for k in range(steps):  # step k needs the prediction of step k - 1
            out[k] = [model.predict(window[:, i])[0] for i, model in enumerate(self.models)]
            window = np.vstack([window[1:], out[k]])
        out = out * self.std + self.mean
        return out[:, 0] if self._vector else out
