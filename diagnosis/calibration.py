"""The healthy stretch of a record: where it ends, the margins and the residual noise it gives, and the
check that it holds no fault.

Every monitor calibrates on a stretch its user declares fault-free: ``calibrate`` seconds, by default
the first :data:`CALIBRATION_SHARE` of the record.  A margin calibrated on a stretch that holds a
fault absorbs it, and the alarm comes late or never.  A degradation, once there, stays: a fault in the
stretch keeps the ARR in alarm up to the stretch's end.  So :func:`check_healthy` calibrates the
margin again on the first half alone and refuses the stretch if the ARR is in alarm in its last quarter,
with that margin or with the whole stretch's (split-half validation); an alarm that ends before (a
transient at an input step, a start-up) is no fault.

:class:`DetectionSettings` holds the settings of the detection family, checked once, for
:func:`calibrate` (one record), :func:`pooled_calibration` (a fleet's first records) and
:func:`~diagnosis.detect`.  An error names the setting (:class:`~bondgraph.errors.SettingError`), so
that the command line can name its option.

>>> import numpy as np
>>> from bondgraph import simulate
>>> from bondgraph.library import rlc_circuit
>>> from diagnosis import add_noise, derive_arrs
>>> bg = rlc_circuit()
>>> t = np.linspace(0.0, 2.0, 2001)
>>> record = add_noise(simulate(bg, (0.0, 2.0), {"V": lambda t: np.sin(20 * t)}, t_eval=t).record(),
...                    {"i": 1e-4}, seed=0)
>>> healthy = calibrate(derive_arrs(bg), record, DetectionSettings(calibrate=0.5))
>>> healthy.until, sorted(healthy.noise_std) == sorted(healthy.margin)
(0.5, True)
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from bondgraph.errors import SettingError

from .detection import CalibrationError, Evaluation, noise_margin, robust_std
from .derivatives import default_window
from .records import Record

__all__ = ["CALIBRATION_SHARE", "MIN_CALIBRATION_SAMPLES", "POOLED_RECORDS", "Calibration", "DetectionSettings",
           "calibrate", "calibration_end", "check_healthy", "pooled_calibration", "quiet_margin",
           "stays_in_alarm"]

#: The share of the record that calibrates the margins when no calibration stretch is given.
CALIBRATION_SHARE = 0.2
#: Samples a calibration stretch needs at least: fewer give no estimate of the residual noise.
MIN_CALIBRATION_SAMPLES = 20
#: Records a fleet's calibration pools by default (:func:`pooled_calibration`): the median of a few
#: resists one odd record, and each costs a calibration.
POOLED_RECORDS = 10
#: A calibrated margin is at least this multiple of the smallest margin that keeps the fault-free stretch
#: quiet (:func:`quiet_margin`): estimator bias at transients, which the noise's robust spread ignores.
SAFETY = 1.25
#: The share of a calibration stretch at its start that the quiet margin leaves out (a start from rest).
START_SHARE = 0.1
#: The smallest residual noise reported: a noise-free simulation gives 0, which no likelihood can use.
NOISE_FLOOR = 1e-300


@dataclass(frozen=True)
class DetectionSettings:
    """How a record's residuals are judged: the healthy stretch, the margins, the persistence.

    Parameters
    ----------
    calibrate : float, optional
        End (s) of the stretch declared fault-free; default the first :data:`CALIBRATION_SHARE` of
        the record.
    margin : float, optional
        A fixed noise margin for every ARR; default ``k`` robust standard deviations of each
        residual on the healthy stretch (and then the stretch is checked, :func:`check_healthy`).
    k : float
        Robust standard deviations in a calibrated margin.
    persistence : int
        Consecutive violations for an alarm.
    window : int, optional
        Savitzky-Golay window of the derivative estimates (odd); default that of
        :func:`~diagnosis.derivatives.default_window` (or, in :func:`~diagnosis.detect`, chosen per ARR).

    >>> DetectionSettings(persistence=0)
    Traceback (most recent call last):
    ...
    bondgraph.errors.SettingError: persistence must be at least 1, got 0
    """

    calibrate: float | None = None
    margin: float | None = None
    k: float = 4.0
    persistence: int = 5
    window: int | None = None

    def __post_init__(self) -> None:
        if isinstance(self.persistence, bool) or int(self.persistence) != self.persistence or self.persistence < 1:
            raise SettingError("persistence", f"{{setting}} must be at least 1, got {self.persistence!r}")
        if self.margin is not None and not (math.isfinite(self.margin) and self.margin >= 0):
            raise SettingError("margin", f"{{setting}} must be a finite non-negative number, got {self.margin!r}")
        if not (math.isfinite(self.k) and self.k > 0):
            raise SettingError("k", f"{{setting}} must be a positive number of standard deviations, got {self.k!r}")
        if self.calibrate is not None and not math.isfinite(self.calibrate):
            raise SettingError("calibrate", f"{{setting}} must be a finite time in s, got {self.calibrate!r}")
        if self.window is not None and (int(self.window) != self.window or self.window < 3 or self.window % 2 == 0):
            raise SettingError("window", f"{{setting}} must be an odd number of samples, at least 3, got "
                                         f"{self.window!r}")

    def options(self) -> dict:
        """The options of :func:`~diagnosis.evaluate` these settings fix (persistence, window)."""
        return {"persistence": int(self.persistence), **({"window": int(self.window)} if self.window else {})}


@dataclass
class Calibration:
    """What a healthy stretch gave: its end, each ARR's evaluation, residual noise and margin (by ARR name), and
    the ARRs it gave no residual to calibrate on (``undecided``: name -> why), left out of the rest."""

    until: float
    evaluations: list = field(default_factory=list)
    noise_std: dict = field(default_factory=dict)
    margin: dict = field(default_factory=dict)
    undecided: dict = field(default_factory=dict)

    def options(self, settings: DetectionSettings) -> dict:
        """ARR name -> the options of :func:`~diagnosis.evaluate` that judge its residual: its margin and the
        settings' persistence and window (a monitor's ``detection``)."""
        return {name: {"margin": margin, **settings.options()} for name, margin in self.margin.items()}


def calibration_end(record: Record, calibrate: float | None = None, *, hint: str = "", checked: bool = True) -> float:
    """The end of the healthy stretch: ``calibrate``, by default the first :data:`CALIBRATION_SHARE` of the record.

    Raises a :class:`~bondgraph.errors.SettingError` (``calibrate``) for a stretch that reaches the
    record's end or holds fewer than :data:`MIN_CALIBRATION_SAMPLES` samples; ``hint`` ends that message.
    ``checked=False``: the end alone (a fixed margin calibrates nothing on the stretch).

    >>> calibration_end(Record(np.linspace(0.0, 10.0, 101), {}))
    2.0
    """
    t0, t1 = float(record.t[0]), float(record.t[-1])
    if not checked:
        return float(calibrate) if calibrate is not None else t0 + CALIBRATION_SHARE * (t1 - t0)
    if calibrate is not None and calibrate >= t1:
        raise SettingError("calibrate", f"{{setting}} {calibrate:g}: at or past the end of the record (t = {t1:g} s); "
                                        "the calibration stretch must be fault-free and leave data to monitor")
    until = float(calibrate) if calibrate is not None else t0 + CALIBRATION_SHARE * (t1 - t0)
    count = int(np.count_nonzero(record.t <= until))
    if count < MIN_CALIBRATION_SAMPLES:
        raise SettingError("calibrate", f"{{setting}} {until:g}: only {count} samples before it; at least "
                                        f"{MIN_CALIBRATION_SAMPLES} are needed to estimate the residual noise{hint}")
    return until


def check_healthy(arr, record: Record, evaluation: Evaluation, until: float, settings: DetectionSettings,
                  options: dict | None = None) -> None:
    """Refuse a calibration stretch that holds a fault (split-half validation, see the module docstring).

    ``evaluation``: ``arr`` on ``record`` with the margin calibrated on ``t <= until``, with the
    options of :func:`~diagnosis.evaluate` ``options`` (default ``settings.options()``).  The ARR
    holds a fault there when, in the stretch's last quarter, it stays in alarm (:func:`stays_in_alarm`)
    with that margin or with one calibrated on the first half alone; the samples whose derivative
    estimate reads past the stretch's end are not the stretch's (a fault that starts right after it
    shows there).  A first half under :data:`MIN_CALIBRATION_SAMPLES` samples, or an ARR that
    integrates measured signals (its healthy residual is a random walk that outgrows an earlier
    half's margin), is not recalibrated.
    Raises a :class:`~bondgraph.errors.SettingError` (``calibrate``) naming the ARR and the time.
    """
    options = settings.options() if options is None else options
    t0 = float(record.t[0])
    half = t0 + 0.5 * (until - t0)
    end = int(np.count_nonzero(record.t <= until)) - _reach(arr, options)
    last = (record.t > t0 + 0.75 * (until - t0)) & (np.arange(record.t.size) < end)
    stretch = (f"{{setting}} {until:g}" if settings.calibrate is not None
               else f"the default calibration stretch (the first {CALIBRATION_SHARE:.0%} of the record, "
                    f"t <= {until:g} s)")
    hint = "give a shorter {setting} (or a fixed {setting:margin})"
    when = stays_in_alarm(evaluation.alarm[last], record.t[last])
    if when is not None:
        raise SettingError("calibrate", f"{stretch} is not fault-free: {evaluation.name} is in alarm from t = "
                                        f"{when:g} s, in the last quarter of it; {hint}")
    if np.count_nonzero(record.t <= half) < MIN_CALIBRATION_SAMPLES or getattr(arr, "integrals", None):
        # an integral of measured noise is a random walk: its spread on a healthy record grows past any
        # margin set on an earlier half (the margin of an integral form is widened for that growth instead)
        return
    first = record.between(end=half)
    start = t0 + START_SHARE * (half - t0)
    margin = max(noise_margin(arr, first, k=settings.k, **options),
                 SAFETY * quiet_margin(arr.evaluate(first, **options), after=start))
    when = stays_in_alarm(arr.evaluate(record, margin=margin, **options).alarm[last], record.t[last])
    if when is not None:
        raise SettingError("calibrate", f"{stretch} is not fault-free: calibrated on its first half (t <= {half:g} "
                                        f"s), {evaluation.name} is in alarm from t = {when:g} s, in the last quarter "
                                        f"of it; {hint}")


def stays_in_alarm(alarm: np.ndarray, t: np.ndarray) -> float | None:
    """The time of the first alarm when the ARR stays in alarm from there to the end of ``t``: on at least
    half of those samples (a degradation, once there, stays; a transient's alarm ends), else None.

    >>> t = np.arange(8.0)
    >>> stays_in_alarm(np.array([0, 1, 1, 0, 0, 0, 0, 0], bool), t) is None   # a transient
    True
    >>> stays_in_alarm(np.array([0, 0, 0, 1, 1, 0, 1, 1], bool), t)
    3.0
    """
    if not alarm.any():
        return None
    first = int(np.argmax(alarm))
    return float(t[first]) if alarm[first:].mean() >= 0.5 else None


def _reach(arr, options: dict) -> int:
    """Samples a derivative estimate of ``arr`` reads on either side of its own (0 without derivatives)."""
    if not getattr(arr, "order", 0):
        return 0
    if options.get("method", "savgol") == "central":
        return int(arr.order) + 1
    return int(options.get("window") or default_window(int(options.get("polyorder", 3)))) // 2


def quiet_margin(evaluation: Evaluation, after: float = -np.inf) -> float:
    """The smallest margin under which ``evaluation`` (of a fault-free stretch) raises no alarm after ``after``.

    The start of a record may hold a start-up transient whose alarms the monitors ignore anyway (they
    watch from the end of the calibration stretch): :func:`detect` looks at the second half only.

    A violation is ``-r_n`` beyond the band by more than the margin; an alarm needs ``persistence`` of
    them in a row, so the margin need only exceed, in every run of ``persistence`` samples, the
    smallest excess of the run.  Derivative estimates are biased where the signals bend sharply (the
    start of a transient): the noise's robust spread does not see that bias, this does.

    >>> e = Evaluation("ARR", np.arange(6.0), np.array([0, -3.0, -3.0, 0, -1.0, 0]), np.zeros(6), np.zeros(6),
    ...                np.zeros(6), 0.0, 2, np.zeros(6, bool), np.zeros(6, bool))
    >>> quiet_margin(e)   # -r_n exceeds the band by 3 on two samples in a row
    3.0
    """
    excess = np.maximum(-evaluation.residual - evaluation.upper, evaluation.lower + evaluation.residual)
    excess = np.where(np.isfinite(excess) & (evaluation.t > after), np.maximum(excess, 0.0), 0.0)
    p = evaluation.persistence
    if excess.size < p:
        return 0.0
    runs = sliding_window_view(excess, p).min(axis=1) if p > 1 else excess
    return float(runs.max()) if runs.size else 0.0


def calibrate(arrs: Sequence, record: Record, settings: DetectionSettings | None = None) -> Calibration:
    """Each ARR evaluated on ``record`` with its margin, and its residual noise, from the healthy stretch.

    The margin is ``settings.margin``, or ``k`` robust standard deviations of the residual on the
    stretch, which is then checked (:func:`check_healthy`); the noise, the residual's robust standard
    deviation there, is measured either way (a filter weighs the residuals by it).  An ARR the stretch gives
    no residual for (a derivative estimate undecided throughout, say) is left out, named in ``undecided``,
    as :func:`~diagnosis.detect` leaves it out; a :class:`~diagnosis.detection.CalibrationError` says when
    none is left.
    """
    settings = settings or DetectionSettings()
    until = calibration_end(record, settings.calibrate)
    healthy, options = record.between(end=until), settings.options()
    result = Calibration(until)
    for arr in arrs:
        try:
            margin = settings.margin if settings.margin is not None else noise_margin(arr, healthy, k=settings.k,
                                                                                      **options)
        except CalibrationError as error:
            result.undecided[arr.name] = str(error).removeprefix(f"{arr.name}: ")
            continue
        evaluation = arr.evaluate(record, margin=margin, **options)
        if settings.margin is None:
            check_healthy(arr, record, evaluation, until, settings)
        result.evaluations.append(evaluation)
        result.margin[arr.name] = float(margin)
        result.noise_std[arr.name] = max(robust_std(evaluation.residual[record.t <= until]), NOISE_FLOOR)
    if arrs and not result.margin:
        reasons = "; ".join(f"{name}: {why}" for name, why in result.undecided.items())
        raise CalibrationError(f"no ARR gives a residual on the healthy stretch to calibrate on ({reasons})")
    return result


def pooled_calibration(arrs: Sequence, records: Iterable[tuple[object, Record]],
                       settings: DetectionSettings) -> tuple[Calibration, Record]:
    """The median noise and margin per ARR over several assets' healthy stretches, and the first record.

    A fleet's assets share one model and one healthy regime: the median over a few records is robust
    to one odd record.  Each record is calibrated and checked as :func:`calibrate` does; an error names
    the asset (``asset 'c3': calibrate 5: ...``).
    """
    noise, margins, first, assets = {a.name: [] for a in arrs}, {a.name: [] for a in arrs}, None, []
    for asset, record in records:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the same warnings would repeat for every calibration record
            try:
                one = calibrate(arrs, record, settings)
            except SettingError as exc:
                raise exc.within(f"asset {asset!r}: ") from None
        for name in one.margin:
            noise[name].append(one.noise_std[name])
            margins[name].append(one.margin[name])
        first = record if first is None else first
        assets.append(asset)
    if first is None:
        raise SettingError("calibrate", "{setting}: no record to calibrate on")
    pooled = Calibration(settings.calibrate, [], {n: float(np.median(v)) for n, v in noise.items() if v},
                         {n: float(np.median(v)) for n, v in margins.items() if v},
                         {n: "no calibration record gives it a residual" for n, v in noise.items() if not v})
    return pooled, first
