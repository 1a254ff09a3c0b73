"""The whole prognosis of one record, as ``bgphm prognose`` runs it: calibrate, detect, isolate, predict.

:func:`prognose` takes the ARRs, a record and the failure values, and decides everything else from
the record and :class:`PrognosisSettings`: the healthy stretch and its check, each residual's margin
and noise (:func:`diagnosis.calibration.calibrate`), the filter step (one derivative window of
samples, :func:`filter_step`), the RUL horizon and its memory bound; then
:class:`~prognosis.isolation.IsolatingMonitor` weighs the candidates and laws from the first alarm.
A setting that does not fit the record raises a :class:`~bondgraph.errors.SettingError` naming it.

>>> import numpy as np
>>> from bondgraph.library import rlc_circuit
>>> from bondgraph.scenarios import drift, rlc_record
>>> from diagnosis import add_noise, derive_arrs
>>> from prognosis.isolation import IsolationSettings
>>> bg = rlc_circuit()
>>> run = rlc_record(np.linspace(0.0, 3.0, 3001), {"R": drift(10.0, 4.0, onset=1.0)})
>>> record = add_noise(run, {"i": 1e-4}, seed=0)
>>> settings = PrognosisSettings(detection=DetectionSettings(calibrate=0.8),
...                              isolation=IsolationSettings(laws=("linear",), n_particles=100, sensors=False))
>>> result = prognose(derive_arrs(bg), record, {"R": 20.0}, settings)
>>> result.decision.candidate, result.settings["filter_step"]
('R', 0.011)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from bondgraph.errors import SettingError
from diagnosis.calibration import DetectionSettings, calibrate
from diagnosis.derivatives import default_window
from diagnosis.records import Record, as_record

from .errors import PrognosisError
from .isolation import HORIZON_STEPS, LAWS, IsolatingMonitor, IsolationResult, IsolationSettings
from .rul import check_horizon

__all__ = ["PrognosisSettings", "check_candidate", "check_failures", "filter_step", "prognose",
           "rul_horizon"]

@dataclass(frozen=True)
class PrognosisSettings:
    """The settings of :func:`prognose`: one settings object per stage, each checked when made.

    Parameters
    ----------
    detection : DetectionSettings
        The healthy stretch, margins and persistence (:mod:`diagnosis.calibration`).
    isolation : IsolationSettings
        How candidates and laws are weighed (:class:`~prognosis.isolation.IsolationSettings`, as
        :class:`~prognosis.isolation.IsolatingMonitor` and :class:`~prognosis.fleet.FleetMonitor` take
        them).  Left None, its ``dt`` is chosen from the record (:func:`filter_step`) and its
        ``horizon`` is :data:`~prognosis.isolation.HORIZON_STEPS` filter steps, checked against the
        memory the RUL predictors would hold (:func:`rul_horizon`).

    >>> PrognosisSettings(isolation=IsolationSettings(n_particles=1))
    Traceback (most recent call last):
    ...
    bondgraph.errors.SettingError: n_particles must be a whole number in [2, 100000], got 1
    """

    detection: DetectionSettings = field(default_factory=DetectionSettings)
    isolation: IsolationSettings = field(default_factory=IsolationSettings)

    def __post_init__(self) -> None:
        for name, kind in (("detection", DetectionSettings), ("isolation", IsolationSettings)):
            if not isinstance(getattr(self, name), kind):
                raise SettingError(name, f"{{setting}} must be a {kind.__name__}, got a "
                                         f"{type(getattr(self, name)).__name__}")


def filter_step(record: Record, window: int | None = None, dt: float | None = None) -> float:
    """The filter step: ``dt``, by default one derivative window of samples, checked against the record.

    One filter step per derivative window: the residuals it reads are then nearly independent.
    Raises a :class:`~bondgraph.errors.SettingError` (``dt``) for a step not shorter than the record
    or not a multiple of its sampling step.

    >>> filter_step(Record(np.arange(0.0, 10.0, 0.01), {}))
    0.11
    """
    step = float(np.median(np.diff(record.t)))
    chosen = dt if dt is not None else float(f"{step * (window or default_window(3)):.12g}")
    span = float(record.t[-1] - record.t[0])
    if chosen >= span:
        raise SettingError("dt", f"{{setting}} {chosen:g}: the filter step is not shorter than the record ({span:g} s)")
    if dt is not None and abs(round(dt / step) * step - dt) > 1e-6 * dt:
        raise SettingError("dt", f"{{setting}} {dt:g}: the filter step must be a multiple of the record's step "
                                 f"{step:g} s")
    return chosen


def check_failures(failures: Mapping[str, float], parameters: Mapping[str, float],
                   domains: Mapping[str, tuple] | None = None, laws: Sequence[str] = LAWS) -> None:
    """Each failure value inside its parameter's physical domain, not its nominal value, and of the nominal's
    sign when the only law is exponential (which keeps the sign); a :class:`~bondgraph.errors.SettingError`
    (``failures``) naming the parameter.

    >>> check_failures({"b": -1.0}, {"b": 1e-4}, {"b": (0.0, float("inf"))})
    Traceback (most recent call last):
    ...
    bondgraph.errors.SettingError: failures b=-1: outside the physical domain (0, inf) the model declares for 'b'
    """
    for name, value in failures.items():
        if name not in parameters:
            raise SettingError("failures", f"{{setting}} {name}={value:g}: the model has no parameter {name!r} "
                                           f"(parameters: {', '.join(parameters)})")
        lo, hi = (domains or {}).get(name, (-math.inf, math.inf))
        if not lo <= value <= hi:
            raise SettingError("failures", f"{{setting}} {name}={value:g}: outside the physical domain ({lo:g}, "
                                           f"{hi:g}) the model declares for {name!r}")
        if value == parameters[name]:
            raise SettingError("failures", f"{{setting}} {name}={value:g} equals the nominal value of {name!r}: the "
                                           "failure value must differ from it")
        if list(laws) == ["exponential"] and value * parameters[name] <= 0:
            raise SettingError("failures", f"{{setting}} {name}={value:g}: an exponential degradation keeps the sign "
                                           f"of {name!r} (nominal {parameters[name]:g}); the failure value must have "
                                           "the same sign")


def check_candidate(candidate: str, arrs: Sequence, failures: Mapping[str, float],
                    direction: str | None = None) -> str:
    """A named candidate that some ARR is sensitive to, with a failure value on the ``direction`` side of its
    nominal value (when given); returns the direction.  A :class:`~bondgraph.errors.SettingError` names what
    is wrong (``candidates``, ``failures`` or ``direction``)."""
    from diagnosis import signature_matrix

    if not any(candidate in a.parameters for a in arrs):
        rows = signature_matrix(arrs)
        raise SettingError("candidates", f"{{setting}} {candidate!r}: no ARR is sensitive to it, so it cannot be "
                                         f"monitored (detectable parameters: "
                                         f"{[r for r, d in zip(rows.rows, rows.detectable) if d]})")
    if candidate not in failures:
        raise SettingError("candidates", f"{{setting}} {candidate!r}: give its failure value ({{setting:failures}} "
                                         f"{candidate}=VALUE)")
    nominal = next(a.values[candidate] for a in arrs if candidate in a.parameters)
    inferred = "up" if failures[candidate] > nominal else "down"
    if direction is not None and direction != inferred:
        side = "above" if inferred == "up" else "below"
        raise SettingError("direction", f"{{setting:failures}} {failures[candidate]:g} is on the wrong side of the "
                                        f"nominal value {nominal:g} of {candidate!r} for {{setting}} {direction}: it "
                                        f"lies {side} nominal; give {{setting}} {inferred} (or leave {{setting}} out: "
                                        f"it follows from the failure value)")
    return inferred


def rul_horizon(dt: float, horizon: float | None, particles: int, hypotheses: int) -> float:
    """The RUL horizon (s): ``horizon``, by default :data:`~prognosis.isolation.HORIZON_STEPS` filter steps,
    within the predictors' limits (:func:`~prognosis.rul.check_horizon`) before any filter runs.

    >>> rul_horizon(0.1, None, 500, 2)
    200.0
    """
    chosen = horizon if horizon is not None else HORIZON_STEPS * dt
    try:
        check_horizon(chosen, dt, particles=particles, predictors=hypotheses)
    except PrognosisError as exc:
        raise SettingError("horizon", f"{{setting}} {chosen:g}: {exc} (particles {particles}, {hypotheses} "
                                      "hypotheses)") from None
    return chosen


def prognose(arrs: Sequence, record, failures: Mapping[str, float], settings: PrognosisSettings | None = None, *,
             domains: Mapping[str, tuple] | None = None,
             progress: Callable[[int, int, float], None] | None = None) -> IsolationResult:
    """Calibrate on the healthy stretch, detect, weigh the candidates and laws, predict the RUL.

    Parameters
    ----------
    arrs : sequence of ARR
    record : mapping, DataFrame or Record
        ``t`` and the ARRs' signals.
    failures : mapping
        Failure value of each parameter that can fail.
    settings : PrognosisSettings, optional
    domains : mapping, optional
        The model's physical domains (:attr:`bondgraph.BondGraph.domains`).
    progress : callable, optional
        ``progress(done, total, t)`` during the filter (:meth:`IsolatingMonitor.run`).

    Returns
    -------
    IsolationResult
        With ``settings``: what the run decided from the record (``calibration_end``,
        ``filter_step``, ``horizon``, ``residual_noise_std``, ``margins``, ``undecided``: the ARRs the
        healthy stretch gave no residual for, left out, and ``pairs``: whether two faults at once were
        weighed, and why) beside the settings given.

    Notes
    -----
    With ``settings.isolation.pairs`` None (the default), single faults are weighed first; when none
    explains the residuals at the end (:attr:`~prognosis.isolation.IsolationResult.contradicted`), or
    no single parameter sees every ARR fired (:attr:`~prognosis.isolation.IsolationResult.wearless`:
    alone, only a sensor's fault could explain them), the record is run again with two parameters
    degrading at once among the hypotheses, and that run is the answer.
    """
    settings = settings or PrognosisSettings()
    chosen = settings.isolation
    arrs = list(arrs)
    check_failures(failures, {p: a.values[p] for a in arrs for p in a.parameters}, domains,
                   list(chosen.law_models))
    record = as_record(record, list(dict.fromkeys(s for a in arrs for s in a.signals)))
    detection = settings.detection
    healthy = calibrate(arrs, record, detection)
    arrs = [arr for arr in arrs if arr.name not in healthy.undecided]   # no residual to weigh: left out, named
    dt = filter_step(record, detection.window, chosen.dt)
    horizon = rul_horizon(dt, chosen.horizon, chosen.n_particles, len(failures) * len(chosen.laws))

    def run(pairs: bool | None) -> IsolationResult:
        monitor = IsolatingMonitor(arrs, failures, noise_std=healthy.noise_std,
                                   settings=chosen.changed(dt=dt, horizon=horizon, pairs=pairs),
                                   detection=healthy.options(detection), healthy_until=healthy.until, domains=domains)
        return monitor.run(record, evaluations=healthy.evaluations, progress=progress)

    result = run(chosen.pairs)
    pairs = "weighed from the first alarm" if chosen.pairs else "not weighed"
    why = ("no single fault explained the residuals" if result.contradicted else
           "no single parameter sees every ARR fired" if result.wearless else None)
    if chosen.pairs is None and chosen.pairs_possible and why:
        # two at once compete, on the whole record from the alarm (their cost is paid only here; a single
        # fault weighed with them is not called two, isolation.held_back)
        result = run(True)
        pairs = f"weighed: {why}"
    result.settings = {"failure_values": dict(failures), "calibration_end": healthy.until, "filter_step": dt,
                       "horizon": horizon, "filter": chosen.method, "particles_per_hypothesis": chosen.n_particles,
                       "residual_noise_std": dict(healthy.noise_std), "margins": dict(healthy.margin),
                       "undecided": dict(healthy.undecided), "pairs": pairs,
                       "seed": chosen.seed if isinstance(chosen.seed, int) else str(chosen.seed)}
    return result
