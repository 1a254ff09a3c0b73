"""What the commands write: never an input, never an output without --force, checked first, written whole."""

import json
import os
import re

import numpy as np
import pytest

from bgphm.cli import main
from bgphm.errors import UsageError
from bgphm.files import check_output, write_text, write_with
from bondgraph.io import to_json
from bondgraph.library import dc_motor


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def motor(tmp_path_factory):
    """A DC-motor model file and a healthy record (1 kHz over 1 s) in their own directory."""
    folder = tmp_path_factory.mktemp("motor")
    model = folder / "model.json"
    model.write_text(to_json(dc_motor(), inputs={"U": 12.0}, t_end=1.0))
    data = folder / "data.csv"
    assert main(["--quiet", "simulate", str(model), "--samples", "1001", "--out", str(data)]) == 0
    return model, data


def snapshot(*paths):
    return {p: p.read_bytes() for p in paths}


# ------------------------------------------------------------------------------------------- inputs are never outputs

@pytest.mark.parametrize("command", [["arr"], ["arr", "--format", "html"], ["simulate"]])
def test_an_output_file_that_is_the_model_is_refused_with_force_too(motor, capsys, command):
    model, _ = motor
    before = snapshot(model)
    for force in ([], ["--force"]):
        code, _, err = run(capsys, command[0], str(model), *command[1:], "--out", str(model), *force)
        assert code == 2 and f"--out {model} is the input file" in err
        assert snapshot(model) == before


@pytest.mark.parametrize("command", ["detect", "prognose"])
def test_an_output_directory_that_holds_an_input_is_refused(motor, capsys, command):
    model, data = motor
    before = snapshot(model, data)
    extra = ["--fail", "b=2e-3"] if command == "prognose" else []
    for out in (data.parent, data.parent.parent):  # the data's own directory, or one above it
        code, _, err = run(capsys, "--quiet", command, str(model), str(data), *extra, "--out", str(out), "--force")
        assert code == 2 and "holds the input file" in err and err.count("\n") == 1
    assert snapshot(model, data) == before


def test_the_record_is_never_an_output(motor, capsys):
    model, data = motor
    before = snapshot(data)
    code, _, err = run(capsys, "detect", str(model), str(data), "--out", str(data), "--force")
    assert code == 2 and "is the input file" in err
    code, _, err = run(capsys, "arr", str(model), "--out", str(data), "--force")  # not its input, but ...
    assert code == 0 and snapshot(data) != before  # ... --force replaces it: the user asked
    data.write_bytes(before[data])


def test_demo_refuses_a_directory_with_the_users_files(tmp_path, capsys):
    mine = tmp_path / "model.json"
    mine.write_text("my own model")
    code, _, err = run(capsys, "--quiet", "demo", "dc-motor", "--out", str(tmp_path))
    assert code == 2 and "is not empty; give --force" in err
    assert mine.read_text() == "my own model"


# ------------------------------------------------------------------------------------------- outputs need --force

def test_an_existing_output_file_is_replaced_only_with_force(tmp_path, capsys):
    report = tmp_path / "report.md"
    report.write_text("keep me")
    code, _, err = run(capsys, "--quiet", "arr", "rlc", "--out", str(report))
    assert code == 2 and "exists; give --force to replace it" in err and report.read_text() == "keep me"
    code, out, _ = run(capsys, "--quiet", "arr", "rlc", "--out", str(report), "--force")
    assert code == 0 and report.read_text().startswith("#") and f"wrote {report}" in out


def test_a_non_empty_output_directory_needs_force(motor, tmp_path, capsys):
    model, data = motor
    other = tmp_path / "notes.txt"
    other.write_text("mine")
    code, _, err = run(capsys, "--quiet", "detect", str(model), str(data), "--margin", "1e-3", "--out", str(tmp_path))
    assert code == 2 and "is not empty" in err
    code, _, _ = run(capsys, "--quiet", "detect", str(model), str(data), "--margin", "1e-3", "--out", str(tmp_path),
                     "--force")
    assert code == 0 and other.read_text() == "mine" and (tmp_path / "detection.json").exists()


