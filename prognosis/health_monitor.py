"""Health monitoring of one prognostic candidate (Jha et al. (2016), Table V).

Detection with the candidate's I-ARR (:mod:`diagnosis`) runs until the first
alarm; the particle filter then starts from the candidate's uncertainty
interval (eq. 39), takes ``y = -r_n`` every ``dt`` seconds, and predicts the
RUL every ``rul_every`` filter steps.  :meth:`HealthMonitor.run` processes a
whole record; :meth:`HealthMonitor.update` takes a sample (or a micro-batch) at a
time, evaluates it online (:class:`diagnosis.StreamingEvaluation`) and processes
every filter step whose sample is at least half a derivative window old (the
Savitzky-Golay estimate is centred), so online results lag the newest sample by
that half window.  Results are deterministic for a seed.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from bondgraph.optional import pandas_for
from diagnosis.streaming import StreamChunk, StreamingEvaluation

from . import metrics, seeds
from .particle_filter import ParticleFilter, VarianceAdaptation, check_particles, check_positive
from .observation import observation_model
from .rul import ParallelRUL, RULPredictor
from .seeds import check_seed
from .errors import PrognosisError

__all__ = ["HealthMonitor", "MonitorResult", "check_failure_side", "filter_stride"]


def check_failure_side(candidate: str, theta_fail: float, nominal: float, direction: str) -> None:
    """Check that ``theta_fail`` lies on the ``direction`` side of ``nominal``; the error suggests the other direction.

    A parameter that wears downwards (a damper losing its oil, a spring softening) fails below its
    nominal value and needs ``direction="down"``; the default is ``"up"``, so the message says
    which direction the failure value calls for.

    Examples
    --------
    >>> check_failure_side("c_s", 3000.0, 1500.0, "up")
    >>> try:
    ...     check_failure_side("c_s", 750.0, 1500.0, "up")
    ... except PrognosisError as error:
    ...     print(error)
    failure value 750 of 'c_s' is on the wrong side for direction 'up': it lies below the nominal value 1500; \
