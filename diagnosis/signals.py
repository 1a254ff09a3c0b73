"""Recorded signals for residual evaluation: validation, derivatives, integrals.

A residual (analytical redundancy relation) of a bond-graph model is an
expression in measured and input signals ``x(t)``, their time derivatives and
integrals, from the start of the record, of known expressions.  This module
turns a user's record (a mapping or a pandas DataFrame with a time column
``t``) into clean float arrays (:func:`as_record`) and estimates the
derivatives (:func:`derivative`) and integrals (:func:`cumulative_integral`)
a residual needs, saying so when they cannot be known.

Sampling
--------
``t`` must be finite and strictly increasing, with at least 3 samples; it
need not be uniform.

* ``derivative(method="savgol")`` (the default) is a Savitzky-Golay filter:
  a polynomial of degree ``polyorder`` (default 3) fitted by least squares
  to a sliding window of ``window`` samples (default 11, see
  :func:`default_window`), differentiated at the window's centre.  Within
  half a window of either end of the record the polynomial fitted to the
  first (last) window is used (scipy's ``mode="interp"``), which is less
  accurate than the interior.  It needs uniform sampling (every step within
  a relative 1e-6 of the median step) and refuses an uneven grid with a
  :class:`RecordError` suggesting ``method="central"`` or
  :func:`diagnosis.uniform_grid.resample`, which puts a record on a uniform grid.
* ``derivative(method="central")`` uses :func:`numpy.gradient` with
  second-order differences in the interior and at the ends, second-order
  accurate on uneven grids too.  Order 2 applies it twice: exact for
  quadratics on any grid, second-order accurate in the interior where the
  steps vary smoothly, but only first order in the two samples at each end.
* ``derivative(method="exact", exact=values)`` takes a derivative the user
  knows (from a simulation, say), checked against the record.
* :func:`cumulative_integral` uses the trapezoidal rule, on any grid.

Gaps (NaN)
----------
NaN in a signal column marks a gap: missing data, not a value (``inf`` is
an error).  Nothing is interpolated across a gap and no estimate uses a NaN
sample; where an estimate would need one, the result is NaN.

* ``method="savgol"``: NaN wherever the window the value is fitted on
  holds a NaN: within half a window of a gap, and over the first (last)
  half window of the record if a gap is in its first (last) window.  A gap
  is missing data, not the end of the record, so no one-sided estimate is
  made next to it.  The filter runs on each finite run of samples
  separately, so every value that is not NaN equals the value the same
  record without the gap would give; runs shorter than the window are all
  NaN.
* ``method="central"``: NaN where the difference stencil touches a gap, one
  sample either side of it per order of differentiation.
* :func:`cumulative_integral`: the integral is unknown once it has crossed a
  gap, so it is NaN from the first NaN sample on and a
  :class:`RecordWarning` names the signal and the time.  It is not restarted
  after the gap: a residual integrating from the start of the record would
  be silently offset.

Examples
--------
>>> import numpy as np
>>> t = np.linspace(0.0, 2.0, 201)
>>> record = as_record({"t": t, "x": np.sin(t)}, name="demo")
>>> record
Record('demo', 201 samples, t in [0, 2], signals ['x'])
>>> v = derivative(record, "x")
>>> float(np.max(np.abs(v - np.cos(t)))) < 1e-4
True
"""

from __future__ import annotations

import math
import numbers
import re
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import cumulative_trapezoid
from scipy.signal import savgol_filter

from bondgraph.errors import PHMError, PHMWarning

__all__ = [
    "MAX_MAGNITUDE", "Record", "RecordError", "RecordWarning", "add_noise", "MAX_RECORD_BYTES", "as_record",
    "check_signals", "cumulative_integral", "read_csv", "central_derivative", "check_savgol_settings",
    "default_window", "derivative", "gaps",
]

TIME = "t"
METHODS = ("savgol", "central", "exact")
UNIFORM_RTOL = 1e-6
#: The largest magnitude of a recorded value.  A residual multiplies signals by each other (squares
#: them, in a quadratic law) and by parameters, and divides them by the sampling step to estimate
#: derivatives: 1e150 squared is 1e300, still below the largest double (1.8e308), where 1e200 squared
#: is infinite and a value near 1e308 overflows in a single difference, leaving every sample it
#: touches silently undecided.  No physical signal in SI units comes near it.
MAX_MAGNITUDE = 1e150
#: The largest CSV record read, in bytes.  Parsing takes several times the file's size in memory (a
#: 2 GB file, sparse or not, grew past 3 GB): a larger record is refused before it is read.  A
#: fleet's large records belong in a Parquet file, read by asset.
MAX_RECORD_BYTES = 1 << 30


