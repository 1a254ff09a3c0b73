"""Online identification: EM re-run on a sliding window of the latest samples (Gasperin et al. (2011), section 3.4)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from .. import _linalg as linalg
from .em import em_arrays_step, initial_model
from .linear_gaussian import LinearGaussianModel
from .smoother import SmootherResult, smooth_arrays
from ..errors import PrognosisError

__all__ = ["OnlineEM", "WindowIdentification", "whitened_model"]


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
    """Sliding-window EM identification (Gasperin et al. (2011), section 3.4).

    Keeps the last ``window`` samples ``(y_t, u_t)``.  When the window first fills, :func:`fit_em` runs
    from the default start (up to ``initial_iterations`` steps).  Afterwards, every ``every`` new samples,
    ``iterations`` EM steps run on the current window, warm-started from the previous model with its
    initial state moved to the new window's first sample (``mu1``, ``P1`` = the last E-step's smoothed
    state at that sample).  Between re-identifications :meth:`update` returns the last model.

    Defaults (the paper re-identifies at every sample and does not say how many iterations): ``window=200``
    (the paper's N, 16.7 h at 5 min), ``every=12`` (hourly at 5 min), ``iterations=5``,
    ``initial_iterations=200``, ``cross_covariance=False`` (the paper's parameter vector, eq. 24, has no S;
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
            raise PrognosisError(f"n_states must be a positive integer, got {n_states!r}")
        if window < 2:
            raise PrognosisError(f"window must be at least 2 samples, got {window}")
        if iterations < 1 or every < 1 or initial_iterations < 1:
            raise PrognosisError("iterations, every and initial_iterations must be >= 1")
        if every >= window:
            raise PrognosisError(f"every ({every}) must be smaller than window ({window}) for the warm start")
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
        return smooth_arrays(self._at_window_start(), y, u)

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
            raise PrognosisError(f"y_t, u_t: expected shapes {self._y[0].shape}, {self._u[0].shape}, got "
                                 f"{y_t.shape}, {u_t.shape}")
        if not np.all(np.isfinite(u_t)):
            raise PrognosisError("u_t must be finite (inputs are known)")
        if np.any(np.isinf(y_t)):
            raise PrognosisError("y_t must be finite or NaN (missing)")
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
            model = whitened_model(self._at_window_start(), self._smoothed, self._since)
            steps = self.iterations
        previous = None
        for _ in range(steps):
            model, res = em_arrays_step(model, y, u, self.cross_covariance, True)
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


def whitened_model(model: LinearGaussianModel, res: SmootherResult, start: int) -> LinearGaussianModel:
    """``model`` in the state basis where the smoothed states from ``start`` on have unit second moment.

    EM leaves the state basis free; along a long record a slowly growing mode lets it drift until ``mu1``
    is 1e7 and ``C`` 1e-2, or two states nearly coincide with ``C`` = 1e6 [1, -1], and the filter then
    loses the definiteness of ``P`` to round-off.  With ``M = avg E[x_t x_t^T] = L L^T``, ``T = L^-1``.
    """
    means, covs = res.smoothed_means[start:], res.smoothed_covariances[start:]
    if means.shape[0] == 0:
        return model
    second = linalg.symmetric(means.T @ means / means.shape[0] + covs.mean(axis=0))
    try:
        root = np.linalg.cholesky(second)
    except np.linalg.LinAlgError:
        return model
    if not np.all(np.isfinite(root)) or np.linalg.cond(root) > 1e8:
        return model
    return model.transformed(np.linalg.inv(root))
