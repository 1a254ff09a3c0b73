"""``bgphm calibrate``: the table, the calibrated model and its provenance block, the report, every option and
every bad input (exit 2, one line naming it), outputs whole or absent and never an input overwritten.

The records are bench runs of a DC motor integrated with scipy's solve_ivp (tests.diagnosis.motor_bench); the
datasheet model is 20-30 % off in R_a, J and b."""

from __future__ import annotations

import contextlib
import io
import json
import os
import stat
from types import SimpleNamespace

import pytest

from bgphm.cli import main
from bgphm.files import csv_text, file_digest
from bondgraph.io import load_model, to_json
from bondgraph.library import dc_motor
from bondgraph.provenance import generated_at, model_sha256, tool_version
from tests.diagnosis.motor_bench import DATASHEET, TRUE, motor_record

EPOCH = "1700000000"


def write_record(path, record, columns=("U", "i", "omega")):
    path.write_text(csv_text({"t": record.t, **{c: record[c] for c in columns}}))
    return path


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """The datasheet model and four healthy runs: a (10 V), b (8 V), c (24 V, driven harder) and d (10 V)."""
    folder = tmp_path_factory.mktemp("bench")
    (folder / "sheet.json").write_text(to_json(dc_motor(**DATASHEET), inputs={"U": 12.0}, t_end=2.0))
    for name, volts, seed in (("a", 10.0, 1), ("b", 8.0, 2), ("c", 24.0, 4), ("d", 10.0, 5)):
        write_record(folder / f"{name}.csv", motor_record(volts, seed))
    return folder


def run(*argv, environment=None):
    """``main(argv)``'s exit code, stdout and stderr (with environment variables set for the run)."""
    out, err = io.StringIO(), io.StringIO()
    saved = {k: os.environ.get(k) for k in environment or {}}
    os.environ.update(environment or {})
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main([str(a) for a in argv])
    except SystemExit as stop:  # argparse's own errors exit
        code = stop.code
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def calibrated(bench, tmp_path_factory):
    """``bgphm calibrate sheet.json a.csv b.csv c.csv --out cal.json``: c.csv held out (the default)."""
    out = tmp_path_factory.mktemp("calibrated") / "cal.json"
    code, stdout, stderr = run("calibrate", bench / "sheet.json", bench / "a.csv", bench / "b.csv", bench / "c.csv",
                               "--out", out, environment={"SOURCE_DATE_EPOCH": EPOCH})
    assert code == 0, stderr
    return out, stdout, stderr


def quiet(*argv):
    """``bgphm --quiet calibrate ARGV``: stderr holds the error alone."""
    return run("--quiet", "calibrate", *argv)


def one_line_error(code, out, err, *words):
    assert code == 2, (out, err)
    assert len(err.strip().splitlines()) == 1 and err.startswith("bgphm: error: "), err
    for word in words:
        assert word in err, err


# ------------------------------------------------------------------------------------------- the default run

def test_the_table_names_each_estimate_and_the_validation(calibrated):
    _, out, err = calibrated
    lines = out.splitlines()
    assert lines[0].split() == ["parameter", "datasheet", "estimate", "95", "%", "interval", "change", "box"]
    rows = {line.split()[0]: line for line in lines[1:6]}
    assert list(rows) == list(TRUE)
    assert "+25.0 %" in rows["R_a"] and "-23." in rows["J"] and "+4" in rows["b"]  # 1/0.8, 1/1.3, 1/0.7
    assert "validation on 1 held-out record(s), margins calibrated on 2 training record(s):" in out
    assert any(line.split()[:4] == ["false", "alarms", "1", "of"] and line.split()[5:] == ["0", "of", "1"]
               for line in lines)
    assert "datasheet: false alarm on c.csv (ARR_1_m" in out
    assert "(white)" in out and "(not white)" in out
    assert "validating on 1 held-out record(s)" in err  # progress on stderr


def test_the_calibrated_model_holds_the_estimates_and_loads_back(calibrated):
    out, _, _ = calibrated
    spec = load_model(out)
    for name in ("R_a", "J", "b"):
        assert abs(spec.model.parameters[name] / TRUE[name] - 1) < 0.02, name
        lo, hi = spec.model.uncertainties[name]
        assert -0.05 < lo < 0 < hi < 0.05, name
    assert spec.inputs == {"U": 12.0} and spec.t_end == 2.0  # the datasheet model's default run is kept
    assert spec.calibration["estimates"]["J"]["estimate"] == spec.model.parameters["J"]