class RecordError(PHMError, ValueError):
    """Bad recorded data or estimator settings; the message names the column or signal."""


class RecordWarning(PHMWarning):
    """A value computed from a record is unknown (NaN) because of a gap in the data."""


# ---------------------------------------------------------------------------
# The record


@dataclass(frozen=True, eq=False)
class Record:
    """Validated recorded data: a time vector and one float array per signal.

    Build it with :func:`as_record`, which checks the data and copies it.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Finite, strictly increasing sample times.
    columns : dict
        Signal name -> float array of shape (n,); NaN marks a gap.
    name : str
        Used in messages.

    Examples
    --------
    >>> record = as_record({"t": [0.0, 0.5, 1.0, 1.5], "x": [1, 2, float("nan"), 4]})
    >>> record.dt, record.is_uniform
    (0.5, True)
    >>> record.gaps("x")
    [(1.0, 1.0)]
    >>> record["x"].tolist()
    [1.0, 2.0, nan, 4.0]
    """

    t: np.ndarray
    columns: dict
    name: str = "record"

    @property
    def signals(self) -> tuple[str, ...]:
        """The signal names, in column order."""
        return tuple(self.columns)

    @property
    def dt(self) -> float:
        """The median sampling step."""
        return float(np.median(np.diff(self.t)))

    @property
    def is_uniform(self) -> bool:
        """Whether every step is within a relative 1e-6 of the median step."""
        return _step_deviation(self.t) < UNIFORM_RTOL

    def gaps(self, signal: str) -> list[tuple[float, float]]:
        """The gaps of a signal as ``(t_start, t_end)``: times of the first and last NaN of each run."""
        x = self[signal]
        return [(float(self.t[a]), float(self.t[b - 1])) for a, b in _runs(np.isnan(x))]

    def between(self, start: float = -np.inf, end: float = np.inf) -> "Record":
        """The samples with ``start <= t <= end``, e.g. a fault-free stretch to calibrate a noise margin.

        >>> record = as_record({"t": [0.0, 0.5, 1.0, 1.5], "x": [1.0, 2.0, 3.0, 4.0]})
        >>> record.between(end=0.5)["x"].tolist(), record.between(1.0).t.tolist()
        ([1.0, 2.0], [1.0, 1.5])
        """
        keep = (self.t >= start) & (self.t <= end)
        if not keep.any():
            raise RecordError(f"{self.name}: no sample with {start:g} <= t <= {end:g} "
                              f"(the record spans [{self.t[0]:g}, {self.t[-1]:g}])")
        return Record(self.t[keep], {k: v[keep] for k, v in self.columns.items()}, self.name)

    def __getitem__(self, name: str) -> np.ndarray:
        """The time vector (``"t"``) or a signal by name."""
        if name == TIME:
            return self.t
        if name not in self.columns:
            raise RecordError(f"{self.name}: no signal {name!r}; signals: {list(self.columns)}")
        return self.columns[name]

    def __contains__(self, name: object) -> bool:
        return name == TIME or name in self.columns

    def __len__(self) -> int:
        return int(self.t.size)

    def __repr__(self) -> str:
        span = f"[{self.t[0]:g}, {self.t[-1]:g}]"
        return f"Record({self.name!r}, {len(self)} samples, t in {span}, signals {list(self.columns)})"


