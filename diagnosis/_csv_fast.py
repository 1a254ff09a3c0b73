"""The fast paths of :func:`diagnosis.csv_reading.read_csv`: a file of plain numbers parsed by pyarrow or numpy.

``read_csv`` checks every cell against a strict number grammar and names the first bad one; for a
file of plain numbers, that is what pyarrow's or numpy's C parser does in a fraction of the time
(a record of 200 000 rows and 4 columns: 0.75 s cell by cell, 0.035 s with pyarrow, 0.055 s with
numpy's ``loadtxt``).  :func:`parse` tries pyarrow when it is installed, then numpy, and gives up
(None) on anything either might read differently from ``read_csv``: a cell neither parses, a row of
another length, a blank line inside the body, a gap word they do not know.  The caller then reads
the file cell by cell and says what is wrong.  Both parsers accept exactly the numbers of the
grammar, with spaces around them (``read_csv`` strips cells) and the words ``nan`` and ``inf``
(NaN is a gap for ``read_csv`` too; an infinite value is left to ``read_csv``, which refuses it).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable
from pathlib import Path

import numpy as np

__all__ = ["parse"]


def parse(path: Path, missing: frozenset, numeric: Callable[[str], bool],
          parsers: tuple = ("pyarrow", "numpy")) -> tuple[list[str], list] | None:
    """``(header cells, columns)`` of a CSV file of numbers, or None to leave it to ``read_csv``.

    ``columns[i]`` is the float array of column ``i`` (NaN for a gap, an empty cell or a word of
    ``missing``), or None for a column that holds text (only pyarrow reads past one; numpy gives
    up).  ``numeric(cell)``: whether ``read_csv`` reads a cell as a number or a gap (a column
    pyarrow calls text but ``read_csv`` would not, its cells padded with spaces, is left to it).
    The header is the first row as ``csv`` reads it, unchecked.  ``parsers``: those tried, in order.
    """
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            header = next(csv.reader([handle.readline()]), [])
    except (OSError, UnicodeDecodeError, csv.Error):
        return None
    if not header:
        return None
    for name in parsers:
        columns = (_by_pyarrow(path, len(header), missing, numeric) if name == "pyarrow"
                   else _by_numpy(path, len(header)))
        if columns is not None:
            return header, columns
    return None


def _by_pyarrow(path: Path, width: int, missing: frozenset, numeric: Callable[[str], bool]) -> list | None:
    try:
        import pyarrow as pa
        import pyarrow.csv as pcsv
    except ImportError:
        return None
    names = [f"c{i}" for i in range(width)]  # the header is read by csv, as read_csv reads it
    floats = dict.fromkeys(names, pa.float64())
    table = _arrow_table(pcsv, pa, path, names, floats, missing)
    if table is None:  # a column of text, perhaps: which ones, then the others as numbers
        guessed = _arrow_table(pcsv, pa, path, names, {}, missing)
        if guessed is None:
            return None
        text = [n for n in names if pa.types.is_string(guessed.column(n).type)]
        if not text or any(all(numeric(cell) for cell in guessed.column(n).to_pylist() if cell is not None)
                           for n in text):
            return None
        table = _arrow_table(pcsv, pa, path, names, {n: t for n, t in floats.items() if n not in text}, missing)
        if table is None:
            return None
    # text (or dates, booleans): what read_csv warns of when unused, refuses when used
    return [table.column(n).to_numpy(zero_copy_only=False) if pa.types.is_floating(table.column(n).type) else None
            for n in names]


def _arrow_table(pcsv, pa, path: Path, names: list, types: dict, missing: frozenset):
    """The table pyarrow reads with these column types (the others inferred), or None if it cannot.

    Numbers are read as floats, never inferred: pyarrow's integers take ``0x10`` for 16, which
    ``read_csv`` refuses.  A quoted gap word is a gap, as ``csv`` unquotes it for ``read_csv``."""
    try:
        return pcsv.read_csv(path, read_options=pcsv.ReadOptions(use_threads=False, skip_rows=1, column_names=names),
                             parse_options=pcsv.ParseOptions(ignore_empty_lines=False),
                             convert_options=pcsv.ConvertOptions(column_types=types, null_values=sorted(missing),
                                                                 quoted_strings_can_be_null=True))
    except (pa.ArrowException, OSError, ValueError):
        return None


def _by_numpy(path: Path, width: int) -> list | None:
    try:
        raw = path.read_bytes()
    except OSError:
        return None
    start = raw.find(b"\n") + 1  # the body's first byte (0: a header alone, no sample)
    end = _body_end(raw, start)
    if not start or end <= start:
        return None  # no sample: read_csv says so
    lines = raw.count(b"\n", start, end) + 1
    try:
        try:  # the file as it is: loadtxt reads a path fastest, and refuses an empty cell
            values = np.loadtxt(path, delimiter=",", dtype=float, ndmin=2, comments=None, skiprows=1,
                                encoding="utf-8-sig")
        except ValueError:  # gaps as empty cells, perhaps: written "nan"
            text = _empty_cells_as_nan(raw[start:end].decode("utf-8").replace("\r\n", "\n"))
            values = np.loadtxt(io.StringIO(text), delimiter=",", dtype=float, ndmin=2, comments=None)
    except ValueError:  # text, a gap word loadtxt does not know, a row of another length, bytes not UTF-8
        return None
    if values.shape != (lines, width):
        return None
    return list(values.T)


def _body_end(raw: bytes, start: int) -> int:
    """Where the body ends once the trailing blank lines (a row of empty cells too) are cut, as read_csv cuts
    them; a blank line inside the body it refuses (loadtxt would skip it: the rows are counted)."""
    end = len(raw)
    while end > start:
        line_start = max(raw.rfind(b"\n", start, end - 1) + 1, start)  # the last line, its newline included
        line = raw[line_start:end]
        if line.strip(b", \t\r\n"):
            return line_start + len(line.rstrip(b" \t\r\n"))
        end = line_start
    return start


def _empty_cells_as_nan(body: str) -> str:
    """Every empty cell written ``nan`` (loadtxt refuses an empty one)."""
    for _ in range(2):  # ",,," needs two passes: each match consumes the comma after the cell
        body = body.replace(",,", ",nan,")
    body = body.replace(",\n", ",nan\n").replace("\n,", "\nnan,")
    body = "nan" + body if body.startswith(",") else body
    return body + "nan" if body.endswith(",") else body
