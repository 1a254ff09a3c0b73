"""The ``bgphm`` command line: ARR reports, simulation, detection and prognosis on recorded data.

::

    bgphm arr MODEL [--format md|html|tex] [--out FILE]
    bgphm simulate MODEL [--t-end T] [--samples N] [--set PARAM=VALUE ...] [--out CSV]
    bgphm detect MODEL DATA.csv [--margin M | --calibrate T] [--persistence N] [--out DIR]
    bgphm prognose MODEL DATA.csv --fail PARAM=VALUE [--fail ...] [--candidate P] [--degradation LAW] [--out DIR]
    bgphm fleet MODEL RECORDS --fail PARAM=VALUE [--fail ...] --calibrate T --out DIR [--scheduler ADDRESS]
                [--workers N] [--particles N] [--dt S] [--rul-every K] [--seed S] [--on-bad-record stop|skip]
                [--force] [--resume]
    bgphm demo [dc-motor|torsion-bar|three-tank] [--out DIR] [--seed N]

MODEL is a JSON file (networkx node-link form), a Python file defining ``model``, or a built-in example
name (see :func:`bondgraph.io.load_model`).  DATA.csv has a header row with a time column ``t`` and one
column per signal the ARRs use (see :func:`diagnosis.signals.read_csv`).  RECORDS is a directory of
such CSV files, one per asset, or a Parquet file with an ``asset`` column (``docs/fleet.md``).

Exit codes: 0 success, 2 bad usage or bad input (one line on stderr naming the file, line, column,
node or parameter), 1 anything else (an interrupted run included).  Progress goes to stderr;
``--quiet`` silences it.  Results go to stdout and to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from bgphm.errors import UsageError
from bgphm.files import check_output, csv_text, input_files, write_text
from bgphm.terminal import terminal_streams
from bondgraph.errors import PHMError, SettingError
from bondgraph.io import ModelSpec, load_model
from diagnosis import DetectionSettings, pooled_calibration
from diagnosis.signals import Record, RecordError, RecordWarning, gaps, read_csv
from prognosis import MAX_PARTICLES, PrognosisSettings, filter_step, rul_horizon

__all__ = ["main"]

EXIT_OK, EXIT_FAILURE, EXIT_USAGE = 0, 1, 2


class Progress:
    """Progress lines on stderr (nothing with ``quiet``)."""

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.start = time.perf_counter()

    def __call__(self, message: str) -> None:
        if not self.quiet:
            print(f"[{time.perf_counter() - self.start:6.1f} s] {message}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------------------------------- commands

def cmd_arr(args, progress: Progress) -> int:
    """``bgphm arr``: the ARR report of ``args.model`` in ``args.format``, to stdout or ``args.out``; returns 0.

    ``args`` is the parsed command line (:func:`build_parser`); ``progress`` prints progress lines on
    stderr.
    """
    from diagnosis.report import arr_report

    out = _output_file(args)
    spec = load_model(args.model)
    progress(f"deriving the ARRs of {spec.model.name!r}")
    text = arr_report(spec.model, format=args.format)
    _emit(text, out)
    return EXIT_OK


def cmd_simulate(args, progress: Progress) -> int:
    """``bgphm simulate``: simulate ``args.model`` over ``[0, t_end]`` and write its record as CSV; returns 0.

    ``args.samples`` evenly spaced times, parameters overridden by ``--set``, inputs from the model file;
    the CSV goes to stdout or ``args.out``.  Raises :class:`UsageError` for a bad ``--t-end``,
    ``--samples`` or ``--set``, or an input signal without a value.
    """
    from bondgraph.simulation import MIN_SPAN, check_sample_count, simulate

    out = _output_file(args)
    if args.samples < 3:
        raise UsageError(f"--samples must be at least 3, got {args.samples}")
    check_sample_count(args.samples, "--samples")
    spec = load_model(args.model)
    t_end = args.t_end if args.t_end is not None else (spec.t_end or 1.0)
    if not (math.isfinite(t_end) and t_end >= MIN_SPAN):
        raise UsageError(f"--t-end must be a number of seconds of at least {MIN_SPAN:g}, got {t_end:g}")
    parameters = _assignments(args.set, spec.model.parameters, "--set")
    missing = [s for s in spec.model.inputs if s not in spec.inputs and not _has_value(spec.model, s)]
    if missing:
        raise UsageError(f"{spec.source}: no value for the input signal(s) {missing}; give them in the model file "
                         "('inputs' in a Python file, graph.inputs in JSON)")
    progress(f"simulating {spec.model.name!r} over [0, {t_end:g}] s")
    result = simulate(spec.model, (0.0, t_end), spec.inputs, x0=spec.x0, parameters=parameters,
                      t_eval=np.linspace(0.0, t_end, args.samples))
    _emit(csv_text(result.record()), out)
    return EXIT_OK


def cmd_detect(args, progress: Progress) -> int:
    """``bgphm detect``: evaluate the ARRs (or ``--arr``) on the record ``args.data``, print each alarm; returns 0.

    :func:`diagnosis.detect` chooses each ARR's form and margin from the record (``--margin``, ``--window``
    and ``--integrals`` fix them); the split-half check refuses a calibration stretch that holds a fault.
    With ``--out``: ``detection.json``, ``residuals.csv`` and residual plots.
    """
    from diagnosis import detect

    settings = _detection_settings(args)
    out = _output_directory(args)
    spec = load_model(args.model)
    arrs = _arrs(spec, progress, args.arr, "avoid" if args.integrals == "auto" else args.integrals)
    record = _record(args.data, arrs, progress, args.resample, extra=spec.model.inputs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RecordWarning)
        result = detect(spec.model, record, settings, integrals=args.integrals,
                        arrs=arrs if args.arr or args.integrals != "auto" else None)
    for w in caught:
        progress(f"warning: {w.message}")
    evaluations = result.evaluations
    summary = {"model": spec.model.name, "data": str(args.data), "samples": len(record),
               "arrs": {e.name: _evaluation_summary(e) for e in evaluations}, **result.as_dict()}
    summary["alarming_arrs"] = [e.name for e in evaluations if e.detection_time is not None]
    for e in evaluations:
        when = "no alarm" if e.detection_time is None else f"alarm at t = {e.detection_time:g} s"
        form = result.forms[e.name]
        how = form["form"] + (f", window {form['window']}" if form["window"] else "")
        print(f"{e.name}: {when} (margin {e.margin:.3g}, persistence {e.persistence}; {how})")
        d = result.detectability[e.name]
        if d.blind:
            print(f"  blind on this record: {d.reason}")
    for name, why in result.undecided.items():
        print(f"{name}: undecided, left out ({why})")
    print(_detectable_line(result))
    if result.fired:
        print(f"faults consistent with {', '.join(result.isolating)}: {', '.join(result.candidates) or 'none'}")
    if out is not None:
        write_text(out / "detection.json", json.dumps(summary, indent=2, default=_json_value))
        columns = {"t": record.t}
        for e in evaluations:
            # the threshold holds -r_n in [lower - margin, upper + margin]; written as the band on r_n itself
            columns.update({f"{e.name}.residual": e.residual, f"{e.name}.lower": -(e.upper + e.margin),
                            f"{e.name}.upper": -(e.lower - e.margin), f"{e.name}.alarm": e.alarm.astype(float)})
        write_text(out / "residuals.csv", csv_text(columns))
        written = [out / "detection.json", out / "residuals.csv"] + _plots("detection", out, evaluations, progress)
        for path in written:
            print(f"wrote {path}")
    return EXIT_OK


def _detectable_line(result) -> str:
    """``smallest detectable change: b 12 %, J 85 %, k_m none`` over every ARR of the detection."""
    parts = [f"{p} {v:.0%}" if np.isfinite(v) else f"{p} none" for p, v in sorted(result.smallest_changes.items())]
    return "smallest detectable change: " + (", ".join(parts) if parts else "no parameter")


def cmd_prognose(args, progress: Progress) -> int:
    """``bgphm prognose``: detect, find the degrading parameter and its law by evidence, predict the RUL.

    ``--fail PARAM=VALUE`` (repeatable) gives the failure value of each parameter that can fail; the
    candidates are those whose fault signature matches the ARRs that fired, each with each law
    (linear, exponential, power), weighed in one particle filter from the first alarm
    (:class:`~prognosis.isolation.IsolatingMonitor`).  ``--candidate`` and ``--degradation`` restrict
    them.  Prints the decision and the last RUL; with ``--out`` writes ``prognosis.json``,
    ``estimates.csv``, ``rul.csv`` and plots.  Returns 0.
    """
    from prognosis import prognose

    detection = _detection_settings(args)
    out = _output_directory(args)
    spec, arrs, failures, candidates, laws = _what_can_fail(args, progress)
    settings = PrognosisSettings(detection=detection, laws=tuple(laws),
                                 candidates=None if candidates is None else tuple(candidates), sensors=args.sensors,
                                 pairs=args.pairs, particles=args.particles, method=args.filter, dt=args.dt,
                                 rate=None if args.rate is None else tuple(args.rate), rul_every=args.rul_every,
                                 horizon=args.horizon, seed=args.seed)
    record = _record(args.data, arrs, progress, args.resample)
    progress(f"calibrating, then the particle filter from the first alarm: {len(laws)} law(s) per candidate, "
             f"{args.particles} particles each")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RecordWarning)
        result = prognose(arrs, record, failures, settings, domains=spec.model.domains,
                          progress=_filter_progress(progress))
    for w in caught:
        progress(f"warning: {w.message}")
    summary = result.as_dict()
    for name, margin in summary["margins"].items():
        progress(f"{name}: margin {margin:.3g}, residual noise {summary['residual_noise_std'][name]:.3g} (t <= "
                 f"{summary['calibration_end']:g} s), filter step {summary['filter_step']:g} s")
    # said even with --quiet: no answer, or no wear left but a sensor's offset (a wrong failure value?)
    if result.decision is not None and result.decision.status == "rejected":
        print(f"bgphm: warning: every hypothesis was rejected: {'; '.join(_first_reasons(result))}", file=sys.stderr)
    elif result.decision is not None and all(h.name in result.rejected for h in result.hypotheses if not h.sensor):
        print(f"bgphm: warning: every wear hypothesis was rejected, only sensors' faults are left: "
              f"{'; '.join(_first_reasons(result))}", file=sys.stderr)
    print(_prognosis_line(result, summary))
    if out is not None:
        write_text(out / "prognosis.json", json.dumps(summary, indent=2, default=_json_value))
        written = [out / "prognosis.json"]
        if result.t.size:
            write_text(out / "estimates.csv", csv_text(_estimate_columns(result)))
            p = result.monitor_result().rul_percentiles((5, 50, 95))
            write_text(out / "rul.csv", csv_text({"t": result.rul_t, "rul_mean": result.monitor_result().rul_mean,
                                                  "rul_p5": p[:, 0], "rul_median": p[:, 1], "rul_p95": p[:, 2]}))
            written += [out / "estimates.csv", out / "rul.csv"]
        primary = next((e for e in result.evaluations if e.name in result.fired), result.evaluations[0])
        best = result.monitor_result() if result.t.size else None
        written += _plots("prognosis", out, (primary, best), progress)
        for path in written:
            print(f"wrote {path}")
    return EXIT_OK


def cmd_fleet(args, progress: Progress) -> int:
    """``bgphm fleet``: detection, estimation and RUL for every asset of a fleet, to Parquet; returns 0.

    RECORDS is a directory of CSV files (one per asset, the asset id is the file name) or a Parquet
    file with an ``asset`` column.  The residual noise and the detection margins are calibrated on the
    first ``--calibrate`` seconds of the first ``--calibrate-assets`` records (by asset id): the median
    over them, per ARR, serves every asset.  The assets then run in shards on a local Dask cluster
    (``--workers``), on a running one (``--scheduler``), or in this process (``--workers 0``), through
    :func:`bgphm.fleet.run_fleet`, which writes the tables ``alarms/``, ``estimates/`` and ``rul/`` and
    ``summary.json`` under ``--out``.  Progress goes to stderr by assets done.
    """
    from bgphm.fleet import FleetSpec, model_reference, open_source, run_fleet
    from bgphm.fleet.engine import require_dask
    from bgphm.fleet.sources import pyarrow_modules

    pyarrow_modules()  # the missing extra named before any work
    if args.scheduler is not None or args.workers > 0:
        require_dask()
    source = open_source(args.records)
    # --resume goes on in the run's own --out: it is not empty, and needs no --force
    out = check_output(args.out, kind="directory", inputs=input_files(args.model) + source.inputs(),
                       force=args.force or args.resume)
    detection = _detection_settings(args)
    spec, arrs, failures, candidates, laws = _what_can_fail(args, progress)
    assets = source.assets()
    progress(f"{len(assets)} assets in {source.describe()}")
    calibrated = assets[:args.calibrate_assets]
    signals = list(dict.fromkeys(s for arr in arrs for s in arr.signals))
    try:
        pooled, first = pooled_calibration(arrs, source.read(calibrated, signals), detection)
        dt = filter_step(first, detection.window, args.dt)
        rul_horizon(dt, args.horizon, args.particles, len(failures) * len(laws))
    except SettingError as exc:
        raise exc.within("records: ") if exc.setting == "calibrate" else exc from None
    calibration = {"assets": list(calibrated), "until": args.calibrate, "noise_std": pooled.noise_std,
                   "margin": pooled.margin}
    for name in pooled.noise_std:
        progress(f"{name}: residual noise {pooled.noise_std[name]:.3g}, margin {pooled.margin[name]:.3g} (median "
                 f"over {len(calibrated)} record(s), t <= {args.calibrate:g} s)")
    detection = {name: {"margin": margin, **detection.options()} for name, margin in pooled.margin.items()}
    job = FleetSpec(model_reference(args.model), failures, noise_std=calibration["noise_std"], detection=detection,
                    laws=laws, candidates=candidates, arrs=None if args.arr is None else [args.arr],
                    integrals=args.integrals, dt=dt, n_particles=args.particles, rul_every=args.rul_every,
                    horizon=args.horizon, healthy_until=args.calibrate, seed=args.seed)
    where = args.scheduler or ("this process" if args.workers == 0 else f"a local cluster of {args.workers} workers")
    progress(f"monitoring {len(assets)} assets ({where}): {len(laws)} law(s) per candidate, {args.particles} "
             f"particles each, dt = {dt:g} s")
    summary = run_fleet(job, source, out, scheduler=args.scheduler, workers=args.workers,
                        shard_size=args.shard_size, progress=_fleet_progress(progress), notes=calibration,
                        resume=args.resume, on_bad_record=args.on_bad_record)
    for asset, why in list(summary["skipped"].items())[:5]:
        progress(f"skipped {asset}: {why}")
    print(f"{summary['assets']} assets, {summary['assets_with_alarm']} with an alarm, {summary['rows']['rul']} RUL "
          f"rows, in {summary['wall_s']:.1f} s ({1e3 * summary['seconds_per_asset']:.1f} ms per asset)")
    resumed = f" ({summary['resumed_shards']} of {summary['shards']} shards kept from the interrupted run)" \
        if args.resume else ""
    if summary["skipped"]:
        print(f"{len(summary['skipped'])} asset(s) skipped for a bad record, each with its reason in "
              f"{out / 'summary.json'} (skipped)")
    print(f"wrote {out / 'alarms'}, {out / 'estimates'}, {out / 'rul'} (Parquet), {out / 'summary.json'} and "
          f"{out / 'manifest.json'}{resumed}")
    return EXIT_OK


def cmd_demo(args, progress: Progress) -> int:
    """``bgphm demo``: write the files of the demo ``args.name`` into ``args.out`` and run its commands.

    :func:`bgphm.demo.prepare_demo` writes the model, the record and ``truth.json`` and lists the
    ``arr``, ``detect`` and ``prognose`` command lines; each is printed, then run as :func:`main` runs
    it, and the true end of life is printed beside the prediction.  Returns 0, or the exit code of
    the first command that fails.
    """
    from bgphm.demo import prepare_demo

    out = check_output(args.out, kind="directory", force=args.force)
    plan = prepare_demo(args.name, out, progress, seed=args.seed)
    quiet = ["--quiet"] if progress.quiet else []
    for command in plan.commands:
        print("$ bgphm " + " ".join(command))
        code = main(quiet + command)
        if code:
            return code
    line = plan.truth_line()
    if line is not None:
        print(line)
    return EXIT_OK


# ------------------------------------------------------------------------------------------- helpers

def _arrs(spec: ModelSpec, progress: Progress, name: str | None, integrals: str = "avoid") -> list:
    from diagnosis.arrs import ARRWarning, derive_arrs

    progress(f"deriving the ARRs of {spec.model.name!r}")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ARRWarning)
        arrs = derive_arrs(spec.model, integrals=integrals)
    for w in caught:
        progress(f"warning: {w.message}")
    if not arrs:
        raise UsageError(f"{spec.source}: the model gives no ARR (it needs De/Df sensors on its junctions)")
    return arrs if name is None else [_named(arrs, name)]


def _named(arrs: list, name: str):
    for arr in arrs:
        if arr.name == name:
            return arr
    raise UsageError(f"--arr {name!r}: no such ARR (available: {', '.join(a.name for a in arrs)})")


def _record(path, arrs: list, progress: Progress, resample: bool = False, extra: Sequence[str] = ()) -> Record:
    """The record's columns for the ARRs' signals (and those of ``extra`` it holds: inputs whose steps matter)."""
    signals = list(dict.fromkeys(s for arr in arrs for s in arr.signals))
    present = _header(path) if extra else []
    signals += [s for s in extra if s in present and s not in signals]
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", RecordWarning)
            record = read_csv(path, signals)
            if resample:
                from diagnosis.resampling import resample as uniform

                record = uniform(record)
                progress(f"resampled {path} to a uniform step of {record.dt:g} s ({len(record)} samples)")
    except RecordError as exc:
        message = str(exc)
        if "missing column" in message:
            message += f" (the ARRs {[a.name for a in arrs]} use the signals {signals})"
        raise RecordError(message) from None
    for w in caught:
        progress(f"warning: {w.message}")
    for signal in signals:
        if np.isnan(record[signal]).all():
            raise RecordError(f"{path}: column {signal!r} has no value (every cell is empty or NaN)")
    for signal, first, last, count in gaps(record, signals):
        progress(f"warning: {path}: column {signal!r} has a gap of {count} sample(s) for t in [{first:g}, {last:g}]; "
                 "no decision is made there")
    progress(f"read {len(record)} samples of {signals} from {path}")
    return record


def _header(path) -> list[str]:
    """The column names of a CSV file's header row (empty if it cannot be read: read_csv says why)."""
    import csv

    try:
        with open(path, newline="", encoding="utf-8") as handle:
            return [c.strip() for c in next(csv.reader(handle), [])]
    except (OSError, UnicodeDecodeError, csv.Error):
        return []


