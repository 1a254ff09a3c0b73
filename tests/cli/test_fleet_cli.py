"""bgphm fleet: a directory of CSV records to Parquet tables, and every bad input as exit 2 with one line.

These runs are in this process (--workers 0); the Dask runs of the command are in test_fleet_dask.py.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from bgphm.cli import main
from bgphm.fleet import read_fleet

from .fleets import without_dask, write_fleet

pytest.importorskip("pyarrow")
pytestmark = pytest.mark.extras   # pyarrow (the dask extra)

ASSETS = {"c0": 0.3, "c1": None, "c2": 0.6}
FAST = ["--degradation", "linear", "--particles", "100", "--dt", "0.05", "--rul-every", "4", "--workers", "0"]


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def usage_error(capsys, *argv) -> str:
    """The one line of a command that must fail with exit code 2."""
    code, out, err = run(capsys, "--quiet", *argv)
    assert code == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bgphm: error: "), err
    return lines[0]


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    return write_fleet(tmp_path_factory.mktemp("fleet") / "records", ASSETS)


@pytest.fixture(scope="module")
def fleet_run(records, tmp_path_factory):
    """One run of the command, its exit code, stdout, stderr and output directory."""
    out = tmp_path_factory.mktemp("run") / "out"
    truth = out.parent / "truth.json"  # R reaches 20 ohm (10 + 4 ohm/s) 2.5 s after the onset
    truth.write_text(json.dumps({"c0": {"eol": 0.3 + 2.5}, "c1": {"eol": None}, "c2": {"eol": 0.6 + 2.5},
                                 "ghost": {"eol": 1.0}}))
    capture = pytest.MonkeyPatch()
    import io
    import sys

    stdout, stderr = io.StringIO(), io.StringIO()
    capture.setattr(sys, "stdout", stdout)
    capture.setattr(sys, "stderr", stderr)
    try:
        code = main(["fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2", *FAST, "--out", str(out),
                     "--truth", str(truth)])
    finally:
        capture.undo()
    return code, stdout.getvalue(), stderr.getvalue(), out


def test_the_command_writes_parquet_tables_and_a_summary(fleet_run):
    code, out, err, folder = fleet_run
    assert code == 0, err
    assert "3 assets, 2 with an alarm" in out and f"wrote {folder / 'alarms'}" in out
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["assets"] == 3 and summary["scheduler"] == "serial"
    assert summary["notes"]["assets"] == ["c0", "c1", "c2"] and summary["notes"]["until"] == 0.2
    assert summary["spec"]["healthy_until"] == 0.2 and summary["spec"]["model"] == "rlc"
    assert set(summary["spec"]["noise_std"]) == set(summary["notes"]["noise_std"])
    result = read_fleet(folder)
    assert sorted(set(result.alarms["asset"])) == ["c0", "c2"]
    assert sorted(set(result.rul["asset"])) == ["c0", "c2"]


def test_truth_scores_each_asset_and_pools_its_predictions(fleet_run):
    """--truth: each failing asset's predictions against its end of life, recomputed here from the RUL table."""
    code, out, _, folder = fleet_run
    assert code == 0
    scored = json.loads((folder / "summary.json").read_text())["truth"]
    rul = read_fleet(folder).rul
    eol = {"c0": 2.8, "c2": 3.1}
    assert sorted(scored["assets"]) == ["c0", "c2"] and scored["not_in_fleet"] == ["ghost"]
    inside, count = 0, 0
    for asset, end in eol.items():
        rows = (rul["asset"] == asset) & (end - rul["t"] > 0) & np.isfinite(rul["p50"])
        held = (rul["p5"][rows] <= end - rul["t"][rows]) & (end - rul["t"][rows] <= rul["p95"][rows])
        assert scored["assets"][asset]["predictions"] == int(rows.sum())
        assert scored["assets"][asset]["coverage_90"] == pytest.approx(held.mean())
        inside, count = inside + held.sum(), count + rows.sum()
    assert scored["pooled"]["predictions"] == count and scored["pooled"]["coverage_90"] == pytest.approx(inside / count)
    assert f"truth: 2 assets, {count} predictions: mean RA" in out and "1 truth(s) for no asset of the fleet" in out


