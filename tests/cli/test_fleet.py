"""bgphm.fleet in this process: the spec that travels, shards, Parquet tables by bucket, sources, read_fleet.

The Dask runs are in test_fleet_dask.py (slow tier: a cluster takes seconds to start).
"""

from __future__ import annotations

import json
import pickle
import warnings

import numpy as np
import pytest

from bgphm.errors import FleetError, MissingExtraError, UsageError
from bgphm.fleet import (CsvDirectory, FleetSpec, ParquetRecords, bucket_of, default_shard_size, open_source, plan,
                         read_fleet, run_fleet, shard_assets)
from bgphm.fleet.spec import monitor_for
from bondgraph.errors import PHMError
from diagnosis.records import RecordError
from prognosis.fleet.results import TABLES

from .fleets import ONSETS, spec, without_dask, write_fleet

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pytestmark = pytest.mark.extras   # pyarrow (the dask extra)


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    return write_fleet(tmp_path_factory.mktemp("fleet") / "records")


@pytest.fixture(scope="module")
def reference(records, tmp_path_factory):
    """The six assets in one shard, in this process."""
    out = tmp_path_factory.mktemp("reference")
    summary = run_fleet(spec(), records, out, workers=0, shard_size=6)
    return out, summary


def same_tables(a, b) -> bool:
    """Bitwise equality of every column of every table (NaN equal to NaN)."""
    for name in TABLES:
        ta, tb = a.table(name), b.table(name)
        if set(ta) != set(tb):
            return False
        for column in ta:
            x, y = ta[column], tb[column]
            if x.dtype == object:
                if x.tolist() != y.tolist():
                    return False
            elif x.shape != y.shape or not np.array_equal(x.view(np.uint8), y.view(np.uint8)):
                return False
    return True


def test_only_bgphm_imports_dask_and_pyarrow_but_read_csvs_optional_parser():
    """The library packages stay free of the extra: prognosis knows nothing of Dask or Parquet.  The one
    exception is read_csv's fast path (diagnosis._csv_fast), which parses CSV with pyarrow when it is
    installed and with numpy otherwise: an accelerator tried inside a function, never a dependency."""
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    extra = re.compile(r"^\s*(?:import|from)\s+(?:dask|distributed|pyarrow)\b", re.M)  # a text scan: ast is slow
    offenders = [str(path.relative_to(root)) for package in ("bondgraph", "diagnosis", "prognosis")
                 for path in (root / package).rglob("*.py") if extra.search(path.read_text())]
    assert offenders == ["diagnosis/_csv_fast.py"]
    parser = (root / "diagnosis" / "_csv_fast.py").read_text()
    assert all(line.startswith("        ") for line in extra.findall(parser))   # inside a function's try only
    assert "except ImportError:" in parser
    assert extra.search((root / "bgphm" / "fleet" / "engine.py").read_text())  # the scan does see them


# ------------------------------------------------------------------------------------------------ the spec

def test_a_spec_pickles_small_and_compares_by_value():
    a, b = spec(seed=3), spec(seed=3)
    assert a == b and hash(a) == hash(b) and a.key() == b.key()
    assert a != spec(seed=4)
    again = pickle.loads(pickle.dumps(a))
    assert again == a and dict(again.detection["ARR_J1"]) == {"margin": 0.011}
    assert len(pickle.dumps(a)) < 2000
    json.dumps(a.as_dict())  # summary.json holds it


def test_a_spec_refuses_law_objects_and_non_mappings():
    from prognosis import LinearDegradation

    with pytest.raises(UsageError, match="laws must be built-in law names"):
        FleetSpec("rlc", {"R": 20.0}, noise_std={}, laws=[LinearDegradation()])
    with pytest.raises(UsageError, match="failures must be a mapping"):
        FleetSpec("rlc", [("R", 20.0)], noise_std={})


def test_a_spec_process_noise_is_an_absolute_sigma_v_of_every_law():
    from prognosis import ExponentialDegradation, LinearDegradation

    built, _ = monitor_for(spec(laws=["linear", "exponential"], process_noise=2e-3))
    laws = {"linear": LinearDegradation(2e-3), "exponential": ExponentialDegradation(2e-3)}
    assert built.monitor.settings.laws == laws
    assert spec(process_noise=0) == spec(process_noise=0.0) != spec()
    for bad in (-1e-3, float("nan"), "0.1", True):
        with pytest.raises(UsageError, match="FleetSpec process_noise must be a finite number >= 0"):
            spec(process_noise=bad)