@pytest.mark.parametrize("argv, message", [
    (["simulate", "rlc", "--out", "{dir}"], "is a directory; give a file name"),
    (["arr", "rlc", "--out", "{dir}"], "is a directory; give a file name"),
    (["demo", "--out", "{file}"], "exists and is not a directory"),
    (["detect", "rlc", "{file}", "--out", "{file}/sub"], "is a file, not a directory"),
])
def test_output_paths_are_checked_before_any_work(monkeypatch, tmp_path, capsys, argv, message):
    import bondgraph.io

    def no_work(*args, **kwargs):
        raise AssertionError("the command started working before checking --out")

    monkeypatch.setattr(bondgraph.io, "load_model", no_work)
    for command in ("_inputs", "arr", "simulate", "detect"):  # each command module that loads a model
        monkeypatch.setattr(f"bgphm.commands.{command}.load_model", no_work)
    monkeypatch.setattr("bgphm.demo_cases.prepare_demo", no_work)
    (tmp_path / "d").mkdir()
    (tmp_path / "f.csv").write_text("t,x\n")
    argv = [a.format(dir=tmp_path / "d", file=tmp_path / "f.csv") for a in argv]
    code, _, err = run(capsys, *argv)
    assert code == 2 and "--out" in err and message in err and err.count("\n") == 1


# ------------------------------------------------------------------------------------------- atomic writes

def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    path = write_text(tmp_path / "result.json", "old")

    def half(temporary):
        temporary.write_text("half a fi")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_with(path, half)
    assert path.read_text() == "old" and os.listdir(tmp_path) == ["result.json"]


def test_check_output_accepts_new_paths_and_names_the_option(tmp_path):
    assert check_output(tmp_path / "a" / "b.csv", kind="file") == tmp_path / "a" / "b.csv"
    with pytest.raises(UsageError, match="^--report "):
        check_output(tmp_path, kind="file", option="--report")


# ------------------------------------------------------------------------------------------- options and exit codes

@pytest.mark.parametrize("argv, message", [
    (["detect", "{model}", "{data}", "--k", "-1"], "--k must be a positive number"),
    (["detect", "{model}", "{data}", "--k", "nan"], "--k must be a positive number"),
    (["prognose", "{model}", "{data}", "--fail", "b=2e-3", "--seed", "-1"], "--seed must be an integer"),
    (["prognose", "{model}", "{data}", "--fail", "b=2e-3", "--particles", "10000000"],
     "--particles must be a whole number in [2, 100000]"),
    (["detect", "{model}", "{data}", "--calibrate", "100"], "--calibrate 100: at or past the end of the record"),
    (["prognose", "{model}", "{data}", "--fail", "b=2e-3", "--calibrate", "0.5", "--dt", "5"],
     "--dt 5: the filter step is not shorter than the record"),
    (["prognose", "{model}", "{data}", "--fail", "b=2e-3", "--calibrate", "0.5", "--horizon", "1e12"],
     "--horizon 1e+12: "),
    (["prognose", "{model}", "{data}", "--fail", "b=2e-3", "--calibrate", "0.5", "--horizon", "1e4",
      "--particles", "50000"], "GiB of random numbers"),
    (["prognose", "{model}", "{data}", "--fail", "b=2e-3", "--calibrate", "0.5", "--pairs", "--filter", "sir"],
     "--pairs: two faults at once are weighed with --filter resample-move"),
    (["prognose", "{model}", "{data}", "--fail", "b=2e-3", "--calibrate", "0.5", "--pairs", "--filter",
      "resample-move", "--candidate", "b"], "without --candidate only"),
])
def test_bad_options_exit_2_naming_the_option(motor, capsys, argv, message):
    model, data = motor
    code, _, err = run(capsys, "--quiet", *[a.format(model=model, data=data) for a in argv])
    assert code == 2 and message in err and err.startswith("bgphm: error: ") and err.count("\n") == 1


@pytest.mark.slow
def test_calibrating_over_a_fault_is_refused(tmp_path, capsys):
    """Friction b x20 from t = 0.5 s: calibrating on t <= 0.9 would absorb the fault in the margin."""
    from bondgraph.simulation import simulate
    from bgphm.files import csv_text
    from diagnosis.records import add_noise, as_record

    t = np.linspace(0.0, 1.0, 1001)
    b = lambda time: 1e-4 * (1.0 + 19.0 * (time >= 0.5))  # noqa: E731
    result = simulate(dc_motor(), (0.0, 1.0), {"U": 12.0}, parameters={"b": b}, t_eval=t, max_step=1e-3)
    record = add_noise(as_record(result.record()), {"i": 1e-3, "omega": 1e-2}, seed=3)
    data = tmp_path / "faulty.csv"
    data.write_text(csv_text({"t": record.t, **record.columns}))
    code, _, err = run(capsys, "--quiet", "detect", "dc-motor", str(data), "--calibrate", "0.9")
    assert code == 2 and err.startswith("bgphm: error: --calibrate 0.9") and "is not fault-free" in err
    assert "ARR_1_m" in err
    code, out, err = run(capsys, "--quiet", "detect", "dc-motor", str(data), "--calibrate", "0.4")
    # a centred derivative window sees the fault a few samples early
    when = float(re.search(r"ARR_1_m: alarm at t = ([0-9.]+) s", out).group(1))
    assert code == 0 and abs(when - 0.5) <= 0.01, out


