"""The bgphm command line: commands, exit codes, bad input named in one line, model files parsed without eval."""

import json
import subprocess
import sys

import numpy as np
import pytest

from bgphm.cli import main
from bondgraph.errors import LawError, ModelError
from bondgraph.io import ModelFileError, load_model, model_from_json, to_json
from bondgraph.library import dc_motor, rlc_circuit


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def motor_csv(tmp_path_factory):
    """A clean DC-motor record (U, i, omega) at 1 kHz over 1 s, written by `bgphm simulate`."""
    path = tmp_path_factory.mktemp("data") / "motor.csv"
    assert main(["--quiet", "simulate", "dc-motor", "--t-end", "1", "--samples", "1001", "--out", str(path)]) == 0
    return path


def write_csv(path, header, rows):
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n")
    return path


def motor_rows(motor_csv):
    lines = motor_csv.read_text().splitlines()
    return lines[0].split(","), [line.split(",") for line in lines[1:]]


# ------------------------------------------------------------------------------------------- commands

def test_simulate_writes_the_signals_as_csv(motor_csv):
    header, rows = motor_rows(motor_csv)
    assert header == ["t", "U", "i", "omega"]
    assert len(rows) == 1001
    omega = np.array([float(r[3]) for r in rows])
    # steady state of the motor at 12 V: omega = k_m U / (k_m^2 + R_a b)
    k_m, r_a, b = 3.89e-2, 1.23, 1e-4
    assert omega[-1] == pytest.approx(k_m * 12.0 / (k_m ** 2 + r_a * b), rel=1e-3)


def test_simulate_set_overrides_a_parameter(tmp_path, capsys):
    out = tmp_path / "slow.csv"
    code, _, _ = run(capsys, "--quiet", "simulate", "dc-motor", "--t-end", "1", "--set", "b=1e-3", "--out", str(out))
    assert code == 0
    last = out.read_text().splitlines()[-1].split(",")
    assert float(last[3]) == pytest.approx(3.89e-2 * 12.0 / (3.89e-2 ** 2 + 1.23e-3), rel=1e-3)
    code, _, err = run(capsys, "simulate", "dc-motor", "--set", "zeta=1")
    assert code == 2 and "'zeta'" in err and "R_a" in err


def test_detect_on_a_healthy_record_raises_no_alarm(motor_csv, tmp_path, capsys):
    code, out, err = run(capsys, "detect", "dc-motor", str(motor_csv), "--margin", "1e-3", "--out", str(tmp_path))
    assert code == 0, err
    summary = json.loads((tmp_path / "detection.json").read_text())
    assert summary["detection_time"] is None and set(summary["arrs"]) == {"ARR_1_e", "ARR_1_m"}
    assert "no alarm" in out and "deriving the ARRs" in err  # progress goes to stderr
    header = (tmp_path / "residuals.csv").read_text().splitlines()[0].split(",")
    assert header[:5] == ["t", "ARR_1_e.residual", "ARR_1_e.lower", "ARR_1_e.upper", "ARR_1_e.alarm"]


def test_detect_finds_a_friction_fault(tmp_path, capsys):
    data = tmp_path / "faulty.csv"
    assert main(["--quiet", "simulate", "dc-motor", "--t-end", "1", "--samples", "1001", "--set", "b=5e-4",
                 "--out", str(data)]) == 0
    code, out, _ = run(capsys, "--quiet", "detect", "dc-motor", str(data), "--margin", "1e-3", "--arr", "ARR_1_m",
                       "--out", str(tmp_path / "detect"))
    assert code == 0
    assert "ARR_1_m: alarm at t =" in out and "ARR_1_e" not in out
    # residuals.csv: the band is on the residual it sits next to, so every sample in alarm lies outside it
    table = np.genfromtxt(tmp_path / "detect" / "residuals.csv", delimiter=",", names=True)
    residual, lower, upper, alarm = (table[f"ARR_1_m{c}"] for c in ("residual", "lower", "upper", "alarm"))
    decided = np.isfinite(lower)  # the ends, where a derivative estimate extrapolates, are left undecided
    assert decided[100:-100].all() and np.all(lower[decided] < upper[decided]) and alarm.any()
    assert not np.allclose(lower[decided], -upper[decided])  # a one-sided band
    outside = (residual < lower) | (residual > upper)
    assert np.all(outside | (alarm == 0))
    summary = json.loads((tmp_path / "detect" / "detection.json").read_text())
    assert outside.sum() == summary["arrs"]["ARR_1_m"]["violations"]