def test_the_monitor_is_built_once_per_spec_and_thread():
    first, built = monitor_for(spec(seed=11))
    again, built_again = monitor_for(spec(seed=11))
    assert built and not built_again and again is first
    assert first.signals == ["V", "i", "v_C"]
    assert first.monitor.settings.law_models == {"linear": None}  # no process_noise: the monitor's relative sigma_v


# ------------------------------------------------------------------------------------------------ shards

def test_shards_are_sorted_ids_of_a_fixed_size():
    assert shard_assets(["b", "c", "a", "d", "e"], 2) == [("a", "b"), ("c", "d"), ("e",)]
    assert default_shard_size(6, 2) == 1 and default_shard_size(800, 2) == 100
    assert default_shard_size(10**5, 2) == 1000 and default_shard_size(3, 0) == 1


def test_tasks_carry_ids_and_paths_and_pickle_small(records, tmp_path):
    for size in (1, 3, 6):
        tasks = plan(spec(), open_source(records), tmp_path, shard_size=size)
        assert [a for t in tasks for a in t.assets] == sorted(ONSETS)
        assert all(len(pickle.dumps(t)) < 10_000 for t in tasks)
        assert isinstance(tasks[0].out, str) and isinstance(tasks[0].source, CsvDirectory)


# ------------------------------------------------------------------------------------------------ run and read

def test_a_serial_run_writes_the_tables_by_bucket_and_a_summary(reference):
    out, summary = reference
    assert summary["assets"] == 6 and summary["assets_with_alarm"] == 4 and summary["shards"] == 1
    assert summary["scheduler"] == "serial" and summary["spec"]["seed"] == 0
    assert json.loads((out / "summary.json").read_text())["rows"] == summary["rows"]
    result = read_fleet(out)
    assert sorted(set(result.alarms["asset"])) == ["c0", "c2", "c3", "c5"]  # c1 and c4 stay healthy
    for part in (out / "rul").glob("bucket=*/*.parquet"):
        assets = set(pq.read_table(part).column("asset").to_pylist())
        assert {bucket_of(a) for a in assets} == {int(part.parent.name.split("=")[1])}
    rul = result.for_asset("c0").rul
    assert np.all(np.diff(rul["t"]) > 0) and rul["status"][-1] == "indistinguishable"  # L: R's signature
    assert abs(rul["t"][-1] + rul["p50"][-1] - 2.8) < 0.5  # R reaches 20 ohm at t = 2.8 s


def test_the_page_is_published_with_the_tables_and_removed_without_it(records, reference, tmp_path):
    from bgphm.fleet.page import read_page_data

    out, summary = reference
    data = read_page_data((out / "index.html").read_text(encoding="utf-8"))
    assert sorted(row[0] for row in data["rows"]) == sorted(ONSETS) and data["counts"]["with_alarm"] == 4
    assert summary["rows"]["residuals"] == 6 * 64   # every asset, the ARR sensitive to R, 64 buckets
    assert summary["units"]["residuals"] == {"ARR_J1": "V"} and summary["units"]["parameters"]["R"] == "Ohm"
    folder = tmp_path / "records"
    folder.mkdir()
    (folder / "c0.csv").write_text((records / "c0.csv").read_text())
    run_fleet(spec(), folder, tmp_path / "out", workers=0)
    assert (tmp_path / "out" / "index.html").is_file()
    run_fleet(spec(), folder, tmp_path / "out", workers=0, page=False)   # a page of another run would mislead
    assert not (tmp_path / "out" / "index.html").exists() and (tmp_path / "out" / "manifest.json").is_file()


@pytest.mark.slow
def test_results_do_not_depend_on_the_sharding(records, reference, tmp_path):
    """One shard of six (the reference), three of two, six of one: bitwise the same tables."""
    expected = read_fleet(reference[0])
    for size in (2, 1):
        run_fleet(spec(), records, tmp_path / str(size), workers=0, shard_size=size)
        assert same_tables(read_fleet(tmp_path / str(size)), expected), f"shards of {size}"