def test_detect_runs_on_the_calibrated_model(calibrated, bench, tmp_path):
    out, _, _ = calibrated
    code, stdout, stderr = run("--quiet", "detect", out, bench / "d.csv", "--out", tmp_path / "detect")
    assert code == 0, stderr
    summary = json.loads((tmp_path / "detect" / "detection.json").read_text())
    assert summary["detection_time"] is None and set(summary["arrs"]) == {"ARR_1_e", "ARR_1_m"}
    assert "ARR_1_m: no alarm" in stdout


def test_the_provenance_block(calibrated, bench):
    out, _, _ = calibrated
    block = json.loads(out.read_text())["graph"]["calibration"]
    assert block["tool"] == "bondgraph-phm" and block["version"] == tool_version()
    assert block["date"] == generated_at({"SOURCE_DATE_EPOCH": EPOCH}) == "2023-11-14 22:13:20 UTC"
    sheet = load_model(bench / "sheet.json").model
    assert block["datasheet"] == {"model": sheet.name, "source": "sheet.json", "sha256": model_sha256(sheet)}
    assert [(r["name"], r["role"], r["samples"]) for r in block["records"]] == [
        ("a.csv", "training", 2001), ("b.csv", "training", 2001), ("c.csv", "held-out", 2001)]
    assert all(r["sha256"] == file_digest(bench / r["name"]) for r in block["records"])
    method = block["method"]
    assert (method["level"], method["prior"], method["boxes"], method["parameters"]) == (0.95, 0.5, "confidence", None)
    assert "estimate_parameters" in method["estimator"]
    b = block["estimates"]["b"]
    assert b["interval"][0] < b["estimate"] < b["interval"][1] and b["datasheet"] == pytest.approx(DATASHEET["b"])
    assert block["boxes"]["b"] == pytest.approx([b["interval"][0] / b["estimate"] - 1, b["interval"][1] / b["estimate"]
                                                 - 1], rel=1e-6)
    assert block["combinations"] == [] and block["unseen"] == []
    validation = block["validation"]
    assert validation["held_out"] == ["c.csv"] and validation["training"] == ["a.csv", "b.csv"]
    assert validation["datasheet"]["false_alarms"] == ["c.csv"] and validation["calibrated"]["false_alarms"] == []


def test_the_report_is_written_beside_the_json_and_offline(calibrated):
    out, _, _ = calibrated
    page = out.with_suffix(".html").read_text()
    assert page.startswith("<!DOCTYPE html>") and "<script" not in page and "http" not in page.split("<svg")[0]
    for heading in ("Estimates", "Validation on held-out records", "Residuals at the fit", "Records and method"):
        assert f"<h2>{heading}</h2>" in page
    assert "2023-11-14 22:13:20 UTC" in page and "c.csv" in page and "autocorrelation of the held-out" in page


# ------------------------------------------------------------------------------------------- options

def test_parameters_boxes_records_hold_out_zero_level_and_prior(bench, tmp_path):
    out = tmp_path / "jb.json"
    code, stdout, stderr = run("calibrate", "dc-motor", bench / "a.csv", bench / "b.csv", "--parameters", "J",
                               "--parameters", "b", "--boxes", "records", "--hold-out", "0", "--level", "0.9",
                               "--prior", "none", "--out", out)
    assert code == 0, stderr
    block = load_model(out).calibration
    assert list(block["estimates"]) == ["J", "b"] and block["validation"] is None
    method = {key: block["method"][key] for key in ("parameters", "level", "prior", "boxes")}
    assert method == {"parameters": ["J", "b"], "level": 0.9, "prior": None, "boxes": "records"}
    assert block["datasheet"]["source"] == "dc-motor"
    assert "90 % interval" in stdout and "no held-out record: no validation" in stdout
    assert [line.split()[0] for line in stdout.splitlines()[1:3]] == ["J", "b"]
    for name, (lo, hi) in block["boxes"].items():  # the spread of the two records' estimates holds the pooled one's
        interval = block["estimates"][name]["interval"]
        value = block["estimates"][name]["estimate"]
        assert lo <= interval[0] / value - 1 + 1e-12 and hi >= interval[1] / value - 1 - 1e-12


