"""`bgphm demo torsion-bar|three-tank` end to end, and progress and interrupts in the filter loop."""

import contextlib
import io
import json
import math
import re

import pytest

import bgphm.commands.prognose as prognose_command
from bgphm.cli import main
from bondgraph.control import PIController
from bondgraph.io import load_model
from diagnosis import derive_arrs
from diagnosis.csv_reading import read_csv
from prognosis.degradation import ExponentialDegradation
from prognosis.health_monitor import HealthMonitor

THETA_TOLERANCE = 0.05  # relative error of the candidate's estimate at the last filter step
RUL_TOLERANCE = 0.15  # relative error of the RUL median at the last prediction


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def demos(tmp_path_factory):
    """Each new demo run once with --quiet: name -> (exit code, stdout, stderr, output directory)."""
    runs = {}
    for name in ("torsion-bar", "three-tank"):
        out = tmp_path_factory.mktemp(name)
        stdout, stderr = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            code = main(["--quiet", "demo", name, "--out", str(out)])
        runs[name] = (code, stdout.getvalue(), stderr.getvalue(), out)
    return runs


@pytest.mark.slow  # runs bgphm demo
@pytest.mark.parametrize("name", ["torsion-bar", "three-tank"])
def test_demo_detects_after_the_onset_and_predicts_the_end_of_life(demos, name):
    code, out, err, path = demos[name]
    assert code == 0 and err == ""  # --quiet: nothing on stderr for the whole chain
    assert "$ bgphm detect" in out and "$ bgphm prognose" in out
    truth = json.loads((path / "truth.json").read_text())
    detection = json.loads((path / "detect" / "detection.json").read_text())
    summary = json.loads((path / "prognose" / "prognosis.json").read_text())
    assert truth["onset"] < detection["detection_time"] < truth["eol"]
    assert summary["detection_time"] > truth["onset"]
    assert summary["filter_step"] == round(summary["filter_step"], 9)  # a whole number of steps, no float dust
    last = summary["last"]
    true_rul = truth["eol"] - last["t"]
    assert last["rul_p5"] <= true_rul <= last["rul_p95"]
    assert last["rul_median"] == pytest.approx(true_rul, rel=RUL_TOLERANCE)
    theta_true = truth["nominal"] * math.exp(truth["rate"] * (last["t"] - truth["onset"]))
    assert last["theta_mean"] == pytest.approx(theta_true, rel=THETA_TOLERANCE)


@pytest.mark.slow  # runs bgphm demo
def test_torsion_bar_writes_a_python_model_with_its_controller(demos):
    *_, path = demos["torsion-bar"]
    spec = load_model(path / "model.py")  # JSON cannot hold the PI speed loop
    assert isinstance(spec.inputs["U"], PIController) and not (path / "model.json").exists()
    assert (path / "report.html").exists()


def test_unknown_demo_names_the_available_ones(tmp_path, capsys):
    code, _, err = run(capsys, "demo", "rlc", "--out", str(tmp_path))
    assert code == 2 and "'rlc'" in err
    assert all(name in err for name in ("dc-motor", "torsion-bar", "three-tank"))


# ------------------------------------------------------------------------------------------- progress

def three_tank_monitor(demos, **options):
    """A small monitor on the three-tank demo's files (az2 on ARR_0_2)."""
    *_, path = demos["three-tank"]
    arr = next(a for a in derive_arrs(load_model(path / "model.json").model) if a.name == "ARR_0_2")
    record = read_csv(path / "data.csv", arr.signals)
    monitor = HealthMonitor(arr, "az2", ExponentialDegradation(), theta_fail=1.2, dt=1.0, n_particles=50,
                            noise_std=3e-6, gamma_bounds=(0.0, 0.01), rul_every=20, horizon=2000.0,
                            detection={"margin": 6e-6, "persistence": 5}, **options)
    return monitor, record


@pytest.mark.slow  # runs bgphm demo
def test_progress_counts_filter_steps_up_to_the_total(demos):
    monitor, record = three_tank_monitor(demos)
    calls = []
    result = monitor.run(record, progress=lambda done, total, t: calls.append((done, total, t)))
    done, totals, times = zip(*calls)
    assert len(set(totals)) == 1 and done[-1] == totals[0] == result.t.size
    assert all(a < b for a, b in zip(done, done[1:])) and all(a < b for a, b in zip(times, times[1:]))
    assert len(calls) <= 101 and isinstance(done[0], int) and times[-1] == result.t[-1]


@pytest.mark.slow  # runs bgphm demo
@pytest.mark.parametrize("workers", [1, 2])
def test_an_interrupt_in_the_callback_stops_the_run(demos, workers):
    monitor, record = three_tank_monitor(demos)
    calls = []

    def interrupt(done, total, t):
        calls.append(done)
        if done >= 10:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        monitor.run(record, workers=workers, progress=interrupt)
    assert calls[-1] < calls[0] + 20  # stopped at the first report past 10 steps


@pytest.mark.slow  # runs bgphm demo
def test_prognose_prints_filter_progress_unless_quiet(demos, capsys):
    *_, path = demos["three-tank"]
    argv = ["prognose", str(path / "model.json"), str(path / "data.csv"), "--candidate", "az2", "--degradation",
            "exponential", "--fail", "1.2", "--calibrate", "190", "--particles", "50", "--rul-every", "50"]
    code, out, err = run(capsys, *argv)
    # the signature is read over a confirmation window: the MSO ARRs stay in alarm after the first one
    signature = "(ARR_0_2, ARR_MSO_2, ARR_MSO_3); candidate az2 (indistinguishable from A_2 (same signature))"
    assert code == 0 and signature in out
    lines = re.findall(r"filter: (\d+) % of (\d+) steps \(t = [\d.e+-]+ s\), [\d.]+ s elapsed", err)
    assert lines and lines[-1][0] == "100"
    code, out_quiet, err = run(capsys, "--quiet", *argv)
    assert code == 0 and err == "" and out_quiet == out


@pytest.mark.slow  # runs bgphm demo
def test_an_interrupted_prognose_exits_1(demos, capsys, monkeypatch):
    *_, path = demos["three-tank"]

    def interrupted(progress):
        def report(done, total, t):
            raise KeyboardInterrupt
        return report

    monkeypatch.setattr(prognose_command, "filter_progress", interrupted)
    code, _, err = run(capsys, "--quiet", "prognose", str(path / "model.json"), str(path / "data.csv"),
                       "--candidate", "az2", "--degradation", "exponential", "--fail", "1.2", "--calibrate", "190",
                       "--particles", "50")
    assert code == 1 and "interrupted" in err
