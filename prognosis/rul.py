"""Remaining useful life by propagating the particles to the failure threshold (Jha et al. (2016), Table IV).

Each particle keeps its weight and is propagated with its degradation model
and the random walk of its gamma until theta crosses ``theta_fail`` (upwards or
downwards).  The horizon is processed in chunks of steps: inside a chunk the
path of every particle comes from cumulative sums (:meth:`path` of the
degradation model), so there is no per-particle and no per-step loop for the
linear and exponential models; only particles that have not failed yet are
carried into the next chunk, and chunks grow from 64 steps.  Particles that have not crossed when the
horizon cap is reached are *censored*: their RUL is ``+inf`` and they are
counted, not dropped.  The mean is over crossed particles (renormalized) and
reported with the censored weight; median and percentiles treat censored
particles as ``+inf``.
"""

from __future__ import annotations

import numbers
import signal
import warnings
from concurrent.futures import Future
from dataclasses import dataclass

import numpy as np

from bondgraph.errors import PHMWarning

from .degradation import LinearDegradation
from .weighted import weighted_quantiles
from .seeds import check_seed, generator
from .errors import PrognosisError

__all__ = [
    "BANK_BYTES_PER_STEP", "MAX_BANK_BYTES", "MAX_HORIZON_STEPS", "ParallelRUL", "ParallelWarning",
    "RULDistribution", "RULPredictor", "check_horizon", "predict_rul",
]

MAX_HORIZON_STEPS = 1_000_000  # a horizon longer than this many filter steps is refused
BANK_BYTES_PER_STEP = 16  # per particle and horizon step: four float32 banks (Z, CW, V, CV)
MAX_BANK_BYTES = 2**31  # the random-number bank of one predictor (rows x steps x 16 bytes) stays under 2 GiB
_BANK, _DRAWS, _KEYED = 0, 1, 2  # a predictor's streams under its seed: the bank, unkeyed and keyed predictions


def check_horizon(horizon: float, dt: float, particles: int = 0, predictors: int = 1) -> int:
    """The number of steps of ``horizon``; a PrognosisError when it is beyond the predictors' limits.

    At most :data:`MAX_HORIZON_STEPS` steps of ``dt``, and the random-number banks of ``predictors``
    predictors of ``particles`` rows each (:data:`BANK_BYTES_PER_STEP` bytes per row and step) at most
    :data:`MAX_BANK_BYTES` in all.

    >>> check_horizon(200.0, 0.1, particles=500)
    2000
    >>> try:
    ...     check_horizon(1e12, 0.1)
    ... except PrognosisError as error:
    ...     print(error)
    horizon 1e+12 s is 1e+13 steps of dt = 0.1 s; at most 1000000 (prognosis.rul.MAX_HORIZON_STEPS)
    """
    if not (np.isfinite(horizon) and np.isfinite(dt) and horizon > 0 and dt > 0):
        raise PrognosisError(f"horizon and dt must be positive and finite, got horizon={horizon}, dt={dt}")
    if horizon / dt > MAX_HORIZON_STEPS:
        raise PrognosisError(f"horizon {horizon:g} s is {horizon / dt:.3g} steps of dt = {dt:g} s; at most "
                             f"{MAX_HORIZON_STEPS} (prognosis.rul.MAX_HORIZON_STEPS)")
    steps = int(np.ceil(horizon / dt - 1e-9))
    need = predictors * particles * steps * BANK_BYTES_PER_STEP
    if need > MAX_BANK_BYTES:
        raise PrognosisError(f"{predictors} x {particles} particles x {steps} steps would need "
                             f"{need / 2**30:.3g} GiB of random numbers, more than {MAX_BANK_BYTES / 2**30:g} GiB "
                             "(prognosis.rul.MAX_BANK_BYTES); "
                             "shorten the horizon or use fewer particles")
    return steps