def test_set_membership_boxes_keep_the_training_records_inside_and_are_no_wider_than_needed(bench, tmp_path):
    out = tmp_path / "sm.json"
    code, stdout, stderr = run("calibrate", "dc-motor", bench / "a.csv", bench / "c.csv", "--parameters", "J", "b",
                               "--boxes", "set-membership", "--hold-out", "0", "--out", out)
    assert code == 0, stderr
    block = load_model(out).calibration
    assert block["method"]["boxes"] == "set-membership" and set(block["boxes"]) == {"J", "b"}
    assert all(-1.0 < lo <= 0.0 <= hi for lo, hi in block["boxes"].values())
    # the calibrated model holds the records within the noise margins: no box wider than its confidence interval
    for name, (lo, hi) in block["boxes"].items():
        interval, value = block["estimates"][name]["interval"], block["estimates"][name]["estimate"]
        assert hi - lo <= (interval[1] - interval[0]) / value + 1e-12, name


def test_a_parameter_the_record_tells_less_well_than_the_datasheet_is_named_and_held(tmp_path):
    """Steps only: the armature's 1 ms transient hides in them and L_a is told less well than by the datasheet."""
    import numpy as np
    from scipy.integrate import solve_ivp

    from diagnosis import add_noise, as_record

    def steps(t):
        return 12.0 * (t >= 0.05) - 6.0 * (t >= 1.0)

    def rhs(t, x):
        return [(steps(t) - TRUE["R_a"] * x[0] - TRUE["k_m"] * x[1]) / TRUE["L_a"],
                (TRUE["k_m"] * x[0] - TRUE["b"] * x[1]) / TRUE["J"]]

    t = np.linspace(0.0, 2.0, 4001)
    sol = solve_ivp(rhs, (0.0, 2.0), [0.0, 0.0], t_eval=t, method="LSODA", rtol=1e-10, atol=1e-12, max_step=1e-3)
    record = add_noise(as_record({"t": t, "U": steps(t), "i": sol.y[0], "omega": sol.y[1]}),
                       {"i": 0.01, "omega": 0.2}, seed=3)
    path = write_record(tmp_path / "steps.csv", record)
    sheet = tmp_path / "sheet.json"
    sheet.write_text(to_json(dc_motor(**{**DATASHEET, "L_a": 0.8 * TRUE["L_a"]}), inputs={"U": 12.0}, t_end=2.0))
    code, stdout, stderr = run("--quiet", "calibrate", sheet, path, "--hold-out", "0", "--out", tmp_path / "s.json")
    assert code == 0, stderr
    assert "told less well by the records than by the datasheet: L_a; L_a kept at its datasheet value" in stdout
    block = load_model(tmp_path / "s.json").calibration
    assert "L_a" not in block["estimates"] and {"R_a", "k_m", "J", "b"} <= set(block["estimates"])
    assert "Told less well by the records than by the datasheet" in (tmp_path / "s.html").read_text()


def test_window_and_quadrature_reach_the_fit_and_the_provenance(bench, tmp_path):
    out = tmp_path / "wq.json"
    code, _, stderr = run("--quiet", "calibrate", "dc-motor", bench / "a.csv", "--parameters", "J", "b",
                          "--window", "20", "--quadrature", "euler", "--hold-out", "0", "--out", out)
    assert code == 0, stderr
    method = load_model(out).calibration["method"]
    assert (method["window"], method["quadrature"]) == (20, "euler")
    default = tmp_path / "default.json"
    assert run("--quiet", "calibrate", "dc-motor", bench / "a.csv", "--parameters", "J", "b", "--hold-out", "0",
               "--out", default)[0] == 0
    # 21-sample windows: more rows than the default's 51 (2001 samples), and another estimate
    assert load_model(out).calibration["method"]["samples"] > 2 * load_model(default).calibration["method"]["samples"]


def test_validate_and_report_and_force(bench, tmp_path):
    out, report = tmp_path / "v.json", tmp_path / "pages" / "calibration.html"
    argv = ["--quiet", "calibrate", bench / "sheet.json", bench / "a.csv", bench / "b.csv", "--validate",
            bench / "c.csv", bench / "d.csv", "--parameters", "R_a", "J", "b", "--report", report, "--out", out]
    code, stdout, stderr = run(*argv)
    assert code == 0 and stderr == ""
    block = load_model(out).calibration
    assert [(r["name"], r["role"]) for r in block["records"]] == [("a.csv", "training"), ("b.csv", "training"),
                                                                   ("c.csv", "held-out"), ("d.csv", "held-out")]
    assert block["validation"]["held_out"] == ["c.csv", "d.csv"] and "2 held-out record(s)" in stdout
    assert report.is_file() and not out.with_suffix(".html").exists()
    before = out.read_text()
    one_line_error(*run(*argv), "--out", "exists", "--force")
    code, _, _ = run(*argv, "--force")
    assert code == 0 and json.loads(out.read_text())["graph"]["calibration"]["estimates"] == \
        json.loads(before)["graph"]["calibration"]["estimates"]