def as_record(data: object, signals: Iterable[str] = (), *, name: str = "record", min_samples: int = 3) -> Record:
    """Check recorded data and copy it into a :class:`Record`.

    Parameters
    ----------
    data : mapping or DataFrame
        Column name -> sequence of numbers, with a time column ``t``.  A
        pandas DataFrame (anything with ``.columns`` and ``[]``) works too;
        the data is copied, never modified.
    signals : iterable of str, optional
        The signal columns to keep.  Default: every column but ``t``.  Other
        columns are neither checked nor kept.
    name : str, optional
        The record's name, used in messages.
    min_samples : int, optional
        The fewest samples accepted: 3 for a record, 0 for a micro-batch of a stream
        (:class:`diagnosis.streaming.StreamingEvaluation` checks its batches here).

    Returns
    -------
    Record

    Raises
    ------
    RecordError
        Naming the column: ``t`` or a signal column missing (all missing
        ones are listed, with the columns present), a non-numeric cell
        (first bad row and value; booleans count as non-numeric), columns of
        different lengths, fewer than 3 samples, NaN or inf in ``t``, ``t``
        not strictly increasing (first offending index and times), inf in a
        signal, a value larger in magnitude than :data:`MAX_MAGNITUDE`.  NaN in
        a signal is a gap and is allowed.

    Examples
    --------
    >>> record = as_record({"t": [0, 1, 2], "u": [0.5, 1.0, 1.5], "note": ["a", "b", "c"]}, ["u"])
    >>> record
    Record('record', 3 samples, t in [0, 2], signals ['u'])
    >>> as_record({"t": [0, 1, 1], "u": [1, 2, 3]})
    Traceback (most recent call last):
    ...
    diagnosis.signals.RecordError: record: column 't' is not strictly increasing: t[2] = 1.0 follows t[1] = 1.0
    """
    if isinstance(data, Record):
        data = {TIME: data.t, **data.columns}
    table = _table(data, name)
    wanted = _signal_names(table, signals, name)
    arrays = {col: _float_column(table[col], col, name) for col in (TIME, *wanted)}
    _check_lengths(arrays, name)
    t = arrays.pop(TIME)
    _check_time(t, name, min_samples)
    _check_magnitude(t, TIME, t, name)
    for col, x in arrays.items():
        _check_no_inf(x, col, t, name)
        _check_magnitude(x, col, t, name)
    return Record(t=t, columns=arrays, name=name)


MISSING_CELLS = frozenset({"", "nan", "NaN", "NAN", "NA", "N/A", "null"})
#: A number in a CSV cell: decimal digits with an optional sign, point and exponent.  Python's
#: ``float()`` also takes ``1_000``, other scripts' digits and surrounding words; a data file should not.
CSV_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_PLAIN_COLUMN = re.compile(f"(?:{CSV_NUMBER.pattern})(?:\n(?:{CSV_NUMBER.pattern}))*")
#: Words ``float()`` reads as infinite or NaN, with an optional sign, in any case.
_SPECIAL_NUMBER = re.compile(r"[+-]?(?:inf|infinity|nan)", re.IGNORECASE)
#: Separators a CSV file written with another convention uses instead of the comma.
_OTHER_SEPARATORS = ((";", "';'"), ("\t", "tabs"), ("|", "'|'"))


def has_column(record, name: str) -> bool:
    """Whether ``record`` (a Record, a mapping or a DataFrame) has a column ``name``, before any validation.

    >>> has_column({"t": [0.0], "x": [1.0]}, "x"), has_column(None, "x")
    (True, False)
    """
    columns = getattr(record, "columns", record)
    try:
        return name in columns
    except TypeError:
        return False


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
    diagnosis.signals.RecordError: ...run.csv line 3, column 'x': 'abc' is not a number
    >>> _ = open(path, "w").write("t;x\n0;1\n0.5;2\n1;3\n")
    >>> read_csv(path)
    Traceback (most recent call last):
    ...
    diagnosis.signals.RecordError: ...run.csv line 1: the file seems to be separated by ';', but read_csv expects commas
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


def gaps(record: Record, signals: Iterable[str] | None = None) -> list[tuple[str, float, float, int]]:
    """Every run of NaN in the record's signals: ``(signal, t_first, t_last, samples)``, by signal.

    >>> gaps(as_record({"t": [0, 1, 2, 3], "x": [1, float("nan"), float("nan"), 4]}))
    [('x', 1.0, 2.0, 2)]
    """
    out = []
    for signal in (record.signals if signals is None else signals):
        missing = np.isnan(record[signal])
        for start, stop in _runs(missing):
            out.append((signal, float(record.t[start]), float(record.t[stop - 1]), stop - start))
    return out


