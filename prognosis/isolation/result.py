"""What :class:`~prognosis.isolation.IsolatingMonitor` found on a record: :class:`IsolationResult`."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import PrognosisError
from ..health_monitor import MonitorResult
from ..hypotheses import sensor_signal
from .decision import Decision, decide, finite_or_none, held_back
from .settings import EVIDENCE_RATIO, FREEZE_BELOW

__all__ = ["RUL_KEYS", "IsolationResult"]

#: The RUL columns of a prediction in :meth:`IsolationResult.as_dict`.
RUL_KEYS = ("rul_mean", "rul_p5", "rul_p25", "rul_median", "rul_p75", "rul_p95", "censored")


@dataclass
class IsolationResult:
    """What :class:`IsolatingMonitor` found on a record.

    Attributes
    ----------
    detection_time : float or None
        First alarm of any ARR.
    fired : list of str
        The ARRs in alarm over at least half of the CONFIRM_STEPS filter steps from the first alarm
        (the signature the candidates come from; :meth:`IsolatingMonitor.signature`).
    transient : list of str
        The ARRs that alarmed in that window without staying in alarm: they rule nothing out.
    late : dict
        ARR name -> time (s) it fired after that window (in alarm over half of a window of
        CONFIRM_STEPS filter steps, dated at the window's end, when it is known), for the ARRs
        outside ``fired``.
    consistent : list of str
        The faults of the model, parameters and sensors (``"sensor <signal>"``), whose signature
        holds every fired ARR (:func:`~prognosis.hypotheses.explaining`), with or without a failure value.
    late_faults : dict
        For a late ARR no candidate is sensitive to: the faults of the model, parameters and
        sensors, that could have fired it alone (:func:`~prognosis.hypotheses.explaining`).
    candidates, groups : list
        Candidates from the signature, parameters and sensors (``"sensor <signal>"``); their groups of
        indistinguishable ones.
    unweighed : dict
        Sensor -> why its fault consistent with the signature is not weighed (an ARR integrates its reading).
    same_signature : dict
        Candidate -> the other faults of the model (parameters, ``"sensor <signal>"``) with its fault
        signature over the monitor's ARRs (:func:`~prognosis.hypotheses.same_signature`).
    hypotheses : list of Hypothesis
    arrs : list of str
        The ARRs whose residuals the hypotheses are weighed on.
    t : ndarray (K,)
        Filter steps.
    log_evidence : ndarray (K, H)
    theta, gamma : dict
        Per hypothesis: ``mean`` (K, H) and ``quantiles`` (K, H, 3) (5, 50, 95 %).
    rul_t : ndarray
    rul : list of RULDistribution
        The mixture of the hypotheses' predictions at each ``rul_t``.
    decisions : list of Decision
        The decision at each ``rul_t``.
    rejected : dict
        Hypothesis name -> why it was rejected.
    evaluations : list
        The detection :class:`~diagnosis.detection.Evaluation` of every ARR.
    ess : ndarray (K, H)
        Smallest effective sample size of each hypothesis' cloud within each filter step.
    collapsed : dict
        Hypothesis name -> first time (s) its cloud collapsed (an update's effective sample size, or
        the distinct particles after a move, below a tenth of them: no distribution); a prediction
        made at a step where it is collapsed leaves it out.
    inadequate : dict
        Hypothesis name -> why its law does not follow the residuals (its standardized innovations
        drift, :data:`ADEQUACY_LIMIT`, or those of an ARR blind to it, :data:`BLIND_LIMIT`: another
        fault acts there; or its forecast from half the record ago misses the last steps,
        :data:`FORECAST_LIMIT`); it is left out of the RUL from then on.
    withheld : list of str or None
        Per RUL prediction: None, or why no RUL is given (every probable hypothesis inadequate or
        collapsed): the answer is then "undecided", not a band.
    on_record : dict
        ``"a ~ b"`` -> why candidates that the structure tells apart are indistinguishable on this
        record (each one's estimated change imitated by the other to within the decisive ratio,
        :func:`~prognosis.hypotheses.record_separation`, over the filter steps up to the end);
        ``record_groups`` are ``groups`` merged with those pairs, the groups the final decision uses.
    parts : dict
        Joint hypothesis name -> parameter -> its mean estimate (K,) (``theta`` holds the first's).
    healthy : dict
        Parameter -> its healthy values (lo, hi), its uncertainty box about nominal: a pair one of whose
        parameters is estimated there is no two faults (:func:`held_back`).
    seen_by : dict
        Parameter of a pair -> the ARRs (of all the monitor's) that see it.
    apart : dict
        Joint hypothesis name -> parameter -> the log likelihood of its estimated change in its own
        ARRs' residuals (blind to the other) over a constant offset, summed up to the end
        (:meth:`~prognosis.isolation.IsolatingMonitor.apart_terms`): a pair one of whose
        parameters is not seen apart from the other is no two faults (:func:`held_back`).
    settings : dict
        What produced the result, for its JSON (:func:`~prognosis.pipeline.prognose` fills it: the
        failure values, the calibration end, the filter step, the residual noise...).
    """

    detection_time: float | None
    fired: list = field(default_factory=list)
    transient: list = field(default_factory=list)
    late: dict = field(default_factory=dict)
    late_faults: dict = field(default_factory=dict)
    consistent: list = field(default_factory=list)
    candidates: list = field(default_factory=list)
    unweighed: dict = field(default_factory=dict)
    groups: list = field(default_factory=list)
    same_signature: dict = field(default_factory=dict)
    hypotheses: list = field(default_factory=list)
    arrs: list = field(default_factory=list)
    t: np.ndarray = field(default_factory=lambda: np.empty(0))
    log_evidence: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    theta: dict = field(default_factory=dict)
    gamma: dict = field(default_factory=dict)
    rul_t: np.ndarray = field(default_factory=lambda: np.empty(0))
    rul: list = field(default_factory=list)
    decisions: list = field(default_factory=list)
    rejected: dict = field(default_factory=dict)
    evaluations: list = field(default_factory=list)
    min_ratio: float = EVIDENCE_RATIO
    ess: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    collapsed: dict = field(default_factory=dict)
    inadequate: dict = field(default_factory=dict)
    withheld: list = field(default_factory=list)
    on_record: dict = field(default_factory=dict)
    record_groups: list = field(default_factory=list)
    parts: dict = field(default_factory=dict)
    healthy: dict = field(default_factory=dict)
    seen_by: dict = field(default_factory=dict)
    apart: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        """Plain data for JSON (what ``prognosis.json`` holds): the decision, the evidence, the predictions and the
        settings (:attr:`settings`); ``status`` is ``"no alarm"``, ``"no candidate"`` or the decision's."""
        result, decision = self, self.decision
        summary = {"detection_time": result.detection_time, "fired": result.fired, "transient": result.transient,
                   "late": result.late, "candidates": result.candidates,
                   # every fault of the model (sensors too) a single fault of which fires the ARRs that fired
                   "consistent": result.consistent,
                   # sensors consistent with them whose fault is not weighed (an ARR integrates the reading)
                   "unweighed": result.unweighed,
                   "indistinguishable": [g for g in result.groups if len(g) > 1], "arrs": result.arrs,
                   # pairs the structure tells apart but this record's operating regime does not
                   "indistinguishable_on_record": result.on_record,
                   "candidate": None if decision is None else decision.candidate,
                   "status": "no alarm" if result.detection_time is None else (
                       "no candidate" if decision is None else decision.status),
                   "degradation": None if decision is None else decision.degradation,
                   "same_signature": [] if decision is None else list(decision.same_signature),
                   # ARRs that fired later and that no candidate sees: another fault than the one decided on
                   "unexplained": {} if decision is None else dict(decision.unexplained),
                   # why the status is not the evidence's alone (every law of every candidate contradicted)
                   "reason": "" if decision is None else decision.reason,
                   **self.settings, "evidence": {}, "predictions": [], "decisions": []}
        if decision is None:
            return summary
        summary.update({"candidate_ratio": finite_or_none(min(decision.candidate_ratio, 1e300)),
                        "degradation_decided": decision.degradation_decided,
                        "degradation_ratio": finite_or_none(min(decision.degradation_ratio, 1e300))})
        for row, h in enumerate(result.hypotheses):
            summary["evidence"][h.name] = {"log_evidence": finite_or_none(result.log_evidence[-1, row]),
                                           "probability": decision.probabilities[h.name],
                                           "rejected": result.rejected.get(h.name),
                                           "inadequate": result.inadequate.get(h.name),
                                           "theta_mean": float(result.theta["mean"][-1, row]),
                                           "gamma_mean": float(result.gamma["mean"][-1, row]),
                                           # a pair's estimate of each of its parameters
                                           **({"parameters": {c: float(v[-1]) for c, v in result.parts[h.name].items()}}
                                              if h.name in result.parts else {})}
        best = result.monitor_result()
        percentiles = best.rul_percentiles((5, 25, 50, 75, 95))
        for k, t in enumerate(result.rul_t):
            withheld = result.withheld[k] if k < len(result.withheld) else None
            if withheld:  # undecided: no figure rather than a band from a law the data contradict
                summary["predictions"].append({"t": float(t), **{key: None for key in RUL_KEYS}, "withheld": withheld})
            else:
                summary["predictions"].append({
                    "t": float(t), "rul_mean": finite_or_none(best.rul_mean[k]),
                    "rul_p5": finite_or_none(percentiles[k, 0]),
                    "rul_p25": finite_or_none(percentiles[k, 1]), "rul_median": finite_or_none(percentiles[k, 2]),
                    "rul_p75": finite_or_none(percentiles[k, 3]), "rul_p95": finite_or_none(percentiles[k, 4]),
                    "censored": float(result.rul[k].censored_weight[0])})
            d = result.decisions[k]
            summary["decisions"].append({"t": float(t), "candidate": d.candidate, "status": d.status,
                                         "degradation": d.degradation, "unexplained": sorted(d.unexplained)})
        top = result.index(max(decision.probabilities, key=decision.probabilities.get))
        summary["last"] = {**(summary["predictions"][-1] if summary["predictions"] else {"t": float(result.t[-1])}),
                           "hypothesis": result.hypotheses[top].name,
                           "theta_mean": float(result.theta["mean"][-1, top]),
                           "gamma_mean": float(result.gamma["mean"][-1, top])}
        return summary

    @property
    def decision(self) -> Decision | None:
        """The decision on all the data (None without an alarm or a candidate)."""
        if not self.t.size:
            return None
        return self.decide_at(self.log_evidence[-1], float(self.t[-1]), self.record_groups or self.groups,
                              {name: {c: float(v[-1]) for c, v in parts.items()} for name, parts in self.parts.items()},
                              self.apart)

    def decide_at(self, log_evidence: np.ndarray, time: float, groups: Sequence,
                  estimates: Mapping[str, Mapping[str, float]] = {},
                  apart: Mapping[str, Mapping[str, float]] = {}) -> Decision:
        """The decision at ``time`` on the hypotheses' evidence then (:func:`decide`, :meth:`revised`), the joint
        hypotheses not more probable than their parts alone, with a part estimated within its healthy values
        (``estimates``: joint hypothesis name -> parameter -> value then), or with a part not seen apart from
        the other (``apart``: name -> parameter -> the log likelihood of its change in its own ARRs),
        held back (:func:`held_back`)."""
        held = held_back(self.hypotheses, log_evidence, self.rejected, self.min_ratio, estimates, self.healthy,
                         self.seen_by, apart)
        decision = decide(self.hypotheses, log_evidence, groups, {**self.rejected, **held}, self.min_ratio,
                          self.same_signature)
        return self.revised(decision, time, held)

    @property
    def contradicted(self) -> bool:
        """No fault weighed explains the residuals: at the end the most probable hypothesis not rejected is
        contradicted by the data (inadequate), or every one was rejected; or the most probable wear is
        contradicted while still in the running (within FREEZE_BELOW of the best's log evidence).

        The most probable, not every one: a hypothesis far behind in evidence is weighed on but no longer
        moved, so it is not judged either, and it explains the record no better for that.  The wears
        apart: a sensor's fault, its gain following whatever the residuals do, can pass for two wears (the
        flow sensor's gain for the pipe's friction and the tank's outflow, both wearing), and explaining
        them does not make a second run of two wears at once needless.

        >>> IsolationResult(None).contradicted   # nothing weighed (no alarm): nothing contradicted
        False
        """
        if not self.hypotheses or self.log_evidence.size == 0:
            return False
        standing = [i for i, h in enumerate(self.hypotheses) if h.name not in self.rejected]
        if not standing:
            return True
        last = self.log_evidence[-1]
        best = max(standing, key=lambda i: last[i])
        wears = [i for i in standing if not self.hypotheses[i].sensor and last[i] >= last[best] - FREEZE_BELOW]
        worn = max(wears, key=lambda i: last[i], default=best)
        return self.hypotheses[best].name in self.inadequate or self.hypotheses[worn].name in self.inadequate

    @property
    def wearless(self) -> bool:
        """A fault was detected and no single parameter explains the ARRs fired: no parameter's signature
        holds them all, so that, one fault at a time, only the sensors' faults are weighed, or nothing.

        Two parameters wearing at once fire the ARRs either one sees, more than any one of them sees
        when the second wear shows from the start; a sensor's gain shifting each of those ARRs (the
        pipe's flow sensor, for its friction and the tank's outflow) may then explain the residuals
        alone, and its doing so does not make two wears at once needless.

        >>> IsolationResult(None).wearless   # no alarm
        False
        >>> IsolationResult(1.0, candidates=["sensor Q"]).wearless, IsolationResult(1.0, candidates=["R_f"]).wearless
        (True, False)
        """
        return self.detection_time is not None and all(sensor_signal(c) is not None
                                                       for c in [*self.candidates, *self.unweighed])

    def revised(self, decision: Decision, time: float, held: Mapping = {}) -> Decision:
        """``decision`` at ``time`` with what the evidence alone does not say: the ARRs fired late that no
        candidate sees (:meth:`unexplained`), and no claim when the data contradict every hypothesis.

        Evidence only ranks the hypotheses weighed; when every one not rejected is inadequate (its
        innovations drift), the best of them is still a wrong explanation: a sensor's fault, a law
        outside the family or a fault without a failure value.  The status is then "undecided"
        (``"rejected"`` when every hypothesis was rejected), naming every fault of the model whose
        signature holds the fired ARRs.
        """
        decision = dataclasses.replace(decision, unexplained=self.unexplained(time))
        weighed = [h.name for h in self.hypotheses if h.name not in self.rejected and h.name not in held]
        if weighed and not all(name in self.inadequate for name in weighed):
            return decision
        what = (f"the data contradict every law of every candidate ({', '.join(self.candidates)})" if weighed
                else f"every hypothesis was rejected ({', '.join(self.candidates)})")
        return dataclasses.replace(
            decision, candidate=list(self.consistent) or decision.candidate,
            status="undecided" if weighed else "rejected", same_signature=(),
            reason=(f"{what}: a fault outside the hypotheses; the ARRs that fired ({', '.join(self.fired)}) are "
                    f"consistent with {', '.join(self.consistent) or 'no single fault of the model'}"))

    def unexplained(self, time: float) -> dict:
        """The ARRs fired late by ``time`` that no candidate is sensitive to, each with why (ARR name -> text)."""
        return {name: (f"{name} fired at t = {when:g} s, after the signature was read, and no candidate is "
                       f"sensitive to it: another fault ({', '.join(self.late_faults[name]) or 'none of the model'})")
                for name, when in self.late.items() if when <= time and name in self.late_faults}

    def index(self, name: str) -> int:
        """Row of the hypothesis ``"candidate/law"``."""
        names = [h.name for h in self.hypotheses]
        if name not in names:
            raise PrognosisError(f"no hypothesis {name!r} (hypotheses: {', '.join(names)})")
        return names.index(name)

    def monitor_result(self, hypothesis: str | None = None) -> MonitorResult:
        """The estimates of one hypothesis (default: the most probable at the end) with the mixture's RUL.

        A :class:`~prognosis.health_monitor.MonitorResult`, so its metrics, frames and plots apply.
        """
        if hypothesis is None:
            probabilities = self.decision.probabilities
            hypothesis = max(probabilities, key=probabilities.get)
        h = self.index(hypothesis)

        def pick(estimate):
            return {"mean": estimate["mean"][:, h], "rmad": estimate["rmad"][:, h],
                    "quantiles": estimate["quantiles"][:, h]}
        return MonitorResult(self.detection_time, t=self.t, theta=pick(self.theta), gamma=pick(self.gamma),
                             rul_t=self.rul_t, rul=self.rul,
                             evaluation=self.evaluations[0] if self.evaluations else None)