def test_hold_out_two_and_one_record_alone(bench, tmp_path):
    code, stdout, stderr = run("calibrate", bench / "sheet.json", bench / "a.csv", bench / "c.csv", bench / "d.csv",
                               "--hold-out", "2", "--parameters", "J", "b", "--out", tmp_path / "h.json")
    assert code == 0, stderr
    roles = [r["role"] for r in load_model(tmp_path / "h.json").calibration["records"]]
    assert roles == ["training", "held-out", "held-out"] and "2 held-out record(s)" in stdout
    code, stdout, stderr = run("calibrate", bench / "sheet.json", bench / "a.csv", "--parameters", "J",
                               "--out", tmp_path / "one.json")
    assert code == 0 and "one record: nothing is held out, so no validation" in stderr
    assert "no held-out record: no validation" in stdout


# ------------------------------------------------------------------------------------------- bad input

@pytest.fixture(scope="module")
def bad_records(bench):
    """A record without the speed column, and a model whose extra resistor is in no ARR."""
    record = motor_record(10.0, 7)
    write_record(bench / "no_omega.csv", record, columns=("U", "i"))
    data = json.loads(to_json(dc_motor(**DATASHEET)))
    data["nodes"] += [{"id": "V2", "kind": "Se"}, {"id": "J9", "kind": "1"}, {"id": "R_x", "kind": "R", "value": 2.0}]
    data["links"] += [{"source": "V2", "target": "J9"}, {"source": "J9", "target": "R_x"}]
    (bench / "extra.json").write_text(json.dumps(data))
    return bench


@pytest.mark.parametrize("extra, words", [
    (["--parameters", "R_z"], ["--parameters 'R_z'", "no such parameter", "R_a"]),
    (["--boxes", "records", "--hold-out", "1"], ["--boxes records", "two training records", "got 1"]),
    (["--boxes", "records"], ["--boxes records", "got 1", "held out by default: give --hold-out 0"]),
    (["--hold-out", "2"], ["--hold-out 2", "[0, 1]"]),
    (["--hold-out", "-1"], ["--hold-out -1"]),
    (["--hold-out", "1", "--validate", "{d}"], ["--validate", "not allowed with argument --hold-out"]),
    (["--validate", "{a}"], ["--validate", "a.csv", "also a training record"]),
    (["--validate", "{d}", "{d}"], ["--validate", "d.csv", "given twice"]),
    (["--level", "1.5"], ["--level", "(0, 1)"]),
    (["--prior", "-1"], ["--prior", "> 0"]),
    (["--prior", "wide"], ["--prior", "invalid prior value: 'wide'"]),
    (["--boxes", "spread"], ["--boxes", "invalid choice"]),
    (["--window", "1"], ["--window", "invalid window (a whole number of samples >= 2) value: '1'"]),
    (["--window", "ten"], ["--window", "invalid window"]),
    (["--quadrature", "simpson"], ["--quadrature", "invalid choice"]),
    (["--window", "5000"], ["HEALTHY.csv", "no window of 5001 usable samples"]),
])
def test_bad_options_exit_2_in_one_line(bench, tmp_path, extra, words):
    extra = [e.format(a=bench / "a.csv", d=bench / "d.csv") for e in extra]
    out = tmp_path / "x.json"
    result = run("--quiet", "calibrate", bench / "sheet.json", bench / "a.csv", bench / "b.csv", "--out", out, *extra)
    one_line_error(*result, *words)
    assert not out.exists() and not out.with_suffix(".html").exists()


