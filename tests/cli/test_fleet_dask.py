"""bgphm.fleet on a real distributed.LocalCluster of two worker processes (slow tier: a cluster starts in seconds).

One cluster serves the module (started as run_fleet starts its own, by bgphm.fleet.local_cluster); one
test lets run_fleet start and stop its own.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

from bgphm.cli import main
from bgphm.errors import FleetError, FleetWarning
from bgphm.fleet import local_cluster, read_fleet, run_fleet
from bgphm.fleet.engine import MALLOC, malloc_setting
from diagnosis.records import RecordError

from .fleets import spec, write_fleet
from .test_fleet import parquet_of, same_tables

distributed = pytest.importorskip("distributed")
dask = pytest.importorskip("dask")
pytest.importorskip("pyarrow")

pytestmark = [pytest.mark.slow, pytest.mark.extras]   # dask, distributed, pyarrow


@pytest.fixture(scope="module")
def client():
    with local_cluster(2) as client:
        yield client


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    return write_fleet(tmp_path_factory.mktemp("fleet") / "records")


@pytest.fixture(scope="module")
def serial(records, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    run_fleet(spec(), records, out, workers=0, shard_size=6)
    return read_fleet(out)


def test_the_workers_do_not_get_the_nannys_malloc_setting(client):
    # Dask's default would give it to them: the test would fail without bgphm's handling
    assert dask.config.get("distributed.nanny.pre-spawn-environ")[MALLOC] == 65536
    settings = client.run(malloc_setting)
    assert len(settings) == 2 and set(settings.values()) == {None}
    assert len(set(client.run(os.getpid).values())) == 2  # two processes, not threads


@pytest.mark.parametrize("size", [6, 3, 1])
def test_dask_gives_the_serial_results_bitwise_whatever_the_shards(client, records, serial, tmp_path, size):
    """1 x 6, 2 x 3 and 6 x 1 on two workers: the tables of the one-shard serial run."""
    seen = []
    summary = run_fleet(spec(), records, tmp_path, scheduler=client, shard_size=size,
                        progress=lambda done, total: seen.append((done, total)))
    assert summary["shards"] == 6 // size and summary["assets"] == 6
    assert seen[-1] == (6, 6) and len(seen) == 6 // size
    assert same_tables(read_fleet(tmp_path), serial)


def test_each_worker_builds_the_monitor_once(client, records, tmp_path):
    summary = run_fleet(spec(seed=7), records, tmp_path, scheduler=client, shard_size=1)
    assert summary["shards"] == 6 and 1 <= summary["monitors_built"] <= 2 == len(client.run(os.getpid))
    again = run_fleet(spec(seed=7), records, tmp_path, scheduler=client, shard_size=1)
    assert again["monitors_built"] == 0  # the workers kept it for the next run of the same job


def test_a_shards_error_reaches_the_driver_with_its_type_and_message(client, records, tmp_path):
    folder = tmp_path / "records"
    folder.mkdir()
    (folder / "a.csv").write_text((records / "c0.csv").read_text())
    (folder / "b.csv").write_text("t,V,i\n0,1,2\n1,2,3\n2,3,4\n")
    with pytest.raises(RecordError, match=r"b\.csv: missing column\(s\) \['v_C'\]"):
        run_fleet(spec(), folder, tmp_path / "out", scheduler=client, shard_size=1)


def test_run_fleet_starts_and_stops_its_own_local_cluster(records, serial, tmp_path):
    before = os.environ.get(MALLOC)
    summary = run_fleet(spec(), records, tmp_path, workers=2)
    assert summary["scheduler"] == "local cluster (2 workers)" and summary["shard_size"] == 1
    assert len(summary["workers"]) == 2
    assert os.environ.get(MALLOC) == before  # this process's environment is left as it was
    assert same_tables(read_fleet(tmp_path), serial)


def test_a_scheduler_address_runs_on_that_cluster(client, records, serial, tmp_path):
    address = client.scheduler.address
    with warnings.catch_warnings():
        warnings.simplefilter("error", FleetWarning)  # these workers are clean: no warning
        summary = run_fleet(spec(), records, tmp_path, scheduler=address)
    assert summary["scheduler"] == address
    assert same_tables(read_fleet(tmp_path), serial)


def test_workers_with_the_malloc_setting_are_warned_about(records, tmp_path):
    saved = os.environ.get(MALLOC)
    try:
        with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                                      silence_logs=50) as cluster, distributed.Client(cluster) as plain:
            with pytest.warns(FleetWarning, match=f"run with {MALLOC}=65536"):
                run_fleet(spec(), records, tmp_path, scheduler=plain)
    finally:  # the default nanny writes the setting into this process's environment too
        os.environ.pop(MALLOC, None)
        if saved is not None:
            os.environ[MALLOC] = saved


def test_an_unreachable_scheduler_is_one_clear_error(records, tmp_path, monkeypatch):
    from bgphm.fleet import engine

    monkeypatch.setattr(engine, "CONNECT_TIMEOUT", "1s")
    with pytest.raises(FleetError, match="scheduler tcp://127.0.0.1:9: cannot connect"):
        run_fleet(spec(), records, tmp_path, scheduler="tcp://127.0.0.1:9")


def test_a_scheduler_without_workers_is_one_clear_error(records, tmp_path, monkeypatch):
    from bgphm.fleet import engine

    monkeypatch.setattr(engine, "WORKER_TIMEOUT", 0.5)
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=":0", silence_logs=50) as empty:
        with pytest.raises(FleetError, match="no worker joined within 0.5 s"):
            run_fleet(spec(), records, tmp_path, scheduler=empty.scheduler_address)


def test_the_command_on_a_parquet_file_with_two_workers(client, records, serial, tmp_path, capsys):
    """bgphm fleet --scheduler on the Parquet form of the records: the tables of the CSV run."""
    parquet = parquet_of(records, tmp_path / "fleet.parquet")
    code = main(["fleet", "rlc", str(parquet), "--fail", "R=20", "--calibrate", "0.2", "--degradation", "linear",
                 "--particles", "100", "--dt", "0.05", "--rul-every", "4", "--out", str(tmp_path / "out"),
                 "--scheduler", client.scheduler.address])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "6 assets, 4 with an alarm" in out and "fleet: 6 of 6 assets (100 %)" in err
    code = main(["--quiet", "fleet", "rlc", str(records), "--fail", "R=20", "--calibrate", "0.2", "--degradation",
                 "linear", "--particles", "100", "--dt", "0.05", "--rul-every", "4", "--out", str(tmp_path / "csv"),
                 "--workers", "0"])
    assert code == 0
    assert same_tables(read_fleet(tmp_path / "out"), read_fleet(tmp_path / "csv"))
    assert np.all(read_fleet(tmp_path / "out").rul["t"] > 0.2)


def _sigint_of_workers():
    import signal
    return signal.getsignal(signal.SIGINT) == signal.SIG_IGN


def test_the_workers_leave_ctrl_c_to_the_driver(client):
    import signal

    assert set(client.run(_sigint_of_workers).values()) == {True}
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler   # this process keeps its own


def test_ctrl_c_in_a_terminal_stops_a_dask_run_with_one_line(tmp_path):
    """SIGINT to the whole process group, as a terminal sends it, once the first shard is done."""
    import signal
    import subprocess
    import sys
    from pathlib import Path

    folder = write_fleet(tmp_path / "records", {f"a{i:02d}": 0.3 if i % 2 else None for i in range(24)})
    command = [sys.executable, "-m", "bgphm", "fleet", "rlc", str(folder), "--fail", "R=20", "--calibrate", "0.2",
               "--workers", "2", "--shard-size", "1", "--particles", "5000", "--out", str(tmp_path / "out")]
    root = str(Path(__file__).resolve().parents[2])
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                             env={**os.environ, "PYTHONPATH": root})
    lines = []
    for line in child.stderr:   # wait for the first shard, then Ctrl-C
        lines.append(line)
        if "fleet: " in line:
            os.killpg(child.pid, signal.SIGINT)
            break
    rest = child.stderr.read()
    child.wait(timeout=600)   # a guard against a hang, not a measure
    assert child.returncode == 1
    assert rest.strip() == "bgphm: interrupted" and "Traceback" not in rest
    assert not (tmp_path / "out" / "manifest.json").exists() and (tmp_path / "out" / ".staging").is_dir()
