"""What an ARR can see on a record: the smallest parameter change it detects at its calibrated margin.

A change of a parameter theta by a relative amount epsilon moves the nominal residual of an ARR, to
first order, by ``-epsilon s(t)`` with the sensitivity ``s = theta_n dr_n/dtheta`` (the observation
model of Jha et al. (2016), eq. 27, per unit of relative change).  The alarm needs ``-r_n`` outside
``[B_lo - m, B_hi + m]`` for ``persistence`` samples in a row, so a rise of theta is detected once

    epsilon > (B_hi + m) / s        (s > 0),   or   (m - B_lo) / |s|   (s < 0)

on every sample of some run of ``persistence`` samples, with the margin counted ``1 +
NOISE_ALLOWANCE`` times (the residual's own noise must not make the alarm a coin toss).  That first-order
figure is one estimate; the other is the smallest epsilon whose *finite* effect on the record's own
signals, ``r_n`` at ``theta_n (1 + epsilon)`` less ``r_n`` at ``theta_n``, clears the band so (a resistance
enters as ``1/R``: a 30 % rise changes it by 23 % until the signals answer the change).  The **detectable
rise** is the larger of the two, so the claim never promises more than either; a fall likewise.  Both
are read on the record at hand (its excitation, its noise through the calibrated margin ``m``), so they
say what this ARR can see on this machine.

An ARR that cannot detect a change of any parameter below :data:`BLIND_CHANGE` is **blind** on the
record: typically the noise of a second derivative inflates its margin beyond any plausible fault.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import sympy as sp
from numpy.lib.stride_tricks import sliding_window_view

from .detection import persistent

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
    responses = _responses(arr, evaluation.points)
    # the residual carries its noise too: a change is claimed where it clears the band by an allowance
    # of NOISE_ALLOWANCE margins more (the margin is k noise deviations), so that the alarm is likely,
    # not a coin toss on each of the persistence samples
    widened = evaluation.margin * (1.0 + NOISE_ALLOWANCE)
    lo = evaluation.lower - widened
    hi = evaluation.upper + widened
    rise, fall = {}, {}
    late = np.asarray(evaluation.t) > after
    for parameter, moved in responses.items():
        if moved is None:
            rise[parameter] = fall[parameter] = float("inf")
            continue
        s = np.where(late, (moved(STEP) - moved(-STEP)) / (2 * STEP), np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            up = np.where(s > 0, hi / s, -lo / -s)      # epsilon > 0 moves -r_n by epsilon * s
            down = np.where(s > 0, -lo / s, hi / -s)    # epsilon < 0 by -|epsilon| * s
        # the finite change moves the residual otherwise than first order (a 30 % rise of R changes 1/R by
        # 23 %) as long as the signals have not answered it; once they have, the effect can be linear again
        # (a current source through R: the voltage rises by 30 %).  The record cannot tell which, so the
        # claim is the larger of the two figures: it promises less, never more, than either
        for sign, first_order, claims in ((1.0, up, rise), (-1.0, down, fall)):
            guess = _smallest(first_order, evaluation.persistence)
            claims[parameter] = max(guess, _finite(moved, sign, guess, lo, hi, late, evaluation.persistence))
    worst = [max(rise[p], fall[p]) for p in rise]
    blind = not worst or min(worst) > BLIND_CHANGE
    return Detectability(evaluation.name, rise, fall, float(evaluation.margin), blind,
                         _blind_reason(arr, evaluation.margin) if blind else "")


def _responses(arr, points: list) -> dict:
    """Parameter -> ``moved(epsilon)``, the shift of ``-r_n`` at every sample when the parameter is ``theta_n (1 +
    epsilon)`` on the machine that made the record; None where no figure is claimed.

    The record obeys the true parameter while ``r_n`` is evaluated at the nominal one, so ``-r_n`` moves by
    ``r_n(theta_n (1 + epsilon)) - r_n(theta_n)`` on the record's point values.  Central differences of it
    give the sensitivity (sympy's derivative of laws with ``sign`` and ``Abs`` gives pulses).
    """
    compiled = arr.compiled
    shape = np.shape(points[0])
    out: dict = {}
    for parameter in sorted(arr.parameters):
        theta = sp.Symbol(parameter)
        if any(theta in i.function.free_symbols for i in arr.nominal.atoms(sp.Integral)):
            # the parameter sits inside an integral: its sensitivity is not a point value of this ARR,
            # so no change of it is claimed detectable (the figure is conservative, never optimistic)
            out[parameter] = None
            continue
        others = {sp.Symbol(p): v for p, v in arr.values.items() if p != parameter}
        residual = arr.nominal.xreplace(compiled.symbols).xreplace(others)
        if _scales_an_integral(residual, theta, compiled.integrals):
            # theta scales an integral from the record's start: a change that comes later acts on part of
            # it only (how much depends on what the integral accumulates), so no figure is claimed
            out[parameter] = None
            continue
        f = sp.lambdify([*compiled.points, theta], residual, modules="numpy")
        nominal = float(arr.values[parameter])
        with np.errstate(all="ignore"):
            base = np.asarray(f(*points, nominal), float)

        def moved(epsilon: float, f=f, nominal=nominal, base=base) -> np.ndarray:
            with np.errstate(all="ignore"):
                return np.broadcast_to(np.asarray(f(*points, nominal * (1.0 + epsilon)), float) - base, shape)

        out[parameter] = moved
    return out


#: The finite-change figure is looked for from half to :data:`SEARCH_SPAN` times the first-order figure, in steps of
#: :data:`SEARCH_RATIO`, then bisects to :data:`SEARCH_TOLERANCE` (relative).
SEARCH_SPAN, SEARCH_RATIO, SEARCH_TOLERANCE = 8.0, 1.1, 0.005


def _finite(moved, sign: float, guess: float, lo: np.ndarray, hi: np.ndarray, late: np.ndarray,
           persistence: int) -> float:
    """The smallest relative change (of sign ``sign``) whose finite effect clears the band on ``persistence``
    samples in a row, looked for around the first-order ``guess``; inf if none up to SEARCH_SPAN times it."""
    if not np.isfinite(guess):
        return float("inf")

    def seen(epsilon: float) -> bool:
        shift = moved(sign * epsilon)
        with np.errstate(invalid="ignore"):
            outside = late & ((shift > hi) | (shift < lo))
        return bool(persistent(outside, persistence).any())

    ceiling = 1.0 if sign < 0 else np.inf   # a parameter cannot fall by 100 % or more
    below, epsilon = 0.0, guess / 2.0
    while not seen(epsilon):
        below, epsilon = epsilon, epsilon * SEARCH_RATIO
        if epsilon > SEARCH_SPAN * guess or epsilon >= ceiling:
            return float("inf")
    while epsilon - below > SEARCH_TOLERANCE * epsilon:
        middle = (below + epsilon) / 2.0
        below, epsilon = (below, middle) if seen(middle) else (middle, epsilon)
    return float(epsilon)


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
