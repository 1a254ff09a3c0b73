"""``bgphm calibrate``: a model's parameters from healthy records, validated on held-out ones, written as a JSON
model with its provenance (:func:`diagnosis.estimate_parameters`, :func:`diagnosis.validate_calibration`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bgphm.errors import EXIT_OK, UsageError
from bgphm.files import check_output, file_digest, input_files, write_text
from bondgraph.errors import SettingError
from bondgraph.io import load_model, to_json

from ._inputs import load_arrs, load_record
from ._outputs import units_of, vars_of
from ._progress import Progress

__all__ = ["Plan", "calibration_block", "plain", "plan_of", "run"]

#: What the estimator does, in words, for the provenance block.
ESTIMATOR = ("diagnosis.estimate_parameters: least squares of the ARRs' nominal residuals, integrated over windows, "
             "over every training record, each ARR weighed by its noise, the datasheet values as a prior")


@dataclass
class Plan:
    """The files of a run, checked before any work: training and held-out records, the model and report paths."""

    training: list
    held_out: list
    out: Path
    report: Path


def run(args, progress: Progress) -> int:
    """``bgphm calibrate``: estimate on the training records, build the boxes, validate on the held-out records,
    print the table, write the calibrated model and its report; returns 0.

    Every bad input (a file, an option, a parameter) raises before anything is written, and both outputs are
    composed whole before the first is written.
    """
    from diagnosis import validate_calibration

    plan = plan_of(args, progress)
    spec = load_model(args.model)
    model = spec.model
    _check_parameters(args.parameters, model)
    arrs = load_arrs(spec, progress, None)
    _check_seen(args.parameters, arrs)
    training = [load_record(path, arrs, progress, extra=model.inputs) for path in plan.training]
    held_out = [load_record(path, arrs, progress, extra=model.inputs) for path in plan.held_out]
    fit, boxes = _estimate(model, arrs, training, plan, args, progress)
    calibrated = fit.model(model, boxes)
    validation = None
    if held_out:
        progress(f"validating on {len(held_out)} held-out record(s)")
        validation = validate_calibration(model, calibrated, _names(plan.training, training),
                                          _names(plan.held_out, held_out))
    for line in _table(fit, boxes) + _validation_lines(validation):
        print(line)
    block = calibration_block(args, plan, spec, fit, boxes, validation, training, held_out)
    text = to_json(calibrated, calibration=block, **_storable(spec, progress))
    from bgphm.run_report import calibration_page

    page = calibration_page(model, calibrated, fit, boxes, validation, block,
                            units=units_of(model, arrs), settings=vars_of(args))
    html = page.html()
    for path, content in ((plan.out, text), (plan.report, html)):
        print(f"wrote {write_text(path, content)}")
    return EXIT_OK


# ------------------------------------------------------------------------------------------- the files

def plan_of(args, progress: Progress) -> Plan:
    """The training and held-out records and the output paths, checked (a :class:`UsageError` names the option
    or the file)."""
    records = [Path(p) for p in args.records]
    _no_repeats(records, "HEALTHY.csv")
    if args.validate:
        held_out = [Path(p) for p in args.validate]
        _no_repeats(held_out, "--validate")
        shared = {p.resolve() for p in records} & {p.resolve() for p in held_out}
        if shared:
            raise UsageError(f"--validate {next(p for p in held_out if p.resolve() in shared)}: also a training "
                             "record; a held-out record must be one the estimate has not seen")
        training = records
    else:
        count = args.hold_out if args.hold_out is not None else (1 if len(records) >= 2 else 0)
        if count < 0 or count >= len(records):
            raise UsageError(f"--hold-out {count}: must lie in [0, {len(records) - 1}], leaving at least one of the "
                             f"{len(records)} record(s) to estimate on")
        if args.hold_out is None and count == 0:
            progress("one record: nothing is held out, so no validation (give two records or more, or --validate "
                     "FILE.csv)")
        training, held_out = records[:len(records) - count], records[len(records) - count:]
    if args.boxes == "records" and len(training) < 2:
        hint = " (the last record is held out by default: give --hold-out 0, or more records)" if held_out and \
            args.hold_out is None and not args.validate else ""
        raise UsageError(f"--boxes records: needs two training records or more (one estimate per record), got "
                         f"{len(training)}{hint}")
    inputs = input_files(args.model, *training, *held_out)
    if not args.out.lower().endswith(".json"):
        raise UsageError(f"--out {args.out}: the calibrated model is JSON; give a name ending in .json (the "
                         "commands read a model by its suffix)")
    out = check_output(args.out, kind="file", inputs=inputs, force=args.force)
    report = Path(args.report) if args.report else out.with_suffix(".html")
    if report.resolve() == out.resolve():
        raise UsageError(f"--report {args.report}: the same file as --out")
    report = check_output(report, kind="file", inputs=inputs, force=args.force,
                          option="--report" if args.report else "the report (--out with .html)")
    return Plan(training, held_out, out, report)


def _no_repeats(paths: list, option: str) -> None:
    seen = set()
    for path in paths:
        if path.resolve() in seen:
            raise UsageError(f"{option} {path}: given twice (each record counts once)")
        seen.add(path.resolve())


def _check_parameters(parameters, model) -> None:
    for name in parameters or ():
        if name not in model.parameters:
            raise UsageError(f"--parameters {name!r}: the model has no such parameter (parameters: "
                             f"{', '.join(model.parameters)})")


def _check_seen(parameters, arrs: list) -> None:
    """Some parameter asked for must be in an ARR: the records say nothing of the others."""
    seen = {p for arr in arrs for p in arr.parameters}
    if parameters and not seen & set(parameters):
        raise UsageError(f"--parameters {' '.join(parameters)}: in no ARR, so no record can tell anything of "
                         f"{'it' if len(parameters) == 1 else 'them'} (the ARRs hold {', '.join(sorted(seen))})")


def _names(paths: list, records: list) -> dict:
    """File name -> record (the whole path where two files share a name)."""
    names = [p.name for p in paths]
    keys = names if len(set(names)) == len(names) else [str(p) for p in paths]
    return dict(zip(keys, records))


# ------------------------------------------------------------------------------------------- the estimate

def _estimate(model, arrs, training: list, plan: Plan, args, progress: Progress):
    """The pooled estimate over the training records and the boxes (``--boxes``)."""
    from diagnosis import estimate_parameters, uncertainty_boxes

    options = {"arrs": arrs, "level": args.level, "prior": args.prior, "window": args.window,
               "quadrature": args.quadrature}
    progress(f"estimating {', '.join(args.parameters) if args.parameters else 'the parameters'} on "
             f"{len(training)} training record(s)")
    fit = _estimated(lambda: estimate_parameters(model, training, args.parameters, **options), plan.training)
    if not fit.intervals:
        raise UsageError(_nothing_estimated(fit, args.parameters))
    per_record = []
    if args.boxes == "records":
        for path, record in zip(plan.training, training):
            progress(f"estimating on {path} alone (--boxes records)")
            per_record.append(_estimated(lambda r=record: estimate_parameters(model, [r], args.parameters,
                                                                               **options), [path]))
    if args.boxes == "set-membership":
        progress("sizing the smallest boxes that keep the training records inside the thresholds")
    return fit, uncertainty_boxes(fit, args.boxes, per_record=per_record, model=model, records=training)


def _estimated(estimate, paths: list):
    """``estimate()``, with a record that gives no sample named by its file."""
    try:
        return estimate()
    except SettingError as exc:
        if exc.setting != "records":
            raise
        files = ", ".join(str(p) for p in paths)
        raise UsageError(exc.naming(lambda _: f"HEALTHY.csv {files}")) from None


def _nothing_estimated(fit, parameters) -> str:
    ident = fit.identifiability
    why = []
    if ident is not None and ident.unseen:
        why.append(f"in no ARR: {', '.join(ident.unseen)}")
    if ident is not None and ident.combinations:
        why.append("seen only together or less well than the datasheet: "
                   + "; ".join(", ".join(c["parameters"]) for c in ident.combinations))
    asked = f"--parameters {' '.join(parameters)}" if parameters else "the model"
    return f"{asked}: no parameter can be estimated from these records ({'; '.join(why) or 'none identified'})"


# ------------------------------------------------------------------------------------------- what is printed

def _table(fit, boxes: dict) -> list[str]:
    """The estimates (parameter, datasheet, estimate, interval, change), then what the records cannot tell."""
    level = f"{fit.level:.0%}".replace("%", " %")
    rows = [("parameter", "datasheet", "estimate", f"{level} interval", "change", "box")]
    for name, (lo, hi) in fit.intervals.items():
        box = boxes.get(name)
        rows.append((name, f"{fit.datasheet[name]:.4g}", f"{fit.values[name]:.4g}", f"[{lo:.4g}, {hi:.4g}]",
                     _change(fit.values[name], fit.datasheet[name]),
                     f"[{box[0]:+.2%}, {box[1]:+.2%}]".replace("%", " %") if box else "-"))
    widths = [max(len(row[k]) for row in rows) for k in range(len(rows[0]))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in rows]
    ident = fit.identifiability
    for group in (ident.combinations if ident else []):
        if group.get("weak"):
            lines.append(f"told less well by the records than by the datasheet: {', '.join(group['parameters'])}; "
                         f"{group['kept']} kept at its datasheet value (its uncertainty widens the intervals)")
            continue
        lines.append(f"seen only together: {', '.join(group['parameters'])} (the records fix {group['expression']}); "
                     f"{group['kept']} kept at its datasheet value")
    if ident and ident.unseen:
        lines.append(f"in no ARR, kept at the datasheet value: {', '.join(ident.unseen)}")
    return lines


def _change(value: float, datasheet: float) -> str:
    return f"{value / datasheet - 1.0:+.1%}".replace("%", " %") if datasheet else "-"


def _validation_lines(validation) -> list[str]:
    if validation is None:
        return ["no held-out record: no validation"]
    before, after = validation.before, validation.after
    count = len(validation.held_out)
    alarms = [f"{len(figures.false_alarms)} of {count}" for figures in (before, after)]
    lines = [f"validation on {count} held-out record(s), margins calibrated on {len(validation.training)} training "
             "record(s):", f"  {'':<30}{'datasheet':<24}calibrated",
             f"  {'false alarms':<30}{alarms[0]:<24}{alarms[1]}", "  smallest detectable change"]
    for name in after.smallest_changes:
        lines.append(f"    {name:<28}{_percent(before.smallest_changes.get(name)):<24}"
                     f"{_percent(after.smallest_changes[name])}")
    lines.append(f"  residual whiteness (Ljung-Box p over {validation.lags} lags)")
    for name, white in after.whiteness.items():
        lines.append(f"    {name:<28}{_whiteness(before.whiteness.get(name)):<24}{_whiteness(white)}")
    for label, figures in (("datasheet", before), ("calibrated", after)):
        for record, arrs in figures.alarms.items():
            if arrs:
                lines.append(f"  {label}: false alarm on {record} ("
                             + ", ".join(f"{a} at t = {t:g} s" for a, t in arrs.items()) + ")")
        for name, why in figures.undecided.items():
            lines.append(f"  {label}: {name} undecided ({why})")
    return lines


def _percent(value) -> str:
    return "none" if value is None or not math.isfinite(value) else f"{value:.1%}".replace("%", " %")


def _whiteness(white) -> str:
    if white is None or not math.isfinite(white.p_value):
        return "-"
    return f"{white.p_value:.2g} ({'white' if white.white else 'not white'})"


# ------------------------------------------------------------------------------------------- what is written

def calibration_block(args, plan: Plan, spec, fit, boxes: dict, validation, training: list, held_out: list) -> dict:
    """The ``graph.calibration`` block of the calibrated model: what made it (tool, version, date), from what
    (the datasheet model and its SHA-256, each record's name, role, samples and SHA-256), how (the method and
    its settings) and what it found (estimates, intervals, boxes, what the records cannot tell, validation)."""
    from bondgraph.provenance import generated_at, model_sha256, tool_version

    source = Path(args.model).name if Path(args.model).is_file() else args.model
    records = [{"name": path.name, "role": role, "samples": len(record), "sha256": file_digest(path)}
               for role, paths, loaded in (("training", plan.training, training), ("held-out", plan.held_out, held_out))
               for path, record in zip(paths, loaded)]
    summary = fit.as_dict()
    return plain({
        "tool": "bondgraph-phm", "version": tool_version(), "date": generated_at(),
        "datasheet": {"model": spec.model.name, "source": source, "sha256": model_sha256(spec.model)},
        "records": records,
        "method": {"estimator": ESTIMATOR, "parameters": args.parameters, "level": fit.level, "prior": args.prior,
                   "boxes": args.boxes, "window": args.window, "quadrature": args.quadrature,
                   "samples": fit.samples},
        "estimates": summary["parameters"], "boxes": {p: list(b) for p, b in boxes.items()},
        "combinations": summary["combinations"], "unseen": summary["unseen"], "condition": summary["condition"],
        "residual_std": summary["residual_std"],
        "validation": None if validation is None else validation.as_dict(),
    })


def plain(value):
    """``value`` as JSON data: numpy numbers as Python ones, tuples as lists, NaN and infinities as None.

    >>> plain({"a": (np.float64(1.5), float("inf")), "b": [np.int64(2)]})
    {'a': [1.5, None], 'b': [2]}
    """
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def _storable(spec, progress: Progress) -> dict:
    """The model's default run as JSON can hold it (numbers and expressions of t); a function of time (a
    controller, Python code) is left out, and said."""
    from bondgraph.inputs import InputExpression

    inputs = {}
    for name, value in spec.inputs.items():
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if number or isinstance(value, (InputExpression, str)):
            inputs[name] = value
        else:
            progress(f"the model's input {name!r} is a {type(value).__name__}, which JSON cannot hold: the calibrated "
                     "model has no default for it")
    x0 = {k: v for k, v in spec.x0.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
    return {"inputs": inputs, "t_end": spec.t_end, "x0": x0}
