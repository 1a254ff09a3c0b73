"""The hypotheses a monitor weighs and where each starts, from what the user tells about the system.

:class:`Priors` checks the failure values, the candidates and the physical domains against the ARRs,
and gives every candidate with every law as a hypothesis (a sensor's with the sensor laws), theta's
start interval at the alarm and its process noise, the rate particles of the prior on the life, and
each law's model.  :class:`~prognosis.isolation.IsolatingMonitor` and
:class:`~prognosis.fleet.FleetMonitor` start their filters from the same :class:`Priors`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from ..degradation import POWER_EXPONENTS, SATURATIONS, SHAPED, degradation_model
from ..errors import PrognosisError
from ..hypotheses import (SENSOR_LAWS, Hypothesis, JointHypothesis, candidate_model, law_distance, rate_prior, sees,
                          sensitivity, sensor_signal)
from ..particle_filter import check_positive
from .settings import IsolationSettings

__all__ = ["Priors", "check_noise_std"]


class Priors:
    """The hypotheses of the candidates and their starting points.

    Parameters
    ----------
    arrs : sequence of ARR
    failures : mapping
        Failure value of each parameter that can fail; each must be a parameter of an ARR, differ
        from its nominal value and lie in its physical domain.
    settings : IsolationSettings
    domains : mapping, optional
        Parameter -> open interval ``(lo, hi)`` of its physical domain, as the model declares it.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> priors = Priors(derive_arrs(rlc_circuit()), {"R": 20.0}, IsolationSettings(laws=("linear", "exponential")))
    >>> [h.name for h in priors.hypotheses_for(["R"])[0]]
    ['R/linear', 'R/exponential']
    >>> priors.nominal
    {'R': 10.0}
    """

    def __init__(self, arrs: Sequence, failures: Mapping[str, float], settings: IsolationSettings,
                 domains: Mapping[str, tuple] | None = None):
        self.settings, self.laws = settings, settings.law_models
        self.failures = {str(k): float(v) for k, v in failures.items()}
        parameters = {p: a.values[p] for a in arrs for p in a.parameters}
        for name in self.failures:
            if name not in parameters:
                raise PrognosisError(f"failure value for {name!r}: no ARR contains that parameter "
                                     f"(parameters the ARRs see: {', '.join(sorted(parameters))})")
        self.nominal = {p: float(parameters[p]) for p in self.failures}
        for name, value in self.failures.items():
            if value == self.nominal[name]:
                raise PrognosisError(f"failure value of {name!r} equals its nominal value {value:g}")
        if settings.candidates is not None:
            read = {s for a in arrs for s in a.signals}
            unknown = [c for c in settings.candidates if c not in self.failures and sensor_signal(c) not in read]
            if unknown:
                raise PrognosisError(f"candidate {unknown[0]!r} has no failure value and is no sensor an ARR reads "
                                     f"(failure values: {', '.join(self.failures)})")
        self.domains = {str(k): (float(v[0]), float(v[1])) for k, v in (domains or {}).items()}
        for name, (lo, hi) in self.domains.items():
            if name in self.failures and not lo <= self.failures[name] <= hi:
                raise PrognosisError(f"failure value of {name!r} ({self.failures[name]:g}) lies outside its physical "
                                     f"domain ({lo:g}, {hi:g})")

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

    def start_interval(self, h: Hypothesis, evaluations: list, arrs: list, k: int, noise: np.ndarray):
        """(lo, hi) of theta at the alarm and sigma_v, for one hypothesis.

        The uncertainty interval widened to the values of theta that explain the residual on the
        samples that raised the alarm (as :class:`~prognosis.health_monitor.HealthMonitor` does with
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
        return start[0], start[1], self.settings.process_noise * resolution

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

    @staticmethod
    def healthy_box(h: Hypothesis, arrs: list) -> tuple[float, float]:
        """The candidate's healthy values: its uncertainty box around nominal (the nominal alone without one);
        a joint hypothesis', its first parameter's."""
        h = h.parts[0] if isinstance(h, JointHypothesis) else h
        lo, hi = next((a.uncertainties[h.candidate] for a in arrs if h.candidate in a.uncertainties), (0.0, 0.0))
        return tuple(sorted((h.nominal * (1 + lo), h.nominal * (1 + hi))))

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
        (exponential) or 1 (power and saturating: ``a`` is one over the power law's life), as
        :func:`~prognosis.hypotheses.rate_prior` draws it).  The power and saturating laws' exponent spans
        :data:`~prognosis.degradation.POWER_EXPONENTS`, the saturating law's ``c``
        :data:`~prognosis.degradation.SATURATIONS`; a gamma the law does not have is fixed at 1.

        A sensor's bias has the rate 0; its drift (its gain's error) goes from 0 to ``offset`` (the far
        end of its start interval) in a life on the same prior, so its rate has that sign.
        """
        if h.sensor:
            ends = ([0.0, 0.0] if h.law == "bias" or offset == 0 else
                    sorted(offset / (steps * self.settings.dt) for steps in self.settings.life))
            return [ends[0]] + [1.0] * (count - 1), [ends[1]] + [1.0] * (count - 1)
        if self.settings.rate is not None:
            ends = sorted(float(r) / (h.failure - h.nominal if h.law in SHAPED else 1.0) for r in self.settings.rate)
        else:
            ends = sorted(law_distance(h) / (steps * self.settings.dt) for steps in self.settings.life)
        lo, hi = [ends[0]] + [1.0] * (count - 1), [ends[1]] + [1.0] * (count - 1)
        if h.law in SHAPED and self.laws[h.law] is None:
            lo[1], hi[1] = POWER_EXPONENTS
        if h.law == "saturating" and self.laws[h.law] is None:
            lo[2], hi[2] = SATURATIONS
        return lo, hi

    def rate_particles(self, h: Hypothesis, rng: np.random.Generator, count: int = 1,
                       offset: float = 0.0) -> np.ndarray:
        """Initial gamma particles (N, ``count``) of a hypothesis: the rate from the ``rate`` interval or the
        prior on the life, the shaped laws' other gammas log-uniform, other gammas 1 (:meth:`gamma_bounds`;
        ``offset``: a sensor's offset at the alarm)."""
        lo, hi = self.gamma_bounds(h, count, offset)
        n = self.settings.n_particles
        gamma = np.ones((n, count))
        if h.sensor:
            ends = np.sort(np.log(np.abs([lo[0], hi[0]]))) if lo[0] != hi[0] else None
            gamma[:, 0] = 0.0 if ends is None else np.sign(lo[0]) * np.exp(rng.uniform(*ends, n))
        else:
            gamma[:, 0] = (rng.uniform(lo[0], hi[0], n) if self.settings.rate is not None
                           else rate_prior(h, self.settings.dt, n, rng, self.settings.life))
        for g in range(1, count):  # a law's shape (the exponent, the saturation), log-uniform
            if lo[g] < hi[g]:
                gamma[:, g] = np.exp(rng.uniform(math.log(lo[g]), math.log(hi[g]), n))
        return gamma


def check_noise_std(noise_std: Mapping[str, float], arrs: Sequence) -> dict:
    """The residual noise of every ARR, by name, each a finite number > 0; a PrognosisError naming what is wrong."""
    if not isinstance(noise_std, Mapping):
        raise PrognosisError(f"noise_std: give the standard deviation of each ARR's residual by ARR name, "
                             f"got a {type(noise_std).__name__}")
    missing = [a.name for a in arrs if a.name not in noise_std]
    if missing:
        raise PrognosisError(f"noise_std has no value for the ARR(s) {missing}")
    return {k: check_positive(v, f"noise_std[{k!r}]") for k, v in noise_std.items()}


def _reading_bracket(model, points: list) -> tuple[float, float]:
    """Where a sensor's offset is searched for: ten times the largest reading of its signal (at least 1)."""
    names = [str(p) for p in model.arr.compiled.points]
    signal = sensor_signal(model.candidate)
    size = float(np.nanmax(np.abs(points[names.index(signal)]))) if signal in names else 0.0
    return (-10.0 * max(size, 1.0), 10.0 * max(size, 1.0))
