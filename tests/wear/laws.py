"""Wear laws of a parameter, from its nominal value at the onset to its failure value at the end of life.

Each law is a function ``theta(t)`` that equals ``nominal`` up to ``onset`` and reaches ``failure`` at
``eol`` exactly, so that the true end of life is known in closed form whatever the law.  Only
``linear`` and ``exponential`` are families the prognoser knows; the others are there to see what it
says of a law it does not know.

>>> law = LAWS["power"](1.0, 2.0, 10.0, 110.0)
>>> float(law(5.0)), float(law(110.0)), round(float(law(60.0)), 4)
(1.0, 2.0, 1.1768)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

POWER = 2.5          # exponent of the power law in the time since onset (an accelerating wear)
LOGISTIC_RATE = 8.0  # steepness of the logistic law over the life (a wear that saturates... then fails)
STEP_SHARE = 0.25    # the step-then-drift law jumps by this share of the way to failure at the onset
PAUSES = 4           # the intermittent law wears in this many bursts with pauses between them


def _share(t, onset: float, eol: float) -> np.ndarray:
    """Time since onset over the life to failure, clipped at 0 before the onset."""
    return np.clip((np.asarray(t, float) - onset) / (eol - onset), 0.0, None)


def linear(nominal: float, failure: float, onset: float, eol: float) -> Callable:
    return lambda t: nominal + (failure - nominal) * _share(t, onset, eol)


def exponential(nominal: float, failure: float, onset: float, eol: float) -> Callable:
    return lambda t: nominal * (failure / nominal) ** _share(t, onset, eol)


def power(nominal: float, failure: float, onset: float, eol: float) -> Callable:
    return lambda t: nominal + (failure - nominal) * _share(t, onset, eol) ** POWER


def logistic(nominal: float, failure: float, onset: float, eol: float) -> Callable:
    def law(t):
        s = _share(t, onset, eol)
        curve = 1.0 / (1.0 + np.exp(-LOGISTIC_RATE * (s - 0.6)))
        start, end = 1.0 / (1.0 + np.exp(0.6 * LOGISTIC_RATE)), 1.0 / (1.0 + np.exp(-0.4 * LOGISTIC_RATE))
        return nominal + (failure - nominal) * np.where(s > 0, (curve - start) / (end - start), 0.0)
    return law


def step_then_drift(nominal: float, failure: float, onset: float, eol: float) -> Callable:
    def law(t):
        s = _share(t, onset, eol)
        return nominal + (failure - nominal) * np.where(s > 0, STEP_SHARE + (1 - STEP_SHARE) * s, 0.0)
    return law


def intermittent(nominal: float, failure: float, onset: float, eol: float) -> Callable:
    def law(t):
        s = _share(t, onset, eol)
        # wear only in the second half of each of PAUSES periods: a staircase whose last ramp ends at eol
        period = 1.0 / PAUSES
        whole, part = np.floor(s / period), np.mod(s, period)
        worn = whole * period + 2 * np.maximum(part - period / 2, 0.0)
        return nominal + (failure - nominal) * np.minimum(worn, 1.0) * (s > 0)
    return law


LAWS = {"linear": linear, "exponential": exponential, "power": power, "logistic": logistic,
        "step_then_drift": step_then_drift, "intermittent": intermittent}
