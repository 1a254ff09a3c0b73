"""A fleet's tables on disk: Parquet datasets partitioned by asset bucket, written shard by shard.

Layout of a table (under the staging area while a run goes, published whole at its end: see
:mod:`bgphm.fleet.outdir`)::

    alarms/bucket=03/part-00012.parquet     # the rows of shard 12 whose asset falls in bucket 3
    estimates/bucket=.../part-....parquet
    rul/bucket=.../part-....parquet

An asset's bucket is ``asset_key(asset) % buckets`` (:func:`prognosis.random_streams.asset_key`, a hash
that is the same in every process), so all of an asset's rows are in one bucket, and in one file
(one shard holds the asset).  Each file is written whole or not at all (:func:`bgphm.files.write_with`:
a hidden temporary file, then a rename), and readers skip hidden files.  pandas reads a published
table with ``pd.read_parquet(out / "rul")`` (the bucket becomes a column); :func:`read_fleet` checks
the files against the run's manifest and gives a :class:`~prognosis.fleet.FleetResult` in an order
that does not depend on the sharding.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from bgphm.errors import FleetError
from bgphm.files import file_digest, write_with
from prognosis.fleet import FleetResult
from prognosis.fleet.results import COLUMNS, INTEGER, TABLES, TEXT
from prognosis.random_streams import asset_key

from .outdir import BUCKET, MANIFEST, PART, STAGING, read_manifest
from .sources import pyarrow_modules

__all__ = ["BUCKETS", "bucket_of", "read_fleet", "read_tables", "write_shard"]

BUCKETS = 16  # partitions per table: few enough files, small enough to read one bucket's assets alone


def bucket_of(asset: str, buckets: int = BUCKETS) -> int:
    """The bucket of an asset id: the same in every process and on every machine.

    >>> bucket_of("pump-1") == bucket_of("pump-1"), 0 <= bucket_of("pump-1") < BUCKETS
    (True, True)
    """
    return asset_key(asset) % buckets


def schema(name: str):
    """The Parquet schema of table ``name``: text as string, ``step`` as int64, the rest float64."""
    pa, _, _ = pyarrow_modules()
    return pa.schema([(c, pa.string() if c in TEXT else pa.int64() if c in INTEGER else pa.float64())
                      for c in COLUMNS[name]])


def write_shard(result: FleetResult, out: str | Path, shard: int, buckets: int = BUCKETS) -> tuple[dict, dict]:
    """Write the tables of one shard's result under ``out``, one file per table and bucket.

    Returns the rows per table and the files written, ``{path relative to out: SHA-256}``.
    """
    pa, _, pq = pyarrow_modules()
    rows, files = {}, {}
    for name in TABLES:
        table = result.table(name)
        rows[name] = int(len(table["asset"]))
        if not rows[name]:
            continue
        ids, index = np.unique(table["asset"].astype(str), return_inverse=True)
        bucket = np.array([bucket_of(a, buckets) for a in ids])[index]
        for b in np.unique(bucket):
            mine = bucket == b
            arrow = pa.table({c: pa.array(table[c][mine].tolist() if c in TEXT else table[c][mine], type=t.type)
                              for c, t in zip(COLUMNS[name], schema(name))}, schema=schema(name))
            relative = f"{name}/bucket={b:0{_width(buckets)}d}/part-{shard:05d}.parquet"
            path = write_with(Path(out) / relative, lambda p, arrow=arrow: pq.write_table(arrow, p))
            files[relative] = file_digest(path)
    return rows, files


def read_fleet(out: str | Path) -> FleetResult:
    """The tables of a fleet run published under ``out``, as a :class:`~prognosis.fleet.FleetResult`.

    Rows are ordered by asset id, and each asset's rows in the order the monitor wrote them, so the
    result is the same whatever the sharding, the workers and the scheduler.

    Raises
    ------
    FleetError
        ``out`` holds no fleet tables; the run did not finish, is still running or was interrupted
        (no ``manifest.json``); a table's files are not those of the manifest, or one was altered.
    """
    out = Path(out)
    if not any((out / name).exists() for name in (*TABLES, MANIFEST, STAGING)):
        raise FleetError(f"{out}: not the output of a fleet run (no {', '.join(TABLES)} directories)")
    manifest = read_manifest(out)
    listed = {path: digest for shard in manifest["shards"] for path, digest in shard["files"].items()}
    present = {p.relative_to(out).as_posix() for name in TABLES for p in _parts(out / name)}
    if present != set(listed):
        extra, missing = sorted(present - set(listed)), sorted(set(listed) - present)
        raise FleetError(f"{out}: the tables' files are not those of manifest.json"
                         + (f"; not listed: {', '.join(extra[:3])}" if extra else "")
                         + (f"; missing: {', '.join(missing[:3])}" if missing else ""))
    return read_tables(out, listed)


def read_tables(root: str | Path, files: dict) -> FleetResult:
    """The tables of the part files ``files`` (``{path relative to root: SHA-256}``), each checked against its digest.

    :func:`read_fleet` reads a published run with it; ``run_fleet`` reads the staged shards of its run with it,
    for the page, before it publishes them.  Rows are ordered by asset id, each asset's rows in the order the
    monitor wrote them.
    """
    pa, pc, pq = pyarrow_modules()
    root = Path(root)
    result = FleetResult()
    for name in TABLES:
        parts = []
        for relative in sorted(path for path in files if path.split("/")[0] == name):
            path = root / relative
            content = path.read_bytes()
            if hashlib.sha256(content).hexdigest() != files[relative]:
                raise FleetError(f"{path}: its SHA-256 is not the manifest's: the file was altered after the run")
            parts.append(pq.read_table(pa.BufferReader(content), schema=schema(name)))
        if not parts:
            continue
        table = pa.concat_tables(parts)
        # a stable sort: an asset's rows keep the monitor's order (all of them come from one file)
        table = table.take(pc.sort_indices(table, sort_keys=[("asset", "ascending")]))
        result.add(name, **{c: table.column(c).to_numpy(zero_copy_only=False) for c in COLUMNS[name]})
    return result


def _parts(folder: Path) -> list[Path]:
    """The part files of a table, in a fixed order (temporary files are hidden and skipped)."""
    return sorted(p for b in folder.glob("bucket=*") if BUCKET.fullmatch(b.name)
                  for p in b.iterdir() if PART.fullmatch(p.name))


def _width(buckets: int) -> int:
    return max(2, len(str(buckets - 1)))
