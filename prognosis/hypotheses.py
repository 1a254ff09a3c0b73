"""Fault hypotheses for prognosis: which parameter is degrading, by which law, and what tells them apart.

A user knows the model, the data, a fault-free stretch and when each parameter counts as failed
(its *failure value*).  From that alone:

* :func:`signature_candidates`: the parameters with a failure value that every fired ARR is
  sensitive to (single fault: an ARR that fired and is blind to a parameter rules it out);
* :func:`indistinguishable_groups`: candidates whose effect on every residual is the same up to a
  constant factor (for example a viscous friction before and after a belt, ``f_m omega_m`` and
  ``b_Md omega_m / k_belt^2``): no record can tell them apart, so they are reported together;
* :class:`Hypothesis`: a candidate, a degradation law and the failure value, with its physical
  domain (:func:`physical_domain`) and a prior on its rate that needs nothing of the truth
  (:func:`rate_prior`);
* :class:`HypothesisObservation`: what each hypothesis predicts for every residual, batched over
  hypotheses (rows) and particles, so that one particle filter weighs them all.

A sensor's fault is a candidate too, ``"sensor <signal>"`` (as in the signature matrix): an offset
``beta`` added to the reading, from 0, by the law ``"bias"`` (a constant) or ``"drift"`` (a straight
line), or a share ``g`` of the reading in error, from 0 along a straight line (``"gain"``); it has no
failure value (:data:`SENSOR_LAWS`, :func:`candidate_model`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from bondgraph.memo import ContentCache, content_key
from diagnosis import signature_matrix

from .degradation import SHAPED
from .observation import SENSOR, observation_model, sensor_model
from .errors import PrognosisError

__all__ = ["Hypothesis", "HypothesisObservation", "JointHypothesis", "JointObservation", "SENSOR_LAWS", "additive",
           "candidate_model", "explaining", "integral_increments",
           "indistinguishable_groups", "law_distance", "physical_domain", "rate_prior", "record_separation",
           "same_signature", "sees", "sensitivity", "sensor_signal", "signature_candidates"]

#: the laws of a sensor's fault: an offset constant from its onset (a slipped code disc, a zero shift)
#: or along a straight line (an ageing transducer's drift), or an error proportional to the reading,
#: its share along a straight line (a gain: an encoder's wrong line count, an amplifier's ageing)
SENSOR_LAWS = ("bias", "drift", "gain")

LIFE_PRIOR = (10.0, 1e5)  # filter steps: the life from nominal to failure, log-uniform between these


@dataclass(frozen=True)
class Hypothesis:
    """``candidate`` degrades by the law ``law`` and fails at ``failure``.

    Examples
    --------
    >>> h = Hypothesis("b_Md", "linear", failure=0.3, nominal=0.005)
    >>> h.name, h.direction, h.domain
    ('b_Md/linear', 'up', (0.0, inf))

    ``bounds`` is the parameter's physical domain as the model declares it
    (:attr:`bondgraph.BondGraph.domains`); without it the domain keeps the sign of nominal
    (:func:`physical_domain`):

    >>> Hypothesis("k", "linear", failure=-1.0, nominal=2.0, bounds=(-math.inf, math.inf)).domain
    (-inf, inf)
    """

    candidate: str
    law: str
    failure: float
    nominal: float
    bounds: tuple[float, float] | None = None

    @classmethod
    def of_sensor(cls, signal: str, law: str) -> "Hypothesis":
        """The sensor of ``signal`` off by an offset from 0 by ``law`` (:data:`SENSOR_LAWS`): no failure value.

        >>> h = Hypothesis.of_sensor("omega_m", "drift")
        >>> h.name, h.sensor, h.domain
        ('sensor omega_m/drift', True, (-inf, inf))
        """
        if law not in SENSOR_LAWS:
            raise PrognosisError(f"a sensor's law is one of {', '.join(SENSOR_LAWS)}, got {law!r}")
        return cls(SENSOR + signal, law, math.nan, 0.0, (-math.inf, math.inf))

    @property
    def name(self) -> str:
        return f"{self.candidate}/{self.law}"

    @property
    def sensor(self) -> bool:
        """A sensor's fault (``"sensor <signal>"``), not a parameter's wear."""
        return sensor_signal(self.candidate) is not None

    @property
    def members(self) -> tuple:
        """The faults it holds, as a joint hypothesis names its parameters: its candidate alone."""
        return (self.candidate,)

    @property
    def direction(self) -> str:
        """``"up"`` when the failure value lies above the nominal value, else ``"down"``."""
        return "up" if self.failure > self.nominal else "down"

    @property
    def domain(self) -> tuple[float, float]:
        """The open interval the candidate's value must stay in."""
        return physical_domain(self.nominal) if self.bounds is None else self.bounds


