"""The run reports: ``report.html`` of detect and prognose (in ``--out``) and simulate (``--report``).

The pages are read as HTML (``html.parser``) here; their rendering in Chromium is tests/browser's.
"""

from __future__ import annotations

import json
from html.parser import HTMLParser

import pytest

from bgphm.cli import main
from bgphm.run_report import Page
from bondgraph.provenance import model_sha256
from bondgraph.library import dc_motor


class _Outline(HTMLParser):
    """The page's headings, SVG texts by class, scripts and external references."""

    def __init__(self):
        super().__init__()
        self.headings, self.svg_texts, self.external, self.scripts, self._stack = [], {}, [], 0, []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        self._stack.append((tag, attrs.get("class", "")))
        self.scripts += tag == "script"
        for key in ("src", "href"):
            if attrs.get(key):
                self.external.append(attrs[key])

    def handle_endtag(self, tag):
        while self._stack and self._stack.pop()[0] != tag:
            pass

    def handle_data(self, data):
        if not self._stack:
            return
        tag, cls = self._stack[-1]
        if tag == "h2":
            self.headings.append(data)
        if tag == "text":
            self.svg_texts.setdefault(cls, []).append(data)


def _outline(path) -> _Outline:
    parser = _Outline()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser


@pytest.fixture(scope="module")
def worn_motor(tmp_path_factory):
    """The README's bench run through the command line: b wears exponentially from 1 s."""
    folder = tmp_path_factory.mktemp("report")
    record = folder / "run.csv"
    assert main(["--quiet", "simulate", "dc-motor", "--degrade", "b=exp:0.8@1", "--noise", "omega=0.5", "--t-end", "4",
                 "--out", str(record), "--report", str(folder / "simulation.html")]) == 0
    truth = folder / "truth.json"
    truth.write_text(json.dumps({"eol": 1 + 2.995732273553991 / 0.8, "candidate": "b", "degradation": "exponential",
                                 "nominal": 1e-4, "rate": 0.8, "onset": 1.0}))
    return folder, record, truth


def test_the_detection_report_holds_each_residual_with_its_unit_and_the_alarm(worn_motor):
    folder, record, _ = worn_motor
    assert main(["--quiet", "detect", "dc-motor", str(record), "--calibrate", "0.9", "--out", str(folder / "d")]) == 0
    page = _outline(folder / "d" / "report.html")
    assert page.headings[:2] == ["Decision", "Residuals against their thresholds"]
    assert {"Model and ARRs", "Settings"} <= set(page.headings)
    assert page.svg_texts["axis-label y-label"] == ["\u2212r\u2099 (V)", "\u2212r\u2099 (N*m)"]
    assert set(page.svg_texts["axis-label x-label"]) == {"t (s)"}
    alarm = json.loads((folder / "d" / "detection.json").read_text())["arrs"]["ARR_1_m"]["detection_time"]
    assert f"alarm at {alarm:g} s" in page.svg_texts["legend-label"]
    assert page.scripts == 0 and page.external == []   # offline: nothing fetched, nothing run
    text = (folder / "d" / "report.html").read_text()
    assert model_sha256(dc_motor()) in text and "<math" in text


@pytest.mark.slow
def test_the_prognosis_report_draws_estimate_failure_value_rul_and_truth(worn_motor):
    folder, record, truth = worn_motor
    out = folder / "p"
    assert main(["--quiet", "prognose", "dc-motor", str(record), "--fail", "b=2e-3", "--calibrate", "0.9",
                 "--truth", str(truth), "--out", str(out)]) == 0
    summary = json.loads((out / "prognosis.json").read_text())
    page = _outline(out / "report.html")
    assert page.headings[:5] == ["Decision", "Residual against its threshold", "Candidates and evidence over time",
                                 "Estimate of the reported candidate", "Remaining useful life"]
    assert "b (N*m*s/rad)" in page.svg_texts["axis-label y-label"] and "RUL (s)" in page.svg_texts["axis-label y-label"]
    legend = page.svg_texts["legend-label"]
    assert "failure value 0.002 N*m*s/rad" in legend and "true RUL" in legend and "true" in legend
    scores = summary["truth"]["scores"]
    assert scores["predictions"] == len([p for p in summary["predictions"] if p["rul_median"] is not None])
    assert 0.0 <= scores["coverage_90"] <= 1.0 and scores["mean_relative_accuracy"] is not None
    text = (out / "report.html").read_text()
    assert f"over {scores['predictions']} predictions" in text.replace("Over", "over")


