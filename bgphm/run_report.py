"""One offline page per run: ``report.html`` of ``bgphm detect``, ``prognose`` and ``simulate``.

A report puts on one page what the command found and how: the decision first, then the charts (inline SVG
from :mod:`bgphm.charts`: the residuals against their thresholds with the alarms, the candidates' evidence over
time, the estimate with its band and failure value, the RUL with its bands, the truth when ``--truth`` gives
it), then the model and ARRs used and every setting, with the provenance (tool version, date, the SHA-256 of
the model and of the record, :mod:`bondgraph.provenance`).  Nothing is fetched: no script, font or style sheet
from elsewhere, and every text that comes from the user (names, paths, messages) is escaped.

The date honours ``SOURCE_DATE_EPOCH`` (a reproducible build sets it); without it, it is the time of the run.

Example
-------
>>> page = Page("bgphm simulate: DC motor", provenance={"model": "dc-motor"})
>>> page.section("Inputs", "<p>U = 12 V</p>")
>>> text = page.html()
>>> text.startswith("<!DOCTYPE html>") and "<h2>Inputs</h2>" in text and "http" not in text.split("<svg")[0]
True
"""

from __future__ import annotations

import html
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bgphm.charts import Chart
from bgphm.files import file_digest

__all__ = ["Page", "calibration_page", "detection_page", "prognosis_page", "provenance", "simulation_page", "table"]

#: -r_n typeset (a minus sign and a subscript n), as the fleet page writes it.
MINUS_R = "\u2212r\u2099"

STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0; color: #1a1a1a; background: #fafafa; }
main { max-width: 1100px; margin: 0 auto; padding: 1.5rem 2rem 3rem; background: #fff; }
h1 { font-size: 1.5rem; margin: 0 0 .3rem; } h2 { font-size: 1.2rem; margin: 2rem 0 .6rem;
  border-bottom: 1px solid #ddd; padding-bottom: .2rem; }
.provenance { color: #555; font-size: .85rem; } .provenance code { font-size: .8rem; }
table { border-collapse: collapse; margin: .4rem 0 1rem; font-size: .9rem; }
th, td { border: 1px solid #ddd; padding: .25rem .55rem; text-align: left; vertical-align: top; }
th { background: #f2f2f2; } td.number { text-align: right; font-variant-numeric: tabular-nums; }
.chart { width: 100%; height: auto; max-width: 1000px; display: block; margin: .3rem 0 1rem; }
.chart text { font-size: 12px; fill: #222; } .chart .chart-title { font-size: 13px; font-weight: 600; }
.chart .axis-label { font-size: 12.5px; }
.equation { overflow-x: auto; max-width: 100%; padding: .2rem 0; }
.decision { font-size: 1.05rem; background: #f4f8fc; border-left: 4px solid #0072b2; padding: .6rem .9rem; }
.note { color: #444; background: #f6f6f6; border-left: 4px solid #999; padding: .4rem .8rem; }
.warning { color: #7a3b00; background: #fff6e5; border-left: 4px solid #e69f00; padding: .4rem .8rem; }
"""


# ------------------------------------------------------------------------------------------- the page

@dataclass
class Page:
    """An HTML page of sections; :meth:`html` writes it whole."""

    title: str
    provenance: Mapping[str, str] = field(default_factory=dict)
    sections: list = field(default_factory=list)

    def section(self, heading: str, body: str, anchor: str | None = None) -> None:
        """Add a section: a heading (escaped here) and its body (HTML the caller built, texts escaped)."""
        self.sections.append((heading, body, anchor))

    def html(self) -> str:
        shown = " · ".join(f"{_e(key)}: <code>{_e(value)}</code>" for key, value in self.provenance.items())
        parts = ['<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">',
                 '<meta name="viewport" content="width=device-width, initial-scale=1">',
                 f"<title>{_e(self.title)}</title><style>{STYLE}</style></head><body><main>",
                 f"<header><h1>{_e(self.title)}</h1><p class=\"provenance\">{shown}</p></header>"]
        for heading, body, anchor in self.sections:
            ident = f' id="{_e(anchor)}"' if anchor else ""
            parts.append(f"<section{ident}><h2>{_e(heading)}</h2>{body}</section>")
        parts.append("</main></body></html>\n")
        return "\n".join(parts)


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def table(header: Sequence[str], rows: Iterable[Sequence], numeric: Sequence[bool] | None = None) -> str:
    r"""An HTML table; every cell is escaped (a float is written with 4 significant digits).

    >>> print(table(["name", "value"], [["b", 1e-4], ["<J>", 2.5]]).replace("</tr>", "</tr>\n"))
    <table><tr><th>name</th><th>value</th></tr>
    <tr><td>b</td><td class="number">0.0001</td></tr>
    <tr><td>&lt;J&gt;</td><td class="number">2.5</td></tr>
    </table>
    """
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = []
    for row in rows:
        cells = []
        for k, value in enumerate(row):
            number = isinstance(value, (float, np.floating)) or (numeric is not None and numeric[k])
            text = _cell(value)
            cells.append(f'<td class="number">{_e(text)}</td>' if number else f"<td>{_e(text)}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def _cell(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, (float, np.floating)):
        return f"{value:.4g}" if np.isfinite(value) else ("beyond the horizon" if value > 0 else "-")
    return str(value)


def _label(name: str, unit: str | None) -> str:
    return f"{name} ({unit})" if unit else name


# ------------------------------------------------------------------------------------------- provenance

def provenance(model, data: str | os.PathLike | None = None) -> dict:
    """What made the report (:func:`bondgraph.provenance.provenance`: the tool's version, the date, the model's
    SHA-256) and the record's name and SHA-256."""
    from bondgraph.provenance import provenance as made

    record = made(model)
    found = {record.tool: record.version, "sympy": record.sympy, "date": record.generated, "model": model.name,
             "model SHA-256": record.model_sha256}
    if data is not None:
        found.update({"record": Path(data).name, "record SHA-256": file_digest(data)})
    return found


# ------------------------------------------------------------------------------------------- sections

def _arr_table(arrs, residual_units: Mapping[str, str], forms: Mapping | None = None,
               margins: Mapping | None = None) -> str:
    from diagnosis.deltas import mathml

    rows = []
    for arr in arrs:
        form = (forms or {}).get(arr.name, {})
        equation = f'<div class="equation"><math display="block">{mathml(arr.nominal)}<mo>=</mo><mn>0</mn></math></div>'
        cells = [_e(arr.name), equation, _e(residual_units.get(arr.name) or "-"), _e(", ".join(arr.signals)),
                 _e(form.get("form", arr.form)), _e(_cell((margins or {}).get(arr.name)))]
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    head = "".join(f"<th>{h}</th>" for h in ("ARR", "nominal residual r<sub>n</sub>", "unit", "signals", "form",
                                              "margin"))
    return f"<table><tr>{head}</tr>{''.join(rows)}</table>"


def _residual_chart(evaluation, unit: str | None, calibration_end: float | None = None) -> str:
    e = evaluation
    chart = Chart(f"{e.name}: residual and robust threshold", x_label="t (s)", y_label=_label(MINUS_R, unit))
    chart.band(e.t, e.lower - e.margin, e.upper + e.margin, label="interval threshold (with margin)",
               colour="#d55e00")
    chart.line(e.t, -np.asarray(e.residual, float), label=MINUS_R, colour="#0072b2")
    if calibration_end is not None:
        chart.vline(calibration_end, label=f"calibration end {calibration_end:g} s", style="dashed",
                    colour="#777777")
    if e.detection_time is not None:
        chart.vline(e.detection_time, label=f"alarm at {e.detection_time:g} s", colour="#b00000")
    return chart.svg()


def _settings_table(settings: Mapping) -> str:
    return table(["setting", "value"], [[k, _cell(v) if not isinstance(v, (list, tuple, dict)) else str(v)]
                                        for k, v in settings.items()])


def detection_page(model, arrs, result, record_path, *, units: Mapping, settings: Mapping) -> Page:
    """The report of ``bgphm detect``: the alarms, each residual against its threshold, the ARRs, the settings.

    ``result`` is the :class:`diagnosis.Detection` of the run, ``units`` the ``units`` block of its JSON
    (:func:`bgphm.units.units_of`), ``settings`` what the command line set.
    """
    page = Page(f"bgphm detect: {model.name}", provenance(model, record_path))
    fired = [e.name for e in result.evaluations if e.detection_time is not None]
    lines = [f"<p><strong>{_e(len(fired))} of {_e(len(result.evaluations))} ARRs in alarm</strong>"
             + (f": {_e(', '.join(fired))}" if fired else "") + "</p>"]
    if result.fired:
        lines.append(f"<p>Faults consistent with them: {_e(', '.join(result.candidates) or 'none')}</p>")
    for name, why in result.undecided.items():
        lines.append(f'<p class="warning">{_e(name)}: undecided, left out ({_e(why)})</p>')
    page.section("Decision", '<div class="decision">' + "".join(lines) + "</div>", "decision")
    residual_units = units.get("residuals", {})
    charts = [_residual_chart(e, residual_units.get(e.name)) for e in result.evaluations]
    page.section("Residuals against their thresholds", "".join(charts), "residuals")
    rows = [[e.name, e.detection_time, e.margin, e.persistence, int(np.sum(e.violation)), int(np.sum(e.alarm))]
            for e in result.evaluations]
    page.section("Alarms", table(["ARR", "first alarm (s)", "margin", "persistence (samples)", "violations",
                                  "samples in alarm"], rows), "alarms")
    margins = {e.name: e.margin for e in result.evaluations}
    page.section("Model and ARRs", _model_summary(model, units) + _arr_table(arrs, residual_units, result.forms,
                                                                              margins), "model")
    page.section("Settings", _settings_table(settings), "settings")
    return page


def _model_summary(model, units: Mapping) -> str:
    values = model.parameters
    rows = [[p, values[p], units.get("parameters", {}).get(p) or "-"] for p in values]
    signals = [[s, units.get("signals", {}).get(s) or "-"] for s in units.get("signals", {})]
    return (table(["parameter", "nominal value", "unit"], rows)
            + table(["signal", "unit"], signals))


def prognosis_page(model, arrs, result, summary: Mapping, record_path, *, units: Mapping, settings: Mapping,
                   failures: Mapping, truth: Mapping | None = None, truth_theta=None) -> Page:
    """The report of ``bgphm prognose``: the decision, the residual, the evidence, the estimate and the RUL.

    ``result`` is the :class:`prognosis.PrognosisResult` of the run and ``summary`` its ``as_dict()`` (what
    ``prognosis.json`` holds).  ``truth`` (``--truth``, with its ``scores`` from
    :func:`prognosis.scores_against_truth`) adds the true RUL; ``truth_theta`` (a callable of t) the parameter's
    true values.
    """
    page = Page(f"bgphm prognose: {model.name}", provenance(model, record_path))
    page.section("Decision", _prognosis_decision(summary, truth), "decision")
    residual_units = units.get("residuals", {})
    primary = next((e for e in result.evaluations if e.name in result.fired), result.evaluations[0])
    page.section("Residual against its threshold",
                 _residual_chart(primary, residual_units.get(primary.name), summary.get("calibration_end")),
                 "residuals")
    if result.t.size:
        page.section("Candidates and evidence over time", _evidence_chart(result), "evidence")
        page.section("Estimate of the reported candidate", _estimate_chart(result, summary, failures, units,
                                                                           truth_theta), "estimate")
        page.section("Remaining useful life", _rul_chart(result, truth) + _predictions_table(summary), "rul")
    page.section("Model and ARRs", _model_summary(model, units) + _arr_table(arrs, residual_units), "model")
    page.section("Settings", _settings_table(settings), "settings")
    return page


def _prognosis_decision(summary: Mapping, truth: Mapping | None) -> str:
    if summary.get("detection_time") is None:
        return '<div class="decision"><p>No alarm, so no prognosis (the filter starts at the first alarm).</p></div>'
    last = summary.get("last") or {}
    lines = [f"<p>First alarm at <strong>{_e(summary['detection_time'])} s</strong> "
             f"({_e(', '.join(summary.get('fired', [])))})</p>"]
    candidate = summary.get("candidate")
    if candidate is None:
        lines.append("<p>No candidate: " + _e(summary.get("reason") or "no parameter with a failure value explains "
                                              "the alarms") + "</p>")
    else:
        shown = ", ".join(candidate) if isinstance(candidate, list) else candidate
        law = (summary.get("degradation") or "-") + ("" if summary.get("degradation_decided", True) else
                                                     " (undecided)")
        lines.append(f"<p>Candidate <strong>{_e(shown)}</strong>: {_e(summary.get('status'))}; degradation "
                     f"{_e(law)}</p>")
        if summary.get("same_signature"):
            lines.append(f"<p>Same fault signature as {_e(', '.join(summary['same_signature']))}.</p>")
        if last.get("withheld"):
            lines.append(f'<p class="warning">At t = {_e(_cell(last.get("t")))} s no RUL: undecided '
                         f"({_e(last['withheld'])})</p>")
        elif last.get("rul_median") is not None:
            lines.append(f"<p>At t = {_e(_cell(last['t']))} s the RUL median is <strong>"
                         f"{_e(_cell(last['rul_median']))} s</strong>, 5-95 % [{_e(_cell(last.get('rul_p5')))}, "
                         f"{_e(_cell(last.get('rul_p95')))}] s</p>")
        elif summary.get("reason"):
            lines.append(f'<p class="warning">{_e(summary["reason"])}</p>')
    if truth:
        lines.append(_truth_line(truth))
    return '<div class="decision">' + "".join(lines) + "</div>"


def _truth_line(truth: Mapping) -> str:
    scores = truth.get("scores") or {}
    if not scores.get("predictions"):
        return f"<p>Truth: end of life {_e(_cell(truth.get('eol')))} s; no prediction before it to score.</p>"
    return (f"<p>Truth: end of life {_e(_cell(truth.get('eol')))} s. Over {_e(scores['predictions'])} predictions: "
            f"mean relative accuracy {_e(_cell(scores['mean_relative_accuracy']))} (worst "
            f"{_e(_cell(scores['worst_relative_accuracy']))}); the 5-95 % band holds the true RUL at "
            f"{_e(_percent(scores['coverage_90']))} of them, the 25-75 % band at {_e(_percent(scores['coverage_50']))};"
            f" the median within {_e(_percent(scores['alpha']))} at {_e(_percent(scores['within_alpha_share']))}.</p>")


def _percent(value) -> str:
    return "-" if value is None else f"{100 * value:.0f} %"


def _evidence_chart(result) -> str:
    chart = Chart("Probability of each hypothesis (at each RUL report)", x_label="t (s)",
                  y_label="probability")
    names = list(result.decisions[0].probabilities) if result.decisions else []
    for name in names[:8]:  # the legend stays readable; the table below the RUL has the rest
        values = [d.probabilities.get(name, np.nan) for d in result.decisions]
        chart.line(result.rul_t, values, label=name)
    if not names:
        chart.line(result.t, np.full(result.t.shape, np.nan))
    return chart.svg()


def _estimate_chart(result, summary: Mapping, failures: Mapping, units: Mapping, truth_theta) -> str:
    best = result.monitor_result()
    candidate = summary.get("candidate")
    name = candidate if isinstance(candidate, str) else "theta"
    unit = units.get("parameters", {}).get(name) or None
    chart = Chart(f"Estimate of {name}", x_label="t (s)", y_label=_label(name, unit))
    quantiles = best.theta.get("quantiles")
    if quantiles is not None and len(quantiles):
        chart.band(best.t, quantiles[:, 0], quantiles[:, -1], label="5-95 %", colour="#0072b2")
    chart.line(best.t, best.theta["mean"], label="estimate (mean)", colour="#0072b2")
    if truth_theta is not None:
        chart.line(best.t, truth_theta(np.asarray(best.t, float)), label="true", style="dashed", colour="#000000")
    if isinstance(candidate, str) and candidate in failures:
        chart.hline(failures[candidate], label=f"failure value {failures[candidate]:.4g}" + (f" {unit}" if unit
                                                                                              else ""))
    return chart.svg()


def _rul_chart(result, truth: Mapping | None) -> str:
    best = result.monitor_result()
    chart = Chart("Remaining useful life at each prediction", x_label="t (s)", y_label="RUL (s)")
    t = np.asarray(best.rul_t, float)
    if len(best.rul):
        horizon = np.array([p.horizon for p in best.rul], float)
        q = best.rul_percentiles((5, 25, 50, 75, 95))
        shown = np.minimum(q, horizon[:, None])
        chart.band(t, shown[:, 0], shown[:, 4], label="5-95 %", colour="#0072b2")
        chart.band(t, shown[:, 1], shown[:, 3], label="25-75 %", colour="#0072b2")
        chart.line(t, shown[:, 2], label="median", colour="#0072b2")
        if (q > horizon[:, None]).any():
            chart.line(t, horizon, label="horizon (percentiles beyond it drawn on it)", style="dotted",
                       colour="#777777")
    if truth and truth.get("eol") is not None:
        true = float(truth["eol"]) - t
        chart.line(t, np.where(true > 0, true, np.nan), label="true RUL", style="dashed", colour="#000000")
    return chart.svg()


def _predictions_table(summary: Mapping) -> str:
    def percentile(p, key):  # None beside a median: beyond the horizon (censored), not missing
        value = p.get(key)
        return float("inf") if value is None and p.get("rul_median") is not None else value

    rows = [[p["t"], percentile(p, "rul_p5"), percentile(p, "rul_median"), percentile(p, "rul_p95"), p.get("rul_mean"),
             p.get("withheld") or ""] for p in summary.get("predictions", [])]
    return table(["t (s)", "RUL 5 % (s)", "RUL median (s)", "RUL 95 % (s)", "RUL mean (s)", "undecided because"],
                 rows, numeric=[True, True, True, True, True, False])


def simulation_page(model, columns: Mapping[str, np.ndarray], *, units: Mapping, settings: Mapping,
                    faults: Sequence[str] = ()) -> Page:
    """The report of ``bgphm simulate``: each signal of the record written (faults and noise included) over time,
    the parameters, the faults injected, the settings."""
    page = Page(f"bgphm simulate: {model.name}", provenance(model))
    described = "".join(f"<li>{_e(f)}</li>" for f in faults) or "<li>none</li>"
    page.section("Faults injected", f"<ul>{described}</ul>", "faults")
    signals = units.get("signals", {})
    charts = []
    for name, values in columns.items():
        if name == "t":
            continue
        chart = Chart(name, x_label="t (s)", y_label=_label(name, signals.get(name)))
        chart.line(columns["t"], values, label=name)
        charts.append(chart.svg())
    page.section("Signals", "".join(charts), "signals")
    page.section("Model", _model_summary(model, units), "model")
    page.section("Settings", _settings_table(settings), "settings")
    return page


def calibration_page(model, calibrated, fit, boxes: Mapping, validation, calibration: Mapping, *, units: Mapping,
                     settings: Mapping) -> Page:
    """The report of ``bgphm calibrate``: the estimates against the datasheet, what the records cannot tell apart,
    the boxes, the validation on held-out records (datasheet model before, calibrated model after), the records
    and the method.

    ``fit`` is the :class:`diagnosis.ParameterEstimate`, ``boxes`` the calibrated uncertainty boxes,
    ``validation`` the :class:`diagnosis.ModelValidation` (None without held-out records), ``calibration`` the
    provenance block the calibrated model carries, ``units`` :func:`bgphm.units.units_of` of the model.
    """
    from bondgraph.provenance import model_sha256

    page = Page(f"bgphm calibrate: {model.name}", {**provenance(model), "calibrated SHA-256": model_sha256(calibrated)})
    page.section("Estimates", _estimates_table(fit, boxes, units.get("parameters", {})) + _unidentified(fit),
                 "estimates")
    page.section("Validation on held-out records", _validation_body(validation), "validation")
    noise = [[name, std, fit.correlation.get(name), units.get("residuals", {}).get(name) or "-"]
             for name, std in fit.residual_std.items()]
    page.section("Residuals at the fit", table(["ARR", "robust std", "correlation inflation", "unit"], noise)
                 + f"<p>{_e(fit.samples)} window-integrated residual samples.</p>", "residuals")
    records = [[r["name"], r["role"], r["samples"], r["sha256"]] for r in calibration.get("records", [])]
    method = calibration.get("method", {})
    page.section("Records and method", table(["record", "role", "samples", "SHA-256"], records)
                 + _settings_table({key: value for key, value in method.items()}), "records")
    page.section("Settings", _settings_table(settings), "settings")
    return page


def _estimates_table(fit, boxes: Mapping, units: Mapping) -> str:
    level = f"{fit.level:.0%}".replace("%", " %")
    rows = []
    for name, (lo, hi) in fit.intervals.items():
        sheet, value = fit.datasheet[name], fit.values[name]
        box = boxes.get(name)
        rows.append([name, units.get(name) or "-", sheet, value, lo, hi, fit.std[name],
                     _signed_percent(value / sheet - 1.0) if sheet else "-",
                     f"[{_signed_percent(box[0])}, {_signed_percent(box[1])}]" if box else "-"])
    return table(["parameter", "unit", "datasheet", "estimate", f"{level} low", f"{level} high", "std. error",
                  "change", "box"], rows)


def _signed_percent(value: float) -> str:
    return f"{100 * value:+.3g} %"


def _unidentified(fit) -> str:
    ident = fit.identifiability
    if ident is None or not (ident.combinations or ident.unseen):
        return "<p>The records identify every parameter asked for.</p>"
    rows = [[", ".join(c["parameters"]), c["expression"], c["kept"]] for c in ident.combinations
            if not c.get("weak")]
    weak = [[", ".join(c["parameters"]), c["kept"]] for c in ident.combinations if c.get("weak")]
    body = ""
    if rows:
        body += ("<p>Seen only together (one kept at its datasheet value, the others carry the combination):</p>"
                 + table(["parameters", "what the records fix", "kept"], rows))
    if weak:
        body += ("<p>Told less well by the records than by the datasheet (kept at its datasheet value, its "
                 "uncertainty widening the others' intervals):</p>" + table(["parameters", "kept"], weak))
    if ident.unseen:
        body += f"<p>In no ARR, kept at the datasheet value: {_e(', '.join(ident.unseen))}</p>"
    return body


def _validation_body(validation) -> str:
    if validation is None:
        return '<p class="note">No held-out record: the calibrated model was not validated.</p>'
    before, after = validation.before, validation.after
    count = len(validation.held_out)
    intro = (f"<p>Margins calibrated on the {_e(len(validation.training))} training record(s) "
             f"({_e(', '.join(validation.training))}) for each model, applied to the {_e(count)} held-out "
             f"one(s); any alarm on a held-out record, all healthy, is false.</p>")
    summary = table(["", "datasheet", "calibrated"], [
        ["held-out records with a false alarm", f"{len(before.false_alarms)} of {count}",
         f"{len(after.false_alarms)} of {count}"]])
    alarms = [[record, _alarm_text(before.alarms.get(record)), _alarm_text(after.alarms.get(record))]
              for record in validation.held_out]
    changes = [[p, _change_text(before.smallest_changes.get(p)), _change_text(v)]
               for p, v in after.smallest_changes.items()]
    white = [[name, *_white_cells(before.whiteness.get(name)), *_white_cells(w)] for name, w in after.whiteness.items()]
    margins = [[name, before.margins.get(name), m] for name, m in after.margins.items()]
    return (intro + summary
            + "<h3>Alarms per held-out record</h3>" + table(["record", "datasheet", "calibrated"], alarms)
            + "<h3>Smallest detectable change (on every held-out record)</h3>"
            + table(["parameter", "datasheet", "calibrated"], changes)
            + f"<h3>Whiteness of the residuals (every derivative window, {_e(validation.lags)} lags)</h3>"
            + table(["ARR", "datasheet lag-1 autocorrelation", "datasheet Ljung-Box p", "calibrated lag-1 "
                     "autocorrelation", "calibrated Ljung-Box p"], white)
            + _autocorrelation_charts(validation)
            + "<h3>Margins</h3>" + table(["ARR", "datasheet", "calibrated"], margins))


def _alarm_text(alarms) -> str:
    if not alarms:
        return "no alarm"
    return ", ".join(f"{name} at {t:g} s" for name, t in alarms.items())


def _change_text(value) -> str:
    return "none" if value is None or not np.isfinite(value) else f"{100 * value:.3g} %"


def _white_cells(white) -> list:
    if white is None:
        return ["-", "-"]
    verdict = "white" if white.white else "not white"
    first = white.autocorrelation[0] if white.autocorrelation else None
    return [first, f"{white.p_value:.2g} ({verdict})" if np.isfinite(white.p_value) else "-"]


def _autocorrelation_charts(validation) -> str:
    charts = []
    for name, after in validation.after.whiteness.items():
        before = validation.before.whiteness.get(name)
        lags = np.arange(1, len(after.autocorrelation) + 1)
        chart = Chart(f"{name}: autocorrelation of the held-out residuals", x_label="lag (derivative windows)",
                      y_label="autocorrelation")
        if after.samples:  # white noise stays within about 2 / sqrt(n) (95 %)
            edge = 1.96 / np.sqrt(after.samples)
            chart.band(lags, np.full(lags.size, -edge), np.full(lags.size, edge), label="white noise, 95 %",
                       colour="#999999")
        if before is not None:
            chart.line(lags, before.autocorrelation, label="datasheet", style="dashed", colour="#d55e00")
        chart.line(lags, after.autocorrelation, label="calibrated", colour="#0072b2")
        charts.append(chart.svg())
    return "".join(charts)