@dataclass(frozen=True)
class RULDistribution:
    """A predicted RUL distribution: weighted samples, ``inf`` where no failure came within the horizon.

    The one result type of every RUL prediction: the particle filter's (:class:`RULPredictor`,
    one row of particles per asset) and the Monte Carlo one from a Gaussian estimate
    (:func:`prognosis.lifecontrol.monte_carlo_rul`, one row of draws).  Statistics reduce the
    last axis, so they have the leading shape of ``samples``: ``(A,)`` for a batch of assets,
    a float for a single row.

    Attributes
    ----------
    samples : ndarray (..., N)
        RUL of each particle or draw (s); ``inf`` where it did not fail within ``horizon``.
    weights : ndarray (..., N), optional
        The samples' weights (normalized or not); equal weights when omitted.
    horizon : float
        The cap of the prediction (s); ``inf`` when not known.
    origin : float
        The prediction time ``t_0``; :attr:`eol` is ``origin + samples``.
    initial : ndarray (d, N), optional
        The drawn initial states of a Monte Carlo prediction.
    times, trajectories : ndarray (T,), (T, d, keep), optional
        Trajectories kept for plots by a Monte Carlo prediction.

    Conventions
    -----------
    - :attr:`mean` and :attr:`std` are over the samples that fail within the horizon (weights
      renormalized), NaN if none does; :attr:`censored_weight` says how much is left out.
    - Quantiles (:meth:`quantile`, :meth:`percentile`, :attr:`median`) count censored samples as
      ``+inf`` and take the smallest sample whose cumulative weight reaches the level (the
      inverted CDF, so an even number of equal weights gives the lower of the two middle samples).

    Examples
    --------
    Four equally weighted particles of one asset, one censored:

    >>> rul = RULDistribution(samples=np.array([[1.0, 2.0, 4.0, np.inf]]), weights=np.full((1, 4), 0.25), horizon=10.0)
    >>> rul.censored.tolist(), rul.censored_weight.tolist()
    ([[False, False, False, True]], [0.25])
    >>> np.round(rul.mean, 4).tolist(), rul.median.tolist()   # mean over the failed ones, median with inf
    ([2.3333], [2.0])
    >>> rul.percentile([10, 90]).tolist()
    [[1.0, inf]]

    A single row of unweighted Monte Carlo draws from ``t_0 = 10``:

    >>> draws = RULDistribution(samples=np.array([1.0, 2.0, 3.0, np.inf]), origin=10.0)
    >>> draws.eol.tolist(), draws.median, draws.mean
    ([11.0, 12.0, 13.0, inf], 2.0, 2.0)
    >>> draws.quantile(0.9), draws.probability_before(2.0)
    (inf, 0.5)
    """

    samples: np.ndarray
    weights: np.ndarray | None = None
    horizon: float = float("inf")
    origin: float = 0.0
    initial: np.ndarray | None = None
    times: np.ndarray | None = None
    trajectories: np.ndarray | None = None

    @property
    def _weights(self) -> np.ndarray:
        samples = np.asarray(self.samples, float)
        if self.weights is None:
            return np.full(samples.shape, 1.0 / max(samples.shape[-1], 1))
        return np.broadcast_to(np.asarray(self.weights, float), samples.shape)

    @staticmethod
    def _reduced(value: np.ndarray):
        return float(value) if np.ndim(value) == 0 else value

    @property
    def censored(self) -> np.ndarray:
        """Samples with no failure within the horizon (non-finite RUL), the shape of ``samples``."""
        return ~np.isfinite(self.samples)

    def _mass(self, mask: np.ndarray):
        """The weight of the samples in ``mask`` per row (the fraction of them without weights)."""
        if self.weights is None:
            return self._reduced(np.mean(mask, axis=-1))
        return self._reduced(np.sum(np.where(mask, self._weights, 0.0), axis=-1))

    @property
    def censored_weight(self):
        """Total weight of the censored samples per row (their fraction without weights)."""
        return self._mass(self.censored)

    @property
    def mean(self):
        """Weighted mean over the samples that fail within the horizon (NaN if none do)."""
        w = np.where(self.censored, 0.0, self._weights)
        total = w.sum(axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = np.where(total > 0, np.sum(w * np.where(self.censored, 0.0, self.samples), axis=-1) / total, np.nan)
        return self._reduced(mean)

    @property
    def std(self):
        """Weighted standard deviation over the samples that fail within the horizon (NaN if none do)."""
        w = np.where(self.censored, 0.0, self._weights)
        total = w.sum(axis=-1, keepdims=True)
        finite = np.where(self.censored, 0.0, self.samples)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = np.sum(w * finite, axis=-1, keepdims=True) / total
            variance = np.sum(w * (finite - mean) ** 2, axis=-1) / total[..., 0]
        return self._reduced(np.sqrt(variance))

    def quantile(self, q):
        """Weighted quantiles (``q`` in [0, 1], a number or a sequence); censored samples count as ``+inf``.

        Shape: the leading shape of ``samples``, plus one axis of ``len(q)`` for a sequence.
        """
        levels = np.atleast_1d(np.asarray(q, float))
        values = weighted_quantiles(np.asarray(self.samples, float), self._weights, levels)
        return self._reduced(values[..., 0]) if np.ndim(q) == 0 else values

    def percentile(self, q) -> np.ndarray:
        """Weighted percentiles (q in [0, 100]), censored samples as ``+inf``; shape (..., len(q))."""
        return self.quantile(np.atleast_1d(np.asarray(q, float)) / 100.0)

    @property
    def median(self):
        """Weighted median RUL: the smallest sample whose cumulative weight reaches 1/2 (censored as ``+inf``)."""
        return self.quantile(0.5)

    def probability_before(self, rul: float):
        """``Pr(RUL <= rul)``: the weight of the samples failing within ``rul``.

        Rodriguez Obando et al. (2021), eq. 51.
        """
        return self._mass(np.asarray(self.samples) <= rul)

    @property
    def eol(self) -> np.ndarray:
        """End-of-life times ``origin + samples``."""
        return self.origin + np.asarray(self.samples, float)


class RULPredictor:
    """Table IV with common random numbers, for predicting at every filter step.

    One bank of unit normals is drawn per predictor (rows x horizon steps):
    ``Z`` for the random walk of gamma and ``V`` for the process noise of
    theta.  Their cumulative sums are computed once, so a prediction needs
    neither new random numbers nor a cumulative sum for gamma:

        sum_{m<l} gamma_{k+m} = l gamma_k + sigma_xi CW_l,   CW_l = sum_{m<l} W_{m-1},  W = cumsum(Z)

    (``W_{-1} = 0``).  Each prediction assigns bank rows to particles by a
    fresh random permutation, so successive predictions use the same noise in
    a different order (common random numbers: the RUL curve over time is not
    jittered by independent Monte-Carlo noise, while each prediction is still
    an exact draw of Table IV).  Models without ``path_from_sums`` (CustomDegradation)
    are propagated step by step within a chunk.

    Parameters
    ----------
    model : degradation model
    dt : float
    theta_fail : float
    direction : {"up", "down"}
    horizon : float
        Cap (s); particles that have not failed by then are censored.
    seed : int or numpy.random.SeedSequence
        The bank, the permutations of unkeyed predictions and each keyed prediction draw from their own
        streams of it (:mod:`prognosis.seeds`).
    chunk : int
        Most steps propagated at once (chunks start at ``min(chunk, 64)`` steps and double up to it).

    Notes
    -----
    The bank (16 bytes per particle and horizon step, 16 MB for 500 particles over 2000 steps) is a
    function of the seed and of its number of rows alone, so it is not pickled: a predictor sent to
    another process rebuilds it on its first prediction, as large as it was, and predicts exactly
    as the original would.

    Examples
    --------
    Linear degradation from 0 to the threshold 2 at rates 0.5, 1 and 4 per second,
    without noise; a rate of 0.1 would need 20 s, beyond the 10 s horizon:

    >>> from prognosis.degradation import LinearDegradation
    >>> predictor = RULPredictor(LinearDegradation(), dt=0.1, theta_fail=2.0, horizon=10.0, seed=0)
    >>> weights = np.full((1, 3), 1 / 3)
    >>> predictor.predict(np.zeros((1, 3)), np.array([[[0.5], [1.0], [4.0]]]), weights, 0.0).samples.tolist()
    [[4.0, 2.0, 0.5]]
    >>> censored = predictor.predict(np.zeros((1, 3)), np.array([[[0.1], [1.0], [4.0]]]), weights, 0.0)
    >>> censored.samples.tolist(), np.round(censored.censored_weight, 4).tolist()
    ([[inf, 2.0, 0.5]], [0.3333])

    With a random walk on gamma, a ``key`` makes a prediction reproducible:

    >>> theta, gamma, weights = np.zeros((1, 100)), np.ones((1, 100, 1)), np.full((1, 100), 0.01)
    >>> first = predictor.predict(theta, gamma, weights, 0.1, key=7)
    >>> again = predictor.predict(theta, gamma, weights, 0.1, key=7)
    >>> bool(np.array_equal(first.samples, again.samples)), bool(np.all(first.samples > 0))
    (True, True)
    """

    def __init__(self, model, *, dt: float, theta_fail: float, direction: str = "up", horizon: float = 200.0,
                 seed: int | np.random.SeedSequence = 0, chunk: int = 512):
        if direction not in ("up", "down"):
            raise PrognosisError(f"direction must be 'up' or 'down', got {direction!r}")
        self.steps = check_horizon(horizon, dt)
        self.model, self.dt, self.theta_fail, self.direction = model, dt, theta_fail, direction
        self.horizon, self.chunk = horizon, chunk
        self.seed = check_seed(seed)
        self.rng = generator(self.seed, _DRAWS)
        self._bank = None
        self._bank_size = 0  # rows of the bank, kept when the bank itself is dropped (pickling)
        self._draws = None

    def __getstate__(self) -> dict:
        """The state without the noise bank (tens of MB), rebuilt from the seed on the next prediction."""
        return {**self.__dict__, "_bank": None, "_draws": None}

    def _generator(self) -> np.random.Generator:
        return self._draws if self._draws is not None else self.rng

    def _bank_rows(self, rows: int):
        if self._bank is None or self._bank["Z"].shape[0] < rows:
            # as many rows as before (the permutations depend on the bank's size), more if needed
            rows = max(rows, self._bank_size)
            check_horizon(self.horizon, self.dt, particles=rows)
            # Z and V from streams of their own: the bank is a function of the seed and its size alone
            z = generator(self.seed, _BANK, 0).standard_normal((rows, self.steps), dtype=np.float32)
            walk = np.cumsum(z, axis=1)
            v = generator(self.seed, _BANK, 1).standard_normal((rows, self.steps), dtype=np.float32)
            v *= np.float32(self.model.process_noise)  # the bank holds the process noise itself
            self._bank = {"Z": z, "CW": np.cumsum(walk - z, axis=1), "V": v, "CV": np.cumsum(v, axis=1)}
            self._bank_size = rows
        return self._bank

    def predict(self, theta: np.ndarray, gamma: np.ndarray, weights: np.ndarray, gamma_std, *,
                key: int | None = None) -> RULDistribution:
        """RUL distribution of particles ``theta`` (A, N), ``gamma`` (A, N, G) with their weights.

        ``key`` (e.g. the filter step) makes this prediction's randomness a function of the seed and
        the key alone, so predictions computed in any order or process give the same result.
        """
        self._draws = None if key is None else generator(self.seed, _KEYED, _check_key(key))
        assets, n, g = gamma.shape
        std = np.broadcast_to(np.broadcast_to(np.asarray(gamma_std, float), (assets, g))[:, None, :], (assets, n, g))
        theta_now = theta.astype(float).reshape(-1)
        gamma_now, std = gamma.astype(float).reshape(-1, g), std.reshape(-1, g)
        rul = np.full(theta_now.size, np.inf)
        failed = _crossed(theta_now, self.theta_fail, self.direction)
        rul[failed] = 0.0
        alive = np.flatnonzero(~failed)
        if hasattr(self.model, "crossing") and not np.any(std) and not np.any(self.model.process_noise):
            # a deterministic path (the resample-move filter's laws): its crossing time in closed form,
            # censored beyond the horizon as a stepped path would be
            with np.errstate(invalid="ignore"):
                time = self.model.crossing(theta_now[alive], gamma_now[alive], self.theta_fail)
            rul[alive] = np.where(time <= self.steps * self.dt, time, np.inf)
        elif hasattr(self.model, "path_from_sums") and g == 1:
            self._propagate_with_sums(theta_now, gamma_now[:, 0], std[:, 0], alive, rul)
        else:
            self._propagate_stepwise(theta_now, gamma_now, std, alive, rul)
        return RULDistribution(rul.reshape(assets, n), weights, self.horizon)

    def _propagate_with_sums(self, theta, gamma, std, alive, rul) -> None:
        bank = self._bank_rows(theta.size)
        rows = self._generator().permutation(bank["Z"].shape[0])[: theta.size]
        carry = np.zeros(theta.size)
        previous = theta.copy()  # theta before the current chunk, for interpolating the crossing
        sigma_v = np.float32(self.model.process_noise)
        done, h = 0, min(self.chunk, 64)
        with np.errstate(over="ignore", invalid="ignore"):
            while done < self.steps and alive.size:
                h = min(h, self.steps - done)
                window, r = slice(done, done + h), rows[alive]
                steps = np.arange(done + 1, done + h + 1, dtype=np.float32)
                gamma_sum = (steps * gamma[alive, None].astype(np.float32)
                             + std[alive, None].astype(np.float32) * bank["CW"][r, window])
                # the exponential model needs this chunk's noise, the linear one its running sum
                uses_sum = isinstance(self.model, LinearDegradation)
                noise = bank["V"][r, window] if sigma_v and not uses_sum else None
                noise_sum = bank["CV"][r, window] if sigma_v and uses_sum else None
                path, carry[alive] = self.model.path_from_sums(theta[alive], gamma_sum, noise, noise_sum,
                                                               carry[alive], self.dt)
                alive = self._record_crossings(path, alive, done, rul, previous)
                done += h
                h = min(2 * h, self.chunk)

    def _propagate_stepwise(self, theta, gamma, std, alive, rul) -> None:
        g = gamma.shape[1]
        previous = theta.copy()
        done, h = 0, min(self.chunk, 64)
        with np.errstate(over="ignore", invalid="ignore"):
            while done < self.steps and alive.size:
                h = min(h, self.steps - done)
                increments = self._generator().standard_normal((alive.size, h, g)) * std[alive, None, :]
                walk = np.cumsum(increments, axis=1)
                used = gamma[alive, None, :] + (walk - increments)  # gamma_{k+l-1} at step l
                noise = self._generator().standard_normal((alive.size, h)) * self.model.process_noise
                path = self.model.path(theta[alive], used, noise, self.dt)
                theta[alive], gamma[alive] = path[:, -1], gamma[alive] + walk[:, -1, :]
                alive = self._record_crossings(path, alive, done, rul, previous)
                done += h
                h = min(2 * h, self.chunk)

    def _record_crossings(self, path, alive, done, rul, previous):
        """RUL of the particles whose path crosses theta_fail in this chunk.

        The crossing time is interpolated linearly between the last step below the threshold and the
        first step at or beyond it, ``l - 1 + (theta_fail - theta_{l-1}) / (theta_l - theta_{l-1})``
        steps, rather than rounded up to whole steps (which biases the RUL by dt/2 on average).
        """
        crossed = path >= self.theta_fail if self.direction == "up" else path <= self.theta_fail
        first = np.argmax(crossed, axis=1)
        hit = crossed[np.arange(first.size), first]
        rows, col = np.flatnonzero(hit), first[hit]
        after = path[rows, col].astype(float)
        before = np.where(col > 0, path[rows, np.maximum(col - 1, 0)], previous[alive[rows]])
        with np.errstate(divide="ignore", invalid="ignore"):
            fraction = np.clip(np.nan_to_num((self.theta_fail - before) / (after - before), nan=1.0), 0.0, 1.0)
        rul[alive[hit]] = (done + col + fraction) * self.dt
        previous[alive] = path[:, -1]
        return alive[~hit]


class ParallelWarning(PHMWarning, RuntimeWarning):
    """Work meant for worker processes runs in the calling process instead (it cannot start any)."""


class ParallelRUL:
    """RUL predictions in worker processes, so they overlap with filtering on a multi-core machine.

    Predictions at different filter steps are independent given the particles, so they can run in
    parallel; each is keyed by its step (:meth:`RULPredictor.predict`), so the results do not depend
    on which worker computes them or when.  Use as a context manager.  The workers ignore SIGINT, so a
    Ctrl-C interrupts only the calling process, not every worker with a traceback of its own.

    Workers are forked where the platform can fork (they start at once and inherit the imports),
    else started the platform's default way.  A daemonic process (a ``multiprocessing.Pool`` or
    Dask worker) cannot have children: there every prediction runs in the calling process when
    submitted, with the same results, and a :class:`ParallelWarning` says so.

    >>> import numpy as np
    >>> from prognosis.degradation import LinearDegradation
    >>> with ParallelRUL(LinearDegradation(), dt=0.1, theta_fail=2.0, workers=2) as pool:
    ...     future = pool.submit(np.zeros((1, 3)), np.ones((1, 3, 1)), np.full((1, 3), 1 / 3), 0.0, key=0)
    ...     future.result().samples.tolist()
    [[2.0, 2.0, 2.0]]
    """

    def __init__(self, model, *, workers: int = 2, **predictor):
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        self._pool = self._local = None
        if multiprocessing.current_process().daemon:
            warnings.warn("ParallelRUL: this process is daemonic (a multiprocessing or Dask worker) and cannot start "
                          "worker processes; the RUL predictions run in it instead (same results, keyed by step)",
                          ParallelWarning, stacklevel=2)
            self._local = RULPredictor(model, **predictor)
            return
        fork = "fork" in multiprocessing.get_all_start_methods()
        context = multiprocessing.get_context("fork" if fork else None)
        # the workers are started here with Ctrl-C blocked, and unblock it only once they ignore it: a
        # worker still starting when the interrupt comes would otherwise print a traceback of its own
        blocked = _block_interrupts()
        try:
            self._pool = ProcessPoolExecutor(workers, mp_context=context, initializer=_start_worker,
                                             initargs=(model, predictor))
            self._pool.submit(int).result()  # a no-op: the pool starts its workers at the first task
        finally:
            _unblock_interrupts(blocked)

    def submit(self, theta, gamma, weights, gamma_std, *, key: int):
        """Start ``RULPredictor.predict(theta, gamma, weights, gamma_std, key=key)`` in a worker; returns its Future.

        ``key`` (e.g. the filter step) is required: it fixes the prediction's random numbers, so the result does
        not depend on the worker.  ``future.result()`` is the :class:`RULDistribution`.
        """
        if self._pool is not None:
            return self._pool.submit(_predict_in_worker, theta, gamma, weights, gamma_std, key)
        future = Future()
        try:
            future.set_result(self._local.predict(theta, gamma, weights, gamma_std, key=key))
        except Exception as error:  # delivered by future.result(), as a worker's would be
            future.set_exception(error)
        return future

    def __enter__(self) -> "ParallelRUL":
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.shutdown()


_WORKER_PREDICTOR = None


def _start_worker(model, predictor) -> None:
    global _WORKER_PREDICTOR
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    _unblock_interrupts(True)
    _WORKER_PREDICTOR = RULPredictor(model, **predictor)


def _block_interrupts() -> bool:
    """Block SIGINT in this thread (children started now inherit the mask); whether it was done."""
    if not hasattr(signal, "pthread_sigmask"):  # not on Windows: there workers are not in the console's group
        return False
    return signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})