@dataclass(frozen=True)
class JointHypothesis:
    """Several parameters degrading at once, each by its own law (``parts``): a multiple fault.

    Named by its parts, ``"a/law + b/law"``; its candidate is ``"a + b"``.  Its RUL is that of the
    first part to reach its failure value.

    >>> h = JointHypothesis((Hypothesis("R_a", "power", 1.0, 0.5), Hypothesis("c_p", "power", 4e-5, 2e-5)))
    >>> h.name, h.candidate, h.members
    ('R_a/power + c_p/power', 'R_a + c_p', ('R_a', 'c_p'))
    """

    parts: tuple

    @property
    def name(self) -> str:
        return " + ".join(h.name for h in self.parts)

    @property
    def candidate(self) -> str:
        return " + ".join(self.members)

    @property
    def members(self) -> tuple:
        return tuple(h.candidate for h in self.parts)

    @property
    def law(self) -> str:
        return " + ".join(h.law for h in self.parts)

    sensor = False

    # what is asked of a single hypothesis' parameter is the first part's here; each part's own is in ``parts``
    failure = property(lambda self: self.parts[0].failure)
    nominal = property(lambda self: self.parts[0].nominal)
    direction = property(lambda self: self.parts[0].direction)
    domain = property(lambda self: self.parts[0].domain)


def sensor_signal(candidate: str) -> str | None:
    """The signal of a sensor's candidate ``"sensor <signal>"``, None for a parameter.

    >>> sensor_signal("sensor omega_m"), sensor_signal("b_Md")
    ('omega_m', None)
    """
    return candidate[len(SENSOR):] if candidate.startswith(SENSOR) else None


def sees(arr, candidate: str) -> bool:
    """``arr`` is sensitive to the candidate: it holds the parameter, or reads the sensor's signal."""
    signal = sensor_signal(candidate)
    return candidate in arr.parameters if signal is None else signal in arr.signals


def candidate_model(arr, candidate: str, law: str | None = None):
    """The observation equation of ``arr`` for a parameter (:func:`~prognosis.observation.observation_model`)
    or a sensor's fault (:func:`~prognosis.observation.sensor_model`: a gain for the law ``"gain"``, else
    an offset)."""
    signal = sensor_signal(candidate)
    kind = None if signal is None else "gain" if law == "gain" else "offset"
    # the same equations are asked for by every hypothesis of a candidate, by the start interval and
    # by the resolution, and again by every run on the same ARRs: derived once (an ARR whose content
    # cannot be keyed is derived each time)
    content = _arr_content(arr)
    key = None if content is None else content_key((content, candidate, kind))
    if signal is None:
        return _MODELS.get(key, lambda: observation_model(arr, candidate))
    return _MODELS.get(key, lambda: sensor_model(arr, signal, kind))


_MODELS = ContentCache(256)  # observation equations by the content of their ARR (bondgraph.memo)


def _arr_content(arr) -> tuple | None:
    """What an ARR's observation equations depend on: its fields, not its lazily compiled functions."""
    if not dataclasses.is_dataclass(arr):
        return None
    return tuple((f.name, getattr(arr, f.name)) for f in dataclasses.fields(arr) if not f.name.startswith("_"))