def test_the_workers_read_the_antiderivative_columns_of_the_detection(records, reference, tmp_path):
    """Integrals read from the records (detection's antiderivatives) are columns a source must read too."""
    folder = tmp_path / "records"
    folder.mkdir()
    for asset in ("c0", "c1"):
        lines = (records / f"{asset}.csv").read_text().splitlines()
        # a column the ARRs do not integrate: the tables must be those of the reference run
        text = "\n".join([lines[0] + ",q"] + [line + ",0.0" for line in lines[1:]])
        (folder / f"{asset}.csv").write_text(text + "\n")
    detection = {name: {**options, "antiderivatives": {"i": "q"}} for name, options in spec().detection.items()}
    job = spec(detection=detection)
    assert monitor_for(job)[0].signals == ["V", "i", "v_C", "q"]
    run_fleet(job, folder, tmp_path / "out", workers=0)
    got, expected = read_fleet(tmp_path / "out"), read_fleet(reference[0])
    assert same_tables(got.for_asset("c0"), expected.for_asset("c0")) and got.rows("rul") == expected.for_asset(
        "c0").rows("rul") > 0


@pytest.mark.slow
def test_a_second_run_replaces_the_parts_of_the_first(records, reference, tmp_path):
    out = tmp_path / "out"
    run_fleet(spec(), records, out, workers=0, shard_size=1)
    (out / "rul" / "notes.txt").write_text("kept")
    summary = run_fleet(spec(), records, out, workers=0, shard_size=6)
    assert {p.name for p in out.glob("*/bucket=*/*")} == {"part-00000.parquet"}  # no part of the first run left
    assert (out / "rul" / "notes.txt").exists() and summary["shards"] == 1
    assert same_tables(read_fleet(out), read_fleet(reference[0]))


def test_read_fleet_refuses_a_folder_that_is_not_a_fleet_and_a_run_without_its_manifest(reference, tmp_path):
    with pytest.raises(FleetError, match="not the output of a fleet run"):
        read_fleet(tmp_path)
    for name in TABLES:
        (tmp_path / name).mkdir()
    with pytest.raises(FleetError, match="no manifest.json: the fleet run did not finish"):
        read_fleet(tmp_path)


def test_a_bad_record_stops_the_run_naming_the_file(records, tmp_path):
    folder = tmp_path / "records"
    folder.mkdir()
    (folder / "a.csv").write_text((records / "c0.csv").read_text())
    (folder / "b.csv").write_text("t,V,i\n0,1,2\n1,2,3\n2,3,4\n")
    with pytest.raises(RecordError, match=r"b\.csv: missing column\(s\) \['v_C'\]"):
        run_fleet(spec(), folder, tmp_path / "out", workers=0)


def test_bad_counts_are_refused(records, tmp_path):
    with pytest.raises(UsageError, match="shard_size must be a whole number >= 1"):
        run_fleet(spec(), records, tmp_path, workers=0, shard_size=0)
    with pytest.raises(UsageError, match="workers must be a whole number >= 0"):
        run_fleet(spec(), records, tmp_path, workers=-1)


def test_a_dask_run_without_dask_names_the_extra(records, tmp_path, monkeypatch):
    without_dask(monkeypatch)
    with pytest.raises(MissingExtraError, match=r"pip install 'bondgraph-phm\[dask\]'") as caught:
        run_fleet(spec(), records, tmp_path / "out", workers=2)
    assert isinstance(caught.value, ImportError) and isinstance(caught.value, PHMError)


# ------------------------------------------------------------------------------------------------ sources

def parquet_of(records, path, *, integer_ids=False, shuffle=True):
    """The CSV records as one Parquet file (rows shuffled), asset ids as strings or integers."""
    from diagnosis.csv_reading import read_csv

    columns = {"asset": [], "t": [], "V": [], "i": [], "v_C": []}
    for k, csv in enumerate(sorted(records.glob("*.csv"))):
        record = read_csv(csv)
        columns["asset"] += [k if integer_ids else csv.stem] * len(record)
        columns["t"] += record.t.tolist()
        for s in ("V", "i", "v_C"):
            columns[s] += record[s].tolist()
    table = pa.table(columns)
    if shuffle:
        table = table.take(np.random.default_rng(0).permutation(table.num_rows))
    pq.write_table(table, path, row_group_size=1000)
    return path


def test_a_parquet_source_reads_the_same_records_as_the_csv_files(records, tmp_path):
    source = open_source(parquet_of(records, tmp_path / "fleet.parquet"))
    assert isinstance(source, ParquetRecords) and source.assets() == sorted(ONSETS)
    from_csv = dict(CsvDirectory(str(records)).read(["c3", "c1"], ["V", "i", "v_C"]))
    from_parquet = dict(source.read(["c3", "c1"], ["V", "i", "v_C"]))
    assert list(from_parquet) == ["c3", "c1"]
    for asset in ("c1", "c3"):
        assert np.array_equal(from_parquet[asset].t, from_csv[asset].t)
        assert np.array_equal(from_parquet[asset]["i"], from_csv[asset]["i"])