def _fleet_progress(progress: Progress, every: float = 2.0):
    """The ``progress`` callback of :func:`bgphm.fleet.run_fleet`: assets done, at most every ``every`` s."""
    if progress.quiet:
        return None
    printed = -math.inf

    def report(done: int, total: int) -> None:
        nonlocal printed
        now = time.perf_counter()
        if done == total or now - printed >= every:
            printed = now
            progress(f"fleet: {done} of {total} assets ({100 * done / total:.0f} %)")

    return report


def _detection_settings(args) -> DetectionSettings:
    """``--calibrate``, ``--margin``, ``--k``, ``--persistence`` and ``--window`` as the library's settings."""
    return DetectionSettings(calibrate=args.calibrate, margin=getattr(args, "margin", None), k=args.k,
                             persistence=args.persistence, window=args.window)


#: The options of the library's settings whose names differ from the settings' (``--`` + the name otherwise).
OPTIONS = {"method": "--filter", "laws": "--degradation", "candidates": "--candidate"}


def _option(setting: str) -> str:
    return OPTIONS.get(setting, "--" + setting.replace("_", "-"))


def _evaluation_summary(e) -> dict:
    finite = np.isfinite(e.residual)
    return {"detection_time": e.detection_time, "margin": e.margin, "persistence": e.persistence,
            "violations": int(e.violation.sum()), "alarm_samples": int(e.alarm.sum()),
            "undecided_samples": int((~finite).sum()),
            "alarm_onsets": e.false_alarms(float("inf"))}