@pytest.mark.slow
def test_truth_scores_follow_from_the_predictions_by_hand(worn_motor):
    """Coverage recomputed here from prognosis.json's own percentiles and the true end of life."""
    folder, record, truth = worn_motor
    out = folder / "p2"
    assert main(["--quiet", "prognose", "dc-motor", str(record), "--fail", "b=2e-3", "--calibrate", "0.9",
                 "--truth", str(truth), "--rul-every", "1", "--out", str(out)]) == 0
    summary = json.loads((out / "prognosis.json").read_text())
    eol = summary["truth"]["eol"]
    made = [p for p in summary["predictions"] if p["rul_median"] is not None and eol - p["t"] > 0]
    inside = [p["rul_p5"] <= eol - p["t"] <= (p["rul_p95"] if p["rul_p95"] is not None else float("inf"))
              for p in made]
    assert summary["truth"]["scores"]["coverage_90"] == pytest.approx(sum(inside) / len(made))


def test_the_simulation_report_shows_the_record_written_with_its_faults(worn_motor):
    folder, record, _ = worn_motor
    page = _outline(folder / "simulation.html")
    assert page.headings[:2] == ["Faults injected", "Signals"]
    assert page.svg_texts["axis-label y-label"] == ["U (V)", "i (A)", "omega (rad/s)"]
    text = (folder / "simulation.html").read_text()
    assert "b: " in text and "sensor omega: noise std 0.5 (seed 0)" in text


@pytest.mark.parametrize("argv, message", [
    (["--truth", "missing.json"], "--truth missing.json: no such file"),
])
def test_a_missing_truth_file_is_refused_before_any_work(worn_motor, capsys, argv, message):
    folder, record, _ = worn_motor
    assert main(["prognose", "dc-motor", str(record), "--fail", "b=2e-3", *argv]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("content, message", [
    ("[1, 2]", "expected a JSON object with 'eol'"),
    ('{"rate": 1}', "no 'eol'"),
    ('{"eol": "soon"}', "'eol' must be a finite number"),
    ('{"eol": 5, "colour": "red"}', "unknown field 'colour'"),
    ('{"eol": 5, "degradation": "cubic"}', "'degradation' 'cubic' is not one of"),
    ("{eol: 5}", "not JSON"),
])
def test_bad_truth_files_name_the_field(worn_motor, tmp_path, capsys, content, message):
    _, record, _ = worn_motor
    bad = tmp_path / "truth.json"
    bad.write_text(content)
    assert main(["prognose", "dc-motor", str(record), "--fail", "b=2e-3", "--truth", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"bgphm: error: --truth {bad}") and message in err and err.count("\n") == 1


def test_user_text_is_escaped_in_the_page():
    page = Page('<script>alert("x")</script>', provenance={"model": "a</code><b>"})
    page.section("<img src=x>", "<p>ok</p>")
    text = page.html()
    assert "<script>" not in text and "<img" not in text and "&lt;script&gt;" in text and "a&lt;/code&gt;" in text


def test_the_report_date_honours_source_date_epoch(monkeypatch):
    from bgphm.run_report import provenance

    monkeypatch.setenv("SOURCE_DATE_EPOCH", "0")
    assert provenance(dc_motor())["date"] == "1970-01-01 00:00:00 UTC"


def test_simulate_refuses_a_report_on_the_csv(tmp_path, capsys):
    out = tmp_path / "run.csv"
    assert main(["simulate", "rlc", "--out", str(out), "--report", str(out)]) == 2
    assert "--report" in capsys.readouterr().err and not out.exists()
