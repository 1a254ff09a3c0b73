"""The isolating monitor: detection, then candidates, laws and rates weighed in one filter, then the RUL.

:class:`IsolatingMonitor` needs what a user knows: the ARRs, the record, the residuals' noise on a
fault-free stretch, and the failure value of each parameter that can fail.  At the first alarm

1. the candidates are the parameters with a failure value that every fired ARR is sensitive to
   (:func:`~prognosis.hypotheses.signature_candidates`), the fired ARRs those in alarm over most of a
   confirmation window after the first alarm (a transient rules nothing out);
2. every candidate with every degradation law is a hypothesis (:class:`~prognosis.isolation.priors.Priors`);
   all of them run as the rows of one vectorized particle filter, each predicting every residual an
   ARR sensitive to a candidate gives (:class:`~prognosis.hypotheses.HypothesisObservation`), its rate
   drawn from a prior on the life (:func:`~prognosis.hypotheses.rate_prior`);
3. each hypothesis accumulates its evidence, the filter's estimate of log p(y_1..k); a hypothesis
   whose estimate leaves its physical domain (a negative inertia) is rejected with the reason;
4. :func:`~prognosis.isolation.decision.decide` ranks them: a candidate (and a law) is declared when
   its evidence beats every other by ``min_ratio``;
5. the RUL is the mixture of the hypotheses' predictions weighted by their posterior probability
   (Bayesian model averaging), so an undecided law or candidate widens the prediction instead of
   being chosen at random.

The decision can change while data come in: it is made again at every RUL prediction.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from diagnosis.derivatives import default_window
from diagnosis.detection import check_closed_form, fitting_order

from .. import seeds
from ..degradation import JointDegradation, PerAssetDegradation, degradation_model
from ..errors import PrognosisError
from ..hypotheses import (Hypothesis, HypothesisObservation, JointHypothesis, JointObservation, additive,
                          candidate_model, explaining, indistinguishable_groups, integral_increments, record_separation,
                          same_signature, sees, sensitivity, sensor_signal, signature_candidates)
from ..likelihood import ResidualNoise, healthy_noise, integral_walk
from ..health_monitor import filter_stride
from ..particle_filter import KernelSmoothing, ParticleFilter
from ..resample_move import ResampleMoveFilter
from ..rul import RULDistribution, RULPredictor
from .decision import Decision
from .priors import Priors, check_noise_std
from .result import IsolationResult
from .settings import (ADEQUACY_LIMIT, ADEQUACY_WINDOW, BEFORE_STEPS, BLIND_LIMIT, CONFIRM_STEPS, DRIFT_AWAY_STEPS,
                       FORECAST_LIMIT, FREEZE_BELOW, MIXTURE_FLOOR, SPIKE, IsolationSettings)

__all__ = ["IsolatingMonitor", "detection_options"]


class IsolatingMonitor:
    """Detection, then candidates, laws and rates weighed in one filter, then the RUL.

    Parameters
    ----------
    arrs : sequence of ARR
    failures : mapping
        Failure value of each parameter that can fail, e.g. ``{"b_Md": 0.3, "J_Md": 1.8e-3}``.
    noise_std : mapping
        Standard deviation of each ARR's residual on healthy data (by ARR name).
    settings : IsolationSettings, optional
        How candidates and laws are weighed (default ``IsolationSettings()``); ``**changes`` change
        single settings of it, e.g. ``n_particles=200`` (:meth:`IsolationSettings.changed`).
    detection : mapping
        Options of :func:`diagnosis.evaluate` (``margin``, ``persistence``...); a mapping per ARR
        name is used for that ARR.
    healthy_until : float, optional
        End of the stretch the user declares fault-free (the one the noise was calibrated on):
        alarms there are not faults (a start-up transient) and start nothing.
    domains : mapping, optional
        Parameter -> open interval ``(lo, hi)`` of its physical domain, as the model declares it
        (:attr:`bondgraph.BondGraph.domains`); a hypothesis whose estimate leaves it is rejected.
        A parameter not given keeps the sign of its nominal value (:func:`~prognosis.hypotheses.physical_domain`).

    Notes
    -----
    ``method="resample-move"`` (the default) weighs each law's static parameters, theta at the alarm and
    the rate, by their posterior on the whole history and moves its particles by MCMC
    (:class:`~prognosis.resample_move.ResampleMoveFilter`), with the residual noise measured on the
    healthy stretch, correlated between ARRs and growing with the candidate (:mod:`~prognosis.likelihood`),
    divided by the gaps' information excess; it does not collapse on a clean residual, and a law the
    innovations contradict is reported inadequate.  ``"sir"`` is the random-walk SIR filter of Jha et
    al. (2016) with kernel smoothing of the rate (:class:`~prognosis.particle_filter.ParticleFilter`):
    no cheaper on the demos, its cloud collapses when the residual is much sharper than its process
    noise, and its random walk absorbs a wrong law instead of showing it (no adequacy check).

    With ``pairs``, two parameters degrading at once are weighed too (:meth:`pairs_for`,
    :class:`~prognosis.hypotheses.JointHypothesis`), each by each of the laws; a pair is declared only
    when its evidence beats each of its members' alone by ``min_ratio`` (one fault unless the data
    demand two) and each member is seen apart from the other (:meth:`apart_terms`), and its RUL
    is that of the first failure.  Off by default: on a noisy residual with a
    derivative (the pipe's flow) an inductance paired with the wearing resistance absorbs the model's
    misfit and wins on a single fault, and a run with pairs costs 2-9 times one without.

    The filter, the prior of the rates and each hypothesis' RUL predictor draw from streams of their
    own spawned from ``seed`` (:mod:`prognosis.seeds`), so no two seeds share a stream.

    Examples
    --------
    The RLC circuit's resistance drifting up linearly from t = 0.5 s; the monitor is told only
    that R fails at 20 ohm and L at 2 H:

    >>> from bondgraph.library import rlc_circuit
    >>> from bondgraph.scenarios import drift, rlc_record
    >>> from diagnosis import derive_arrs
    >>> record = rlc_record(np.linspace(0.0, 3.0, 3001), {"R": drift(10.0, 4.0, onset=0.5)})
    >>> arrs = derive_arrs(rlc_circuit())
    >>> monitor = IsolatingMonitor(arrs, {"R": 20.0, "L": 2.0}, noise_std={a.name: 1e-3 for a in arrs},
    ...                            dt=0.01, n_particles=100, detection={"margin": 0.01})
    >>> result = monitor.run(record)
    >>> d = result.decision
    >>> d.candidate, d.status, d.degradation, d.same_signature   # L fires the same ARR: not isolable in the model
    ('R', 'indistinguishable', 'linear', ('L',))
    """

    def __init__(self, arrs: Sequence, failures: Mapping[str, float], *, noise_std: Mapping[str, float],
                 settings: IsolationSettings | None = None, detection: Mapping | None = None,
                 healthy_until: float | None = None, domains: Mapping[str, tuple] | None = None, **changes):
        self.settings = (settings or IsolationSettings()).changed(**changes)
        self.arrs = list(arrs)
        for arr in self.arrs:
            check_closed_form(arr, "IsolatingMonitor")
        self.priors = Priors(self.arrs, failures, self.settings, domains)
        self.noise_std = check_noise_std(noise_std, self.arrs)
        self.detection = dict(detection or {})
        self.healthy_until = -math.inf if healthy_until is None else float(healthy_until)
        self.settings.require_step("IsolatingMonitor")

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
        result = IsolationResult(None, evaluations=evaluations, min_ratio=self.settings.min_ratio)
        t = evaluations[0].t
        alarms = [np.flatnonzero(e.alarm & (t > self.healthy_until)) for e in evaluations]
        firsts = [a[0] for a in alarms if a.size]
        if not firsts:
            return result
        k = min(firsts)
        result.detection_time = float(t[k])
        stride = filter_stride(t, self.settings.dt)
        result.fired, result.transient = self.signature(evaluations, k, stride)
        result.consistent = explaining(self.arrs, result.fired)
        result.candidates = (self.settings.candidates if self.settings.candidates is not None
                             else signature_candidates(self.arrs, self.priors.failures, result.fired)
                             + [c for c in result.consistent if self.settings.sensors and sensor_signal(c)])
        result.unweighed = {c: why for c in result.candidates if (why := self._unmodelled(c, self.arrs))}
        result.candidates = [c for c in result.candidates if c not in result.unweighed]
        weigh_pairs = bool(self.settings.pairs) and self.settings.pairs_possible
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
        result.hypotheses, result.rejected = self.priors.hypotheses_for(result.candidates)
        result.hypotheses += [h for pair in pairs for h in self.pair_hypotheses(pair)]
        result.seen_by = {m: [a.name for a in self.arrs if sees(a, m)] for m in members}
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
        """This ARR's detection options (:func:`detection_options`)."""
        return detection_options(self.detection, self.arrs, arr)

    def pairs_for(self, result: IsolationResult) -> tuple[list, list]:
        """The pairs of parameters weighed as two faults at once, and their groups of indistinguishable pairs.

        Each parameter candidate with every other parameter that has a failure value and that an ARR
        sees (a second fault may show first in ARRs the first one already fired, or in others later);
        without a single candidate (no one parameter sees every fired ARR), every pair that does.  A
        pair is left out when its members act on the residuals in proportion (no record tells how
        much each moved) or when an ARR multiplies them (their changes do not add).  Two pairs whose
        members are pairwise indistinguishable are one group.
        """
        seen = [p for p in self.priors.failures if any(p in a.parameters for a in self.arrs)]
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
        p = self.priors
        options = [[Hypothesis(c, law, p.failures[c], p.nominal[c], p.domains.get(c)) for law in p.laws
                    if law != "exponential" or self.priors.failures[c] * self.priors.nominal[c] > 0] for c in pair]
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
        starts = [tuple(self.priors.start_interval(part, evaluations, arrs, k0, noise) for part in h.parts)
                  if isinstance(h, JointHypothesis) else self.priors.start_interval(h, evaluations, arrs, k0, noise)
                  for h in hypotheses]
        self._reject_wrong_side(result, evaluations, arrs, k0, noise)
        t = evaluations[0].t
        stride = filter_stride(t, self.settings.dt)
        span = self.resolution(stride, arrs)   # the record times a change no finer (s), nor in fewer steps
        lag = max(1, round(span / self.settings.dt))
        if self.settings.method == "sir":
            observation = HypothesisObservation(arrs, hypotheses)
            bounds = (np.array([s[0] for s in starts]), np.array([s[1] for s in starts]))
            # a model per row: sigma_v is on the scale of each candidate
            models = tuple(self.priors.law(h, s[2]) for h, s in zip(hypotheses, starts))
            bank = PerAssetDegradation(models, tuple(range(len(models))))
            pf = ParticleFilter(bank, observation,
                                n_particles=self.settings.n_particles, dt=self.settings.dt, noise_std=noise,
                                inflation=self.settings.likelihood_inflation,
                                gamma_std=np.zeros(bank.n_gamma), adaptation=KernelSmoothing(self.settings.discount),
                                seed=seeds.spawn(self.settings.seed, seeds.FILTER))
            rng = seeds.generator(self.settings.seed, seeds.RATE_PRIOR)
            gamma0 = np.stack([self.priors.rate_particles(h, rng, bank.n_gamma, offset=_offset(s))
                               for h, s in zip(hypotheses, starts)])
            pf.initialize(bounds, gamma0=gamma0, assets=len(hypotheses))
            models = [(m,) for m in models]
        else:
            pf, observation, models = self._resample_move(hypotheses, starts, evaluations, arrs, stride, k0)
        steps = range(k0, t.size, stride)
        information = self._information(result, observation, evaluations, noise, steps)
        own = self.apart_terms(hypotheses, arrs, evaluations, noise, steps)
        result.apart = {h.name: dict.fromkeys(h.members, 0.0) for h in hypotheses if isinstance(h, JointHypothesis)}
        fits = {key: np.zeros(3) for key in own}   # the path's log likelihood, the sums of score and information
        every = -(-len(steps) // 100)
        rows, rul_t, rul, decisions, ess, innovations = [], [], [], [], [], []
        predictors, away = {}, np.zeros(len(hypotheses), int)
        forecasts = []  # (step, time, particles, log-weights) of the cloud at each RUL report
        boxes = np.array([self.priors.healthy_box(h, arrs) for h in hypotheses])
        # each hypothesis' ARRs blind to it (H, M): it predicts their healthy residual, judged more strictly
        blind = np.array([[not any(sees(a, m) for m in h.members) for a in arrs] for h in hypotheses])
        result.healthy = {part.candidate: self.priors.healthy_box(part, arrs)
                          for h in hypotheses if isinstance(h, JointHypothesis) for part in h.parts}
        for done, k in enumerate(steps, 1):
            y, points = _measured(evaluations, k)
            if self.settings.method != "sir":  # far behind the best, or not following the data: weighed on, not moved
                names = [h.name for h in hypotheses]
                pf.frozen = ((pf.log_evidence < pf.log_evidence.max() - FREEZE_BELOW)
                             | np.array([n in result.inadequate for n in names]))
            diagnostics = pf.step(np.broadcast_to(y, (len(hypotheses), y.size)), points)
            ess.append(diagnostics.ess)
            if diagnostics.innovation is not None:
                innovations.append(diagnostics.innovation)
                self._check_adequacy(result, hypotheses, arrs, innovations, float(t[k]), blind)
            # a cloud collapsed at this step is no band now (a random-walk cloud may spread again later)
            collapsed_now = {hypotheses[row].name: float(t[k]) for row in np.flatnonzero(diagnostics.collapsed)}
            for name, time in collapsed_now.items():
                result.collapsed.setdefault(name, time)
            estimate = pf.estimate()
            parts = _part_estimates(hypotheses, estimate)
            self._weigh_apart(result, hypotheses, parts, own, fits, done - 1)
            self._reject(result, hypotheses, estimate, float(t[k]))
            away = self._reject_drift_away(result, hypotheses, estimate, float(t[k]), boxes, away)
            rows.append((float(t[k]), pf.log_evidence.copy(), estimate))
            if (done - 1) % self.settings.rul_every == 0 or done == len(steps):
                groups, result.on_record = self._record_groups(result, information[done - 1], pf.log_evidence,
                                                               np.ravel(estimate["theta_mean"]))
                result.record_groups = groups
            if (done - 1) % self.settings.rul_every == 0:
                if self.settings.method != "sir":  # the clouds' forecasts, checked later on what came
                    self._check_forecasts(result, hypotheses, arrs, pf, forecasts, done, float(t[k]), lag)
                    forecasts.append((done, float(t[k]), pf.z.copy(), pf.log_weights.copy(), pf.excess.copy()))
                decision = result.decide_at(pf.log_evidence, float(t[k]), groups, parts, result.apart)
                distribution, reason = self._mixture(pf, hypotheses, decision, predictors, models, span, key=done,
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
        steps = [_part_estimates(hypotheses, r[2]) for r in rows]
        result.parts = {name: {c: np.array([step[name][c] for step in steps]) for c in parts}
                        for name, parts in (steps[0].items() if steps else ())}

    def _resample_move(self, hypotheses: list, starts: list, evaluations: list, arrs: list, stride: int, k0: int):
        """The resample-move filter over the hypotheses' static parameters, its observation, and each row's
        models (one per parameter, for the RUL).

        Without a joint hypothesis theta is (H, N).  With one it is (H, N, C): component c of a row is
        its c-th parameter (a single hypothesis' others fixed and blind, so that all weigh in one
        filter on the same residuals), each by its own law with its own gammas.  The residuals of the
        steps before the first alarm (:meth:`steps_before`) are weighed too, each particle with an
        onset per parameter.
        """
        parts = [h.parts if isinstance(h, JointHypothesis) else (h,) for h in hypotheses]
        part_starts = [s if isinstance(h, JointHypothesis) else (s,) for h, s in zip(hypotheses, starts)]
        width = max(len(p) for p in parts)
        banks, observations, theta_lo, theta_hi, gamma_lo, gamma_hi, logs = [], [], [], [], [], [], []
        for c in range(width):
            mine = [p[c] if c < len(p) else None for p in parts]  # None: this row has no c-th parameter
            bank = PerAssetDegradation(tuple(self.priors.law(h, 0.0) if h is not None else degradation_model("linear")
                                             for h in mine), tuple(range(len(mine))))
            g = bank.n_gamma
            ends = [s[c] if c < len(s) else (0.0, 0.0, 0.0) for s in part_starts]
            rates = np.array([self.priors.gamma_bounds(h, g, offset=_offset(e)) if h is not None else [[0.0] * g] * 2
                              for h, e in zip(mine, ends)])  # (H, 2, G)
            # the rate log-uniform on the prior of the life (uniform on a given interval), other gammas
            # log-uniform; a coordinate the prior fixes (a bias's rate, 0) is not
            log_gamma = np.arange(g) > 0 if self.settings.rate is not None else np.ones(g, bool)
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
                                dt=self.settings.dt, n_particles=self.settings.n_particles, discrepancy="shared",
                                seed=seeds.spawn(self.settings.seed, seeds.FILTER))
        bounds = (np.array(theta_lo).T, np.array(theta_hi).T) if joint else (np.array(theta_lo[0]),
                                                                               np.array(theta_hi[0]))
        # every row takes the same residuals, as at each step
        before = [(np.broadcast_to(y, (len(hypotheses), y.size)), points)
                  for y, points in (_measured(evaluations, k) for k in self.steps_before(evaluations, k0, stride))]
        # a row's missing part is held at 0, its nominal value
        nominal = np.array([[p[c].nominal if c < len(p) else 0.0 for c in range(width)] for p in parts])
        pf.initialize(bounds, gamma_bounds=(np.hstack(gamma_lo), np.hstack(gamma_hi)), assets=len(hypotheses),
                      log_gamma=np.hstack(logs), components=width if joint else None, before=before,
                      nominal=nominal if joint else nominal[:, 0])
        models = [tuple(bank.models[row] for bank in banks[:len(p)]) for row, p in enumerate(parts)]
        return pf, observations[0], models

    def steps_before(self, evaluations: list, k0: int, stride: int) -> list:
        """The samples of the filter steps before the first, ``k0``, whose residuals the filter weighs too.

        Back from ``k0`` by filter steps while no ARR is in alarm and the record is past the healthy
        stretch, at most :data:`BEFORE_STEPS`: the change below the thresholds, before it was seen.
        """
        back = np.arange(k0 - stride, -1, -stride)[:BEFORE_STEPS]
        quiet = (evaluations[0].t[back] > self.healthy_until) & ~np.any([e.alarm[back] for e in evaluations], axis=0)
        return back[:int(np.argmin(quiet)) if not quiet.all() else back.size][::-1].tolist()

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

    @staticmethod
    def apart_terms(hypotheses: Sequence, arrs: Sequence, evaluations: list, noise: np.ndarray,
                    steps: range) -> dict:
        """What each pair's parameters' own ARRs (blind to the other) say of their change: (pair name,
        parameter) -> ``(fit, score, information)``.

        ``fit(step, changes)`` is the log likelihood of each change ``d`` (H,) at the filter step
        ``step`` in those ARRs over no change, ``sum (y h(d) - h(d)^2 / 2) / sd^2`` with ``h`` the
        observation model (the residual's shift ``y = -r`` the change predicts) and the noise at its
        healthy sd: exact, where a linear ``h`` would take a resistance doubled in a conductance's
        place (the tank's ``p / R_o``) for twice what it shows.  ``score`` and ``information`` (K,)
        sum ``s y / sd^2`` and ``s^2 / sd^2`` (``s = dh/dtheta`` at nominal) at each step: a small
        constant offset's terms.  :meth:`_weigh_apart` weighs the pair's estimates with them, to tell
        whether that parameter is seen apart from the other (:func:`~prognosis.isolation.held_back`).
        """
        index = list(steps)

        def terms(name: str, other: str) -> tuple[Callable, np.ndarray, np.ndarray]:
            score, information, own = np.zeros(len(index)), np.zeros(len(index)), []
            for a, e, sd in zip(arrs, evaluations, noise):
                if sees(a, name) and not sees(a, other):
                    model = candidate_model(a, name)
                    points = [np.asarray(p, float)[index] for p in e.points]
                    with np.errstate(all="ignore"):
                        s = sensitivity(model, points)
                        y = -np.asarray(e.residual, float)[index]
                    usable = np.isfinite(s) & np.isfinite(y)   # a step it cannot be evaluated at tells nothing
                    score += np.where(usable, s * y, 0.0) / sd ** 2
                    information += np.where(usable, s * s, 0.0) / sd ** 2
                    own.append((model, points, np.where(usable, y, np.nan), sd))

            def fit(step: int, changes: np.ndarray) -> np.ndarray:
                total = np.zeros(len(changes))
                for model, points, y, sd in own:
                    if np.isfinite(y[step]):
                        with np.errstate(all="ignore"):
                            h = model.function()((model.nominal + np.asarray(changes, float))[None, :],
                                                 *(p[step] for p in points))
                            shift = np.broadcast_to(np.asarray(h, float), (1, len(changes)))[0]
                            total += np.nan_to_num((y[step] * shift - 0.5 * shift ** 2) / sd ** 2, nan=0.0)
                return total

            return fit, score, information

        ordered = {h.name: (h.members, h.members[::-1]) for h in hypotheses if isinstance(h, JointHypothesis)}
        cached = {pair: terms(*pair) for both in ordered.values() for pair in both}
        return {(name, pair[0]): cached[pair] for name, both in ordered.items() for pair in both}

    @staticmethod
    def _weigh_apart(result: IsolationResult, hypotheses: Sequence, parts: Mapping, own: Mapping, fits: Mapping,
                     step: int) -> None:
        """Set ``result.apart`` to how much better each pair's parameters' estimated changes (``parts``: joint
        hypothesis name -> parameter -> estimate), step by step up to this one, fit their own ARRs than
        the best constant offset does (no change among them), in log likelihood.

        Why an offset and not no change alone: a model's mismatch shows in an ARR as a parameter set
        off its nominal value from the start (the pump's ARR on its physics reads the gear ratio 10 %
        high, 6 sd over the life), and a second fault is a change.  The offset is small, so its
        likelihood is the linear one, ``(sum s y)^2 / (2 sum s^2)``.  ``fits``: (pair name, parameter)
        -> the path's log likelihood and the sums of the score and the information so far, updated here.
        """
        by_terms = {}   # a pair's law combinations share its parameters' terms: each parameter weighed in one call
        for h in hypotheses:
            if isinstance(h, JointHypothesis):
                for part in h.parts:
                    by_terms.setdefault((part.candidate, h.members), []).append((h.name, part))
        for shared in by_terms.values():
            fit, score, information = own[(shared[0][0], shared[0][1].candidate)]
            changes = np.array([parts[name][part.candidate] - part.nominal for name, part in shared])
            for (name, part), likelihood in zip(shared, fit(step, changes)):
                total = fits[(name, part.candidate)]
                total += (likelihood, score[step], information[step])
                offset = 0.5 * total[1] ** 2 / total[2] if total[2] > 0 else 0.0
                result.apart[name][part.candidate] = float(total[0] - offset)

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
        limit = math.log(self.settings.min_ratio)
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
                model, points, residual, _ = self.priors._resolving(h, evaluations, arrs, k, noise)
                values[h.candidate] = (float(np.nanmedian(model.invert(-residual, points)))
                                       if model.coefficient is not None else math.nan, model.arr)
            value, arr = values[h.candidate]
            if h.name in result.rejected or not math.isfinite(value):
                continue
            lo, hi = self.priors.healthy_box(h, [arr])
            if (value < lo and h.direction == "up") or (value > hi and h.direction == "down"):
                side = "below" if value < lo else "above"
                result.rejected[h.name] = (
                    f"at the alarm (t = {result.detection_time:g} s) the residual of {arr.name} puts "
                    f"{h.candidate} at {value:.3g}, {side} its healthy values [{lo:.3g}, {hi:.3g}], while its failure "
                    f"value {h.failure:g} is {'above' if h.direction == 'up' else 'below'} them: the drift goes away "
                    "from failure (a failure value on the wrong side?)")

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
            return ResidualNoise.independent(std, self.settings.likelihood_inflation)
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
                             nominal[:, 0] if len(parts) == 1 else nominal, self.settings.likelihood_inflation,
                             np.array(walk))

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
                        time: float, blind: np.ndarray) -> None:
        """Flag the hypotheses whose standardized innovations drift over the last ADEQUACY_WINDOW steps.

        A law that fits leaves innovations near N(0, 1) about zero; one the data contradict leaves
        them on one side (a power-law wear seen through a linear law lags more and more).  The test
        is on the window's mean, in predictive sd: beyond ADEQUACY_LIMIT it is no chance (white
        innovations give a mean of sd 1/sqrt(window)) nor a small misfit of the model (a clean
        residual shows those at about 1 sd).  On an ARR blind to the hypothesis (``blind``: (H, M))
        it predicts the healthy residual, with no law to misfit: beyond BLIND_LIMIT another fault acts
        there (a second wear below the ARR's threshold), and no single fault of this one explains it.
        """
        if len(innovations) < ADEQUACY_WINDOW:
            return
        # each innovation clipped: a single spike (a derivative stencil straddling a step) is no drift
        window = np.clip(np.array(innovations[-ADEQUACY_WINDOW:]), -SPIKE, SPIKE)  # (W, H, M)
        with np.errstate(invalid="ignore"):
            count = np.sum(np.isfinite(window), axis=0)
            drift = np.nansum(window, axis=0) / np.sqrt(np.maximum(count, 1))
        excess = np.nan_to_num(np.abs(drift), nan=0.0) / (np.where(blind, BLIND_LIMIT, ADEQUACY_LIMIT)
                                                          * math.sqrt(ADEQUACY_WINDOW))
        for row, h in enumerate(hypotheses):
            if h.name in result.inadequate or h.name in result.rejected:
                continue
            worst = int(np.argmax(excess[row]))
            if excess[row, worst] > 1.0:
                mean = np.nanmean(window[:, row, worst])
                side = "above" if mean > 0 else "below"
                result.inadequate[h.name] = (
                    f"at t = {time:g} s the residual of {arrs[worst].name}, blind to {h.candidate}, stays {side} "
                    f"its healthy level by {abs(mean):.2g} sd on average over {ADEQUACY_WINDOW} filter steps: "
                    "another fault acts there" if blind[row, worst] else
                    f"at t = {time:g} s the {h.law} law leaves the residual of {arrs[worst].name} "
                    f"{side} its prediction by {abs(mean):.2g} sd on average over "
                    f"{ADEQUACY_WINDOW} filter steps: the data contradict the law")

    def _check_forecasts(self, result: IsolationResult, hypotheses: list, arrs: list, pf, forecasts: list,
                         done: int, time: float, lag: int = 1) -> None:
        """Flag the hypotheses whose cloud, as it was when the filter had seen half the steps since the alarm,
        misses the residuals' mean over the last ADEQUACY_WINDOW steps by more than FORECAST_LIMIT sd
        (``lag``: the filter steps the record does not time a change within, :meth:`resolution`).

        The one-step innovations judge a cloud refitted to every step; a flexible law bent through
        the whole history passes them while it cannot say where the wear goes (a power law through a
        wear that saturates).  A RUL is a forecast, so each law is judged on one: as far ahead as
        it had seen.
        """
        start = done - ADEQUACY_WINDOW
        origins = [i for i, f in enumerate(forecasts) if f[0] <= done // 2 and f[0] <= start]
        if not origins:
            return
        del forecasts[:origins[-1]]  # later checks start from later clouds
        made, when, z, log_weights, excess = forecasts[0]
        with np.errstate(invalid="ignore"):
            miss = pf.forecast_miss(z, log_weights, made - 1, start, excess, lag=lag)
        for row, h in enumerate(hypotheses):
            if h.name in result.inadequate or h.name in result.rejected or not np.isfinite(miss[row]).any():
                continue
            worst = int(np.nanargmax(np.abs(miss[row])))
            if abs(miss[row, worst]) > FORECAST_LIMIT:
                result.inadequate[h.name] = (
                    f"at t = {time:g} s the {h.law} law's forecast made at t = {when:g} s misses the residual of "
                    f"{arrs[worst].name} over the last {ADEQUACY_WINDOW} filter steps by {abs(miss[row, worst]):.2g} "
                    f"sd: the data contradict the law's forecast")

    def _mixture(self, pf: ParticleFilter, hypotheses: list, decision: Decision, predictors: dict, models: tuple,
                 span: float, key: int, left_out: Mapping = {}) -> tuple[RULDistribution, str | None]:
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
            return RULDistribution(np.full((1, 1), np.inf), np.ones((1, 1)), self.settings.rul_horizon), reason
        for row, h in enumerate(hypotheses):
            p = decision.probabilities[h.name]
            if p < MIXTURE_FLOOR or h.name in left_out:
                continue
            # a joint hypothesis' RUL is its first failure: each particle's earliest crossing over its parameters
            first = np.full(weights.shape[1], np.inf)
            for c, part in enumerate(h.parts if isinstance(h, JointHypothesis) else (h,)):
                if (row, c) not in predictors:  # the first parameter's stream as a single hypothesis'
                    stream = seeds.spawn(self.settings.seed, seeds.PREDICTORS, row, *((c,) if c else ()))
                    predictors[row, c] = RULPredictor(models[row][c], dt=self.settings.dt, theta_fail=part.failure,
                                                      direction=part.direction, horizon=self.settings.rul_horizon,
                                                      seed=stream)
                theta, gamma = _component(pf, row, c)
                prediction = predictors[row, c].predict(theta, gamma, weights[row:row + 1], 0.0, key=key)
                first = np.minimum(first, prediction.samples[0])
            samples.append(first)
            mixed.append(p * weights[row])
        if not samples:  # every hypothesis rejected
            return RULDistribution(np.full((1, 1), np.inf), np.ones((1, 1)), self.settings.rul_horizon), None
        return (RULDistribution(self._resolved(np.concatenate(samples), span, key)[None, :],
                                np.concatenate(mixed)[None, :], self.settings.rul_horizon), None)

    def resolution(self, stride: int, arrs: Sequence) -> float:
        """The shortest time (s) the residuals of ``arrs``, read every ``stride`` samples (one filter step),
        time a change by: the filter step, or the widest derivative window among them when it is longer.

        A derivative estimate fits a polynomial to its window's samples, so a residual that
        differentiates a signal smooths a change over its window, whatever the filter step it is read
        at.  By default the step is one window (:func:`prognosis.filter_step`) and the two agree.

        >>> from bondgraph.library import rlc_circuit
        >>> from diagnosis import derive_arrs
        >>> arrs = derive_arrs(rlc_circuit())
        >>> monitor = IsolatingMonitor(arrs, {"R": 20.0}, noise_std={a.name: 1e-3 for a in arrs}, dt=0.1,
        ...                            detection={"window": 31})
        >>> round(monitor.resolution(10, arrs), 6), round(IsolatingMonitor(arrs, {"R": 20.0},   # 10 ms samples
        ...     noise_std={a.name: 1e-3 for a in arrs}, dt=0.1).resolution(10, arrs), 6)
        (0.31, 0.11)
        """
        windows = [self.options_for(a).get("window") or default_window(fitting_order(a, None))
                   for a in arrs if getattr(a, "order", 0) > 0]
        return self.settings.dt * max(1.0, max(windows, default=0) / stride)

    def _resolved(self, rul: np.ndarray, span: float, key: int) -> np.ndarray:
        """The RUL samples spread uniformly over ``span`` (s, :meth:`resolution`) about each (censored ones kept).

        The filter reads the residual once a step, and a residual that differentiates a signal is
        computed over a derivative window (by default the step): the record resolves the time of the
        change no finer than the longer of the two.  A lag of the residual within the window (a
        zero-order hold, a sensor's filter) is a shift of theta at the alarm that no gap shows, and on
        a clean residual it is all the error there is; a narrower band would claim what the record
        cannot tell.
        """
        rng = seeds.generator(self.settings.seed, seeds.RESOLUTION, key)
        spread = span * (rng.random(rul.shape) - 0.5)
        return np.where(np.isfinite(rul), np.maximum(rul + spread, 0.0), rul)


def _component(pf, row: int, c: int) -> tuple[np.ndarray, np.ndarray]:
    """theta (1, N) and gamma (1, N, G) of parameter ``c`` of hypothesis ``row`` (a joint filter's component)."""
    if getattr(pf, "components", None) is None:
        return pf.theta[row:row + 1], pf.gamma[row:row + 1]
    bank, start = pf.model.banks[c], pf.model.offsets[c]
    return pf.theta[row:row + 1, :, c], pf.gamma[row:row + 1, :, start:start + bank.n_gamma]


def _part_estimates(hypotheses: Sequence, estimate: Mapping) -> dict:
    """Each joint hypothesis' mean estimate of each of its parameters in the filter's ``estimate``:
    name -> parameter -> value."""
    components = estimate.get("components", ())
    return {h.name: {part.candidate: float(components[c]["theta_mean"][row]) for c, part in enumerate(h.parts)}
            for row, h in enumerate(hypotheses) if isinstance(h, JointHypothesis)}


def _measured(evaluations: Sequence, k: int) -> tuple[np.ndarray, list]:
    """What the filter takes at sample ``k``: the residuals' ``-r`` (M,) and their points."""
    return np.array([-e.residual[k] for e in evaluations]), [[p[k] for p in e.points] for e in evaluations]


def _offset(start: tuple) -> float:
    """The offset a hypothesis' start interval ``(lo, hi, sigma_v)`` shows at the alarm: its end farther from 0."""
    return start[0] if abs(start[0]) > abs(start[1]) else start[1]


def detection_options(detection: Mapping, arrs: Sequence, arr) -> dict:
    """``arr``'s detection options: its own entry when ``detection`` is keyed by the ARRs' names, else the
    shared ones.

    >>> from types import SimpleNamespace as ARR
    >>> a, b = ARR(name="A"), ARR(name="B")
    >>> detection_options({"A": {"margin": 0.1}}, [a, b], b), detection_options({"margin": 0.2}, [a, b], b)
    ({}, {'margin': 0.2})
    """
    names = {a.name for a in arrs}
    if detection and set(detection) <= names:
        return dict(detection.get(arr.name, {}))
    return dict(detection)
