"""Set-membership uncertainty boxes: the smallest boxes in which every healthy record stays inside the thresholds.

The threshold of an ARR is the range of its uncertain part Psi_2 over the box of each parameter
(:func:`~diagnosis.thresholds.interval_threshold`).  In the BG-LFT form Psi_2 is ``sum_p delta_p g_p(t)``,
one term per parameter, with a sensitivity ``g_p`` that depends on the signals alone, so over a box
``delta_p in [-a_p, b_p]`` the band is exactly (up to outward rounding)

    B_hi = sum_p  b_p g_p+ + a_p g_p-,        B_lo = -sum_p  a_p g_p+ + b_p g_p-,

with ``g+ = max(g, 0)`` and ``g- = max(-g, 0)``; a symmetric box (``a_p = b_p = h_p``) gives the BG-LFT band
``+-sum_p h_p |g_p|``.  The band tells the two sides of a box apart (a friction that only rises widens the
band on one side only), so each parameter has two unknowns, ``a_p`` and ``b_p``, and the band is linear in
them.  :func:`~diagnosis.detect` finds a sample in violation when ``-r_n`` leaves ``[B_lo - m, B_hi + m]``
(``m`` the noise margin): keeping a record inside is, sample by sample, a linear inequality in the half-widths,
and the smallest box is a linear program.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import sympy as sp
from scipy.optimize import linprog

from bondgraph.errors import SettingError

from ._revalued import revalued
from .calibration import START_SHARE, DetectionSettings, calibration_end
from .deltas import delta, delta_parameter
from .derivation import derive_arrs
from .derivatives import default_window
from .detection import CalibrationError, check_closed_form, noise_margin, persistent
from .intervals import affine_range, compile_interval
from .monitoring import STEPS_IN_SENSORS, WINDOWS
from .records import Record, as_record, has_column
from .residuals import integral_depth

__all__ = ["set_membership_boxes"]

#: The lower end of a box stays this far above -1: ``value * (1 + delta)`` must not reach zero (the model refuses
#: ``lo <= -1``: a law solved for its other variable divides by it).
EDGE = 1e-6
#: The solution is widened by this share: the linear program meets its constraints to a tolerance of about 1e-7
#: of each one, and the box must keep every sample inside, not nearly inside.
SLACK = 1e-6


def set_membership_boxes(bg, records: Sequence, parameters: Sequence[str], *, arrs: Sequence | None = None,
                         settings: DetectionSettings | None = None) -> dict:
    """Parameter -> (lo, hi): the smallest multiplicative boxes about bg's values in which every healthy record
    stays inside the robust thresholds.

    The boxes are the solution of a linear program (scipy's HiGHS):

    * **unknowns**: each sized parameter's relative half-widths below and above its value, ``a_p = -lo`` and
      ``b_p = hi`` (both >= 0, since a box holds 0);
    * **objective**: minimize ``sum_p w_p (a_p + b_p)`` with ``w_p = 1 + W_p``.  A box costs its own size and
      what it blunts.  Its size: the half-widths are relative (an absolute half-width over the parameter's
      value), so 10 % of an inductance in H counts as 10 % of a resistance in Ohm.  What it blunts: ``W_p`` is
      the sum over the ARRs holding ``p`` of the mean over their counted samples of ``|g_p| / m``, the widening
      of the thresholds, in noise margins, that a relative half-width of 1 causes on average.  In the DC motor
      10 % of the motor constant widens the electrical ARR's threshold by some twenty margins, 10 % of the
      friction the mechanical one's by a third of one: by size alone the box would go to the motor constant
      (the largest relative sensitivity) and blunt the electrical ARR; by blunting alone it would go to a
      parameter the records see only through noise (an inductance at a steady current), cheap in band at a
      size of hundreds of percent that means nothing;
    * **constraints**: at every counted sample of every record, for every ARR whose uncertain part holds a sized
      parameter, ``-r_n`` lies in ``[B_lo - m, B_hi + m]``, ``B`` the band above with the sized boxes unknown and
      every other parameter's box as the model (or ``arrs``) declares it.  Only the binding side of a sample is
      kept, and only where the other boxes and the margin alone do not hold it;
    * **bounds**: ``a_p <= 1 - EDGE`` (the value stays off zero) and the parameter's domain
      (:attr:`BondGraph.domains`).

    The **margin** ``m`` is the noise margin :func:`~diagnosis.detect` calibrates on that record: ``k`` robust
    standard deviations of the residual on its healthy stretch, for the same form and derivative window (or
    ``settings.margin`` when fixed, and widened as :func:`~diagnosis.detect` widens it for an ARR holding
    integrals).  The detection's margin is at least that; the rest of it (a multiple of the margin that keeps the
    stretch quiet) depends on the box itself and would absorb whatever the box leaves out, so it does not count:
    what is not noise must be explained by the box.  Where :func:`~diagnosis.detect` would choose the derivative
    window (``settings.window`` unset), every window it may choose on that record is constrained, so the box
    holds whichever it picks.

    The **counted samples** are those :func:`~diagnosis.detect` decides: not the undecided ones near a step of an
    input or a sensor, near either end of the record, or in a gap, and not the start-up (the first
    ``START_SHARE`` of the healthy stretch, which the detection's margin leaves out too).  The rest of the healthy
    stretch counts, although no alarm is raised there: kept inside at the noise margin, it keeps the margin
    :func:`~diagnosis.detect` calibrates within ``SAFETY`` times the noise margin, instead of letting it grow to
    hold the model's error.  An alarm needs violations on as many samples in a row as the form's persistence
    (``settings.persistence``, and at least half the derivative window), and a box can only shorten a run of
    samples outside the band: a sample outside it with the sized boxes at 0 sets a constraint only if it lies in
    a run of that many such samples (a lone burst of noise sizes no box).  Every sample of such a run must stay
    inside, where the detection's rule needs one of every ``persistence`` of them: the boxes are sufficient for the
    rule and a little wider than the smallest it allows (which is no linear program).

    A side of a box no sample needs is 0, and a parameter no sample needs gets ``(0.0, 0.0)`` (the model accepts
    it: a box must hold 0, nothing more): the boxes are the smallest the records allow, and anything wider only
    blunts detection in that direction.  What the records did not show (another operating point) they cannot
    size; a record's own noise is its calibrated margin's to cover, not the box's.

    Parameters
    ----------
    bg : BondGraph
        The model, typically calibrated (:meth:`ParameterEstimate.model <diagnosis.ParameterEstimate.model>`).
    records : sequence of Record, mapping or DataFrame
        Healthy records (:func:`~diagnosis.as_record`).
    parameters : sequence of str
        The parameters whose boxes are sized; the others keep the boxes the model declares.
    arrs : sequence of ARR, optional
        The ARRs the detection will use (default :func:`~diagnosis.derive_arrs` of ``bg``, with a box of 0 for a
        sized parameter that declares none, so that its uncertainty has a term).
    settings : DetectionSettings, optional
        As given to :func:`~diagnosis.detect`: the healthy stretch, ``k`` or a fixed margin, a fixed window.

    Returns
    -------
    dict
        Parameter -> ``(lo, hi)``, ``lo <= 0 <= hi``, for ``uncertainty=`` of the model's elements.

    Raises
    ------
    SettingError
        A parameter the model lacks or no ARR holds (or holds other than linearly in its uncertainty), no record,
        no counted sample, or a sample no box of ``parameters`` within their domains keeps inside (the message
        names the ARR, the record and the time).

    Examples
    --------
    A motor whose model has the friction 20 % low, run at 3 V over the healthy stretch and at 12 V after it: the
    box of b opens upwards only, by about the 25 % the truth needs less what the noise margin holds, and the
    inertia needs no box.

    >>> from bondgraph import simulate
    >>> from bondgraph.library import dc_motor
    >>> from diagnosis import add_noise
    >>> t = np.linspace(0.0, 2.0, 2001)
    >>> run = simulate(dc_motor(b=1e-4), (0.0, 2.0), {"U": lambda t: 3.0 * (t >= 0.05) + 9.0 * (t >= 0.5)},
    ...                t_eval=t).record()
    >>> run = add_noise(run, {"i": 0.005, "omega": 0.05}, seed=0)
    >>> boxes = set_membership_boxes(dc_motor(b=0.8e-4), [run], ["b", "J"])
    >>> boxes["b"][0], round(boxes["b"][1], 2), boxes["J"]
    (0.0, 0.2, (0.0, 0.0))
    """
    settings = settings or DetectionSettings()
    sized = _checked_parameters(bg, parameters)
    if arrs is None:
        declared = bg.uncertainties
        arrs = derive_arrs(revalued(bg, boxes={p: declared.get(p, (0.0, 0.0)) for p in sized}))
    # the record's columns as detect reads them: every ARR's signals and the inputs (whose steps it looks for)
    for arr in arrs:
        check_closed_form(arr, "set_membership_boxes")
    names = list(dict.fromkeys(s for arr in arrs for s in arr.signals))
    arrs = [arr for arr in arrs if set(arr.compiled.terms) & set(sized)]  # the thresholds these boxes widen
    unheld = [p for p in sized if not any(p in arr.compiled.terms for arr in arrs)]
    if unheld:
        raise SettingError("parameters", f"{{setting}}: no ARR holds the uncertainty of {unheld[0]!r}, so no record "
                                         "can size its box (declare a box for it in the model the ARRs come from)")
    records = list(records)
    if not records:
        raise SettingError("records", "{setting}: at least one healthy record is needed")
    data = [as_record(r, names + [n for n in bg.inputs if has_column(r, n) and n not in names], name=f"records[{k}]")
            for k, r in enumerate(records)]
    rows, needs, where, weights, counted = [], [], [], np.zeros(len(sized)), 0
    for arr in arrs:
        widening, weighed = np.zeros(len(sized)), 0
        for k, record in enumerate(data):
            for coefficients, need, t, spread, decided in _constraints(arr, record, k, sized, bg, settings):
                rows.append(coefficients)
                needs.append(need)
                where += [(arr.name, k, float(s)) for s in t]
                counted += decided
                if spread is not None:
                    widening, weighed = widening + spread, weighed + decided
        if weighed:
            weights += widening / weighed
    if not counted:
        raise SettingError("records", f"{{setting}}: no sample where an ARR holding {', '.join(sized)} is decided "
                                      "(the records are too short, or every sample lies near a step, a gap or an end)")
    return _solve(np.vstack(rows), np.concatenate(needs), where, sized, 1.0 + weights, _bounds(bg, sized))


def _checked_parameters(bg, parameters: Sequence[str]) -> list:
    if isinstance(parameters, str):  # a lone name would be read letter by letter
        parameters = [parameters]
    sized = list(dict.fromkeys(parameters))
    if not sized:
        raise SettingError("parameters", "{setting}: name at least one parameter whose box to size")
    values = bg.parameters
    unknown = [p for p in sized if p not in values]
    if unknown:
        raise SettingError("parameters", f"{{setting}}: the model has no parameter {unknown[0]!r} (parameters: "
                                         f"{', '.join(values)})")
    return sized


def _constraints(arr, data: Record, k: int, sized: list, bg, settings: DetectionSettings):
    """``(coefficients, need, times, spread, counted)`` per form of ``arr`` that :func:`~diagnosis.detect` may
    choose on the ``k``-th record: the rows ``coefficients @ [a, b] >= need`` (need > 0) of its counted samples
    that the margin and the other boxes alone do not hold, their times, the sum over the counted samples of each
    sized parameter's ``|g_p| / m`` (None when ``m`` is 0), and how many samples were counted."""
    sensitivities = [_sensitivity(arr, p) for p in sized]
    band = arr.compiled.cached(f"set membership band {sized}", lambda: _fixed_band(arr, sized))
    try:
        until = calibration_end(data, settings.calibrate, checked=settings.margin is None)
    except SettingError as exc:
        raise exc.within(f"records[{k}]: ") from None
    healthy = data.between(end=until)
    start = float(data.t[0] + START_SHARE * (until - data.t[0]))
    watched = list(bg.inputs) + list(bg.outputs) if STEPS_IN_SENSORS else list(bg.inputs)
    steps = [n for n in watched if n in data.columns]
    # the windows detect tries on this record (monitoring._choose): one when fixed or when nothing is estimated
    windows = [settings.window] if settings.window is not None or arr.order == 0 else [
        w for w in WINDOWS if w is None or w <= len(healthy) // 10]
    for window in windows:
        options = {"steps": steps, "ends": True, **({"window": window} if window else {}),
                   **({"polyorder": arr.order} if arr.order > 3 else {})}
        try:
            margin = settings.margin if settings.margin is not None else noise_margin(arr, healthy, k=settings.k,
                                                                                      **options)
        except CalibrationError:  # detect passes over a form its healthy stretch cannot calibrate
            continue
        if settings.margin is None and arr.integrals:  # detect's widening for an integral's random walk
            margin *= (_span(data) / max(_span(healthy), 1e-300)) ** (integral_depth(arr.nominal) - 0.5)
        evaluation = arr.evaluate(data, **options)
        points, s = evaluation.points, -evaluation.residual
        g = np.column_stack([np.broadcast_to(np.asarray(f(*points), float), s.shape) if f else np.zeros(s.shape)
                             for f in sensitivities])
        interval = band(*points)
        lo, hi = np.broadcast_to(interval.lo, s.shape), np.broadcast_to(interval.hi, s.shape)
        keep = (np.isfinite(s) & np.isfinite(g).all(axis=1) & np.isfinite(lo) & np.isfinite(hi)
                & (evaluation.t > start))
        if not keep.any():
            continue
        rise, fall = np.maximum(g, 0.0), np.maximum(-g, 0.0)
        with np.errstate(invalid="ignore"):
            above = keep & (s - margin - hi > 0)   # -r_n above the band: the upper ends must reach it
            below = keep & (lo - margin - s > 0)
        # only a run as long as an alarm needs can become one (a box only shortens the runs outside the band)
        run = _in_runs(above | below, settings.persistence if arr.order == 0 else max(
            settings.persistence, (window or default_window(options.get("polyorder", 3))) // 2))
        above, below = above & run, below & run
        # [a, b] coefficients: above, a widens where g < 0 and b where g > 0; below, the other way round
        yield (np.vstack([np.hstack([fall[above], rise[above]]), np.hstack([rise[below], fall[below]])]),
               np.concatenate([(s - margin - hi)[above], (lo - margin - s)[below]]),
               np.concatenate([evaluation.t[above], evaluation.t[below]]),
               # a margin of 0 (a noise-free record) measures no widening
               np.abs(g[keep]).sum(axis=0) / margin if margin > 0 else None, int(keep.sum()))


def _in_runs(outside: np.ndarray, length: int) -> np.ndarray:
    """True at the samples of ``outside`` that lie in a run of at least ``length`` of them in a row.

    >>> _in_runs(np.array([1, 1, 0, 1, 1, 1, 0], bool), 3).astype(int).tolist()
    [0, 0, 0, 1, 1, 1, 0]
    """
    ends = np.concatenate(([0], np.cumsum(persistent(outside, length))))   # runs of `length` end at these
    reach = np.minimum(np.arange(outside.size) + length, outside.size)
    return ends[reach] - ends[:-1] > 0


def _sensitivity(arr, parameter: str):
    """``g_p`` of ``arr`` as a numpy function of its points (None when its uncertain part lacks ``parameter``).

    Psi_2 must be linear in ``delta_p``, alone (no product with another delta): otherwise the band is not
    linear in the half-widths.
    """
    compiled = arr.compiled
    if parameter not in compiled.terms:
        return None
    d = delta(parameter)
    g = sp.diff(compiled.uncertain, d)
    if any(delta_parameter(s) is not None for s in g.free_symbols):
        raise SettingError("parameters", f"{{setting}}: {arr.name} is not linear in the uncertainty of "
                                         f"{parameter!r} ({compiled.terms[parameter]}); a linear program cannot "
                                         "size its box (give arrs= without it)")
    return compiled.function(f"set membership sensitivity {parameter}", g)


def _fixed_band(arr, sized: list):
    """The band of Psi_2 over the boxes of the parameters not sized (the sized ones at 0), as the thresholds
    compute it (:func:`~diagnosis.thresholds.interval_threshold`)."""
    compiled = arr.compiled
    boxes = {delta(p): (0.0, 0.0) if p in sized else tuple(map(float, box))
             for p, box in compiled.arr.uncertainties.items()}
    try:
        return affine_range(compiled.uncertain, compiled.points, boxes)
    except ValueError:  # not of the BG-LFT linear form: the natural extension, as the thresholds use
        return compile_interval(compiled.uncertain, compiled.points, boxes)


def _bounds(bg, sized: list) -> list:
    """``(0, upper)`` of each unknown, ``a`` of every parameter then ``b``: lo stays above -1 and in the domain."""
    values, domains = bg.parameters, bg.domains
    below, above = [], []
    for p in sized:
        value, (lo, hi) = values[p], domains.get(p, (-math.inf, math.inf))
        # the relative changes that keep value * (1 + delta) in the domain
        least, most = sorted((lo / value - 1.0, hi / value - 1.0)) if value else (-math.inf, math.inf)
        below.append((0.0, min(1.0, -least) - EDGE))
        above.append((0.0, most - EDGE if math.isfinite(most) else None))
    return below + above


def _solve(rows: np.ndarray, needs: np.ndarray, where: list, sized: list, weights: np.ndarray, bounds: list
           ) -> dict:
    """The smallest ``sum w (a + b)`` with ``rows @ [a, b] >= needs``, as boxes; a SettingError when none exists."""
    n = len(sized)
    if not needs.size:  # the margin and the other boxes hold every sample
        return {p: (0.0, 0.0) for p in sized}
    reach = np.array([hi if hi is not None else math.inf for _, hi in bounds])
    with np.errstate(invalid="ignore"):
        reachable = np.where(rows > 0, rows * reach, 0.0).sum(axis=1)
    short = np.flatnonzero(reachable < needs)
    if short.size:  # a sample no box of these parameters, in their domains, widens the band enough for
        name, k, t = where[short[0]]
        raise SettingError("records", f"{{setting}}[{k}]: {name} leaves its threshold at t = {t:g} s by "
                                      f"{needs[short[0]]:.3g} beyond the noise margin, where no box of "
                                      f"{', '.join(sized)} within their domains widens it enough")
    # each row over its need: rows in the units of different ARRs count alike, and the tolerance is relative
    scaled = rows / needs[:, None]
    result = linprog(np.concatenate([weights, weights]), A_ub=-scaled, b_ub=-np.ones(len(needs)), bounds=bounds,
                     method="highs")
    if result.status != 0:
        raise SettingError("parameters", f"{{setting}}: no boxes of {', '.join(sized)} within their domains keep "
                                         f"every record inside the thresholds ({result.message})")
    x = result.x * (1.0 + SLACK)
    x = np.minimum(x, [hi if hi is not None else math.inf for _, hi in bounds])
    return {p: (0.0 - float(x[i]) + 0.0, float(x[n + i])) for i, p in enumerate(sized)}


def _span(data: Record) -> float:
    return float(data.t[-1] - data.t[0])