def physical_domain(nominal: float) -> tuple[float, float]:
    """Where a parameter can lie: it keeps the sign of its nominal value.

    Masses, inertias, compliances, frictions, resistances and moduli are positive; a parameter
    whose nominal value is negative stays negative; a zero nominal value leaves it free.

    >>> physical_domain(1.5e-3), physical_domain(-2.0), physical_domain(0.0)
    ((0.0, inf), (-inf, 0.0), (-inf, inf))
    """
    if nominal > 0:
        return (0.0, math.inf)
    if nominal < 0:
        return (-math.inf, 0.0)
    return (-math.inf, math.inf)


def rate_prior(hypothesis: Hypothesis, dt: float, particles: int, rng: np.random.Generator,
               life: tuple[float, float] = LIFE_PRIOR) -> np.ndarray:
    """Initial rate particles (particles,): the life from nominal to failure log-uniform over ``life`` steps.

    The rate is the one that takes the parameter from its nominal value to its failure value in
    that life, ``law_distance / T``: ``(failure - nominal) / T`` for the linear law,
    ``log(failure / nominal) / T`` for the exponential one, ``1 / T`` for the power law (its rate is
    one over the life), so every law gets the same prior on the life, and nothing comes from the
    simulated truth or the record's length.  Other laws get the linear law's rate.

    >>> h = Hypothesis("R", "exponential", failure=2.0, nominal=1.0)
    >>> gamma = rate_prior(h, dt=0.1, particles=1000, rng=np.random.default_rng(0))
    >>> bool(np.all(gamma > 0)), bool(gamma.min() >= np.log(2) / 1e4), bool(gamma.max() <= np.log(2) / 1.0)
    (True, True, True)
    """
    lo, hi = life
    steps = np.exp(rng.uniform(np.log(lo), np.log(hi), particles))
    return law_distance(hypothesis) / (steps * dt)


def law_distance(hypothesis: Hypothesis) -> float:
    """How far the hypothesis' law goes from nominal to failure, in its rate's units times time.

    ``log(failure / nominal)`` for the exponential law (of one sign), 1 for the power law (a share
    of the way), ``failure - nominal`` for the others.

    >>> law_distance(Hypothesis("R", "exponential", failure=2.0, nominal=1.0)) == math.log(2.0)
    True
    >>> law_distance(Hypothesis("R", "linear", 2.0, 1.5)), law_distance(Hypothesis("R", "power", 2.0, 1.5))
    (0.5, 1.0)
    """
    if hypothesis.law == "exponential" and hypothesis.failure * hypothesis.nominal > 0:
        return math.log(hypothesis.failure / hypothesis.nominal)
    if hypothesis.law in SHAPED:   # a share of the way
        return 1.0
    return hypothesis.failure - hypothesis.nominal


def signature_candidates(arrs: Sequence, failures: Mapping[str, float], fired: Iterable[str]) -> list[str]:
    """Parameters with a failure value that every fired ARR is sensitive to, in the order of ``failures``.

    Under a single fault, an ARR that fired and does not contain a parameter rules that parameter
    out; an ARR that stayed quiet rules nothing out by itself (a weak effect may stay within the
    thresholds), but the estimation then weighs it (:class:`HypothesisObservation` predicts every
    residual).

    >>> from bondgraph.library import torsion_bar_monitorable
    >>> from diagnosis import derive_arrs
    >>> arrs = derive_arrs(torsion_bar_monitorable())
    >>> signature_candidates(arrs, {"b_Md": 0.3, "b_Ld": 1e-3, "k_s": 1.0}, fired=["ARR_MSO_1"])
    ['b_Md', 'b_Ld']
    """
    fired = set(fired)
    by_name = {a.name: a for a in arrs}
    unknown = sorted(fired - set(by_name))
    if unknown:
        raise PrognosisError(f"no ARR named {unknown[0]!r} (ARRs: {', '.join(by_name)})")
    return [p for p in failures if all(p in by_name[name].parameters for name in fired)]