def test_quiet_silences_progress(motor_csv, capsys):
    code, out, err = run(capsys, "--quiet", "detect", "dc-motor", str(motor_csv), "--margin", "1e-3")
    assert code == 0 and err == "" and "ARR_1_m" in out


def test_arr_report_formats(tmp_path, capsys):
    for fmt in ("md", "html", "tex"):
        out = tmp_path / f"report.{fmt}"
        code, _, err = run(capsys, "--quiet", "arr", "dc-motor", "--format", fmt, "--out", str(out))
        assert code == 0, err
        text = out.read_text()
        name = "ARR\\_1\\_m" if fmt == "tex" else "ARR_1_m"
        parameter = "<msub><mi>k</mi><mi>m</mi></msub>" if fmt == "html" else "k_{m}"  # typeset, as in the ARRs
        assert name in text and parameter in text
    html = (tmp_path / "report.html").read_text()
    assert "<svg" in html and "<math" in html
    assert "http://" not in html.replace("http://www.w3.org/", "")  # nothing fetched from the network
    assert "\\begin{tikzpicture}" in (tmp_path / "report.tex").read_text()


def test_reports_typeset_deltas_and_signals_with_their_own_subscripts():
    """delta_L_a is delta sub L_a (sympy alone prints delta_{L a}); omega(t) is a Greek omega, not 'omega'."""
    from diagnosis.report import arr_report

    tex, md, html = (arr_report(dc_motor(), fmt) for fmt in ("tex", "md", "html"))
    for text in (tex, md):
        assert "\\delta_{L_{a}}" in text and "\\delta_{k_{m}}" in text and "\\omega{\\left(t \\right)}" in text
        assert "\\delta_{L a}" not in text
    assert ("<msub><mi>&#948;</mi><msub><mi>L</mi><mi>a</mi></msub></msub>" in html
            and '<mi>&#969;</mi><mrow><mo stretchy="false">(</mo><mi>t</mi><mo stretchy="false">)</mo></mrow>' in html)
    assert "<mi>omega</mi>" not in html and "delta" not in html.split("<math", 1)[1]


def test_python_model_file(tmp_path, capsys):
    path = tmp_path / "circuit.py"
    path.write_text("from bondgraph.library import rlc_circuit\n\ndef build():\n    return rlc_circuit(R=5.0)\n\n"
                    "inputs = {'V': 2.0}\nt_end = 0.2\n")
    spec = load_model(path)
    assert spec.model.parameters["R"] == 5.0 and spec.inputs == {"V": 2.0} and spec.t_end == 0.2
    code, out, _ = run(capsys, "--quiet", "simulate", str(path), "--samples", "11")
    assert code == 0 and out.splitlines()[0] == "t,V,i,v_C" and len(out.splitlines()) == 12
    path.write_text("x = 1\n")
    code, _, err = run(capsys, "simulate", str(path))
    assert code == 2 and "circuit.py" in err and "define 'model'" in err
    path.write_text("def model(:\n")
    code, _, err = run(capsys, "simulate", str(path))
    assert code == 2 and "circuit.py line 1" in err


def test_json_round_trip_keeps_the_model():
    bg = dc_motor()
    again = model_from_json(to_json(bg, inputs={"U": 12.0}, t_end=1.0)).model
    assert again.parameters == bg.parameters and again.uncertainties == bg.uncertainties
    assert [(b.tail, b.head) for b in again.bonds] == [(b.tail, b.head) for b in bg.bonds]
    assert str(again.state_equations()) == str(bg.state_equations())


def test_unexpected_errors_exit_1_and_interrupts_are_clean(monkeypatch, capsys):
    import bgphm.commands.arr as command

    def boom(args, progress):
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(command, "run", boom)
    code, _, err = run(capsys, "arr", "dc-motor")
    assert code == 1 and "RuntimeError: disk on fire" in err and "--debug" in err

    def interrupted(args, progress):
        raise KeyboardInterrupt

    monkeypatch.setattr(command, "run", interrupted)
    code, _, err = run(capsys, "arr", "dc-motor")
    assert code == 1 and "interrupted" in err


