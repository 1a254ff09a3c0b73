"""Degradation models of the prognostic candidate theta (Jha et al. (2016), section 3.1).

A model maps ``theta_{k-1}`` and the degradation progression parameters
``gamma_{k-1}`` to ``theta_k``, plus additive process noise ``v ~ N(0, s^2)``:

* :class:`LinearDegradation` ``theta_k = theta_{k-1} + gamma dt + v``           (Jha et al. (2016), eq. 60)
* :class:`ExponentialDegradation` ``theta_k = theta_{k-1} exp(gamma dt) + v``        (Jha et al. (2016), eq. 53)
* :class:`PowerDegradation` ``theta = origin + span (a tau)^q``, tau the time since onset: a power law in
  time whose exponent ``q`` is estimated with the rate ``a`` (gamma = (a, q)); it holds the linear law
  (q = 1) and bends either way, the flexible law that takes over when the data contradict the others
* :class:`SaturatingDegradation` ``u = (1 - exp(-c (a tau)^q)) / c``: the power law levelling off toward
  ``1 / c`` of the way to failure (gamma = (a, q, c)), for a wear that accelerates then slows
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

__all__ = [
    "MODELS", "POWER_EXPONENTS", "SATURATIONS", "SHAPED", "CustomDegradation", "ExponentialDegradation",
    "JointDegradation", "LinearDegradation", "PerAssetDegradation", "PowerDegradation", "SaturatingDegradation",
    "degradation_model", "prefix_sum", "stepped_path", "trajectory",
]


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

    def trajectory(self, theta: np.ndarray, gamma: np.ndarray, start: int, stop: int, dt: float) -> np.ndarray:
        """theta after ``j`` deterministic steps, ``j`` in ``start..stop`` (..., N, stop - start): in closed form."""
        return theta[..., None] + dt * gamma[..., 0][..., None] * np.arange(start, stop)

    def crossing(self, theta: np.ndarray, gamma: np.ndarray, theta_fail: float) -> np.ndarray:
        """Time (s) until the deterministic path from ``theta`` (...) reaches ``theta_fail``; inf if it never does.

        >>> LinearDegradation().crossing(np.array([1.0, 1.0]), np.array([[0.5], [-0.5]]), 2.0).tolist()
        [2.0, inf]
        """
        with np.errstate(divide="ignore", invalid="ignore"):
            return _ahead((theta_fail - theta) / gamma[..., 0])

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

    def trajectory(self, theta: np.ndarray, gamma: np.ndarray, start: int, stop: int, dt: float) -> np.ndarray:
        """theta after ``j`` deterministic steps, ``j`` in ``start..stop`` (..., N, stop - start): in closed form."""
        with np.errstate(over="ignore"):
            return theta[..., None] * np.exp(gamma[..., 0][..., None] * dt * np.arange(start, stop))

    def crossing(self, theta: np.ndarray, gamma: np.ndarray, theta_fail: float) -> np.ndarray:
        """Time (s) until the deterministic path from ``theta`` (...) reaches ``theta_fail``; inf if it never does."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return _ahead(np.log(theta_fail / theta) / gamma[..., 0])

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


#: exponents q of the power law a hypothesis weighs (log-uniform): from a wear slowing like a square root
#: of time to one accelerating like its fifth power
POWER_EXPONENTS = (0.5, 5.0)


