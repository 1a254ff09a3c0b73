"""Derivatives and integrals of a record's signals, saying so when they cannot be known.

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
>>> from diagnosis.records import as_record
>>> record = as_record({"t": t, "x": np.sin(t)}, name="demo")
>>> record
Record('demo', 201 samples, t in [0, 2], signals ['x'])
>>> v = derivative(record, "x")
>>> float(np.max(np.abs(v - np.cos(t)))) < 1e-4
True
"""

from __future__ import annotations

import numbers
import warnings

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import cumulative_trapezoid
from scipy.signal import savgol_filter


from .records import (TIME, Record, RecordError, RecordWarning, as_record, check_magnitude, check_no_inf, float_column,
                      runs, step_deviation)

__all__ = [
    "METHODS", "central_derivative", "check_savgol_settings", "cumulative_integral", "default_window",
    "derivative",
]


METHODS = ("savgol", "central", "exact")


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
    values = float_column(x, name, record.name)
    if values.size != record.t.size:
        raise RecordError(f"{record.name}: signal {name!r} has {values.size} samples, "
                          f"{TIME!r} has {record.t.size}")
    check_no_inf(values, name, record.t, record.name)
    check_magnitude(values, name, record.t, record.name)
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
    diagnosis.records.RecordError: signal 'i': window must be an odd number of samples > polyorder 3, got 10
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
                          f"the median step {record.dt:g} by up to {step_deviation(record.t):.2%}; "
                          "use method='central', which handles uneven steps, or put the record on a uniform grid "
                          "first with diagnosis.resample(record) (bgphm: --resample)")
    if len(record) < window:
        raise RecordError(f"signal {name!r} has {len(record)} samples, fewer than the Savitzky-Golay window "
                          f"of {window}; pass a smaller odd window= or use method='central'")


def _savgol(x: np.ndarray, dt: float, order: int, window: int, polyorder: int) -> np.ndarray:
    out = np.full(x.size, np.nan)
    half = window // 2
    for start, stop in runs(~np.isnan(x)):
        if stop - start < window:
            continue
        d = savgol_filter(x[start:stop], window, polyorder, deriv=order, delta=dt, mode="interp")
        # next to a gap only one side has data: no one-sided estimate there
        lo = start + (half if start > 0 else 0)
        hi = stop - (half if stop < x.size else 0)
        out[lo:hi] = d[lo - start:hi - start]
    return out