give direction='down' for a parameter that fails below nominal
    """
    if direction not in ("up", "down"):
        raise PrognosisError(f"direction must be 'up' or 'down', got {direction!r}")
    if not np.isfinite(theta_fail):
        raise PrognosisError(f"failure value of {candidate!r} must be a finite number, got {theta_fail!r}")
    if theta_fail == nominal:
        raise PrognosisError(f"failure value {theta_fail:g} of {candidate!r} equals its nominal value: it must lie "
                             f"{'above' if direction == 'up' else 'below'} it for direction {direction!r}")
    side = "above" if theta_fail > nominal else "below"
    needed = "up" if side == "above" else "down"
    if direction != needed:
        raise PrognosisError(f"failure value {theta_fail:g} of {candidate!r} is on the wrong side for direction "
                             f"{direction!r}: it lies {side} the nominal value {nominal:g}; give "
                             f"direction={needed!r} for a parameter that fails {side} nominal")


@dataclass
class MonitorResult:
    """Time-indexed output of a health monitor (one asset)."""

    detection_time: float | None
    t: np.ndarray = field(default_factory=lambda: np.empty(0))
    theta: dict = field(default_factory=dict)
    gamma: dict = field(default_factory=dict)
    rul_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    rul: list = field(default_factory=list)
    degenerate_steps: list = field(default_factory=list)
    evaluation: object = None  # the detection Evaluation of the last processed record (residual, thresholds)

    @property
    def rul_mean(self) -> np.ndarray:
        """Weighted mean RUL (s) of the crossing particles per prediction time ``rul_t``; NaN where all are censored."""
        return np.array([p.mean[0] for p in self.rul])

    @property
    def rul_median(self) -> np.ndarray:
        """Weighted median RUL (s) per prediction time ``rul_t``, censored particles counted as ``+inf``."""
        return np.array([p.median[0] for p in self.rul])

    def rul_percentiles(self, q=(5, 95)) -> np.ndarray:
        """Weighted RUL percentiles (s), ``q`` in [0, 100], shape (len(rul), len(q)); censored particles as ``+inf``."""
        q = np.atleast_1d(np.asarray(q, float))
        return np.array([p.percentile(q)[0] for p in self.rul]).reshape(len(self.rul), q.size)

    def to_frame(self):
        """The estimates at every filter step as a pandas DataFrame (pandas imported on demand).

        Columns ``t`` (a column, default integer index), then for ``theta`` and ``gamma`` each:
        ``_mean``, ``_median``, ``_p5``, ``_p95`` (weighted over the particles) and ``_rmad``.
        No rows before detection.

        >>> import numpy as np
        >>> from prognosis.rul import RULDistribution
        >>> estimate = {"mean": np.array([1.0, 1.2]), "rmad": np.array([0.1, 0.05]),
        ...             "quantiles": np.array([[0.9, 1.0, 1.1], [1.1, 1.2, 1.3]])}
        >>> rul = [RULDistribution(np.array([[10.0, 20.0, np.inf]]), np.array([[0.5, 0.25, 0.25]]), 100.0)]
        >>> result = MonitorResult(0.5, t=np.array([0.5, 0.6]), theta=estimate, gamma=estimate,
        ...                        rul_t=np.array([0.5]), rul=rul)
        >>> frame = result.to_frame()
        >>> list(frame.columns)  # doctest: +NORMALIZE_WHITESPACE
        ['t', 'theta_mean', 'theta_median', 'theta_p5', 'theta_p95', 'theta_rmad',
         'gamma_mean', 'gamma_median', 'gamma_p5', 'gamma_p95', 'gamma_rmad']
        >>> frame["theta_p95"].tolist()
        [1.1, 1.3]
        """
        pd = pandas_for("to_frame")
        t = np.asarray(self.t, float)
        columns = {"t": t}
        missing = np.full(t.size, np.nan)  # no estimate before detection (t is empty then)
        for name, estimate in (("theta", self.theta), ("gamma", self.gamma)):
            quantiles = np.asarray(estimate.get("quantiles", np.full((t.size, 3), np.nan)), float).reshape(t.size, 3)
            for suffix, values in (("mean", estimate.get("mean", missing)), ("median", quantiles[:, 1]),
                                   ("p5", quantiles[:, 0]), ("p95", quantiles[:, 2]),
                                   ("rmad", estimate.get("rmad", missing))):
                columns[f"{name}_{suffix}"] = np.asarray(values, float)
        return pd.DataFrame(columns)

    def rul_frame(self):
        """The RUL predictions as a pandas DataFrame (pandas imported on demand).

        Columns ``rul_t`` (prediction time), ``mean`` (over the particles that fail within the
        horizon), ``median``, ``p5`` and ``p95`` (censored particles counted as ``+inf``, so
        these may be ``inf``), with the default integer index.

        >>> import numpy as np
        >>> from prognosis.rul import RULDistribution
        >>> rul = [RULDistribution(np.array([[10.0, 20.0, np.inf]]), np.array([[0.5, 0.25, 0.25]]), 100.0)]
        >>> frame = MonitorResult(0.5, rul_t=np.array([0.5]), rul=rul).rul_frame()
        >>> list(frame.columns)
        ['rul_t', 'mean', 'median', 'p5', 'p95']
        >>> float(frame["mean"][0]), float(frame["p95"][0])
        (13.333333333333334, inf)
        """
        pd = pandas_for("rul_frame")
        q = self.rul_percentiles((5, 50, 95)).reshape(len(self.rul), 3)
        return pd.DataFrame({"rul_t": np.asarray(self.rul_t, float), "mean": self.rul_mean.reshape(-1),
                             "median": q[:, 1], "p5": q[:, 0], "p95": q[:, 2]})

    def metrics(self, theta_true, gamma_true, eol: float, *, after: float | None = None,
                alpha: float = 0.1, beta: float = 0.5) -> dict:
        """The metrics of Jha et al. (2016), section 5, against the truth.

        ``theta_true``, ``gamma_true``: callables of t; ``eol``: true end of
        life (s).  RA, RMAD of the RUL and the alpha-lambda pass rate use the
        predictions made at or after ``after`` (Jha et al. (2016) use t = 52 s) and
        before the end of life (the true RUL must be positive).  The
        prognostic horizon is ``eol - t_j`` from the first prediction after
        which at least ``beta`` of the RUL mass stays within ``RUL* -+ alpha
        eol`` (fixed-width bounds, Saxena et al. 2010; the alpha-lambda cone
        shrinks to zero width at the end of life, where no prediction can
        stay inside it).
        """
        theta_star = np.asarray([theta_true(t) for t in self.t])
        gamma_star = np.asarray([gamma_true(t) for t in self.t])
        alive = self.rul_t < eol
        keep = alive & (self.rul_t >= (-np.inf if after is None else after))
        samples, weights = self._rul_arrays()
        rul_true = eol - self.rul_t
        _, passed = metrics.alpha_lambda(samples[keep], weights[keep], rul_true[keep], alpha, beta)
        horizon_ok = metrics.mass_within(samples[alive], weights[alive], rul_true[alive] - alpha * eol,
                                         rul_true[alive] + alpha * eol) >= beta
        rmad_rul = [metrics.rmad(s[np.isfinite(s)], w[np.isfinite(s)]) if np.isfinite(s).any() else np.nan
                    for s, w in zip(samples[keep], weights[keep])]  # spread of the RUL over crossed particles
        ra = metrics.relative_accuracy(rul_true[keep], self.rul_mean[keep]) if keep.any() else np.array([np.nan])
        return {
            "rmse_theta": float(metrics.relative_rmse(self.theta["mean"], theta_star)),
            "rmse_gamma": float(metrics.relative_rmse(self.gamma["mean"], gamma_star)),
            "rmad_gamma": float(np.nanmean(self.gamma["rmad"])),
            "ra": float(metrics.mean_relative_accuracy(ra)),
            "rmad_rul": float(np.nanmean(rmad_rul)) if rmad_rul else float("nan"),
            "alpha_lambda_pass_rate": float(np.mean(passed)) if np.size(passed) else float("nan"),
            "prognostic_horizon_s": (_number(metrics.prognostic_horizon(self.rul_t[alive], horizon_ok, eol))
                                     if alive.any() else None),
        }

    def _rul_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """RUL samples and weights of the single asset, (K, N) each.

        A mixture over hypotheses may hold more samples at one prediction than at another: the
        shorter rows are padded with censored samples of weight 0.
        """
        k = len(self.rul)
        n = max((np.size(p.samples[0]) for p in self.rul), default=0)
        samples, weights = np.full((k, n), np.inf), np.zeros((k, n))
        for row, p in enumerate(self.rul):
            size = np.size(p.samples[0])
            samples[row, :size], weights[row, :size] = p.samples[0], p.weights[0]
        return samples, weights


def filter_stride(t: np.ndarray, dt: float) -> int:
    """Record samples per filter step ``dt``; raises PrognosisError unless ``dt`` is a multiple of the record's step.

    >>> filter_stride(np.arange(0.0, 1.0, 0.01), 0.1)
    10
    """
    step = float(np.median(np.diff(t)))
    stride = int(round(dt / step))
    if stride < 1 or abs(stride * step - dt) > 1e-6 * dt:
        raise PrognosisError(f"the filter step dt = {dt} s is not a multiple of the record's step {step} s")
    return stride


def _tail(chunk: StreamChunk, count: int) -> StreamChunk:
    """The last ``count`` samples of a chunk of a stream."""
    keep = slice(max(0, len(chunk) - count), None)
    return StreamChunk(chunk.name, chunk.t[keep], chunk.residual[keep], chunk.lower[keep], chunk.upper[keep],
                       chunk.bglft[keep], chunk.margin, chunk.persistence, chunk.violation[keep], chunk.alarm[keep],
                       [p[keep] for p in chunk.points], chunk.start + keep.indices(len(chunk))[0])


def _number(value) -> float | None:
    return None if value is None or not np.isfinite(value) else float(value)


class HealthMonitor:
    """Detection, then estimation of theta and gamma, then RUL, for one candidate.

    Parameters
    ----------
    arr : ARR sensitive to ``candidate``
    candidate : str
    model : degradation model
    theta_fail : float
    direction : {"up", "down"}
    dt : float
        Filter step (s); the record's sampling step must divide it.
    n_particles, noise_std, inflation, gamma_std, gamma0, resampling, resample_below
        Particle filter settings (:class:`~prognosis.particle_filter.ParticleFilter`).
    gamma_bounds : (lo, hi), optional
        Draw the initial gamma uniformly over this interval instead of ``gamma0``.
    start : {"residual", "uncertainty_box"}
        Initial theta interval.  ``"uncertainty_box"``: the candidate's uncertainty interval, as in
        Jha et al. (2016), eq. 39.
        ``"residual"``: that interval widened to contain the theta that explains the residual on
        the ``persistence`` samples that raised the alarm (inverting the observation equation);
        by the time a degradation is detected, theta has usually left the uncertainty interval.
    theta_bounds : (lo, hi), optional
        Replaces the candidate's uncertainty interval (needed when the ARR gives none).
    adaptation : VarianceAdaptation or KernelSmoothing, optional
        The filter works on its own copy, so one object can configure several monitors.
    prediction_walk : float
        Scale of the random-walk standard deviation of gamma in the RUL
        prediction: 1 propagates gamma with the current adapted variance as in
        Table IV, 0 holds each particle's gamma at its estimate (the walk is an
        estimation device, not a model of the future).
    rul_every : int
        Predict the RUL every this many filter steps.
    horizon : float
        RUL horizon cap (s).
    detection : mapping
        Options of :func:`diagnosis.evaluate` (``margin``, ``persistence``,
        ``antiderivatives``, ``method``...).
    seed : int or numpy.random.SeedSequence
        The filter and the RUL predictor draw from streams of their own spawned from it
        (:mod:`prognosis.seeds`), so no two seeds share a stream.

    Notes
    -----
    A monitor pickles with the standard library (to a pool or Dask worker, or to disk): the
    lambdified observation and residual functions and the RUL noise bank (16 MB for 500 particles
    over 2000 steps) are left out and rebuilt on first use, so an unpickled monitor gives the same
    results bit for bit.  A monitor pickled after :meth:`run` also leaves out the result that run
    returned (pickle the :class:`MonitorResult` itself to ship it), so it stays small: 18 kB on the
    torsion bar's 100 s record with 500 particles, against 18 MB with the bank and the result.  A
    monitor fed by :meth:`update` pickles whole, its history included, and goes on where it stood.
    """

    def __init__(self, arr, candidate: str, model, *, theta_fail: float, direction: str = "up", dt: float = 0.1,
                 n_particles: int = 500, noise_std: float = 0.01, inflation: float = 4.0, gamma_std=0.02,
                 gamma0=0.0, gamma_bounds=None, start: str = "residual", theta_bounds=None,
                 adaptation: VarianceAdaptation | None = None, resampling: str = "systematic",
                 resample_below: float = 1.0, prediction_walk: float = 1.0, rul_every: int = 1, horizon: float = 200.0,
                 detection: Mapping | None = None, seed: int | np.random.SeedSequence = 0):
        if isinstance(noise_std, Mapping):
            raise PrognosisError(f"noise_std: HealthMonitor watches one ARR; give the standard deviation of its "
                                 f"residual as one number, got a {type(noise_std).__name__}")
        noise_std = check_positive(noise_std, "noise_std")
        n_particles = check_particles(n_particles)
        dt, horizon = check_positive(dt, "dt"), check_positive(horizon, "horizon")
        self.arr, self.candidate, self.model = arr, candidate, model
        self.observation = observation_model(arr, candidate)
        self.theta_fail, self.direction, self.dt = theta_fail, direction, dt
        nominal = self.observation.nominal
        lo, hi = arr.uncertainties.get(candidate, (0.0, 0.0))
        self.theta_bounds = (nominal * (1 + lo), nominal * (1 + hi)) if theta_bounds is None else tuple(theta_bounds)
        if start not in ("residual", "uncertainty_box"):
            raise PrognosisError(f"start must be 'residual' or 'uncertainty_box', got {start!r}")
        self.start, self.gamma_bounds = start, gamma_bounds
        check_failure_side(candidate, theta_fail, nominal, direction)
        seed = check_seed(seed)
        self.filter = ParticleFilter(model, self.observation, n_particles=n_particles, dt=dt, noise_std=noise_std,
                                     inflation=inflation, gamma_std=gamma_std, adaptation=adaptation,
                                     resampling=resampling, resample_below=resample_below,
                                     seed=seeds.spawn(seed, seeds.FILTER))
        if prediction_walk < 0:
            raise PrognosisError(f"prediction_walk must be >= 0, got {prediction_walk}")
        if isinstance(rul_every, bool) or int(rul_every) != rul_every or rul_every < 1:
            raise PrognosisError(f"rul_every must be a positive whole number of filter steps, got {rul_every!r}")
        self.gamma0, self.rul_every, self.horizon = gamma0, rul_every, horizon
        self.prediction_walk = float(prediction_walk)
        self.detection = dict(detection or {})
        self.predictor = RULPredictor(model, dt=dt, theta_fail=theta_fail, direction=direction, horizon=horizon,
                                      seed=seeds.spawn(seed, seeds.RUL))
        self._reset()

    def _reset(self) -> None:
        self.result = MonitorResult(None)
        self._rows: list = []
        self._rul_t: list = []
        self._next_index = None
        self._steps = 0
        self._stream = None  # the online evaluation of update()
        self._recent = None  # its last final samples: the alarm's window, and the step
        self._pool = None
        self._finished = False  # a whole record was run: its result is output, not state to go on from

    def __getstate__(self) -> dict:
        """The state to pickle: the ARR and observation drop their lambdified functions, the predictor
        its noise bank (each rebuilt on first use); after :meth:`run`, the result it returned is left
        out too (the record-sized evaluation and every RUL distribution: output, not state)."""
        state = {**self.__dict__, "_pool": None}
        if self._finished:
            state.update(result=MonitorResult(None), _rows=[], _rul_t=[], _finished=False)
        return state

    # -- whole record -------------------------------------------------------
    def run(self, record, *, workers: int = 1,
            progress: Callable[[int, int, float], None] | None = None) -> MonitorResult:
        """Process a whole record (mapping or DataFrame with ``t`` and the ARR's signals).

        ``workers > 1`` computes the RUL predictions in that many processes while the filter goes
        on; the results are the same as with one process (predictions are keyed by filter step).

        ``progress(done, total, t)`` is called with the filter steps done, the steps the record
        holds from the alarm on and the time of the last step done, after every 1 % of the steps
        and after the last one (never without an alarm).  An exception it raises, such as
        ``KeyboardInterrupt``, stops the run and propagates; pending predictions are cancelled.

        The result stays available as :attr:`result` in this process; a copy of the monitor
        pickled after the run travels without it (see the class notes).
        """
        self._reset()
        if workers > 1:
            with ParallelRUL(self.model, workers=workers, dt=self.dt, theta_fail=self.theta_fail,
                             direction=self.direction, horizon=self.horizon, seed=self.predictor.seed) as pool:
                self._pool = pool
                try:
                    self._advance(record, last=None, progress=progress)
                    self.result.rul = [f.result() for f in self.result.rul]
                except BaseException:
                    # the pool's shutdown waits for queued predictions: drop them so an interrupt is prompt
                    for future in self.result.rul:
                        future.cancel()
                    raise
                finally:
                    self._pool = None
        else:
            self._advance(record, last=None, progress=progress)
        result = self._finish()
        self._finished = True
        return result

    # -- one sample at a time ------------------------------------------------
    def update(self, sample: Mapping) -> MonitorResult:
        """Append samples and process what has become final.

        ``sample``: ``t`` and the signals, numbers for one sample or arrays for a micro-batch.  The
        ARR is evaluated online (:class:`diagnosis.StreamingEvaluation`): every sample is evaluated
        once, from a ring buffer of the derivative window and running integrals, so a sample costs
        the same after 10^6 samples as after 10^3.  The result grows by one row per filter step and
        one RUL distribution per prediction; for streams without end,
        :meth:`prognosis.fleet.FleetMonitor.update` hands its rows over instead of keeping them.
        """
        self._finished = False
        columns = {str(k): np.atleast_1d(np.asarray(v, float)) for k, v in sample.items()}
        if "t" not in columns:
            raise PrognosisError(f"update: the sample has no 't' (columns: {', '.join(columns)})")
        if self._stream is None:
            self._stream = StreamingEvaluation(self.arr, **self.detection)
        chunk = self._stream.push(columns.pop("t"), columns)
        if len(chunk):
            self._consume(chunk)
        return self._finish()

    def _consume(self, chunk) -> None:
        """Detection, then the filter steps due, on the samples of a stream that became final."""
        self.result.evaluation = chunk
        joined = chunk if self._recent is None else StreamChunk.concatenate([self._recent, chunk])
        offset = len(joined) - len(chunk)
        if self.result.detection_time is None:
            alarms = np.flatnonzero(chunk.alarm)
            if alarms.size:
                k = offset + int(alarms[0])
                self.result.detection_time = float(joined.t[k])
                self.filter.initialize(self._start_bounds(joined, k), self.gamma0, gamma_bounds=self.gamma_bounds)
                self._next_index = chunk.start + int(alarms[0])
        if self._next_index is not None and len(joined) >= 2:
            stride = self._stride(joined.t[:2])
            while self._next_index < chunk.start + len(chunk):
                i = self._next_index - joined.start
                self._filter_step(joined.t[i], -joined.residual[i], [p[i:i + 1] for p in joined.points])
                self._next_index += stride
        self._recent = _tail(joined, max(chunk.persistence, 2))

    # -- shared ----------------------------------------------------------------
    def _advance(self, record, last: int | None, progress: Callable | None = None) -> None:
        evaluation = self.arr.evaluate(record, **self.detection)
        self.result.evaluation = evaluation
        t = evaluation.t
        last = t.size - 1 if last is None else last
        if self.result.detection_time is None:
            alarms = np.flatnonzero(evaluation.alarm[: last + 1])
            if not alarms.size:
                return
            start = alarms[0]
            self.result.detection_time = float(t[start])
            self.filter.initialize(self._start_bounds(evaluation, start), self.gamma0,
                                   gamma_bounds=self.gamma_bounds)
            self._next_index = start
        stride = self._stride(t)
        points = evaluation.points  # the observation equation uses the same signals, derivatives, integrals
        first = self._next_index
        total = len(range(first, last + 1, stride))
        every = -(-total // 100)  # a report per 1 % of the steps (at most 100): negligible beside a step
        while self._next_index is not None and self._next_index <= last:
            k = self._next_index
            self._filter_step(t[k], -evaluation.residual[k], [p[k:k + 1] for p in points])
            self._next_index = k + stride
            done = int(k - first) // stride + 1
            if progress is not None and (done % every == 0 or done == total):
                progress(done, total, float(t[k]))

    def _start_bounds(self, evaluation, k: int) -> tuple[float, float]:
        """Initial theta interval at detection (see ``start``)."""
        lo, hi = self.theta_bounds
        if self.start == "uncertainty_box":
            return lo, hi
        window = slice(max(0, k - evaluation.persistence + 1), k + 1)
        bracket = (min(lo, self.theta_fail), max(hi, self.theta_fail))
        explained = self.observation.invert(-evaluation.residual[window], [p[window] for p in evaluation.points],
                                            bracket)
        explained = np.clip(explained[np.isfinite(explained)], *bracket)
        if not explained.size:
            return lo, hi
        return min(lo, float(explained.min())), max(hi, float(explained.max()))

    def _stride(self, t: np.ndarray) -> int:
        return filter_stride(t, self.dt)

    def _filter_step(self, time: float, y: float, points: list) -> None:
        diagnostics = self.filter.step(np.array([y]), points)
        if diagnostics.degenerate.any():
            self.result.degenerate_steps.append(time)
        estimate = self.filter.estimate()
        self._rows.append((time, estimate))
        if self._steps % self.rul_every == 0:
            arguments = (self.filter.theta, self.filter.gamma, self.filter.weights,
                         self.prediction_walk * np.sqrt(self.filter.variance))
            if self._pool is not None:
                prediction = self._pool.submit(*arguments, key=self._steps)
            else:
                prediction = self.predictor.predict(*arguments, key=self._steps)
            self.result.rul.append(prediction)
            self._rul_t.append(time)
        self._steps += 1

    def _finish(self) -> MonitorResult:
        result = self.result
        result.t = np.array([row[0] for row in self._rows])
        if self._rows:
            est = [row[1] for row in self._rows]
            result.theta = {"mean": np.array([e["theta_mean"][0] for e in est]),
                            "rmad": np.array([e["theta_rmad"][0] for e in est]),
                            "quantiles": np.array([e["theta_quantiles"][0] for e in est])}
            result.gamma = {"mean": np.array([e["gamma_mean"][0, 0] for e in est]),
                            "rmad": np.array([e["gamma_rmad"][0, 0] for e in est]),
                            "quantiles": np.array([e["gamma_quantiles"][0, 0] for e in est])}
        result.rul_t = np.array(self._rul_t)
        return result
