"""``bgphm detect``: residuals, thresholds and alarms on a record (:func:`diagnosis.detect`)."""

from __future__ import annotations

import json
import warnings

import numpy as np

from bgphm.errors import EXIT_OK
from bgphm.files import csv_text, write_text
from bondgraph.io import load_model
from diagnosis.records import RecordWarning

from ._inputs import (
    detection_settings,
    load_arrs,
    load_record,
)
from ._outputs import json_value, output_directory, units_of, vars_of, write_plots, write_report
from ._progress import Progress

__all__ = ["detectable_line", "evaluation_summary", "run"]


def run(args, progress: Progress) -> int:
    """``bgphm detect``: evaluate the ARRs (or ``--arr``) on the record ``args.data``, print each alarm; returns 0.

    :func:`diagnosis.detect` chooses each ARR's form and margin from the record (``--margin``, ``--window``
    and ``--integrals`` fix them); the split-half check refuses a calibration stretch that holds a fault.
    With ``--out``: ``detection.json``, ``residuals.csv`` and residual plots.
    """
    from diagnosis import detect

    settings = detection_settings(args)
    out = output_directory(args)
    spec = load_model(args.model)
    arrs = load_arrs(spec, progress, args.arr, "avoid" if args.integrals == "auto" else args.integrals,
                     simulated=args.simulated)
    record = load_record(args.data, arrs, progress, args.resample, extra=spec.model.inputs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RecordWarning)
        result = detect(spec.model, record, settings, integrals=args.integrals,
                        arrs=arrs if args.arr or args.integrals != "auto" or args.simulated else None)
    for w in caught:
        progress(f"warning: {w.message}")
    evaluations = result.evaluations
    summary = {"model": spec.model.name, "data": str(args.data), "samples": len(record),
               "arrs": {e.name: evaluation_summary(e) for e in evaluations}, **result.as_dict()}
    summary["alarming_arrs"] = [e.name for e in evaluations if e.detection_time is not None]
    summary["units"] = units_of(spec.model, arrs)
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
    print(detectable_line(result))
    if result.fired:
        print(f"faults consistent with {', '.join(result.isolating)}: {', '.join(result.candidates) or 'none'}")
    if out is not None:
        write_text(out / "detection.json", json.dumps(summary, indent=2, default=json_value))
        columns = {"t": record.t}
        for e in evaluations:
            # the threshold holds -r_n in [lower - margin, upper + margin]; written as the band on r_n itself
            columns.update({f"{e.name}.residual": e.residual, f"{e.name}.lower": -(e.upper + e.margin),
                            f"{e.name}.upper": -(e.lower - e.margin), f"{e.name}.alarm": e.alarm.astype(float)})
        write_text(out / "residuals.csv", csv_text(columns))
        written = [out / "detection.json", out / "residuals.csv"]
        written += write_plots("detection", out, evaluations, progress, {"units": summary["units"]["residuals"]})
        from bgphm.run_report import detection_page

        written.append(write_report(out, detection_page(spec.model, result.arrs or arrs, result, args.data,
                                                        units=summary["units"], settings=vars_of(args))))
        for path in written:
            print(f"wrote {path}")
    return EXIT_OK


def detectable_line(result) -> str:
    """``smallest detectable change: b 12 %, J 85 %, k_m none`` over every ARR of the detection."""
    parts = [f"{p} {v:.0%}" if np.isfinite(v) else f"{p} none" for p, v in sorted(result.smallest_changes.items())]
    return "smallest detectable change: " + (", ".join(parts) if parts else "no parameter")


def evaluation_summary(e) -> dict:
    finite = np.isfinite(e.residual)
    return {"detection_time": e.detection_time, "margin": e.margin, "persistence": e.persistence,
            "violations": int(e.violation.sum()), "alarm_samples": int(e.alarm.sum()),
            "undecided_samples": int((~finite).sum()),
            "alarm_onsets": e.false_alarms(float("inf"))}