def check_signals(record: Record, signals: Iterable[str], sensors: Iterable[str] = (), *, name: str | None = None
                  ) -> None:
    """Refuse a record whose signals cannot tell a fault: a column without a value, a sensor that never changes.

    A dead sensor (every cell empty) leaves every residual that reads it undecided, and a stuck one
    (the same value throughout) makes them follow the model as if nothing moved: either way the
    record raises no alarm and looks healthy.  ``signals``: the columns the ARRs read; ``sensors``:
    those that are measurements (an input such as a set voltage may well be constant).

    >>> record = as_record({"t": [0.0, 1.0, 2.0], "V": [5.0, 5.0, 5.0], "i": [0.2, 0.2, 0.2]})
    >>> check_signals(record, ["V", "i"], sensors=["V"])
    Traceback (most recent call last):
    ...
    diagnosis.signals.RecordError: record: sensor column 'V' never changes (every value is 5): a stuck ...
    >>> check_signals(record, ["V", "i"])   # constant, but no sensor among them: an input may be
    """
    name = name or record.name
    sensors = set(sensors)
    for signal in signals:
        values = record[signal]
        finite = values[np.isfinite(values)]
        if finite.size == 0:
            raise RecordError(f"{name}: column {signal!r} has no value (every cell is empty or NaN): a dead sensor "
                              "would hide any fault")
        if signal in sensors and finite.size > 1 and np.all(finite == finite[0]):
            raise RecordError(f"{name}: sensor column {signal!r} never changes (every value is {finite[0]:g}): a "
                              "stuck sensor would hide any fault")


def _table(data: object, name: str) -> dict:
    """Column name -> raw column, from a mapping or a duck-typed DataFrame."""
    if isinstance(data, Mapping):
        return {str(k): v for k, v in data.items()}
    if hasattr(data, "columns") and hasattr(data, "__getitem__"):
        return {str(k): _column_values(data[k]) for k in data.columns}
    raise RecordError(f"{name}: expected a mapping or a DataFrame of columns, got {type(data).__name__}")


def _column_values(column: object) -> object:
    """A DataFrame column as an array, keeping each cell's type so bad cells can be reported."""
    to_numpy = getattr(column, "to_numpy", None)
    return to_numpy() if callable(to_numpy) else column


def _signal_names(table: dict, signals: Iterable[str], name: str) -> list[str]:
    """The requested signals (or all but ``t``), after checking every column exists."""
    signals = (signals,) if isinstance(signals, str) else tuple(signals)  # one name, not its letters
    wanted = list(dict.fromkeys(signals)) or [c for c in table if c != TIME]
    if TIME in signals:
        raise RecordError(f"{name}: {TIME!r} is the time column, not a signal")
    missing = [c for c in (TIME, *wanted) if c not in table]
    if missing:
        raise RecordError(f"{name}: missing column(s) {missing}; columns present: {list(table)}")
    return wanted


def _float_column(values: object, column: str, name: str = "record") -> np.ndarray:
    """A 1-D float copy of a column; RecordError at the first non-numeric cell."""
    try:
        arr = np.asarray(values)
    except (ValueError, TypeError):  # ragged nesting: locate the bad cell below
        arr = np.array(list(values), dtype=object)
    if arr.ndim != 1:
        raise RecordError(f"{name}: column {column!r} must be one-dimensional, got shape {arr.shape}")
    if arr.dtype.kind in "iuf" and isinstance(values, np.ndarray):
        return arr.astype(float)  # always a copy
    # numpy turns [1.0, True] into floats and [1, "a"] into text: judge the cells as given
    keep = arr.dtype == object or isinstance(values, np.ndarray)
    cells = arr if keep else np.array(values, dtype=object)
    for row, cell in enumerate(cells):
        if isinstance(cell, (bool, np.bool_)) or not isinstance(cell, numbers.Real):
            value = cell.item() if isinstance(cell, np.generic) else cell  # True, not np.True_
            raise RecordError(f"{name}: column {column!r} has a non-numeric value {value!r} at row {row}"
                              " (use float('nan') for a gap)")
    return cells.astype(float)


def _check_lengths(arrays: dict, name: str) -> None:
    n = arrays[TIME].size
    wrong = [f"{col!r} has {x.size}" for col, x in arrays.items() if x.size != n]
    if wrong:
        raise RecordError(f"{name}: columns of different lengths: {TIME!r} has {n} samples, " + ", ".join(wrong))


