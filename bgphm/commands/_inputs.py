"""What the commands read: models' ARRs, records, failure values, candidates, laws, settings."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from bgphm.errors import UsageError
from bondgraph.io import ModelSpec, load_model
from diagnosis import DetectionSettings
from diagnosis.csv_reading import read_csv
from diagnosis.records import Record, RecordError, RecordWarning, gaps

from ._progress import Progress

__all__ = [
    "MAX_TRUTH_BYTES", "TRUTH_FIELDS", "assignments", "candidates_of", "check_truth", "csv_header",
    "detection_settings", "failures_of", "has_value", "laws_of", "load_arrs", "load_record", "named_arr",
    "parameter_item",
    "read_fleet_truth", "read_truth", "truth_values", "what_can_fail",
]


def load_arrs(spec: ModelSpec, progress: Progress, name: str | None, integrals: str = "avoid",
              simulated: bool = False) -> list:
    from diagnosis.derivation import ARRWarning, derive_arrs

    progress(f"deriving the ARRs of {spec.model.name!r}")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ARRWarning)
        arrs = derive_arrs(spec.model, integrals=integrals, simulated=simulated)
    for w in caught:
        progress(f"warning: {w.message}")
    if not arrs:
        raise UsageError(f"{spec.source}: the model gives no ARR (it needs De/Df sensors on its junctions)")
    return arrs if name is None else [named_arr(arrs, name)]


def named_arr(arrs: list, name: str):
    for arr in arrs:
        if arr.name == name:
            return arr
    raise UsageError(f"--arr {name!r}: no such ARR (available: {', '.join(a.name for a in arrs)})")


def load_record(path, arrs: list, progress: Progress, resample: bool = False, extra: Sequence[str] = ()) -> Record:
    """The record's columns for the ARRs' signals (and those of ``extra`` it holds: inputs whose steps matter)."""
    signals = list(dict.fromkeys(s for arr in arrs for s in arr.signals))
    present = csv_header(path) if extra else []
    signals += [s for s in extra if s in present and s not in signals]
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", RecordWarning)
            record = read_csv(path, signals)
            if resample:
                from diagnosis.uniform_grid import resample as uniform

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


def csv_header(path) -> list[str]:
    """The column names of a CSV file's header row (empty if it cannot be read: read_csv says why)."""
    import csv

    try:
        with open(path, newline="", encoding="utf-8") as handle:
            return [c.strip() for c in next(csv.reader(handle), [])]
    except (OSError, UnicodeDecodeError, csv.Error):
        return []


def detection_settings(args) -> DetectionSettings:
    """``--calibrate``, ``--margin``, ``--k``, ``--persistence`` and ``--window`` as the library's settings."""
    return DetectionSettings(calibrate=args.calibrate, margin=getattr(args, "margin", None), k=args.k,
                             persistence=args.persistence, window=args.window)


def what_can_fail(args, progress: Progress) -> tuple:
    """``prognose`` and ``fleet``: the model, its ARRs, the failure values, the candidates and the laws."""
    spec = load_model(args.model)
    arrs = load_arrs(spec, progress, args.arr, args.integrals)
    parameters, domains = spec.model.parameters, spec.model.domains
    failures = failures_of(args, parameters, domains)
    candidates = candidates_of(args, arrs, failures, parameters)
    return spec, arrs, failures, candidates, laws_of(args)


def laws_of(args) -> list:
    """The competing laws: ``--degradation`` (once in ``fleet``, repeatable in ``prognose``), else the library's
    default (``fleet``: the laws with one rate)."""
    from prognosis.fleet import FLEET_LAWS
    from prognosis.isolation import LAWS

    if not args.degradation:
        return list(LAWS if args.command == "prognose" else FLEET_LAWS)
    return list(dict.fromkeys(args.degradation if isinstance(args.degradation, list) else [args.degradation]))


def failures_of(args, parameters: dict, domains: dict) -> dict:
    """``--fail`` as {parameter: failure value}: ``PARAM=VALUE`` items, or one VALUE for ``--candidate``, checked
    by the library (:func:`prognosis.check_failures`)."""
    from prognosis import check_failures

    if args.candidate is not None and args.candidate not in parameters:
        raise UsageError(f"--candidate {args.candidate!r}: the model has no such parameter "
                         f"(parameters: {', '.join(parameters)})")
    named = [item for item in args.fail if "=" in item]
    bare = [item for item in args.fail if "=" not in item]
    failures = assignments(named, parameters, "--fail")
    if bare:
        if args.candidate is None or len(bare) > 1:
            raise UsageError(f"--fail {bare[0]}: give PARAM=VALUE (repeatable), or one VALUE with --candidate")
        failures.update(assignments([f"{args.candidate}={bare[0]}"], parameters, "--fail"))
    check_failures(failures, parameters, domains, laws_of(args))
    return failures


def candidates_of(args, arrs: list, failures: dict, parameters: dict) -> list | None:
    """``--candidate`` checked by the library against the ARRs, the failure values and ``--direction``
    (:func:`prognosis.check_candidate`); None without it."""
    from prognosis import check_candidate

    if args.candidate is None:
        if args.direction is not None:
            raise UsageError("--direction checks the failure value of --candidate: give --candidate too")
        return None
    check_candidate(args.candidate, arrs, failures, args.direction)
    return [args.candidate]