def same_signature(arrs: Sequence, candidate: str) -> list[str]:
    """The other faults, model parameters and sensors, whose fault signature over ``arrs`` is ``candidate``'s.

    A candidate is isolable in the model only when this list is empty: otherwise a fault of any of
    them fires exactly the same ARRs, whatever the failure values given (the rows of
    :func:`diagnosis.signature_matrix`, sensors as ``"sensor <signal>"``).

    Examples
    --------
    The RLC circuit's resistance and inductance sit in the loop's ARR alone; the capacitance alone
    in the node's, while both sensors are read by both ARRs:

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arrs = derive_arrs(rlc_circuit())
    >>> same_signature(arrs, "R"), same_signature(arrs, "C")
    (['L'], [])
    >>> same_signature(arrs, "sensor i")
    ['sensor v_C']
    """
    signatures = signature_matrix(arrs)
    if candidate not in signatures.rows:
        return []
    mine = signatures.matrix[signatures.rows.index(candidate)]
    return [row for row, signature in zip(signatures.rows, signatures.matrix)
            if row != candidate and np.array_equal(signature, mine)]


def explaining(arrs: Sequence, fired: Iterable[str]) -> list[str]:
    """The faults of the model, parameters and sensors (``"sensor <signal>"``), whose signature holds every
    ARR of ``fired``: those a single fault among them could have fired.

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arrs = derive_arrs(rlc_circuit())
    >>> explaining(arrs, [arrs[0].name])
    ['R', 'L', 'sensor i', 'sensor v_C']
    """
    signatures = signature_matrix(arrs)
    columns = [signatures.columns.index(name) for name in fired]
    return [row for row, signature in zip(signatures.rows, signatures.matrix) if all(signature[c] for c in columns)]


def indistinguishable_groups(arrs: Sequence, candidates: Sequence[str], *, rtol: float = 1e-5,
                             probes: int = 8, seed: int = 0) -> list[list[str]]:
    """Candidates grouped when their effect on every residual is the same up to one constant factor.

    Two parameters are indistinguishable (at their nominal values) when the sensitivities of the
    residuals to them, ``d r_n / d theta``, are proportional with one constant ratio over every ARR:
    any change of one is then explained, sample by sample, by a change of the other.  The
    sensitivities are compared at ``probes`` random values of each ARR's signals, derivatives and
    integrals (central differences), not on a record, so the answer does not depend on how much a
    record excites the system: two analytic functions whose ratio is the same at random points
    have a constant ratio.

    Examples
    --------
    The motor's viscous friction before the belt (``f_m``) and the motor disk's after it (``b_Md``)
    act through ``omega_m`` alone, as do the two inertias:

    >>> from bondgraph.library import torsion_bar_monitorable
    >>> from diagnosis import derive_arrs
    >>> arrs = derive_arrs(torsion_bar_monitorable())
    >>> indistinguishable_groups(arrs, ["b_Md", "J_Md", "f_m", "J_m", "b_Ld"])
    [['b_Md', 'f_m'], ['J_Md', 'J_m'], ['b_Ld']]
    """
    rng = np.random.default_rng(seed)
    sensitivities = {c: [] for c in candidates}
    for arr in arrs:
        points = [rng.uniform(0.5, 2.0, probes) for _ in arr.compiled.points]
        for c in candidates:
            slope = sensitivity(candidate_model(arr, c), points) if sees(arr, c) else np.zeros(probes)
            sensitivities[c].append(slope)
    vectors = {c: np.concatenate(v) for c, v in sensitivities.items()}
    groups: list[list[str]] = []
    for candidate in candidates:
        for group in groups:
            if _proportional(vectors[group[0]], vectors[candidate], rtol):
                group.append(candidate)
                break
        else:
            groups.append([candidate])
    return groups


