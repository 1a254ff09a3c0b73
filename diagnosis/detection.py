"""Fault detection with interval-valued ARRs (Jha et al. (2016), Table I).

At every sample the nominal residual ``r_n`` is compared with the range of the
uncertain part: normal when ``-r_n`` lies in ``[B_lo, B_hi]`` (eq. 19), fault
when it leaves it (eq. 20).  Two options make this usable on measured data,
where noise alone crosses the bare parametric band:

* a noise margin ``m`` widening the band to ``[B_lo - m, B_hi + m]``,
  typically ``k`` standard deviations of the residual on a nominal record
  (:func:`noise_margin`);
* persistence: an alarm is raised only after ``m`` consecutive violations.

Samples where the residual or the band is NaN (gaps in the data, derivative
stencils touching a gap) are undecided: never a violation, and they break a
run of consecutive violations.

Example
-------
>>> import numpy as np
>>> from bondgraph import simulate
>>> from bondgraph.library import rlc_circuit
>>> from diagnosis import derive_arrs
>>> bg = rlc_circuit()
>>> data = simulate(bg, (0, 0.5), {"V": 1.0}, t_eval=np.linspace(0, 0.5, 2001)).record()
>>> result = derive_arrs(bg)[0].evaluate(data, margin=1e-5)
>>> bool(result.alarm.any())
False
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np

from bondgraph.optional import pandas_for

from .residuals import ARRError, read_record
from .derivatives import default_window
from .records import RecordError, has_column
from .steps import step_mask
from .thresholds import bglft_threshold, interval_threshold

__all__ = [
    "CalibrationError", "Evaluation", "check_arr", "check_closed_form", "check_options", "evaluate", "fitting_order",
    "judge", "noise_margin", "persistent", "robust_std",
]


class CalibrationError(RecordError):
    """A fault-free record that gives no residual to calibrate a margin on (every value undecided)."""


@dataclass
class Evaluation:
    """An ARR evaluated over a record.

    Attributes
    ----------
    t, residual : ndarray
        Time and nominal residual ``r_n``.
    lower, upper : ndarray
        Interval threshold ``[B_lo, B_hi]`` on ``-r_n`` (without margin).
    bglft : ndarray
        BG-LFT half-width ``sum |w_i|`` (band ``[-bglft, bglft]``).
    margin : float
        Noise margin added on both sides.
    violation, alarm : ndarray of bool
        ``-r_n`` outside the widened band; violation persisting ``persistence`` samples.
    detection_time : float or None
        Time of the first alarm.
    points : list of ndarray
        The ARR's point values per sample (signals, derivative estimates,
        integrals), in the order of :class:`~diagnosis.residuals.CompiledARR`.
    masked : ndarray of bool
        Samples left undecided because a derivative estimate reaches across a step of an input.

    Examples
    --------
    Returned by :func:`evaluate` (or :meth:`ARR.evaluate <diagnosis.derivation.ARR.evaluate>`):

    >>> from bondgraph import simulate
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> bg = rlc_circuit()
    >>> t = np.linspace(0.0, 1.0, 1001)
    >>> record = simulate(bg, (0.0, 1.0), {"V": lambda t: np.sin(20 * t)}, t_eval=t).record()
    >>> result = derive_arrs(bg)[0].evaluate(record, margin=1e-3)
    >>> result.name, result.t.shape, result.residual.shape, result.margin, result.persistence
    ('ARR_J1', (1001,), (1001,), 0.001, 1)
    >>> bool(np.all(result.lower <= result.upper)), bool(np.all(result.bglft >= 0))
    (True, True)
    >>> result.detection_time is None, result.false_alarms(before=1.0), int(result.alarm.sum())
    (True, 0, 0)
    """

    name: str
    t: np.ndarray
    residual: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    bglft: np.ndarray
    margin: float
    persistence: int
    violation: np.ndarray
    alarm: np.ndarray
    points: list = field(default_factory=list, repr=False)
    masked: np.ndarray | None = field(default=None, repr=False, kw_only=True)

    @property
    def detection_time(self) -> float | None:
        """Time of the first sample in alarm (the end of the first run of ``persistence`` violations), or None."""
        index = np.flatnonzero(self.alarm)
        return float(self.t[index[0]]) if index.size else None

    def to_frame(self):
        """The per-sample arrays as a pandas DataFrame (pandas is imported here, on demand).

        Columns ``t, residual, lower, upper, bglft, violation, alarm``, one row per sample, with
        the default integer index: ``t`` is a column, as in the records that
        :func:`evaluate` reads.  ``lower`` and ``upper`` are the band on ``-residual`` (Jha et al. (2016):
        ``-r_n`` in ``[B_lo, B_hi]``) without the margin (``self.margin``), as on the object; the
        ``residuals.csv`` of ``bgphm detect`` writes the band on ``r_n`` itself, margin included.

        >>> flags = np.array([False, False, True])
        >>> result = Evaluation("ARR_demo", np.array([0.0, 0.1, 0.2]), residual=np.array([0.0, -0.1, -0.5]),
        ...                     lower=np.full(3, -0.2), upper=np.full(3, 0.2), bglft=np.full(3, 0.3),
        ...                     margin=0.05, persistence=1, violation=flags, alarm=flags)
        >>> frame = result.to_frame()
        >>> list(frame.columns)
        ['t', 'residual', 'lower', 'upper', 'bglft', 'violation', 'alarm']
        >>> frame.loc[frame["alarm"], "t"].tolist()
        [0.2]
        """
        pd = pandas_for("to_frame")
        return pd.DataFrame({"t": self.t, "residual": self.residual, "lower": self.lower, "upper": self.upper,
                             "bglft": self.bglft, "violation": self.violation, "alarm": self.alarm})

    def false_alarms(self, before: float) -> int:
        """Number of alarm onsets (rising edges) strictly before time ``before``."""
        onsets = self.alarm & ~np.concatenate([[False], self.alarm[:-1]])
        return int(np.count_nonzero(onsets & (self.t < before)))


def evaluate(arr, record, *, method: str = "savgol", window: int | None = None, polyorder: int | None = None,
             exact_derivatives: Mapping | None = None, antiderivatives: Mapping | None = None,
             margin: float = 0.0, persistence: int = 1, threshold: str = "interval",
             steps: bool | Iterable[str] = True, ends: bool = False, initial="rest") -> Evaluation:
    """Residual, thresholds and alarms of one ARR over a record.

    Parameters
    ----------
    arr : ARR
    record : mapping or DataFrame
        Column ``t`` and one column per signal of the ARR.
    method, window, polyorder : derivative estimator (``"savgol"`` or ``"central"``); ``polyorder``
        defaults to 3, or the ARR's highest derivative order when above (:func:`fitting_order`).
    exact_derivatives : mapping, optional
        Signal name (``"x"``, or ``"x:2"`` for the second derivative) -> exact values.
    antiderivatives : mapping, optional
        Signal name -> record column holding its integral, e.g. encoder angles
        ``{"omega_m": "theta_m"}``; integrals linear in such signals are read
        from it instead of integrating (noisy) samples.
    margin : float
        Noise margin widening the band on both sides (see :func:`noise_margin`).
    persistence : int
        Consecutive violations needed to raise an alarm.
    threshold : {"interval", "bglft"}
        Which band decides: the interval range of Psi_2 or the BG-LFT ``sum |w_i|``.
    steps : bool or iterable of str
        Leave undecided the samples a derivative estimate takes across a step of an input
        (:mod:`diagnosis.steps`): True (default) looks for steps in the ARR's input signals (those not
        measured), an iterable names the record columns to look in (a model's inputs, say), False
        judges every sample.  Only an ARR that estimates derivatives is affected.
    ends : bool
        Leave undecided as well the samples as close to either end of the record, where the estimate
        extrapolates a one-sided fit (:func:`diagnosis.detect` does; a stream cannot know its end).
    initial : "rest" or mapping
        For a simulation residual (:mod:`diagnosis.simulation_residuals`), its states' initial values or
        ``(lo, hi)`` boxes by name, or ``"rest"`` (default): at rest at the first sample.  Other ARRs ignore it.

    Returns
    -------
    Evaluation

    Examples
    --------
    The resistance of the RLC circuit steps from 10 to 13 ohm at t = 0.5 s;
    the loop's ARR (sensitive to R) detects it, the capacitor's does not:

    >>> from bondgraph import simulate
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> bg = rlc_circuit()
    >>> loop, capacitor = derive_arrs(bg)
    >>> t = np.linspace(0.0, 1.0, 1001)
    >>> faulty = simulate(bg, (0.0, 1.0), {"V": lambda t: np.sin(20 * t)}, t_eval=t,
    ...                   parameters={"R": lambda t: 10.0 if t < 0.5 else 13.0}).record()
    >>> evaluate(loop, faulty, margin=1e-3, persistence=3).detection_time
    0.501
    >>> evaluate(capacitor, faulty, margin=1e-3, persistence=3).detection_time is None
    True
    """
    check_options(arr, "evaluate", method=method, antiderivatives=antiderivatives, margin=margin,
                  persistence=persistence, threshold=threshold)
    polyorder = fitting_order(arr, polyorder)
    data, band = arr.prepared(record, extra=tuple((antiderivatives or {}).values()), method=method, window=window,
                              polyorder=polyorder, exact=exact_derivatives, initial=initial)
    compiled = arr.compiled
    points = compiled.point_values(data, method=method, window=window, polyorder=polyorder,
                                   exact=exact_derivatives, antiderivatives=antiderivatives)
    masked = _across_steps(arr, data, _step_columns(arr, data, steps), method, window, polyorder,
                           exact_derivatives, ends)
    if masked.any():
        points = [np.where(masked, np.nan, p) for p in points]
    if band is None:
        residual, lower, upper, bglft, violation = judge(compiled, points, margin, threshold)
    else:   # a simulation residual: its band comes with the simulation, Psi_2's range is not needed
        residual = compiled.residual(points)
        lower, upper = band(residual)
        bglft = np.maximum(np.abs(lower), np.abs(upper))
        violation = _outside(residual, lower, upper, bglft, margin, threshold)
    alarm = persistent(violation, persistence)
    return Evaluation(arr.name, data.t, residual, lower, upper, bglft, float(margin), int(persistence), violation,
                      alarm, points, masked=masked)


def _step_columns(arr, record, steps) -> dict:
    """Input name -> samples, for the inputs whose steps :func:`evaluate` looks for (``steps``)."""
    if steps is False:
        return {}
    if steps is True:
        names = [s for s in arr.signals if s not in arr.sensors]
    elif isinstance(steps, str) or not isinstance(steps, Iterable):
        raise ValueError(f"steps must be True, False or a list of input names, got {steps!r}")
    else:
        names = list(dict.fromkeys(steps))
    present = [n for n in names if n in arr.signals or has_column(record, n)]
    if not present:
        return {}
    data = read_record(arr, record, extra=tuple(n for n in present if n not in arr.compiled.signals))
    return {n: data[n] for n in present}


def _across_steps(arr, data, inputs: Mapping, method: str, window: int | None, polyorder: int,
                  exact, ends: bool = False) -> np.ndarray:
    """The samples whose derivative estimates reach across a step of an input, or an end (see :func:`evaluate`)."""
    estimated = [order for name, order in arr.derivatives.items() if order and not _known(name, order, exact)]
    if not (inputs or ends) or not estimated:
        return np.zeros(len(data), bool)
    order = max(estimated)
    # half a window reaches the step itself; the signals' fast transient right after it bends them as
    # sharply, so a whole window (and the derivative's order) is left undecided on each side
    reach = ((window or default_window(polyorder)) if method == "savgol" else 2) + order
    masked = step_mask({"t": data.t, **inputs}, list(inputs), reach)
    if ends:
        masked[:reach] = True
        masked[len(masked) - reach:] = True
    return masked


def _known(name: str, order: int, exact) -> bool:
    """Whether every derivative of ``name`` up to ``order`` is given exactly."""
    return bool(exact) and all((name if k == 1 else f"{name}:{k}") in exact for k in range(1, order + 1))


def fitting_order(arr, polyorder):
    """The Savitzky-Golay polynomial order for ``arr``: ``polyorder`` if given, else 3 or the ARR's order.

    An ARR the library offers is evaluated with the defaults: one that needs a fourth derivative gets
    a quartic fit rather than an error (a fit of lower order has no such derivative).  A polyorder the
    caller gives is used as given (and checked).

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> fitting_order(derive_arrs(rlc_circuit())[0], None), fitting_order(derive_arrs(rlc_circuit())[0], 5)
    (3, 5)
    """
    if polyorder is None:
        return max(3, getattr(arr, "order", 0))
    return polyorder


def check_options(arr, caller: str, *, method: str = "savgol", antiderivatives: Mapping | None = None,
                  margin: float = 0.0, persistence: int = 1, threshold: str = "interval") -> None:
    """The checks of :func:`evaluate`'s options, shared by every caller that evaluates an ARR.

    Raises a TypeError unless ``arr`` is an ARR, a :class:`~diagnosis.records.RecordError` for an unknown
    derivative method or antiderivatives that are not a mapping of names, a ValueError naming the option
    for a bad ``threshold``, ``persistence`` or ``margin``.

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arr = derive_arrs(rlc_circuit())[0]
    >>> check_options(arr, "evaluate", margin=1e-3, persistence=3)
    >>> check_options(arr, "evaluate", persistence=0)
    Traceback (most recent call last):
    ...
    ValueError: persistence must be a whole number of samples >= 1, got 0
    """
    check_arr(arr, caller)
    if threshold not in ("interval", "bglft"):
        raise ValueError(f"threshold must be 'interval' or 'bglft', got {threshold!r}")
    if isinstance(persistence, bool) or not isinstance(persistence, numbers.Integral) or persistence < 1:
        raise ValueError(f"persistence must be a whole number of samples >= 1, got {persistence!r}")
    if isinstance(margin, bool) or not isinstance(margin, numbers.Real) or not math.isfinite(margin) or margin < 0:
        raise ValueError(f"margin: the noise margin must be a finite number >= 0, got {margin!r}")
    if method not in ("savgol", "central"):
        raise RecordError(f"{arr.name}: unknown derivative method {method!r}; choose 'savgol' or 'central' "
                          "(known derivatives go in exact_derivatives=)")
    if antiderivatives is not None and (not isinstance(antiderivatives, Mapping) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in antiderivatives.items())):
        raise RecordError(f"{arr.name}: antiderivatives must map signal names to record columns, e.g. "
                          f"{{'omega_m': 'theta_m'}}, got {antiderivatives!r}")


def judge(compiled, points: list[np.ndarray], margin: float, threshold: str, both: bool = True
          ) -> tuple[np.ndarray, ...]:
    """``(residual, lower, upper, bglft, violation)`` at every sample of the point values ``points``.

    Each sample is judged on its own point values (no sample depends on another here), so a stream
    can judge its samples a batch at a time (:class:`diagnosis.streaming.StreamingEvaluation`).
    ``both=False`` computes only the band of ``threshold`` (the other is NaN): for a caller that
    keeps the alarms alone.

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> compiled = derive_arrs(rlc_circuit())[0].compiled   # V - 0.1 d1_i - 10 i - v_C
    >>> V, i, v_C, d1_i = np.array([1.0, 1.0]), np.array([0.1, 0.0]), np.zeros(2), np.zeros(2)
    >>> residual, lower, upper, bglft, violation = judge(compiled, [V, i, v_C, d1_i], 0.0, "interval")
    >>> residual.tolist(), violation.tolist()
    ([0.0, 1.0], [False, True])
    """
    residual = compiled.residual(points)
    undecided = np.full(np.shape(residual), np.nan)
    if both or threshold == "interval":
        lower, upper = interval_threshold(compiled, points)
    else:
        lower, upper = undecided, undecided.copy()
    bglft = bglft_threshold(compiled, points) if both or threshold != "interval" else undecided.copy()
    return residual, lower, upper, bglft, _outside(residual, lower, upper, bglft, margin, threshold)


def _outside(residual, lower, upper, bglft, margin: float, threshold: str) -> np.ndarray:
    """Where ``-r_n`` leaves the band of ``threshold`` widened by ``margin`` (a NaN is undecided, not outside)."""
    lo, hi = (lower, upper) if threshold == "interval" else (-bglft, bglft)
    with np.errstate(invalid="ignore"):
        return (-residual < lo - margin) | (-residual > hi + margin)


def check_closed_form(arr, caller: str) -> None:
    """Raise an ARRError naming ``caller`` when ``arr`` is a simulation residual, which has no closed form.

    Its states are integrated over the whole record (:mod:`diagnosis.simulation_residuals`), so a consumer that
    compiles ``nominal`` alone (a stream, generated code, a parameter box or a prognoser) cannot use it.

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> check_closed_form(derive_arrs(rlc_circuit())[0], "StreamingEvaluation")   # a closed form: nothing said
    """
    if getattr(arr, "simulation", False):
        raise ARRError(f"{caller}: {arr.name} is a simulation residual (its states {', '.join(arr.states)} are "
                       "integrated over the record) with no closed form; use evaluate or detect for it, or derive "
                       "the ARRs without simulated=True")


def check_arr(arr: object, caller: str) -> None:
    """Raise a TypeError naming ``caller`` unless ``arr`` is an ARR (anything with a name and a compiled form).

    >>> check_arr("ARR_1_m", "noise_margin")
    Traceback (most recent call last):
    ...
    TypeError: noise_margin: arr must be an ARR from diagnosis.derive_arrs, got the str 'ARR_1_m' (look the ARR up ...
    """
    if hasattr(arr, "compiled") and hasattr(arr, "name"):
        return
    shown = repr(arr) if len(repr(arr)) <= 60 else repr(arr)[:57] + "..."
    hint = " (look the ARR up by its name in the list derive_arrs returns)" if isinstance(arr, str) else ""
    raise TypeError(f"{caller}: arr must be an ARR from diagnosis.derive_arrs, got the {type(arr).__name__} "
                    f"{shown}{hint}")


def persistent(violation: np.ndarray, samples: int) -> np.ndarray:
    """True where the last ``samples`` entries (this one included) are all True.

    >>> persistent(np.array([1, 1, 0, 1, 1, 1], bool), 2).astype(int).tolist()
    [0, 1, 0, 0, 1, 1]
    """
    if samples <= 1:
        return violation.copy()
    # a running count of violations, O(n) whatever the window (a convolution costs O(n * samples))
    count = np.concatenate(([0], np.cumsum(violation, dtype=np.int64)))
    window = count[1:] - count[np.maximum(np.arange(violation.size) + 1 - samples, 0)]
    return window >= samples


def noise_margin(arr, nominal_record, k: float = 3.0, **options) -> float:
    """``k`` robust standard deviations of ``r_n`` on a fault-free record.

    ``sigma = 1.4826 * median(|r_n - median(r_n)|)`` (the MAD, scaled to
    the standard deviation of Gaussian noise): start-up transients and the
    edges of the derivative estimator are outliers that a plain standard
    deviation would turn into a band wide enough to hide faults; persistence
    (:func:`evaluate`) deals with them instead.

    Parameters
    ----------
    arr : ARR
    nominal_record : mapping or DataFrame
        A fault-free record (column ``t`` and the ARR's signals).
    k : float
        Number of robust standard deviations.
    **options
        Passed to :func:`evaluate` (derivative estimator settings).

    Returns
    -------
    float
        The margin to pass to :func:`evaluate` with the same options.

    Examples
    --------
    On a noisy current measurement the bare band raises false alarms; the
    calibrated margin with persistence does not, and still sees the fault:

    >>> from bondgraph import simulate
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import add_noise, derive_arrs
    >>> bg = rlc_circuit()
    >>> arr = derive_arrs(bg)[0]
    >>> t = np.linspace(0.0, 1.0, 1001)
    >>> source = {"V": lambda t: np.sin(20 * t)}
    >>> nominal = add_noise(simulate(bg, (0.0, 1.0), source, t_eval=t).record(), {"i": 1e-4}, seed=0)
    >>> evaluate(arr, nominal, window=31).false_alarms(before=1.0) > 0
    True
    >>> margin = noise_margin(arr, nominal, window=31)
    >>> round(margin, 4)
    0.0033
    >>> evaluate(arr, nominal, window=31, margin=margin, persistence=10).detection_time is None
    True
    >>> faulty = simulate(bg, (0.0, 1.0), source, t_eval=t, parameters={"R": lambda t: 10.0 if t < 0.5 else 13.0})
    >>> found = evaluate(arr, add_noise(faulty.record(), {"i": 1e-4}, seed=1), window=31, margin=margin,
    ...                  persistence=10).detection_time
    >>> 0.5 < found < 0.52
    True
    """
    check_arr(arr, "noise_margin")
    if isinstance(k, bool) or not isinstance(k, numbers.Real) or not math.isfinite(k) or k <= 0:
        raise ValueError(f"k: the number of standard deviations must be a finite number > 0, got {k!r}")
    result = evaluate(arr, nominal_record, **options)
    if np.isfinite(result.residual).sum() < 2:
        raise CalibrationError(f"{arr.name}: the nominal record gives fewer than 2 finite residual values")
    return k * robust_std(result.residual)


def robust_std(values: np.ndarray) -> float:
    """``1.4826 * median(|x - median(x)|)`` over the finite values (0 with fewer than 2).

    >>> robust_std(np.array([1.0, 2.0, 3.0, np.nan, 100.0]))
    1.4826
    """
    finite = values[np.isfinite(values)]
    if finite.size < 2:
        return 0.0
    return float(1.4826 * np.median(np.abs(finite - np.median(finite))))