def parameter_item(item: str, parameters, option: str, form: str = "PARAM=VALUE") -> tuple[str, str]:
    """``PARAM=TEXT`` split, the parameter checked against the model's; an error names the option and the item."""
    name, sep, value = item.partition("=")
    name = name.strip()
    if not sep:
        raise UsageError(f"{option} {item!r}: expected {form}")
    if name not in parameters:
        raise UsageError(f"{option} {item!r}: the model has no parameter {name!r} "
                         f"(parameters: {', '.join(parameters)})")
    return name, value


def assignments(items: Sequence[str] | None, parameters: dict, option: str) -> dict:
    out = {}
    for item in items or ():
        name, value = parameter_item(item, parameters, option)
        try:
            number = float(value)
        except ValueError:
            raise UsageError(f"{option} {item!r}: {value!r} is not a number") from None
        if not math.isfinite(number):
            raise UsageError(f"{option} {item!r}: the value must be finite")
        out[name] = number
    return out


def has_value(model, signal: str) -> bool:
    return any(e.signal == signal and e.value is not None for e in model.elements.values())


#: The largest ``--truth`` file read (a fleet's holds one entry per asset).
MAX_TRUTH_BYTES = 64 * 2**20
#: The fields of a truth entry and what each must be (``eol`` alone is required; null: no end of life).
TRUTH_FIELDS = {"eol": "the true end of life in s (a number, or null for an asset that does not fail)",
                "candidate": "the degrading parameter", "degradation": "its law", "nominal": "its nominal value",
                "rate": "the law's rate", "onset": "the onset in s", "exponent": "a power law's exponent",
                "failure_value": "the failure value"}


def read_truth(path: str, *, option: str = "--truth") -> dict:
    """A ``--truth`` JSON file (what ``bgphm demo`` writes as ``truth.json``): an object with ``eol``, the true end
    of life in s, and optionally the degradation (``candidate``, ``degradation``, ``nominal``, ``rate``,
    ``onset``, ``exponent``) that draws the parameter's true values.  Raises :class:`UsageError` naming the file
    and the field."""
    return check_truth(_json_file(path, option), f"{option} {path}")


def read_fleet_truth(path: str, *, option: str = "--truth") -> dict:
    """A fleet's ``--truth`` JSON file: an object mapping each asset id to its truth entry (as :func:`read_truth`
    reads one); an asset left out has no truth given."""
    data = _json_file(path, option)
    if not isinstance(data, dict):
        raise UsageError(f"{option} {path}: expected a JSON object mapping asset ids to truth entries")
    return {str(asset): check_truth(entry, f"{option} {path}: asset {asset!r}") for asset, entry in data.items()}


def _json_file(path: str, option: str):
    import json

    file = Path(path)
    if not file.is_file():
        raise UsageError(f"{option} {path}: no such file")
    if file.stat().st_size > MAX_TRUTH_BYTES:
        raise UsageError(f"{option} {path}: larger than {MAX_TRUTH_BYTES // 2**20} MiB")
    try:
        return json.loads(file.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UsageError(f"{option} {path}: not JSON ({exc})") from None


def check_truth(entry, where: str) -> dict:
    """One truth entry checked: known fields, a finite (or null) ``eol``, finite numbers, a known law."""
    from bondgraph.scenarios import DEGRADATION_LAWS

    if not isinstance(entry, dict):
        raise UsageError(f"{where}: expected a JSON object with 'eol' (the true end of life in s)")
    unknown = sorted(set(entry) - set(TRUTH_FIELDS) - {"noise_std", "seed"})
    if unknown:
        raise UsageError(f"{where}: unknown field {unknown[0]!r} (fields: {', '.join(TRUTH_FIELDS)})")
    if "eol" not in entry:
        raise UsageError(f"{where}: no 'eol' ({TRUTH_FIELDS['eol']})")
    for key in ("eol", "nominal", "rate", "onset", "exponent", "failure_value"):
        value = entry.get(key)
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise UsageError(f"{where}: {key!r} must be a finite number ({TRUTH_FIELDS[key]}), got {value!r}")
    if entry.get("degradation") is not None and entry["degradation"] not in DEGRADATION_LAWS:
        raise UsageError(f"{where}: 'degradation' {entry['degradation']!r} is not one of "
                         f"{', '.join(DEGRADATION_LAWS)}")
    if entry.get("candidate") is not None and not isinstance(entry["candidate"], str):
        raise UsageError(f"{where}: 'candidate' must be a parameter's name, got {entry['candidate']!r}")
    return dict(entry)


def truth_values(truth: dict, candidate):
    """The parameter's true values over time (a callable of t), when the truth says how ``candidate`` degrades;
    else None."""
    from bondgraph.scenarios import drift

    needed = ("candidate", "degradation", "nominal", "rate")
    if any(truth.get(k) is None for k in needed) or truth["candidate"] != candidate:
        return None
    return drift(truth["nominal"], truth["rate"], truth.get("onset") or 0.0, truth["degradation"],
                 truth.get("exponent") or 1.0)