def test_library_warnings_reach_stderr_as_one_line_without_a_source_path(monkeypatch, capsys):
    import bgphm.commands.arr as command

    def noisy(args, progress):
        np.log(np.zeros(1))  # numpy's RuntimeWarning, raised in site-packages
        return 0

    monkeypatch.setattr(command, "run", noisy)
    code, _, err = run(capsys, "arr", "rlc")
    assert code == 0 and err.startswith("bgphm: warning: divide by zero") and err.count("\n") == 1
    assert ".py" not in err


@pytest.mark.slow  # runs the dc-motor demo: about 8 s
def test_a_failure_value_on_the_wrong_side_of_the_drift_is_reported(tmp_path, capsys):
    """Friction b grows (x5 from t = 0.5 s); --fail b below nominal contradicts the drift."""
    code, _, _ = run(capsys, "--quiet", "demo", "dc-motor", "--out", str(tmp_path / "demo"))
    assert code == 0
    folder = tmp_path / "demo"
    code, _, err = run(capsys, "--quiet", "detect", str(folder / "model.json"), str(folder / "data.csv"),
                       "--calibrate", "3")  # b is x4 at t = 2.7 s: the split-half check sees it
    assert code == 2 and "--calibrate 3 is not fault-free: calibrated on its first half (t <= 1.5 s)" in err
    code, out, err = run(capsys, "--quiet", "prognose", str(folder / "model.json"), str(folder / "data.csv"),
                         "--fail", "b=1e-5", "--calibrate", "0.9", "--particles", "200", "--out", str(tmp_path / "p"))
    # b's laws are rejected by name, said even with --quiet; the sensors' offsets are what is left to weigh
    assert code == 0 and err.startswith("bgphm: warning: every wear hypothesis was rejected, only sensors' faults "
                                        "are left: b/linear: ")
    assert "wrong side" in err
    summary = json.loads((tmp_path / "p" / "prognosis.json").read_text())
    assert all("wrong side" in summary["evidence"][f"b/{law}"]["rejected"] for law in ("linear", "exponential"))
    # no claim on b: what the data leave is sensors' offsets, or (each law of theirs contradicted by the
    # data) "undecided", listing every fault the fired ARRs are consistent with, b among them
    assert summary["status"] != "isolated"
    assert summary["status"] == "undecided" or "b" not in summary["candidate"]
    # with the sensors taken as healthy (or b the only candidate) nothing is left: no claim
    code, out, err = run(capsys, "--quiet", "prognose", str(folder / "model.json"), str(folder / "data.csv"),
                         "--fail", "b=1e-5", "--calibrate", "0.9", "--particles", "200", "--no-sensors",
                         "--out", str(tmp_path / "no-sensors"))
    assert code == 0 and err.startswith("bgphm: warning: every hypothesis was rejected: b/linear: ")
    summary = json.loads((tmp_path / "no-sensors" / "prognosis.json").read_text())
    assert summary["status"] == "rejected" and not any(name.startswith("sensor") for name in summary["evidence"])
    code, out, err = run(capsys, "--quiet", "prognose", str(folder / "model.json"), str(folder / "data.csv"),
                         "--fail", "b=1e-5", "--calibrate", "0.9", "--particles", "200", "--candidate", "b",
                         "--out", str(tmp_path / "only-b"))
    assert code == 0 and "every hypothesis was rejected" in out and "wrong side" in out
    assert err.startswith("bgphm: warning: every hypothesis was rejected: b/linear: ")
    summary = json.loads((tmp_path / "only-b" / "prognosis.json").read_text())
    # no claim: the faults consistent with the ARRs that fired, b among them, and why
    assert summary["status"] == "rejected" and "b" in summary["candidate"] and "sensor omega" in summary["candidate"]
    assert summary["reason"].startswith("every hypothesis was rejected (b): a fault outside the hypotheses")
