"""``bgphm simulate``: a model's record, as CSV, with the faults and inputs the options inject."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from bgphm.errors import EXIT_OK, UsageError
from bgphm.files import check_output, csv_text, input_files, write_text
from bondgraph.errors import PHMError
from bondgraph.io import ModelSpec, load_model

from ._inputs import (
    assignments,
    has_value,
    parameter_item,
)
from ._outputs import emit, output_file, units_of, vars_of
from ._progress import Progress

__all__ = ["run"]

#: The options of the sensor faults, their kind (:class:`diagnosis.records.SensorFault`) and what VALUE is.
_SENSOR_OPTIONS = (("bias", "VALUE"), ("drift", "RATE"), ("gain", "FACTOR"))


def run(args, progress: Progress) -> int:
    """``bgphm simulate``: simulate ``args.model`` over ``[0, t_end]`` and write its record as CSV; returns 0.

    ``args.samples`` evenly spaced times, parameters overridden by ``--set`` or degrading by ``--degrade``,
    inputs from the model file, ``--inputs`` and ``--input``; then the sensors' ``--gain``, ``--bias`` and
    ``--drift`` and their ``--noise``.  The CSV goes to stdout or ``args.out``.  Raises :class:`UsageError`
    naming the option and the parameter or signal for a bad option, or an input signal without a value.
    """
    from bondgraph.simulation import DEFAULT_T_END, MIN_SPAN, check_sample_count, simulate
    from diagnosis.records import add_noise, add_sensor_faults, as_record

    out = output_file(args)
    report = (check_output(args.report, kind="file", inputs=input_files(args.model, args.inputs), force=args.force,
                           option="--report") if args.report else None)
    if report is not None and out is not None and report.resolve() == out.resolve():
        raise UsageError(f"--report {args.report} is the --out file too; give two names")
    check_sample_count(args.samples, "--samples", least=3)
    spec = load_model(args.model)
    t_end = args.t_end if args.t_end is not None else (spec.t_end or DEFAULT_T_END)
    if not (math.isfinite(t_end) and t_end >= MIN_SPAN):
        raise UsageError(f"--t-end must be a number of seconds of at least {MIN_SPAN:g}, got {t_end:g}")
    parameters = assignments(args.set, spec.model.parameters, "--set")
    degraded = _degradations(args.degrade, spec, t_end, parameters)
    inputs = {**spec.inputs, **_input_signals(args.inputs, args.input, spec)}
    missing = [s for s in spec.model.inputs if s not in inputs and not has_value(spec.model, s)]
    if missing:
        raise UsageError(f"{spec.source}: no value for the input signal(s) {missing}; give them in the model file "
                         "('inputs' in a Python file, graph.inputs in JSON), with --input or with --inputs")
    signals = [*spec.model.inputs, *spec.model.outputs]
    faults = _sensor_faults(args, signals)
    noise = _sensor_noise(args.noise, signals)
    progress(f"simulating {spec.model.name!r} over [0, {t_end:g}] s"
             + "".join(f"; {name} {law}" for name, law in degraded.items()))
    parameters.update({name: law.truth(spec.model.parameters[name]) for name, law in degraded.items()})
    result = simulate(spec.model, (0.0, t_end), inputs, x0=spec.x0, parameters=parameters,
                      t_eval=np.linspace(0.0, t_end, args.samples))
    columns = result.record()
    if faults or noise:
        record = as_record(columns, name=spec.model.name)
        if faults:
            progress("sensor faults: " + ", ".join(f"{f.signal} {f.kind} {f.size:g} from {f.onset:g} s"
                                                   for f in faults))
            record = add_sensor_faults(record, faults)
        if noise:
            progress(f"sensor noise (seed {args.seed}): " + ", ".join(f"{s} std {v:g}" for s, v in noise.items()))
            record = add_noise(record, noise, seed=args.seed)
        columns = {"t": record.t, **record.columns}
    emit(csv_text(columns), out)
    if report is not None:
        from bgphm.run_report import simulation_page

        injected = [f"{name}: {law}" for name, law in degraded.items()]
        injected += [f"sensor {f.signal}: {f.kind} {f.size:g} from {f.onset:g} s" for f in faults]
        injected += [f"sensor {s}: noise std {v:g} (seed {args.seed})" for s, v in noise.items()]
        page = simulation_page(spec.model, columns, units=units_of(spec.model, []), settings=vars_of(args),
                               faults=injected)
        print(f"wrote {write_text(report, page.html())}")
    return EXIT_OK


def _degradations(items: Sequence[str] | None, spec: ModelSpec, t_end: float, fixed: dict) -> dict:
    """``--degrade PARAM=LAW:RATE@ONSET`` items as {parameter: Degradation}, each checked against the model: a
    parameter it has, not also given by ``--set`` (``fixed``) nor twice, a law that keeps it in its physical
    domain up to ``t_end``."""
    from bondgraph.scenarios import parse_degradation

    parameters = spec.model.parameters
    out = {}
    for item in items or ():
        name, text = parameter_item(item, parameters, "--degrade", "PARAM=LAW:RATE@ONSET, e.g. b=exp:0.05@10")
        if name in fixed:
            raise UsageError(f"--degrade {item!r}: {name} is also set by --set; give one of them")
        if name in out:
            raise UsageError(f"--degrade {item!r}: {name} has a degradation already; give one per parameter")
        where = f"--degrade {name}={text.strip()}"
        law = parse_degradation(text, where=where)
        law.check_domain(parameters[name], spec.model.domains.get(name, (-math.inf, math.inf)), t_end, where=where)
        out[name] = law
    return out


def _input_signals(path: str | None, items: Sequence[str] | None, spec: ModelSpec) -> dict:
    """The inputs ``--inputs FILE.csv`` and ``--input SIGNAL=EXPR`` give, as {signal: callable of t}; an input
    given by both, twice, or that is not an input of the model is an error naming it."""
    from bondgraph.inputs import InputExpression

    out = _tabulated(path, spec) if path is not None else {}
    given: set = set()
    for item in items or ():
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not text.strip():
            raise UsageError(f"--input {item!r}: expected SIGNAL=EXPR, an expression of t such as U='12*step(t - 1)'")
        _check_input(name, spec, f"--input {item!r}")
        if name in given:
            raise UsageError(f"--input {item!r}: {name} is given twice")
        if name in out:
            raise UsageError(f"--input {item!r}: {name} is a column of --inputs {path} too; give one of them")
        out[name] = InputExpression(text, where=f"--input {name}")
        given.add(name)
    return out


def _tabulated(path: str, spec: ModelSpec) -> dict:
    """Each column of the CSV file but ``t`` as the input of that name (:class:`bondgraph.inputs.TabulatedInput`)."""
    from bondgraph.inputs import TabulatedInput
    from diagnosis.csv_reading import read_csv

    try:
        record = read_csv(path)
    except PHMError as exc:  # it names the file, the line and the column
        raise UsageError(f"--inputs: {exc}") from None
    if not record.signals:
        raise UsageError(f"--inputs {path}: no column but t; give one column per input signal "
                         f"({', '.join(spec.model.inputs)})")
    for column in record.signals:
        _check_input(column, spec, f"--inputs {path}: column {column!r}")
    return {column: TabulatedInput(record.t, record[column], where=f"--inputs {path}: column {column!r}")
            for column in record.signals}


def _check_input(name: str, spec: ModelSpec, where: str) -> None:
    if name not in spec.model.inputs:
        raise UsageError(f"{where}: {name!r} is not an input signal of the model (inputs: "
                         f"{', '.join(spec.model.inputs) or 'none'})")


def _sensor_faults(args, signals: Sequence[str]) -> list:
    """``--gain``, ``--bias`` and ``--drift`` items ``SIGNAL=VALUE@ONSET`` as :class:`diagnosis.records.SensorFault`
    (one of each kind per signal, an onset 0 when it is left out)."""
    from diagnosis.records import SensorFault

    faults = []
    for kind, value in _SENSOR_OPTIONS:
        option = f"--{kind}"
        seen: set = set()
        for item in getattr(args, kind) or ():
            name, size, onset = _signal_item(item, option, f"SIGNAL={value}@ONSET", signals)
            if name in seen:
                raise UsageError(f"{option} {item!r}: {name} has a {kind} already; give one per signal")
            seen.add(name)
            faults.append(SensorFault(name, kind, _number(size, value.lower(), option, item),
                                      _number(onset, "onset", option, item) if onset is not None else 0.0))
    return faults


def _sensor_noise(items: Sequence[str] | None, signals: Sequence[str]) -> dict:
    """``--noise SIGNAL=STD`` items as {signal: standard deviation}, each a finite number >= 0, once a signal."""
    noise = {}
    for item in items or ():
        name, std, onset = _signal_item(item, "--noise", "SIGNAL=STD", signals)
        if onset is not None:
            raise UsageError(f"--noise {item!r}: the noise has no onset (it is there from the start): give SIGNAL=STD")
        if name in noise:
            raise UsageError(f"--noise {item!r}: {name} has a noise already; give one per signal")
        noise[name] = _number(std, "standard deviation", "--noise", item)
        if noise[name] < 0:
            raise UsageError(f"--noise {item!r}: the standard deviation must be >= 0, got {std.strip()}")
    return noise


def _signal_item(item: str, option: str, form: str, signals: Sequence[str]) -> tuple[str, str, str | None]:
    """``SIGNAL=VALUE[@ONSET]``: the signal (checked against the record's), the value text, the onset text or None."""
    name, sep, rest = item.partition("=")
    name = name.strip()
    if not sep:
        raise UsageError(f"{option} {item!r}: expected {form}")
    if name not in signals:
        raise UsageError(f"{option} {item!r}: the record has no signal {name!r} (signals: {', '.join(signals)})")
    value, at, onset = rest.partition("@")
    return name, value, onset if at else None


def _number(text: str, what: str, option: str, item: str) -> float:
    try:
        number = float(text)
    except ValueError:
        raise UsageError(f"{option} {item!r}: the {what} {text.strip()!r} is not a number") from None
    if not math.isfinite(number):
        raise UsageError(f"{option} {item!r}: the {what} must be finite, got {text.strip()!r}")
    return number
