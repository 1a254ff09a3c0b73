"""Streaming evaluation of an ARR: samples in micro-batches, constant cost per sample, bounded memory.

:func:`diagnosis.detection.evaluate` takes a whole record.  A monitor that receives its data as it
comes would have to keep every sample and evaluate the record again at each step, at a cost growing
with the record.  :class:`StreamingEvaluation` takes the samples of one asset a batch at a time
(:meth:`~StreamingEvaluation.push`) and keeps only what the next samples need:

* the last samples a derivative estimate reaches: a Savitzky-Golay window (``window`` samples), or
  ``2 * order + 2`` samples for central differences;
* a running trapezoid sum per integral of the ARR, and the first value of each antiderivative column
  (an integral read from an encoder angle is ``X(t) - X(t_0)``);
* the current run of consecutive violations, for persistence.

A sample is *final* once the samples its derivative estimates need have arrived: a Savitzky-Golay
estimate is centred, so the newest ``window // 2`` samples wait for the next batch;
:meth:`~StreamingEvaluation.flush` finalizes them with the one-sided fit a record's end gets when the
stream ends.  Every final sample has the values :func:`~diagnosis.detection.evaluate` gives on the
whole record with the same options, however the record is split into batches: the point values,
the residual, the thresholds, the violations and the alarms (persistence counts across batches),
gaps (NaN) included.  With ``dt`` equal to the record's median step (``Record.dt``) the Savitzky-Golay
values are bitwise those of the batch estimator; by default the stream's first step is used, and the
values agree to rounding.

Sampling
--------
``t`` must increase strictly, within a batch and from one batch to the next.  With
``method="savgol"`` (and an ARR that has derivatives) every step must be within a relative
``UNIFORM_RTOL`` (1e-6) of the stream's step, the first one (or ``dt``); the batch estimator
compares steps with the record's median step instead.  ``method="central"`` takes any steps.

Example
-------
>>> import numpy as np
>>> from bondgraph import simulate
>>> from bondgraph.library import rlc_circuit
>>> from diagnosis import derive_arrs, evaluate
>>> bg = rlc_circuit()
>>> arr = derive_arrs(bg)[0]
>>> record = simulate(bg, (0.0, 1.0), {"V": lambda t: np.sin(20 * t)}, t_eval=np.linspace(0.0, 1.0, 1001)).record()
>>> stream = StreamingEvaluation(arr, margin=1e-3)
>>> first = stream.push(record["t"][:100], {s: record[s][:100] for s in ("V", "i", "v_C")})
>>> first.t.size, first.start, stream.samples, stream.final   # the newest 5 samples wait for their window
(95, 0, 100, 95)
>>> rest = stream.push(record["t"][100:], {s: record[s][100:] for s in ("V", "i", "v_C")})
>>> whole = StreamChunk.concatenate([first, rest, stream.flush()])
>>> batch = evaluate(arr, record, margin=1e-3)
>>> bool(np.allclose(whole.residual, batch.residual, rtol=1e-12, atol=1e-15))
True

A stream does not mask the samples around steps of the inputs as :func:`~diagnosis.detection.evaluate`
does by default (:mod:`diagnosis.steps` needs the whole record to tell a step from a fast change); to
compare a stream with a batch evaluation, evaluate with ``steps=False``.
"""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp
from numpy.typing import ArrayLike
from scipy.ndimage import convolve1d
from scipy.signal import savgol_coeffs, savgol_filter

from .detection import Evaluation, check_closed_form, check_options, fitting_order, judge
from .residuals import antiderivative_integral, trusted_edge
from .derivatives import central_derivative, check_savgol_settings, default_window
from .records import MAX_MAGNITUDE, RecordError, RecordWarning, TIME, UNIFORM_RTOL, as_record

__all__ = ["BANDS", "CheckedBatch", "StreamChunk", "StreamingEvaluation"]

#: what :meth:`StreamingEvaluation.push` can compute for the samples that become final
BANDS = ("both", "alarm", "none")

#: The keys of :meth:`StreamingEvaluation.state`.
STATE_KEYS = ("arr", "columns", "options", "samples", "final", "step", "t", "buffer", "origin", "run", "integrals",
              "integrands", "t_final", "unknown", "ended")