def _filter_progress(progress: Progress, every: float = 2.0):
    """The ``progress`` callback of :meth:`~prognosis.monitor.HealthMonitor.run` for a command.

    It prints a line at the first report, then at most every ``every`` seconds, and at the last step;
    None with ``--quiet``, so that the monitor makes no calls at all.
    """
    if progress.quiet:
        return None
    start = time.perf_counter()
    printed = -math.inf

    def report(done: int, total: int, t: float) -> None:
        nonlocal printed
        now = time.perf_counter()
        if done == total or now - printed >= every:
            printed = now
            progress(f"filter: {100 * done / total:.0f} % of {total} steps (t = {t:.4g} s), "
                     f"{now - start:.1f} s elapsed")

    return report


def _what_can_fail(args, progress: Progress) -> tuple:
    """``prognose`` and ``fleet``: the model, its ARRs, the failure values, the candidates and the laws."""
    spec = load_model(args.model)
    arrs = _arrs(spec, progress, args.arr, args.integrals)
    parameters, domains = spec.model.parameters, spec.model.domains
    failures = _failures(args, parameters, domains)
    candidates = _candidates(args, arrs, failures, parameters)
    return spec, arrs, failures, candidates, _laws(args)


def _laws(args) -> list:
    """The competing laws: ``--degradation`` (once in ``fleet``, repeatable in ``prognose``), else the library's
    default (``fleet``: the laws with one rate)."""
    from prognosis.fleet import FLEET_LAWS
    from prognosis.isolation import LAWS

    if not args.degradation:
        return list(LAWS if args.command == "prognose" else FLEET_LAWS)
    return list(dict.fromkeys(args.degradation if isinstance(args.degradation, list) else [args.degradation]))