@pytest.mark.slow  # two interpreters started: about 4 s
def test_console_entry_point_runs():
    done = subprocess.run([sys.executable, "-m", "bgphm", "--help"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "prognose" in done.stdout
    done = subprocess.run([sys.executable, "-m", "bgphm", "frobnicate"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "invalid choice" in done.stderr


# ------------------------------------------------------------------------------------------- bad input

def test_missing_files(tmp_path, capsys, motor_csv):
    code, _, err = run(capsys, "arr", str(tmp_path / "nope.json"))
    assert code == 2 and "nope.json: no such file" in err and len(err.strip().splitlines()) == 1
    code, _, err = run(capsys, "detect", "dc-motor", str(tmp_path / "nope.csv"))
    assert code == 2 and "nope.csv: no such file" in err


def test_csv_without_t(tmp_path, capsys):
    path = write_csv(tmp_path / "d.csv", ["time", "U", "i", "omega"], [[0, 1, 2, 3], [1, 1, 2, 3], [2, 1, 2, 3]])
    code, _, err = run(capsys, "--quiet", "detect", "dc-motor", str(path))
    assert code == 2 and "no time column 't'" in err and "rename 'time' to 't'" in err


def test_csv_missing_sensor_column(motor_csv, tmp_path, capsys):
    header, rows = motor_rows(motor_csv)
    path = write_csv(tmp_path / "d.csv", header[:3], [r[:3] for r in rows])  # no omega
    code, _, err = run(capsys, "--quiet", "detect", "dc-motor", str(path))
    assert code == 2 and "'omega'" in err and "missing column" in err


def test_csv_non_numeric_cell_names_line_and_column(motor_csv, tmp_path, capsys):
    header, rows = motor_rows(motor_csv)
    rows[9][2] = "12,5".replace(",", ";")
    path = write_csv(tmp_path / "d.csv", header, rows)
    code, _, err = run(capsys, "--quiet", "detect", "dc-motor", str(path))
    assert code == 2 and "line 11, column 'i'" in err and "'12;5' is not a number" in err


def test_csv_non_monotonic_time(motor_csv, tmp_path, capsys):
    header, rows = motor_rows(motor_csv)
    rows[20][0], rows[21][0] = rows[21][0], rows[20][0]
    path = write_csv(tmp_path / "d.csv", header, rows)
    code, _, err = run(capsys, "--quiet", "detect", "dc-motor", str(path))
    assert code == 2 and "line 23, column 't'" in err and "does not increase" in err


def test_csv_ragged_row(motor_csv, tmp_path, capsys):
    header, rows = motor_rows(motor_csv)
    rows[4] = rows[4][:2]
    path = write_csv(tmp_path / "d.csv", header, rows)
    code, _, err = run(capsys, "--quiet", "detect", "dc-motor", str(path))
    assert code == 2 and "line 6: 2 cells for 4 columns" in err


@pytest.mark.slow
def test_csv_nan_run_is_a_reported_gap(motor_csv, tmp_path, capsys):
    header, rows = motor_rows(motor_csv)
    for r in rows[400:450]:
        r[3] = ""
    path = write_csv(tmp_path / "d.csv", header, rows)
    code, out, err = run(capsys, "detect", "dc-motor", str(path), "--margin", "1e-3", "--out", str(tmp_path / "o"))
    assert code == 0
    assert "column 'omega' has a gap of 50 sample(s) for t in [0.4, 0.449]" in err
    summary = json.loads((tmp_path / "o" / "detection.json").read_text())
    assert summary["arrs"]["ARR_1_m"]["undecided_samples"] >= 50 and summary["detection_time"] is None
    for r in rows:
        r[3] = "nan"
    path = write_csv(tmp_path / "d.csv", header, rows)
    code, _, err = run(capsys, "--quiet", "detect", "dc-motor", str(path))
    assert code == 2 and "column 'omega' has no value" in err


def test_unknown_candidate(motor_csv, capsys):
    code, _, err = run(capsys, "--quiet", "prognose", "dc-motor", str(motor_csv), "--candidate", "mu",
                       "--degradation", "linear", "--fail", "1")
    assert code == 2 and "--candidate 'mu'" in err and "R_a, L_a, k_m, J, b" in err


@pytest.mark.parametrize("extra, message", [
    (["--fail", "1e-5", "--direction", "up"], "wrong side of the nominal value 0.0001"),
    (["--fail", "1e-5", "--direction", "up"], "lies below nominal; give --direction down"),
    (["--fail", "1e-3", "--direction", "down"], "lies above nominal; give --direction up"),
    (["--fail", "1e-4"], "equals the nominal value"),
    (["--fail=-1e-3"], "outside the physical domain (0, inf)"),  # the exponential sign check comes after
])
def test_failure_value_on_the_wrong_side(motor_csv, capsys, extra, message):
    code, _, err = run(capsys, "--quiet", "prognose", "dc-motor", str(motor_csv), "--candidate", "b",
                       "--degradation", "exponential", *extra)
    assert code == 2 and message in err


@pytest.mark.parametrize("extra, message", [
    (["--horizon", "0"], "--horizon must be a positive number of seconds, got 0.0"),  # was silently the default
    (["--horizon=-5"], "--horizon must be a positive number of seconds, got -5.0"),
    (["--dt", "0"], "--dt must be a positive number of seconds, got 0.0"),
    (["--rul-every", "0"], "--rul-every must be at least 1 filter step, got 0"),
    (["--margin", "1e-3", "--calibrate", "0.001"], "only 2 samples before it; at least 20 are needed to "
                                                   "estimate the residual noise"),
])
def test_bad_prognosis_settings_exit_2_naming_the_option(motor_csv, capsys, extra, message):
    code, _, err = run(capsys, "--quiet", "prognose", "dc-motor", str(motor_csv), "--candidate", "b",
                       "--degradation", "exponential", "--fail", "2e-3", *extra)
    assert code == 2 and message in err
    assert "or give --margin" not in err  # the filter needs the noise level even with a margin


def test_bad_usage_exits_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["detect", "dc-motor"])  # DATA.csv missing
    assert exc.value.code == 2
    code, _, err = run(capsys, "detect", "dc-motor", "x.csv", "--persistence", "0")
    assert code == 2 and "--persistence" in err


# ------------------------------------------------------------------------------------------- hostile JSON

def motor_json(**law):
    data = json.loads(to_json(rlc_circuit()))
    for node in data["nodes"]:
        if node["id"] == "R":
            node.update(law)
    return json.dumps(data)


@pytest.mark.parametrize("law", [
    "e - R*f.__class__",                                   # attribute access
    "__import__('os').system('echo pwned')",               # import through a dunder
    "e - R*f + __builtins__",                              # dunder name
    "(lambda: 1)() + e - R*f",                             # lambda
    "e - R*f + 9**9**9",                                   # huge exponent
    "e - R*f + (10**100)**100",                            # huge number
    "e - R*f + eval('1')",                                 # a call that is not a law function
    "e - R*f + [1, 2][0]",                                 # subscripts, lists
    "import os",                                           # a statement
    "e - R*f if e else f",                                 # conditional expression
    "e/0 - f",                                             # a division by zero (found by test_fuzz.py)
    "log(0)*e - f",                                        # an infinite constant
])
def test_hostile_laws_are_rejected_with_the_node_named(law, tmp_path, capsys):
    with pytest.raises(LawError) as exc:
        model_from_json(motor_json(law=law), where="m.json")
    assert "'R'" in str(exc.value) and "m.json" in str(exc.value)
    path = tmp_path / "m.json"
    path.write_text(motor_json(law=law))
    code, _, err = run(capsys, "arr", str(path))
    assert code == 2 and "m.json" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("change, message", [
    ({"value": "__import__('os')"}, "'value' must be a number"),
    ({"law": ["e", "-", "f"]}, "'law' must be a string"),
    ({"uncertainty": [-0.1]}, "expected [lo, hi]"),
    ({"exec": "print(1)"}, "unknown field(s) ['exec']"),
    ({"kind": "Xx"}, "unknown kind 'Xx'"),
])
def test_bad_node_fields_are_named(change, message):
    with pytest.raises(ModelError) as exc:
        model_from_json(motor_json(**change), where="m.json")
    assert message in str(exc.value) and "'R'" in str(exc.value)


def test_bad_json_documents_are_named():
    with pytest.raises(ModelFileError, match=r"m.json line 1 column \d+: not valid JSON"):
        model_from_json('{"nodes": [}', where="m.json")
    with pytest.raises(ModelFileError, match="NaN is not a finite number"):
        model_from_json('{"nodes": [{"id": "R", "kind": "R", "value": NaN}], "links": []}', where="m.json")
    with pytest.raises(ModelFileError, match="overflows"):
        model_from_json('{"nodes": [{"id": "R", "kind": "R", "value": 1e999}], "links": []}', where="m.json")
    with pytest.raises(ModelFileError, match=r"links\[0\] \('V' -> 'X'\): node 'X' is not in 'nodes'"):
        model_from_json('{"nodes": [{"id": "V", "kind": "Se"}], "links": [{"source": "V", "target": "X"}]}',
                        where="m.json")
    with pytest.raises(ModelFileError, match="graph.inputs names \\['W'\\]"):
        data = json.loads(to_json(rlc_circuit()))
        data["graph"]["inputs"] = {"W": 1.0}
        model_from_json(json.dumps(data), where="m.json")


@pytest.mark.slow  # runs bgphm demo
def test_demo_runs_the_chain_and_predicts_the_injected_end_of_life(tmp_path, capsys):
    code, out, _ = run(capsys, "--quiet", "demo", "dc-motor", "--out", str(tmp_path))
    assert code == 0
    for name in ("model.json", "data.csv", "truth.json", "report.html", "detect/detection.json",
                 "prognose/prognosis.json", "prognose/rul.csv"):
        assert (tmp_path / name).exists(), name
    assert "$ bgphm prognose" in out  # each command is shown so it can be rerun by hand
    truth = json.loads((tmp_path / "truth.json").read_text())
    summary = json.loads((tmp_path / "prognose" / "prognosis.json").read_text())
    assert truth["onset"] < summary["detection_time"] < truth["eol"]
    assert summary["filter_step"] == 0.011  # a derivative window of 11 samples of 1 ms, without float dust
    assert summary["candidate"] == "b" and summary["degradation"] in ("linear", "exponential")
    last = summary["last"]
    true_rul = truth["eol"] - last["t"]
    assert last["rul_p5"] <= true_rul <= last["rul_p95"]
    assert abs(last["rul_median"] - true_rul) < 0.3 * true_rul
    b_true = truth["nominal"] * np.exp(truth["rate"] * (last["t"] - truth["onset"]))
    assert last["theta_mean"] == pytest.approx(b_true, rel=0.1)


# ------------------------------------------------------------------------------------------- guards

@pytest.mark.parametrize("argv, message", [
    (["simulate", "rlc", "--samples", "100000000"], "--samples"),
    (["simulate", "rlc", "--t-end", "1e-300"], "--t-end must be a number of seconds of at least 1e-12"),
    (["simulate", "rlc", "--t-end", "-1"], "--t-end must be"),
])
def test_simulation_guards_name_the_option(capsys, argv, message):
    code, _, err = run(capsys, "--quiet", *argv)
    assert code == 2 and message in err and err.count("\n") == 1


def test_an_open_circuit_or_a_tiny_capacitance_simulates_with_a_warning(tmp_path, capsys):
    # LSODA gives up on both; the CLI used to end in AttributeError, exit 1
    for setting, column, expected in [("R=1e12", "i", 1.0 / 1e12), ("C=1e-300", "v_C", 1.0)]:
        out = tmp_path / f"{setting}.csv"
        code, _, err = run(capsys, "simulate", "rlc", "--set", setting, "--out", str(out))
        assert code == 0, err
        assert "bgphm: warning: LSODA failed" in err and "integrated with Radau instead" in err
        header, *rows = out.read_text().splitlines()
        last = dict(zip(header.split(","), map(float, rows[-1].split(","))))
        # the source voltage is 1 V: through 1e12 ohm flows 1e-12 A; a 1e-300 F capacitor follows the source
        assert last[column] == pytest.approx(expected, rel=1e-3)


@pytest.mark.slow
def test_a_hopeless_simulation_ends_in_one_line_naming_the_limit(tmp_path, capsys):
    # an undamped LC circuit over 1.4e6 s, i.e. about 3e7 periods: found by test_fuzz.py, which it held for
    # minutes of CPU; the pace check stops it after PACE_START evaluations
    model = tmp_path / "rlc.json"
    model.write_text(to_json(rlc_circuit(), inputs={"V": 1.0}, t_end=0.2))
    code, _, err = run(capsys, "--quiet", "simulate", str(model), "--set", "R=0", "--t-end", "1436643",
                       "--out", str(tmp_path / "o.csv"))
    assert code == 2 and err.count("\n") == 1
    assert err.startswith("bgphm: error: max_evaluations: ") and "at that pace" in err
    assert not (tmp_path / "o.csv").exists()


def test_uneven_sampling_is_resampled_on_request(motor_csv, tmp_path, capsys):
    header, rows = motor_rows(motor_csv)
    uneven = write_csv(tmp_path / "uneven.csv", header + ["operator"],
                       [r + ["alice"] for k, r in enumerate(rows) if k % 7 != 3])  # a sample in 7 lost
    code, _, err = run(capsys, "detect", "dc-motor", str(uneven), "--margin", "1e-3")
    assert code == 2 and "--resample" in err
    code, out, err = run(capsys, "detect", "dc-motor", str(uneven), "--margin", "1e-3", "--resample")
    assert code == 0 and "ARR_1_m: no alarm" in out
    assert "'operator'" in err and "ignored" in err  # the text column no ARR uses: a note, not an error
    assert "resampled" in err and "uniform step of 0.001 s" in err


def test_a_failure_value_outside_the_physical_domain_is_refused(motor_csv, capsys):
    code, _, err = run(capsys, "--quiet", "prognose", "dc-motor", str(motor_csv), "--fail", "b=-1e-3")
    assert code == 2 and "--fail b=-0.001: outside the physical domain (0, inf)" in err
