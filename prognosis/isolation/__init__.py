"""Isolation by estimation: which parameter degrades, by which law, and its RUL, weighed by evidence.

One job per module:

- :mod:`~prognosis.isolation.settings`: :class:`IsolationSettings`, the settings of both the single-asset
  and the fleet monitor, and the method's constants;
- :mod:`~prognosis.isolation.priors`: :class:`Priors`, the hypotheses (candidate x law) and where each starts;
- :mod:`~prognosis.isolation.decision`: :class:`Decision`, :func:`decide` and :func:`held_back`, the
  decision from the evidence;
- :mod:`~prognosis.isolation.result`: :class:`IsolationResult`, what a record gave;
- :mod:`~prognosis.isolation.isolating_monitor`: :class:`IsolatingMonitor`, the pipeline on one record.
"""

from .decision import Decision, decide, held_back
from .isolating_monitor import IsolatingMonitor, detection_options
from .priors import Priors, check_noise_std
from .result import RUL_KEYS, IsolationResult
from .settings import (ADEQUACY_LIMIT, ADEQUACY_WINDOW, BEFORE_STEPS, BLIND_LIMIT, CONFIRM_STEPS, DRIFT_AWAY_STEPS,
                       EVIDENCE_RATIO, FLEET_LAWS, FLEET_SETTINGS, FORECAST_LIMIT, FREEZE_BELOW, HORIZON_STEPS, LAWS,
                       MAX_PARTICLES, METHODS, MIXTURE_FLOOR, PROCESS_NOISE, SPIKE, IsolationSettings)

__all__ = [
    # the monitor, its settings and its result
    "IsolatingMonitor", "IsolationSettings", "IsolationResult", "FLEET_SETTINGS", "detection_options",
    # the decision
    "Decision", "decide", "held_back",
    # the hypotheses and their starts
    "Priors", "check_noise_std",
    # constants of the method
    "ADEQUACY_LIMIT", "ADEQUACY_WINDOW", "BEFORE_STEPS", "BLIND_LIMIT", "CONFIRM_STEPS", "DRIFT_AWAY_STEPS",
    "EVIDENCE_RATIO",
    "FLEET_LAWS", "FORECAST_LIMIT", "FREEZE_BELOW", "HORIZON_STEPS", "LAWS", "MAX_PARTICLES", "METHODS",
    "MIXTURE_FLOOR", "PROCESS_NOISE", "RUL_KEYS", "SPIKE",
]
