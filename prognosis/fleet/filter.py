"""The fleet's particle filter: rows of (asset, hypothesis), each row stepping on its own stream.

One array per quantity holds every row: ``theta`` (R, N), ``gamma`` (R, G, N) (particles on the
last, contiguous axis, so every reduction is a per-row pairwise sum whatever the number of rows),
the kernel-smoothing mean and jitter variance (R, G), the log evidence (R,).  A step moves a subset
of rows (the assets with a measurement at that tick), each at its own filter step, so assets start
at their own alarm and run at their own pace.

The step is the SIR filter of :class:`~prognosis.particle_filter.ParticleFilter` with the settings a
fleet uses: kernel smoothing of the rate (:class:`~prognosis.particle_filter.KernelSmoothing`) and
systematic resampling at every step (so the weights are equal between steps and the estimates are
plain means), by :func:`~prognosis.resampling.systematic_indices`, the one systematic resampler of
the package, fed with each row's own uniform.

Every random number of a row at a step comes from :class:`~prognosis.random_streams.AssetStreams` keyed by
(seed, asset, step) with the hypothesis as lane, and no operation mixes rows (no BLAS product, no
reduction across rows), so a row's numbers are bitwise the same in any batch.
"""

from __future__ import annotations

import functools
import numpy as np
from scipy.special import ndtr

from ..degradation import ExponentialDegradation, LinearDegradation
from ..particle_filter import COLLAPSE_BELOW, StepDiagnostics
from ..random_streams import MOVES, STARTS
from ..resampling import systematic_indices

__all__ = ["QUANTILES", "ROW_STATE", "FleetFilter", "law_step"]

QUANTILES = (0.05, 0.5, 0.95)
ROW_STATE = ("theta", "gamma", "hypothesis", "mean", "variance", "sigma_v", "log_evidence", "steps", "rejected",
             "away")  # what a row is: a checkpoint saves these


class _RowsStep(StepDiagnostics):
    """:class:`~prognosis.particle_filter.StepDiagnostics` of a fleet step, computed when asked: a stream
    reports every few steps, and the ESS's array operations every step would be a tenth of its cost."""

    def __init__(self, finite: np.ndarray, degenerate: np.ndarray, weights: np.ndarray, total: np.ndarray):
        self.degenerate, self.innovation = degenerate, None
        self._finite, self._weights, self._total, self._ess = finite, weights, total, None

    @property
    def updated(self) -> np.ndarray:
        return self._finite.any(axis=1)

    @property
    def resampled(self) -> np.ndarray:
        return np.ones(self._total.size, bool)  # every row, every step

    @property
    def ess(self) -> np.ndarray:
        if self._ess is None:
            self._ess = self._total * self._total / (self._weights * self._weights).sum(axis=1)
        return self._ess

    @property
    def collapsed(self) -> np.ndarray:
        return self.ess < COLLAPSE_BELOW * self._weights.shape[1]