def test_parquet_asset_ids_may_be_integers(records, tmp_path):
    source = open_source(parquet_of(records, tmp_path / "ints.parquet", integer_ids=True, shuffle=False))
    assert source.assets() == ["0", "1", "2", "3", "4", "5"]
    [(asset, record)] = list(source.read(["4"], ["i"]))
    assert asset == "4" and len(record) == 2001


@pytest.mark.parametrize("integer_ids", [False, True])
def test_a_parquet_chunk_reads_only_the_row_groups_of_its_assets(records, tmp_path, integer_ids):
    """Sorted by asset, a file's row groups hold few assets: a chunk's filter must let pyarrow skip the others."""
    import pyarrow.dataset

    path = parquet_of(records, tmp_path / "sorted.parquet", integer_ids=integer_ids, shuffle=False)
    source = open_source(path)
    ids = source.assets()
    fragment = next(pyarrow.dataset.dataset(path).get_fragments())
    groups = fragment.split_by_row_group()
    # a chunk holds hundreds of ids: pyarrow prunes by a list of ids only when it is short (here 80 ids)
    wanted = fragment.split_by_row_group(source.selection(ids[2:4] * 40))
    assert len(groups) == 13 and len(wanted) == 5  # rows 4002-8003 of 12006, 1000 per row group
    from_csv = dict(CsvDirectory(str(records)).read(["c2", "c3"], ["i"]))
    got = dict(source.read(ids[2:4], ["i"]))
    assert [np.array_equal(got[a]["i"], from_csv[c]["i"]) for a, c in zip(ids[2:4], ["c2", "c3"])] == [True, True]
    missing = "x" if not integer_ids else "02"  # "02" is not how the integer 2 reads
    with pytest.raises(RecordError, match=f"no row for asset '{missing}'"):
        list(source.read([missing], ["i"]))


def test_sources_name_what_is_wrong(records, tmp_path):
    with pytest.raises(RecordError, match="no such directory or file"):
        open_source(tmp_path / "missing")
    with pytest.raises(RecordError, match=r"no \.csv file in it"):
        CsvDirectory(str(tmp_path)).assets()
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(RecordError, match="expected a directory of CSV files"):
        open_source(tmp_path / "notes.txt")
    (tmp_path / "bad.parquet").write_text("not parquet")
    with pytest.raises(RecordError, match="not a readable Parquet file"):
        open_source(tmp_path / "bad.parquet").assets()
    pq.write_table(pa.table({"id": ["a"], "t": [0.0]}), tmp_path / "noasset.parquet")
    with pytest.raises(RecordError, match=r"missing column\(s\) \['asset'\]"):
        open_source(tmp_path / "noasset.parquet").assets()
    pq.write_table(pa.table({"asset": ["a", None], "t": [0.0, 1.0]}), tmp_path / "noid.parquet")
    with pytest.raises(RecordError, match="column 'asset' has empty cells; every row needs an asset id"):
        open_source(tmp_path / "noid.parquet").assets()
    pq.write_table(pa.table({"asset": pa.array([], pa.string()), "t": pa.array([], pa.float64())}),
                   tmp_path / "empty.parquet")
    with pytest.raises(RecordError, match="no rows"):
        open_source(tmp_path / "empty.parquet").assets()
    pq.write_table(pa.table({"asset": ["a"] * 3, "t": [0.0, 1.0, 1.0], "i": [1.0, 2.0, 3.0]}),
                   tmp_path / "twice.parquet")
    with pytest.raises(RecordError, match=r"asset 'a'.*not strictly increasing"):
        list(open_source(tmp_path / "twice.parquet").read(["a"], ["i"]))


def test_warnings_from_a_run_are_toolkit_warnings(records, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a run on clean records warns of nothing
        run_fleet(spec(), records, tmp_path / "out", workers=0, shard_size=6)


def test_a_serial_run_builds_the_monitor_once(records, tmp_path):
    summary = run_fleet(spec(seed=12), records, tmp_path, workers=0, shard_size=2)
    assert summary["shards"] == 3 and summary["monitors_built"] == 1