def _failures(args, parameters: dict, domains: dict) -> dict:
    """``--fail`` as {parameter: failure value}: ``PARAM=VALUE`` items, or one VALUE for ``--candidate``."""
    if args.candidate is not None and args.candidate not in parameters:
        raise UsageError(f"--candidate {args.candidate!r}: the model has no such parameter "
                         f"(parameters: {', '.join(parameters)})")
    named = [item for item in args.fail if "=" in item]
    bare = [item for item in args.fail if "=" not in item]
    failures = _assignments(named, parameters, "--fail")
    if bare:
        if args.candidate is None or len(bare) > 1:
            raise UsageError(f"--fail {bare[0]}: give PARAM=VALUE (repeatable), or one VALUE with --candidate")
        failures.update(_assignments([f"{args.candidate}={bare[0]}"], parameters, "--fail"))
    for name, value in failures.items():
        lo, hi = domains.get(name, (-math.inf, math.inf))
        if not lo <= value <= hi:
            raise UsageError(f"--fail {name}={value:g}: outside the physical domain ({lo:g}, {hi:g}) the model "
                             f"declares for {name!r}")
        if value == parameters[name]:
            raise UsageError(f"--fail {name}={value:g} equals the nominal value of {name!r}: the failure value must "
                             "differ from it")
    return failures