def _check_time(t: np.ndarray, name: str, min_samples: int = 3) -> None:
    if t.size < min_samples:
        raise RecordError(f"{name}: column {TIME!r} has {t.size} samples; at least {min_samples} are needed")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        i = int(bad[0])
        raise RecordError(f"{name}: column {TIME!r} has a non-finite value {t[i]} at row {i}")
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise RecordError(f"{name}: column {TIME!r} is not strictly increasing: "
                          f"t[{i}] = {float(t[i])!r} follows t[{i - 1}] = {float(t[i - 1])!r}")


def _check_magnitude(x: np.ndarray, column: str, t: np.ndarray, name: str) -> None:
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero(np.abs(x) > MAX_MAGNITUDE)
    if bad.size:
        i = int(bad[0])
        raise RecordError(f"{name}: column {column!r} has a value {x[i]:g} at row {i} (t = {float(t[i])!r}) larger "
                          f"in magnitude than {MAX_MAGNITUDE:g} (MAX_MAGNITUDE): the residuals would overflow")


def _check_no_inf(x: np.ndarray, column: str, t: np.ndarray, name: str) -> None:
    bad = np.flatnonzero(np.isinf(x))
    if bad.size:
        i = int(bad[0])
        raise RecordError(f"{name}: column {column!r} has an infinite value {x[i]} at row {i} "
                          f"(t = {float(t[i])!r}); use NaN for a gap")


# ---------------------------------------------------------------------------
# Derivatives and integrals


def default_window(polyorder: int = 3) -> int:
    """The default Savitzky-Golay window: 11 samples, odd and at least ``polyorder + 2``.

    With the default cubic fit, 11 samples differentiate ``sin(t)`` sampled
    at ``dt = 0.01`` to about 2e-8 in the interior and 6e-6 at the ends, and
    average out much of the measurement noise.

    Examples
    --------
    >>> default_window(), default_window(10)
    (11, 13)
    """
    window = max(11, polyorder + 2)
    return window + 1 - window % 2


def derivative(
    record_or_t: Record | ArrayLike,
    x: str | ArrayLike,
    order: int = 1,
    method: str = "savgol",
    *,
    window: int | None = None,
    polyorder: int = 3,
    name: str = "signal",
    exact: ArrayLike | None = None,
) -> np.ndarray:
    """Time derivative of a sampled signal.

    Parameters
    ----------
    record_or_t : Record or array_like
        The record, or the sample times.
    x : str or array_like
        A signal of the record by name, or its samples.
    order : int, optional
        Order of the derivative (1 or more).
    method : {"savgol", "central", "exact"}, optional
        ``"savgol"``: Savitzky-Golay filter, uniform sampling only.
        ``"central"``: :func:`numpy.gradient`, second order, any grid.
        ``"exact"``: return ``exact``, a derivative the caller knows.
    window : int, optional
        Savitzky-Golay window, odd, in samples; default :func:`default_window`.
    polyorder : int, optional
        Degree of the Savitzky-Golay polynomial, at least ``order``.
    name : str, optional
        Signal name for messages when ``x`` is an array.
    exact : array_like, optional
        The known derivative, for ``method="exact"``.

    Returns
    -------
    ndarray
        The derivative at every sample, NaN where a gap makes it unknown
        (see the module docstring).

    Raises
    ------
    RecordError
        Bad data; ``"savgol"`` on uneven sampling or on a record shorter than
        the window; bad settings.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 21)
    >>> bool(np.allclose(derivative(t, t**3, order=2), 6 * t))
    True
    >>> x = t.copy(); x[10] = np.nan
    >>> d = derivative(t, x, method="central")
    >>> np.round(d[7:14], 6).tolist()
    [1.0, 1.0, nan, nan, nan, 1.0, 1.0]
    """
    record, values, name = _resolve(record_or_t, x, name)
    _check_order(order, name)
    if method == "exact":
        return _exact(record, exact, name)
    if exact is not None:
        raise RecordError(f"signal {name!r}: exact= is only used with method='exact', not {method!r}")
    if method == "central":
        return central_derivative(record.t, values, order)
    if method == "savgol":
        window = default_window(polyorder) if window is None else window
        _check_savgol(record, name, order, window, polyorder)
        return _savgol(values, record.dt, order, window, polyorder)
    raise RecordError(f"signal {name!r}: unknown method {method!r}; choose one of {list(METHODS)}")