@dataclass
class StreamChunk(Evaluation):
    """The samples of a stream that became final in one :meth:`~StreamingEvaluation.push` or ``flush``.

    The fields of :class:`~diagnosis.detection.Evaluation`, for those samples only, and ``start``: the
    index of the first of them in the stream (0 for the stream's first sample).  ``detection_time`` is
    the first alarm within the chunk; an alarm that goes on from the previous chunk counts as one here
    too.

    Examples
    --------
    >>> a = StreamChunk("ARR_demo", np.array([0.0, 0.1]), np.zeros(2), np.full(2, -1.0), np.ones(2), np.ones(2),
    ...                 margin=0.0, persistence=1, violation=np.zeros(2, bool), alarm=np.zeros(2, bool),
    ...                 points=[np.zeros(2)], start=0)
    >>> b = StreamChunk("ARR_demo", np.array([0.2]), np.full(1, -2.0), np.full(1, -1.0), np.ones(1), np.ones(1),
    ...                 margin=0.0, persistence=1, violation=np.ones(1, bool), alarm=np.ones(1, bool),
    ...                 points=[np.full(1, 3.0)], start=2)
    >>> both = StreamChunk.concatenate([a, b])
    >>> len(both), both.start, both.detection_time, both.points[0].tolist()
    (3, 0, 0.2, [0.0, 0.0, 3.0])
    """

    start: int = 0

    def __len__(self) -> int:
        return int(self.t.size)

    @classmethod
    def concatenate(cls, chunks: Sequence["StreamChunk"]) -> "StreamChunk":
        """One chunk holding consecutive chunks of a stream, in order (e.g. to compare with ``evaluate``)."""
        chunks = list(chunks)
        if not chunks:
            raise ValueError("chunks: nothing to concatenate (an empty list)")
        for before, after in zip(chunks, chunks[1:]):
            if after.start != before.start + len(before):
                raise ValueError(f"chunks: a chunk starting at sample {after.start} does not follow one holding "
                                 f"samples {before.start} to {before.start + len(before) - 1}")
        first = chunks[0]

        def join(field: str) -> np.ndarray:
            return np.concatenate([getattr(c, field) for c in chunks])

        points = [np.concatenate([c.points[k] for c in chunks]) for k in range(len(first.points))]
        return cls(first.name, join("t"), join("residual"), join("lower"), join("upper"), join("bglft"),
                   first.margin, first.persistence, join("violation"), join("alarm"), points, first.start)


@dataclass(frozen=True)
class CheckedBatch:
    """A micro-batch :meth:`StreamingEvaluation.check` read and checked against a stream at ``samples`` samples."""

    stream: object
    samples: int
    t: np.ndarray
    block: np.ndarray
    step: float
    raw_t: object = None
    signals: object = None


