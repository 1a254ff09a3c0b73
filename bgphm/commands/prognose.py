"""``bgphm prognose``: the candidate, its law and the RUL from a record (:func:`prognosis.prognose`)."""

from __future__ import annotations

import json
import math
import sys
import warnings

from bgphm.errors import EXIT_OK
from bgphm.files import csv_text, write_text
from diagnosis.records import RecordWarning
from prognosis import IsolationSettings, PrognosisSettings

from ._inputs import (
    detection_settings,
    load_record,
    read_truth,
    truth_values,
    what_can_fail,
)
from ._outputs import (
    estimate_labels,
    fmt,
    json_value,
    output_directory,
    units_of,
    vars_of,
    write_plots,
    write_report,
)
from ._progress import Progress, filter_progress

__all__ = ["estimate_columns", "first_reasons", "prognosis_line", "run", "truth_line", "truth_scores"]


def run(args, progress: Progress) -> int:
    """``bgphm prognose``: detect, find the degrading parameter and its law by evidence, predict the RUL.

    ``--fail PARAM=VALUE`` (repeatable) gives the failure value of each parameter that can fail; the
    candidates are those whose fault signature matches the ARRs that fired, each with each law
    (linear, exponential, power), weighed in one particle filter from the first alarm
    (:class:`~prognosis.isolation.IsolatingMonitor`); when none explains the residuals, two parameters
    wearing at once are weighed too, on the record again (``--pairs``: from the start; ``--no-pairs``:
    never).  ``--candidate`` and ``--degradation`` restrict
    them.  Prints the decision and the last RUL; with ``--out`` writes ``prognosis.json``,
    ``estimates.csv``, ``rul.csv`` and plots.  Returns 0.
    """
    from prognosis import prognose

    detection = detection_settings(args)
    out = output_directory(args)
    truth = read_truth(args.truth) if args.truth is not None else None
    spec, arrs, failures, candidates, laws = what_can_fail(args, progress)
    isolation = IsolationSettings(laws=tuple(laws), candidates=None if candidates is None else tuple(candidates),
                                  sensors=args.sensors, pairs=args.pairs, n_particles=args.particles,
                                  method=args.filter, dt=args.dt, rate=None if args.rate is None else tuple(args.rate),
                                  rul_every=args.rul_every, horizon=args.horizon, seed=args.seed)
    settings = PrognosisSettings(detection=detection, isolation=isolation)
    record = load_record(args.data, arrs, progress, args.resample)
    progress(f"calibrating, then the particle filter from the first alarm: {len(laws)} law(s) per candidate, "
             f"{args.particles} particles each")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RecordWarning)
        result = prognose(arrs, record, failures, settings, domains=spec.model.domains,
                          progress=filter_progress(progress))
    for w in caught:
        progress(f"warning: {w.message}")
    summary = result.as_dict()
    if summary.get("pairs", "").startswith("weighed:"):
        progress(f"two parameters wearing at once {summary['pairs']} (the filter ran again with them)")
    summary["units"] = units_of(spec.model, arrs)
    for name, margin in summary["margins"].items():
        progress(f"{name}: margin {margin:.3g}, residual noise {summary['residual_noise_std'][name]:.3g} (t <= "
                 f"{summary['calibration_end']:g} s), filter step {summary['filter_step']:g} s")
    for name, why in summary.get("undecided", {}).items():   # as detect says it, even with --quiet
        print(f"{name}: undecided, left out ({why})")
    # said even with --quiet: no answer, or no wear left but a sensor's offset (a wrong failure value?)
    if result.decision is not None and result.decision.status == "rejected":
        print(f"bgphm: warning: every hypothesis was rejected: {'; '.join(first_reasons(result))}", file=sys.stderr)
    elif result.decision is not None and all(h.name in result.rejected for h in result.hypotheses if not h.sensor):
        print(f"bgphm: warning: every wear hypothesis was rejected, only sensors' faults are left: "
              f"{'; '.join(first_reasons(result))}", file=sys.stderr)
    print(prognosis_line(result, summary))
    if truth is not None:
        truth["scores"] = truth_scores(summary, truth)
        summary["truth"] = truth
        print(truth_line(truth))
    if out is not None:
        write_text(out / "prognosis.json", json.dumps(summary, indent=2, default=json_value))
        written = [out / "prognosis.json"]
        if result.t.size:
            write_text(out / "estimates.csv", csv_text(estimate_columns(result)))
            p = result.monitor_result().rul_percentiles((5, 50, 95))
            write_text(out / "rul.csv", csv_text({"t": result.rul_t, "rul_mean": result.monitor_result().rul_mean,
                                                  "rul_p5": p[:, 0], "rul_median": p[:, 1], "rul_p95": p[:, 2]}))
            written += [out / "estimates.csv", out / "rul.csv"]
        primary = next((e for e in result.evaluations if e.name in result.fired), result.evaluations[0])
        best = result.monitor_result() if result.t.size else None
        from bgphm.run_report import prognosis_page

        labels = estimate_labels(summary, failures, spec.model.units)
        if truth is not None:
            labels.update(eol=truth.get("eol"), truth=truth_values(truth, summary.get("candidate")))
        written += write_plots("prognosis", out, (primary, best), progress, labels)
        written.append(write_report(out, prognosis_page(
            spec.model, arrs, result, summary, args.data, units=summary["units"], settings=vars_of(args),
            failures=failures, truth=truth, truth_theta=labels.get("truth"))))
        for path in written:
            print(f"wrote {path}")
    return EXIT_OK


