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
from diagnosis.signals import MAX_RECORD_BYTES, MISSING_CELLS, Record, RecordError, as_record, read_csv

__all__ = ["CsvDirectory", "ParquetRecords", "open_source", "pyarrow_modules", "read_csv_fast"]

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

    Each file is read with :func:`diagnosis.signals.read_csv` (a header row with ``t`` and the signals).
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

        A well-formed file is parsed by pyarrow; any other goes through
        :func:`~diagnosis.signals.read_csv`, which names what is wrong (:func:`read_csv_fast`).  A file
        that cannot be read raises that error, or, with ``skip``, is reported as ``skip(asset, reason)``.
        """
        for asset in assets:
            path = Path(self.path) / f"{asset}.csv"
            try:
                record = read_csv_fast(path, signals) or read_csv(path, signals)
            except RecordError as error:
                if skip is None:
                    raise
                skip(asset, str(error))
                continue
            yield asset, record

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
        for asset in assets:
            try:
                if asset not in bounds:
                    raise RecordError(f"records {self.path}: no row for asset {asset!r}")
                lo, hi = bounds[asset]
                data = {c: _floats(v[lo:hi]) for c, v in columns.items()}
                record = as_record(data, signals, name=f"{self.path} (asset {asset!r})")
            except RecordError as error:
                if skip is None:
                    raise
                skip(asset, str(error))
                continue
            yield asset, record


def read_csv_fast(path: Path, signals: Sequence[str]) -> Record | None:
    r"""The record of a well-formed CSV file, parsed by pyarrow; None for any file it cannot vouch for.

    :func:`~diagnosis.signals.read_csv` parses cells one by one in Python (about 25 us a row): for a
    fleet of long records, reading took longer than monitoring.  This reads the same numbers (both
    parsers round correctly; the gaps are the same words) about fifty times faster, and gives up --
    returning None, so that ``read_csv`` reads the file and names what is wrong -- on anything
    unusual: a header ``read_csv`` would refuse or strip, a cell pyarrow cannot parse (spaces around a
    number, text), a record :func:`~diagnosis.signals.as_record` refuses.  ``read_csv``'s warning
    about text in unused columns is not given here (those columns are not read at all).

    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "a.csv"
    >>> _ = path.write_text("t,x,note\n0,1.5,ok\n0.5,,ok\n1,2.5e-3,ok\n")
    >>> read_csv_fast(path, ["x"])["x"].tolist()
    [1.5, nan, 0.0025]
    >>> _ = path.write_text("t,x\n0,1_000\n0.5,2\n1,3\n")   # not a number for read_csv: left to it
    >>> read_csv_fast(path, ["x"]) is None
    True
    """
    import csv

    pa, _, _ = pyarrow_modules()
    import pyarrow.csv as pcsv

    columns = ["t", *signals]
    try:
        if path.stat().st_size > MAX_RECORD_BYTES:  # read_csv refuses it, naming the limit
            return None
        with path.open(newline="", encoding="utf-8-sig") as handle:
            header = next(csv.reader(handle), [])
    except (OSError, UnicodeDecodeError, csv.Error):
        return None
    if (len(set(header)) != len(header) or any(not c or c != c.strip() for c in header)
            or any(c not in header for c in columns)):
        return None
    options = pcsv.ConvertOptions(include_columns=columns, column_types={c: pa.float64() for c in columns},
                                  null_values=sorted(MISSING_CELLS), quoted_strings_can_be_null=False)
    try:
        # one thread: a Dask worker runs one task per core already
        table = pcsv.read_csv(path, read_options=pcsv.ReadOptions(use_threads=False), convert_options=options)
        record = as_record({c: table.column(c).to_numpy() for c in columns}, signals, name=str(path))
    except (pa.ArrowException, OSError, ValueError, KeyError):
        return None
    return record if np.all(np.isfinite(record.t)) else None


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