def cumulative_integral(record_or_t: Record | ArrayLike, x: str | ArrayLike, *, name: str = "signal") -> np.ndarray:
    """Integral of a sampled signal from the start of the record (trapezoidal rule).

    Parameters
    ----------
    record_or_t : Record or array_like
        The record, or the sample times (uneven steps are fine).
    x : str or array_like
        A signal of the record by name, or its samples.
    name : str, optional
        Signal name for messages when ``x`` is an array.

    Returns
    -------
    ndarray
        Starts at 0; NaN from the first NaN sample on.

    Warns
    -----
    RecordWarning
        When the signal has a gap, naming the signal and the time.

    Examples
    --------
    >>> cumulative_integral([0.0, 1.0, 3.0], [0.0, 2.0, 2.0]).tolist()
    [0.0, 1.0, 5.0]
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     y = cumulative_integral([0.0, 1.0, 2.0, 3.0], [1.0, 1.0, float("nan"), 1.0], name="i")
    >>> y.tolist()
    [0.0, 1.0, nan, nan]
    >>> print(caught[0].message)
    integral of 'i' is unknown from t = 2.0 on: the signal has a gap (NaN) there
    """
    record, values, name = _resolve(record_or_t, x, name)
    out = cumulative_trapezoid(values, record.t, initial=0.0)
    gap = np.flatnonzero(np.isnan(values))
    if gap.size:
        first = int(gap[0])
        out[first:] = np.nan  # beyond a gap the integral's offset is unknown
        warnings.warn(f"integral of {name!r} is unknown from t = {float(record.t[first])!r} on: "
                      "the signal has a gap (NaN) there", RecordWarning, stacklevel=2)
    return out


def _resolve(record_or_t: object, x: object, name: str) -> tuple[Record, np.ndarray, str]:
    """The record, the checked signal samples and the signal's name."""
    if not isinstance(record_or_t, Record):
        if isinstance(x, str):
            raise RecordError(f"signal {x!r} given by name, but no Record to look it up in")
        record = as_record({TIME: record_or_t, name: x}, [name])
        return record, record[name], name
    if isinstance(x, str):
        return record_or_t, record_or_t[x], x
    return record_or_t, _checked_signal(record_or_t, x, name), name


def _checked_signal(record: Record, x: object, name: str) -> np.ndarray:
    """Samples of a signal given as an array, checked against the record's time vector."""
    values = _float_column(x, name, record.name)
    if values.size != record.t.size:
        raise RecordError(f"{record.name}: signal {name!r} has {values.size} samples, "
                          f"{TIME!r} has {record.t.size}")
    _check_no_inf(values, name, record.t, record.name)
    _check_magnitude(values, name, record.t, record.name)
    return values


def _check_order(order: object, name: str) -> None:
    if isinstance(order, bool) or not isinstance(order, numbers.Integral) or order < 1:
        raise RecordError(f"signal {name!r}: derivative order must be an integer >= 1, got {order!r}")


def _exact(record: Record, exact: object, name: str) -> np.ndarray:
    if exact is None:
        raise RecordError(f"signal {name!r}: method='exact' needs the derivative as exact=")
    return _checked_signal(record, exact, f"exact derivative of {name}")


def central_derivative(t: np.ndarray, x: np.ndarray, order: int) -> np.ndarray:
    """The ``order``-th derivative by second-order differences (:func:`numpy.gradient`, applied ``order`` times).

    The computation behind ``derivative(method="central")``, without its checks: ``t`` strictly
    increasing with at least 3 samples, ``x`` of the same length.  A value depends on the ``order``
    samples either side of it (one-sided stencils at the ends), so a stream can evaluate it on its
    last samples alone.

    >>> t = np.array([0.0, 1.0, 3.0, 4.0])
    >>> np.round(central_derivative(t, t**2, 1), 12).tolist()   # exact for quadratics, on any grid
    [0.0, 2.0, 6.0, 8.0]
    """
    # np.gradient is local, so NaN spreads only as far as its stencil reaches
    d = x
    for _ in range(order):
        gap = np.isnan(d)
        d = np.gradient(d, t, edge_order=2)
        # on exactly equal steps numpy's formula gives the middle sample weight 0, skipping a gap's own
        # sample; on any other grid it is NaN there: the same record must not depend on the last bits of t
        d[gap] = np.nan
    return d


