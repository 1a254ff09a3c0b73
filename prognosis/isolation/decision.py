"""The decision from the evidence: which candidate and law, or why none is claimed.

:func:`decide` ranks the hypotheses (candidate x law) by their evidence, the filter's estimate of
log p(y_1..k): a candidate (and a law) is declared when its evidence beats every other by
``min_ratio``; candidates with the same effect on every residual are reported together
(:func:`~prognosis.hypotheses.indistinguishable_groups`).  :func:`held_back` says which pairs of
parameters (two faults at once) the data do not demand.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..hypotheses import Hypothesis, JointHypothesis
from .settings import EVIDENCE_RATIO

__all__ = ["Decision", "decide", "finite_or_none", "held_back"]


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
        return {"candidate": self.candidate, "status": self.status,
                "candidate_ratio": finite_or_none(self.candidate_ratio),
                "degradation": self.degradation, "degradation_decided": self.degradation_decided,
                "degradation_ratio": finite_or_none(self.degradation_ratio), "probabilities": self.probabilities,
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
              min_ratio: float = EVIDENCE_RATIO, estimates: Mapping[str, Mapping[str, float]] = {},
              healthy: Mapping[str, tuple] = {}, seen_by: Mapping[str, Collection[str]] = {},
              apart: Mapping[str, Mapping[str, float]] = {}) -> dict:
    """The joint hypotheses two faults are not claimed for (name -> why): one fault explains the data as well.

    Three reasons, each enough: the pair's evidence (over its laws) does not beat each of its
    parameters' alone by ``min_ratio``; or one of its parameters' estimate (``estimates``: joint
    hypothesis name -> parameter -> value) lies within that parameter's healthy values (``healthy``:
    parameter -> (lo, hi), its uncertainty box), so it is no fault: the pair only uses a tolerance
    to absorb what the single fault's law misses; or, by the ARRs that see each parameter
    (``seen_by``: parameter -> ARR names), one of its parameters is not seen apart from the other:
    neither has an ARR of its own, blind to the other, or one has, and its estimated change fits
    there by less than ``min_ratio`` (``apart``: joint hypothesis name -> parameter -> the log
    likelihood of its estimated change in its own ARRs' residuals over a constant offset,
    :meth:`IsolatingMonitor.apart_terms`).  Its change then shows only where the other acts, and cannot
    be told from the other's law being wrong (a logistic wear of one parameter, bent by a second one).

    A candidate's evidence is the mean over its laws (a rejected law: none); a parameter without a
    single hypothesis (a second fault no fired ARR pointed to at the alarm) is not compared.

    >>> a, b = Hypothesis("a", "power", 2.0, 1.0), Hypothesis("b", "power", 2.0, 1.0)
    >>> hs = [a, b, JointHypothesis((a, b))]
    >>> sorted(held_back(hs, np.array([0.0, -50.0, 2.0])))   # e^2 over a alone: not decisive
    ['a/power + b/power']
    >>> held_back(hs, np.array([0.0, -50.0, 9.0]))
    {}
    >>> why = held_back(hs, np.array([0.0, -50.0, 9.0]), estimates={"a/power + b/power": {"a": 1.5, "b": 1.02}},
    ...                 healthy={"a": (0.95, 1.05), "b": (0.95, 1.05)})
    >>> why["a/power + b/power"]
    "b's estimate 1.02 lies within its healthy values [0.95, 1.05]: no second fault"
    >>> seen_by = {"a": ["r1"], "b": ["r1", "r2"]}
    >>> why = held_back(hs, np.array([0.0, -50.0, 9.0]), seen_by=seen_by, apart={hs[2].name: {"b": 2.5}})
    >>> why[hs[2].name].split(", by ")[1]
    "a likelihood ratio of 12.2 < 100 over an offset: not seen apart from a's"
    >>> held_back(hs, np.array([0.0, -50.0, 9.0]), seen_by=seen_by, apart={hs[2].name: {"b": 40.0}})
    {}
    >>> why = held_back(hs, np.array([0.0, -50.0, 9.0]), seen_by={"a": ["r1"], "b": ["r1"]})
    >>> why["a/power + b/power"]
    'a and b are seen by the same ARRs (r1): a second fault there cannot be told from another law of one'
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
    held = {h.name: why[h.candidate] for h in hypotheses
            if isinstance(h, JointHypothesis) and h.name not in rejected and h.candidate in why}
    for h in hypotheses:
        if isinstance(h, JointHypothesis) and h.name not in rejected and h.name not in held:
            why_not = (_within_healthy(estimates.get(h.name, {}), healthy)
                       or _unseen_apart(h.members, seen_by, apart.get(h.name, {}), min_ratio))
            if why_not:
                held[h.name] = why_not
    return held


def _unseen_apart(members: Sequence[str], seen_by: Mapping[str, Collection[str]], apart: Mapping[str, float],
                  min_ratio: float) -> str:
    """Why a pair is no two faults: no ARR of its own for either parameter, or one whose change its own ARRs
    show by less than ``min_ratio`` ('' if each is seen apart, or the ARRs are not given)."""
    if not all(m in seen_by for m in members):
        return ""
    first, second = (set(seen_by[m]) for m in members)
    if first == second:
        return (f"{members[0]} and {members[1]} are seen by the same ARRs ({', '.join(sorted(first))}): a second "
                "fault there cannot be told from another law of one")
    for name, other, own in ((members[0], members[1], first - second), (members[1], members[0], second - first)):
        shown = apart.get(name, 0.0)
        if own and shown < math.log(min_ratio):
            return (f"{name}'s estimated change fits its own ARRs ({', '.join(sorted(own))}), blind to {other}, "
                    f"by a likelihood ratio of {math.exp(max(shown, -700.0)):.3g} < {min_ratio:g} over an offset: not "
                    f"seen apart from {other}'s")
    return ""


def _within_healthy(estimates: Mapping[str, float], healthy: Mapping[str, tuple]) -> str:
    """Why a pair is no two faults: its first parameter whose estimate lies within its healthy values ('' if none)."""
    for name, value in estimates.items():
        if name in healthy and healthy[name][0] <= value <= healthy[name][1]:
            lo, hi = healthy[name]
            return f"{name}'s estimate {value:.4g} lies within its healthy values [{lo:.4g}, {hi:.4g}]: no second fault"
    return ""


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


def finite_or_none(value: float) -> float | None:
    """``value`` as a float where it is finite, else None (JSON has no inf or NaN)."""
    return float(value) if math.isfinite(value) else None
