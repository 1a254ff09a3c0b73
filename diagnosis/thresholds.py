"""Robust thresholds: the range of Psi_2 over the uncertainty box, per sample.

Interval threshold (Jha et al. (2016), eqs. 16-20, Table I): ``[B_lo(t), B_hi(t)]``, the
range of the uncertain part Psi_2 when every ``delta_p`` ranges over its
interval, computed by outward-rounded interval arithmetic
(:mod:`diagnosis.intervals`).  When Psi_2 is linear in each delta with no
products of deltas (the BG-LFT form of elements whose parameter multiplies
their law) the range is exact; otherwise the natural interval extension is
used, which is sound but may overestimate when a delta occurs more than once.

BG-LFT threshold (Djeziri et al.): ``sum_i |w_i|`` with each uncertain
effort or flow at its worst-case delta, a symmetric band ``[-W, W]``.  For the
linear form ``w_i = delta_i g_i`` the interval band has width
``sum (hi_i - lo_i) |g_i| <= 2 sum max(|lo_i|, |hi_i|) |g_i|``: never wider.
"""

from __future__ import annotations

import numpy as np

from .deltas import delta
from .intervals import affine_range, compile_interval
from .residuals import CompiledARR

__all__ = ["bglft_threshold", "interval_threshold"]


def interval_threshold(compiled: CompiledARR, points: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """``(B_lo, B_hi)`` of Psi_2 at every sample; ``-r_n`` is normal inside it."""
    evaluator = compiled.cached("interval", lambda: _interval_evaluator(compiled))
    shape = points[0].shape if points else ()
    band = evaluator(*points)
    return np.broadcast_to(band.lo, shape).copy(), np.broadcast_to(band.hi, shape).copy()


def bglft_threshold(compiled: CompiledARR, points: list[np.ndarray]) -> np.ndarray:
    """``sum_i max over delta_i in {lo_i, hi_i} of |w_i(delta_i)|`` at every sample.

    Each term is evaluated at both ends of its delta interval (the BG-LFT
    terms are monotone in their delta).
    """
    shape = points[0].shape if points else ()
    total = np.zeros(shape)
    for function, ends in compiled.cached("bglft terms", lambda: _bglft_terms(compiled)):
        # both ends in one call (a stream judges a few samples at a time: the calls are the cost)
        values = np.asarray(function(*(np.asarray(p)[..., None] for p in points), ends), float)
        total += np.abs(np.broadcast_to(values, (*shape, 2))).max(axis=-1)
    return total


def _bglft_terms(compiled: CompiledARR) -> list:
    """Each uncertain parameter's term as a function of the points and its delta, with its delta's two ends."""
    return [(compiled.function(f"term {parameter}", term, (delta(parameter),)),
             np.asarray(compiled.arr.uncertainties[parameter], float)) for parameter, term in compiled.terms.items()]


def _interval_evaluator(compiled: CompiledARR):
    """The range of Psi_2 over the box of the deltas, as a function of the point values."""
    boxes = {delta(p): tuple(map(float, box)) for p, box in compiled.arr.uncertainties.items()}
    try:
        return affine_range(compiled.uncertain, compiled.points, boxes)
    except ValueError:  # not of the BG-LFT linear form: natural extension (sound, may overestimate)
        return compile_interval(compiled.uncertain, compiled.points, boxes)