def _candidates(args, arrs: list, failures: dict, parameters: dict) -> list | None:
    """``--candidate`` checked against the model, the failure values, the ARRs and ``--direction``; None without it."""
    from diagnosis.signatures import signature_matrix

    for name, value in failures.items():
        if _laws(args) == ["exponential"] and value * parameters[name] <= 0:
            raise UsageError(f"--fail {name}={value:g}: an exponential degradation keeps the sign of {name!r} "
                             f"(nominal {parameters[name]:g}); the failure value must have the same sign")
    if args.candidate is None:
        if args.direction is not None:
            raise UsageError("--direction checks the failure value of --candidate: give --candidate too")
        return None
    name = args.candidate
    if not any(name in a.parameters for a in arrs):
        rows = signature_matrix(arrs)
        raise UsageError(f"--candidate {name!r}: no ARR is sensitive to it, so it cannot be monitored "
                         f"(detectable parameters: {[r for r, d in zip(rows.rows, rows.detectable) if d]})")
    if name not in failures:
        raise UsageError(f"--candidate {name!r}: give its failure value (--fail {name}=VALUE)")
    inferred = "up" if failures[name] > parameters[name] else "down"
    if args.direction is not None and args.direction != inferred:
        side = "above" if inferred == "up" else "below"
        raise UsageError(f"--fail {failures[name]:g} is on the wrong side of the nominal value {parameters[name]:g} of "
                         f"{name!r} for --direction {args.direction}: it lies {side} nominal; give --direction "
                         f"{inferred} (or leave --direction out: it follows from --fail)")
    return [name]


def _prognosis_line(result, summary: dict) -> str:
    if result.detection_time is None:
        return "no alarm, so no prognosis (the filter starts at the first alarm)"
    head = f"alarm at t = {result.detection_time:g} s ({', '.join(result.fired)})"
    if summary["candidate"] is None:
        why = (f"no parameter with a failure value is sensitive to every ARR that fired (consistent with them: "
               f"{', '.join(result.consistent) or 'no single fault of the model'})" if not result.candidates
               else "every hypothesis was rejected: " + "; ".join(_first_reasons(result)))
        return f"{head}; {why}"
    last = summary["last"]
    later = "".join(f"; but {reason}" for reason in summary["unexplained"].values())
    if summary["reason"]:
        rejected = f" ({'; '.join(_first_reasons(result))})" if summary["status"] == "rejected" else ""
        return f"{head}; {summary['status']}: {summary['reason']}{rejected}; at t = {last['t']:g} s no RUL{later}"
    law = summary["degradation"] + ("" if summary["degradation_decided"] else " (undecided)")
    status = summary["status"]
    if summary["same_signature"]:   # isolable in the model only when no other fault shares the signature
        status = f"indistinguishable from {', '.join(summary['same_signature'])} (same signature)"
    reported = summary["candidate"] if isinstance(summary["candidate"], list) else [summary["candidate"]]
    if any(set(pair.split(" ~ ")) <= set(reported) for pair in summary["indistinguishable_on_record"]):
        status += ", on this record (the operating regime does not tell them apart)"
    if last.get("withheld"):
        return (f"{head}; candidate {summary['candidate']} ({status}), degradation {law}; at t = "
                f"{last['t']:g} s no RUL (undecided: {last['withheld']}){later}")
    return (f"{head}; candidate {summary['candidate']} ({status}), degradation {law}; at t = "
            f"{last['t']:g} s RUL median {_fmt(last['rul_median'])} s, 5-95 % [{_fmt(last['rul_p5'])}, "
            f"{_fmt(last['rul_p95'])}] s{later}")


def _first_reasons(result) -> list[str]:
    """The first rejection reason of each candidate (its laws are often rejected for the same reason)."""
    reasons = {}
    for h in result.hypotheses:
        if h.name in result.rejected:
            reasons.setdefault(h.candidate, f"{h.name}: {result.rejected[h.name]}")
    return list(reasons.values())


def _estimate_columns(result) -> dict:
    columns = {"t": result.t}
    for row, h in enumerate(result.hypotheses):
        columns[f"{h.name}.theta_mean"] = result.theta["mean"][:, row]
        for parameter, mean in result.parts.get(h.name, {}).items():  # a pair's: each of its parameters
            columns[f"{h.name}.{parameter}.theta_mean"] = mean
        columns[f"{h.name}.gamma_mean"] = result.gamma["mean"][:, row]
        columns[f"{h.name}.log_evidence"] = result.log_evidence[:, row]
    return columns