def check_savgol_settings(name: str, order: int, window: object, polyorder: object) -> None:
    """Raise a :class:`RecordError` naming the signal unless ``window`` and ``polyorder`` suit a Savitzky-Golay
    derivative of this order: ``polyorder`` an integer >= ``order``, ``window`` odd and > ``polyorder``.

    >>> check_savgol_settings("i", 1, window=11, polyorder=3)
    >>> check_savgol_settings("i", 1, window=10, polyorder=3)
    Traceback (most recent call last):
    ...
    diagnosis.signals.RecordError: signal 'i': window must be an odd number of samples > polyorder 3, got 10
    """
    if isinstance(polyorder, bool) or not isinstance(polyorder, numbers.Integral) or polyorder < order:
        raise RecordError(f"signal {name!r}: polyorder must be an integer >= the derivative order {order}, "
                          f"got {polyorder!r}")
    if isinstance(window, bool) or not isinstance(window, numbers.Integral) or window % 2 == 0 \
            or window <= polyorder:
        raise RecordError(f"signal {name!r}: window must be an odd number of samples > polyorder {polyorder}, "
                          f"got {window!r}")


def _check_savgol(record: Record, name: str, order: int, window: object, polyorder: object) -> None:
    check_savgol_settings(name, order, window, polyorder)
    if not record.is_uniform:
        raise RecordError(f"signal {name!r}: method='savgol' needs uniform sampling, but steps deviate from "
                          f"the median step {record.dt:g} by up to {_step_deviation(record.t):.2%}; "
                          "use method='central', which handles uneven steps, or put the record on a uniform grid "
                          "first with diagnosis.resample(record) (bgphm: --resample)")
    if len(record) < window:
        raise RecordError(f"signal {name!r} has {len(record)} samples, fewer than the Savitzky-Golay window "
                          f"of {window}; pass a smaller odd window= or use method='central'")


def _savgol(x: np.ndarray, dt: float, order: int, window: int, polyorder: int) -> np.ndarray:
    out = np.full(x.size, np.nan)
    half = window // 2
    for start, stop in _runs(~np.isnan(x)):
        if stop - start < window:
            continue
        d = savgol_filter(x[start:stop], window, polyorder, deriv=order, delta=dt, mode="interp")
        # next to a gap only one side has data: no one-sided estimate there
        lo = start + (half if start > 0 else 0)
        hi = stop - (half if stop < x.size else 0)
        out[lo:hi] = d[lo - start:hi - start]
    return out


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of True in a boolean array."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def _step_deviation(t: np.ndarray) -> float:
    steps = np.diff(t)
    dt = np.median(steps)
    return float(np.max(np.abs(steps - dt)) / dt)


# ---------------------------------------------------------------------------
# Test data


def add_noise(record: Record, std: Mapping[str, float], seed: int) -> Record:
    """A copy of the record with Gaussian noise added to some signals.

    Parameters
    ----------
    record : Record
    std : mapping
        Signal name -> standard deviation (finite, >= 0).
    seed : int
        Seed of :func:`numpy.random.default_rng`; the same seed gives the
        same noise.  Signals draw in record column order, whatever the order
        of ``std``.

    Returns
    -------
    Record
        A new record; the given one is untouched.  Gaps stay NaN.

    Examples
    --------
    >>> record = as_record({"t": [0, 1, 2, 3], "x": [0, 0, 0, 0], "y": [1, 1, 1, 1]})
    >>> noisy = add_noise(record, {"x": 0.1}, seed=1)
    >>> noisy["y"].tolist(), bool(np.all(noisy["x"] != 0))
    ([1.0, 1.0, 1.0, 1.0], True)
    """
    if not isinstance(record, Record):
        record = as_record(record)
    unknown = [s for s in std if s not in record.columns]
    if unknown:
        raise RecordError(f"{record.name}: no signal(s) {unknown} to add noise to; signals: {list(record.columns)}")
    rng = np.random.default_rng(seed)
    columns = {}
    for signal, x in record.columns.items():
        columns[signal] = x.copy()
        if signal in std:
            columns[signal] += _checked_std(std[signal], signal) * rng.standard_normal(x.size)
    return Record(t=record.t.copy(), columns=columns, name=record.name)


def _checked_std(value: object, signal: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not np.isfinite(value) or value < 0:
        raise RecordError(f"noise std of signal {signal!r} must be a finite number >= 0, got {value!r}")
    return float(value)