class FleetFilter:
    """Particle arrays of many rows, stepped together.

    Parameters
    ----------
    laws : sequence of degradation models, one per hypothesis
    observations : sequence of sequences
        ``observations[h][m]``: the observation model of hypothesis ``h`` for ARR ``m`` (a callable
        ``(theta (R, N), points) -> (R, N)``), or None where ARR ``m`` is blind to its candidate.
    noise_std : array (M,)
        Residual noise of each ARR.
    n_particles, dt, inflation, discount, floor
        As :class:`~prognosis.particle_filter.ParticleFilter` and
        :class:`~prognosis.particle_filter.KernelSmoothing`.
    streams : AssetStreams

    Examples
    --------
    >>> from prognosis.random_streams import AssetStreams
    >>> pf = FleetFilter([LinearDegradation()], [[lambda theta, points: theta]], noise_std=[0.05],
    ...                  n_particles=200, dt=1.0, inflation=1.0, streams=AssetStreams(0))
    >>> rows = pf.add(["a", "b"], hypothesis=[0, 0], lo=[0.0, 0.0], hi=[2.0, 2.0],
    ...               rates=np.full((2, 1, 200), 0.1), process_noise=[0.0, 0.0])
    >>> for k in range(1, 21):
    ...     _ = pf.step(np.full((2, 1), 0.1 * k), [[]], rows=rows)
    >>> np.round(pf.theta_mean(rows), 1).tolist()
    [2.0, 2.0]
    """

    def __init__(self, laws, observations, *, noise_std, n_particles: int, dt: float, inflation: float = 4.0,
                 discount: float = 0.98, floor: float = 1e-3, streams):
        self.laws, self.observations = tuple(laws), [list(o) for o in observations]
        self.noise_std = np.asarray(noise_std, float)
        variance = inflation * np.square(self.noise_std)
        self._scale = -0.5 / variance  # log-likelihood per squared gap, per ARR
        self._constant = -0.5 * np.log(2 * np.pi * variance)  # the Gaussian's normalizing constant, in the evidence
        self._constant_sum = float(np.sum(self._constant))
        self.n, self.dt, self.inflation = int(n_particles), float(dt), float(inflation)
        self.shrinkage = (3 * discount - 1) / (2 * discount)
        self.floor, self.streams = float(floor), streams
        self.g = self.laws[0].n_gamma
        self.capacity = 0
        self.asset: list = []
        self.free: list[int] = []
        self.theta = np.empty((0, self.n))
        self.gamma = np.empty((0, self.g, self.n))
        self.hypothesis = np.empty(0, int)
        self.mean = np.empty((0, self.g))
        self.variance = np.empty((0, self.g))
        self.sigma_v = np.empty(0)
        self.log_evidence = np.empty(0)
        self.steps = np.empty(0, int)
        self.rejected = np.empty(0, bool)  # the hypothesis left its domain or drifts away from failure
        self.away = np.empty(0, int)  # consecutive reports drifting away from failure

    # -- rows --------------------------------------------------------------------------------
    def add(self, assets, *, hypothesis, lo, hi, rates, process_noise) -> np.ndarray:
        """New rows at their detection: theta ~ U(lo, hi) from each asset's stream, gamma the given particles.

        ``rates`` (rows, G, N): the initial rate particles.  Returns the rows' indices.
        """
        count = len(assets)
        rows = self.allocate(count)
        hypothesis = np.asarray(hypothesis, int)
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        u = np.empty((count, self.n))
        for i, (asset, h) in enumerate(zip(assets, hypothesis)):
            self.streams.generator(asset, 0, STARTS, lane=int(h)).random(out=u[i])
        for i, row in enumerate(rows):
            self.asset[row] = assets[i]
        self.theta[rows] = lo[:, None] + (hi - lo)[:, None] * u
        self.gamma[rows] = np.asarray(rates, float)
        self.hypothesis[rows] = hypothesis
        self.mean[rows] = np.sum(self.gamma[rows], axis=-1) / self.n
        self.variance[rows] = 0.0  # kernel smoothing: the first move only shrinks toward the mean
        self.sigma_v[rows] = np.asarray(process_noise, float)
        self.log_evidence[rows] = 0.0
        self.steps[rows] = 0
        self.rejected[rows], self.away[rows] = False, 0
        return rows

    def remove(self, rows) -> None:
        """Free rows (their asset is done); their slots are reused."""
        for row in np.atleast_1d(rows):
            self.asset[int(row)] = None
            self.free.append(int(row))

    def allocate(self, count: int) -> np.ndarray:
        """``count`` free rows, the lowest first; the arrays double when they are full."""
        if len(self.free) < count:
            self._grow(self.capacity + count - len(self.free))
        return np.array(sorted(self.free.pop() for _ in range(count)), int)

    def _grow(self, size: int) -> None:
        size = max(size, 2 * self.capacity)
        extra = size - self.capacity
        self.asset += [None] * extra
        self.theta = np.concatenate([self.theta, np.zeros((extra, self.n))])
        self.gamma = np.concatenate([self.gamma, np.zeros((extra, self.g, self.n))])
        self.hypothesis = np.concatenate([self.hypothesis, np.zeros(extra, int)])
        self.mean = np.concatenate([self.mean, np.zeros((extra, self.g))])
        self.variance = np.concatenate([self.variance, np.zeros((extra, self.g))])
        self.sigma_v = np.concatenate([self.sigma_v, np.zeros(extra)])
        self.log_evidence = np.concatenate([self.log_evidence, np.zeros(extra)])
        self.steps = np.concatenate([self.steps, np.zeros(extra, int)])
        self.rejected = np.concatenate([self.rejected, np.zeros(extra, bool)])
        self.away = np.concatenate([self.away, np.zeros(extra, int)])
        self.free = sorted(self.free + list(range(self.capacity, size)), reverse=True)  # pop() gives the lowest
        self.capacity = size

    # -- one step ----------------------------------------------------------------------------
    def step(self, y: np.ndarray, points=(), rows: np.ndarray | None = None) -> StepDiagnostics:
        """Predict, weigh by ``y`` (rows, M), resample and smooth the rows ``rows`` (default: every row in use).

        The step of every particle filter of the package (:meth:`~prognosis.particle_filter.ParticleFilter.step`),
        a row for an asset: ``points[m]``, the point values of ARR ``m``, is a list of arrays (rows,).
        A NaN in ``y`` leaves that ARR out of the row's likelihood; a row with no finite ``y`` is only
        moved.  Every row is resampled at every step.
        """
        rows = np.flatnonzero([a is not None for a in self.asset]) if rows is None else np.asarray(rows, int)
        at = _span(rows)
        n, y = self.n, np.asarray(y, float)
        draws = self._draws(rows, 1 + self.g)
        theta, gamma = self._predict(at, draws)
        log_likelihood, finite = self._log_likelihood(at, theta, y, points)
        top = log_likelihood.max(axis=1, keepdims=True)  # methods: a stream steps one row at a time
        # a finite top (the common case) puts the total in [1, N]: no row can be degenerate
        tracking = bool(np.isfinite(top).all())
        if not tracking:
            top[~np.isfinite(top)] = 0.0
        log_likelihood -= top
        weights = np.exp(log_likelihood, out=log_likelihood)
        total = weights.sum(axis=1)
        if tracking:
            degenerate = np.zeros(total.size, bool)
        else:
            degenerate = ~((total > 0) & (total < np.inf))  # NaN too
            # every weight vanished: start again from equal weights, and say so
            weights[degenerate] = 1.0
            total[degenerate] = n
        evidence = top[:, 0] + np.log(total / n)
        if finite.all():  # the common case: every ARR measured
            evidence += self._constant_sum
            measured = None if tracking else ~degenerate
        else:
            evidence += np.sum(np.where(finite, self._constant, 0.0), axis=1)
            measured = finite.any(axis=1) & ~degenerate
        self.log_evidence[at] += evidence if measured is None or measured.all() else np.where(measured, evidence, 0.0)
        flat = systematic_indices(weights, total, ndtr(draws[:, -1].astype(float)), flat=True)
        self.theta[at] = theta.reshape(-1)[flat].reshape(theta.shape)
        if self.g == 1:
            gamma = gamma.reshape(-1)[flat].reshape(gamma.shape)
        else:
            gamma = np.stack([gamma[:, g].reshape(-1)[flat].reshape(theta.shape) for g in range(self.g)], axis=1)
        self._smooth(at, gamma)
        self.gamma[at] = gamma
        self.steps[at] += 1
        return _RowsStep(finite, degenerate, weights, total)

    def _draws(self, rows: np.ndarray, blocks: int) -> np.ndarray:
        """(rows, blocks N + 1) normals: theta's process noise, gamma's jitter, the resampling's uniform.

        Single precision: twice as fast to draw, and a noise needs no more than 24 bits.
        """
        out = np.empty((rows.size, blocks * self.n + 1), np.float32)
        for i, row in enumerate(rows):
            self.streams.generator(self.asset[row], self.steps[row] + 1, MOVES,
                                   lane=int(self.hypothesis[row])).standard_normal(dtype=np.float32, out=out[i])
        return out

    def _predict(self, rows, draws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The moved theta and the smoothed gamma of ``rows`` (indices or a slice: views, not written)."""
        n, g = self.n, self.g
        theta, gamma = self.theta[rows], self.gamma[rows]
        if len(self.laws) == 1:
            moved = law_step(self.laws[0], theta, gamma, self.dt)
        else:
            moved = np.empty_like(theta)
            hypotheses = self.hypothesis[rows]
            for h, law in enumerate(self.laws):
                mine = hypotheses == h
                if mine.any():
                    moved[mine] = law_step(law, theta[mine], gamma[mine], self.dt)
        moved += draws[:, :n] * self.sigma_v[rows][:, None]
        a = self.shrinkage
        smoothed = draws[:, n:(1 + g) * n].reshape(len(draws), g, n) * np.sqrt(self.variance[rows])[:, :, None]
        smoothed += (1 - a) * self.mean[rows][:, :, None]
        smoothed += gamma * a
        return moved, smoothed

    def _log_likelihood(self, rows, theta, y, points) -> tuple[np.ndarray, np.ndarray]:
        """Gaussian log-likelihood (rows, N) without its constant, and which measurements were finite."""
        finite = np.isfinite(y)
        complete = bool(finite.all())  # the common case: no column to check for gaps
        hypotheses = self.hypothesis[rows]
        single = len(self.observations) == 1
        total = None
        for m in range(y.shape[1]):
            if not complete and not finite[:, m].any():
                continue
            if single and self.observations[0][m] is not None:  # the common case: one hypothesis
                predicted = self.observations[0][m](theta, points[m])
            else:
                predicted = np.zeros_like(theta)
                for h, models in enumerate(self.observations):
                    mine = hypotheses == h
                    if models[m] is not None and mine.any():
                        predicted[mine] = models[m](theta[mine], [p[mine] for p in points[m]])
            gap = (y[:, m] if complete else np.where(finite[:, m], y[:, m], 0.0))[:, None] - predicted
            gap *= gap
            gap *= self._scale[m]
            if not complete and not finite[:, m].all():
                gap[~finite[:, m]] = 0.0
            total = gap if total is None else total + gap
        return (np.zeros_like(theta) if total is None else total), finite

    def _smooth(self, rows, gamma: np.ndarray) -> None:
        """Kernel smoothing's mean and jitter variance for the next move (equal weights after resampling)."""
        mean = gamma.sum(axis=-1) / self.n
        spread = np.square(gamma - mean[:, :, None]).sum(axis=-1) / self.n
        self.mean[rows] = mean
        self.variance[rows] = np.maximum((1 - self.shrinkage**2) * spread, np.square(self.floor * mean))

    # -- estimates ---------------------------------------------------------------------------
    def theta_mean(self, rows) -> np.ndarray:
        return np.sum(self.theta[rows], axis=1) / self.n

    def gamma_mean(self, rows) -> np.ndarray:
        """Mean of the first progression parameter per row."""
        return self.mean[rows, 0]

    def quantiles(self, rows) -> tuple[np.ndarray, np.ndarray]:
        """5, 50 and 95 % of theta and of the first gamma per row, (rows, 3) each (equal weights)."""
        positions = _ranks(self.n)
        theta = np.partition(self.theta[rows], positions, axis=1)[:, positions]
        gamma = np.partition(self.gamma[rows, 0], positions, axis=1)[:, positions]
        return theta, gamma


def _span(rows: np.ndarray) -> "slice | np.ndarray":
    """``rows`` as a slice when they are consecutive and ascending (a stream's asset, a fresh block): a slice
    reads views and writes in place, where an index array copies on every read."""
    first = int(rows[0]) if rows.size else 0
    if rows.size == 1 or (rows.size and int(rows[-1]) - first + 1 == rows.size and (np.diff(rows) > 0).all()):
        return slice(first, first + rows.size)
    return rows


def law_step(law, theta: np.ndarray, gamma: np.ndarray, dt: float) -> np.ndarray:
    """``theta_k`` from ``theta_{k-1}`` (R, N) and ``gamma`` (R, G, N) by the law's deterministic step."""
    if isinstance(law, LinearDegradation):
        return theta + gamma[:, 0] * dt
    if isinstance(law, ExponentialDegradation):
        return theta * np.exp(gamma[:, 0] * dt)
    # a copy: a law may hand back its input, and the filter's rows are views that the step must not write
    return np.array(law.step(theta, np.moveaxis(gamma, 1, -1), dt), float)


@functools.lru_cache(maxsize=8)
def _ranks(n: int) -> list[int]:
    """The ranks of the :data:`QUANTILES` among ``n`` equally weighted particles."""
    return [int(np.ceil(q * n - 1e-9)) - 1 for q in QUANTILES]