def _plots(kind: str, out: Path, payload, progress: Progress) -> list[Path]:
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only: no window, no display needed
        import matplotlib.pyplot as plt

        from bgphm import plotting
    except ImportError:
        progress("matplotlib is not installed: no plots (pip install 'bondgraph-phm[plot]')")
        return []

    paths = []
    if kind == "detection":
        for e in payload:
            fig, ax = plt.subplots(figsize=(8, 3.5))
            plotting.plot_evaluation(e, ax=ax, title=e.name)
            paths.append(plotting.save_figure(fig, out / f"residual_{e.name}.png"))
    else:
        evaluation, result = payload
        fig, ax = plt.subplots(figsize=(8, 3.5))
        plotting.plot_evaluation(evaluation, ax=ax, title=evaluation.name)
        paths.append(plotting.save_figure(fig, out / f"residual_{evaluation.name}.png"))
        if result is not None and result.t.size:
            fig, ax = plt.subplots(figsize=(8, 3.5))
            plotting.plot_estimate(result, ax=ax)
            paths.append(plotting.save_figure(fig, out / "estimate.png"))
            fig, ax = plt.subplots(figsize=(8, 3.5))
            plotting.plot_rul(result, ax=ax)
            paths.append(plotting.save_figure(fig, out / "rul.png"))
            if result.rul:
                fig, ax = plt.subplots(figsize=(6, 3.5))
                plotting.plot_rul_distribution(result.rul[-1], ax=ax)
                paths.append(plotting.save_figure(fig, out / "rul_distribution.png"))
    return paths


def _assignments(items: Sequence[str] | None, parameters: dict, option: str) -> dict:
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep:
            raise UsageError(f"{option} {item!r}: expected PARAM=VALUE")
        if name not in parameters:
            raise UsageError(f"{option} {item!r}: the model has no parameter {name!r} "
                             f"(parameters: {', '.join(parameters)})")
        try:
            number = float(value)
        except ValueError:
            raise UsageError(f"{option} {item!r}: {value!r} is not a number") from None
        if not math.isfinite(number):
            raise UsageError(f"{option} {item!r}: the value must be finite")
        out[name] = number
    return out


def _has_value(model, signal: str) -> bool:
    return any(e.signal == signal and e.value is not None for e in model.elements.values())


def _output_file(args) -> Path | None:
    """``--out`` of a command writing one file, checked before any work; None for stdout."""
    if args.out in (None, "-"):
        return None
    return check_output(args.out, kind="file", inputs=input_files(args.model), force=args.force)


def _output_directory(args) -> Path | None:
    """``--out`` of a command writing a directory of files, checked before any work; None without it."""
    if args.out is None:
        return None
    return check_output(args.out, kind="directory", inputs=input_files(args.model, args.data), force=args.force)


def _emit(text: str, out: Path | None) -> None:
    if out is None:
        sys.stdout.write(text)
        return
    print(f"wrote {write_text(out, text)}")


def _finite(value) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def _fmt(value) -> str:
    return "n/a" if value is None else f"{value:.4g}"


