"""A fleet's --out: one writer at a time, tables published whole with a manifest, an interrupted run resumed."""

from __future__ import annotations

import json

import pytest

from bgphm.errors import FleetError
from bgphm.fleet import read_fleet, run_fleet
from bgphm.fleet.outdir import locked

from .fleets import spec
from .test_fleet import records, same_tables  # noqa: F401 (records: the fleet's fixture)

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pytestmark = pytest.mark.extras   # pyarrow (the dask extra)


class Interrupt(KeyboardInterrupt):
    """Ctrl-C after a number of shards (raised from the progress callback, between two shards)."""


def interrupt_after(shards: int):
    count = []

    def progress(done, total):
        count.append(done)
        if len(count) == shards:
            raise Interrupt
    return progress


@pytest.fixture(scope="module")
def whole(records, tmp_path_factory):  # noqa: F811
    """An uninterrupted run, a shard per asset: its tables and its manifest."""
    out = tmp_path_factory.mktemp("whole")
    run_fleet(spec(), records, out, workers=0, shard_size=1)
    return read_fleet(out), json.loads((out / "manifest.json").read_text())


def digests(manifest: dict) -> dict:
    return {path: digest for shard in manifest["shards"] for path, digest in shard["files"].items()}


def test_a_second_run_on_the_same_out_is_refused_while_the_first_writes(records, whole, tmp_path):  # noqa: F811
    out = tmp_path / "out"
    run_fleet(spec(), records, out, workers=0, shard_size=1)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    with locked(out):   # the first run, still writing
        with pytest.raises(FleetError, match="another fleet run is writing there"):
            run_fleet(spec(), records, out, workers=0, shard_size=3)
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before   # nothing of it touched
    assert digests(json.loads((out / "manifest.json").read_text())) == digests(whole[1])


def test_an_interrupted_run_is_not_read_as_whole_and_resumes_bitwise(records, whole, tmp_path):  # noqa: F811
    out = tmp_path / "out"
    with pytest.raises(Interrupt):
        run_fleet(spec(), records, out, workers=0, shard_size=1, progress=interrupt_after(2))
    assert not (out / "rul").exists()   # nothing published: pandas or pyarrow find no partial table
    with pytest.raises(FleetError, match=r"interrupted \(bgphm fleet --resume goes on\)"):
        read_fleet(out)
    summary = run_fleet(spec(), records, out, workers=0, shard_size=1, resume=True)
    assert summary["resumed_shards"] == 2 and summary["shards"] == 6
    manifest = json.loads((out / "manifest.json").read_text())
    assert digests(manifest) == digests(whole[1])   # the same files, to the last bit
    assert not (out / ".staging").exists()
    assert same_tables(read_fleet(out), whole[0])


def test_an_interrupted_run_leaves_the_previous_tables_whole(records, whole, tmp_path):  # noqa: F811
    out = tmp_path / "out"
    run_fleet(spec(), records, out, workers=0, shard_size=1)
    (out / "rul" / "notes.txt").write_text("mine")
    with pytest.raises(Interrupt):
        run_fleet(spec(seed=5), records, out, workers=0, shard_size=2, progress=interrupt_after(1))
    assert digests(json.loads((out / "manifest.json").read_text())) == digests(whole[1])
    assert same_tables(read_fleet(out), whole[0])   # the first run's, whole
    run_fleet(spec(seed=5), records, out, workers=0, shard_size=2)
    assert (out / "rul" / "notes.txt").read_text() == "mine"   # a user's file stays with its table
    assert {p.name for p in out.glob("rul/bucket=*/*")} <= {f"part-0000{i}.parquet" for i in range(3)}


def test_resume_refuses_another_job_and_reruns_a_damaged_shard(records, whole, tmp_path):  # noqa: F811
    out = tmp_path / "out"
    with pytest.raises(FleetError, match="nothing to resume"):
        run_fleet(spec(), records, out, workers=0, shard_size=1, resume=True)
    with pytest.raises(Interrupt):
        run_fleet(spec(), records, out, workers=0, shard_size=1, progress=interrupt_after(3))
    with pytest.raises(FleetError, match="cannot resume: the interrupted run had other spec"):
        run_fleet(spec(seed=9), records, out, workers=0, shard_size=1, resume=True)
    with pytest.raises(FleetError, match="cannot resume: the interrupted run had other shards"):
        run_fleet(spec(), records, out, workers=0, shard_size=2, resume=True)
    staged = sorted((out / ".staging").rglob("part-*.parquet"))
    damaged = bytearray(staged[0].read_bytes())
    damaged[len(damaged) // 2] ^= 0x01
    staged[0].write_bytes(bytes(damaged))
    summary = run_fleet(spec(), records, out, workers=0, shard_size=1, resume=True)
    assert summary["resumed_shards"] == 2   # of the three finished, the damaged one ran again
    assert digests(json.loads((out / "manifest.json").read_text())) == digests(whole[1])


def test_read_fleet_refuses_tables_that_are_not_the_manifests(records, tmp_path):  # noqa: F811
    out = tmp_path / "out"
    run_fleet(spec(), records, out, workers=0, shard_size=1)
    part = sorted(out.glob("rul/bucket=*/part-*.parquet"))[0]
    stray = part.with_name("part-99999.parquet")
    stray.write_bytes(part.read_bytes())
    with pytest.raises(FleetError, match="not those of manifest.json; not listed: rul/bucket=.*part-99999"):
        read_fleet(out)
    stray.unlink()
    table = pq.read_table(part)
    pq.write_table(table.slice(0, table.num_rows - 1), part)   # a row dropped by hand
    with pytest.raises(FleetError, match="SHA-256 is not the manifest's"):
        read_fleet(out)
