"""Monitoring a fleet: detection, estimation and RUL of many assets in one vectorized filter.

:class:`FleetMonitor` is :class:`~prognosis.isolation.IsolatingMonitor` for many assets at once.  Each
asset's records go through detection with the ARRs; at an asset's first alarm, its rows start: one
row of particles per hypothesis (a candidate with a law, from the failure values, as in
:class:`~prognosis.isolation.IsolatingMonitor`'s isolation by evidence; a single named hypothesis is one row
per asset).  From then on all started
rows step together, each at its own filter step, on random streams keyed by (seed, asset, step)
(:mod:`prognosis.random_streams`), so an asset's results are bitwise the same alone, in any batch and on
any worker.  The RUL is predicted in closed form (:mod:`prognosis.fleet.closed_form_rul`) and mixed over the
hypotheses by posterior probability.

Results are tidy tables (:class:`~prognosis.fleet.results.FleetResult`): alarms, estimates every
``report_every`` steps, RUL every ``rul_every`` steps.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from bondgraph.errors import SettingError
from diagnosis import RecordError, as_record, check_signals

from ..hypotheses import indistinguishable_groups, same_signature, signature_candidates
from ..isolation import (DRIFT_AWAY_STEPS, FLEET_LAWS, FLEET_SETTINGS, MIXTURE_FLOOR, IsolationSettings, Priors,
                         check_noise_std, decide, detection_options)
from ..health_monitor import filter_stride
from ..degradation import SHAPED
from ..observation import observation_model
from .. import seeds
from ..rul import RULPredictor
from ..random_streams import RATES, AssetStreams, asset_key
from .checkpoint import check_state, read_checkpoint, write_checkpoint
from .filter import ROW_STATE, FleetFilter
from .live import LiveAsset
from .results import FleetResult
from .traces import TRACE_BUCKETS, residual_trace
from .closed_form_rul import crossing_times, has_closed_form, summarize
from ..errors import PrognosisError

__all__ = ["FleetMonitor", "BLOCK", "FLEET_LAWS"]

BLOCK = 1000  # assets filtered together by run(): bounds the memory of the observations held
PAD_STEPS = 64  # filter steps whose observations the block lays side by side at once
STEP_ROWS = 256  # rows stepped at once: bounds a step's temporaries whatever the block


@dataclass
class _Window:
    """The residual and point values of the samples that raised an alarm (what the start needs)."""

    residual: np.ndarray
    points: list
    persistence: int


@dataclass
class _Asset:
    """One asset of a block: its observations at its filter steps (from its alarm on)."""

    asset: object
    t: np.ndarray  # (K,)
    y: np.ndarray  # (K, M)
    points: list  # per ARR: (K, P_m)
    hypotheses: list  # indices of the hypotheses started at the alarm
    starts: list  # (lo, hi, sigma_v) per started hypothesis


class FleetMonitor:
    """Detection, isolation by evidence, estimation and RUL for many assets.

    Parameters
    ----------
    arrs : sequence of ARR
    failures : mapping
        Failure value of each parameter that can fail, e.g. ``{"b_Md": 0.45}``.
    noise_std : mapping
        Standard deviation of each ARR's residual on healthy data (by ARR name), the same for every
        asset (assets of one type; calibrate on one healthy record).
    settings : IsolationSettings, optional
        The settings of :class:`~prognosis.isolation.IsolatingMonitor`, with one meaning in both
        (default :data:`~prognosis.isolation.FLEET_SETTINGS`); ``**changes`` change single settings
        of it.  The fleet's filter is the random-walk one (``method="sir"``), its laws carry one rate
        (linear, exponential or a custom law with one gamma), and it weighs parameters only
        (``sensors=False``, no ``pairs``); ``candidates`` are checked against each asset's signature.
    detection, healthy_until, domains
        As :class:`~prognosis.isolation.IsolatingMonitor`.
    report_every : int, optional
        Write the estimates (with quantiles) every this many steps (default ``rul_every``).
    trace_buckets : int
        :meth:`run` keeps each asset's residuals, per ARR, in this many buckets at most (the ``residuals``
        table, :func:`~prognosis.fleet.traces.residual_trace`; default
        :data:`~prognosis.fleet.traces.TRACE_BUCKETS`); 0 keeps none.  A stream (:meth:`update`) keeps none.

    Examples
    --------
    Three RLC circuits, two of them with a resistance drifting up from different times:

    >>> from bondgraph.library import rlc_circuit
    >>> from bondgraph.scenarios import drift, rlc_record
    >>> from diagnosis import derive_arrs
    >>> t = np.linspace(0.0, 3.0, 3001)
    >>> records = {"c1": rlc_record(t, {"R": drift(10.0, 4.0, onset=0.5)}), "c2": rlc_record(t),
    ...            "c3": rlc_record(t, {"R": drift(10.0, 4.0, onset=1.0)})}
    >>> arr = derive_arrs(rlc_circuit(), complete=False, integrals="keep")[0]
    >>> fleet = FleetMonitor([arr], {"R": 20.0}, laws=["linear"], noise_std={arr.name: 1e-3}, dt=0.01,
    ...                      n_particles=200, detection={"margin": 0.01})
    >>> result = fleet.run(records)
    >>> sorted(set(result.alarms["asset"]))   # c2 stays healthy
    ['c1', 'c3']
    >>> rul = result.for_asset("c1").rul
    >>> bool(abs(rul["t"][-1] + rul["p50"][-1] - 3.0) < 0.2)   # R reaches 20 ohm at t = 3.0 s
    True
    """

    def __init__(self, arrs: Sequence, failures: Mapping[str, float], *, noise_std: Mapping[str, float],
                 settings: IsolationSettings | None = None, detection: Mapping | None = None,
                 healthy_until: float | None = None, domains: Mapping[str, tuple] | None = None,
                 report_every: int | None = None, trace_buckets: int = TRACE_BUCKETS, **changes):
        self.settings = s = (settings or FLEET_SETTINGS).changed(**changes)
        if s.method != "sir":
            raise SettingError("method", f"{{setting}}: the fleet's filter is the random-walk one, 'sir'; "
                                         f"got {s.method!r}")
        if s.sensors:
            raise SettingError("sensors", "{setting}: the fleet weighs parameters only; give sensors=False "
                                          "(as FLEET_SETTINGS)")
        for name, model in s.law_models.items():  # the fleet filter carries one gamma per particle: a rate
            if (model is None and name in SHAPED) or (model is not None and model.n_gamma != 1):
                raise SettingError("laws", f"{{setting}}: the fleet filter weighs laws with one rate; {name!r} has "
                                           "more gammas")
        self.priors = Priors(arrs, failures, s, domains)
        noise_std = check_noise_std(noise_std, arrs)
        self.detection = dict(detection or {})
        self.healthy_until = -math.inf if healthy_until is None else float(healthy_until)
        s.require_step("FleetMonitor")
        if report_every is None:
            report_every = s.rul_every
        if isinstance(report_every, bool) or int(report_every) != report_every or report_every < 1:
            raise PrognosisError(f"report_every must be a positive whole number of filter steps, got {report_every!r}")
        self.report_every = int(report_every)
        if isinstance(trace_buckets, bool) or int(trace_buckets) != trace_buckets or trace_buckets < 0:
            raise PrognosisError(f"trace_buckets must be a whole number >= 0, got {trace_buckets!r}")
        self.trace_buckets = int(trace_buckets)
        self.streams = AssetStreams(s.seed)
        candidates = list(s.candidates) if s.candidates is not None else list(self.priors.failures)
        self.hypotheses, self.never = self.priors.hypotheses_for(candidates)
        self.arrs = [a for a in arrs if any(c in a.parameters for c in candidates)]
        if not self.arrs:
            raise PrognosisError(f"no ARR is sensitive to any of the candidates {candidates}")
        self.groups = indistinguishable_groups(self.arrs, candidates)
        # isolable in the model: over every ARR given, as IsolatingMonitor reads it
        self.signatures = {c: same_signature(list(arrs), c) for c in candidates}
        self.noise = np.array([noise_std[a.name] for a in self.arrs])
        self.options = [detection_options(self.detection, arrs, a) for a in self.arrs]
        # one text per hypothesis, shared by every row of the tables (a name is built anew at each call)
        self._names = [h.name for h in self.hypotheses]
        # what a record must hold, checked before it is evaluated: every column read, the sensors not stuck
        self._signals = list(dict.fromkeys(x for a in self.arrs for x in a.signals))
        self._sensors = [x for x in self._signals if any(x in a.sensors for a in self.arrs)]
        self._columns = list(dict.fromkeys([*self._signals, *(c for o in self.options
                                                                for c in (o.get("antiderivatives") or {}).values())]))
        self.observations = [[observation_model(a, h.candidate) if h.candidate in a.parameters else None
                              for a in self.arrs] for h in self.hypotheses]
        # the point values a block keeps per ARR: those an observation reads (the torsion bar's b_Md reads 1 of 5)
        self._kept = [sorted({i for models in self.observations if models[m] is not None
                              for i in models[m].points_used()}) for m in range(len(self.arrs))]
        self.boxes = np.array([self.priors.healthy_box(h, self.arrs) for h in self.hypotheses]).reshape(-1, 2)
        self.domains = np.array([h.domain for h in self.hypotheses], float).reshape(-1, 2)
        self.up = np.array([h.direction == "up" for h in self.hypotheses])
        self._filter = None  # the streaming filter (run() uses one per block)
        self._alone = None  # the status of a single hypothesis that stands
        self._laws = None
        self._live: dict = {}  # text of the asset id -> its stream (ids that print the same are one)
        self._predictors: dict = {}
        self._keep_particles = False  # RUL predictors of laws without a closed form, by hypothesis

    # -- the batch pipeline ------------------------------------------------------------------
    def run(self, records: Mapping | Iterable, *, progress: Callable[[int, int], None] | None = None,
            block: int = BLOCK, particles: bool = False, on_bad_record: str = "stop") -> FleetResult:
        """Process whole records, ``{asset: record}`` or an iterable of ``(asset, record)`` pairs.

        Records are read one at a time and only their values at the filter steps are kept; ``block``
        assets are filtered together.  ``progress(done, total)`` is called after each block with the
        number of assets done (``total`` is None for an iterable of unknown length).  With
        ``particles``, the result's :attr:`~prognosis.fleet.FleetResult.particles` holds each asset's
        particles after its last step (otherwise they are dropped with the block).

        Each record is checked as ``bgphm prognose`` checks its own (:func:`diagnosis.check_signals`:
        a column without a value, a sensor that never changes; then the ARRs' evaluation: too few
        samples, bad times).  ``on_bad_record="stop"`` raises the error, naming the asset;
        ``"skip"`` leaves the asset out and says why in the result's
        :attr:`~prognosis.fleet.FleetResult.skipped`.
        """
        if on_bad_record not in ("stop", "skip"):
            raise PrognosisError(f"on_bad_record must be 'stop' or 'skip', got {on_bad_record!r}")
        self._keep_particles = bool(particles)
        pairs = records.items() if isinstance(records, Mapping) else records
        total = len(records) if hasattr(records, "__len__") else None
        result, done, batch = FleetResult(), 0, []
        for asset, record in pairs:
            try:
                prepared = self._prepare(asset, record, result)
            except (RecordError, PrognosisError) as error:
                if on_bad_record == "stop":
                    named = str(error) if str(asset) in str(error) else f"asset {asset!r}: {error}"
                    raise type(error)(named) from None
                result.skipped[str(asset)] = str(error)
                prepared = None
            batch.append(prepared)
            if len(batch) == block:
                self._filter_block(batch, result)
                done += len(batch)
                batch = []
                if progress is not None:
                    progress(done, total)
        if batch or done == 0:
            self._filter_block(batch, result)
            done += len(batch)
            if progress is not None:
                progress(done, total)
        return result

    def _prepare(self, asset, record, result: FleetResult) -> _Asset | None:
        """Detection on one record; its observations at the filter steps from the alarm on (None if healthy)."""
        asset_key(asset)  # a clear error for an id that is neither an integer nor a string
        record = as_record(record, self._columns, name=getattr(record, "name", None) or f"asset {asset!r}")
        check_signals(record, self._signals, self._sensors)
        evaluations = [a.evaluate(record, **o) for a, o in zip(self.arrs, self.options)]
        if self.trace_buckets:
            self._trace(asset, evaluations, result)
        t = evaluations[0].t
        alarm = np.zeros(t.size, bool)
        for e in evaluations:
            alarm |= e.alarm
        alarm &= t > self.healthy_until
        if not alarm.any():
            return None
        k = int(np.argmax(alarm))
        fired = [a.name for a, e in zip(self.arrs, evaluations) if e.alarm[k]]
        result.add("alarms", asset=[asset] * len(fired), t=[t[k]] * len(fired), arr=fired)
        persistence = max(e.persistence for e in evaluations)
        window = slice(max(0, k - persistence + 1), k + 1)
        started, starts = self._start([_Window(e.residual[window], [p[window] for p in e.points], e.persistence)
                                       for e in evaluations], fired)
        if not started:
            return None
        steps = np.arange(k, t.size, filter_stride(t, self.settings.dt))
        y = np.stack([-e.residual[steps] for e in evaluations], axis=1)
        points = [np.stack([e.points[i][steps] for i in kept], axis=1) if kept else np.empty((steps.size, 0))
                  for e, kept in zip(evaluations, self._kept)]
        return _Asset(asset, t[steps], y, points, started, starts)

    def _trace(self, asset, evaluations: list, result: FleetResult) -> None:
        """The residuals table's rows of one asset: each ARR's trace (:func:`~prognosis.fleet.traces.residual_trace`).
        """
        for arr, evaluation in zip(self.arrs, evaluations):
            trace = residual_trace(evaluation, self.trace_buckets)
            size = trace["t"].size
            result.add("residuals", asset=[asset] * size, arr=[arr.name] * size, **trace)

    def _start(self, windows: list, fired: list) -> tuple[list, list]:
        """The hypotheses an alarm starts (those of the signature's candidates) and their initial boxes.

        ``windows``: per ARR, the residual and point values of the samples that raised the alarm.
        """
        s = self.settings
        allowed = (set(s.candidates) if s.candidates is not None
                   else set(signature_candidates(self.arrs, self.priors.failures, fired)))
        started, starts = [], []
        for index, h in enumerate(self.hypotheses):
            if h.candidate in allowed and h.name not in self.never:
                started.append(index)
                alarm = len(windows[0].residual) - 1
                starts.append(self.priors.start_interval(h, windows, self.arrs, alarm, self.noise))
        return started, starts

    def _filter_block(self, batch: list, result: FleetResult) -> None:
        assets = [a for a in batch if a is not None]
        if not assets:
            return
        pf = self._new_filter()
        rows, owner = self._add_rows(pf, assets)
        length = np.array([a.t.size for a in assets])
        ids = np.array([a.asset for a in assets], dtype=object)
        for first in range(0, int(length.max()), PAD_STEPS):
            # the block's observations side by side a few steps at a time: a padded copy of all of them
            # would double the block's memory
            t, y, points = _padded(assets, first, first + PAD_STEPS)
            for j in range(first, min(first + PAD_STEPS, int(length.max()))):
                live = np.flatnonzero(length[owner] > j)
                # a few hundred rows at a time: a step's temporaries (a dozen arrays of rows x N) would
                # otherwise grow with the block; rows do not interact, so the results are the same
                for start in range(0, live.size, STEP_ROWS):
                    index = live[start:start + STEP_ROWS]
                    mine, k = owner[index], j - first
                    step = pf.step(y[mine, k], self._all_points([[p[mine, k] for p in m] for m in points], index.size),
                                   rows=rows[index])
                    self._outputs(pf, rows[index], mine, ids[mine], np.full(index.size, j), t[mine, k], step,
                                  result, common=j)
        if self._keep_particles:
            for a, item in enumerate(assets):
                result.particles[str(item.asset)] = self._particles_of(pf, rows[owner == a])
        pf.remove(rows)

    def _all_points(self, kept: list, size: int) -> list:
        """Every ARR's point values for the filter from the ones a block keeps (per ARR, arrays (size,)): the
        others, which no observation reads, as zeros."""
        zeros = np.broadcast_to(0.0, (size,))
        out = []
        for m, values in enumerate(kept):
            full = [zeros] * len(self.arrs[m].compiled.points)
            for i, v in zip(self._kept[m], values):
                full[i] = v
            out.append(full)
        return out

    def particles(self, asset) -> dict:
        """The particles of a streamed asset now: ``{hypothesis: {"theta": (N,), "gamma": (G, N)}}`` (copies)."""
        live = self._stream_of(asset)
        return {} if live.rows is None else self._particles_of(self._filter, live.rows)

    def _particles_of(self, pf: FleetFilter, rows: np.ndarray) -> dict:
        return {self.hypotheses[pf.hypothesis[r]].name: {"theta": pf.theta[r].copy(), "gamma": pf.gamma[r].copy()}
                for r in rows}

    def _outputs(self, pf, rows, owner, ids, steps, times, step, result: FleetResult, common: int | None = None
                 ) -> None:
        """The estimates and RUL of the rows whose step (``steps``, taken before the step; ``step``, what it did) is
        due.

        ``common``: the step of every row when they share one (a block's tick, a stream's asset), so that
        the usual tick, with nothing due, costs two remainders of integers.
        """
        if common is not None:
            if common % self.report_every == 0:
                self._report(pf, rows, ids, steps, times, step.ess, result)
            if common % self.settings.rul_every == 0:
                self._predict(pf, rows, owner, ids, steps, times, result)
            return
        report = steps % self.report_every == 0
        if report.any():
            self._report(pf, rows[report], ids[report], steps[report], times[report], step.ess[report], result)
        due = steps % self.settings.rul_every == 0
        if due.any():
            self._predict(pf, rows[due], owner[due], ids[due], steps[due], times[due], result)

    # -- streaming ---------------------------------------------------------------------------
    def update(self, batch) -> FleetResult:
        """Take a micro-batch of samples of any assets; the rows (alarms, estimates, RUL) it produced.

        ``batch``: a mapping or DataFrame with columns ``asset``, ``t`` and the ARRs' signals (and the
        antiderivative columns of the detection options), one row per sample; each asset's samples in
        time order, continuing its previous ones.  Each asset's ARRs are evaluated online
        (:class:`diagnosis.StreamingEvaluation`), so a sample is final once its centred derivative
        window is complete and the results lag the newest sample by half a window.  The monitor keeps
        no history: memory stays bounded however long the stream, and the returned rows are the
        caller's to keep.
        """
        result = FleetResult()
        touched = []
        for live, new, t, signals, checked in self._checked_batch(_columns(batch)):
            if new:
                self._live[str(live.asset)] = live
            final = live.push(t, signals, checked)
            if final is not None:
                self._watch(live, final, result)
                touched.append(live)
        self._drain(touched, result)
        return result

    def _checked_batch(self, columns: dict) -> list:
        """Each asset's part of a micro-batch, ``(live, new, t, signals, checked)``, all checked before any stream
        moves (``checked``: the batch as each ARR's stream read it, not read again when pushed).

        A batch refused changes nothing, so it can be corrected and sent again.  Ids stay as given
        (text or whole numbers, their random streams keyed by them), but two that print the same (7
        and "7") cannot be told apart in a table: they are refused, in one batch or across batches.
        """
        parts = []
        for asset, index in _by_asset(columns["asset"]):
            live, new = self._live.get(str(asset)), False
            other = next((a for a in columns["asset"][index] if not _same_id(a, asset)), None)
            if other is None and live is not None and not _same_id(live.asset, asset):
                other = live.asset
            if other is not None:
                raise PrognosisError(f"update: asset ids {other!r} and {asset!r} collide: ids are compared as text")
            try:
                if live is None:
                    asset_key(asset)
                    live, new = LiveAsset.start(asset, self.arrs, self.options), True
                t = columns["t"][index]
                signals = {name: values[index] for name, values in columns.items() if name not in ("asset", "t")}
                checked = live.check(t, signals)
            except (TypeError, ValueError) as error:
                raise PrognosisError(f"update: asset {asset!r}: {error}") from None
            parts.append((live, new, t, signals, checked))
        return parts

    def _watch(self, live: LiveAsset, final, result: FleetResult) -> None:
        """Detection on the new final samples, the start at the alarm, and the filter steps they make due."""
        first = live.count
        if live.alarm is None:
            alarm = final.alarm.any(axis=1) & (final.t > self.healthy_until)
            if alarm.any():
                i = int(np.argmax(alarm))
                fired = [a.name for a, on in zip(self.arrs, final.alarm[i]) if on]
                result.add("alarms", asset=[live.asset] * len(fired), t=[final.t[i]] * len(fired), arr=fired)
                window = live.window(final, i)
                persistence = [int(o.get("persistence", 1)) for o in self.options]
                live.hypotheses, live.starts = self._start(
                    [_Window(-window.y[:, m], list(window.points[m].T), persistence[m]) for m in range(len(self.arrs))],
                    fired)
                live.alarm = first + i
                if live.hypotheses:
                    pf = self._streaming_filter()
                    live.rows, _ = self._add_rows(pf, [live])
        live.remember(final)
        if live.rows is None or live.alarm >= live.count:
            return
        if live.stride is None:
            live.stride = filter_stride(np.array([0.0, live.sample_step]), self.settings.dt)
        index = np.arange(first, live.count)
        due = np.flatnonzero((index >= live.alarm) & ((index - live.alarm) % live.stride == 0))
        for i in due:
            live.queue.append((final.t[i], final.y[i], [p[i] for p in final.points]))

    def _drain(self, lives: list, result: FleetResult) -> None:
        """Step the filter until none of ``lives`` has a step waiting, each tick one step of every waiting one."""
        pf = self._filter
        while True:
            waiting = [live for live in lives if live.queue]
            if not waiting:
                return
            items = [live.queue.pop(0) for live in waiting]
            if len(waiting) == 1:
                self._tick(pf, waiting[0], *items[0], result)
                continue
            rows = np.concatenate([live.rows for live in waiting])
            owner = np.repeat(np.arange(len(waiting)), [live.rows.size for live in waiting])
            y = np.array([item[1] for item in items])[owner]
            points = [list(np.array([item[2][m] for item in items])[owner].T) for m in range(len(self.arrs))]
            times = np.array([item[0] for item in items])[owner]
            ids = np.array([live.asset for live in waiting], dtype=object)[owner]
            steps = pf.steps[rows].copy()
            step = pf.step(y, points, rows=rows)
            self._outputs(pf, rows, owner, ids, steps, times, step, result)

    def _tick(self, pf: FleetFilter, live: LiveAsset, t: float, y: np.ndarray, points: list, result: FleetResult
              ) -> None:
        """A stream's usual tick: one step of one asset's rows, its sample broadcast, not copied, and the
        output columns built only on the ticks that report."""
        rows, size = live.rows, live.rows.size
        if size == 0:
            return
        y = y[None, :] if size == 1 else np.broadcast_to(y, (size, y.size))
        points = [list(p[:, None] if size == 1 else np.broadcast_to(p, (size, p.size)).T) for p in points]
        steps = pf.steps[rows].copy()
        step = pf.step(y, points, rows=rows)
        common = int(steps[0])  # one asset's rows were started together and step together: one step count
        if common % self.report_every == 0 or common % self.settings.rul_every == 0:
            self._outputs(pf, rows, np.zeros(size, int), np.full(size, live.asset, dtype=object), steps,
                          np.full(size, t), step, result, common)

    def _streaming_filter(self) -> FleetFilter:
        if self._filter is None:
            self._filter = self._new_filter()
        return self._filter

    def retire(self, asset) -> None:
        """Forget an asset (replaced, or its stream ended): its rows and buffers are freed."""
        live = self._stream_of(asset)
        del self._live[str(asset)]
        if live.rows is not None:
            self._filter.remove(live.rows)

    @property
    def assets(self) -> list:
        """The assets of the stream so far."""
        return [live.asset for live in self._live.values()]

    def _stream_of(self, asset) -> LiveAsset:
        live = self._live.get(str(asset))
        if live is None or not _same_id(live.asset, asset):
            raise KeyError(f"no asset {asset!r} in the stream")
        return live

    # -- checkpoints -------------------------------------------------------------------------
    def checkpoint(self, path: str | os.PathLike | None = None) -> dict:
        """The streaming state of every asset as plain data (numeric arrays, numbers, text); with ``path``,
        written there too as a checkpoint file (:func:`~prognosis.fleet.checkpoint.write_checkpoint`).

        Particles, kernel-smoothing state, log evidence and filter step of each row (the step is
        the whole state of an asset's random stream), the online evaluation's buffers and running
        integrals, the alarm and the queued samples: :meth:`restore` on a monitor with the same
        settings goes on exactly as if there had been no restart.  The file is numeric arrays under
        a JSON header with a format version and a checksum, never a pickle: reading it runs no code.
        """
        pf = self._filter
        assets = []
        for live in self._live.values():
            state = live.state()
            state["queue"] = [(float(t), np.asarray(y), [np.asarray(p) for p in points]) for t, y, points in live.queue]
            if live.rows is not None:
                state["rows"] = {name: getattr(pf, name)[live.rows].copy() for name in ROW_STATE}
            assets.append(state)
        state = {"version": 1, "settings": self._fingerprint(), "assets": assets}
        if path is not None:
            write_checkpoint(state, path)
        return state

    def restore(self, checkpoint: Mapping | str | os.PathLike) -> None:
        """Take up the streams of a :meth:`checkpoint`, the dict or its file (replacing this monitor's streams).

        Every key, shape, dtype, finiteness and range is checked first (:func:`~prognosis.fleet.checkpoint.
        check_state`), and a file's format, version and checksum; a checkpoint refused raises a
        :class:`~prognosis.errors.PrognosisError` naming the key or the file and leaves this monitor as it was.
        """
        if isinstance(checkpoint, (str, os.PathLike)):
            checkpoint = read_checkpoint(checkpoint)
        if not isinstance(checkpoint, Mapping) or checkpoint.get("version") != 1:
            got = checkpoint.get("version") if isinstance(checkpoint, Mapping) else type(checkpoint).__name__
            raise PrognosisError(f"checkpoint: unknown version {got!r} (expected 1)")
        if checkpoint.get("settings") != self._fingerprint():
            raise PrognosisError("checkpoint: it was made by a monitor with other settings "
                                 f"({checkpoint.get('settings')}); this one has {self._fingerprint()}")
        pf = self._new_filter()
        check_state(checkpoint, arrs=len(self.arrs), hypotheses=self.hypotheses, particles=pf.n, gammas=pf.g,
                    domains=self.domains, row_state=ROW_STATE)
        live_assets, used = {}, False
        for state in checkpoint["assets"]:
            try:
                live = LiveAsset.restore(state, self.arrs, self.options)
            except ValueError as error:
                raise PrognosisError(f"checkpoint: asset {state['asset']!r}: {error}") from None
            live.queue = [(float(t), np.asarray(y, float), [np.asarray(p, float) for p in points])
                          for t, y, points in state.get("queue", [])]
            if "rows" in state:
                rows = pf.allocate(len(state["rows"]["theta"]))
                for name in ROW_STATE:
                    getattr(pf, name)[rows] = state["rows"][name]
                for row in rows:
                    pf.asset[row] = live.asset
                live.rows, used = rows, True
            live_assets[str(live.asset)] = live
        self._live, self._filter = live_assets, (pf if used else None)

    def _fingerprint(self) -> dict:
        s = self.settings
        return {"hypotheses": [h.name for h in self.hypotheses], "arrs": [a.name for a in self.arrs],
                "particles": s.n_particles, "dt": s.dt, "seed": s.seed}

    def _new_filter(self) -> FleetFilter:
        s = self.settings
        if self._laws is None:
            self._laws = [self.priors.law(h, 0.0) for h in self.hypotheses]
        return FleetFilter(self._laws, self.observations, noise_std=self.noise, n_particles=s.n_particles, dt=s.dt,
                           inflation=s.likelihood_inflation, discount=s.discount, streams=self.streams)

    def _add_rows(self, pf: FleetFilter, assets: list) -> tuple[np.ndarray, np.ndarray]:
        """Start every asset's rows; returns the rows and the index (into ``assets``) of each row's asset."""
        ids, hypotheses, lo, hi, sigma_v, owner = [], [], [], [], [], []
        rates = []
        for a, item in enumerate(assets):
            for h, (start_lo, start_hi, noise) in zip(item.hypotheses, item.starts):
                ids.append(item.asset)
                hypotheses.append(h)
                lo.append(start_lo)
                hi.append(start_hi)
                law = self.priors.laws[self.hypotheses[h].law]
                sigma_v.append(noise if law is None else law.process_noise)
                owner.append(a)
                rng = self.streams.generator(item.asset, 0, RATES, lane=h)
                rates.append(self.priors.rate_particles(self.hypotheses[h], rng)[None, :, 0])
        rows = pf.add(ids, hypothesis=hypotheses, lo=lo, hi=hi, rates=np.stack(rates), process_noise=sigma_v)
        return rows, np.array(owner)

    def _report(self, pf, rows, ids, steps, times, ess, result: FleetResult) -> None:
        """Estimates with quantiles; reject hypotheses that left their domain or drift away from failure."""
        hypotheses = pf.hypothesis[rows]
        theta_q, gamma_q = pf.quantiles(rows)
        result.add("estimates", asset=ids, hypothesis=[self._names[h] for h in hypotheses], step=steps,
                   t=times, theta_mean=pf.theta_mean(rows), theta_p5=theta_q[:, 0], theta_p50=theta_q[:, 1],
                   theta_p95=theta_q[:, 2], gamma_mean=pf.gamma_mean(rows), gamma_p5=gamma_q[:, 0],
                   gamma_p50=gamma_q[:, 1], gamma_p95=gamma_q[:, 2], ess=ess, log_evidence=pf.log_evidence[rows])
        domain = self.domains[hypotheses]
        outside = ~((domain[:, 0] < theta_q[:, 1]) & (theta_q[:, 1] < domain[:, 1]))
        boxes, up = self.boxes[hypotheses], self.up[hypotheses]
        wrong = np.where(up, theta_q[:, 2] < boxes[:, 0], theta_q[:, 0] > boxes[:, 1])
        pf.away[rows] = np.where(wrong, pf.away[rows] + 1, 0)
        pf.rejected[rows] |= outside | (pf.away[rows] >= DRIFT_AWAY_STEPS)

    def _predict(self, pf, rows, owner, ids, steps, times, result: FleetResult) -> None:
        """The RUL of each asset: its hypotheses' crossing times mixed by posterior probability.

        ``owner`` labels the rows of one asset (consecutive); ``ids``, ``steps``, ``times`` are per row.
        """
        if rows.size == 1 or (np.diff(owner) > 0).all():
            self._predict_alone(pf, rows, ids, steps, times, result)
            return
        starts = np.ones(rows.size, bool)  # each asset's first row
        np.not_equal(owner[1:], owner[:-1], out=starts[1:])
        first = np.flatnonzero(starts)
        count = np.diff(first, append=rows.size)
        position = np.repeat(np.arange(first.size), count)
        lane = np.arange(rows.size) - first[position]  # rank of a row in its asset
        hypotheses, rejected = pf.hypothesis[rows], pf.rejected[rows]
        log_z = np.full((first.size, int(count.max())), -np.inf)
        log_z[position, lane] = np.where(rejected, -np.inf, pf.log_evidence[rows])
        top = np.max(log_z, axis=1, keepdims=True)
        with np.errstate(invalid="ignore"):
            p = np.exp(log_z - np.where(np.isfinite(top), top, 0.0))
            p /= np.sum(p, axis=1, keepdims=True)
        if not np.isfinite(p).all():  # every hypothesis of an asset rejected: 0 / 0
            p = np.nan_to_num(p)
        probability = p[position, lane]
        crossing = self._crossings(pf, rows, hypotheses, ids, steps)
        n = pf.n
        share = np.where(probability >= MIXTURE_FLOOR, probability, 0.0)[:, None] / n
        if first.size == rows.size:  # one hypothesis per asset: its particles are the asset's samples
            samples, weights = crossing, np.repeat(share, n, axis=1)
        else:  # each asset's hypotheses side by side, padded with censored samples of no weight
            samples = np.full((first.size, log_z.shape[1] * n), np.inf)
            weights = np.zeros(samples.shape)
            columns = lane[:, None] * n + np.arange(n)
            samples[position[:, None], columns] = crossing
            weights[position[:, None], columns] = share
        empty = np.sum(weights, axis=1) == 0  # every hypothesis rejected: one censored sample
        weights[empty, 0], samples[empty, 0] = 1.0, np.inf
        summary = summarize(samples, weights)
        best = np.argmax(p, axis=1)
        names = ["" if e else self._names[h] for h, e in zip(hypotheses[first + best], empty)]
        status = self._status(position, hypotheses, rejected, log_z, empty)
        result.add("rul", asset=ids[first], step=steps[first], t=times[first], mean=summary["mean"],
                   p5=summary["p5"], p50=summary["p50"], p95=summary["p95"], censored=summary["censored"],
                   hypothesis=names, probability=np.where(empty, 0.0, p[np.arange(first.size), best]),
                   status=status)

    def _predict_alone(self, pf, rows, ids, steps, times, result: FleetResult) -> None:
        """:meth:`_predict` where every asset has one row: its hypothesis has probability 1, or 0 where it is
        rejected (or its evidence is not finite), and its particles are equally weighted samples."""
        hypotheses, rejected = pf.hypothesis[rows], pf.rejected[rows]
        log_z = np.where(rejected, -np.inf, pf.log_evidence[rows])
        probability = np.isfinite(log_z).astype(float)
        empty = probability == 0  # rejected: one censored sample
        crossing = self._crossings(pf, rows, hypotheses, ids, steps)
        summary = summarize(crossing, np.full(crossing.shape, 1.0 / pf.n), equal=True)
        if empty.any():
            for name in ("p5", "p50", "p95"):
                summary[name][empty] = np.inf
            summary["mean"][empty], summary["censored"][empty] = np.nan, 1.0
        names = ["" if e else self._names[h] for h, e in zip(hypotheses, empty)]
        status = self._status(np.arange(rows.size), hypotheses, rejected, log_z[:, None], empty)
        result.add("rul", asset=ids, step=steps, t=times, mean=summary["mean"], p5=summary["p5"], p50=summary["p50"],
                   p95=summary["p95"], censored=summary["censored"], hypothesis=names, probability=probability,
                   status=status)

    def _crossings(self, pf, rows, hypotheses, ids, steps) -> np.ndarray:
        """Crossing times (rows, N): closed form per law where it exists, else propagated paths."""
        s = self.settings
        times = np.empty((rows.size, pf.n))
        single = len(self.hypotheses) == 1  # every row is hypothesis 0: no grouping
        for h in (hypotheses[:1] if single else np.unique(hypotheses)):
            mine = slice(None) if single else np.flatnonzero(hypotheses == h)
            law, hypothesis = self._laws[h], self.hypotheses[h]
            theta, rate = pf.theta[rows[mine]], pf.gamma[rows[mine], 0]
            if has_closed_form(law):
                times[mine] = crossing_times(law, theta, rate, np.full(theta.shape[0], hypothesis.failure),
                                             np.full(theta.shape[0], hypothesis.direction == "up"), s.rul_horizon)
                continue
            predictor = self._predictors.get(h)
            if predictor is None:  # one noise bank per hypothesis, shared by every asset
                predictor = self._predictors[h] = RULPredictor(law, dt=s.dt, theta_fail=hypothesis.failure,
                                                               direction=hypothesis.direction, horizon=s.rul_horizon,
                                                               seed=seeds.spawn(s.seed, seeds.PREDICTORS, int(h)))
            for i, row, asset, step in zip(np.arange(rows.size)[mine], rows[mine], ids[mine], steps[mine]):
                gamma = np.moveaxis(pf.gamma[row:row + 1], 1, -1)
                key = (asset_key(asset) << 32) | int(step)
                times[i] = predictor.predict(
                    pf.theta[row:row + 1], gamma, np.full((1, pf.n), 1.0 / pf.n), 0.0, key=key).samples[0]
        return times

    def _status(self, position, hypotheses, rejected, log_z, empty) -> list:
        """The decision's status per asset ("isolated" for a single hypothesis that stands)."""
        if len(self.hypotheses) == 1:  # alone, it stands or it is rejected: one decision, made once
            if self._alone is None:
                self._alone = decide(self.hypotheses, np.zeros(1), self.groups, {}, self.settings.min_ratio,
                                     self.signatures).status
            return ["rejected" if e else self._alone for e in empty]
        names = {}
        out = []
        for a in range(log_z.shape[0]):
            mine = position == a
            hs = [self.hypotheses[h] for h in hypotheses[mine]]
            rejected_names = {h.name: "rejected" for h, r in zip(hs, rejected[mine]) if r}
            key = (tuple(h.name for h in hs), tuple(sorted(rejected_names)))
            groups = names.setdefault(key, [g for g in self.groups if any(c in {h.candidate for h in hs} for c in g)])
            out.append(decide(hs, log_z[a, :len(hs)], groups, rejected_names, self.settings.min_ratio,
                              self.signatures).status)
        return out


def _padded(assets: list, first: int, stop: int) -> tuple[np.ndarray, np.ndarray, list]:
    """Times (A, S), measurements (A, S, M) and point values (per ARR, per point: (A, S)) of the filter steps
    ``first..stop`` of every asset (S = stop - first), NaN-padded where an asset has fewer."""
    count, steps = len(assets), stop - first
    t = np.full((count, steps), np.nan)
    y = np.full((count, steps, assets[0].y.shape[1]), np.nan)
    points = [[np.full((count, steps), np.nan) for _ in range(p.shape[1])] for p in assets[0].points]
    for a, item in enumerate(assets):
        size = max(0, min(item.t.size, stop) - first)
        t[a, :size], y[a, :size] = item.t[first:first + size], item.y[first:first + size]
        for m, values in enumerate(item.points):
            for p in range(values.shape[1]):
                points[m][p][a, :size] = values[first:first + size, p]
    return t, y, points


def _columns(batch) -> dict:
    """A micro-batch's columns as arrays; ``asset`` and ``t`` required."""
    if hasattr(batch, "columns") and hasattr(batch, "to_numpy"):  # a DataFrame
        columns = {str(c): batch[c].to_numpy() for c in batch.columns}
    elif isinstance(batch, Mapping):
        columns = {str(c): np.asarray(v) for c, v in batch.items()}
    else:
        raise TypeError(f"update: give a mapping or a DataFrame of columns, got a {type(batch).__name__}")
    for needed in ("asset", "t"):
        if needed not in columns:
            raise PrognosisError(f"update: the batch has no column {needed!r} (columns: {', '.join(columns)})")
    sizes = {name: np.shape(values)[0] if np.ndim(values) else -1 for name, values in columns.items()}
    if len(set(sizes.values())) > 1:
        raise PrognosisError(f"update: columns of different lengths {sizes}")
    return columns


def _same_id(first, second) -> bool:
    """One asset id: equal values of one kind (``7`` and ``numpy.int64(7)``, not ``7`` and ``"7"``)."""
    return isinstance(first, str) == isinstance(second, str) and first == second


def _by_asset(assets: np.ndarray):
    """(asset, indices of its samples in order) for each asset, in order of first appearance."""
    assets = np.asarray(assets, dtype=object)
    if assets.size and len(set(map(str, assets))) == 1:
        yield assets[0], np.arange(assets.size)  # one asset (a stream pushed sample by sample): no sort
        return
    keys = np.array([str(a) for a in assets]) if assets.size else np.empty(0, str)
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    order = np.argsort(inverse, kind="stable")
    bounds = np.cumsum(np.bincount(inverse))
    groups = np.split(order, bounds[:-1])
    for g in np.argsort(first, kind="stable"):
        index = groups[g]
        yield assets[index[0]], index
