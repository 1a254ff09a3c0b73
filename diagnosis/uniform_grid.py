"""A record put on a uniform time grid, for the estimators that need one.

The Savitzky-Golay derivative (the default of :func:`diagnosis.evaluate`) needs uniform sampling; a
logger with jitter or dropped samples gives an uneven grid.  Either estimate derivatives with
``method="central"``, which takes any grid, or resample the record first with :func:`resample`:
linear interpolation between neighbouring samples, never across a gap (NaN stays NaN where a grid
time falls next to a missing sample), with a :class:`~diagnosis.records.RecordWarning` when the
record has steps much longer than the new one (the values there are straight lines, not data).
"""

from __future__ import annotations

import math
import numbers
import warnings

import numpy as np

from bondgraph.simulation import MAX_SAMPLES

from .records import Record, RecordError, RecordWarning, TIME, as_record

__all__ = ["RESAMPLE_METHODS", "resample"]

#: The interpolation methods of :func:`resample`.
RESAMPLE_METHODS = ("linear",)


def resample(record: Record | object, step: float | None = None, *, method: str = "linear") -> Record:
    """The record on a uniform grid from its first time, by linear interpolation within runs of data.

    Parameters
    ----------
    record : Record, mapping or DataFrame
        Column ``t`` and the signals (see :func:`~diagnosis.records.as_record`).
    step : float, optional
        The new sampling step (s); default the record's median step.  The grid is
        ``t0, t0 + step, ...`` up to the last time of the record, at least 3 and at most
        :data:`bondgraph.simulation.MAX_SAMPLES` samples.
    method : {"linear"}
        Interpolation between the two samples around each grid time.

    Returns
    -------
    Record
        Same name and signals; a grid time next to a NaN sample is NaN (a gap is never bridged),
        one that falls on a sample takes its value.

    Warns
    -----
    RecordWarning
        When a grid time lies more than one new step from the nearest sample (the record has a
        step more than twice the new one, or is upsampled), with the largest such distance.

    Raises
    ------
    RecordError
        A bad record, ``step`` or ``method``, or a grid of fewer than 3 or more than ``MAX_SAMPLES``
        samples.

    Examples
    --------
    >>> import numpy as np
    >>> record = as_record({"t": [0.0, 0.1, 0.21, 0.3, 0.4, 0.5], "x": [0.0, 1.0, 2.1, np.nan, 4.0, 5.0]})
    >>> record.is_uniform
    False
    >>> uniform = resample(record)
    >>> uniform.is_uniform, np.round(uniform.t, 3).tolist()
    (True, [0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    >>> np.round(uniform["x"], 3).tolist()   # 0.2 between 1.0 and 2.1; the gap at 0.3 stays a gap
    [0.0, 1.0, 2.0, nan, 4.0, 5.0]
    """
    record = record if isinstance(record, Record) else as_record(record)
    if method not in RESAMPLE_METHODS:
        raise RecordError(f"{record.name}: resample method {method!r} is not one of {list(RESAMPLE_METHODS)}")
    step = record.dt if step is None else _checked_step(step, record.name)
    grid = _grid(record, step)
    left = np.clip(np.searchsorted(record.t, grid, side="right") - 1, 0, len(record) - 2)
    t0, t1 = record.t[left], record.t[left + 1]
    weight = (grid - t0) / (t1 - t0)
    columns = {name: _interpolate(x[left], x[left + 1], weight) for name, x in record.columns.items()}
    _warn_far_from_data(record, grid, t0, t1, step)
    return Record(t=grid, columns=columns, name=record.name)


def _checked_step(step: object, name: str) -> float:
    if isinstance(step, bool) or not isinstance(step, numbers.Real) or not math.isfinite(step) or step <= 0:
        raise RecordError(f"{name}: resample step must be a finite number of seconds > 0, got {step!r}")
    return float(step)


def _grid(record: Record, step: float) -> np.ndarray:
    """``t0 + k step`` up to the last time (within rounding), checked for size."""
    span = float(record.t[-1] - record.t[0])
    ratio = span / step
    # a last grid time that misses t_end by a rounding error still counts
    count = (round(ratio) if abs(ratio - round(ratio)) <= 1e-9 * ratio else math.floor(ratio)) + 1
    if count < 3:
        raise RecordError(f"{record.name}: resample step {step:g} s gives {count} sample(s) over the record's "
                          f"{span:g} s; at least 3 are needed")
    if count > MAX_SAMPLES:
        raise RecordError(f"{record.name}: resample step {step:g} s gives {count} samples over the record's "
                          f"{span:g} s, more than the limit of {MAX_SAMPLES} (MAX_SAMPLES)")
    grid = record.t[0] + step * np.arange(count)
    grid[-1] = min(grid[-1], record.t[-1])  # never beyond the data: that would be extrapolation
    return grid


def _interpolate(before: np.ndarray, after: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Linear interpolation, NaN if either sample is; a grid time on a sample takes that sample alone."""
    with np.errstate(invalid="ignore"):
        between = before + weight * (after - before)
    return np.where(weight == 0.0, before, np.where(weight == 1.0, after, between))


def _warn_far_from_data(record: Record, grid: np.ndarray, t0: np.ndarray, t1: np.ndarray, step: float) -> None:
    distance = np.minimum(grid - t0, t1 - grid)
    worst = int(np.argmax(distance))
    if distance[worst] > step * (1 + 1e-9):
        longest = int(np.argmax(np.diff(record.t)))
        warnings.warn(f"{record.name}: resampled to a step of {step:g} s, but the record has steps up to "
                      f"{record.t[longest + 1] - record.t[longest]:g} s (from {TIME} = {record.t[longest]:g}): "
                      f"values up to {distance[worst]:g} s from the nearest sample are straight-line "
                      "interpolations, not data", RecordWarning, stacklevel=2)
