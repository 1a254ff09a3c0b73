"""RUL control: the least change of operation that keeps the life (Rodriguez Obando et al. (2021), section 5.2).

The decision ``theta`` shifts the operation (for the friction drive the speed
reference, ``omega2* = omega2_ref + theta``, eq. 47).  The RUL controller
solves the chance-constrained problem (eqs. 50-52)::

    theta* = argmin theta^2 / 2   subject to   Pr(RUL(x^, P, theta) <= RUL_ref) <= eta,

where the RUL distribution comes from :func:`prognosis.lifecontrol.montecarlo.monte_carlo_rul`
run with the same draws for every candidate ``theta`` (common random numbers,
so the predicted quantile is a deterministic, monotone function of ``theta``).
On ``N`` draws the constraint holds exactly when ``q_eta``, the
``(floor(eta N) + 1)``-th smallest RUL, exceeds ``RUL_ref``.  When the RUL decreases as ``theta`` grows (more speed,
more wear) the feasible set is ``theta <= theta_root``, and the minimal-norm
decision is ``min(0, theta_root)`` clipped to the admissible range.

It is found with the iteration of eq. (53)::

    theta(s+1) = theta(s) + K (q_eta(theta(s)) - RUL_ref),

``K(e) = gain * e``, safeguarded by bisection on the bracket the iterates
establish (a fixed gain alone can overshoot or crawl), and the returned
decision is the largest feasible ``theta`` met, so the constraint holds on the
draws used.

Example
-------
Life ``10 / (1 + theta)`` hours: keeping ``Pr(RUL <= 8) <= 5 %`` needs ``theta <= 0.25``; 0 is feasible:

>>> from prognosis import RULDistribution
>>> life = lambda theta: RULDistribution(np.full(100, 10.0 / (1.0 + theta)))
>>> RULController(rul_ref=8.0, eta=0.05, gain=0.1).decide(life).theta
0.0
>>> round(RULController(rul_ref=12.0, eta=0.05, gain=0.1, lower=-0.9).decide(life).theta, 4)
-0.1667
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["RULController", "RULDecision"]


@dataclass(frozen=True)
class RULDecision:
    """Outcome of :meth:`RULController.decide`.

    Attributes
    ----------
    theta : float
        The decision (largest feasible value found, at most 0).
    quantile : float
        ``q_eta`` at ``theta``: the ``(floor(eta N) + 1)``-th smallest of the N predicted RULs.
    probability : float
        ``Pr(RUL <= RUL_ref)`` at ``theta`` (at most ``eta`` when ``feasible``).
    feasible : bool
        False when even ``lower`` cannot meet the constraint (``theta = lower`` then).
    history : tuple of (theta, quantile)
        Every evaluated candidate, in order.

    Examples
    --------
    Returned by :meth:`RULController.decide`.  Life ``10 / (1 + theta)``: even
    ``theta = -0.4`` gives only 16.7 h, short of the 20 h asked for:

    >>> from prognosis import RULDistribution
    >>> life = lambda theta: RULDistribution(np.full(100, 10.0 / (1.0 + theta)))
    >>> decision = RULController(rul_ref=20.0, eta=0.05, lower=-0.4).decide(life)
    >>> decision.theta, round(decision.quantile, 2), decision.probability, decision.feasible
    (-0.4, 16.67, 1.0, False)
    >>> [(theta, round(q, 2)) for theta, q in decision.history]   # theta = 0 first, then the lower bound
    [(0.0, 10.0), (-0.4, 16.67)]
    """

    theta: float
    quantile: float
    probability: float
    feasible: bool
    history: tuple


@dataclass
class RULController:
    """Chance-constrained RUL controller (eqs. 50-53).

    Parameters
    ----------
    rul_ref : float
        Required RUL, in the time unit of the predictions.
    eta : float
        Allowed probability ``Pr(RUL <= rul_ref)``.
    gain : float
        ``K`` of eq. (53), decision units per time unit of RUL error.
    lower, upper : float
        Admissible decisions; the minimal-norm decision never exceeds ``min(0, upper)``.
    tolerance : float
        Stop when ``|q_eta - rul_ref|`` is below it (time units), or when the
        bracket is narrower than ``1e-6 (1 + |theta|)``.
    max_iterations : int

    Examples
    --------
    Life ``10 / (1 + theta)`` hours on 100 identical draws; requiring 12 h
    needs ``theta <= 10 / 12 - 1 = -1/6``:

    >>> from prognosis import RULDistribution
    >>> life = lambda theta: RULDistribution(np.full(100, 10.0 / (1.0 + theta)))
    >>> controller = RULController(rul_ref=12.0, eta=0.05, gain=0.1, lower=-0.9)
    >>> decision = controller.decide(life)
    >>> round(decision.theta, 3), round(decision.quantile, 2), decision.probability, decision.feasible
    (-0.167, 12.0, 0.0, True)
    >>> decision.quantile > controller.rul_ref   # the constraint holds on the draws
    True
    >>> RULController(rul_ref=0.5).decide(life).theta   # already long enough: no change
    0.0
    """

    rul_ref: float
    eta: float = 0.05
    gain: float = 1.0
    lower: float = -np.inf
    upper: float = 0.0
    tolerance: float = 1e-3
    max_iterations: int = 60

    def __post_init__(self):
        if not 0.0 < self.eta < 1.0:
            raise ValueError(f"eta must be in (0, 1), got {self.eta!r}")
        if not self.gain > 0 or not self.rul_ref > 0:
            raise ValueError(f"gain and rul_ref must be positive, got {self.gain!r}, {self.rul_ref!r}")
        if not self.lower <= min(0.0, self.upper):
            raise ValueError(f"need lower <= min(0, upper), got lower={self.lower!r}, upper={self.upper!r}")

    def decide(self, predict: Callable, theta0: float = 0.0) -> RULDecision:
        """``theta*`` for ``predict(theta) -> RULDistribution`` (its RUL must not grow with theta)."""
        top = min(0.0, self.upper)
        history = []

        def evaluate(theta):
            rul = np.asarray(predict(float(theta)).samples, float)
            # the (floor(eta N) + 1)-th smallest RUL: Pr(RUL <= ref) <= eta on the N draws iff it exceeds ref
            q = float(np.partition(rul, int(np.floor(self.eta * rul.size)))[int(np.floor(self.eta * rul.size))])
            history.append((float(theta), q))
            return float(theta), q, float(np.mean(rul <= self.rul_ref))

        def decision(point, feasible):
            return RULDecision(point[0], point[1], point[2], feasible, tuple(history))

        def meets(point):  # eq. 51 on the draws: Pr(RUL <= RUL_ref) <= eta
            return point[1] > self.rul_ref

        high = evaluate(top)
        if meets(high):  # no change needed: theta = 0 (or upper) is the minimal-norm decision
            return decision(high, True)
        low = None  # the largest feasible point found
        if np.isfinite(self.lower):
            low = evaluate(self.lower)
            if not meets(low):  # even the most cautious operation cannot keep the RUL
                return decision(low, False)
        theta = float(theta0)
        for _ in range(self.max_iterations):
            floor = low[0] if low is not None else -np.inf
            if not floor < theta < high[0]:  # outside the bracket: bisect, or search downwards
                theta = 0.5 * (floor + high[0]) if low is not None else high[0] - 2.0 * max(abs(high[0]), 1.0)
            point = evaluate(theta)
            if meets(point):
                low = point
                if point[1] - self.rul_ref <= self.tolerance:
                    break
            else:
                high = point
            if low is not None and high[0] - low[0] <= 1e-6 * (1.0 + abs(high[0])):
                break
            theta = theta + self.gain * (min(point[1], 1e300) - self.rul_ref)  # eq. 53
        if low is None:
            raise RuntimeError(f"no feasible decision found in {self.max_iterations} iterations down to "
                               f"theta = {high[0]:.4g}; give a finite lower bound")
        return decision(low, True)