def truth_scores(summary: dict, truth: dict) -> dict:
    """The predictions scored against ``truth["eol"]`` (:func:`prognosis.scores_against_truth`)."""
    from prognosis import scores_against_truth

    if truth.get("eol") is None:
        return {"predictions": 0}
    rows = summary["predictions"]
    keys = ("rul_p5", "rul_p25", "rul_median", "rul_p75", "rul_p95")
    percentiles = [[math.inf if p[k] is None and p["rul_median"] is not None else
                    (math.nan if p[k] is None else p[k]) for k in keys] for p in rows]
    means = [math.nan if p["rul_mean"] is None else p["rul_mean"] for p in rows]
    return scores_against_truth([p["t"] for p in rows], percentiles, means, truth["eol"])


def truth_line(truth: dict) -> str:
    scores = truth["scores"]
    if not scores.get("predictions"):
        return f"truth: end of life {fmt(truth.get('eol'))} s; no RUL prediction before it to score"
    return (f"truth: end of life {fmt(truth['eol'])} s; over {scores['predictions']} predictions mean RA "
            f"{fmt(scores['mean_relative_accuracy'])} (worst {fmt(scores['worst_relative_accuracy'])}), the 5-95 % "
            f"band holds the truth at {100 * scores['coverage_90']:.0f} %, the 25-75 % at "
            f"{100 * scores['coverage_50']:.0f} %, the median within {100 * scores['alpha']:.0f} % at "
            f"{100 * scores['within_alpha_share']:.0f} %")


def prognosis_line(result, summary: dict) -> str:
    if result.detection_time is None:
        return "no alarm, so no prognosis (the filter starts at the first alarm)"
    head = f"alarm at t = {result.detection_time:g} s ({', '.join(result.fired)})"
    if summary["candidate"] is None:
        why = (f"no parameter with a failure value is sensitive to every ARR that fired (consistent with them: "
               f"{', '.join(result.consistent) or 'no single fault of the model'})" if not result.candidates
               else "every hypothesis was rejected: " + "; ".join(first_reasons(result)))
        return f"{head}; {why}"
    last = summary["last"]
    later = "".join(f"; but {reason}" for reason in summary["unexplained"].values())
    if summary["reason"]:
        rejected = f" ({'; '.join(first_reasons(result))})" if summary["status"] == "rejected" else ""
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
            f"{last['t']:g} s RUL median {fmt(last['rul_median'])} s, 5-95 % [{fmt(last['rul_p5'])}, "
            f"{fmt(last['rul_p95'])}] s{later}")


def first_reasons(result) -> list[str]:
    """The first rejection reason of each candidate (its laws are often rejected for the same reason)."""
    reasons = {}
    for h in result.hypotheses:
        if h.name in result.rejected:
            reasons.setdefault(h.candidate, f"{h.name}: {result.rejected[h.name]}")
    return list(reasons.values())


def estimate_columns(result) -> dict:
    columns = {"t": result.t}
    for row, h in enumerate(result.hypotheses):
        columns[f"{h.name}.theta_mean"] = result.theta["mean"][:, row]
        for parameter, mean in result.parts.get(h.name, {}).items():  # a pair's: each of its parameters
            columns[f"{h.name}.{parameter}.theta_mean"] = mean
        columns[f"{h.name}.gamma_mean"] = result.gamma["mean"][:, row]
        columns[f"{h.name}.log_evidence"] = result.log_evidence[:, row]
    return columns
