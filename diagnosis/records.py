"""Recorded signals: a record of a time column and signal columns, checked, with its gaps and noise.

A residual of a bond-graph model reads measured and input signals ``x(t)``.  :func:`as_record` turns
a user's record (a mapping or a pandas DataFrame with a time column ``t``) into clean float arrays
(:class:`Record`): ``t`` finite and strictly increasing with at least 3 samples, the columns finite
numbers of one length, NaN marking a gap (missing data, never a value).  :func:`gaps` lists the gaps,
:func:`check_signals` refuses a column with no value or a stuck sensor, and :func:`add_noise` and
:func:`add_sensor_faults` make a copy whose sensors are noisy or faulty (a bias, a drift, a wrong gain from
an onset: :class:`SensorFault`), for tests, demos and ``bgphm simulate``.  Reading records from CSV files
is :mod:`diagnosis.csv_reading`; derivatives and integrals of a record's signals are :mod:`diagnosis.derivatives`.

>>> import numpy as np
>>> record = as_record({"t": np.linspace(0.0, 2.0, 201), "x": np.zeros(201)}, name="demo")
>>> record
Record('demo', 201 samples, t in [0, 2], signals ['x'])
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from bondgraph.errors import PHMError, PHMWarning


__all__ = [
    "MAX_MAGNITUDE", "Record", "RecordError", "RecordWarning", "SENSOR_FAULTS", "SensorFault", "TIME", "UNIFORM_RTOL",
    "add_noise", "add_sensor_faults", "as_record", "check_magnitude", "check_no_inf", "check_signals", "float_column",
    "gaps", "has_column", "runs", "step_deviation",
]


TIME = "t"


UNIFORM_RTOL = 1e-6


#: The largest magnitude of a recorded value.  A residual multiplies signals by each other (squares
#: them, in a quadratic law) and by parameters, and divides them by the sampling step to estimate
#: derivatives: 1e150 squared is 1e300, still below the largest double (1.8e308), where 1e200 squared
#: is infinite and a value near 1e308 overflows in a single difference, leaving every sample it
#: touches silently undecided.  No physical signal in SI units comes near it.
MAX_MAGNITUDE = 1e150


class RecordError(PHMError, ValueError):
    """Bad recorded data or estimator settings; the message names the column or signal."""


class RecordWarning(PHMWarning):
    """A value computed from a record is unknown (NaN) because of a gap in the data."""


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
        return step_deviation(self.t) < UNIFORM_RTOL

    def gaps(self, signal: str) -> list[tuple[float, float]]:
        """The gaps of a signal as ``(t_start, t_end)``: times of the first and last NaN of each run."""
        x = self[signal]
        return [(float(self.t[a]), float(self.t[b - 1])) for a, b in runs(np.isnan(x))]

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
    diagnosis.records.RecordError: record: column 't' is not strictly increasing: t[2] = 1.0 follows t[1] = 1.0
    """
    if isinstance(data, Record):
        data = {TIME: data.t, **data.columns}
    table = _table(data, name)
    wanted = _signal_names(table, signals, name)
    arrays = {col: float_column(table[col], col, name) for col in (TIME, *wanted)}
    _check_lengths(arrays, name)
    t = arrays.pop(TIME)
    _check_time(t, name, min_samples)
    check_magnitude(t, TIME, t, name)
    for col, x in arrays.items():
        check_no_inf(x, col, t, name)
        check_magnitude(x, col, t, name)
    return Record(t=t, columns=arrays, name=name)


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


def gaps(record: Record, signals: Iterable[str] | None = None) -> list[tuple[str, float, float, int]]:
    """Every run of NaN in the record's signals: ``(signal, t_first, t_last, samples)``, by signal.

    >>> gaps(as_record({"t": [0, 1, 2, 3], "x": [1, float("nan"), float("nan"), 4]}))
    [('x', 1.0, 2.0, 2)]
    """
    out = []
    for signal in (record.signals if signals is None else signals):
        missing = np.isnan(record[signal])
        for start, stop in runs(missing):
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
    diagnosis.records.RecordError: record: sensor column 'V' never changes (every value is 5): a stuck ...
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


def float_column(values: object, column: str, name: str = "record") -> np.ndarray:
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


def check_magnitude(x: np.ndarray, column: str, t: np.ndarray, name: str) -> None:
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero(np.abs(x) > MAX_MAGNITUDE)
    if bad.size:
        i = int(bad[0])
        raise RecordError(f"{name}: column {column!r} has a value {x[i]:g} at row {i} (t = {float(t[i])!r}) larger "
                          f"in magnitude than {MAX_MAGNITUDE:g} (MAX_MAGNITUDE): the residuals would overflow")