def record_separation(gram: np.ndarray, changes: np.ndarray) -> np.ndarray:
    """How far apart, in nats of evidence, the record can set each candidate's change from another's.

    ``gram`` (C, C): ``sum_k s_a(k) . s_b(k)`` over the record's filter steps, with ``s_c(k)`` the
    residuals' sensitivities to candidate c at step k, each divided by its residual's noise sd (the
    Fisher information of the record about the candidates' changes).  ``changes`` (C,): the change
    of each candidate considered, from nominal to its failure value (the largest that matters).

    Entry ``[a, b]`` is the expected log-likelihood ratio between a change ``changes[a]`` of ``a`` and
    the change of ``b`` that imitates it best: ``changes[a]^2 (G_aa - G_ab^2 / G_bb) / 2``.  It is small
    when, over the operating regime of this record, the two act on the residuals nearly in
    proportion (two frictions at a steady speed), even if the structure tells them apart; the
    evidence can then not single out either, whatever it says.

    Examples
    --------
    Two candidates seen through the same speed at a steady 10 rad/s, with noise sd 1, over 100
    steps; a third one seen through a swinging speed:

    >>> speed, swing = np.full(100, 10.0), 10.0 + np.sin(np.arange(100) / 5)
    >>> s = np.stack([speed, 0.5 * speed, speed * swing / 10])      # (C, K)
    >>> separation = record_separation(s @ s.T, np.array([1.0, 1.0, 1.0]))
    >>> float(separation[0, 1]), round(float(separation[0, 2]), 1)
    (0.0, 24.1)
    """
    gram = np.asarray(gram, float)
    changes = np.asarray(changes, float)
    diagonal = np.diagonal(gram)
    with np.errstate(divide="ignore", invalid="ignore"):
        explained = np.where(diagonal[None, :] > 0, np.square(gram) / diagonal[None, :], 0.0)
    unexplained = np.maximum(diagonal[:, None] - explained, 0.0)
    return 0.5 * np.square(changes)[:, None] * unexplained


def sensitivity(observation, points: list) -> np.ndarray:
    """``d y / d theta`` at the nominal value at each of the points (central difference).

    ``observation`` is an :class:`~prognosis.observation.ObservationModel`; ``points`` its ARR's point
    values, one array (K,) per point.

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> from prognosis.observation import observation_model
    >>> h = observation_model(derive_arrs(rlc_circuit(), complete=False, integrals="keep")[0], "R")
    >>> sensitivity(h, [np.ones(2), np.array([0.5, 2.0]), np.zeros(2), np.zeros(2)]).round(6).tolist()   # -i
    [-0.5, -2.0]
    """
    nominal = observation.nominal
    step = 1e-6 * (abs(nominal) or 1.0)
    at = np.array([nominal - step, nominal + step])
    values = [np.asarray(p, float)[:, None] for p in points]
    size = len(np.atleast_1d(points[0])) if points else 1
    y = np.broadcast_to(np.asarray(observation.function()(at[None, :], *values), float), (size, 2))
    return (y[:, 1] - y[:, 0]) / (2 * step)


def integral_increments(arr, points: Sequence, steps: np.ndarray) -> np.ndarray:
    """The nominal residual's change over each of the filter ``steps`` through the ARR's integrals alone (K - 1,).

    ``sum_i (dr_n / dI_i) (I_i(t_k+1) - I_i(t_k))``, the gain of each integral ``I_i`` read at the
    first step; ``points`` the ARR's point values at every sample (its :class:`~diagnosis.Evaluation`'s),
    ``steps`` the samples of the filter steps.  Zeros for an ARR without integrals.  What
    :func:`~prognosis.likelihood.integral_walk` reads the integrals' drift from.

    The torsion bar's load ARR has the shaft's twist, ``k_s`` times the integral of the speeds' gap:

    >>> from bondgraph.library import torsion_bar_monitorable
    >>> from diagnosis import derive_arrs
    >>> arr = derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")[1]
    >>> arr.name, [str(p) for p in arr.compiled.points]
    ('ARR_1_2', ['omega_Ld', 'omega_m', 'd1_omega_Ld', 'int0'])
    >>> points = [np.zeros(5), np.zeros(5), np.zeros(5), np.arange(5.0) ** 2]
    >>> integral_increments(arr, points, np.arange(5)).round(3).tolist()   # k_s = 1.786
    [1.786, 5.358, 8.93, 12.502]
    """
    compiled = arr.compiled
    steps = np.asarray(steps)
    total = np.zeros(max(steps.size - 1, 0))
    at = [np.asarray(p, float)[steps[:1]] for p in points]
    for symbol in compiled.integrals:
        gain = compiled.function(f"integral gain {symbol}", sp.diff(compiled.nominal, symbol))(*at)
        values = np.asarray(points[compiled.points.index(symbol)], float)[steps]
        total = total + float(np.ravel(gain)[0]) * np.diff(values)
    return total


