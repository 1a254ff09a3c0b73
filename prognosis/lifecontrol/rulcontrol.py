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
establish: a fixed gain alone can overshoot, or crawl towards the boundary
from the infeasible side without ever crossing it, so whenever an iterate
leaves the bracket or an eq. (53) step fails to halve it, the next step
bisects.  The returned decision is the largest feasible ``theta`` met, so the
constraint holds on the draws used.

Every decision says how it was reached (:attr:`RULDecision.status`):

* ``"converged"``: the minimal-norm decision, to the tolerance;
* ``"not converged"``: the iteration ran out of ``max_iterations``; ``theta``
  is the largest feasible value met, which meets the constraint but may
  change the operation more than needed;
* ``"no feasible setting found"``: not even ``lower`` meets the constraint;
  ``theta = lower``, the most life-extending admissible setting.  The RUL
  falls as theta grows, so ``lower`` gives the smallest ``Pr(RUL <= RUL_ref)``
  there is: it comes closest to the mission, where keeping the previous
  setting or the nominal one would knowingly accept a larger risk.

The last two also issue a :class:`RULControlWarning` naming the time (the
prediction's origin) and the setting used, so that no fallback passes as a
solution.

Example
-------
Life ``10 / (1 + theta)`` hours: keeping ``Pr(RUL <= 8) <= 5 %`` needs ``theta <= 0.25``; 0 is feasible:

>>> from prognosis import RULDistribution
>>> life = lambda theta: RULDistribution(np.full(100, 10.0 / (1.0 + theta)))
>>> RULController(rul_ref=8.0, eta=0.05, gain=0.1).decide(life).theta
0.0
>>> decision = RULController(rul_ref=12.0, eta=0.05, gain=0.1, lower=-0.9).decide(life)
>>> round(decision.theta, 4), decision.status
(-0.1667, 'converged')
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from bondgraph.errors import PHMWarning

from ..errors import PrognosisError

__all__ = ["RULControlWarning", "RULController", "RULDecision"]

# the values of RULDecision.status
CONVERGED = "converged"
NOT_CONVERGED = "not converged"
INFEASIBLE = "no feasible setting found"


class RULControlWarning(PHMWarning, RuntimeWarning):
    """The RUL controller fell back: no feasible setting exists, or its iteration did not converge."""


class _Point(NamedTuple):
    """One evaluated candidate: the decision, ``q_eta``, ``Pr(RUL <= RUL_ref)``, the prediction's origin."""

    theta: float
    quantile: float
    probability: float
    origin: float


@dataclass(frozen=True)
class RULDecision:
    """Outcome of :meth:`RULController.decide`.

    Attributes
    ----------
    theta : float
        The decision to apply (at most ``min(0, upper)``).
    quantile : float
        ``q_eta`` at ``theta``: the ``(floor(eta N) + 1)``-th smallest of the N predicted RULs.
    probability : float
        ``Pr(RUL <= RUL_ref)`` at ``theta`` (at most ``eta`` when ``feasible``).
    feasible : bool
        Whether ``theta`` meets the constraint on the draws.
    status : str
        ``"converged"`` (the minimal-norm decision), ``"not converged"`` (the largest feasible
        ``theta`` met when the iterations ran out) or ``"no feasible setting found"``
        (``theta = lower``, the most life-extending admissible setting).
    history : tuple of (theta, quantile)
        Every evaluated candidate, in order.

    Examples
    --------
    Returned by :meth:`RULController.decide`.  Life ``10 / (1 + theta)``: even
    ``theta = -0.4`` gives only 16.7 h, short of the 20 h asked for:

    >>> import warnings
    >>> from prognosis import RULDistribution
    >>> life = lambda theta: RULDistribution(np.full(100, 10.0 / (1.0 + theta)))
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     decision = RULController(rul_ref=20.0, eta=0.05, lower=-0.4).decide(life)
    >>> decision.theta, round(decision.quantile, 2), decision.probability, decision.feasible
    (-0.4, 16.67, 1.0, False)
    >>> decision.status, decision.converged
    ('no feasible setting found', False)
    >>> [(theta, round(q, 2)) for theta, q in decision.history]   # theta = 0 first, then the lower bound
    [(0.0, 10.0), (-0.4, 16.67)]
    >>> print(caught[0].message)
    RUL controller at t = 0: no feasible setting found: even theta = -0.4 gives Pr(RUL <= 20) = 1 > eta = 0.05; \
using theta = -0.4, the most life-extending admissible setting
    """

    theta: float
    quantile: float
    probability: float
    feasible: bool
    status: str
    history: tuple

    @property
    def converged(self) -> bool:
        """True when ``theta`` is the minimal-norm decision (``status == "converged"``)."""
        return self.status == CONVERGED


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
        Stop when a feasible ``q_eta`` exceeds ``rul_ref`` by less than it (time units), or when
        the bracket is narrower than ``1e-6 (1 + |theta|)``.
    max_iterations : int
        Budget of the iteration; running out of it gives the status ``"not converged"``.

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

    A small gain from just above the boundary crawls towards it from the
    infeasible side; the bisection safeguard still finds it:

    >>> crawl = RULController(rul_ref=12.0, eta=0.05, gain=0.01, lower=-0.9).decide(life, theta0=-0.1)
    >>> round(crawl.theta, 3), crawl.status
    (-0.167, 'converged')
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
            raise PrognosisError(f"eta must be in (0, 1), got {self.eta!r}")
        if not self.gain > 0 or not self.rul_ref > 0:
            raise PrognosisError(f"gain and rul_ref must be positive, got {self.gain!r}, {self.rul_ref!r}")
        if not self.lower <= min(0.0, self.upper):
            raise PrognosisError(f"need lower <= min(0, upper), got lower={self.lower!r}, upper={self.upper!r}")
        if not self.max_iterations >= 1:
            raise PrognosisError(f"max_iterations must be at least 1, got {self.max_iterations!r}")

    def decide(self, predict: Callable, theta0: float = 0.0) -> RULDecision:
        """``theta*`` for ``predict(theta) -> RULDistribution`` (its RUL must not grow with theta).

        Parameters
        ----------
        predict : callable
            The RUL distribution under the decision ``theta``; the same draws for every ``theta``.
        theta0 : float
            First iterate of eq. (53), e.g. the decision in force.

        Returns
        -------
        RULDecision
            Its ``status`` says whether ``theta`` is the minimal-norm decision or a fallback; a
            fallback also issues a :class:`RULControlWarning`.

        Raises
        ------
        RuntimeError
            When ``lower`` is infinite and no feasible ``theta`` was met: there is no admissible
            setting to fall back on.

        Examples
        --------
        A budget of two iterations (after ``theta = 0`` and ``lower``): ``theta0`` and a
        bisection, both feasible, stop short of the boundary at ``-1/6``:

        >>> import warnings
        >>> from prognosis import RULDistribution
        >>> life = lambda theta: RULDistribution(np.full(100, 10.0 / (1.0 + theta)), origin=7.0)
        >>> with warnings.catch_warnings(record=True) as caught:
        ...     warnings.simplefilter("always")
        ...     decision = RULController(rul_ref=12.0, lower=-0.9, max_iterations=2).decide(life, theta0=-0.5)
        >>> decision.theta, decision.feasible, decision.status
        (-0.25, True, 'not converged')
        >>> print(caught[0].message)
        RUL controller at t = 7: the eq. 53 iteration did not converge in 2 iterations (feasible at theta = -0.25, \
infeasible at 0); using theta = -0.25, the largest feasible setting found
        """
        history: list[tuple[float, float]] = []

        def evaluate(theta: float) -> _Point:
            rul = predict(float(theta))
            samples = np.asarray(rul.samples, float)
            # the (floor(eta N) + 1)-th smallest RUL: Pr(RUL <= ref) <= eta on the N draws iff it exceeds ref
            k = int(np.floor(self.eta * samples.size))
            q = float(np.partition(samples, k)[k])
            history.append((float(theta), q))
            return _Point(float(theta), q, float(np.mean(samples <= self.rul_ref)), float(rul.origin))

        high = evaluate(min(0.0, self.upper))
        if self._meets(high):  # no change needed: theta = 0 (or upper) is the minimal-norm decision
            return self._decision(high, CONVERGED, history)
        low = None  # the largest feasible point found
        if np.isfinite(self.lower):
            low = evaluate(self.lower)
            if not self._meets(low):  # even the most cautious operation cannot keep the RUL
                self._warn(low, f"no feasible setting found: even theta = {low.theta:g} gives "
                                f"Pr(RUL <= {self.rul_ref:g}) = {low.probability:.3g} > eta = {self.eta:g}; "
                                f"using theta = {low.theta:g}, the most life-extending admissible setting")
                return self._decision(low, INFEASIBLE, history)
        low, high, converged = self._iterate(evaluate, low, high, float(theta0))
        if low is None:
            raise RuntimeError(f"no feasible decision found in {self.max_iterations} iterations down to "
                               f"theta = {high.theta:.4g}; give a finite lower bound")
        if converged:
            return self._decision(low, CONVERGED, history)
        self._warn(low, f"the eq. 53 iteration did not converge in {self.max_iterations} iterations (feasible at "
                        f"theta = {low.theta:.6g}, infeasible at {high.theta:.6g}); using theta = {low.theta:.6g}, "
                        "the largest feasible setting found")
        return self._decision(low, NOT_CONVERGED, history)

    def _iterate(self, evaluate: Callable, low: _Point | None, high: _Point,
                 theta: float) -> tuple[_Point | None, _Point, bool]:
        """Eq. (53) on the bracket ``[low, high)``: ``(low, high, converged)`` when it stops.

        The next step bisects (or, while no feasible point is known, searches downwards) when the
        iterate leaves the bracket or the last step did not halve the bracket (or find a feasible
        point): a small gain converges to the boundary from the infeasible side, one side only,
        and would otherwise spend the whole budget there.
        """
        safeguard = False
        for _ in range(self.max_iterations):
            floor = low.theta if low is not None else -np.inf
            if safeguard or not floor < theta < high.theta:
                theta = 0.5 * (floor + high.theta) if low is not None else high.theta - 2.0 * max(abs(high.theta), 1.0)
            width = high.theta - floor
            point = evaluate(theta)
            if self._meets(point):
                low = point
                if point.quantile - self.rul_ref <= self.tolerance:
                    return low, high, True
            else:
                high = point
            if low is None:
                safeguard = True  # the step found no feasible point: the next one searches downwards
            else:
                narrowed = high.theta - low.theta
                if narrowed <= 1e-6 * (1.0 + abs(high.theta)):
                    return low, high, True
                safeguard = not narrowed <= 0.5 * width
            theta = theta + self.gain * (min(point.quantile, 1e300) - self.rul_ref)  # eq. 53
        return low, high, False

    def _meets(self, point: _Point) -> bool:
        """Eq. 51 on the draws: ``Pr(RUL <= RUL_ref) <= eta``, that is ``q_eta > RUL_ref``."""
        return point.quantile > self.rul_ref

    @staticmethod
    def _decision(point: _Point, status: str, history: list) -> RULDecision:
        return RULDecision(point.theta, point.quantile, point.probability, status != INFEASIBLE, status,
                           tuple(history))

    @staticmethod
    def _warn(point: _Point, what: str) -> None:
        warnings.warn(f"RUL controller at t = {point.origin:g}: {what}", RULControlWarning, stacklevel=3)