def check_no_inf(x: np.ndarray, column: str, t: np.ndarray, name: str) -> None:
    bad = np.flatnonzero(np.isinf(x))
    if bad.size:
        i = int(bad[0])
        raise RecordError(f"{name}: column {column!r} has an infinite value {x[i]} at row {i} "
                          f"(t = {float(t[i])!r}); use NaN for a gap")


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of True in a boolean array."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def step_deviation(t: np.ndarray) -> float:
    steps = np.diff(t)
    dt = np.median(steps)
    return float(np.max(np.abs(steps - dt)) / dt)


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


#: The faults of a sensor :class:`SensorFault` describes.
SENSOR_FAULTS = ("bias", "drift", "gain")


@dataclass(frozen=True)
class SensorFault:
    """A fault of the sensor of ``signal`` from ``onset`` (s) on.  For the true value ``x`` it reads

    * ``"bias"``: ``x + size`` (an offset in the signal's unit: a zero shift, a slipped code disc);
    * ``"drift"``: ``x + size (t - onset)`` (an offset growing by ``size`` a second: an ageing transducer);
    * ``"gain"``: ``size x`` (a wrong gain: 1.05 reads 5 % high, 0 a dead sensor that reads 0);

    and ``x`` before the onset.  :func:`add_sensor_faults` applies faults to a record.

    Raises
    ------
    RecordError
        For an unknown kind or a size or onset that is not a finite number, naming the signal.

    Examples
    --------
    >>> fault = SensorFault("omega", "drift", 0.5, onset=2.0)
    >>> fault.reading(np.array([0.0, 2.0, 4.0]), np.array([100.0, 100.0, 100.0])).tolist()
    [100.0, 100.0, 101.0]
    """

    signal: str
    kind: str
    size: float
    onset: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in SENSOR_FAULTS:
            raise RecordError(f"sensor {self.signal!r}: unknown fault {self.kind!r} (expected one of "
                              f"{', '.join(SENSOR_FAULTS)})")
        for what in ("size", "onset"):
            value = getattr(self, what)
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not np.isfinite(value):
                raise RecordError(f"sensor {self.signal!r}: the {what} of its {self.kind} must be a finite number, "
                                  f"got {value!r}")

    def reading(self, t: np.ndarray, x: np.ndarray) -> np.ndarray:
        """What the faulty sensor reads at the times ``t`` of the true values ``x`` (a new array)."""
        t, x = np.asarray(t, float), np.asarray(x, float)
        after = t >= self.onset
        if self.kind == "gain":
            return np.where(after, self.size * x, x)
        offset = self.size if self.kind == "bias" else self.size * (t - self.onset)
        return np.where(after, x + offset, x)


def add_sensor_faults(record: Record, faults: Iterable[SensorFault]) -> Record:
    """A copy of the record whose sensors read through the given faults (:class:`SensorFault`).

    Several faults of one sensor add up: its gains act on the true value first, then its biases and
    drifts add their offsets, so that a bias of 2 and a gain of 1.1 read ``1.1 x + 2``.  Noise comes
    after, from :func:`add_noise`: ``add_noise(add_sensor_faults(record, faults), std, seed)`` is a
    sensor that reads ``gain x + offsets + noise``, its noise the same draws as without the faults.

    Parameters
    ----------
    record : Record
        The true signals (any mapping :func:`as_record` takes).
    faults : iterable of SensorFault

    Returns
    -------
    Record
        A new record; the given one is untouched.  Gaps stay NaN.

    Raises
    ------
    RecordError
        For a fault of a signal the record does not hold, naming it and the record's signals.

    Examples
    --------
    >>> record = as_record({"t": [0.0, 1.0, 2.0, 3.0], "x": [10.0, 10.0, 10.0, 10.0]})
    >>> faulty = add_sensor_faults(record, [SensorFault("x", "bias", 2.0, onset=1.0),
    ...                                     SensorFault("x", "gain", 1.1, onset=2.0)])
    >>> faulty["x"].tolist()
    [10.0, 12.0, 13.0, 13.0]
    """
    if not isinstance(record, Record):
        record = as_record(record)
    faults = list(faults)
    unknown = [f.signal for f in faults if f.signal not in record.columns]
    if unknown:
        raise RecordError(f"{record.name}: no signal(s) {unknown} for a sensor fault; signals: {list(record.columns)}")
    columns = {signal: x.copy() for signal, x in record.columns.items()}
    # the gains scale the true value; the offsets then add to the scaled reading
    for fault in sorted(faults, key=lambda f: f.kind != "gain"):
        columns[fault.signal] = fault.reading(record.t, columns[fault.signal])
    return Record(t=record.t.copy(), columns=columns, name=record.name)
