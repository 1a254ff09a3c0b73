"""What an ARR can see on a record: the smallest parameter change it detects at its calibrated margin.

A change of a parameter theta by a relative amount epsilon moves the nominal residual of an ARR, to
first order, by ``-epsilon s(t)`` with the sensitivity ``s = theta_n dr_n/dtheta`` (the observation
model of Jha et al. (2016), eq. 27, per unit of relative change).  The alarm needs ``-r_n`` outside
``[B_lo - m, B_hi + m]`` for ``persistence`` samples in a row, so a rise of theta is detected once

    epsilon > (B_hi + m) / s        (s > 0),   or   (m - B_lo) / |s|   (s < 0)

on every sample of some run of ``persistence`` samples, with the margin counted ``1 +
NOISE_ALLOWANCE`` times (the residual's own noise must not make the alarm a coin toss): the smallest
such epsilon over the record is the **detectable rise**; a fall likewise. Both are read on the
record at hand (its excitation, its noise through the calibrated margin ``m``), so they say what
this ARR can see on this machine.

An ARR that cannot detect a change of any parameter below :data:`BLIND_CHANGE` is **blind** on the
record: typically the noise of a second derivative inflates its margin beyond any plausible fault.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import sympy as sp
from numpy.lib.stride_tricks import sliding_window_view

__all__ = ["BLIND_CHANGE", "Detectability", "detectability"]

#: An ARR that needs a larger relative change than this of every parameter is reported blind.
BLIND_CHANGE = 1.0
#: Extra margins a change must clear beyond the band's edge to be claimed detectable (see detectability).
NOISE_ALLOWANCE = 0.5
#: Relative step of the central difference that gives a residual's sensitivity to a parameter.
STEP = 1e-6


@dataclass(frozen=True)
class Detectability:
    """The smallest relative changes an ARR detects on a record.

    Attributes
    ----------
    arr : str
        The ARR's name.
    rise, fall : dict
        Parameter -> smallest detectable relative rise (fall) of it, ``inf`` if none is.
    margin : float
        The noise margin the figures are for.
    blind : bool
        No parameter is detectable below :data:`BLIND_CHANGE` in either direction.
    reason : str
        Why the ARR is blind ("" when it is not).
    """

    arr: str
    rise: dict
    fall: dict
    margin: float
    blind: bool
    reason: str

    def change(self, parameter: str) -> float:
        """The smallest relative change of ``parameter`` detected whichever its sign: the larger of rise and fall."""
        return max(self.rise[parameter], self.fall[parameter])

    def detectable(self, parameter: str, change: float) -> bool:
        """Whether a relative change ``change`` (signed, e.g. 0.3 or -0.3) of ``parameter`` is detected."""
        if parameter not in self.rise:
            return False
        return change >= self.rise[parameter] if change > 0 else -change >= self.fall[parameter]

    def as_dict(self) -> dict:
        finite = {k: (None if not np.isfinite(v) else float(v)) for k, v in self.rise.items()}
        return {"arr": self.arr, "margin": self.margin, "blind": self.blind, "reason": self.reason,
                "rise": finite, "fall": {k: (None if not np.isfinite(v) else float(v)) for k, v in self.fall.items()}}


def detectability(evaluation, arr, *, after: float = -np.inf) -> Detectability:
    """The detectable changes of each parameter of ``arr`` on ``evaluation``'s record, from ``after`` on.

    ``evaluation`` is ``arr.evaluate(record, margin=..., persistence=...)``: its point values, band and
    margin are used; ``after`` restricts the figures to the monitored stretch (after calibration).

    Examples
    --------
    The motor's speed ARR on a bench run: friction b is seen from a rise of a few percent, the
    inertia J only where the speed changes.

    >>> from bondgraph import simulate
    >>> from bondgraph.library import dc_motor
    >>> from diagnosis import derive_arrs, noise_margin
    >>> motor = dc_motor()
    >>> t = np.linspace(0.0, 2.0, 2001)
    >>> run = simulate(motor, (0.0, 2.0), {"U": 12.0}, t_eval=t).record()
    >>> arr = derive_arrs(motor)[1]
    >>> d = detectability(arr.evaluate(run, margin=1e-6, persistence=5), arr)
    >>> sorted(d.rise), d.blind
    (['J', 'b', 'k_m'], False)
    >>> 0.2 < d.rise["b"] < 0.3   # b's box is (0, +20 %): a rise must clear it first
    True
    """
    sensitivities = _sensitivities(arr, evaluation.points)
    # the residual carries its noise too: a change is claimed where it clears the band by an allowance
    # of NOISE_ALLOWANCE margins more (the margin is k noise deviations), so that the alarm is likely,
    # not a coin toss on each of the persistence samples
    widened = evaluation.margin * (1.0 + NOISE_ALLOWANCE)
    lo = evaluation.lower - widened
    hi = evaluation.upper + widened
    rise, fall = {}, {}
    late = np.asarray(evaluation.t) > after
    for parameter, s in sensitivities.items():
        s = np.where(late, s, np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            up = np.where(s > 0, hi / s, -lo / -s)      # epsilon > 0 moves -r_n by epsilon * s
            down = np.where(s > 0, -lo / s, hi / -s)    # epsilon < 0 by -|epsilon| * s
        rise[parameter] = _smallest(up, evaluation.persistence)
        fall[parameter] = _smallest(down, evaluation.persistence)
    worst = [max(rise[p], fall[p]) for p in rise]
    blind = not worst or min(worst) > BLIND_CHANGE
    return Detectability(evaluation.name, rise, fall, float(evaluation.margin), blind,
                         _blind_reason(arr, evaluation.margin) if blind else "")


def _sensitivities(arr, points: list) -> dict:
    """Parameter -> ``theta_n dr_n/dtheta`` at every sample, from the ARR's point values.

    A central difference of ``r_n`` in the parameter (relative step :data:`STEP`) rather than sympy's
    derivative: laws with ``sign`` and ``Abs`` differentiate to pulses and unevaluated derivatives.
    """
    compiled = arr.compiled
    out = {}
    for parameter in sorted(arr.parameters):
        theta = sp.Symbol(parameter)
        if any(theta in i.function.free_symbols for i in arr.nominal.atoms(sp.Integral)):
            # the parameter sits inside an integral: its sensitivity is not a point value of this ARR,
            # so no change of it is claimed detectable (the figure is conservative, never optimistic)
            out[parameter] = np.full(np.shape(points[0]), np.nan)
            continue
        others = {sp.Symbol(p): v for p, v in arr.values.items() if p != parameter}
        residual = arr.nominal.xreplace(compiled.symbols).xreplace(others)
        if _scales_an_integral(residual, theta, compiled.integrals):
            # theta scales an integral from the record's start: a change that comes later acts on part of
            # it only (how much depends on what the integral accumulates), so no figure is claimed
            out[parameter] = np.full(np.shape(points[0]), np.nan)
            continue
        f = sp.lambdify([*compiled.points, theta], residual, modules="numpy")
        nominal = float(arr.values[parameter])
        with np.errstate(all="ignore"):
            up = np.asarray(f(*points, nominal * (1 + STEP)), float)
            down = np.asarray(f(*points, nominal * (1 - STEP)), float)
        out[parameter] = np.broadcast_to((up - down) / (2 * STEP), np.shape(points[0])).copy()
    return out


def _scales_an_integral(residual: sp.Expr, theta: sp.Symbol, integrals) -> bool:
    """Whether the residual's sensitivity to ``theta`` holds one of the ARR's integrals."""
    held = set(integrals)
    if not held or not residual.free_symbols & held:
        return False
    return bool(sp.diff(residual, theta).free_symbols & held)


def _smallest(required: np.ndarray, persistence: int) -> float:
    """The smallest change that exceeds ``required`` on each of ``persistence`` consecutive samples."""
    need = np.where(np.isfinite(required) & (required > 0), required, np.inf)
    if need.size < persistence:
        return float("inf")
    runs = sliding_window_view(need, persistence).max(axis=1) if persistence > 1 else need
    return float(runs.min()) if runs.size else float("inf")


def _blind_reason(arr, margin: float) -> str:
    order = arr.order
    if order >= 2:
        return (f"its calibrated margin {margin:.3g} is set by the noise of derivative estimates of order {order}, "
                f"larger than a {BLIND_CHANGE:.0%} change of any parameter moves the residual")
    return f"a {BLIND_CHANGE:.0%} change of any of its parameters moves the residual less than its margin {margin:.3g}"


def summary(rows: Mapping[str, Detectability]) -> dict:
    """Parameter -> the smallest change any of the ARRs detects (whichever sign), over ``rows``."""
    best: dict = {}
    for d in rows.values():
        for p in d.rise:
            best[p] = min(best.get(p, float("inf")), d.change(p))
    return best
