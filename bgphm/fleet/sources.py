"""Where a fleet's records come from: a directory of CSV files, or one Parquet file with an asset column.

A source is a small picklable object (a path), listed by the driver and read by the workers:

* :meth:`assets` gives the asset ids, as sorted strings;
* :meth:`read` yields ``(asset, record)`` pairs for the ids of one shard, one record at a time, so a
  worker holds the records of a few assets at most (:class:`~prognosis.fleet.FleetMonitor` keeps only
  their values at the filter steps);
* :meth:`inputs` lists the input files, which no output may overwrite.

Examples
--------
>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> for name in ("pump-2", "pump-1"):
...     _ = (folder / f"{name}.csv").write_text("t,x\\n0,1\\n1,2\\n2,3\\n")
>>> source = open_source(folder)
>>> source.assets()
['pump-1', 'pump-2']
>>> [(asset, len(record)) for asset, record in source.read(["pump-2"], ["x"])]
[('pump-2', 3)]
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bgphm.errors import MissingExtraError
from diagnosis.csv_reading import read_csv
from diagnosis.records import Record, RecordError, as_record

__all__ = ["CsvDirectory", "ParquetRecords", "open_source", "pyarrow_modules"]

READ_CHUNK = 250  # assets read from a Parquet file at once: bounds a worker's memory, not its scans


def pyarrow_modules():
    """``(pyarrow, pyarrow.compute, pyarrow.parquet)``, or :class:`MissingExtraError` naming the extra."""
    try:
        import pyarrow
        import pyarrow.compute
        import pyarrow.parquet
    except ImportError as error:
        raise MissingExtraError("pyarrow is needed for fleet runs (Parquet input and output): "
                                "pip install 'bondgraph-phm[dask]'") from error
    return pyarrow, pyarrow.compute, pyarrow.parquet


def open_source(records: str | os.PathLike | "CsvDirectory | ParquetRecords"):
    """The source of ``records``: a directory of CSV files or a ``.parquet`` file (a source is kept as is).

    Raises
    ------
    RecordError
        ``records`` does not exist, or is a file that is not Parquet.
    """
    if isinstance(records, (CsvDirectory, ParquetRecords)):
        return records
    path = Path(records)
    if path.is_dir():
        return CsvDirectory(str(path.resolve()))
    if not path.exists():
        raise RecordError(f"records {path}: no such directory or file")
    if path.suffix.lower() != ".parquet":
        raise RecordError(f"records {path}: expected a directory of CSV files (one per asset) or a .parquet file "
                          "with an 'asset' column")
    return ParquetRecords(str(path.resolve()))


@dataclass(frozen=True)
class CsvDirectory:
    """A directory of ``*.csv`` records, one per asset; the asset id is the file name without ``.csv``.

    Each file is read with :func:`diagnosis.csv_reading.read_csv` (a header row with ``t`` and the signals).
    Hidden files (a name starting with ``.``) are skipped.
    """

    path: str

    def assets(self) -> list[str]:
        """The asset ids, sorted; RecordError if the directory is missing or holds no CSV file."""
        return [p.name[:-4] for p in self.inputs()]

    def inputs(self) -> list[Path]:
        """The CSV files, sorted by name."""
        folder = Path(self.path)
        if not folder.is_dir():
            raise RecordError(f"records {folder}: no such directory")
        files = sorted(p for p in folder.iterdir() if p.name.endswith(".csv") and not p.name.startswith(".")
                       and p.is_file())
        for path in files:
            try:
                path.name.encode("utf-8")
            except UnicodeEncodeError:  # bytes the file system gave that are not text: no id, no table cell
                raise RecordError(f"records {folder}: the file name {path.name!r} is not valid UTF-8; asset ids are "
                                  "text: rename the file") from None
        if not files:
            raise RecordError(f"records {folder}: no .csv file in it (one record per asset; the asset id is the "
                              "file name)")
        return files

    def read(self, assets: Iterable[str], signals: Sequence[str], skip=None) -> Iterator[tuple[str, Record]]:
        """``(asset, record)`` for each id, read when the consumer asks for it.

        Each file is read by :func:`~diagnosis.csv_reading.read_csv` (pyarrow or numpy parse a file of
        plain numbers; any other is read cell by cell and what is wrong is named).  A file that cannot
        be read raises that error, or, with ``skip``, is reported as ``skip(asset, reason)``.
        """
        for asset in assets:
            yield from _readable(asset, lambda a=asset: read_csv(Path(self.path) / f"{a}.csv", signals), skip)

    def describe(self) -> str:
        return f"CSV directory {self.path}"


@dataclass(frozen=True)
class ParquetRecords:
    """One Parquet file holding every asset's record: a column ``asset``, a time column ``t``, the signals.

    Asset ids are read as strings (an integer column too).  Rows may come in any order: each asset's
    rows are sorted by ``t`` when read (its times must then be distinct).  A file sorted by asset reads
    faster, as pyarrow skips the row groups of other assets.
    """

    path: str
    column: str = "asset"

    def assets(self) -> list[str]:
        """The distinct asset ids, sorted.

        The column is read batch by batch, keeping each batch's distinct ids: the whole column as text
        took 1.5 GB and 4 s for 10^4 assets of 10^4 rows.
        """
        pa, pc, _ = pyarrow_modules()
        self._check_columns([])
        ids = set()
        for batch in self._dataset().to_batches(columns=[self.column], use_threads=False):
            column = batch.column(0)
            if column.null_count:
                raise RecordError(f"records {self.path}: column {self.column!r} has empty cells; every row needs an "
                                  "asset id")
            ids.update(pc.unique(column).cast(pa.string()).to_pylist())
        if not ids:
            raise RecordError(f"records {self.path}: no rows")
        return sorted(ids)

    def inputs(self) -> list[Path]:
        return [Path(self.path)]

    def read(self, assets: Iterable[str], signals: Sequence[str], skip=None) -> Iterator[tuple[str, Record]]:
        """``(asset, record)`` for each id, read in chunks of :data:`READ_CHUNK` assets (an asset's record
        that cannot be read: its error raised, or reported as ``skip(asset, reason)``)."""
        self._check_columns(signals)
        assets = list(assets)
        for start in range(0, len(assets), READ_CHUNK):
            yield from self._chunk(assets[start:start + READ_CHUNK], list(signals), skip)

    def describe(self) -> str:
        return f"Parquet file {self.path}"

    def _dataset(self):
        pa, _, _ = pyarrow_modules()
        import pyarrow.dataset

        try:
            return pyarrow.dataset.dataset(self.path, format="parquet")
        except (pa.ArrowInvalid, OSError) as error:
            reason = " ".join(str(error).split()).rpartition(": ")[2]  # pyarrow's last clause says why
            raise RecordError(f"records {self.path}: not a readable Parquet file ({reason})") from None

    def _check_columns(self, signals: Sequence[str]) -> None:
        pa, _, _ = pyarrow_modules()
        schema = self._dataset().schema
        missing = [c for c in (self.column, "t", *signals) if c not in schema.names]
        if missing:
            raise RecordError(f"records {self.path}: missing column(s) {missing}; columns present: {schema.names}")
        kind = schema.field(self.column).type
        if not (pa.types.is_string(kind) or pa.types.is_large_string(kind) or pa.types.is_integer(kind)):
            raise RecordError(f"records {self.path}: column {self.column!r} holds {kind}; asset ids must be text or "
                              "whole numbers")

    def selection(self, assets: Sequence[str]):
        """The dataset filter of these asset ids, on the column as stored.

        A filter on the stored column, with the ids' range, lets pyarrow skip the row groups whose
        statistics exclude them (a file sorted by asset is then read once over all chunks); a cast of
        the column, or a long list of ids alone, would make it read and test every row of the file for
        every chunk.  For an integer column the ids are compared as the integers whose text they are
        (an id that is not one matches no row).

        >>> import tempfile, pathlib, pyarrow as pa, pyarrow.dataset, pyarrow.parquet as pq
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "fleet.parquet"
        >>> pq.write_table(pa.table({"asset": ["a", "a", "b", "b"], "t": [0.0, 1.0, 0.0, 1.0]}), path,
        ...                row_group_size=2)
        >>> source = ParquetRecords(str(path))
        >>> fragment = next(pyarrow.dataset.dataset(path).get_fragments())
        >>> len(fragment.split_by_row_group(source.selection(["b"])))   # one row group of two is read
        1
        """
        pa, pc, _ = pyarrow_modules()
        kind = self._dataset().schema.field(self.column).type
        column = pc.field(self.column)
        if pa.types.is_string(kind) or pa.types.is_large_string(kind):
            return _within(column, pa.array(list(assets), type=kind))
        if pa.types.is_integer(kind):
            try:
                return _within(column, pa.array([int(a) for a in assets if _integer_text(a)], type=kind))
            except (pa.ArrowInvalid, OverflowError):  # an id beyond the column's integers: compare as text
                pass
        return column.cast(pa.string()).isin(list(assets))

    def _chunk(self, assets: list, signals: list, skip=None) -> Iterator[tuple[str, Record]]:
        pa, pc, _ = pyarrow_modules()
        # one thread: a Dask worker runs one task per core already (and the threaded scan was slower here)
        table = self._dataset().to_table(columns=[self.column, "t", *signals], filter=self.selection(assets),
                                         use_threads=False)
        table = table.set_column(0, self.column, table.column(self.column).cast(pa.string()))
        order = pc.sort_indices(table, sort_keys=[(self.column, "ascending"), ("t", "ascending")]).to_numpy()
        if np.any(order[1:] < order[:-1]):  # a file sorted by asset and time needs no copy
            table = table.take(order)
        # each asset's first and last row from the counts (in order of appearance, i.e. sorted), not a
        # Python string per row
        counts = pc.value_counts(table.column(self.column)).flatten()
        ends = np.cumsum(counts[1].to_numpy())
        bounds = dict(zip(counts[0].to_pylist(), zip((ends - counts[1].to_numpy()).tolist(), ends.tolist())))
        columns = {c: table.column(c).to_numpy(zero_copy_only=False) for c in ["t", *signals]}
        del table, order  # the chunk is held once, as the numpy columns
        def record(asset):
            if asset not in bounds:
                raise RecordError(f"records {self.path}: no row for asset {asset!r}")
            lo, hi = bounds[asset]
            return as_record({c: _floats(v[lo:hi]) for c, v in columns.items()}, signals,
                             name=f"{self.path} (asset {asset!r})")

        for asset in assets:
            yield from _readable(asset, lambda a=asset: record(a), skip)


def _readable(asset: str, read, skip) -> Iterator[tuple[str, Record]]:
    """``(asset, read())``; a record that cannot be read raises its error, or with ``skip`` is reported as
    ``skip(asset, reason)`` and yields nothing."""
    try:
        record = read()
    except RecordError as error:
        if skip is None:
            raise
        skip(asset, str(error))
        return
    yield asset, record


def _within(column, values):
    """``column`` in ``values``, with their range first: pyarrow prunes row groups by a range, but not by
    a long list of values (a shard's chunk holds hundreds of ids)."""
    _, pc, _ = pyarrow_modules()
    if not len(values):
        return column.isin(values)
    bounds = pc.min_max(values)
    return (column >= bounds["min"]) & (column <= bounds["max"]) & column.isin(values)


def _integer_text(asset: str) -> bool:
    """Whether an id is the text of an integer as an integer column's ids are written (``"12"``, ``"-3"``)."""
    try:
        return str(int(asset)) == asset
    except (TypeError, ValueError):
        return False


def _floats(values: np.ndarray) -> np.ndarray:
    """A Parquet column slice as numbers (an empty cell of a numeric column is NaN, a gap)."""
    if values.dtype == object:
        return np.array([np.nan if v is None else v for v in values], dtype=object)
    return values