def _json_value(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serializable: {type(value).__name__}")


# ------------------------------------------------------------------------------------------- parser

class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error: ``bgphm: error: argument --k: invalid float value: 'x' (see ...)``."""

    def error(self, message: str):
        self.exit(EXIT_USAGE, f"bgphm: error: {_one_line(message)} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The ``bgphm`` argument parser: ``--quiet``, ``--debug`` and the commands arr, simulate, detect, prognose, fleet,
    demo.

    Each command's parser sets ``run`` to its ``cmd_*`` function, which :func:`main` calls.
    """
    parser = _Parser(prog="bgphm", description="Bond-graph modelling, robust fault diagnosis and "
                                     "prognosis: ARR reports, simulation, detection and RUL prediction.")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an unexpected error")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    model_help = "JSON (node-link) or Python model file, or a built-in example (dc-motor, rlc, three-tank, torsion-bar)"

    p = sub.add_parser("arr", help="ARR report: elements, drawing, ARRs, fault signatures")
    p.add_argument("model", metavar="MODEL", help=model_help)
    p.add_argument("--format", choices=("md", "html", "tex"), default="md", help="report format (default md)")
    p.add_argument("--out", help="output file (default: stdout)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file (never an input)")
    p.set_defaults(run=cmd_arr)

    p = sub.add_parser("simulate", help="simulate the model and write its signals as CSV")
    p.add_argument("model", metavar="MODEL", help=model_help)
    p.add_argument("--t-end", type=float, help="horizon in s (default: the model file's t_end, else 1)")
    p.add_argument("--samples", type=int, default=501, help="output samples (default 501)")
    p.add_argument("--set", action="append", metavar="PARAM=VALUE", help="override a parameter (repeatable)")
    p.add_argument("--out", help="CSV file (default: stdout)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file (never an input)")
    p.set_defaults(run=cmd_simulate)

    for name, helptext in (("detect", "residuals, robust thresholds and alarms on recorded data"),
                           ("prognose", "estimate a degrading parameter and predict the RUL from recorded data")):
        p = sub.add_parser(name, help=helptext)
        p.add_argument("model", metavar="MODEL", help=model_help)
        p.add_argument("data", metavar="DATA.csv", help="CSV with a column t and one per signal")
        p.add_argument("--arr", help="use only this ARR (default: all; for prognose the first sensitive one)")
        p.add_argument("--margin", type=float, help="noise margin added to the thresholds (default: calibrated)")
        p.add_argument("--calibrate", type=float, metavar="T",
                       help="calibrate the margin on t <= T, assumed fault-free (default: the first 20 %%)")
        p.add_argument("--k", type=float, default=4.0, help="margin = k robust std of the residual (default 4)")
        p.add_argument("--persistence", type=int, default=5,
                       help="consecutive violations for an alarm (default 5; detect: at least half the derivative "
                            "window)")
        if name == "detect":
            p.add_argument("--window", type=int, help="Savitzky-Golay window for derivatives (odd; default: "
                                                      "chosen per ARR from the record)")
            p.add_argument("--integrals", choices=("auto", "avoid", "keep"), default="auto",
                           help="auto: per ARR, the form that detects the smallest changes on the record "
                                "(default); avoid: differentiate an ARR that would integrate measured signals; "
                                "keep: keep the integrals")
        else:
            p.add_argument("--window", type=int, help="Savitzky-Golay window for derivatives (odd; default 11)")
            p.add_argument("--integrals", choices=("avoid", "keep"), default="avoid",
                           help="avoid: differentiate an ARR that would integrate measured signals (default); keep: "
                                "keep the integrals (better on long records sampled fast, where a second "
                                "derivative of the noise is larger than the integral's random walk)")
        p.add_argument("--resample", action="store_true",
                       help="put a record with uneven steps on a uniform grid of its median step (linear "
                            "interpolation within runs of data, never across a gap)")
        p.add_argument("--out", help="output directory (new or empty, unless --force)")
        p.add_argument("--force", action="store_true",
                       help="write into a non-empty --out directory, replacing files of the same names")
        p.set_defaults(run=cmd_detect if name == "detect" else cmd_prognose)
    p.add_argument("--fail", action="append", required=True, metavar="PARAM=VALUE",
                   help="failure value of a parameter that can fail (repeatable); the candidates are those whose "
                        "signature matches the ARRs that fired")
    p.add_argument("--candidate", help="only this candidate (it needs a failure value; a bare --fail VALUE is its)")
    p.add_argument("--degradation", choices=("exponential", "linear", "power"), action="append",
                   help="a law that competes (repeatable; default: linear, exponential and power compete on "
                        "evidence); power: a power of the time since onset, its exponent estimated too")
    p.add_argument("--sensors", action=argparse.BooleanOptionalAction, default=True,
                   help="weigh a bias, drift or gain of each sensor consistent with the ARRs that fired too "
                        "(default; --no-sensors: the sensors are healthy)")
    p.add_argument("--pairs", action=argparse.BooleanOptionalAction, default=False,
                   help="weigh two parameters wearing at once too (the resample-move filter only), declared only when "
                        "the data demand two faults; the RUL is the first failure's (default: one fault)")
    p.add_argument("--direction", choices=("up", "down"), help="check that --candidate's failure value lies on "
                   "this side of nominal")
    p.add_argument("--rate", type=float, nargs=2, metavar=("LO", "HI"),
                   help="uniform prior interval of the rate (default: the life from nominal to failure "
                        "log-uniform over 10 to 1e5 filter steps)")
    p.add_argument("--particles", type=int, default=500, help="particles per hypothesis (default 500)")
    p.add_argument("--filter", choices=("resample-move", "sir"), default="resample-move",
                   help="resample-move (the default): the law's parameters weighed on the whole history, moved "
                        "by MCMC, with the residual noise measured on the healthy stretch; a law the data "
                        "contradict is reported inadequate.  sir: the random-walk particle filter of Jha et al. "
                        "2016 (collapses on a clean residual; no adequacy check)")
    p.add_argument("--dt", type=float, help="filter step in s, a multiple of the record's (default: one "
                   "derivative window of samples)")
    p.add_argument("--rul-every", type=int, default=10, help="predict the RUL every N filter steps (default 10)")
    p.add_argument("--horizon", type=float, help="RUL horizon cap in s (default 2000 filter steps)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")

    _fleet_parser(sub, model_help)

    from bgphm.demo import DEMOS

    listing = "\n".join(f"  {name:<13} {demo.description}" for name, demo in DEMOS.items())
    p = sub.add_parser("demo", help="run the whole chain on a built-in example and write every output",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Simulate an example with a degrading parameter, write the model, the record and "
                       "truth.json,\nthen run arr, detect and prognose on those files (each command is printed so "
                       f"it can be\nrerun by hand with the same results).\n\ndemos:\n{listing}")
    p.add_argument("name", nargs="?", default="dc-motor", metavar="NAME",
                   help=f"demo to run: {', '.join(DEMOS)} (default dc-motor)")
    p.add_argument("--out", default="results/demo", help="output directory (default results/demo; new or "
                   "empty, unless --force)")
    p.add_argument("--force", action="store_true",
                   help="write into a non-empty --out directory, replacing files of the same names")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    p.set_defaults(run=cmd_demo)
    return parser


def _fleet_parser(sub, model_help: str) -> None:
    p = sub.add_parser("fleet", help="monitor a fleet: records of many assets to Parquet tables of alarms, "
                       "estimates and RULs, on Dask workers")
    p.add_argument("model", metavar="MODEL", help=model_help)
    p.add_argument("records", metavar="RECORDS", help="a directory of CSV files, one per asset (the asset id is the "
                   "file name), or a Parquet file with a column 'asset' (its rows sorted by t or not)")
    p.add_argument("--fail", action="append", required=True, metavar="PARAM=VALUE",
                   help="failure value of a parameter that can fail (repeatable)")
    p.add_argument("--candidate", help="only this candidate (it needs a failure value)")
    p.add_argument("--degradation", choices=("exponential", "linear"),
                   help="only this law (default: linear and exponential compete on evidence)")
    p.add_argument("--calibrate", type=float, required=True, metavar="T",
                   help="every record is fault-free for t <= T: the noise and margins are calibrated there, and "
                        "alarms there start nothing")
    p.add_argument("--calibrate-assets", type=int, default=10, metavar="N",
                   help="calibrate on the first N records by asset id, the median per ARR (default 10)")
    p.add_argument("--arr", help="use only this ARR (default: every ARR sensitive to a candidate)")
    p.add_argument("--k", type=float, default=4.0, help="margin = k robust std of the residual (default 4)")
    p.add_argument("--persistence", type=int, default=5, help="consecutive violations for an alarm (default 5)")
    p.add_argument("--window", type=int, help="Savitzky-Golay window for derivatives (odd; default 11)")
    p.add_argument("--integrals", choices=("avoid", "keep"), default="avoid",
                   help="as for prognose: avoid (differentiate) or keep the integrals of measured signals")
    p.add_argument("--particles", type=int, default=500, help="particles per hypothesis (default 500)")
    p.add_argument("--dt", type=float, help="filter step in s, a multiple of the records' (default: one "
                   "derivative window of samples)")
    p.add_argument("--rul-every", type=int, default=10, help="predict the RUL every N filter steps (default 10)")
    p.add_argument("--horizon", type=float, help="RUL horizon cap in s (default 2000 filter steps)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0); each asset's draws depend only on "
                   "it, the asset id and the step")
    p.add_argument("--out", required=True, help="output directory (new or empty, unless --force)")
    p.add_argument("--force", action="store_true", help="write into a non-empty --out directory (a previous "
                   "fleet run's tables there are replaced, whole, when this one ends)")
    p.add_argument("--on-bad-record", choices=("stop", "skip"), default="stop",
                   help="a record that cannot be used (unreadable, a column without a value, a stuck sensor, too "
                   "short): stop the run naming it (default), or skip the asset and list it with the reason in "
                   "summary.json")
    p.add_argument("--resume", action="store_true", help="go on with the run interrupted in --out: the same "
                   "options and records, its finished shards kept (checked by SHA-256), the same tables as "
                   "an uninterrupted run")
    p.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler, e.g. tcp://10.0.0.5:8786 "
                   "(default: a local cluster of --workers processes)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the local cluster (default 2; 0 runs "
                   "every asset in this process, without Dask)")
    p.add_argument("--shard-size", type=int, metavar="N", help="assets per task (default: a quarter of each "
                   "worker's share, at most 1000); the results do not depend on it")
    p.set_defaults(run=cmd_fleet, margin=None, direction=None)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``bgphm`` console script; returns the exit code.

    Commands: ``arr`` (the ARR report), ``simulate``, ``detect``, ``prognose``, ``fleet`` and ``demo``; ``bgphm
    COMMAND --help`` lists each one's options.  Exit codes: 0 success, 2 bad usage or bad input (one
    line on stderr naming the file, line, column, node or parameter), 1 anything else, including an
    interrupted run.  Progress goes to stderr unless ``--quiet``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "rlc.csv"
    >>> main(["--quiet", "simulate", "rlc", "--t-end", "0.1", "--samples", "11",
    ...       "--out", str(out)])  # doctest: +ELLIPSIS
    wrote ...rlc.csv
    0
    >>> out.read_text().splitlines()[0]
    't,V,i,v_C'
    >>> main(["--quiet", "simulate", "no-such-model.json"])   # exit code 2, message on stderr
    2
    """
    with terminal_streams():  # a file name's escape sequence is shown, never obeyed (argparse's messages too)
        args = build_parser().parse_args(argv)  # exits with 2 on bad usage
        return _run(args, Progress(args.quiet))


def _run(args, progress: Progress) -> int:
    """Run the command; the exit code, and one line on stderr for an error."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")  # each distinct warning once, as one line without a source path
            warnings.showwarning = _warning_line
            _check_options(args)
            return args.run(args, progress)
    except SettingError as exc:  # a setting that does not fit the input: named as the option that gave it
        print(f"bgphm: error: {_one_line(exc.naming(_option))}", file=sys.stderr)
        return EXIT_USAGE
    except PHMError as exc:  # bad usage or bad input: a model, a record, equations, a simulation
        print(f"bgphm: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("bgphm: interrupted", file=sys.stderr)
        return EXIT_FAILURE
    except Exception as exc:  # anything else is a bug or an environment problem: exit 1
        if args.debug:
            raise
        print(f"bgphm: {type(exc).__name__}: {_one_line(exc)} (run with --debug for the traceback)", file=sys.stderr)
        return EXIT_FAILURE


def _check_options(args) -> None:
    """The checks of single options that need no file: a UsageError naming the option."""
    if getattr(args, "persistence", 1) < 1:
        raise UsageError(f"--persistence must be at least 1, got {args.persistence}")
    if getattr(args, "margin", None) is not None and not (math.isfinite(args.margin) and args.margin >= 0):
        raise UsageError(f"--margin must be a finite non-negative number, got {args.margin}")
    if not (math.isfinite(getattr(args, "k", 1.0)) and getattr(args, "k", 1.0) > 0):
        raise UsageError(f"--k must be a positive number of standard deviations, got {args.k}")
    if getattr(args, "calibrate", None) is not None and not math.isfinite(args.calibrate):
        raise UsageError(f"--calibrate must be a finite time in s, got {args.calibrate}")
    if not 0 <= getattr(args, "seed", 0) < 2**63:
        raise UsageError(f"--seed must be an integer in [0, 2**63), got {args.seed}")
    if not 2 <= getattr(args, "particles", 2) <= MAX_PARTICLES:
        raise UsageError(f"--particles must be in [2, {MAX_PARTICLES}], got {args.particles}")
    if getattr(args, "rul_every", 1) < 1:
        raise UsageError(f"--rul-every must be at least 1 filter step, got {args.rul_every}")
    for option, low in (("workers", 0), ("shard_size", 1), ("calibrate_assets", 1)):
        value = getattr(args, option, None)
        if value is not None and value < low:
            raise UsageError(f"--{option.replace('_', '-')} must be at least {low}, got {value}")
    for option in ("horizon", "dt"):
        value = getattr(args, option, None)
        if value is not None and not (math.isfinite(value) and value > 0):
            raise UsageError(f"--{option} must be a positive number of seconds, got {value}")


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """``warnings.showwarning`` for the commands: ``bgphm: warning: ...`` on one line, no source path."""
    print(f"bgphm: warning: {_one_line(message)}", file=sys.stderr, flush=True)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