def test_the_command_writes_the_overview_page_with_the_units(fleet_run):
    """A real run of the command (three RLC circuits, --workers 0) writes index.html beside the tables."""
    from bgphm.fleet.page import read_page_data

    code, out, _, folder = fleet_run
    assert code == 0 and f"{folder / 'index.html'} (open it in a browser)" in out
    assert f"{folder / 'residuals'}" in out
    data = read_page_data((folder / "index.html").read_text(encoding="utf-8"))
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["units"]["parameters"]["R"] == "Ohm" and summary["units"]["t"] == "s"
    assert data["units"]["residuals"] == summary["units"]["residuals"] and data["units"]["rul"] == "s"
    assert all(summary["units"]["residuals"][arr] for arr in data["arrs"])   # every residual has its unit
    assert [row[0] for row in data["rows"]][2] == "c1" and data["rows"][2][9] == "no alarm"
    rul = read_fleet(folder).rul
    last = {asset: p5 for asset, p5 in zip(rul["asset"], rul["p5"])}   # each asset's last row wins
    assert [row[0] for row in data["rows"][:2]] == sorted(last, key=last.get)
    assert data["counts"]["with_alarm"] == 2 and data["kept"] == 3 and data["failures"] == {"R": 20.0}
    assert data["horizon"] > 0 and data["model"] == "rlc"
    assert len(data["provenance"]["model SHA-256"]) == 64 and data["provenance"]["date"].endswith(" UTC")


def test_the_command_reports_progress_by_assets_done(fleet_run):
    _, _, err, _ = fleet_run
    assert "3 assets in CSV directory" in err and "fleet: 3 of 3 assets (100 %)" in err
    assert "median over 3 record(s), t <= 0.2 s" in err


def test_quiet_silences_the_progress_and_force_replaces_the_tables(records, fleet_run, capsys):
    folder = fleet_run[3]
    before = read_fleet(folder).rul
    code, out, err = run(capsys, "--quiet", "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2",
                         *FAST, "--out", str(folder), "--force")
    assert code == 0 and err == "" and "3 assets" in out
    assert read_fleet(folder).rul["p50"].tolist() == before["p50"].tolist()


def test_resume_goes_on_with_an_interrupted_run_and_names_what_it_kept(records, fleet_run, capsys, tmp_path,
                                                                        monkeypatch):
    from bgphm.fleet import engine

    out, real = tmp_path / "out", engine.run_shard
    calls = []

    def interrupted(task):   # Ctrl-C as the second shard starts
        calls.append(task.shard)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(engine, "run_shard", interrupted)
    argv = ["--quiet", "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2", *FAST,
            "--shard-size", "1", "--out", str(out)]
    code, _, err = run(capsys, *argv)
    assert code == 1 and "interrupted" in err
    monkeypatch.setattr(engine, "run_shard", real)
    code, stdout, _ = run(capsys, *argv, "--resume")
    assert code == 0 and "(1 of 3 shards kept from the interrupted run)" in stdout
    assert read_fleet(out).rul["p50"].tolist() == read_fleet(fleet_run[3]).rul["p50"].tolist()
    line = usage_error(capsys, *argv[1:], "--resume")
    assert "nothing to resume (no interrupted fleet run there)" in line


# ------------------------------------------------------------------------------------------------ bad input

def test_a_missing_records_directory(capsys, tmp_path):
    line = usage_error(capsys, "fleet", "rlc", str(tmp_path / "nowhere"), "--fail", "R=20", "--calibrate", "0.2",
                       "--out", str(tmp_path / "out"), "--workers", "0")
    assert "nowhere: no such directory or file" in line


def test_a_directory_without_csv_files(capsys, tmp_path):
    (tmp_path / "records").mkdir()
    (tmp_path / "records" / "notes.txt").write_text("x")
    line = usage_error(capsys, "fleet", "rlc", str(tmp_path / "records"), "--fail", "R=20", "--calibrate", "0.2",
                       "--out", str(tmp_path / "out"), "--workers", "0")
    assert "no .csv file in it" in line


@pytest.mark.parametrize("fail, message", [("X=20", "--fail 'X=20': the model has no parameter 'X'"),
                                           ("R=abc", "--fail 'R=abc': 'abc' is not a number"),
                                           ("R=10", "equals the nominal value of 'R'")])
def test_a_bad_fail(capsys, records, tmp_path, fail, message):
    line = usage_error(capsys, "fleet", "rlc", str(records), "--fail", fail, "--calibrate", "0.2",
                       "--out", str(tmp_path / "out"), "--workers", "0")
    assert message in line


def test_the_output_may_not_be_the_records_directory(capsys, records):
    line = usage_error(capsys, "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2",
                       "--out", str(records), "--workers", "0", "--force")
    assert "the directory holds the input file" in line


def test_an_existing_output_needs_force(capsys, records, tmp_path):
    (tmp_path / "old.txt").write_text("x")
    line = usage_error(capsys, "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2",
                       "--out", str(tmp_path), "--workers", "0")
    assert "is not empty; give --force" in line


@pytest.mark.parametrize("option, value, message", [
    ("--workers", "-1", "--workers must be at least 0"),
    ("--shard-size", "0", "--shard-size must be at least 1"),
    ("--calibrate-assets", "0", "--calibrate-assets must be at least 1"),
    ("--particles", "1", "--particles must be a whole number in [2,"),
])
def test_bad_counts(capsys, records, tmp_path, option, value, message):
    line = usage_error(capsys, "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2",
                       "--out", str(tmp_path / "out"), option, value)
    assert message in line


