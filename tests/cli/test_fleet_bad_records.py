"""Bad records in a fleet: the checks of `prognose` per asset; --on-bad-record stop (naming it) or skip (listing it)."""

from __future__ import annotations

import json

import pytest

from bgphm.cli import main
from bgphm.fleet import read_fleet, run_fleet
from diagnosis import RecordError
from diagnosis.csv_reading import MAX_RECORD_BYTES

from .fleets import spec, write_fleet
from .test_fleet import same_tables

pytest.importorskip("pyarrow")
pytestmark = pytest.mark.extras   # pyarrow (the dask extra)

GOOD = {"c0": 0.3, "c1": None, "c3": 0.5}


def damaged(text: str, column: str, value) -> str:
    """The CSV ``text`` with every cell of ``column`` replaced by ``value`` (a dead or stuck sensor)."""
    lines = text.splitlines()
    index = lines[0].split(",").index(column)
    rows = [line.split(",") for line in lines[1:]]
    for row in rows:
        row[index] = value
    return "\n".join([lines[0], *(",".join(row) for row in rows)]) + "\n"


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    """Three good records, a dead current sensor, a stuck capacitor voltage, a record of two samples."""
    folder = write_fleet(tmp_path_factory.mktemp("fleet") / "records", GOOD)
    good = (folder / "c0.csv").read_text()
    (folder / "dead.csv").write_text(damaged(good, "i", ""))
    (folder / "stuck.csv").write_text(damaged(good, "v_C", "2.5"))
    (folder / "short.csv").write_text("\n".join(good.splitlines()[:3]) + "\n")
    clean = write_fleet(tmp_path_factory.mktemp("clean") / "records", GOOD)
    reference = tmp_path_factory.mktemp("reference")
    run_fleet(spec(), clean, reference, workers=0)
    return folder, read_fleet(reference)


@pytest.mark.parametrize("asset, message", [
    ("dead", r"dead\.csv: column 'i' has no value \(every cell is empty or NaN\): a dead sensor"),
    ("stuck", r"stuck\.csv: sensor column 'v_C' never changes \(every value is 2\.5\): a stuck sensor"),
    ("short", r"short\.csv.*2 samples"),
])
def test_a_bad_record_stops_the_run_naming_it(fleet, tmp_path, asset, message):
    folder, _ = fleet
    only = tmp_path / "records"
    only.mkdir()
    (only / f"{asset}.csv").write_text((folder / f"{asset}.csv").read_text())
    (only / "c0.csv").write_text((folder / "c0.csv").read_text())
    with pytest.raises(RecordError, match=message):
        run_fleet(spec(), only, tmp_path / "out", workers=0)
    assert not (tmp_path / "out" / "manifest.json").exists()


def test_skip_leaves_the_bad_assets_out_with_their_reasons_and_the_others_whole(fleet, tmp_path):
    folder, reference = fleet
    summary = run_fleet(spec(), folder, tmp_path / "out", workers=0, shard_size=2, on_bad_record="skip")
    assert sorted(summary["skipped"]) == ["dead", "short", "stuck"]
    assert "a dead sensor" in summary["skipped"]["dead"] and "a stuck sensor" in summary["skipped"]["stuck"]
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["skipped"] == summary["skipped"]
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert sorted(a for s in manifest["shards"] for a in s["skipped"]) == ["dead", "short", "stuck"]
    assert same_tables(read_fleet(tmp_path / "out"), reference)   # the good assets' rows, bit for bit


def test_the_command_skips_and_says_so(fleet, tmp_path, capsys):
    folder, _ = fleet
    code = main(["fleet", "rlc", str(folder), "--fail", "R=20", "--calibrate", "0.2", "--calibrate-assets", "2",
                 "--degradation", "linear", "--particles", "100", "--dt", "0.05", "--workers", "0",
                 "--on-bad-record", "skip", "--out", str(tmp_path / "out")])
    out, err = capsys.readouterr()
    assert code == 0 and "3 asset(s) skipped for a bad record" in out
    assert "skipped dead: " in err and "skipped stuck: " in err


def test_a_csv_record_beyond_the_size_limit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    import diagnosis.csv_reading as csv_reading

    path = tmp_path / "huge.csv"
    path.write_text("t,x\n0,1\n1,2\n2,3\n")
    monkeypatch.setattr(csv_reading, "MAX_RECORD_BYTES", 10)   # as if the file were larger than 1 GiB
    with pytest.raises(RecordError, match=r"huge\.csv: .* GiB, more than the .* GiB a CSV record may hold"):
        csv_reading.read_csv(path)
    assert MAX_RECORD_BYTES == 1 << 30