@dataclass(frozen=True)
class PowerDegradation:
    """``theta = origin + span u``, ``u = (a tau)^q``: a power law of the time ``tau`` since onset.

    ``u`` is the share of the way from ``origin`` (the nominal value) to ``origin + span`` (the
    failure value), ``a`` one over the life from onset to failure (1/s) and ``q`` the exponent:
    1 is the linear law, above 1 a wear that accelerates, below 1 one that slows.  The onset is
    not a parameter: the law is stepped from the current theta, since ``u^(1/q)`` grows by ``a dt``
    a step whatever the time since onset,

        u_{k+1} = (u_k^(1/q) + a dt)^q,

    exact at any step.  gamma is ``(a, q)``; a theta on the nominal side of ``origin`` steps as from
    ``u = 0``.

    >>> import numpy as np
    >>> model = PowerDegradation(origin=1.0, span=1.0)
    >>> gamma = np.array([[0.1, 2.0]])                   # fails 10 s after onset, as tau^2
    >>> theta = np.array([1.0])
    >>> for _ in range(5):
    ...     theta = model.step(theta, gamma, dt=1.0)
    >>> round(float(theta[0]), 6)                        # u = (0.1 * 5)^2
    1.25
    """

    origin: float
    span: float
    process_noise: float = 0.0
    n_gamma: int = 2

    def __post_init__(self):
        _check_ends("power", self.origin, self.span)

    def step(self, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
        """``u_{k+1} = (u_k^(1/q) + a dt)^q`` with ``a, q = gamma[..., 0], gamma[..., 1]``."""
        share = np.maximum((theta - self.origin) / self.span, 0.0)
        rate, exponent = gamma[..., 0], gamma[..., 1]
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            clock = np.maximum(share ** (1.0 / exponent) + rate * dt, 0.0)  # a tau, up to the step's end
            return self.origin + self.span * clock ** exponent

    def trajectory(self, theta: np.ndarray, gamma: np.ndarray, start: int, stop: int, dt: float) -> np.ndarray:
        """theta after ``j`` deterministic steps, for ``j`` in ``start..stop`` (..., N, stop - start): the clock
        ``a tau`` grows by ``a dt`` a step."""
        share = np.maximum((theta - self.origin) / self.span, 0.0)
        rate, exponent = gamma[..., 0][..., None], gamma[..., 1][..., None]
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            clock = np.maximum(share[..., None] ** (1.0 / exponent) + rate * dt * np.arange(start, stop), 0.0)
            return self.origin + self.span * clock ** exponent

    def crossing(self, theta: np.ndarray, gamma: np.ndarray, theta_fail: float) -> np.ndarray:
        """Time (s) until the deterministic path from ``theta`` (...) reaches ``theta_fail``; inf if it never does:
        the clock ``u^(1/q)`` must grow from its value now to the failure value's at ``a`` a second.

        >>> model = PowerDegradation(origin=1.0, span=1.0)
        >>> float(model.crossing(np.array([1.25]), np.array([[0.1, 2.0]]), 2.0)[0])   # tau from 5 s to 10 s
        5.0
        """
        share = np.maximum((theta - self.origin) / self.span, 0.0)
        rate, exponent = gamma[..., 0], gamma[..., 1]
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            goal = ((theta_fail - self.origin) / self.span) ** (1.0 / exponent)
            return _ahead(np.where(exponent > 0, (goal - share ** (1.0 / exponent)) / rate, np.nan))

    def path(self, theta: np.ndarray, gamma: np.ndarray, noise: np.ndarray, dt: float) -> np.ndarray:
        """theta over a horizon: ``gamma`` (..., N, H, 2) used at each step, ``noise`` (..., N, H); returns (..., N, H).

        Without process noise the clock ``a tau`` is a cumulative sum of the rates (no loop over
        steps); with it, one step at a time.
        """
        if not np.any(noise):
            share = np.maximum((theta - self.origin) / self.span, 0.0)
            exponent = gamma[..., 0, 1]
            with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
                clock = (share ** (1.0 / exponent))[..., None] + dt * np.cumsum(gamma[..., 0], axis=-1)
                return self.origin + self.span * np.maximum(clock, 0.0) ** exponent[..., None]
        return stepped_path(self, theta, gamma, noise, dt)


#: the saturating law's ``c``, one over the level its wear tends to (as a share of the way from nominal to
#: failure), log-uniform: from a saturation at 20 times the way (a power law to within 1 % of the life) to
#: one just beyond the failure value, so that every path still reaches it
SATURATIONS = (0.05, 0.99)


@dataclass(frozen=True)
class SaturatingDegradation:
    """``theta = origin + span u``, ``u = (1 - exp(-c w)) / c``, ``w = (a tau)^q``: a power law that saturates.

    Early on (``c w`` small) ``u`` is the power law ``(a tau)^q`` of :class:`PowerDegradation`; then it
    slows toward ``1 / c`` of the way from ``origin`` (the nominal value) to ``origin + span`` (the
    failure value): a wear that accelerates, then levels off, as fouling that tends to an asymptote
    (``q = 1``: Kern and Seaton's law) or a sigmoid wear (``q > 1``).  ``c`` below 1 puts the level beyond
    the failure value, so the failure is reached at ``w = -log(1 - c) / c``.  The law is stepped from
    the current theta as the power law is: ``w`` follows from ``u``, and ``w^(1/q)`` grows by ``a dt``.
    gamma is ``(a, q, c)``.

    >>> import numpy as np
    >>> model = SaturatingDegradation(origin=0.0, span=1.0)
    >>> gamma = np.array([[0.1, 1.0, 0.5]])              # w = tau / 10, levelling off at twice the way
    >>> theta = np.array([0.0])
    >>> for _ in range(10):
    ...     theta = model.step(theta, gamma, dt=1.0)
    >>> round(float(theta[0]), 6), round(float((1 - np.exp(-0.5)) / 0.5), 6)   # w = 1 after 10 s
    (0.786939, 0.786939)
    >>> round(float(model.crossing(np.array([0.0]), gamma, 1.0)[0]), 4)   # w = log(2) / 0.5 = 1.3863
    13.8629
    """

    origin: float
    span: float
    process_noise: float = 0.0
    n_gamma: int = 3

    def __post_init__(self):
        _check_ends("saturating", self.origin, self.span)

    def _clock(self, theta: np.ndarray, exponent: np.ndarray, level: np.ndarray) -> np.ndarray:
        """``w^(1/q)`` of theta: the power law's clock ``a tau`` (inf at or beyond the level)."""
        share = np.maximum((theta - self.origin) / self.span, 0.0)
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            power = -np.log1p(-np.minimum(level * share, 1.0)) / level
            return power ** (1.0 / exponent)

    def _share(self, clock: np.ndarray, exponent: np.ndarray, level: np.ndarray) -> np.ndarray:
        with np.errstate(over="ignore", invalid="ignore"):
            return -np.expm1(-level * np.maximum(clock, 0.0) ** exponent) / level

    def step(self, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
        """One step: the clock ``w^(1/q)`` grows by ``a dt``; ``a, q, c = gamma[..., 0], [..., 1], [..., 2]``."""
        return self.trajectory(theta, gamma, 1, 2, dt)[..., 0]

    def trajectory(self, theta: np.ndarray, gamma: np.ndarray, start: int, stop: int, dt: float) -> np.ndarray:
        """theta after ``j`` deterministic steps, for ``j`` in ``start..stop`` (..., N, stop - start)."""
        rate, exponent, level = (gamma[..., g][..., None] for g in range(3))
        # before the onset (a step traced back past it) the clock stays at 0
        clock = np.maximum(self._clock(theta[..., None], exponent, level) + rate * dt * np.arange(start, stop), 0.0)
        # a theta at or beyond this particle's level stays where it is: the law never gets there
        return np.where(np.isfinite(clock), self.origin + self.span * self._share(clock, exponent, level),
                        theta[..., None])

    def crossing(self, theta: np.ndarray, gamma: np.ndarray, theta_fail: float) -> np.ndarray:
        """Time (s) until the deterministic path from ``theta`` (...) reaches ``theta_fail``; inf if it never does
        (the failure value at or beyond the level ``1 / c``)."""
        rate, exponent, level = gamma[..., 0], gamma[..., 1], gamma[..., 2]
        goal = self._clock(np.broadcast_to(np.asarray(theta_fail, float), np.shape(theta)), exponent, level)
        with np.errstate(invalid="ignore"):
            return _ahead((goal - self._clock(theta, exponent, level)) / rate)

    def path(self, theta: np.ndarray, gamma: np.ndarray, noise: np.ndarray, dt: float) -> np.ndarray:
        """theta over a horizon, one step at a time: ``gamma`` (..., N, H, 3), ``noise`` (..., N, H)."""
        return stepped_path(self, theta, gamma, noise, dt)


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
        return stepped_path(self, theta, gamma, noise, dt)



@dataclass(frozen=True)
class PerAssetDegradation:
    """A law per row of the particle arrays: competing hypotheses batched in one filter.

    ``models[laws[a]]`` moves row ``a`` of ``theta`` (A, N) and ``gamma`` (A, N, G); G is the largest
    number of gammas of the models, and a model with fewer reads the first of them (its rows carry the
    others unused).  Each law's rows move in one vectorized call.

    >>> import numpy as np
    >>> bank = PerAssetDegradation((LinearDegradation(), ExponentialDegradation()), laws=(0, 1, 0))
    >>> bank.step(np.ones((3, 1)), np.full((3, 1, 1), np.log(2.0)), dt=1.0).round(3).ravel().tolist()
    [1.693, 2.0, 1.693]
    >>> bank.process_noise.shape
    (3, 1)
    """

    models: tuple
    laws: tuple  # index into models, per asset row

    @property
    def n_gamma(self) -> int:
        return max(m.n_gamma for m in self.models)

    @property
    def process_noise(self) -> np.ndarray:
        """Standard deviation of v per row, (A, 1), to broadcast over the particles."""
        return np.array([[self.models[i].process_noise] for i in self.laws], float)

    def rows(self, index: np.ndarray) -> "PerAssetDegradation":
        """The bank of the rows ``index`` alone.

        >>> PerAssetDegradation((LinearDegradation(), ExponentialDegradation()), laws=(0, 1, 0)).rows([1]).laws
        (1,)
        """
        return PerAssetDegradation(self.models, tuple(self.laws[i] for i in index))

    def step(self, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
        """Deterministic step of each row with its own law."""
        out = np.empty(np.shape(theta))
        rows = np.asarray(self.laws)
        for index, model in enumerate(self.models):
            mine = rows == index
            if mine.any():
                out[mine] = model.step(theta[mine], gamma[mine][..., :model.n_gamma], dt)
        return out

    def trajectory(self, theta: np.ndarray, gamma: np.ndarray, start: int, stop: int, dt: float) -> np.ndarray:
        """theta (A, N) after j steps of each row's law, ``j`` in ``start..stop`` (A, N, stop - start).

        >>> bank = PerAssetDegradation((LinearDegradation(), ExponentialDegradation()), laws=(0, 1))
        >>> bank.trajectory(np.ones((2, 1)), np.full((2, 1, 1), np.log(2.0)), 1, 3, dt=1.0).round(3).tolist()
        [[[1.693, 2.386]], [[2.0, 4.0]]]
        """
        out = np.empty((*np.shape(theta), stop - start))
        rows = np.asarray(self.laws)
        for index, model in enumerate(self.models):
            mine = rows == index
            if mine.any():
                out[mine] = trajectory(model, theta[mine], gamma[mine][..., :model.n_gamma], start, stop, dt)
        return out

@dataclass(frozen=True)
class JointDegradation:
    """Several parameters per row degrading at once, each by its own law: a joint hypothesis.

    Component ``c`` of ``theta`` (A, N, C) moves by ``banks[c]`` (a
    :class:`PerAssetDegradation`, a law per row) with its own gammas, ``gamma[..., offsets[c]:]``
    of the row's (A, N, G); G sums the banks' gammas.

    >>> import numpy as np
    >>> first = PerAssetDegradation((LinearDegradation(),), laws=(0,))
    >>> second = PerAssetDegradation((ExponentialDegradation(),), laws=(0,))
    >>> joint = JointDegradation((first, second))
    >>> theta, gamma = np.ones((1, 1, 2)), np.array([[[0.5, np.log(2.0)]]])
    >>> joint.step(theta, gamma, dt=1.0).tolist()   # 1 + 0.5 and 1 * 2
    [[[1.5, 2.0]]]
    """

    banks: tuple

    @property
    def n_gamma(self) -> int:
        return sum(b.n_gamma for b in self.banks)

    @property
    def offsets(self) -> list[int]:
        """Where each component's gammas start in a row's gammas."""
        return [sum(b.n_gamma for b in self.banks[:c]) for c in range(len(self.banks))]

    def rows(self, index) -> "JointDegradation":
        return JointDegradation(tuple(b.rows(index) for b in self.banks))

    def trajectory(self, theta: np.ndarray, gamma: np.ndarray, start: int, stop: int, dt: float) -> np.ndarray:
        """theta (A, N, C) after ``j`` deterministic steps, ``j`` in ``start..stop``: (A, N, stop - start, C)."""
        return np.stack([bank.trajectory(theta[..., c], gamma[..., first:first + bank.n_gamma], start, stop, dt)
                         for c, (bank, first) in enumerate(zip(self.banks, self.offsets))], axis=-1)

    def step(self, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
        """Deterministic step of each component with its row's law."""
        return np.stack([bank.step(theta[..., c], gamma[..., start:start + bank.n_gamma], dt)
                         for c, (bank, start) in enumerate(zip(self.banks, self.offsets))], axis=-1)


def _check_ends(law: str, origin: float, span: float) -> None:
    """A PrognosisError unless a law between two values has a finite origin and a nonzero span."""
    if not (np.isfinite(origin) and np.isfinite(span) and span != 0):
        raise PrognosisError(f"a {law} law needs a finite origin and a nonzero span, got origin {origin}, span {span}")


def _ahead(time: np.ndarray) -> np.ndarray:
    """A crossing time where it lies ahead (positive and finite), else inf: the path never gets there."""
    return np.where(np.isfinite(time) & (time > 0), time, np.inf)


def trajectory(model, theta: np.ndarray, gamma: np.ndarray, start: int, stop: int, dt: float) -> np.ndarray:
    """theta (..., N) after ``j`` deterministic steps of ``model``, ``j`` in ``start..stop``: (..., N, stop - start);
    in closed form where the model has one, else step by step, and then held at ``theta`` for ``j < 0`` (a
    law known only by its step cannot be traced back).

    >>> trajectory(CustomDegradation(lambda theta, gamma, dt: theta + 1.0), np.zeros(1), np.zeros((1, 1)), -1, 3,
    ...            dt=1.0).tolist()
    [[0.0, 0.0, 1.0, 2.0]]
    """
    if hasattr(model, "trajectory"):
        return model.trajectory(theta, gamma, start, stop, dt)
    out = np.empty((*np.shape(theta), stop - start))
    for j in range(min(start, 0), stop):
        if j >= start:
            out[..., j - start] = theta
        if j >= 0:
            theta = model.step(theta, gamma, dt)
    return out


def stepped_path(model, theta: np.ndarray, gamma: np.ndarray, noise: np.ndarray, dt: float) -> np.ndarray:
    """theta over a horizon by ``model.step``, one step at a time (each step vectorized over particles):
    ``theta_{k+l} = step(theta_{k+l-1}, gamma_{k+l-1}, dt) + v_l``; ``gamma`` (..., N, H, G), ``noise`` (..., N, H).

    >>> import numpy as np
    >>> stepped_path(LinearDegradation(), np.zeros(1), np.ones((1, 3, 1)), np.zeros((1, 3)), dt=0.5).tolist()
    [[0.5, 1.0, 1.5]]
    """
    out = np.empty(noise.shape)
    current = theta
    for step in range(noise.shape[-1]):
        current = model.step(current, gamma[..., step, :], dt) + noise[..., step]
        out[..., step] = current
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


MODELS = {"linear": LinearDegradation, "exponential": ExponentialDegradation, "power": PowerDegradation,
          "saturating": SaturatingDegradation}
#: the built-in laws that run between the nominal and the failure value and carry more than a rate
SHAPED = ("power", "saturating")


def degradation_model(name: str, process_noise: float = 0.0, *, nominal: float | None = None,
                      failure: float | None = None):
    """A built-in model by name: ``"linear"``, ``"exponential"``, ``"power"`` or ``"saturating"``.

    Parameters
    ----------
    name : {"linear", "exponential", "power", "saturating"}
    process_noise : float
        Standard deviation of the additive process noise ``v``.
    nominal, failure : float
        ``"power"`` and ``"saturating"`` only: the parameter's nominal and failure values, between which the
        law runs.

    Returns
    -------
    LinearDegradation, ExponentialDegradation, PowerDegradation or SaturatingDegradation

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
    >>> degradation_model("power", nominal=1.0, failure=3.0)
    PowerDegradation(origin=1.0, span=2.0, process_noise=0.0, n_gamma=2)
    """
    if name not in MODELS:
        raise PrognosisError(f"unknown degradation model {name!r}; choose from {sorted(MODELS)} "
                             "or use CustomDegradation(g)")
    if name in SHAPED:
        if nominal is None or failure is None:
            raise PrognosisError(f"the {name} law runs from the nominal to the failure value: give nominal= and "
                                 "failure=")
        return MODELS[name](float(nominal), float(failure) - float(nominal), process_noise=process_noise)
    return MODELS[name](process_noise=process_noise)
