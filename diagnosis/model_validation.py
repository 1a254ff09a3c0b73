"""Validation of a calibrated model against its datasheet model, on healthy records it was not fitted on.

A model calibrated on healthy records (:func:`~diagnosis.estimate_parameters`) should do better than the
datasheet model on *other* healthy records of the same machine: raise no more false alarms, see smaller
parameter changes, and leave residuals that are noise rather than the trace of a wrong parameter.
:func:`validate_calibration` measures the three, for both models alike:

1. **Margins from the training records.** For each model and ARR, the noise margin is calibrated on the
   training records (the records the calibration was fitted on, each healthy from end to end): the larger
   of ``k`` robust standard deviations of the residual and :data:`~diagnosis.calibration.SAFETY` times the
   smallest margin that keeps the record quiet after its start-up (the first
   :data:`~diagnosis.calibration.START_SHARE` of it), the largest over the training records.  A datasheet
   whose values are wrong leaves a systematic residual there, which its margin absorbs; the comparison is
   then fair: each model gets the margin its own training residuals ask for.  Both use the same derivative
   window (``settings.window``, else the default), so that their figures differ by the model alone.
2. **Detection on the held-out records** (:func:`~diagnosis.detect` with those fixed margins): a **false
   alarm** is any alarm after the record's start-up, on a record known to be healthy; the **smallest
   detectable change** of each parameter (:attr:`~diagnosis.Detection.smallest_changes`) is read on each
   held-out record and the largest over them is reported (the change seen on every one).
3. **Whiteness of the residuals** on the held-out records: the autocorrelation at lags 1 to ``lags`` and the
   Ljung-Box statistic of each ARR's residual, taken every derivative window (a derivative estimate's noise
   is correlated over its window, so neighbouring samples are never independent; estimates one window
   apart share no sample).  The residual of a right model is noise; that of a wrong one follows the
   signals and is correlated over many lags.

Example
-------
A DC motor whose datasheet friction is 40 % low and inertia 30 % high, calibrated on two bench runs and
validated on a third, driven harder:

>>> import numpy as np
>>> from bondgraph import simulate
>>> from bondgraph.library import dc_motor
>>> from diagnosis import add_noise, as_record, estimate_parameters, uncertainty_boxes
>>> t = np.linspace(0.0, 2.0, 2001)
>>> def run(volts, seed):
...     U = lambda t: volts * ((t >= 0.05) - 0.5 * (t >= 1.0)) + 2.0 * np.sin(9 * t)
...     clean = simulate(dc_motor(b=1.4e-4, J=0.77e-4), (0, 2), {"U": U}, t_eval=t).record()
...     return add_noise(as_record(clean), {"i": 0.01, "omega": 0.2}, seed=seed)
>>> training, held_out = [run(12.0, 1), run(10.0, 2)], [run(18.0, 3)]
>>> sheet = dc_motor(b=1e-4, J=1e-4)
>>> fit = estimate_parameters(sheet, training, parameters=["b", "J"])
>>> result = validate_calibration(sheet, fit.model(sheet, uncertainty_boxes(fit)), training, held_out)
>>> result.before.false_alarm_rate, result.after.false_alarm_rate
(1.0, 0.0)
>>> result.before.whiteness["ARR_1_m"].autocorrelation[0] > 0.5 > result.after.whiteness["ARR_1_m"].autocorrelation[0]
True
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from bondgraph.errors import SettingError

from .calibration import SAFETY, START_SHARE, DetectionSettings, quiet_margin
from .derivation import derive_arrs
from .derivatives import default_window
from .detection import robust_std
from .monitoring import detect
from .records import Record, as_record

__all__ = ["LAGS", "WHITE_LEVEL", "ModelFigures", "ModelValidation", "Whiteness", "held_out_figures",
           "residual_whiteness", "validate_calibration"]

#: Lags of the whiteness test (each one derivative window of samples apart).
LAGS = 10
#: A residual is called white when the Ljung-Box test does not reject whiteness at this level.
WHITE_LEVEL = 0.01


@dataclass(frozen=True)
class Whiteness:
    """How far an ARR's residual is from white noise, on the held-out records.

    Attributes
    ----------
    arr : str
    autocorrelation : list of float
        At lags 1, 2, ... (in steps of ``spacing`` samples), pooled over the records (each record's own
        mean removed; pairs that hold an undecided sample left out).
    statistic : float
        Ljung-Box ``Q = n (n + 2) sum_k rho_k^2 / (n - k)``, chi-squared with ``len(autocorrelation)``
        degrees of freedom for white noise; NaN with too few samples.
    p_value : float
        Its upper tail: small when the residual is correlated.
    samples : int
        Residual values used (every ``spacing``-th, finite).
    spacing : int
        Samples between the values used: the ARR's derivative window (1 without derivatives).
    """

    arr: str
    autocorrelation: list
    statistic: float
    p_value: float
    samples: int
    spacing: int

    @property
    def white(self) -> bool:
        """The test does not reject whiteness at :data:`WHITE_LEVEL` (False without enough samples)."""
        return bool(math.isfinite(self.p_value) and self.p_value >= WHITE_LEVEL)

    def as_dict(self) -> dict:
        return {"arr": self.arr, "autocorrelation": [_finite(v) for v in self.autocorrelation],
                "ljung_box": _finite(self.statistic), "p_value": _finite(self.p_value), "white": self.white,
                "samples": self.samples, "spacing": self.spacing}


@dataclass
class ModelFigures:
    """One model on the held-out records, with margins from the training records.

    Attributes
    ----------
    margins : dict
        ARR -> the noise margin calibrated on the training records.
    windows : dict
        ARR -> its derivative window (None for an ARR without derivatives).
    alarms : dict
        Held-out record -> {ARR: time of its first alarm after the start-up}; an empty dict: no alarm.
    changes : dict
        Held-out record -> {parameter: smallest detectable relative change over the ARRs} (``inf``: none).
    whiteness : dict
        ARR -> :class:`Whiteness` of its residual on the held-out records.
    undecided : dict
        ARR -> why the records cannot evaluate it (left out of every figure).
    """

    margins: dict = field(default_factory=dict)
    windows: dict = field(default_factory=dict)
    alarms: dict = field(default_factory=dict)
    changes: dict = field(default_factory=dict)
    whiteness: dict = field(default_factory=dict)
    undecided: dict = field(default_factory=dict)

    @property
    def false_alarms(self) -> list:
        """The held-out records with an alarm (each is healthy, so any alarm is false)."""
        return [name for name, fired in self.alarms.items() if fired]

    @property
    def false_alarm_rate(self) -> float:
        """The share of held-out records with a false alarm."""
        return len(self.false_alarms) / len(self.alarms) if self.alarms else math.nan

    @property
    def smallest_changes(self) -> dict:
        """Parameter -> the smallest relative change detected on every held-out record (the largest of the
        records' figures; ``inf``: not on every one)."""
        found: dict = {}
        for per_record in self.changes.values():
            for parameter, change in per_record.items():
                found[parameter] = max(found.get(parameter, 0.0), change)
        return found

    def as_dict(self) -> dict:
        return {"false_alarms": self.false_alarms, "false_alarm_rate": _finite(self.false_alarm_rate),
                "alarms": {r: dict(a) for r, a in self.alarms.items()},
                "smallest_changes": {p: _finite(v) for p, v in self.smallest_changes.items()},
                "changes": {r: {p: _finite(v) for p, v in c.items()} for r, c in self.changes.items()},
                "margins": dict(self.margins), "windows": dict(self.windows),
                "whiteness": {a: w.as_dict() for a, w in self.whiteness.items()}, "undecided": dict(self.undecided)}


@dataclass
class ModelValidation:
    """What :func:`validate_calibration` found: the datasheet model (``before``) and the calibrated one
    (``after``) on the same held-out records, with margins from the same training records."""

    training: list
    held_out: list
    before: ModelFigures
    after: ModelFigures
    settings: DetectionSettings
    lags: int = LAGS

    def as_dict(self) -> dict:
        """Plain data for JSON (an infinite or undefined figure is None)."""
        s = self.settings
        return {"training": list(self.training), "held_out": list(self.held_out),
                "settings": {"k": s.k, "persistence": s.persistence, "window": s.window, "margin": s.margin,
                             "lags": self.lags},
                "datasheet": self.before.as_dict(), "calibrated": self.after.as_dict()}


# ------------------------------------------------------------------------------------------- validation

def validate_calibration(datasheet, calibrated, training, held_out, settings: DetectionSettings | None = None, *,
                         lags: int = LAGS) -> ModelValidation:
    """The datasheet model and the calibrated one, each with margins from ``training``, on ``held_out``.

    Parameters
    ----------
    datasheet, calibrated : BondGraph
        The model before and after calibration (:meth:`~diagnosis.ParameterEstimate.model`).
    training, held_out : sequence of records, or mapping of name -> record
        Healthy records: those the calibration was fitted on, and others.  A sequence's records are named
        ``training 1``, ... and ``held-out 1``, ...
    settings : DetectionSettings, optional
        ``k``, ``persistence`` and ``window`` of the detection (defaults: the library's); a fixed ``margin``
        replaces the training margins.  ``calibrate`` does not apply: every training record is healthy
        from end to end.
    lags : int
        Lags of the whiteness test.

    Returns
    -------
    ModelValidation

    Raises
    ------
    SettingError
        No training or no held-out record, ``calibrate`` given, or ``lags`` below 1.
    """
    settings = settings or DetectionSettings()
    training, held_out = _named(training, "training"), _named(held_out, "held-out")
    before = held_out_figures(datasheet, training, held_out, settings, lags=lags)
    after = held_out_figures(calibrated, training, held_out, settings, lags=lags)
    return ModelValidation(list(training), list(held_out), before, after, settings, lags)


def held_out_figures(model, training, held_out, settings: DetectionSettings | None = None, *,
                     lags: int = LAGS) -> ModelFigures:
    """One model's false alarms, detectable changes and residual whiteness on ``held_out``, with margins
    calibrated on ``training`` (see the module docstring; the arguments as for :func:`validate_calibration`)."""
    settings = settings or DetectionSettings()
    if settings.calibrate is not None:
        raise SettingError("calibrate", "{setting} does not apply to a validation: the margins are calibrated on "
                                        "whole training records, each healthy from end to end")
    if isinstance(lags, bool) or int(lags) != lags or lags < 1:
        raise SettingError("lags", f"{{setting}} must be a whole number >= 1, got {lags!r}")
    training, held_out = _named(training, "training"), _named(held_out, "held-out")
    for what, records in (("training", training), ("held_out", held_out)):
        if not records:
            raise SettingError(what, "{setting}: at least one record is needed")
    figures = ModelFigures(alarms={name: {} for name in held_out}, changes={name: {} for name in held_out})
    for arr in derive_arrs(model):
        window = (settings.window or default_window(max(3, arr.order))) if arr.order else None
        margin = settings.margin if settings.margin is not None else _training_margin(model, arr, training,
                                                                                       settings, window)
        if margin is None:
            figures.undecided[arr.name] = "no training record gives it a residual"
            continue
        residuals = _held_out(model, arr, held_out, settings, window, margin, figures)
        if not residuals:
            figures.undecided[arr.name] = "no held-out record gives it a residual"
            continue
        figures.margins[arr.name], figures.windows[arr.name] = margin, window
        figures.whiteness[arr.name] = residual_whiteness(residuals, spacing=window or 1, lags=int(lags),
                                                         arr=arr.name)
    return figures


def _training_margin(model, arr, training: Mapping, settings: DetectionSettings, window: int | None) -> float | None:
    """The margin that keeps every training record quiet after its start-up, and at least ``k`` robust standard
    deviations of its residual; None when no training record can evaluate the ARR."""
    margins = []
    bare = DetectionSettings(margin=0.0, k=settings.k, persistence=settings.persistence, window=window)
    for record in training.values():
        found = detect(model, record, bare, arrs=[arr])
        if not found.evaluations:
            continue
        evaluation = found.evaluations[0]
        margins.append(max(settings.k * robust_std(evaluation.residual),
                           SAFETY * quiet_margin(evaluation, after=_start_up(record))))
    return float(max(margins)) if margins else None


def _held_out(model, arr, held_out: Mapping, settings: DetectionSettings, window: int | None, margin: float,
              figures: ModelFigures) -> list:
    """Detect with ``margin`` on each held-out record: its alarms and detectable changes go into ``figures``;
    the residuals are returned (for the whiteness test)."""
    fixed = DetectionSettings(margin=margin, k=settings.k, persistence=settings.persistence, window=window)
    residuals = []
    for name, record in held_out.items():
        found = detect(model, record, fixed, arrs=[arr])
        if not found.evaluations:
            continue
        evaluation = found.evaluations[0]
        late = evaluation.alarm & (evaluation.t > _start_up(record))
        if late.any():
            figures.alarms[name][arr.name] = float(evaluation.t[np.argmax(late)])
        for parameter, change in found.smallest_changes.items():
            figures.changes[name][parameter] = min(figures.changes[name].get(parameter, math.inf), change)
        residuals.append(evaluation.residual)
    return residuals


def _start_up(record: Record) -> float:
    """The end of a record's start-up, where no margin is asked to hold (as on a calibration stretch)."""
    return float(record.t[0] + START_SHARE * (record.t[-1] - record.t[0]))


def _named(records, prefix: str) -> dict:
    if isinstance(records, Mapping):
        return {str(name): as_record(record) for name, record in records.items()}
    return {f"{prefix} {k}": as_record(record) for k, record in enumerate(records, start=1)}


# ------------------------------------------------------------------------------------------- whiteness

def residual_whiteness(residuals: Sequence[np.ndarray], *, spacing: int = 1, lags: int = LAGS,
                       arr: str = "") -> Whiteness:
    """The autocorrelation and Ljung-Box test of residuals taken every ``spacing`` samples, pooled over records.

    Each record's residual is thinned to every ``spacing``-th sample and its mean removed; the autocorrelation
    at lag ``k`` sums the products of values ``k`` apart within each record, where both are finite, over the
    sum of squares.  ``n`` is the number of finite values over all records.

    >>> rng = np.random.default_rng(0)
    >>> noise = residual_whiteness([rng.normal(size=2000)], lags=5)
    >>> noise.white, abs(noise.autocorrelation[0]) < 0.1
    (True, True)
    >>> walk = residual_whiteness([np.cumsum(rng.normal(size=2000))], lags=5)
    >>> walk.white, walk.autocorrelation[0] > 0.9
    (False, True)
    """
    spacing = max(int(spacing), 1)
    thinned = []
    for residual in residuals:
        x = np.asarray(residual, float)[::spacing]
        finite = np.isfinite(x)
        if finite.any():
            thinned.append(np.where(finite, x - x[finite].mean(), np.nan))
    n = int(sum(np.isfinite(x).sum() for x in thinned))
    energy = float(sum(np.nansum(x * x) for x in thinned))
    if n <= lags + 1 or energy <= 0:
        return Whiteness(arr, [math.nan] * lags, math.nan, math.nan, n, spacing)
    rho = []
    for lag in range(1, lags + 1):
        products = [np.nansum(x[lag:] * x[:-lag]) for x in thinned if x.size > lag]
        rho.append(float(sum(products) / energy))
    statistic = float(n * (n + 2) * sum(r * r / (n - k) for k, r in enumerate(rho, start=1)))
    return Whiteness(arr, rho, statistic, float(stats.chi2.sf(statistic, lags)), n, spacing)


def _finite(value) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None