def _proportional(first: np.ndarray, second: np.ndarray, rtol: float) -> bool:
    """One constant ratio between two sensitivity vectors (zero exactly where the other is zero)."""
    if not (np.all(np.isfinite(first)) and np.all(np.isfinite(second))):
        return False
    scale = max(np.max(np.abs(first)), 1e-300)
    zero_a, zero_b = np.abs(first) <= 1e-12 * scale, np.abs(second) <= 1e-12 * max(np.max(np.abs(second)), 1e-300)
    if np.any(zero_a != zero_b) or np.all(zero_a):
        return False
    ratio = second[~zero_a] / first[~zero_a]
    return bool(np.all(np.abs(ratio - ratio[0]) <= rtol * abs(ratio[0])))


class HypothesisObservation:
    """What each hypothesis predicts for every residual: ``y_m = h_m(theta)`` for row ``h``, ARR ``m``.

    Row ``h`` of the particles is hypothesis ``hypotheses[h]`` (None: no fault, it predicts 0 everywhere,
    the healthy part of a :class:`JointObservation`); an ARR blind to its candidate
    predicts 0 (the residual stays at its healthy level), so an ARR that stays quiet counts
    against a hypothesis that would move it.  Called with ``theta`` (H, N) and ``points``, one
    list of point values per ARR (the order of each ARR's compiled points), it returns (H, N, M).

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arrs = derive_arrs(rlc_circuit(), complete=False, integrals="keep")[:1]   # the loop's ARR
    >>> h = HypothesisObservation(arrs, [Hypothesis("R", "linear", 20.0, 10.0)])
    >>> h(np.array([[9.0, 11.0]]), [[1.0, 0.5, 0.0, 0.0]]).tolist()   # y = -(R - R_n) i, i = 0.5 A
    [[[0.5], [-0.5]]]
    """

    def __init__(self, arrs: Sequence, hypotheses: Sequence[Hypothesis]):
        self.arrs, self.hypotheses = list(arrs), list(hypotheses)
        models = {None: [None] * len(self.arrs)}  # one per candidate, and per kind of a sensor's fault
        keys = [None if h is None else (h.candidate, h.sensor and h.law == "gain") for h in self.hypotheses]
        for h, key in zip(self.hypotheses, keys):
            if key not in models:
                models[key] = [candidate_model(a, h.candidate, h.law) if sees(a, h.candidate) else None
                               for a in self.arrs]
        self.models = [models[key] for key in keys]

    def rows(self, index: Sequence[int]) -> "HypothesisObservation":
        """The observation of the rows (hypotheses) ``index`` alone, sharing their compiled models."""
        view = object.__new__(HypothesisObservation)
        view.arrs, view.hypotheses = self.arrs, [self.hypotheses[i] for i in index]
        view.models = [self.models[i] for i in index]
        return view

    @property
    def rates(self) -> bool:
        """Some prediction depends on theta's rate of change (a differentiated ARR, ``rate_coefficient``)."""
        return any(m is not None and m.rate_coefficient is not None for models in self.models for m in models)

    def __call__(self, theta: np.ndarray, points, rate: np.ndarray | None = None) -> np.ndarray:
        out = np.zeros((*np.shape(theta), len(self.arrs)))
        for row, models in enumerate(self.models):
            for m, model in enumerate(models):
                if model is not None:
                    out[row, :, m] = model(theta[row], points[m], None if rate is None else rate[row])
        return out

    def trajectory(self, theta: np.ndarray, points: Sequence, rate: np.ndarray | None = None) -> np.ndarray:
        """Predictions (H, N, K, M) along paths ``theta`` (H, N, K) (rates ``rate`` alike), with ``points`` the
        K steps' point lists.

        >>> from bondgraph.library import rlc_circuit
        >>> from diagnosis import derive_arrs
        >>> arrs = derive_arrs(rlc_circuit(), complete=False, integrals="keep")[:1]
        >>> h = HypothesisObservation(arrs, [Hypothesis("R", "linear", 20.0, 10.0)])
        >>> steps = [[[1.0, 0.5, 0.0, 0.0]], [[1.0, 2.0, 0.0, 0.0]]]   # i = 0.5 A, then 2 A
        >>> h.trajectory(np.array([[[11.0, 12.0]]]), steps)[0, 0, :, 0].tolist()
        [-0.5, -4.0]
        """
        out = np.zeros((*np.shape(theta), len(self.arrs)))
        stacked = [np.asarray([step[m] for step in points], float) for m in range(len(self.arrs))]  # (K, P_m)
        for row, models in enumerate(self.models):
            for m, model in enumerate(models):
                if model is not None:
                    out[row, :, :, m] = model(theta[row].T, list(stacked[m].T),
                                              None if rate is None else rate[row].T).T
        return out


