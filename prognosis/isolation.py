"""Isolation by estimation: which parameter degrades, by which law, and its RUL, weighed by evidence.

:class:`IsolatingMonitor` needs what a user knows: the ARRs, the record, the residuals' noise on a
fault-free stretch, and the failure value of each parameter that can fail.  At the first alarm

1. the candidates are the parameters with a failure value that every fired ARR is sensitive to
   (:func:`~prognosis.hypotheses.signature_candidates`), the fired ARRs those in alarm over most of a
   confirmation window after the first alarm (a transient rules nothing out);
2. every candidate with every degradation law is a hypothesis; all of them run as the rows of one
   vectorized particle filter (:class:`~prognosis.particle_filter.ParticleFilter`), each
   predicting every residual an ARR sensitive to a candidate gives
   (:class:`~prognosis.hypotheses.HypothesisObservation`), its rate drawn from a prior on the life
   (:func:`~prognosis.hypotheses.rate_prior`) and kept by kernel smoothing
   (:class:`~prognosis.particle_filter.KernelSmoothing`);
3. each hypothesis accumulates its evidence, the filter's estimate of log p(y_1..k); a hypothesis
   whose estimate leaves its physical domain (a negative inertia) is rejected with the reason;
4. :func:`decide` ranks them: a candidate (and a law) is declared when its evidence beats every
   other by ``min_ratio``; candidates with the same effect on every residual
   (:func:`~prognosis.hypotheses.indistinguishable_groups`) are reported together;
5. the RUL is the mixture of the hypotheses' predictions weighted by their posterior probability
   (Bayesian model averaging), so an undecided law or candidate widens the prediction instead of
   being chosen at random.

The decision can change while data come in: it is made again at every RUL prediction.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from . import seeds
from .degradation import POWER_EXPONENTS, JointDegradation, PerAssetDegradation, degradation_model
from .hypotheses import (LIFE_PRIOR, SENSOR_LAWS, Hypothesis, HypothesisObservation, JointHypothesis, JointObservation,
                         additive, candidate_model, explaining, indistinguishable_groups, integral_increments,
                         law_distance, rate_prior,
                         record_separation, same_signature, sees, sensitivity, sensor_signal, signature_candidates)
from .likelihood import ResidualNoise, healthy_noise, integral_walk
from .monitor import MonitorResult, filter_stride
from .particle_filter import KernelSmoothing, ParticleFilter, check_particles, check_positive
from .resample_move import ResampleMoveFilter
from .rul import RULDistribution, RULPredictor
from .seeds import check_seed
from .errors import PrognosisError

__all__ = [
    "Decision", "IsolatingMonitor", "IsolationResult", "decide", "held_back", "LAWS", "HORIZON_STEPS", "METHODS",
]

METHODS = ("resample-move", "sir")
#: the competing laws by default: the two of Jha et al. (2016) and the flexible power law, which holds the
#: linear one and takes over where the data bend away from both
LAWS = ("linear", "exponential", "power")

EVIDENCE_RATIO = 100.0  # "decisive" on Jeffreys' scale: a hypothesis is declared beyond this ratio
MIXTURE_FLOOR = 1e-3  # hypotheses less probable than this are left out of the RUL mixture
PROCESS_NOISE = 0.1  # sigma_v per filter step, as a fraction of the candidate's resolution per sample
HORIZON_STEPS = 2000  # RUL horizon cap in filter steps, unless given
CONFIRM_STEPS = 20  # filter steps after the first alarm over which the fired ARRs are read
ADEQUACY_WINDOW = 30  # filter steps of standardized innovations a law's fit is judged on
#: mean standardized innovation over the window beyond which the law does not follow the residual: a
#: fitting law stays within about 1 (clean or noisy torsion-bar wear), a law that lags drifts to tens
ADEQUACY_LIMIT = 3.0
#: standardized innovations are clipped at this many sd before the window's mean is taken: a drifting
#: law still shows (each innovation beyond the limit counts in full up to here), one spike moves the
#: mean by at most SPIKE / ADEQUACY_WINDOW
SPIKE = 3 * ADEQUACY_LIMIT
#: log evidence behind the best hypothesis beyond which a hypothesis' particles are no longer moved
#: (its evidence still accumulates): 1e-8 of the best's probability, beyond any decision
FREEZE_BELOW = 8 * math.log(10.0)
DRIFT_AWAY_STEPS = 5  # consecutive filter steps beyond the healthy box, away from failure, that reject a hypothesis


@dataclass(frozen=True)
class Decision:
    """What the evidence says at one time.

    Attributes
    ----------
    candidate : str, list of str or None
        The isolated parameter; a list when several are indistinguishable (``status``
        ``"indistinguishable"``) or not yet told apart (``"undecided"``); None if every hypothesis
        was rejected.
    status : {"isolated", "indistinguishable", "undecided", "rejected"}
        ``"isolated"`` only when the evidence singles out one candidate *and* no other fault of the
        model (parameter or sensor) has its signature; otherwise ``"indistinguishable"``.
    candidate_ratio : float
        Evidence ratio of the reported candidate(s) over the best other one (inf when alone).
    degradation : str or None
        The law with the most evidence for the reported candidate(s).
    degradation_decided : bool
        Its ratio over the next law reaches the minimum ratio.
    degradation_ratio : float
    probabilities : dict
        Posterior probability of each hypothesis (``"candidate/law"``), uniform prior.
    same_signature : tuple of str
        The faults outside the reported candidate(s), parameters and ``"sensor <signal>"``, with the
        same fault signature over the ARRs: the evidence cannot have told them apart.
    unexplained : dict
        ARR name -> why it is unexplained: an ARR that fired after the signature was read, which no
        candidate is sensitive to (another fault, or a sensor's); the decision is about the first fault.
    reason : str
        Why the status is not the evidence's alone: when the data contradict every law of every
        candidate (or reject every hypothesis), no candidate is claimed; the status is
        ``"undecided"`` (``"rejected"``) and ``candidate`` lists the faults of the model, parameters
        and sensors, consistent with the ARRs that fired.
    """

    candidate: str | list | None
    status: str
    candidate_ratio: float
    degradation: str | None
    degradation_decided: bool
    degradation_ratio: float
    probabilities: dict
    same_signature: tuple = ()
    unexplained: dict = field(default_factory=dict)
    reason: str = ""

    def as_dict(self) -> dict:
        return {"candidate": self.candidate, "status": self.status, "candidate_ratio": _finite(self.candidate_ratio),
                "degradation": self.degradation, "degradation_decided": self.degradation_decided,
                "degradation_ratio": _finite(self.degradation_ratio), "probabilities": self.probabilities,
                "same_signature": list(self.same_signature), "unexplained": dict(self.unexplained),
                "reason": self.reason}


def decide(hypotheses: Sequence[Hypothesis], log_evidence: np.ndarray, groups: Sequence[Sequence[str]],
           rejected: Mapping[str, str] = {}, min_ratio: float = EVIDENCE_RATIO,
           signatures: Mapping[str, Sequence[str]] = {}) -> Decision:
    """Rank hypotheses by evidence: the candidate, then the law, each declared beyond ``min_ratio``.

    A candidate's evidence is the mean of its laws' (uniform priors over the candidates, then over each
    one's laws; a rejected law has none).  The best candidate is
    isolated when it beats every candidate outside its group of indistinguishable ones by
    ``min_ratio`` and ``signatures`` (candidate -> the other faults with its fault signature,
    :func:`~prognosis.hypotheses.same_signature`) names none; its group, or the faults sharing its
    signature, make it ``"indistinguishable"``; otherwise every candidate within the ratio of the
    best is reported, undecided.

    Examples
    --------
    >>> hs = [Hypothesis(c, law, 2.0, 1.0) for c in ("a", "b", "c") for law in ("linear", "exponential")]
    >>> log_z = np.array([0.0, -9.0, -1.0, -10.0, -20.0, -20.0])
    >>> d = decide(hs, log_z, [["a", "b"], ["c"]])
    >>> d.candidate, d.status, d.degradation, d.degradation_decided
    (['a', 'b'], 'indistinguishable', 'linear', True)
    >>> decide(hs, log_z, [["a"], ["b"], ["c"]]).status   # e^1 is not decisive
    'undecided'
    >>> d = decide(hs, log_z, [["a", "b"], ["c"]], signatures={"a": ["b", "k"], "b": ["a", "k"]})
    >>> d.status, d.same_signature   # a fault without a failure value shares their signature
    ('indistinguishable', ('k',))
    """
    log_z = np.array([-np.inf if h.name in rejected else float(v) for h, v in zip(hypotheses, log_evidence)])
    laws_of = Counter(h.candidate for h in hypotheses)
    # a uniform prior over the candidates, then over each one's laws: a pair with nine pairs of laws
    # weighs no more than a parameter with three
    probabilities = _softmax(log_z - np.log([laws_of[h.candidate] for h in hypotheses]))
    named = {h.name: float(p) for h, p in zip(hypotheses, probabilities)}
    if not np.isfinite(log_z).any():
        return Decision(None, "rejected", math.nan, None, False, math.nan, named)
    candidates = list(dict.fromkeys(h.candidate for h in hypotheses))
    by_candidate = {c: _logmeanexp(log_z[[h.candidate == c for h in hypotheses]]) for c in candidates}
    best = max(candidates, key=by_candidate.get)
    group = next((list(g) for g in groups if best in g), [best])
    members = [c for c in group if np.isfinite(by_candidate.get(c, -np.inf))]
    others = [by_candidate[c] for c in candidates if c not in group]
    margin = by_candidate[best] - max(others, default=-np.inf)
    if margin >= math.log(min_ratio):
        reported, status = members, ("isolated" if len(members) == 1 else "indistinguishable")
    else:
        close = [c for c in candidates if by_candidate[c] >= by_candidate[best] - math.log(min_ratio)]
        reported = list(dict.fromkeys(c for c in close for g in groups if c in g for c in g
                                      if np.isfinite(by_candidate.get(c, -np.inf)))) or close
        status = "undecided"
    laws = list(dict.fromkeys(h.law for h in hypotheses))
    by_law = {law: _logsumexp(log_z[[h.law == law and h.candidate in reported for h in hypotheses]]) for law in laws}
    ranked = sorted(laws, key=by_law.get, reverse=True)
    law_margin = by_law[ranked[0]] - (by_law[ranked[1]] if len(ranked) > 1 else -np.inf)
    twins = ()
    if status != "undecided":
        twins = tuple(dict.fromkeys(f for c in reported for f in signatures.get(c, ()) if f not in reported))
        status = "indistinguishable" if twins else status
    return Decision(reported[0] if len(reported) == 1 else reported, status, math.exp(min(margin, 700.0)),
                    ranked[0], bool(law_margin >= math.log(min_ratio)), math.exp(min(law_margin, 700.0)), named,
                    twins)


def held_back(hypotheses: Sequence, log_evidence: np.ndarray, rejected: Mapping[str, str] = {},
              min_ratio: float = EVIDENCE_RATIO) -> dict:
    """The joint hypotheses of a pair whose evidence (over its laws) does not beat each of its parameters'
    alone by ``min_ratio`` (name -> why): one fault explains the data as well, and two are claimed only
    when the data demand them.

    A candidate's evidence is the mean over its laws (a rejected law: none); a parameter without a
    single hypothesis (a second fault no fired ARR pointed to at the alarm) is not compared.

    >>> a, b = Hypothesis("a", "power", 2.0, 1.0), Hypothesis("b", "power", 2.0, 1.0)
    >>> hs = [a, b, JointHypothesis((a, b))]
    >>> sorted(held_back(hs, np.array([0.0, -50.0, 2.0])))   # e^2 over a alone: not decisive
    ['a/power + b/power']
    >>> held_back(hs, np.array([0.0, -50.0, 9.0]))
    {}
    """
    alone, pairs = {}, {}
    for h, value in zip(hypotheses, log_evidence):  # a rejected one counts with no evidence
        value = -np.inf if h.name in rejected else float(value)
        (pairs if isinstance(h, JointHypothesis) else alone).setdefault(h.candidate, []).append(value)
    why = {}  # pair candidate -> why it is held back
    for candidate, values in pairs.items():
        together = _logmeanexp(values)
        rivals = {m: _logmeanexp(alone[m]) for m in candidate.split(" + ")
                  if m in alone and np.isfinite(alone[m]).any()}
        best = max(rivals, key=rivals.get, default=None)
        if best is not None and together - rivals[best] < math.log(min_ratio):
            why[candidate] = (f"{candidate} explain the residuals no better than {best} alone (evidence ratio "
                              f"{math.exp(min(together - rivals[best], 700.0)):.3g} < {min_ratio:g})")
    return {h.name: why[h.candidate] for h in hypotheses
            if isinstance(h, JointHypothesis) and h.name not in rejected and h.candidate in why}


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
        drift, :data:`ADEQUACY_LIMIT`); it is left out of the RUL from then on.
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
        summary.update({"candidate_ratio": _finite(min(decision.candidate_ratio, 1e300)),
                        "degradation_decided": decision.degradation_decided,
                        "degradation_ratio": _finite(min(decision.degradation_ratio, 1e300))})
        for row, h in enumerate(result.hypotheses):
            summary["evidence"][h.name] = {"log_evidence": _finite(result.log_evidence[-1, row]),
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
                    "t": float(t), "rul_mean": _finite(best.rul_mean[k]), "rul_p5": _finite(percentiles[k, 0]),
                    "rul_p25": _finite(percentiles[k, 1]), "rul_median": _finite(percentiles[k, 2]),
                    "rul_p75": _finite(percentiles[k, 3]), "rul_p95": _finite(percentiles[k, 4]),
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
        return self.decide_at(self.log_evidence[-1], float(self.t[-1]), self.record_groups or self.groups)

    def decide_at(self, log_evidence: np.ndarray, time: float, groups: Sequence) -> Decision:
        """The decision at ``time`` on the hypotheses' evidence then (:func:`decide`, :meth:`revised`), the joint
        hypotheses not more probable than their parts alone held back (:func:`held_back`)."""
        held = held_back(self.hypotheses, log_evidence, self.rejected, self.min_ratio)
        decision = decide(self.hypotheses, log_evidence, groups, {**self.rejected, **held}, self.min_ratio,
                          self.same_signature)
        return self.revised(decision, time, held)

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

        A :class:`~prognosis.monitor.MonitorResult`, so its metrics, frames and plots apply.
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


class IsolatingMonitor:
    """Detection, then candidates, laws and rates weighed in one filter, then the RUL.

    Parameters
    ----------
    arrs : sequence of ARR
    failures : mapping
        Failure value of each parameter that can fail, e.g. ``{"b_Md": 0.3, "J_Md": 1.8e-3}``.
    noise_std : mapping
        Standard deviation of each ARR's residual on healthy data (by ARR name).
    laws : sequence of str or mapping
        Competing degradation laws: names of built-in ones (default :data:`LAWS`: linear,
        exponential and the power law of the time since onset, whose exponent is estimated), or
        ``{name: model}`` (any model of :mod:`prognosis.degradation`, e.g. a
        :class:`~prognosis.degradation.CustomDegradation`).
    candidates : sequence of str, optional
        Only these candidates (each parameter needs a failure value; a sensor is ``"sensor <signal>"``),
        instead of those of the signature.
    sensors : bool
        Weigh the faults of the sensors whose signature holds the fired ARRs too (on by default), by
        the laws :data:`~prognosis.hypotheses.SENSOR_LAWS`: an offset of the reading from 0, a bias
        or a drift, or a gain.  A sensor's fault has no failure value: the RUL is that of the wear hypotheses
        (given that a parameter wears), and none is given when only sensors are probable.
    pairs : bool
        ``method="resample-move"`` and no ``candidates`` only, off by default: weigh two parameters
        degrading at once too
        (:meth:`pairs_for`, :class:`~prognosis.hypotheses.JointHypothesis`), each by each of ``laws``;
        a pair is declared only when its evidence beats each of its members' alone by
        ``min_ratio`` (one fault unless the data demand two), and its RUL is that of the first failure.
        Off by default: on a noisy residual with a derivative (the pipe's flow) an inductance paired
        with the wearing resistance absorbs the model's misfit and wins on a single fault, and a
        run with pairs costs 2-9 times one without.
    dt : float
        Filter step (s), a multiple of the record's step.
    n_particles : int
        Particles per hypothesis.
    inflation : float, optional
        Multiplier of the residual noise covariance in the likelihood; default 4 with ``method="sir"``
        (Jha et al. (2016)), 1 with ``"resample-move"`` (the noise as measured on the healthy stretch).
    life : (float, float)
        Prior of the life from nominal to failure, in filter steps (log-uniform).
    rate : (float, float), optional
        A prior interval of the rate instead (uniform; the same for every hypothesis).
    process_noise : float
        ``method="sir"`` only: sigma_v per step as a fraction of the candidate's resolution per
        sample (the residual noise over the sensitivity of the residual to it at the alarm).
    discount : float
        ``method="sir"`` only: kernel smoothing of the rate (:class:`~prognosis.particle_filter.KernelSmoothing`).
    rul_every : int
        Predict the RUL every this many filter steps.
    horizon : float, optional
        RUL horizon cap (s); default 2000 filter steps.
    detection : mapping
        Options of :func:`diagnosis.evaluate` (``margin``, ``persistence``...); a mapping per ARR
        name is used for that ARR.
    min_ratio : float
        Evidence ratio before a candidate or a law is declared.
    healthy_until : float, optional
        End of the stretch the user declares fault-free (the one the noise was calibrated on):
        alarms there are not faults (a start-up transient) and start nothing.
    method : {"resample-move", "sir"}
        The filter: ``"resample-move"`` (the default) weighs each law's static parameters, theta at the
        alarm and the rate, by their posterior on the whole history and moves its particles by MCMC
        (:class:`~prognosis.resample_move.ResampleMoveFilter`), with the residual noise measured on
        the healthy stretch, correlated between ARRs and growing with the candidate
        (:mod:`~prognosis.likelihood`), divided by the gaps' information excess; it does not collapse
        on a clean residual, and a law the innovations contradict is reported inadequate.  ``"sir"`` is
        the random-walk SIR filter of Jha et al. (2016) with kernel smoothing of the rate
        (:class:`~prognosis.particle_filter.ParticleFilter`): no cheaper on the demos, its cloud collapses
        when the residual is much sharper than its process noise, and its random walk absorbs a
        wrong law instead of showing it (no adequacy check).
    domains : mapping, optional
        Parameter -> open interval ``(lo, hi)`` of its physical domain, as the model declares it
        (:attr:`bondgraph.BondGraph.domains`); a hypothesis whose estimate leaves it is rejected.
        A parameter not given keeps the sign of its nominal value (:func:`~prognosis.hypotheses.physical_domain`).
    seed : int or numpy.random.SeedSequence
        The filter, the prior of the rates and each hypothesis' RUL predictor draw from streams of
        their own spawned from it (:mod:`prognosis.seeds`), so no two seeds share a stream.

    Examples
    --------
    The RLC circuit's resistance drifting up linearly from t = 0.5 s; the monitor is told only
    that R fails at 20 ohm and L at 2 H:

    >>> from bondgraph import simulate
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> bg = rlc_circuit()
    >>> t = np.linspace(0.0, 3.0, 3001)
    >>> drift = lambda t: 10.0 + 4.0 * max(0.0, t - 0.5)
    >>> record = simulate(bg, (0.0, 3.0), {"V": lambda t: 5 + np.sin(7 * t)}, t_eval=t,
    ...                   parameters={"R": drift}).record()
    >>> arrs = derive_arrs(bg)
    >>> monitor = IsolatingMonitor(arrs, {"R": 20.0, "L": 2.0}, noise_std={a.name: 1e-3 for a in arrs},
    ...                            dt=0.01, n_particles=100, detection={"margin": 0.01})
    >>> result = monitor.run(record)
    >>> d = result.decision
    >>> d.candidate, d.status, d.degradation, d.same_signature   # L fires the same ARR: not isolable in the model
    ('R', 'indistinguishable', 'linear', ('L',))
    """

    def __init__(self, arrs: Sequence, failures: Mapping[str, float], *, noise_std: Mapping[str, float],
                 laws: Sequence[str] | Mapping = LAWS, candidates: Sequence[str] | None = None,
                 sensors: bool = True, dt: float = 0.1, n_particles: int = 500, inflation: float | None = None,
                 life: tuple = LIFE_PRIOR,
                 rate: tuple | None = None, process_noise: float = PROCESS_NOISE, discount: float = 0.98,
                 rul_every: int = 10, horizon: float | None = None, detection: Mapping | None = None,
                 min_ratio: float = EVIDENCE_RATIO, healthy_until: float | None = None,
                 domains: Mapping[str, tuple] | None = None, method: str = "resample-move", pairs: bool = False,
                 seed: int | np.random.SeedSequence = 0):
        if method not in METHODS:
            raise PrognosisError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
        self.method = method
        self.arrs = list(arrs)
        self.failures = {str(k): float(v) for k, v in failures.items()}
        parameters = {p: a.values[p] for a in self.arrs for p in a.parameters}
        for name in self.failures:
            if name not in parameters:
                raise PrognosisError(f"failure value for {name!r}: no ARR contains that parameter "
                                     f"(parameters the ARRs see: {', '.join(sorted(parameters))})")
        self.nominal = {p: float(parameters[p]) for p in self.failures}
        for name, value in self.failures.items():
            if value == self.nominal[name]:
                raise PrognosisError(f"failure value of {name!r} equals its nominal value {value:g}")
        if not isinstance(noise_std, Mapping):
            raise PrognosisError(f"noise_std: give the standard deviation of each ARR's residual by ARR name, "
                                 f"got a {type(noise_std).__name__}")
        missing = [a.name for a in self.arrs if a.name not in noise_std]
        if missing:
            raise PrognosisError(f"noise_std has no value for the ARR(s) {missing}")
        self.noise_std = {k: check_positive(v, f"noise_std[{k!r}]") for k, v in noise_std.items()}
        self.laws = dict(laws) if isinstance(laws, Mapping) else {name: None for name in laws}
        if not self.laws:
            raise PrognosisError("laws: give at least one degradation law")
        if candidates is not None:
            read = {s for a in self.arrs for s in a.signals}
            unknown = [c for c in candidates if c not in self.failures and sensor_signal(c) not in read]
            if unknown:
                raise PrognosisError(f"candidate {unknown[0]!r} has no failure value and is no sensor an ARR reads "
                                     f"(failure values: {', '.join(self.failures)})")
        self.candidates = None if candidates is None else list(candidates)
        self.sensors, self.pairs = bool(sensors), bool(pairs)
        self.dt, self.n_particles = check_positive(dt, "dt"), check_particles(n_particles)
        # the random walk's likelihood is widened as in Jha et al. (2016); the resample-move one takes the
        # noise as measured
        self.inflation = check_positive((4.0 if method == "sir" else 1.0) if inflation is None else inflation,
                                        "inflation")
        self.life, self.rate, self.process_noise, self.discount = life, rate, process_noise, discount
        if isinstance(rul_every, bool) or int(rul_every) != rul_every or rul_every < 1:
            raise PrognosisError(f"rul_every must be a positive whole number of filter steps, got {rul_every!r}")
        self.rul_every = int(rul_every)
        self.horizon = HORIZON_STEPS * self.dt if horizon is None else check_positive(horizon, "horizon")
        self.detection = dict(detection or {})
        self.min_ratio, self.seed = float(min_ratio), check_seed(seed)
        self.domains = {str(k): (float(v[0]), float(v[1])) for k, v in (domains or {}).items()}
        for name, (lo, hi) in self.domains.items():
            if name in self.failures and not lo <= self.failures[name] <= hi:
                raise PrognosisError(f"failure value of {name!r} ({self.failures[name]:g}) lies outside its physical "
                                     f"domain ({lo:g}, {hi:g})")
        self.healthy_until = -math.inf if healthy_until is None else float(healthy_until)

    # -- the pipeline ------------------------------------------------------------------------
    def run(self, record, *, evaluations: Sequence | None = None,
            progress: Callable[[int, int, float], None] | None = None) -> IsolationResult:
        """Process a whole record (mapping or DataFrame with ``t`` and the ARRs' signals).

        ``evaluations``: the ARRs' detection on this record, if already computed (one per ARR, in
        order).  ``progress(done, total, t)`` is called after every 1 % of the filter steps.
        """
        if evaluations is None:
            evaluations = [a.evaluate(record, **self.options_for(a)) for a in self.arrs]
        elif len(evaluations) != len(self.arrs):
            raise PrognosisError(f"evaluations: {len(evaluations)} given for {len(self.arrs)} ARRs")
        result = IsolationResult(None, evaluations=evaluations, min_ratio=self.min_ratio)
        t = evaluations[0].t
        alarms = [np.flatnonzero(e.alarm & (t > self.healthy_until)) for e in evaluations]
        firsts = [a[0] for a in alarms if a.size]
        if not firsts:
            return result
        k = min(firsts)
        result.detection_time = float(t[k])
        stride = filter_stride(t, self.dt)
        result.fired, result.transient = self.signature(evaluations, k, stride)
        result.consistent = explaining(self.arrs, result.fired)
        result.candidates = (self.candidates if self.candidates is not None
                             else signature_candidates(self.arrs, self.failures, result.fired)
                             + [c for c in result.consistent if self.sensors and sensor_signal(c)])
        result.unweighed = {c: why for c in result.candidates if (why := self._unmodelled(c, self.arrs))}
        result.candidates = [c for c in result.candidates if c not in result.unweighed]
        weigh_pairs = self.method != "sir" and self.pairs and self.candidates is None
        pairs, pair_groups = self.pairs_for(result) if weigh_pairs else ([], [])
        if not result.candidates and not pairs:
            return result
        members = {m for pair in pairs for m in pair}
        used = [i for i, a in enumerate(self.arrs) if any(sees(a, c) for c in [*result.candidates, *members])]
        arrs = [self.arrs[i] for i in used]
        result.arrs = [a.name for a in arrs]
        result.late = self.late_firings(evaluations, k, stride, result.fired)
        result.late_faults = {name: [f for f in explaining(self.arrs, [name]) if f not in result.candidates]
                              for name in result.late if name not in result.arrs}
        result.groups = indistinguishable_groups(arrs, result.candidates) if result.candidates else []
        # isolable in the model: over every ARR given, not only those the filter weighs
        result.same_signature = {c: same_signature(self.arrs, c) for c in result.candidates}
        result.hypotheses, result.rejected = self.hypotheses_for(result.candidates)
        result.hypotheses += [h for pair in pairs for h in self.pair_hypotheses(pair)]
        result.groups += pair_groups
        start = self.settled(evaluations, k, stride, result.transient)
        self._filter(result, [evaluations[i] for i in used], arrs, start, progress)
        return result

    def late_firings(self, evaluations: list, k: int, stride: int, fired: Sequence[str]) -> dict:
        """ARR name -> the time an ARR outside ``fired`` fires after the signature's window from ``k``.

        By the signature's rule (in alarm over at least half of CONFIRM_STEPS filter steps), dated at
        the end of the first such window: the time the firing is known, so a decision before it
        does not use it.
        """
        width = CONFIRM_STEPS * stride
        t = evaluations[0].t
        late = {}
        for a, e in zip(self.arrs, evaluations):
            if a.name in fired or t.size < k + 2 * width:
                continue
            counts = np.concatenate([[0], np.cumsum(e.alarm[k + width:])])
            share = (counts[width:] - counts[:-width]) / width  # over [j, j + width), j from k + width
            ends = np.flatnonzero(share >= 0.5)
            if ends.size:
                late[a.name] = float(t[k + width + ends[0] + width - 1])
        return late

    def settled(self, evaluations: list, k: int, stride: int, transient: Sequence[str]) -> int:
        """The sample the filter starts from: after the last alarm of a transient ARR in the confirmation window.

        A transient (an ARR blind to the fault alarming for a few samples) shows a discontinuity: a
        step of the parameter, an input's jump.  Over it the residuals carry the ringing and the
        derivative windows that straddle the kink, which no law of theta explains; a law fitted
        through them is wrong from its start.  Without a transient, the first alarm ``k``.
        """
        window = slice(k, k + CONFIRM_STEPS * stride)
        last = [k + int(np.flatnonzero(e.alarm[window])[-1]) for a, e in zip(self.arrs, evaluations)
                if a.name in transient and e.alarm[window].any()]
        return max(last) + 1 if last else k

    def signature(self, evaluations: list, k: int, stride: int) -> tuple[list, list]:
        """The ARRs that fired, read over CONFIRM_STEPS filter steps from the first alarm at sample ``k``.

        An ARR in alarm over at least half of the window has fired; one that alarmed only in part of
        it is a transient (an input's discontinuity, the ringing of a step) and rules nothing out: a
        step of one parameter can upset, for a few samples, an ARR blind to it.  When no ARR stays in
        alarm over half of the window, those alarming at ``k`` are the signature.  Returns (fired,
        transient).
        """
        window = slice(k, k + CONFIRM_STEPS * stride)
        share = {a.name: float(np.mean(e.alarm[window])) for a, e in zip(self.arrs, evaluations)}
        fired = [name for name, s in share.items() if s >= 0.5]
        if not fired:
            fired = [a.name for a, e in zip(self.arrs, evaluations) if e.alarm[k]]
        return fired, [name for name, s in share.items() if s > 0 and name not in fired]

    def options_for(self, arr) -> dict:
        """This ARR's detection options: its own entry when ``detection`` is keyed by ARR name, else the shared ones."""
        names = {a.name for a in self.arrs}
        if self.detection and set(self.detection) <= names:
            return dict(self.detection.get(arr.name, {}))
        return dict(self.detection)

    def hypotheses_for(self, candidates: list) -> tuple[list, dict]:
        """Every candidate with every law (a sensor's with the sensor laws), and those rejected before any
        data (name -> reason)."""
        hypotheses, rejected = [], {}
        for c in candidates:
            signal = sensor_signal(c)
            if signal is not None:
                hypotheses += [Hypothesis.of_sensor(signal, law) for law in SENSOR_LAWS]
                continue
            for law in self.laws:
                h = Hypothesis(c, law, self.failures[c], self.nominal[c], self.domains.get(c))
                hypotheses.append(h)
                if law == "exponential" and h.failure * h.nominal <= 0:
                    rejected[h.name] = (f"an exponential law keeps the sign of {c} (nominal {h.nominal:g}), "
                                        f"so it never reaches {h.failure:g}")
        return hypotheses, rejected

    def pairs_for(self, result: IsolationResult) -> tuple[list, list]:
        """The pairs of parameters weighed as two faults at once, and their groups of indistinguishable pairs.

        Each parameter candidate with every other parameter that has a failure value and that an ARR
        sees (a second fault may show first in ARRs the first one already fired, or in others later);
        without a single candidate (no one parameter sees every fired ARR), every pair that does.  A
        pair is left out when its members act on the residuals in proportion (no record tells how
        much each moved) or when an ARR multiplies them (their changes do not add).  Two pairs whose
        members are pairwise indistinguishable are one group.
        """
        seen = [p for p in self.failures if any(p in a.parameters for a in self.arrs)]
        groups = indistinguishable_groups(self.arrs, seen)
        group_of = {p: i for i, g in enumerate(groups) for p in g}
        singles = [c for c in result.candidates if sensor_signal(c) is None]
        if singles:
            pairs = [(c, q) for c in singles for q in seen if q != c]
        else:
            covers = {p: {a.name for a in self.arrs if p in a.parameters} for p in seen}
            pairs = [(c, q) for i, c in enumerate(seen) for q in seen[i + 1:]
                     if set(result.fired) <= covers[c] | covers[q]]
        kept, keys = [], {}
        for c, q in pairs:
            key = frozenset((group_of[c], group_of[q]))
            if group_of[c] == group_of[q] or any({c, q} == set(k) for k in kept) or additive(self.arrs, c, q):
                continue
            kept.append((c, q))
            keys.setdefault(key, []).append(f"{c} + {q}")
        return kept, [g for g in keys.values() if len(g) > 1]

    def pair_hypotheses(self, pair: tuple) -> list[JointHypothesis]:
        """Two parameters degrading at once, each by each of the laws: a hypothesis per pair of laws (an
        exponential law left out for a parameter whose sign it cannot take to its failure value)."""
        options = [[Hypothesis(c, law, self.failures[c], self.nominal[c], self.domains.get(c)) for law in self.laws
                    if law != "exponential" or self.failures[c] * self.nominal[c] > 0] for c in pair]
        return [JointHypothesis((first, second)) for first in options[0] for second in options[1]]

    @staticmethod
    def _unmodelled(candidate: str, arrs: Sequence) -> str:
        """Why a sensor's fault has no observation model on ``arrs`` ("" when it has one on each, or is a
        parameter): an ARR integrates its reading, and no law of the offset from its onset gives the
        integral since the record's start."""
        if sensor_signal(candidate) is None:
            return ""
        for a in arrs:
            if sees(a, candidate):
                try:
                    candidate_model(a, candidate)
                except PrognosisError as error:
                    return str(error)
        return ""

    def _filter(self, result: IsolationResult, evaluations: list, arrs: list, k0: int, progress) -> None:
        hypotheses = result.hypotheses
        noise = np.array([self.noise_std[a.name] for a in arrs])
        # a joint hypothesis starts each of its parameters where the alarm puts it
        starts = [tuple(self.start_interval(part, evaluations, arrs, k0, noise) for part in h.parts)
                  if isinstance(h, JointHypothesis) else self.start_interval(h, evaluations, arrs, k0, noise)
                  for h in hypotheses]
        self._reject_wrong_side(result, evaluations, arrs, k0, noise)
        t = evaluations[0].t
        stride = filter_stride(t, self.dt)
        if self.method == "sir":
            observation = HypothesisObservation(arrs, hypotheses)
            bounds = (np.array([s[0] for s in starts]), np.array([s[1] for s in starts]))
            # a model per row: sigma_v is on the scale of each candidate
            models = tuple(self.law(h, s[2]) for h, s in zip(hypotheses, starts))
            bank = PerAssetDegradation(models, tuple(range(len(models))))
            pf = ParticleFilter(bank, observation,
                                n_particles=self.n_particles, dt=self.dt, noise_std=noise, inflation=self.inflation,
                                gamma_std=np.zeros(bank.n_gamma), adaptation=KernelSmoothing(self.discount),
                                seed=seeds.spawn(self.seed, seeds.FILTER))
            rng = seeds.generator(self.seed, seeds.RATE_PRIOR)
            gamma0 = np.stack([self.rate_particles(h, rng, bank.n_gamma, offset=_offset(s))
                               for h, s in zip(hypotheses, starts)])
            pf.initialize(bounds, gamma0=gamma0, assets=len(hypotheses))
            models = [(m,) for m in models]
        else:
            pf, observation, models = self._resample_move(hypotheses, starts, evaluations, arrs, stride)
        steps = range(k0, t.size, stride)
        information = self._information(result, observation, evaluations, noise, steps)
        every = -(-len(steps) // 100)
        rows, rul_t, rul, decisions, ess, innovations = [], [], [], [], [], []
        predictors, away = {}, np.zeros(len(hypotheses), int)
        boxes = np.array([self.healthy_box(h, arrs) for h in hypotheses])
        for done, k in enumerate(steps, 1):
            y = np.array([-e.residual[k] for e in evaluations])
            points = [[p[k] for p in e.points] for e in evaluations]
            if self.method != "sir":  # far behind the best, or not following the data: weighed on, not moved
                names = [h.name for h in hypotheses]
                pf.frozen = ((pf.log_evidence < pf.log_evidence.max() - FREEZE_BELOW)
                             | np.array([n in result.inadequate for n in names]))
            diagnostics = pf.step(np.broadcast_to(y, (len(hypotheses), y.size)), points)
            ess.append(diagnostics.ess)
            if diagnostics.innovation is not None:
                innovations.append(diagnostics.innovation)
                self._check_adequacy(result, hypotheses, arrs, innovations, float(t[k]))
            # a cloud collapsed at this step is no band now (a random-walk cloud may spread again later)
            collapsed_now = {hypotheses[row].name: float(t[k]) for row in np.flatnonzero(diagnostics.collapsed)}
            for name, time in collapsed_now.items():
                result.collapsed.setdefault(name, time)
            estimate = pf.estimate()
            self._reject(result, hypotheses, estimate, float(t[k]))
            away = self._reject_drift_away(result, hypotheses, estimate, float(t[k]), boxes, away)
            rows.append((float(t[k]), pf.log_evidence.copy(), estimate))
            if (done - 1) % self.rul_every == 0 or done == len(steps):
                groups, result.on_record = self._record_groups(result, information[done - 1], pf.log_evidence,
                                                               np.ravel(estimate["theta_mean"]))
                result.record_groups = groups
            if (done - 1) % self.rul_every == 0:
                decision = result.decide_at(pf.log_evidence, float(t[k]), groups)
                distribution, reason = self._mixture(pf, hypotheses, decision, predictors, models, key=done,
                                                     left_out={**collapsed_now, **result.inadequate})
                rul.append(distribution)
                result.withheld.append(reason)
                rul_t.append(float(t[k]))
                decisions.append(decision)
            if progress is not None and (done % every == 0 or done == len(steps)):
                progress(done, len(steps), float(t[k]))
        result.t = np.array([r[0] for r in rows])
        result.log_evidence = np.array([r[1] for r in rows])
        for key in ("theta", "gamma"):  # of gamma, the rate (a law's other gammas are not reported)
            first = (lambda v: v) if key == "theta" else (lambda v: v[:, 0])
            mean = np.array([first(r[2][f"{key}_mean"]) for r in rows]).reshape(len(rows), -1)
            rmad = np.array([first(r[2][f"{key}_rmad"]) for r in rows]).reshape(len(rows), -1)
            quantiles = np.array([first(r[2][f"{key}_quantiles"]) for r in rows]).reshape(len(rows), -1, 3)
            setattr(result, key, {"mean": mean, "rmad": rmad, "quantiles": quantiles})
        result.rul_t, result.rul, result.decisions = np.array(rul_t), rul, decisions
        result.ess = np.array(ess)
        for row, h in enumerate(hypotheses):  # a joint hypothesis' estimate of each of its parameters
            if isinstance(h, JointHypothesis):
                result.parts[h.name] = {part.candidate: np.array([r[2]["components"][c]["theta_mean"][row]
                                                                  for r in rows]) for c, part in enumerate(h.parts)}

    def _resample_move(self, hypotheses: list, starts: list, evaluations: list, arrs: list, stride: int):
        """The resample-move filter over the hypotheses' static parameters, its observation, and each row's
        models (one per parameter, for the RUL).

        Without a joint hypothesis theta is (H, N).  With one it is (H, N, C): component c of a row is its
        c-th parameter (a single hypothesis' others fixed and blind, so that all weigh in one filter on
        the same residuals), each by its own law with its own gammas.
        """
        parts = [h.parts if isinstance(h, JointHypothesis) else (h,) for h in hypotheses]
        part_starts = [s if isinstance(h, JointHypothesis) else (s,) for h, s in zip(hypotheses, starts)]
        width = max(len(p) for p in parts)
        banks, observations, theta_lo, theta_hi, gamma_lo, gamma_hi, logs = [], [], [], [], [], [], []
        for c in range(width):
            mine = [p[c] if c < len(p) else None for p in parts]  # None: this row has no c-th parameter
            bank = PerAssetDegradation(tuple(self.law(h, 0.0) if h is not None else degradation_model("linear")
                                             for h in mine), tuple(range(len(mine))))
            g = bank.n_gamma
            ends = [s[c] if c < len(s) else (0.0, 0.0, 0.0) for s in part_starts]
            rates = np.array([self.gamma_bounds(h, g, offset=_offset(e)) if h is not None else [[0.0] * g] * 2
                              for h, e in zip(mine, ends)])  # (H, 2, G)
            # the rate log-uniform on the prior of the life (uniform on a given interval), other gammas
            # log-uniform; a coordinate the prior fixes (a bias's rate, 0) is not
            log_gamma = np.arange(g) > 0 if self.rate is not None else np.ones(g, bool)
            banks.append(bank)
            observations.append(HypothesisObservation(arrs, mine))
            theta_lo.append([e[0] for e in ends])
            theta_hi.append([e[1] for e in ends])
            gamma_lo.append(rates[:, 0])
            gamma_hi.append(rates[:, 1])
            logs.append((rates[:, 0] < rates[:, 1]) & log_gamma)
        joint = width > 1
        model = JointDegradation(tuple(banks)) if joint else banks[0]
        observation = JointObservation(observations) if joint else observations[0]
        # the noise grows with each of a row's parameters
        pf = ResampleMoveFilter(model, observation, noise=self.residual_noise(observations, evaluations, stride),
                                dt=self.dt, n_particles=self.n_particles, discrepancy="shared",
                                seed=seeds.spawn(self.seed, seeds.FILTER))
        bounds = (np.array(theta_lo).T, np.array(theta_hi).T) if joint else (np.array(theta_lo[0]),
                                                                               np.array(theta_hi[0]))
        pf.initialize(bounds, gamma_bounds=(np.hstack(gamma_lo), np.hstack(gamma_hi)), assets=len(hypotheses),
                      log_gamma=np.hstack(logs), components=width if joint else None)
        models = [tuple(bank.models[row] for bank in banks[:len(p)]) for row, p in enumerate(parts)]
        return pf, observations[0], models

    def _information(self, result: IsolationResult, observation: HypothesisObservation, evaluations: list,
                     noise: np.ndarray, steps: range) -> np.ndarray:
        """The record's Fisher information about the candidates' changes (K, C, C), summed up to each step.

        Each candidate's sensitivities ``dy/dtheta`` at its nominal value, per ARR over its noise sd,
        at the filter's steps; a step where a sensitivity cannot be evaluated adds nothing.
        """
        index = list(steps)
        rows = [next(i for i, h in enumerate(result.hypotheses) if h.candidate == c) for c in result.candidates]
        scaled = np.zeros((len(index), len(rows), len(evaluations)))
        for ci, row in enumerate(rows):
            for m, (model, e) in enumerate(zip(observation.models[row], evaluations)):
                if model is not None:
                    with np.errstate(all="ignore"):
                        scaled[:, ci, m] = sensitivity(model, [np.asarray(p)[index] for p in e.points]) / noise[m]
        scaled = np.nan_to_num(scaled, nan=0.0, posinf=0.0, neginf=0.0)
        return np.cumsum(np.einsum("kcm,kdm->kcd", scaled, scaled), axis=0)

    def _record_groups(self, result: IsolationResult, information: np.ndarray, log_evidence: np.ndarray,
                       theta: np.ndarray) -> tuple[list, dict]:
        """``result.groups`` merged with the pairs this record cannot tell apart, and why (pair -> reason).

        Each candidate's change is its estimate under its most probable hypothesis (``theta`` (H,));
        two candidates are indistinguishable when each one's change is imitated by the other to within
        the decisive evidence ratio (:func:`~prognosis.hypotheses.record_separation`): the evidence
        between them can then come only from what the residuals do not carry (the laws' shapes, the
        priors, a model error), so it does not single either out.  Candidates whose every hypothesis
        is rejected or contradicted by the data (inadequate) take no part: the residuals told them apart.
        """
        hypotheses, candidates = result.hypotheses, result.candidates
        changes = np.zeros(len(candidates))
        alive = np.zeros(len(candidates), bool)
        for ci, c in enumerate(candidates):
            rows = [i for i, h in enumerate(hypotheses) if h.candidate == c and h.name not in result.rejected
                    and h.name not in result.inadequate]
            if rows:
                best = max(rows, key=lambda i: log_evidence[i])
                changes[ci], alive[ci] = float(theta[best]) - hypotheses[best].nominal, True
        separation = record_separation(information, changes)
        limit = math.log(self.min_ratio)
        groups = [list(g) for g in result.groups]
        reasons = {}
        for a, b in ((a, b) for a in range(len(candidates)) for b in range(a + 1, len(candidates))):
            first, second = candidates[a], candidates[b]
            if not (alive[a] and alive[b]) or any(first in g and second in g for g in groups):
                continue
            apart = float(max(separation[a, b], separation[b, a]))
            if apart >= limit:
                continue
            reasons[f"{first} ~ {second}"] = (
                f"{first} and {second} act on the residuals nearly in proportion over this record: each one's "
                f"estimated change is imitated by a change of the other to within {apart:.2g} nats of evidence "
                f"(decisive: {limit:.2g}); the operating regime does not excite what tells them apart")
            merged = [c for g in groups if first in g or second in g for c in g]
            groups = [g for g in groups if first not in g and second not in g] + [merged]
        return groups, reasons

    def start_interval(self, h: Hypothesis, evaluations: list, arrs: list, k: int, noise: np.ndarray):
        """(lo, hi) of theta at the alarm and sigma_v, for one hypothesis.

        The uncertainty interval widened to the values of theta that explain the residual on the
        samples that raised the alarm (as :class:`~prognosis.monitor.HealthMonitor` does with
        ``start="residual"``), inverting the observation equation of the ARR that resolves the
        candidate best there: the largest sensitivity ``|d y / d theta|`` over the residual's noise.
        """
        model, points, residual, total = self._resolving(h, evaluations, arrs, k, noise)
        box = self.healthy_box(h, [model.arr])
        # a sensor's offset has no failure value: it is bracketed by the readings' own size
        bracket = ((min(box[0], h.failure), max(box[1], h.failure)) if not h.sensor
                   else _reading_bracket(model, points))
        explained = model.invert(-residual, points, bracket)
        explained = np.clip(explained[np.isfinite(explained)], *bracket)
        if h.sensor:  # a bias is a step, which the first alarm may catch half-way through its stencil
            explained = 2.0 * explained
        start = (min(box[0], float(explained.min())), max(box[1], float(explained.max()))) if explained.size else box
        distance = abs(h.failure - h.nominal) if not h.sensor else math.inf
        resolution = min(1.0 / math.sqrt(total), distance) if total > 0 else distance
        if not math.isfinite(resolution):
            raise PrognosisError(f"no ARR resolves {h.candidate} at the alarm (t = {evaluations[0].t[k]:g} s)")
        return start[0], start[1], self.process_noise * resolution

    def _resolving(self, h: Hypothesis, evaluations: list, arrs: list, k: int, noise: np.ndarray):
        """The observation model of the ARR that resolves ``h``'s candidate best on the samples that raised
        the alarm at ``k``, its point values and residual there, and the information of all ARRs per sample."""
        window = slice(max(0, k - evaluations[0].persistence + 1), k + 1)
        seeing = [m for m, a in enumerate(arrs) if sees(a, h.candidate)]
        models = {m: candidate_model(arrs[m], h.candidate, h.law) for m in seeing}
        points = {m: [p[window] for p in evaluations[m].points] for m in seeing}
        # information per sample: (sensitivity / noise)^2, summed over the ARRs
        information = {m: float(np.nanmedian(np.square(sensitivity(models[m], points[m]) / noise[m])))
                       for m in seeing}
        best = max(seeing, key=lambda m: information[m] if np.isfinite(information[m]) else -1.0)
        total = sum(v for v in information.values() if np.isfinite(v))
        return models[best], points[best], evaluations[best].residual[window], total

    def _reject_wrong_side(self, result: IsolationResult, evaluations: list, arrs: list, k: int,
                           noise: np.ndarray) -> None:
        """Reject the hypotheses whose failure value lies on the other side of the change the alarm shows.

        The residual that raised the alarm, inverted for the candidate (an observation equation linear
        in it), puts it beyond its healthy values on one side; a law from there to a failure value on
        the other side would first have to undo the change.  The resample-move filter cannot follow a
        drift away from failure (its rates point toward it), so this is said at the alarm.
        """
        values = {}  # candidate -> (its value at the alarm, the ARR it is read on): one inversion per candidate
        # an offset has no failure value to be wrong about; a joint hypothesis' parts are the single ones'
        for h in (h for h in result.hypotheses if not h.sensor and not isinstance(h, JointHypothesis)):
            if h.candidate not in values:
                model, points, residual, _ = self._resolving(h, evaluations, arrs, k, noise)
                values[h.candidate] = (float(np.nanmedian(model.invert(-residual, points)))
                                       if model.coefficient is not None else math.nan, model.arr)
            value, arr = values[h.candidate]
            if h.name in result.rejected or not math.isfinite(value):
                continue
            lo, hi = self.healthy_box(h, [arr])
            if (value < lo and h.direction == "up") or (value > hi and h.direction == "down"):
                side = "below" if value < lo else "above"
                result.rejected[h.name] = (
                    f"at the alarm (t = {result.detection_time:g} s) the residual of {arr.name} puts "
                    f"{h.candidate} at {value:.3g}, {side} its healthy values [{lo:.3g}, {hi:.3g}], while its failure "
                    f"value {h.failure:g} is {'above' if h.direction == 'up' else 'below'} them: the drift goes away "
                    "from failure (a failure value on the wrong side?)")

    @staticmethod
    def healthy_box(h: Hypothesis, arrs: list) -> tuple[float, float]:
        """The candidate's healthy values: its uncertainty box around nominal (the nominal alone without one);
        a joint hypothesis', its first parameter's."""
        h = h.parts[0] if isinstance(h, JointHypothesis) else h
        lo, hi = next((a.uncertainties[h.candidate] for a in arrs if h.candidate in a.uncertainties), (0.0, 0.0))
        return tuple(sorted((h.nominal * (1 + lo), h.nominal * (1 + hi))))

    def _reject_drift_away(self, result: IsolationResult, hypotheses: list, estimate: dict, time: float,
                           boxes: np.ndarray, away: np.ndarray) -> np.ndarray:
        """Reject the hypotheses whose estimate drifts away from their failure value.

        A hypothesis says its candidate moves from nominal toward the failure value.  When the whole
        5-95 % band of the estimate lies beyond the healthy box on the other side, for
        DRIFT_AWAY_STEPS filter steps in a row, the data contradict it (a failure value on the wrong
        side of the observed drift): its evidence alone would not say so, since the filter follows
        the drift either way.  Returns the updated counts of consecutive steps.
        """
        q = estimate["theta_quantiles"]
        up = np.array([h.direction == "up" for h in hypotheses])
        sensor = np.array([h.sensor for h in hypotheses])  # an offset may go either way
        wrong = np.where(up, q[:, 2] < boxes[:, 0], q[:, 0] > boxes[:, 1]) & ~sensor
        away = np.where(wrong, away + 1, 0)
        for row in np.flatnonzero(away >= DRIFT_AWAY_STEPS):
            h = hypotheses[row]
            if h.name not in result.rejected:
                side = "below" if up[row] else "above"
                result.rejected[h.name] = (
                    f"at t = {time:g} s the estimate of {h.candidate} is {q[row, 1]:.3g}, {side} its healthy values "
                    f"[{boxes[row, 0]:.3g}, {boxes[row, 1]:.3g}], while its failure value {h.failure:g} is "
                    f"{'above' if up[row] else 'below'} them: the drift goes away from failure (a failure value "
                    "on the wrong side?)")
        return away

    def law(self, h: Hypothesis, process_noise: float):
        """The degradation model of ``h``'s law: the user's, or the built-in one with ``process_noise``."""
        if h.sensor:  # an offset along a straight line (a bias: its rate 0)
            return degradation_model("linear", process_noise)
        model = self.laws[h.law]
        if model is not None:
            return model
        return degradation_model(h.law, process_noise, nominal=h.nominal, failure=h.failure)

    def gamma_bounds(self, h: Hypothesis, count: int, offset: float = 0.0) -> tuple[list, list]:
        """(lo, hi), each of ``count`` gammas, of a hypothesis' prior: its rate's, then its law's other gammas.

        The rate: the ``rate`` interval, or the rates of the prior on the life (the life from
        nominal to failure in ``life`` filter steps gives the rate ``distance / (T dt)``, with the
        distance ``failure - nominal`` (linear and other laws), ``log(failure / nominal)``
        (exponential) or 1 (power: ``a`` is one over the life), as
        :func:`~prognosis.hypotheses.rate_prior` draws it).  The power law's exponent spans
        :data:`~prognosis.degradation.POWER_EXPONENTS`; a gamma the law does not have is fixed at 1.

        A sensor's bias has the rate 0; its drift (its gain's error) goes from 0 to ``offset`` (the far
        end of its start interval) in a life on the same prior, so its rate has that sign.
        """
        if h.sensor:
            ends = ([0.0, 0.0] if h.law == "bias" or offset == 0 else
                    sorted(offset / (steps * self.dt) for steps in self.life))
            return [ends[0]] + [1.0] * (count - 1), [ends[1]] + [1.0] * (count - 1)
        if self.rate is not None:
            ends = sorted(float(r) / (h.failure - h.nominal if h.law == "power" else 1.0) for r in self.rate)
        else:
            ends = sorted(law_distance(h) / (steps * self.dt) for steps in self.life)
        lo, hi = [ends[0]] + [1.0] * (count - 1), [ends[1]] + [1.0] * (count - 1)
        if h.law == "power" and self.laws[h.law] is None:
            lo[1], hi[1] = POWER_EXPONENTS
        return lo, hi

    def residual_noise(self, observation: HypothesisObservation | Sequence, evaluations: list,
                       stride: int) -> ResidualNoise:
        """The likelihood's noise per hypothesis: ``noise_std`` with, from the healthy stretch, the residuals'
        correlations, how their noise grows with the candidate (:func:`~prognosis.likelihood.healthy_noise`)
        and how far the integrals of an ARR drift a step (:func:`~prognosis.likelihood.integral_walk`).

        ``observation``: one :class:`~prognosis.hypotheses.HypothesisObservation`, or one per parameter
        of joint hypotheses (rows aligned; the noise then grows with each). Without a healthy stretch of
        at least three filter steps the residuals are independent with ``noise_std`` and their noise
        does not grow.
        """
        parts = [observation] if isinstance(observation, HypothesisObservation) else list(observation)
        arrs = parts[0].arrs
        std = np.array([self.noise_std[a.name] for a in arrs])
        t = evaluations[0].t
        healthy = np.flatnonzero(t <= self.healthy_until)[::stride]
        if healthy.size < 3:
            return ResidualNoise.independent(std, self.inflation)
        residuals = np.column_stack([e.residual[healthy] for e in evaluations])
        covariance, cross, growth = [], [], []
        for row in range(len(parts[0].hypotheses)):
            # each parameter's observation model per ARR (None: blind to it), side by side
            columns = [sensitivity(model, [p[healthy] for p in e.points]) if model is not None
                       else np.zeros(healthy.size) for part in parts for model, e in zip(part.models[row], evaluations)]
            estimate = healthy_noise(residuals, np.column_stack(columns))
            scale = np.sqrt(np.diagonal(estimate["covariance"]))
            # the user's noise_std sets each residual's level; the stretch gives the correlations
            covariance.append(estimate["covariance"] / np.outer(scale, scale) * np.outer(std, std))
            cross.append(estimate["cross"])
            growth.append(estimate["growth"])
        nominal = np.array([[0.0 if h is None else h.nominal for h in part.hypotheses] for part in parts]).T
        walk = [integral_walk(integral_increments(a, e.points, healthy)) for a, e in zip(arrs, evaluations)]
        return ResidualNoise(np.array(covariance), np.array(cross), np.array(growth),
                             nominal[:, 0] if len(parts) == 1 else nominal, self.inflation, np.array(walk))

    def rate_particles(self, h: Hypothesis, rng: np.random.Generator, count: int = 1,
                       offset: float = 0.0) -> np.ndarray:
        """Initial gamma particles (N, ``count``) of a hypothesis: the rate from the ``rate`` interval or the
        prior on the life, the power law's exponent log-uniform, other gammas 1 (:meth:`gamma_bounds`;
        ``offset``: a sensor's offset at the alarm)."""
        lo, hi = self.gamma_bounds(h, count, offset)
        gamma = np.ones((self.n_particles, count))
        if h.sensor:
            ends = np.sort(np.log(np.abs([lo[0], hi[0]]))) if lo[0] != hi[0] else None
            gamma[:, 0] = 0.0 if ends is None else np.sign(lo[0]) * np.exp(rng.uniform(*ends, self.n_particles))
        else:
            gamma[:, 0] = (rng.uniform(lo[0], hi[0], self.n_particles) if self.rate is not None
                           else rate_prior(h, self.dt, self.n_particles, rng, self.life))
        if count > 1 and lo[1] < hi[1]:
            gamma[:, 1] = np.exp(rng.uniform(math.log(lo[1]), math.log(hi[1]), self.n_particles))
        return gamma

    def _reject(self, result: IsolationResult, hypotheses: list, estimate: dict, time: float) -> None:
        """Reject the hypotheses whose median estimate of a parameter left its physical domain."""
        components = estimate.get("components", [estimate])
        for row, h in enumerate(hypotheses):
            for c, part in enumerate(h.parts if isinstance(h, JointHypothesis) else (h,)):
                value = components[c]["theta_quantiles"][row, 1]
                lo, hi = part.domain
                if h.name not in result.rejected and not lo < value < hi:
                    result.rejected[h.name] = (f"at t = {time:g} s the estimate of {part.candidate} is {value:.3g}, "
                                               f"outside its physical domain ({lo:g}, {hi:g})")

    def _check_adequacy(self, result: IsolationResult, hypotheses: list, arrs: list, innovations: list,
                        time: float) -> None:
        """Flag the hypotheses whose standardized innovations drift over the last ADEQUACY_WINDOW steps.

        A law that fits leaves innovations near N(0, 1) about zero; one the data contradict leaves
        them on one side (a power-law wear seen through a linear law lags more and more).  The test
        is on the window's mean, in predictive sd: beyond ADEQUACY_LIMIT it is no chance (white
        innovations give a mean of sd 1/sqrt(window)) nor a small misfit of the model (a clean
        residual shows those at about 1 sd).
        """
        if len(innovations) < ADEQUACY_WINDOW:
            return
        # each innovation clipped: a single spike (a derivative stencil straddling a step) is no drift
        window = np.clip(np.array(innovations[-ADEQUACY_WINDOW:]), -SPIKE, SPIKE)  # (W, H, M)
        with np.errstate(invalid="ignore"):
            count = np.sum(np.isfinite(window), axis=0)
            drift = np.nansum(window, axis=0) / np.sqrt(np.maximum(count, 1))
        for row, h in enumerate(hypotheses):
            if h.name in result.inadequate or h.name in result.rejected:
                continue
            worst = int(np.nanargmax(np.abs(np.nan_to_num(drift[row], nan=0.0))))
            if abs(drift[row, worst]) > ADEQUACY_LIMIT * math.sqrt(ADEQUACY_WINDOW):
                mean = np.nanmean(window[:, row, worst])
                result.inadequate[h.name] = (
                    f"at t = {time:g} s the {h.law} law leaves the residual of {arrs[worst].name} "
                    f"{'above' if mean > 0 else 'below'} its prediction by {abs(mean):.2g} sd on average over "
                    f"{ADEQUACY_WINDOW} filter steps: the data contradict the law")

    def _mixture(self, pf: ParticleFilter, hypotheses: list, decision: Decision, predictors: dict, models: tuple,
                 key: int, left_out: Mapping = {}) -> tuple[RULDistribution, str | None]:
        """The RUL of every probable hypothesis not ``left_out`` (collapsed, inadequate), mixed by probability.

        Returns the distribution and None, or, when every probable hypothesis is left out, a
        distribution censored at the horizon and the reason no RUL is given.
        """
        weights = pf.weights
        # a sensor's fault wears nothing: the RUL is that of the wear hypotheses, given that one holds
        left_out = {**left_out, **{h.name: "a sensor's fault, nothing wears" for h in hypotheses if h.sensor}}
        samples, mixed = [], []
        probable = [h.name for h in hypotheses if decision.probabilities[h.name] >= MIXTURE_FLOOR]
        if probable and all(name in left_out for name in probable):
            reason = "; ".join(f"{name}: " + (f"its particle cloud has collapsed (t = {left_out[name]:g} s)"
                                              if isinstance(left_out[name], float) else left_out[name])
                               for name in probable)
            return RULDistribution(np.full((1, 1), np.inf), np.ones((1, 1)), self.horizon), reason
        for row, h in enumerate(hypotheses):
            p = decision.probabilities[h.name]
            if p < MIXTURE_FLOOR or h.name in left_out:
                continue
            # a joint hypothesis' RUL is its first failure: each particle's earliest crossing over its parameters
            first = np.full(weights.shape[1], np.inf)
            for c, part in enumerate(h.parts if isinstance(h, JointHypothesis) else (h,)):
                if (row, c) not in predictors:  # the first parameter's stream as a single hypothesis'
                    stream = seeds.spawn(self.seed, seeds.PREDICTORS, row, *((c,) if c else ()))
                    predictors[row, c] = RULPredictor(models[row][c], dt=self.dt, theta_fail=part.failure,
                                                      direction=part.direction, horizon=self.horizon, seed=stream)
                theta, gamma = _component(pf, row, c)
                prediction = predictors[row, c].predict(theta, gamma, weights[row:row + 1], 0.0, key=key)
                first = np.minimum(first, prediction.samples[0])
            samples.append(first)
            mixed.append(p * weights[row])
        if not samples:  # every hypothesis rejected
            return RULDistribution(np.full((1, 1), np.inf), np.ones((1, 1)), self.horizon), None
        return (RULDistribution(self._resolved(np.concatenate(samples), key)[None, :], np.concatenate(mixed)[None, :],
                                self.horizon), None)

    def _resolved(self, rul: np.ndarray, key: int) -> np.ndarray:
        """The RUL samples spread uniformly over one filter step about each (censored ones kept).

        The filter reads the residual once a step, and by default a step is the derivative window
        the residual is computed over: the record resolves the time of the change no finer than that.
        A lag of the residual within the window (a zero-order hold, a sensor's filter) is a shift of
        theta at the alarm that no gap shows, and on a clean residual it is all the error there is;
        a band narrower than the step would claim what the record cannot tell.
        """
        rng = seeds.generator(self.seed, seeds.RESOLUTION, key)
        spread = self.dt * (rng.random(rul.shape) - 0.5)
        return np.where(np.isfinite(rul), np.maximum(rul + spread, 0.0), rul)


def _component(pf, row: int, c: int) -> tuple[np.ndarray, np.ndarray]:
    """theta (1, N) and gamma (1, N, G) of parameter ``c`` of hypothesis ``row`` (a joint filter's component)."""
    if getattr(pf, "components", None) is None:
        return pf.theta[row:row + 1], pf.gamma[row:row + 1]
    bank, start = pf.model.banks[c], pf.model.offsets[c]
    return pf.theta[row:row + 1, :, c], pf.gamma[row:row + 1, :, start:start + bank.n_gamma]


def _offset(start: tuple) -> float:
    """The offset a hypothesis' start interval ``(lo, hi, sigma_v)`` shows at the alarm: its end farther from 0."""
    return start[0] if abs(start[0]) > abs(start[1]) else start[1]


def _reading_bracket(model, points: list) -> tuple[float, float]:
    """Where a sensor's offset is searched for: ten times the largest reading of its signal (at least 1)."""
    names = [str(p) for p in model.arr.compiled.points]
    signal = sensor_signal(model.candidate)
    size = float(np.nanmax(np.abs(points[names.index(signal)]))) if signal in names else 0.0
    return (-10.0 * max(size, 1.0), 10.0 * max(size, 1.0))


def _softmax(log_z: np.ndarray) -> np.ndarray:
    if not np.isfinite(log_z).any():
        return np.zeros(log_z.shape)
    p = np.exp(log_z - log_z.max())
    return p / p.sum()


def _logsumexp(values: np.ndarray) -> float:
    values = np.asarray(values, float)
    if not values.size or not np.isfinite(values).any():
        return -np.inf
    top = values.max()
    return float(top + np.log(np.sum(np.exp(values - top))))


def _logmeanexp(values) -> float:
    """log of the mean of exp(values): a candidate's evidence under a uniform prior over its laws."""
    values = np.asarray(values, float)
    return _logsumexp(values) - math.log(values.size) if values.size else -np.inf


#: The RUL columns of a prediction in :meth:`IsolationResult.as_dict`.
RUL_KEYS = ("rul_mean", "rul_p5", "rul_p25", "rul_median", "rul_p75", "rul_p95", "censored")


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None