def _unblock_interrupts(blocked: bool) -> None:
    """Undo :func:`_block_interrupts`: an interrupt that came meanwhile is delivered now."""
    if blocked and hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _predict_in_worker(theta, gamma, weights, gamma_std, key) -> RULDistribution:
    return _WORKER_PREDICTOR.predict(theta, gamma, weights, gamma_std, key=key)


def predict_rul(model, theta: np.ndarray, gamma: np.ndarray, weights: np.ndarray, *, dt: float,
                theta_fail: float, gamma_std, direction: str = "up", horizon: float = 200.0,
                rng: np.random.Generator, chunk: int = 512) -> RULDistribution:
    """One-off RUL prediction (Table IV); see :class:`RULPredictor` for repeated predictions.

    Examples
    --------
    >>> import numpy as np
    >>> from prognosis.degradation import LinearDegradation
    >>> rul = predict_rul(LinearDegradation(), np.array([[0.0]]), np.array([[[1.0]]]), np.array([[1.0]]), dt=0.1,
    ...                   theta_fail=2.0, gamma_std=0.0, rng=np.random.default_rng(0))
    >>> float(rul.samples[0, 0])
    2.0
    """
    predictor = RULPredictor(model, dt=dt, theta_fail=theta_fail, direction=direction, horizon=horizon,
                             seed=int(rng.integers(2**63)), chunk=chunk)
    return predictor.predict(theta, gamma, weights, gamma_std)


def _check_key(key: object) -> int:
    """A prediction's ``key`` as an int; a PrognosisError unless it is a whole number >= 0 (a spawn key)."""
    if isinstance(key, (bool, np.bool_)) or not isinstance(key, numbers.Integral) or key < 0:
        raise PrognosisError(f"key must be a whole number >= 0 (e.g. the filter step), got {key!r}")
    return int(key)


def _crossed(theta: np.ndarray, theta_fail: float, direction: str) -> np.ndarray:
    return theta >= theta_fail if direction == "up" else theta <= theta_fail