class JointObservation:
    """What rows of joint hypotheses predict: several parameters degrade at once, ``y = sum_c h_c(theta_c)``.

    Component ``c`` of every row is observed by ``parts[c]``, a :class:`HypothesisObservation` with
    one hypothesis per row (None: that row's component stays healthy, so a single fault weighs in
    the same filter as pairs).  ``theta`` is (H, N, C); the sum of each parameter's change is the
    ARR's change when no ARR multiplies two of them (:func:`additive`).

    Examples
    --------
    The RLC circuit's loop, ``y = -(R - R_n) i - (L - L_n) di/dt``, with R = 11 ohm and L = 0.2 H, at
    i = 0.5 A and di/dt = 2 A/s (R_n = 10, L_n = 0.1):

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arrs = derive_arrs(rlc_circuit(), complete=False, integrals="keep")[:1]
    >>> joint = JointObservation([HypothesisObservation(arrs, [Hypothesis("R", "linear", 20.0, 10.0)]),
    ...                           HypothesisObservation(arrs, [Hypothesis("L", "linear", 2.0, 0.1)])])
    >>> joint(np.array([[[11.0, 0.2]]]), [[1.0, 0.5, 0.0, 2.0]]).round(9).tolist()
    [[[-0.7]]]
    """

    def __init__(self, parts: Sequence[HypothesisObservation]):
        self.parts = list(parts)
        self.arrs = self.parts[0].arrs

    def rows(self, index: Sequence[int]) -> "JointObservation":
        """The observation of the rows ``index`` alone."""
        return JointObservation([part.rows(index) for part in self.parts])

    @property
    def rates(self) -> bool:
        return any(part.rates for part in self.parts)

    def __call__(self, theta: np.ndarray, points, rate: np.ndarray | None = None) -> np.ndarray:
        return sum(part(theta[..., c], points, None if rate is None else rate[..., c])
                   for c, part in enumerate(self.parts))

    def trajectory(self, theta: np.ndarray, points: Sequence, rate: np.ndarray | None = None) -> np.ndarray:
        """Predictions (H, N, K, M) along paths ``theta`` (H, N, K, C)."""
        return sum(part.trajectory(theta[..., c], points, None if rate is None else rate[..., c])
                   for c, part in enumerate(self.parts))


def additive(arrs: Sequence, first: str, second: str) -> str:
    """Why two parameters' changes do not add up in the ARRs ("" when they do): an ARR's nominal part holds
    a product of them, so one's effect depends on the other's value.

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> additive(derive_arrs(rlc_circuit()), "R", "L")
    ''
    """
    a, b = sp.Symbol(first), sp.Symbol(second)
    for arr in arrs:
        if first in arr.parameters and second in arr.parameters and sp.diff(arr.nominal, a, b) != 0:
            return (f"{arr.name} holds {first} and {second} in one product, so the change of one depends on the "
                    "other: a pair of them is not weighed")
    return ""
