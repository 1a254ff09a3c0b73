"""Records from CSV files: a header row with ``t`` and the signals, one row per sample, empty cells as gaps.

:func:`read_csv` parses a file of plain numbers with pyarrow when it is installed, else with numpy
(:mod:`diagnosis._csv_fast`), and falls back to a reader that goes cell by cell and names the file,
the line and the column of a cell that is not a number; files over :data:`MAX_RECORD_BYTES` are
refused before they are read.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Iterable

import numpy as np


from .records import MAX_MAGNITUDE, Record, RecordError, RecordWarning, TIME, as_record

__all__ = ["CSV_NUMBER", "MAX_RECORD_BYTES", "MISSING_CELLS", "PARSERS", "read_csv"]


#: The largest CSV record read, in bytes.  Parsing takes several times the file's size in memory (a
#: 2 GB file, sparse or not, grew past 3 GB): a larger record is refused before it is read.  A
#: fleet's large records belong in a Parquet file, read by asset.
MAX_RECORD_BYTES = 1 << 30


MISSING_CELLS = frozenset({"", "nan", "NaN", "NAN", "NA", "N/A", "null"})


#: A number in a CSV cell: decimal digits with an optional sign, point and exponent.  Python's
#: ``float()`` also takes ``1_000``, other scripts' digits and surrounding words; a data file should not.
CSV_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


_PLAIN_COLUMN = re.compile(f"(?:{CSV_NUMBER.pattern})(?:\n(?:{CSV_NUMBER.pattern}))*")


#: Words ``float()`` reads as infinite or NaN, with an optional sign, in any case.
_SPECIAL_NUMBER = re.compile(r"[+-]?(?:inf|infinity|nan)", re.IGNORECASE)


#: Separators a CSV file written with another convention uses instead of the comma.
_OTHER_SEPARATORS = ((";", "';'"), ("\t", "tabs"), ("|", "'|'"))


def read_csv(path, signals: Iterable[str] = (), *, name: str | None = None, parser: str = "auto") -> Record:
    r"""Read a CSV file with a header row and a time column ``t`` into a :class:`Record`.

    Cells are parsed as numbers, never evaluated: decimal digits with an optional sign, point and
    exponent (:data:`CSV_NUMBER`; ``1_000`` is refused although Python's ``float()`` reads it), of
    magnitude at most :data:`MAX_MAGNITUDE`.  An empty cell or ``nan``/``NA``/``null`` is a gap
    (NaN); ``inf`` is an error (leave the cell empty for a gap).

    Only ``t`` and the ``signals`` (default: every column) are read.  A column that is not
    among them is ignored; if it holds text, one :class:`RecordWarning` names it (and every other
    such column).  Errors name the file, the line (1 = the header) and the column: a missing ``t``
    or signal column, a duplicate column, a row with too many or too few cells, a file separated by
    ``;``, tabs or ``|`` instead of commas, a non-numeric, infinite or too large cell, a gap or a
    step back in ``t``.  ``signals`` and the rest of the checks are as in :func:`as_record`.

    ``parser``: who parses a file of plain numbers first: ``"auto"`` (pyarrow when it is installed,
    else numpy's ``loadtxt``), ``"pyarrow"``, ``"numpy"``, or ``"cells"`` (cell by cell, as every
    file that either of them might read differently is read anyway).  The record, the warnings and
    the errors are the same whichever it is; only the time differs.

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "run.csv")
    >>> _ = open(path, "w").write("t,x\n0,1\n0.5,\n1,3\n")
    >>> read_csv(path)["x"].tolist()
    [1.0, nan, 3.0]
    >>> _ = open(path, "w").write("t,x\n0,1\n0.5,abc\n1,3\n")
    >>> read_csv(path)
    Traceback (most recent call last):
    ...
    diagnosis.records.RecordError: ...run.csv line 3, column 'x': 'abc' is not a number
    >>> _ = open(path, "w").write("t;x\n0;1\n0.5;2\n1;3\n")
    >>> read_csv(path)
    Traceback (most recent call last):
    ...
    diagnosis.records.RecordError: ...run.csv line 1: the file seems to be separated by ';', but read_csv expects commas
    """
    from pathlib import Path

    path = Path(path)
    name = name or str(path)
    _check_size(path, name)
    if parser not in PARSERS:
        raise RecordError(f"{name}: parser must be one of {', '.join(map(repr, PARSERS))}, got {parser!r}")
    signals = (signals,) if isinstance(signals, str) else tuple(signals)  # one name, not its letters
    fast = None if parser == "cells" else _plain_record(path, name, signals, PARSERS[parser])
    if fast is not None:
        return fast
    rows = _csv_rows(path, name)
    header = _csv_header(rows[0], name)
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise RecordError(f"{name} line {line}: {len(row)} cells for {len(header)} columns"
                              + _separator_hint(row, ", as if"))
    wanted = [c for c in header if not signals or c == TIME or c in signals]
    data = rows[1:]
    columns = {}
    for column in wanted:
        index = header.index(column)
        columns[column] = _csv_column([row[index] for row in data], name, column)
    _warn_text_columns(header, wanted, data, name)
    t = columns[TIME]
    for i in np.flatnonzero(~np.isfinite(t)):
        raise RecordError(f"{name} line {i + 2}, column {TIME!r}: missing time")
    for i in np.flatnonzero(np.diff(t) <= 0):
        raise RecordError(f"{name} line {i + 3}, column {TIME!r}: t = {t[i + 1]!r} does not increase "
                          f"(line {i + 2} has t = {t[i]!r})")
    return as_record(columns, signals, name=name)


def _check_size(path, name: str) -> None:
    """Refuse a file larger than :data:`MAX_RECORD_BYTES` before reading it (a missing file is read_csv's to say)."""
    try:
        size = path.stat().st_size
    except OSError:
        return
    if size > MAX_RECORD_BYTES:
        raise RecordError(f"{name}: {size / 2**30:.2f} GiB, more than the {MAX_RECORD_BYTES / 2**30:g} GiB a CSV "
                          "record may hold (MAX_RECORD_BYTES): split it, or give a fleet a Parquet file")


#: read_csv's parsers of plain numbers, tried in this order before the cell-by-cell reading
PARSERS = {"auto": ("pyarrow", "numpy"), "pyarrow": ("pyarrow",), "numpy": ("numpy",), "cells": ()}


def _plain_record(path, name: str, signals: tuple, parsers: tuple) -> Record | None:
    """The record of a file of plain numbers, parsed by pyarrow or numpy (:mod:`diagnosis._csv_fast`); None for
    any file that needs the cell-by-cell reading, which names what is wrong (or reads what they cannot)."""
    from ._csv_fast import parse

    parsed = parse(path, MISSING_CELLS, _is_number_or_gap, parsers)
    if parsed is None:
        return None
    row, numbers = parsed
    try:
        header = _csv_header(row, name)
    except RecordError:
        return None
    wanted = [c for c in header if not signals or c == TIME or c in signals]
    columns = {c: numbers[header.index(c)] for c in wanted}
    if any(v is None for v in columns.values()) or any(s not in header for s in signals):
        return None
    # one NaN for every gap (a parser keeps the sign of "-nan"), in arrays of our own (pyarrow's are read-only)
    columns = {c: np.where(np.isnan(v), np.nan, v) for c, v in columns.items()}
    t = columns[TIME]
    with np.errstate(invalid="ignore"):
        plain = all(not np.isinf(v).any() and not (np.abs(v) > MAX_MAGNITUDE).any() for v in columns.values())
        if not (plain and np.isfinite(t).all() and (np.diff(t) > 0).all()):
            return None  # read_csv says which cell
    _warn_text([c for i, c in enumerate(header) if numbers[i] is None and c not in wanted], name, stacklevel=4)
    return as_record(columns, signals, name=name)


def _csv_rows(path, name: str) -> list[list[str]]:
    """The rows of a CSV file, trailing blank lines dropped; RecordError if unreadable or empty."""
    import csv

    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            rows = list(csv.reader(handle))
    except FileNotFoundError:
        raise RecordError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise RecordError(f"{name}: is a directory, not a CSV file") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise RecordError(f"{name}: cannot be read as CSV ({exc})") from None
    while rows and not any(cell.strip() for cell in rows[-1]):
        rows.pop()  # trailing blank lines
    if not rows:
        raise RecordError(f"{name}: the file is empty (expected a header row with a column {TIME!r})")
    return rows


def _csv_header(row: list[str], name: str) -> list[str]:
    """The column names: each named once, ``t`` among them, the file comma-separated."""
    hint = _separator_hint(row, ": the file seems to be")
    if hint:
        raise RecordError(f"{name} line 1{hint}")
    header = [cell.strip() for cell in row]
    seen = set()
    for column in header:
        if not column:
            raise RecordError(f"{name} line 1: a column has no name")
        if column in seen:
            raise RecordError(f"{name} line 1: column {column!r} appears twice")
        seen.add(column)
    if TIME not in header:
        hint = [c for c in header if c.lower() in ("time", "t", "t_s", "time_s", "seconds")]
        raise RecordError(f"{name} line 1: no time column {TIME!r} (columns: {header})"
                          + (f"; rename {hint[0]!r} to 't'" if hint else ""))
    return header


def _separator_hint(row: list[str], lead: str) -> str:
    """``"<lead> separated by ';', but read_csv expects commas"`` when a one-cell row holds another separator."""
    if len(row) == 1:
        for separator, label in _OTHER_SEPARATORS:
            if separator in row[0]:
                return f"{lead} separated by {label}, but read_csv expects commas"
    return ""


def _csv_column(cells: list[str], name: str, column: str) -> np.ndarray:
    """The numbers of one used column (its cells from line 2 on); RecordError naming the first bad cell."""
    # the common case, every cell a plain finite number, checked by one regular expression over the column
    # and converted by numpy; anything else (gaps, words, huge values) goes cell by cell for the exact message
    if _PLAIN_COLUMN.fullmatch("\n".join(cells)) is not None:
        values = np.array(cells, dtype=float)
        if np.all(np.abs(values) <= MAX_MAGNITUDE):
            return values
    return np.array([_csv_number(cell, name, line, column) for line, cell in enumerate(cells, start=2)],
                    dtype=float)


def _csv_number(cell: str, name: str, line: int, column: str) -> float:
    """The number in one cell of a used column: NaN for a gap, else a RecordError naming the cell."""
    text = cell.strip()
    if text in MISSING_CELLS:
        return np.nan
    where = f"{name} line {line}, column {column!r}: {text[:40]!r}"
    if CSV_NUMBER.fullmatch(text) is None:
        if _SPECIAL_NUMBER.fullmatch(text) is None:
            reason = " (digit separators such as '_' are not allowed)" if "_" in text else ""
            raise RecordError(f"{where} is not a number{reason}")
    value = float(text)
    if math.isnan(value):
        return np.nan
    if math.isinf(value):
        raise RecordError(f"{where} is infinite (leave the cell empty for a gap)")
    if abs(value) > MAX_MAGNITUDE:
        raise RecordError(f"{where} is larger in magnitude than {MAX_MAGNITUDE:g} (MAX_MAGNITUDE): the residuals "
                          "would overflow")
    return value


def _is_number_or_gap(cell: str) -> bool:
    text = cell.strip()
    return text in MISSING_CELLS or bool(CSV_NUMBER.fullmatch(text) or _SPECIAL_NUMBER.fullmatch(text))


def _warn_text_columns(header: list[str], wanted: list[str], rows: list[list[str]], name: str) -> None:
    """One RecordWarning naming the columns that are not read and hold text."""
    _warn_text([c for i, c in enumerate(header) if c not in wanted and not all(_is_number_or_gap(row[i])
                                                                                for row in rows)], name, stacklevel=4)


def _warn_text(text: list[str], name: str, stacklevel: int) -> None:
    """One RecordWarning naming the unused columns ``text`` that hold text (none: no warning)."""
    if text:
        listed = ", ".join(map(repr, text))
        verb = "is" if len(text) == 1 else "are"
        warnings.warn(f"{name}: column{'s' * (len(text) > 1)} {listed} {verb} not numeric and not among the "
                      f"signals read: ignored", RecordWarning, stacklevel=stacklevel)
