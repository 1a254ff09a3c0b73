"""Degradation models of the prognostic candidate theta (Jha et al. (2016), section 3.1).

A model maps ``theta_{k-1}`` and the degradation progression parameters
``gamma_{k-1}`` to ``theta_k``, plus additive process noise ``v ~ N(0, s^2)``:

* :class:`LinearDegradation` ``theta_k = theta_{k-1} + gamma dt + v``           (Jha et al. (2016), eq. 60)
* :class:`ExponentialDegradation` ``theta_k = theta_{k-1} exp(gamma dt) + v``        (Jha et al. (2016), eq. 53)
* :class:`CustomDegradation` ``theta_k = g(theta_{k-1}, gamma, dt) + v``

Arrays are vectorized over assets and particles: ``theta`` has shape
``(..., N)`` and ``gamma`` shape ``(..., N, G)`` with ``G`` the number of
progression parameters.  :meth:`path` propagates a whole horizon at once: for
the linear and exponential models with cumulative sums (no loop over steps),

    linear:       theta_{k+l} = theta_k + dt sum_{m<l} gamma_{k+m} + sum_{j<=l} v_j
    exponential:  theta_{k+l} = E_l (theta_k + sum_{j<=l} v_j / E_j),
                  E_l = exp(dt sum_{m<l} gamma_{k+m}).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .errors import PrognosisError


@dataclass(frozen=True)
class LinearDegradation:
    """``theta_k = theta_{k-1} + gamma_{k-1} dt + v``, ``v ~ N(0, process_noise^2)``.

    >>> import numpy as np
    >>> LinearDegradation().step(np.array([1.0]), np.array([[0.5]]), dt=0.1)
    array([1.05])
    """

    process_noise: float = 0.0
    n_gamma: int = 1

    def step(self, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
        """Deterministic step ``theta_k = theta_{k-1} + gamma_{k-1} dt``: ``theta`` (..., N), ``gamma`` (..., N, G).

        Uses ``gamma[..., 0]``; the caller (the particle filter) adds the process noise ``v``.
        """
        return theta + gamma[..., 0] * dt

    def path(self, theta: np.ndarray, gamma: np.ndarray, noise: np.ndarray, dt: float) -> np.ndarray:
        """theta over a horizon: ``gamma`` (..., N, H, G) used at each step, ``noise`` (..., N, H)."""
        return theta[..., None] + dt * np.cumsum(gamma[..., 0], axis=-1) + np.cumsum(noise, axis=-1)

    def path_from_sums(self, theta, gamma_sum, noise, noise_sum, carry, dt):
        """theta_{k+l} = theta_k + dt gamma_sum + noise_sum, with ``gamma_sum`` = sum_{m<l} gamma_{k+m}
        and ``noise_sum`` = sum_{j<=l} v_j, both (M, H) and counted from the prediction time."""
        return theta[:, None] + dt * gamma_sum + (0.0 if noise_sum is None else noise_sum), carry


@dataclass(frozen=True)
class ExponentialDegradation:
    """``theta_k = theta_{k-1} exp(gamma_{k-1} dt) + v``, ``v ~ N(0, process_noise^2)``.

    >>> import numpy as np
    >>> float(ExponentialDegradation().step(np.array([2.0]), np.array([[np.log(2) / 0.5]]), dt=0.5)[0])
    4.0
    """

    process_noise: float = 0.0
    n_gamma: int = 1

    def step(self, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
        """Deterministic step ``theta_{k+1} = theta_k exp(gamma_k dt)``: ``theta`` (..., N), ``gamma`` (..., N, G).

        Uses ``gamma[..., 0]``; the caller (the particle filter) adds the process noise ``v``.
        """
        return theta * np.exp(gamma[..., 0] * dt)

    def path(self, theta: np.ndarray, gamma: np.ndarray, noise: np.ndarray, dt: float) -> np.ndarray:
        """theta over a horizon: ``gamma`` (..., N, H, G) used at each step, ``noise`` (..., N, H); returns (..., N, H).

        ``theta_{k+l} = E_l (theta_k + sum_{j<=l} v_j / E_j)`` with ``E_l = exp(dt sum_{m<l} gamma_{k+m})``, from
        cumulative sums (no loop over steps).
        """
        growth = np.exp(dt * np.cumsum(gamma[..., 0], axis=-1))  # E_l
        return growth * (theta[..., None] + np.cumsum(noise / growth, axis=-1))

    def path_from_sums(self, theta, gamma_sum, noise, noise_sum, carry, dt):
        """theta_{k+l} = E_l (theta_k + sum_{j<=l} v_j / E_j), E_l = exp(dt sum_{m<l} gamma_{k+m}).

        ``noise`` holds this chunk's v_j (M, H); ``carry`` the sum of v_j / E_j of earlier chunks.
        Works in place on ``gamma_sum`` and ``noise`` (scratch arrays of the caller).
        """
        # |exponent| <= 80 keeps float32 growth finite and non-zero (no inf/0 -> NaN); a path
        # scaled by e^80 has crossed any practical threshold, one scaled by e^-80 has not
        growth = gamma_sum
        growth *= dt
        np.clip(growth, -80.0, 80.0, out=growth)
        np.exp(growth, out=growth)
        if noise is None:
            return growth * (theta + carry)[:, None], carry
        np.divide(noise, growth, out=noise)
        noise[:, 0] += theta + carry  # one pass: the prefix sum gives theta + S_l directly
        level = prefix_sum(noise)
        carry = level[:, -1] - theta
        level *= growth
        return level, carry


@dataclass(frozen=True)
class CustomDegradation:
    """``theta_k = g(theta_{k-1}, gamma_{k-1}, dt) + v`` for a user function ``g``.

    ``g`` receives ``theta`` (..., N) and ``gamma`` (..., N, G) and must be
    vectorized over them.  Its horizon path steps through time in a loop
    (each step still vectorized over particles).

    >>> import numpy as np
    >>> model = CustomDegradation(lambda theta, gamma, dt: theta * (1 + gamma[..., 0] * dt + gamma[..., 1] * dt**2),
    ...                           n_gamma=2)
    >>> model.step(np.array([1.0]), np.array([[1.0, 2.0]]), dt=0.5)
    array([2.])
    """

    g: Callable
    n_gamma: int = 1
    process_noise: float = 0.0

    def step(self, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
        """Deterministic step ``theta_k = g(theta_{k-1}, gamma_{k-1}, dt)`` as a float array, ``theta`` (..., N).

        ``gamma`` is (..., N, G); the caller (the particle filter) adds the process noise ``v``.
        """
        return np.asarray(self.g(theta, gamma, dt), dtype=float)

    def path(self, theta: np.ndarray, gamma: np.ndarray, noise: np.ndarray, dt: float) -> np.ndarray:
        """theta over a horizon, one step at a time: ``theta_{k+l} = g(theta_{k+l-1}, gamma_{k+l-1}, dt) + v_l``.

        ``gamma`` (..., N, H, G) holds the gamma used at each step, ``noise`` (..., N, H) the ``v_l``; returns
        (..., N, H).
        """
        out = np.empty(noise.shape)
        current = theta
        for step in range(noise.shape[-1]):
            current = self.step(current, gamma[..., step, :], dt) + noise[..., step]
            out[..., step] = current
        return out



@dataclass(frozen=True)
class PerAssetDegradation:
    """A law per row of the particle arrays: competing hypotheses batched in one filter.

    ``models[laws[a]]`` moves row ``a`` of ``theta`` (A, N) and ``gamma`` (A, N, G); every model has the
    same number of gammas.  Each law's rows move in one vectorized call.

    >>> import numpy as np
    >>> bank = PerAssetDegradation((LinearDegradation(), ExponentialDegradation()), laws=(0, 1, 0))
    >>> bank.step(np.ones((3, 1)), np.full((3, 1, 1), np.log(2.0)), dt=1.0).round(3).ravel().tolist()
    [1.693, 2.0, 1.693]
    >>> bank.process_noise.shape
    (3, 1)
    """

    models: tuple
    laws: tuple  # index into models, per asset row

    def __post_init__(self):
        if len({m.n_gamma for m in self.models}) > 1:
            raise PrognosisError("every law of a PerAssetDegradation must have the same number of gammas")

    @property
    def n_gamma(self) -> int:
        return self.models[0].n_gamma

    @property
    def process_noise(self) -> np.ndarray:
        """Standard deviation of v per row, (A, 1), to broadcast over the particles."""
        return np.array([[self.models[i].process_noise] for i in self.laws], float)

    def step(self, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
        """Deterministic step of each row with its own law."""
        out = np.empty(np.shape(theta))
        rows = np.asarray(self.laws)
        for index, model in enumerate(self.models):
            mine = rows == index
            if mine.any():
                out[mine] = model.step(theta[mine], gamma[mine], dt)
        return out

_BLOCK = 16
_TRIANGLE = np.triu(np.ones((_BLOCK, _BLOCK), np.float32))


def prefix_sum(x: np.ndarray) -> np.ndarray:
    """Cumulative sum along axis 1 of a 2-D array.

    numpy's ``cumsum`` along a row is a serial loop (about 4 ns an element);
    for long rows, sums inside blocks of 16 as one matrix product with a
    triangular matrix (BLAS) plus a cumulative sum of the block totals is
    faster.  Short rows use ``cumsum``.

    >>> import numpy as np
    >>> x = np.arange(40, dtype=np.float32).reshape(1, 40)
    >>> bool(np.allclose(prefix_sum(x), np.cumsum(x, axis=1)))
    True
    """
    rows, h = x.shape
    if h < 128 or h % _BLOCK or x.dtype != np.float32:
        return np.cumsum(x, axis=1)
    blocks = x.reshape(rows, h // _BLOCK, _BLOCK) @ _TRIANGLE
    offsets = np.cumsum(blocks[:, :, -1], axis=1)
    blocks[:, 1:, :] += offsets[:, :-1, None]
    return blocks.reshape(rows, h)


MODELS = {"linear": LinearDegradation, "exponential": ExponentialDegradation}


def degradation_model(name: str, process_noise: float = 0.0):
    """A built-in model by name: ``"linear"`` or ``"exponential"``.

    Parameters
    ----------
    name : {"linear", "exponential"}
    process_noise : float
        Standard deviation of the additive process noise ``v``.

    Returns
    -------
    LinearDegradation or ExponentialDegradation

    Examples
    --------
    >>> import numpy as np
    >>> model = degradation_model("exponential", process_noise=0.01)
    >>> model
    ExponentialDegradation(process_noise=0.01, n_gamma=1)
    >>> round(float(model.step(np.array([1.0]), np.array([[np.log(2.0)]]), dt=1.0)[0]), 9)   # doubles in a step
    2.0
    >>> degradation_model("linear").step(np.array([1.0]), np.array([[0.5]]), dt=2.0).tolist()
    [2.0]
    """
    if name not in MODELS:
        raise PrognosisError(f"unknown degradation model {name!r}; choose from {sorted(MODELS)} "
                             "or use CustomDegradation(g)")
    return MODELS[name](process_noise=process_noise)
