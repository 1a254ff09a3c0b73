"""Detection on a record, with the defaults a user's model needs: every choice made from the data.

:func:`detect` is the pipeline behind ``bgphm detect``:

1. **Forms from the record.** Each ARR is tried in its differentiated form with several derivative
   windows (:data:`WINDOWS`) and, when its relation holds integrals, in integral form; each
   candidate's margin is calibrated on the fault-free stretch (``k`` robust standard deviations of
   the residual, and at least :data:`SAFETY` times the margin that keeps that stretch, but for its
   start, free of alarms: a derivative estimate's bias at a transient is not noise) and the form
   that detects the smallest parameter changes after that stretch (:mod:`diagnosis.detectability`) is
   kept. An integral form is kept only where every differentiated form is blind: an integral of
   measured noise is a random walk, so its margin is widened by ``(record span / calibration span)
   ** (n - 1/2)`` for an ``n``-fold integral (how the spread of integrated white noise grows).
2. **Steps of the inputs** are found in the record and the samples whose derivative estimates reach
   across them are left undecided (:mod:`diagnosis.steps`).  An alarm needs ``persistence`` violations
   in a row and, for an ARR that estimates derivatives, at least half the derivative window:
   neighbouring estimates share most of their samples, so a shorter run is a single piece of evidence
   (a burst of estimator bias where the signals ring after a step, say).
3. **Detectability**: per ARR and parameter, the smallest relative change detected at its margin; an
   ARR that sees no change below 100 % is reported blind, with the reason.
4. **Isolation**: the faults (parameters and sensors) consistent with the ARRs that fired: every
   fired ARR whose alarm is sustained (not a lone burst at a transient) is sensitive to them. An ARR
   that did not fire exonerates nothing (a sensitive ARR may still be blind to a small change), so
   the list is the faults that explain every alarm.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .derivation import derive_arrs
from .detectability import Detectability, detectability, summary
from .calibration import (SAFETY, START_SHARE, DetectionSettings, calibration_end, check_healthy,
                          quiet_margin)
from .detection import CalibrationError, Evaluation, noise_margin
from .residuals import integral_depth as _integral_depth
from .signatures import SignatureMatrix, signature_matrix
from .structural import sensor_fault
from .derivatives import default_window
from .records import Record, RecordWarning, as_record, has_column

__all__ = ["SAFETY", "WINDOWS", "Detection", "consistent_faults", "detect", "quiet_margin"]

#: Derivative windows tried for each differentiated ARR (Savitzky-Golay samples; None is the default 11),
#: those up to a tenth of the calibration stretch.
WINDOWS = (None, 21, 41, 81, 161)
#: A fired ARR takes part in isolation when its alarms last this many times ``persistence`` samples in all.
SUSTAINED = 3
STEPS_IN_SENSORS = True


@dataclass
class Detection:
    """The outcome of :func:`detect`.

    Attributes
    ----------
    evaluations : list of Evaluation
        One per ARR, in the chosen form, over the whole record.
    forms : dict
        ARR name -> ``{"form": ..., "window": ...}``, what was chosen and why (``"reason"``).
    detectability : dict
        ARR name -> :class:`~diagnosis.detectability.Detectability`: over the record, at the margin
        calibrated on its fault-free stretch.
    signatures : SignatureMatrix
        Of the ARRs used.
    fired : list of str
        ARRs in alarm after the calibration stretch.
    candidates : list of str
        Faults consistent with the ARRs in ``isolating`` (empty when nothing fired).
    calibration_end : float
    undecided : dict
        ARR name -> why the record cannot evaluate it in any form (it is left out, not guessed).
    steps : list of str
        The record columns whose steps were looked for (inputs and sensors).
    isolating : list of str
        The fired ARRs whose alarms last at least :data:`SUSTAINED` times ``persistence`` samples (all of
        ``fired`` if none does): ``candidates`` must explain these.
    """

    evaluations: list
    forms: dict
    detectability: dict
    signatures: SignatureMatrix
    fired: list
    candidates: list
    calibration_end: float
    arrs: list = field(default_factory=list, repr=False)
    undecided: dict = field(default_factory=dict)
    steps: list = field(default_factory=list)
    isolating: list = field(default_factory=list)

    @property
    def detection_time(self) -> float | None:
        """The first alarm after the calibration stretch, or None."""
        times = [_first_alarm(e, self.calibration_end) for e in self.evaluations]
        times = [t for t in times if t is not None]
        return min(times) if times else None

    @property
    def smallest_changes(self) -> dict:
        """Parameter -> the smallest relative change (whichever sign) any of the ARRs detects."""
        return summary(self.detectability)

    @property
    def blind(self) -> list:
        """The ARRs that detect no parameter change below 100 % on this record."""
        return [name for name, d in self.detectability.items() if d.blind]

    def as_dict(self) -> dict:
        """Plain data for JSON."""
        return {"detection_time": self.detection_time, "calibration_end": self.calibration_end,
                "fired": list(self.fired), "isolating": list(self.isolating), "candidates": list(self.candidates),
                "blind": self.blind,
                "undecided": dict(self.undecided),
                "forms": self.forms, "detectability": {k: d.as_dict() for k, d in self.detectability.items()}}


def detect(bg, record, settings: DetectionSettings | None = None, *, integrals: str = "auto",
           arrs: Sequence | None = None, steps: bool = True) -> Detection:
    """Evaluate the ARRs of ``bg`` on ``record`` with forms, margins and masks chosen from the record.

    Parameters
    ----------
    bg : BondGraph
    record : mapping, DataFrame or Record
    settings : DetectionSettings, optional
        The healthy stretch (``calibrate``, default the first 20 % of the record), a fixed
        ``margin`` for every ARR instead of the calibrated ones, ``k`` and ``persistence``, a fixed
        derivative ``window`` (no choice among :data:`WINDOWS`).  With calibrated margins, the
        stretch is checked to hold no fault (:func:`~diagnosis.calibration.check_healthy`): a
        :class:`~bondgraph.errors.SettingError` names the ARR in alarm there.
    integrals : {"auto", "avoid", "keep"}
        ``"auto"`` chooses per ARR (see the module), the others force the form for every ARR.
    arrs : sequence of ARR, optional
        The ARRs to evaluate (default: :func:`derive_arrs` of ``bg`` with ``integrals``).
    steps : bool
        Leave undecided the samples whose derivative estimates reach across a step of a model input.

    Examples
    --------
    >>> from bondgraph import simulate
    >>> from bondgraph.library import rlc_circuit
    >>> bg = rlc_circuit()
    >>> t = np.linspace(0.0, 2.0, 2001)
    >>> run = simulate(bg, (0.0, 2.0), {"V": lambda t: np.sin(20 * t)}, t_eval=t,
    ...                parameters={"R": lambda t: 10.0 if t < 1.0 else 14.0}).record()
    >>> result = detect(bg, run, DetectionSettings(calibrate=0.8, margin=1e-3))
    >>> result.fired, result.candidates[:2]
    (['ARR_J1'], ['R', 'L'])
    """
    if integrals not in ("auto", "avoid", "keep"):
        raise ValueError(f"option integrals: {integrals!r} is not one of auto, avoid, keep")
    settings = settings or DetectionSettings()
    calibrate, margin, k, persistence, window = (settings.calibrate, settings.margin, settings.k,
                                                 settings.persistence, settings.window)
    inputs = list(bg.inputs)
    given = arrs is not None
    first = list(arrs) if given else derive_arrs(bg, integrals="avoid" if integrals == "auto" else integrals)
    names = list(dict.fromkeys(s for arr in first for s in arr.signals))
    data = as_record(record, names + [n for n in inputs if has_column(record, n) and n not in names])
    until = calibration_end(data, calibrate, hint=" (or give a fixed {setting:margin})", checked=margin is None)
    healthy = data.between(end=until)
    kept = {"avoid": {a.name: a for a in first}}
    if integrals == "auto" and not given:
        kept["keep"] = {a.name: a for a in derive_arrs(bg, integrals="keep")}
    watched = inputs + list(bg.outputs) if STEPS_IN_SENSORS else inputs
    step_inputs = [n for n in watched if n in data.columns] if steps else False
    evaluations, forms, seen, used, undecided = [], {}, {}, [], {}
    for arr in first:
        candidates = [kept[form][arr.name] for form in kept if arr.name in kept[form]]
        chosen, options, d, evaluation, reason = _choose(candidates, healthy, data, until, margin, k, persistence,
                                                         window, step_inputs)
        if chosen is None:
            undecided[arr.name] = reason.removeprefix("undecided: ")
            continue
        if margin is None:  # a calibrated margin: the stretch must hold no fault
            check_healthy(chosen, data, evaluation, until, settings,
                          {"persistence": persistence, "steps": step_inputs, "ends": True,
                           **({"window": options["window"]} if options.get("window") else {})})
        evaluations.append(evaluation)
        forms[arr.name] = {"form": chosen.form, "window": options.get("window"), "margin": options["margin"],
                           "reason": reason}
        seen[arr.name] = d
        used.append(chosen)
    # every parameter can fail, law constants included (a gas precharge, a cubic stiffness), and every sensor
    rows = list(bg.parameters) + [sensor_fault(s) for s in bg.outputs]
    signatures = signature_matrix(used, rows=rows)
    fired = [e.name for e in evaluations if _first_alarm(e, until) is not None]
    # isolation reads the sustained alarms: a lone burst (a transient's estimator bias) would exclude the
    # true fault, whereas leaving a fired ARR out only widens the consistent set (nothing is exonerated)
    sustained = [e.name for e in evaluations if e.name in fired
                 and int(np.count_nonzero(e.alarm & (e.t > until))) >= SUSTAINED * e.persistence]
    isolating = sustained or fired
    return Detection(evaluations, forms, seen, signatures, fired, consistent_faults(signatures, isolating), until,
                     used, undecided, list(step_inputs or []), isolating)


def consistent_faults(signatures: SignatureMatrix, fired: Sequence[str]) -> list:
    """The faults whose signature holds every fired ARR: exact matches first, then the others.

    >>> from bondgraph.library import dc_motor
    >>> from diagnosis import derive_arrs
    >>> consistent_faults(signature_matrix(derive_arrs(dc_motor())), ["ARR_1_m"])
    ['J', 'b', 'k_m', 'sensor i', 'sensor omega']
    """
    if not fired:
        return []
    columns = [signatures.columns.index(name) for name in fired]
    exact, wider = [], []
    for row, name in zip(signatures.matrix, signatures.rows):
        if all(row[c] for c in columns):
            (exact if int(row.sum()) == len(columns) else wider).append(name)
    return exact + wider


def _choose(candidates, healthy: Record, data: Record, until: float, margin, k, persistence, window, steps):
    """``(arr, options, detectability, evaluation, reason)``: the form that sees the smallest changes.

    Margins come from ``healthy``; the detectable changes are read over the whole record ``data``.  A
    form the record cannot calibrate (a derivative estimate undecided everywhere, say) is passed over;
    when every form is, the result is ``(None, ..., reason)``.
    """
    trials, failures = [], []
    for arr in candidates:
        windows = [window] if window is not None or arr.order == 0 else [
            w for w in WINDOWS if w is None or w <= len(healthy) // 10]
        for w in windows:
            polyorder = {"polyorder": arr.order} if arr.order > 3 else {}  # Savitzky-Golay: at least the order
            options = {"persistence": _persistence(arr, persistence, w, polyorder), "steps": steps, "ends": True,
                       **({"window": w} if w else {}), **polyorder}
            try:
                trials.append(_trial(arr, options, healthy, data, margin, k))
            except CalibrationError as exc:
                failures.append(str(exc).removeprefix(f"{arr.name}: "))
    if not trials:
        return None, {}, None, None, f"undecided: {failures[0]}"
    if len(trials) == 1:
        return (*trials[0], "the only form")
    differentiated = [t for t in trials if not t[0].integrals]
    pool = [t for t in differentiated if not t[2].blind] or trials
    arr, options, d, evaluation = min(pool, key=lambda t: _score(t[2]))
    reason = "sees the smallest changes on this record"
    if arr.integrals and differentiated:
        reason = "every differentiated form is blind on this record"
    return arr, options, d, evaluation, reason


def _persistence(arr, persistence: int, window: int | None, polyorder: dict) -> int:
    """``persistence`` violations in a row, and at least half the derivative window for an ARR that estimates
    derivatives: neighbouring estimates share most of their window, so a shorter run is one piece of evidence
    (a burst of estimator bias where the signals bend, not a fault)."""
    if arr.order == 0:
        return persistence
    return max(persistence, (window or default_window(polyorder.get("polyorder", 3))) // 2)


def _trial(arr, options: dict, healthy: Record, data: Record, margin, k) -> tuple:
    """``(arr, options with the margin, detectability, evaluation)`` of one form of an ARR."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RecordWarning)
        m = margin if margin is not None else noise_margin(arr, healthy, k=k, **options)
        if margin is None:
            start = float(healthy.t[0] + START_SHARE * (healthy.t[-1] - healthy.t[0]))
            m = max(m, SAFETY * quiet_margin(arr.evaluate(healthy, **options), after=start))
        if margin is None and arr.integrals:
            m *= (_span(data) / max(_span(healthy), 1e-300)) ** (_integral_depth(arr.nominal) - 0.5)
        evaluation = arr.evaluate(data, margin=m, **options)
    # what a change would show over the monitored stretch (its excitation), at the healthy stretch's margin
    return arr, {**options, "margin": float(m)}, detectability(evaluation, arr, after=healthy.t[-1]), evaluation


def _score(d: Detectability) -> float:
    """The geometric mean of the detectable changes (capped at 1e6 so an invisible parameter counts, finitely)."""
    changes = [min(d.change(p), 1e6) for p in d.rise] or [1e6]
    return float(np.exp(np.mean(np.log(np.maximum(changes, 1e-12)))))


def _first_alarm(evaluation: Evaluation, after: float) -> float | None:
    late = evaluation.alarm & (evaluation.t > after)
    return float(evaluation.t[np.argmax(late)]) if late.any() else None


def _span(data: Record) -> float:
    return float(data.t[-1] - data.t[0])