def test_bad_files_exit_2_in_one_line_and_no_input_is_overwritten(bad_records, tmp_path):
    bench = bad_records
    sheet, a, b = bench / "sheet.json", bench / "a.csv", bench / "b.csv"
    model_text, record_text = sheet.read_text(), a.read_text()
    one_line_error(*quiet(sheet, a, b, "--out", sheet), "--out", "is the input file")
    one_line_error(*quiet(sheet, a, b, "--out", tmp_path / "c.json", "--report", a), "--report",
                   "is the input file")
    one_line_error(*quiet(sheet, a, b, "--out", tmp_path / "c.json", "--report", tmp_path / "c.json"),
                   "--report", "the same file as --out")
    one_line_error(*quiet(sheet, a, b, "--out", tmp_path / "c.txt"), "--out", ".json")
    one_line_error(*quiet(sheet, a, a, "--out", tmp_path / "c.json"), "a.csv", "given twice")
    one_line_error(*quiet(sheet, a, bench / "no_omega.csv", "--out", tmp_path / "c.json"),
                   "no_omega.csv", "omega")
    one_line_error(*quiet(bench / "nothing.json", a, "--out", tmp_path / "c.json"), "nothing.json")
    one_line_error(*quiet(sheet, bench / "nothing.csv", "--out", tmp_path / "c.json"), "nothing.csv")
    one_line_error(*quiet(bench / "extra.json", a, "--parameters", "R_x", "--out", tmp_path / "c.json"),
                   "--parameters R_x", "in no ARR")
    one_line_error(*quiet(sheet, a, b), "--out")
    (tmp_path / "taken.html").write_text("mine")
    one_line_error(*quiet(sheet, a, b, "--out", tmp_path / "taken.json"), "taken.html", "exists",
                   "--force")
    assert (tmp_path / "taken.html").read_text() == "mine" and not (tmp_path / "taken.json").exists()
    assert sheet.read_text() == model_text and a.read_text() == record_text
    assert not list(tmp_path.glob("c.*"))


def test_an_error_after_the_estimate_leaves_no_output(bench, tmp_path, monkeypatch):
    """Both files are composed before the first is written: a failure on the way leaves neither."""
    import bgphm.run_report as pages

    def broken(*args, **kwargs):
        raise RuntimeError("the page failed")

    monkeypatch.setattr(pages, "calibration_page", broken)
    code, _, err = run("calibrate", bench / "sheet.json", bench / "a.csv", "--parameters", "J", "--out",
                       tmp_path / "cal.json")
    assert code == 1 and "the page failed" in err
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------- files and text

@pytest.fixture
def umask():
    saved = os.umask(0o022)
    yield lambda mask: os.umask(mask)
    os.umask(saved)


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600)])
def test_both_files_take_the_mode_the_umask_gives(bench, tmp_path, umask, mask, mode):
    umask(mask)
    code, _, err = run("--quiet", "calibrate", bench / "sheet.json", bench / "a.csv", "--parameters", "b",
                       "--out", tmp_path / "cal.json")
    assert code == 0, err
    assert {p.name: stat.S_IMODE(p.stat().st_mode) for p in tmp_path.iterdir()} == {"cal.json": mode,
                                                                                    "cal.html": mode}


def test_a_hostile_model_name_and_record_name_are_escaped_in_the_report(bench, tmp_path):
    data = json.loads((bench / "sheet.json").read_text())
    data["graph"]["name"] = "<script>alert('x')</script>"
    model = tmp_path / "hostile.json"
    model.write_text(json.dumps(data))
    record = tmp_path / "<img src=x onerror=alert(1)>.csv"
    record.write_bytes((bench / "a.csv").read_bytes())
    code, _, err = run("--quiet", "calibrate", model, record, "--parameters", "J", "--out", tmp_path / "cal.json")
    assert code == 0, err
    page = (tmp_path / "cal.html").read_text()
    assert "<script" not in page and "<img" not in page
    assert "&lt;script&gt;alert(&#x27;x&#x27;)&lt;/script&gt;" in page
    assert "&lt;img src=x onerror=alert(1)&gt;.csv" in page
    assert load_model(tmp_path / "cal.json").model.name == "<script>alert('x')</script>"  # kept as data, in JSON


def test_a_function_of_time_the_json_cannot_hold_is_left_out_and_said():
    from bgphm.commands.calibrate import _storable
    from bondgraph.inputs import InputExpression

    said = []
    spec = SimpleNamespace(inputs={"U": 12.0, "V": InputExpression("step(t - 1)"), "W": lambda t: t},
                           x0={"q": 1.0}, t_end=3.0)
    kept = _storable(spec, said.append)
    assert set(kept["inputs"]) == {"U", "V"} and kept["x0"] == {"q": 1.0} and kept["t_end"] == 3.0
    assert len(said) == 1 and "'W'" in said[0] and "JSON cannot hold" in said[0]
