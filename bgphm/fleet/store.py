"""A fleet's tables on disk: Parquet datasets partitioned by asset bucket, written shard by shard.

Layout under the output directory::

    alarms/bucket=03/part-00012.parquet     # the rows of shard 12 whose asset falls in bucket 3
    estimates/bucket=.../part-....parquet
    rul/bucket=.../part-....parquet
    summary.json                            # written last: the run finished

An asset's bucket is ``asset_key(asset) % buckets`` (:func:`prognosis.streams.asset_key`, a hash
that is the same in every process), so all of an asset's rows are in one bucket, and in one file
(one shard holds the asset).  Each file is written whole or not at all (:func:`bgphm.files.write_with`:
a hidden temporary file, then a rename), and readers skip hidden files.  pandas reads a table with
``pd.read_parquet(out / "rul")`` (the bucket becomes a column); :func:`read_fleet` gives a
:class:`~prognosis.fleet.FleetResult` in an order that does not depend on the sharding.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from bgphm.errors import FleetError, FleetWarning
from bgphm.files import write_with
from prognosis.fleet import FleetResult
from prognosis.fleet.results import COLUMNS, INTEGER, TABLES, TEXT
from prognosis.streams import asset_key

from .sources import pyarrow_modules

__all__ = ["BUCKETS", "bucket_of", "clear_outputs", "read_fleet", "write_shard"]

BUCKETS = 16  # partitions per table: few enough files, small enough to read one bucket's assets alone
SUMMARY = "summary.json"
PART = re.compile(r"part-\d+\.parquet")
BUCKET = re.compile(r"bucket=\d+")


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


def write_shard(result: FleetResult, out: str | Path, shard: int, buckets: int = BUCKETS) -> dict:
    """Write the tables of one shard's result, one file per table and bucket; return the rows per table."""
    pa, _, pq = pyarrow_modules()
    rows = {}
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
            path = Path(out) / name / f"bucket={b:0{_width(buckets)}d}" / f"part-{shard:05d}.parquet"
            write_with(path, lambda p, arrow=arrow: pq.write_table(arrow, p))
    return rows


def clear_outputs(out: str | Path) -> None:
    """Remove a previous run's tables and summary from ``out`` (only the files this module writes).

    Parts of a run with another sharding would otherwise be read with the new ones.
    """
    out = Path(out)
    (out / SUMMARY).unlink(missing_ok=True)
    for name in TABLES:
        for folder in (out / name).glob("bucket=*"):
            if not (folder.is_dir() and BUCKET.fullmatch(folder.name)):
                continue
            for part in folder.iterdir():
                if PART.fullmatch(part.name):
                    part.unlink()
            if not any(folder.iterdir()):
                folder.rmdir()


def read_fleet(out: str | Path) -> FleetResult:
    """The tables of a fleet run written under ``out``, as a :class:`~prognosis.fleet.FleetResult`.

    Rows are ordered by asset id, and each asset's rows in the order the monitor wrote them, so the
    result is the same whatever the sharding, the workers and the scheduler.

    Raises
    ------
    FleetError
        ``out`` holds no fleet tables.

    Warns
    -----
    FleetWarning
        No ``summary.json``: the run did not finish, and assets may be missing.
    """
    pa, pc, pq = pyarrow_modules()
    out = Path(out)
    if not all((out / name).is_dir() for name in TABLES):
        raise FleetError(f"{out}: not the output of a fleet run (no {', '.join(TABLES)} directories)")
    if not (out / SUMMARY).is_file():
        warnings.warn(f"{out}: no {SUMMARY}, so the run did not finish; assets may be missing", FleetWarning,
                      stacklevel=2)
    result = FleetResult()
    for name in TABLES:
        parts = [pq.read_table(p, schema=schema(name)) for p in _parts(out / name)]
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