def test_calibrate_is_required(capsys, records, tmp_path):
    with pytest.raises(SystemExit) as exit_:
        main(["fleet", "rlc", str(records), "--fail", "R=20", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and len(err.strip().splitlines()) == 1
    assert "the following arguments are required: --calibrate" in err


def test_a_calibration_stretch_with_a_fault_names_the_asset(capsys, records, tmp_path):
    line = usage_error(capsys, "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "1.6",
                       "--out", str(tmp_path / "out"), *FAST)
    assert "records: asset 'c0': --calibrate 1.6 is not fault-free" in line


def test_a_calibration_past_the_records_end(capsys, records, tmp_path):
    line = usage_error(capsys, "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "5",
                       "--out", str(tmp_path / "out"), "--workers", "0")
    assert "asset 'c0': --calibrate 5: at or past the end of the record" in line


def test_a_file_that_is_not_parquet(capsys, tmp_path):
    (tmp_path / "fleet.parquet").write_text("t,x\n")
    line = usage_error(capsys, "fleet", "rlc", str(tmp_path / "fleet.parquet"), "--fail", "R=20", "--calibrate",
                       "0.2", "--out", str(tmp_path / "out"), "--workers", "0")
    assert "not a readable Parquet file" in line


def test_a_dask_run_without_dask_names_the_extra_before_any_work(capsys, records, tmp_path, monkeypatch):
    without_dask(monkeypatch)
    line = usage_error(capsys, "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2",
                       "--out", str(tmp_path / "out"), "--workers", "2")
    assert "pip install 'bondgraph-phm[dask]'" in line and "--workers 0" in line
    assert not (tmp_path / "out").exists()


def test_a_file_name_is_shown_never_obeyed(capsys, tmp_path):
    hostile = str(tmp_path / "run\x1b[2J\x1b]0;owned\x07.csv")
    line = usage_error(capsys, "detect", "rlc", hostile, "--calibrate", "0.1")
    assert "\x1b" not in line and "\x07" not in line
    assert "run\\x1b[2J\\x1b]0;owned\\x07.csv" in line


def test_a_file_name_that_is_not_utf8_is_named_with_exit_2(capsys, records, tmp_path):
    import os

    folder = tmp_path / "records"
    folder.mkdir()
    (folder / "c0.csv").write_text((records / "c0.csv").read_text())
    os.close(os.open(os.fsencode(folder) + b"/motor-\xff.csv", os.O_CREAT | os.O_WRONLY))
    line = usage_error(capsys, "fleet", "rlc", str(folder), "--fail", "R=20", "--calibrate", "0.2",
                       "--out", str(tmp_path / "out"), "--workers", "0")
    assert "the file name 'motor-\\udcff.csv' is not valid UTF-8; asset ids are text" in line


@pytest.mark.parametrize("kind", ["binary", "list", "struct"])
def test_a_parquet_asset_column_of_another_type_is_named_with_exit_2(capsys, tmp_path, kind):
    import pyarrow as pa
    import pyarrow.parquet as pq

    values = {"binary": pa.array([b"a", b"a", b"a"]), "list": pa.array([[1], [1], [1]]),
              "struct": pa.array([{"x": 1}] * 3)}[kind]
    path = tmp_path / "fleet.parquet"
    pq.write_table(pa.table({"asset": values, "t": [0.0, 0.5, 1.0], "V": [1.0] * 3, "i": [0.1, 0.2, 0.3],
                             "v_C": [0.0, 0.1, 0.2]}), path)
    line = usage_error(capsys, "fleet", "rlc", str(path), "--fail", "R=20", "--calibrate", "0.2",
                       "--out", str(tmp_path / "out"), "--workers", "0")
    assert "column 'asset' holds" in line and "asset ids must be text or whole numbers" in line



@pytest.mark.parametrize("content, message", [
    ('["c0"]', "expected a JSON object mapping asset ids to truth entries"),
    ('{"c0": {"eol": "soon"}}', "asset 'c0': 'eol' must be a finite number"),
    ('{"c0": 2.8}', "asset 'c0': expected a JSON object with 'eol'"),
])
def test_a_bad_fleet_truth_file_is_refused_before_any_work(records, tmp_path, capsys, content, message):
    truth = tmp_path / "truth.json"
    truth.write_text(content)
    line = usage_error(capsys, "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2", *FAST, "--out",
                       str(tmp_path / "out"), "--truth", str(truth))
    assert line.startswith(f"bgphm: error: --truth {truth}") and message in line
    assert not (tmp_path / "out").exists()