class StreamingEvaluation:
    """An ARR evaluated over a stream of samples of one asset, a micro-batch at a time.

    Parameters
    ----------
    arr : ARR
    method, window, polyorder, antiderivatives, margin, persistence, threshold
        As in :func:`~diagnosis.detection.evaluate`, checked the same way.  ``antiderivatives``
        columns (e.g. ``{"omega_m": "theta_m"}``) must come in every batch.
    exact_derivatives : None
        Refused: a stream has no exact derivative columns; the derivatives are estimated.
    dt : float, optional
        The sampling step of the stream (``method="savgol"``): the steps are checked against it and the
        Savitzky-Golay coefficients use it.  Default: the stream's first step.  Central differences
        take the times as they come and do not use it.

    Attributes
    ----------
    samples : int
        Samples pushed so far.
    final : int
        Samples returned as final so far (``samples - final`` wait for their derivative window).

    Raises
    ------
    RecordError
        An unknown method, bad ``window``/``polyorder`` for a derivative of the ARR (naming the signal),
        ``exact_derivatives``, a bad ``dt``.
    ValueError
        A bad ``margin``, ``persistence`` or ``threshold`` (as :func:`~diagnosis.detection.evaluate`).

    Examples
    --------
    One sample at a time, a fault persisting across the pushes:

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arr = derive_arrs(rlc_circuit())[0]       # V - L di/dt - R i - v_C
    >>> stream = StreamingEvaluation(arr, method="central", persistence=3)
    >>> alarms = []
    >>> for k in range(8):
    ...     V = 1.0 if k < 3 else 2.0                 # a fault from the 4th sample on
    ...     chunk = stream.push([0.01 * k], {"V": [V], "i": [0.0], "v_C": [1.0]})
    ...     alarms += chunk.alarm.tolist()
    >>> alarms += stream.flush().alarm.tolist()
    >>> alarms
    [False, False, False, False, False, True, True, True]
    """

    def __init__(self, arr, *, method: str = "savgol", window: int | None = None, polyorder: int | None = None,
                 exact_derivatives: Mapping | None = None, antiderivatives: Mapping | None = None,
                 margin: float = 0.0, persistence: int = 1, threshold: str = "interval",
                 dt: float | None = None) -> None:
        check_options(arr, "StreamingEvaluation", method=method, antiderivatives=antiderivatives, margin=margin,
                      persistence=persistence, threshold=threshold)
        check_closed_form(arr, "StreamingEvaluation")
        if exact_derivatives:
            raise RecordError(f"{arr.name}: exact_derivatives: a stream has no exact derivative columns; its "
                              "derivatives are estimated (method='savgol' or 'central')")
        if dt is not None and (isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not math.isfinite(dt)
                               or dt <= 0):
            raise RecordError(f"{arr.name}: dt: the sampling step must be a finite number > 0, got {dt!r}")
        self.arr = arr
        polyorder = fitting_order(arr, polyorder)
        self._options = {"method": method, "window": window, "polyorder": polyorder,
                         "antiderivatives": dict(antiderivatives or {}), "margin": float(margin),
                         "persistence": int(persistence), "threshold": threshold,
                         "dt": None if dt is None else float(dt)}
        self._plan()
        self._reset()

    # -- what the ARR needs ------------------------------------------------------------------------------
    def _plan(self) -> None:
        """The columns to buffer, the derivatives by order, the integrals, and how far the estimates reach."""
        compiled, options = self.arr.compiled, self._options
        method, polyorder = options["method"], options["polyorder"]
        self._columns = tuple(dict.fromkeys([*compiled.signals, *options["antiderivatives"].values()]))
        self._row = {name: k for k, name in enumerate(self._columns)}
        self._signals = [(sp.Symbol(name), self._row[name]) for name in compiled.signals]
        orders: dict = {}
        for symbol, (name, order) in compiled.derivatives.items():
            orders.setdefault(order, []).append((symbol, self._row[name], name))
        self._orders = orders
        if method == "savgol":
            self._window = self._checked_window(compiled)
        # samples a derivative at i needs after i (the lag), samples kept, samples before anything is final
        half = self._window // 2 if method == "savgol" and orders else 0
        top = max(orders, default=0)
        if not orders:
            self._lag, self._keep, self._ready_at = 0, 1, 1
        elif method == "savgol":
            self._lag, self._keep, self._ready_at = half, self._window, self._window
        else:
            self._lag, self._keep, self._ready_at = top, 2 * top + 2, max(3, top + 2)
        self._uniform = method == "savgol" and bool(orders)
        self._edges = {symbol: trusted_edge(order, method, options["window"], polyorder)
                       for symbol, (_, order) in compiled.derivatives.items()}
        self._integrals = [(symbol, compiled.antiderivative_terms(symbol, options["antiderivatives"]))
                           for symbol in compiled.integrals]
        self._coefficients: dict = {}

    def _checked_window(self, compiled) -> int:
        """The Savitzky-Golay window, checked for every derivative of the ARR as :func:`derivative` would."""
        window, polyorder = self._options["window"], self._options["polyorder"]
        if window is None and isinstance(polyorder, numbers.Integral) and not isinstance(polyorder, bool):
            window = default_window(polyorder)
        for name, order in compiled.derivatives.values():
            check_savgol_settings(name, order, window, polyorder)
        return window if window is not None else default_window()

    def _reset(self) -> None:
        """The state of a stream that has seen no sample."""
        self._count = 0
        self._final = 0
        self._step = math.nan
        self._t = np.empty(0)
        self._x = np.empty((len(self._columns), 0))
        self._origin = np.full(len(self._columns), np.nan)
        self._run = 0
        self._integral = np.zeros(len(self._integrals))
        self._integrand = np.full(len(self._integrals), np.nan)
        self._t_final = math.nan
        self._unknown = np.zeros(len(self._integrals), bool)
        self._ended = False

    @property
    def samples(self) -> int:
        """Samples pushed so far."""
        return self._count

    @property
    def final(self) -> int:
        """Samples returned as final so far."""
        return self._final

    @property
    def columns(self) -> tuple[str, ...]:
        """The columns every batch must hold: the ARR's signals, then the antiderivative columns."""
        return self._columns

    def __repr__(self) -> str:
        return (f"StreamingEvaluation({self.arr.name!r}, {self._count} samples, {self._final} final, "
                f"method={self._options['method']!r})")

    # -- the stream ----------------------------------------------------------------------------------------
    def push(self, t: "ArrayLike | CheckedBatch", signals: Mapping[str, ArrayLike] | None = None, *,
             thresholds: str = "both") -> StreamChunk:
        """Take the next samples of the stream and return those that became final.

        Parameters
        ----------
        t : array_like, shape (n,)
            Strictly increasing times, after the previous batch's last one (a number for one sample).
        signals : mapping
            Signal name -> ``n`` samples, for every signal the ARR reads and every antiderivative
            column (:attr:`columns`); other entries are ignored.  NaN marks a gap.
        thresholds : {"both", "alarm", "none"}
            Which bands the samples that become final get: both (the interval and BG-LFT ones); the
            one the alarm is judged on (the other NaN), for a caller that keeps the alarms alone; or
            none, for the residual alone: not judged (thresholds NaN, no violation, no alarm, and the
            persistence run starts again), which saves the interval evaluation, most of a short
            batch's cost, for a caller that no longer needs it (a fleet's asset after its alarm).

        Returns
        -------
        StreamChunk
            The samples that became final, possibly none (a chunk of length 0).

        Raises
        ------
        RecordError
            Naming ``t`` and the time: ``t`` not increasing (within the batch or from the previous one),
            a step off the stream's step (``method="savgol"``).  Naming the signal: a signal missing,
            non-numeric, infinite, too large, or of another length than ``t``.  After :meth:`flush`.
        """
        if thresholds not in BANDS:
            raise ValueError(f"thresholds must be one of {', '.join(map(repr, BANDS))}, got {thresholds!r}")
        if isinstance(t, CheckedBatch) and t.stream is self and t.samples == self._count:
            t, block, self._step = t.t, t.block, t.step  # checked against this very state: not read again
        else:
            t, block, self._step = self._checked(t.raw_t if isinstance(t, CheckedBatch) else t,
                                                 t.signals if isinstance(t, CheckedBatch) else signals)
        if t.size == 0:
            return self._empty()
        if self._count == 0:
            self._origin = block[:, 0].copy()
        self._t = np.concatenate((self._t, t))
        self._x = np.concatenate((self._x, block), axis=1)
        self._count += t.size
        ready = self._count - self._lag if self._count >= self._ready_at else 0
        chunk = self._advance(ready, at_end=False, thresholds=thresholds)
        if self._t.size > self._keep:  # copies, so that the batch's arrays are not kept alive
            self._t, self._x = self._t[-self._keep:].copy(), self._x[:, -self._keep:].copy()
        return chunk

    def check(self, t: ArrayLike, signals: Mapping[str, ArrayLike]) -> "CheckedBatch":
        """Raise the error :meth:`push` would raise for these samples, without taking them.

        The stream is left as it was, so a caller with several streams (a fleet's assets, an asset's
        ARRs) can check a whole batch before any of them moves.  Returns the batch as read, which
        :meth:`push` then takes without reading it again (if the stream has not moved meanwhile).

        >>> from bondgraph.library import rlc_circuit
        >>> from diagnosis import derive_arrs
        >>> stream = StreamingEvaluation(derive_arrs(rlc_circuit())[0])
        >>> try:
        ...     stream.check([0.0, 0.01], {"V": [1.0, 1.0], "i": [0.0, 0.0]})
        ... except RecordError as error:
        ...     print(str(error).split(";")[0])
        ARR_J1 stream: missing signal(s) ['v_C'] in this batch
        >>> stream.samples
        0
        """
        read, block, step = self._checked(t, signals)
        return CheckedBatch(self, self._count, read, block, step, t, signals)

    def _checked(self, t: ArrayLike, signals: Mapping) -> tuple[np.ndarray, np.ndarray, float]:
        """The batch read and checked: ``t``, the columns (columns, n) and the stream's step after it."""
        if self._ended:
            raise RecordError(f"{self._name}: the stream has ended (flush() was called); start a new "
                              "StreamingEvaluation for new data")
        t, block = self._read(t, signals)
        return t, block, (self._check_times(t) if t.size else self._step)

    def flush(self) -> StreamChunk:
        """End the stream: finalize the waiting samples with the one-sided fit a record's end gets.

        Raises a :class:`RecordError` when samples wait but the stream is shorter than the derivative
        estimator needs (as :func:`~diagnosis.detection.evaluate` refuses such a record).  A second
        ``flush()`` returns an empty chunk; :meth:`push` is refused from then on.
        """
        if self._ended:
            return self._empty()
        if self._final < self._count < self._ready_at:
            need = (f"the Savitzky-Golay window of {self._window}; pass a smaller odd window= or use "
                    "method='central'") if self._options["method"] == "savgol" else "central differences"
            raise RecordError(f"{self._name}: the stream has {self._count} samples, fewer than the {self._ready_at} "
                              f"of {need}")
        chunk = self._advance(self._count, at_end=True)
        self._ended = True
        return chunk

    @property
    def _name(self) -> str:
        return f"{self.arr.name} stream"

    # -- reading a batch -------------------------------------------------------------------------------
    def _read(self, t: ArrayLike, signals: Mapping) -> tuple[np.ndarray, np.ndarray]:
        """``t`` and the columns as a float array (columns, n), after the checks of :func:`as_record`."""
        if not isinstance(signals, Mapping):
            raise RecordError(f"{self._name}: signals must be a mapping of signal name -> samples, "
                              f"got {type(signals).__name__}")
        missing = [c for c in self._columns if c not in signals]
        if missing:
            raise RecordError(f"{self._name}: missing signal(s) {missing} in this batch; every batch needs "
                              f"{list(self._columns)}, got {list(signals)}")
        arrays = [_plain(t), *(_plain(signals[c]) for c in self._columns)]
        n = arrays[0].size if arrays[0] is not None else -1
        if all(a is not None and a.size == n for a in arrays):
            block = np.array(arrays[1:]).reshape(len(self._columns), n)
            with np.errstate(invalid="ignore"):
                if np.isfinite(arrays[0]).all() and not (np.abs(block) > MAX_MAGNITUDE).any() \
                        and not (np.abs(arrays[0]) > MAX_MAGNITUDE).any():
                    return arrays[0], block
        # something is wrong, or merely unusual (numbers in an object array): the record checks say which
        data = {c: np.atleast_1d(signals[c]) if np.ndim(signals[c]) == 0 else signals[c] for c in self._columns}
        record = as_record({TIME: np.atleast_1d(t) if np.ndim(t) == 0 else t, **data}, self._columns,
                           name=self._name, min_samples=0)
        return record.t, np.array([record.columns[c] for c in self._columns]).reshape(len(self._columns), -1)

    def _check_times(self, t: np.ndarray) -> float:
        """``t`` increases within the batch and from the previous one; steps uniform for Savitzky-Golay.

        Returns the stream's step once these samples are taken (read from the first two samples when
        ``dt`` is not given); the stream itself is not changed."""
        before = self._t[-1:] if self._count else np.empty(0)
        times = np.concatenate((before, t))
        steps = np.diff(times)
        back = np.flatnonzero(steps <= 0)
        if back.size:
            i = int(back[0])
            where = "the previous batch's last sample" if (i == 0 and before.size) else "the previous sample"
            raise RecordError(f"{self._name}: t must increase: t = {float(times[i + 1])!r} follows "
                              f"t = {float(times[i])!r} ({where})")
        step = self._step
        if not self._uniform or not steps.size:
            return step
        if math.isnan(step):
            step = self._options["dt"] if self._options["dt"] is not None else float(steps[0])
        off = np.abs(steps - step) > UNIFORM_RTOL * step
        if off.any():
            i = int(np.flatnonzero(off)[0])
            raise RecordError(f"{self._name}: t = {float(times[i + 1])!r} comes {float(steps[i]):.9g} after the "
                              f"previous sample, but the stream's step is {step:.9g} (off by "
                              f"{abs(steps[i] - step) / step:.2%}); method='savgol' needs uniform "
                              f"sampling (within {UNIFORM_RTOL:g}): use method='central', which handles uneven steps")
        return step

    # -- finalizing samples ----------------------------------------------------------------------------
    def _advance(self, ready: int, at_end: bool, thresholds: str = "both") -> StreamChunk:
        """Compute the samples ``final .. ready - 1`` from the buffer, then drop what is no longer needed."""
        first = self._final
        if ready <= first:
            return self._empty()
        offset = self._count - self._t.size  # stream index of the buffer's first sample
        lo, hi = first - offset, ready - offset
        t = self._t[lo:hi].copy()
        values = {symbol: self._x[row, lo:hi].copy() for symbol, row in self._signals}
        values.update(self._derivatives(lo, hi, at_end))
        for k, (symbol, terms) in enumerate(self._integrals):
            if terms is not None:
                values[symbol] = antiderivative_integral(
                    terms, {c: self._x[self._row[c], lo:hi] for c, _ in terms},
                    {c: self._origin[self._row[c]] for c, _ in terms})
            else:
                values[symbol] = self._trapezoid(k, symbol, t, values)
        self._t_final = float(t[-1])
        compiled = self.arr.compiled
        points = [values[p] for p in compiled.points]
        if thresholds != "none":
            residual, lower, upper, bglft, violation = judge(compiled, points, self._options["margin"],
                                                             self._options["threshold"], thresholds == "both")
            alarm = self._persistent(violation)
        else:
            residual, undecided = compiled.residual(points), np.full(t.size, np.nan)
            lower, upper, bglft = undecided, undecided.copy(), undecided.copy()
            violation, alarm, self._run = np.zeros(t.size, bool), np.zeros(t.size, bool), 0
        self._final = ready
        return StreamChunk(self.arr.name, t, residual, lower, upper, bglft, self._options["margin"],
                           self._options["persistence"], violation, alarm, points, first)

    def _derivatives(self, lo: int, hi: int, at_end: bool) -> dict:
        """Every derivative point at buffer positions ``lo .. hi - 1``, NaN where the batch leaves it undecided."""
        out = {}
        for order, wanted in self._orders.items():
            if self._options["method"] == "savgol":
                estimates = self._savgol(order, [row for _, row, _ in wanted], lo, hi, at_end)
            else:
                estimates = [self._central(order, row, lo, hi) for _, row, _ in wanted]
            for (symbol, _, _), values in zip(wanted, estimates):
                out[symbol] = self._trusted(symbol, values, lo, hi, at_end)
        return out

    def _savgol(self, order: int, rows: list, lo: int, hi: int, at_end: bool) -> np.ndarray:
        """Savitzky-Golay derivatives of some buffered columns: the batch filter's convolution in the interior,
        its polynomial fit on the first (last) window within half a window of the stream's start (end)."""
        window, polyorder = self._window, self._options["polyorder"]
        half, size = window // 2, self._t.size
        start, stop = max(0, lo - half), min(size, hi + half)
        x = self._x[rows, start:stop]
        coefficients = self._coefficients.get(order)
        if coefficients is None:  # the same coefficients as scipy's savgol_filter, for the same step
            coefficients = self._coefficients[order] = savgol_coeffs(window, polyorder, deriv=order,
                                                                     delta=self._step)
        d = convolve1d(x, coefficients, axis=-1, mode="constant")[:, lo - start:hi - start]
        # buffer position p is d[:, p - lo]; the edge fits cover positions [0, half) and [size - half, size)
        offset = self._count - size  # stream index of buffer position 0
        if offset == 0 and lo < half:  # the stream's first window: fitted one-sided, as at a record's start
            edge = self._edge(self._x[rows, :window], order)
            d[:, :half - lo] = edge[:, lo:half]
        if at_end and hi > size - half:  # the stream's last window, one-sided as at a record's end
            edge = self._edge(self._x[rows, size - window:], order)
            first = max(lo, size - half)
            d[:, first - lo:] = edge[:, first - (size - window):hi - (size - window)]
        return d

    def _edge(self, x: np.ndarray, order: int) -> np.ndarray:
        """The batch filter's one-sided values on one window per row: NaN for a row with a gap in it."""
        out = np.full(x.shape, np.nan)
        for k, row in enumerate(x):
            if np.isfinite(row).all():  # a gap is missing data, not the record's end: no one-sided fit
                out[k] = savgol_filter(row, self._window, self._options["polyorder"], deriv=order,
                                       delta=self._step, mode="interp")
        return out

    def _central(self, order: int, row: int, lo: int, hi: int) -> np.ndarray:
        """Central differences of one buffered column, on enough samples either side to be the record's values."""
        start, stop = max(0, lo - order - 1), min(self._t.size, hi + order + 1)
        d = central_derivative(self._t[start:stop], self._x[row, start:stop], order)
        return d[lo - start:hi - start]

    def _trusted(self, symbol: sp.Symbol, values: np.ndarray, lo: int, hi: int, at_end: bool) -> np.ndarray:
        """NaN within :func:`~diagnosis.residuals.trusted_edge` samples of the stream's start (and end, at the end)."""
        edge = self._edges[symbol]
        if not edge:
            return values
        offset = self._count - self._t.size
        index = np.arange(offset + lo, offset + hi)
        undecided = index < edge
        if at_end:
            undecided |= index >= self._count - edge
        values = values.copy()
        values[undecided] = np.nan
        return values

    def _trapezoid(self, k: int, symbol: sp.Symbol, t: np.ndarray, values: dict) -> np.ndarray:
        """The running trapezoid integral of integral ``k``: scipy's ``cumulative_trapezoid`` continued."""
        g = self.arr.compiled.integrand_values(symbol, values, t.size)
        if self._final == 0:  # the stream's first sample: the integral starts at 0 there
            times, integrand, carried = t, g, 0.0
        else:
            times, integrand = np.concatenate(([self._t_final], t)), np.concatenate(([self._integrand[k]], g))
            carried = self._integral[k]
        # the same operations, in the same order, as cumulative_trapezoid: the values are bitwise equal
        terms = np.diff(times) * (integrand[1:] + integrand[:-1]) / 2.0
        total = np.cumsum(np.concatenate(([carried], terms)))
        total = total if self._final == 0 else total[1:]
        gap = np.flatnonzero(np.isnan(g))
        if gap.size:
            total[gap[0]:] = np.nan  # unknown from the gap on, the gap's own sample included (a gap at t_0 too)
        if gap.size and not self._unknown[k]:
            self._unknown[k] = True
            when = float(t[gap[0]])
            warnings.warn(f"integral of {str(self.arr.compiled.integrals[symbol])!r} is unknown from t = {when!r} "
                          "on: the signal has a gap (NaN) there", RecordWarning, stacklevel=4)
        self._integral[k], self._integrand[k] = total[-1], g[-1]
        return total

    def _persistent(self, violation: np.ndarray) -> np.ndarray:
        """Alarms: the run of consecutive violations, carried over from the previous batch, reaches persistence."""
        index = np.arange(violation.size)
        last_clear = np.maximum.accumulate(np.where(violation, -1 - self._run, index))
        run = index - last_clear
        self._run = int(min(run[-1], self._options["persistence"]))  # only "at least persistence" matters
        return run >= self._options["persistence"]

    def _empty(self) -> StreamChunk:
        empty = np.empty(0)
        return StreamChunk(self.arr.name, empty, empty.copy(), empty.copy(), empty.copy(), empty.copy(),
                           self._options["margin"], self._options["persistence"], np.zeros(0, bool),
                           np.zeros(0, bool), [np.empty(0) for _ in self.arr.compiled.points], self._final)

    # -- surviving a restart -----------------------------------------------------------------------------
    def state(self) -> dict:
        """Everything the stream needs to go on, as a plain dict of numbers, strings and numpy arrays.

        Not the ARR: :meth:`restore` takes it again.  The buffer holds at most ``window`` samples
        (Savitzky-Golay) whatever the stream's length.

        >>> from bondgraph.library import rlc_circuit
        >>> from diagnosis import derive_arrs
        >>> arr = derive_arrs(rlc_circuit())[0]
        >>> stream = StreamingEvaluation(arr)
        >>> _ = stream.push(np.arange(30) * 0.01, {"V": np.ones(30), "i": np.zeros(30), "v_C": np.ones(30)})
        >>> saved = stream.state()
        >>> saved["samples"], saved["final"], saved["buffer"].shape
        (30, 25, (3, 11))
        >>> again = StreamingEvaluation.restore(arr, saved)
        >>> again.push([0.30], {"V": [1.0], "i": [0.0], "v_C": [1.0]}).t.tolist()
        [0.25]
        """
        options = dict(self._options)
        options["antiderivatives"] = dict(options["antiderivatives"])
        return {"arr": self.arr.name, "columns": list(self._columns), "options": options,
                "samples": self._count, "final": self._final, "step": self._step, "t": self._t.copy(),
                "buffer": self._x.copy(), "origin": self._origin.copy(), "run": self._run,
                "integrals": self._integral.copy(), "integrands": self._integrand.copy(), "t_final": self._t_final,
                "unknown": self._unknown.copy(), "ended": self._ended}

    @classmethod
    def restore(cls, arr, state: Mapping, **options) -> "StreamingEvaluation":
        """A stream that goes on from a :meth:`state`: the same results as if it had never stopped.

        ``options`` default to the saved ones; an option given must equal the saved one (a stream
        cannot change its estimator or thresholds midway).  Raises a :class:`RecordError` naming the
        key or option for a state that does not fit the ARR or is incomplete.
        """
        if not isinstance(state, Mapping):
            raise RecordError(f"restore: state must be the dict StreamingEvaluation.state() returns, "
                              f"got {type(state).__name__}")
        missing = [key for key in STATE_KEYS if key not in state]
        if missing:
            raise RecordError(f"restore: the state lacks {missing}; expected the dict StreamingEvaluation.state() "
                              "returns")
        name = getattr(arr, "name", None)
        if state["arr"] != name:
            raise RecordError(f"restore: the state is of the stream of {state['arr']!r}, not of {name!r}")
        saved = dict(state["options"])
        if "antiderivatives" in options:  # as the constructor keeps them: None is no antiderivative
            options["antiderivatives"] = dict(options["antiderivatives"] or {})
        for key, value in options.items():
            if key in saved and value != saved[key]:
                raise RecordError(f"{name}: restore: option {key}={value!r} differs from the stream's {key}="
                                  f"{saved[key]!r}; a stream goes on with the options it started with")
        stream = cls(arr, **{**saved, **options})
        stream._load(state)
        return stream

    def _load(self, state: Mapping) -> None:
        """Take a state checked against this stream's columns and integrals."""
        if list(state["columns"]) != list(self._columns):
            raise RecordError(f"{self._name}: restore: the state's columns {list(state['columns'])} are not the "
                              f"stream's {list(self._columns)}")
        t = np.array(state["t"], dtype=float).reshape(-1)
        x = np.array(state["buffer"], dtype=float)
        shapes = {"buffer": (x.shape, (len(self._columns), t.size)),
                  "origin": (np.shape(state["origin"]), (len(self._columns),)),
                  "integrals": (np.shape(state["integrals"]), (len(self._integrals),)),
                  "integrands": (np.shape(state["integrands"]), (len(self._integrals),)),
                  "unknown": (np.shape(state["unknown"]), (len(self._integrals),))}
        for key, (shape, expected) in shapes.items():
            if shape != expected:
                raise RecordError(f"{self._name}: restore: state[{key!r}] has shape {shape}, expected {expected}")
        samples, final = int(state["samples"]), int(state["final"])
        if not 0 <= final <= samples or t.size > min(samples, self._keep) or samples - final > t.size:
            raise RecordError(f"{self._name}: restore: inconsistent state: {samples} samples, {final} final, "
                              f"{t.size} buffered")
        self._count, self._final, self._step = samples, final, float(state["step"])
        self._t, self._x = t, x
        self._origin = np.array(state["origin"], dtype=float)
        self._run = int(state["run"])
        self._integral = np.array(state["integrals"], dtype=float)
        self._integrand = np.array(state["integrands"], dtype=float)
        self._t_final = float(state["t_final"])
        self._unknown = np.array(state["unknown"], dtype=bool)
        self._ended = bool(state["ended"])

    def __getstate__(self) -> dict:
        # the ARR and the plain state; the plan (coefficients, symbols) is rebuilt on loading
        return {"arr": self.arr, "state": self.state()}

    def __setstate__(self, pickled: dict) -> None:
        self.__dict__.update(type(self).restore(pickled["arr"], pickled["state"]).__dict__)


def _plain(values: object) -> np.ndarray | None:
    """A 1-D float view of numeric samples (a number is one sample), or None when the record checks must look."""
    array = np.asarray(values) if not isinstance(values, (str, bytes)) else None
    if array is None or array.dtype.kind not in "iuf" or array.ndim > 1:
        return None
    return array.astype(float, copy=False).reshape(-1)
