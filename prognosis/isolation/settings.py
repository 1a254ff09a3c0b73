"""How a monitor weighs candidates and laws: one frozen settings object for the single asset and the fleet.

:class:`IsolationSettings` holds every setting of isolation by estimation, checked once (a
:class:`~bondgraph.errors.SettingError` names the setting), with one name and one meaning:
:class:`~prognosis.isolation.IsolatingMonitor` and :class:`~prognosis.fleet.FleetMonitor` both take
it (the fleet from :data:`FLEET_SETTINGS`, its random-walk filter's), and so does
:class:`~prognosis.pipeline.PrognosisSettings`.  What a monitor is told about the system (the ARRs,
the failure values, the residuals' noise, the detection options, the healthy stretch, the physical
domains) is not a setting: it goes to the monitor itself.

>>> settings = IsolationSettings(laws=("linear",), n_particles=200)
>>> settings.changed(method="sir").likelihood_inflation, settings.likelihood_inflation
(4.0, 1.0)
>>> IsolationSettings(n_particles=1)
Traceback (most recent call last):
...
bondgraph.errors.SettingError: n_particles must be a whole number in [2, 100000], got 1
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from bondgraph.errors import SettingError

from ..hypotheses import LIFE_PRIOR

__all__ = ["MAX_PARTICLES", "ADEQUACY_LIMIT", "ADEQUACY_WINDOW", "BEFORE_STEPS", "BLIND_LIMIT", "CONFIRM_STEPS",
           "DRIFT_AWAY_STEPS",
           "EVIDENCE_RATIO", "FORECAST_LIMIT", "FLEET_LAWS", "FLEET_SETTINGS", "FREEZE_BELOW", "HORIZON_STEPS",
           "IsolationSettings", "LAWS", "METHODS", "MIXTURE_FLOOR", "PROCESS_NOISE", "SPIKE"]

METHODS = ("resample-move", "sir")
#: the competing laws by default: the two of Jha et al. (2016) and the flexible power law, which holds the
#: linear one and takes over where the data bend away from both
LAWS = ("linear", "exponential", "power")

EVIDENCE_RATIO = 100.0  # "decisive" on Jeffreys' scale: a hypothesis is declared beyond this ratio
MIXTURE_FLOOR = 1e-3  # hypotheses less probable than this are left out of the RUL mixture
PROCESS_NOISE = 0.1  # sigma_v per filter step, as a fraction of the candidate's resolution per sample
HORIZON_STEPS = 2000  # RUL horizon cap in filter steps, unless given
CONFIRM_STEPS = 20  # filter steps after the first alarm over which the fired ARRs are read
#: filter steps before the first alarm the resample-move filter weighs too (the change below the thresholds): at most
BEFORE_STEPS = 1000
ADEQUACY_WINDOW = 30  # filter steps of standardized innovations a law's fit is judged on
#: mean standardized innovation over the window beyond which the law does not follow the residual: a
#: fitting law stays within about 1 (clean or noisy torsion-bar wear), a law that lags drifts to tens
ADEQUACY_LIMIT = 3.0
#: the same mean on an ARR blind to the hypothesis, which predicts the healthy residual there: no law of its
#: own to misfit, so a sustained shift is another fault.  The single wears of the scenario suite leave their
#: blind ARRs within 0.6 sd (white noise: the window's mean has sd 0.18); a second wear below the ARR's
#: threshold shows at 2.8-4.2 sd (the pump's impeller, the tank's outflow)
BLIND_LIMIT = 1.5
#: standardized innovations are clipped at this many sd before the window's mean is taken: a drifting
#: law still shows (each innovation beyond the limit counts in full up to here), one spike moves the
#: mean by at most SPIKE / ADEQUACY_WINDOW
SPIKE = 3 * ADEQUACY_LIMIT
#: sd beyond which a law's forecast, made when the filter had seen half the steps since the alarm, misses
#: the residuals' mean over the last ADEQUACY_WINDOW steps: the law cannot extrapolate what it fitted.  Above
#: the true laws' misses: within 4 on the wear scenarios, up to 4.4 on the RLC circuit over 10 seeds
FORECAST_LIMIT = 6.0
#: log evidence behind the best hypothesis beyond which a hypothesis' particles are no longer moved
#: (its evidence still accumulates): 1e-8 of the best's probability, beyond any decision
FREEZE_BELOW = 8 * math.log(10.0)
DRIFT_AWAY_STEPS = 5  # consecutive filter steps beyond the healthy box, away from failure, that reject a hypothesis
#: Particles per hypothesis at most: a filter holds (hypotheses, particles) arrays at every step.
MAX_PARTICLES = 100_000
#: the laws a fleet weighs by default: its filter carries one rate per particle
FLEET_LAWS = ("linear", "exponential")


@dataclass(frozen=True)
class IsolationSettings:
    """The settings of isolation by estimation, checked when made (a :class:`~bondgraph.errors.SettingError`
    names the setting).

    Parameters
    ----------
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
        the laws :data:`~prognosis.hypotheses.SENSOR_LAWS`.
    pairs : bool or None
        Weigh two parameters degrading at once too (``method="resample-move"`` and no ``candidates``
        only: :class:`~prognosis.isolation.IsolatingMonitor`): True from the first alarm, False never;
        None (default): :func:`prognosis.prognose` weighs them when no single fault explains the
        residuals (the most probable hypothesis ends contradicted by the data, or every one rejected:
        :attr:`~prognosis.isolation.IsolationResult.contradicted`) or no single parameter sees every ARR
        fired (:attr:`~prognosis.isolation.IsolationResult.wearless`), running the record again with them;
        a monitor alone weighs them only when True.
    method : {"resample-move", "sir"}
        The filter (:class:`~prognosis.isolation.IsolatingMonitor`); a fleet's is ``"sir"``.
    dt : float, optional
        Filter step (s), a multiple of the records' step.  A monitor needs it; :func:`prognosis.prognose`
        chooses, when it is None, one derivative window of the record's samples.
    n_particles : int
        Particles per hypothesis, 2 to :data:`MAX_PARTICLES`.
    inflation : float, optional
        Multiplier of the residual noise covariance in the likelihood; default
        :attr:`likelihood_inflation`: 4 with ``"sir"`` (Jha et al. (2016)), 1 with ``"resample-move"``.
    life : (float, float)
        Prior of the life from nominal to failure, in filter steps (log-uniform).
    rate : (float, float), optional
        A prior interval of the rate instead (uniform; the same for every hypothesis).
    process_noise : float
        ``"sir"`` only: sigma_v per step as a fraction of the candidate's resolution per sample (the
        residual noise over the sensitivity of the residual to it at the alarm), in both monitors,
        for the built-in laws; a law given as a model (``laws={name: model}``) keeps its own.
    discount : float
        ``"sir"`` only: kernel smoothing of the rate (:class:`~prognosis.particle_filter.KernelSmoothing`).
    rul_every : int
        Predict the RUL every this many filter steps.
    horizon : float, optional
        RUL horizon cap (s); default :attr:`rul_horizon`, :data:`HORIZON_STEPS` filter steps.
    min_ratio : float
        Evidence ratio before a candidate or a law is declared.
    seed : int or numpy.random.SeedSequence
    """

    laws: tuple | Mapping = LAWS
    candidates: tuple | None = None
    sensors: bool = True
    pairs: bool | None = None
    method: str = "resample-move"
    dt: float | None = None
    n_particles: int = 500
    inflation: float | None = None
    life: tuple = LIFE_PRIOR
    rate: tuple | None = None
    process_noise: float = PROCESS_NOISE
    discount: float = 0.98
    rul_every: int = 10
    horizon: float | None = None
    min_ratio: float = EVIDENCE_RATIO
    seed: int | np.random.SeedSequence = 0

    def __post_init__(self) -> None:
        def keep(name: str, value) -> None:
            object.__setattr__(self, name, value)

        if self.method not in METHODS:
            raise SettingError("method", f"{{setting}} must be one of {', '.join(METHODS)}, got {self.method!r}")
        if isinstance(self.laws, str):
            raise SettingError("laws", f"{{setting}}: give a sequence of law names, e.g. ({self.laws!r},), "
                                       "not one string")
        keep("laws", MappingProxyType(dict(self.laws)) if isinstance(self.laws, Mapping) else tuple(self.laws))
        if not self.laws:
            raise SettingError("laws", "{setting}: give at least one degradation law")
        if self.candidates is not None:
            if isinstance(self.candidates, str):
                raise SettingError("candidates", f"{{setting}}: give a sequence of names, e.g. ({self.candidates!r},)")
            keep("candidates", tuple(self.candidates))
        keep("sensors", bool(self.sensors))
        keep("pairs", None if self.pairs is None else bool(self.pairs))
        for name, what in (("dt", "number of seconds"), ("horizon", "number of seconds"), ("inflation", "number")):
            if getattr(self, name) is not None:  # None: chosen (see the parameters)
                keep(name, _positive(getattr(self, name), name, what))
        if isinstance(self.n_particles, (bool, np.bool_)) or not isinstance(self.n_particles, numbers.Integral) \
                or not 2 <= self.n_particles <= MAX_PARTICLES:
            raise SettingError("n_particles", f"{{setting}} must be a whole number in [2, {MAX_PARTICLES}], "
                                              f"got {self.n_particles!r}")
        keep("n_particles", int(self.n_particles))
        keep("life", _interval(self.life, "life", positive=True))
        if self.rate is not None:
            keep("rate", _interval(self.rate, "rate"))
        if not (_real(self.process_noise) and self.process_noise >= 0):
            raise SettingError("process_noise", f"{{setting}} must be a finite number >= 0, got {self.process_noise!r}")
        if not (_real(self.discount) and 1 / 3 < self.discount <= 1):
            raise SettingError("discount", f"{{setting}} must be a number in (1/3, 1], got {self.discount!r}")
        if isinstance(self.rul_every, (bool, np.bool_)) or not isinstance(self.rul_every, numbers.Integral) \
                or self.rul_every < 1:
            raise SettingError("rul_every", f"{{setting}} must be at least 1 filter step, got {self.rul_every!r}")
        keep("rul_every", int(self.rul_every))
        if not (_real(self.min_ratio) and self.min_ratio >= 1):
            raise SettingError("min_ratio", f"{{setting}} must be a finite evidence ratio >= 1, got {self.min_ratio!r}")
        keep("min_ratio", float(self.min_ratio))
        if not isinstance(self.seed, np.random.SeedSequence) and (
                isinstance(self.seed, (bool, np.bool_)) or not isinstance(self.seed, numbers.Integral)
                or not 0 <= self.seed < 2**63):
            raise SettingError("seed", f"{{setting}} must be an integer in [0, 2**63) or a numpy.random.SeedSequence, "
                                       f"got {self.seed!r}")
        if not isinstance(self.seed, np.random.SeedSequence):
            keep("seed", int(self.seed))
        if self.pairs and not self.pairs_possible:
            raise SettingError("pairs", "{setting}: two faults at once are weighed with {setting:method} "
                                        "resample-move and without {setting:candidates} only")

    def require_step(self, who: str) -> None:
        """A SettingError naming ``dt`` unless it is given: a monitor steps its filter by it."""
        if self.dt is None:
            raise SettingError("dt", f"{{setting}}: {who} needs the filter step (s), a multiple of the records' step; "
                                     "prognosis.prognose chooses one derivative window of the record")

    @property
    def law_models(self) -> dict:
        """Law name -> the user's model, or None for a built-in law (made per hypothesis)."""
        return dict(self.laws) if isinstance(self.laws, Mapping) else {name: None for name in self.laws}

    @property
    def pairs_possible(self) -> bool:
        """Two faults at once can be weighed: the resample-move filter, candidates from the signature.

        >>> IsolationSettings().pairs_possible, IsolationSettings(method="sir").pairs_possible
        (True, False)
        """
        return self.method == "resample-move" and self.candidates is None

    @property
    def likelihood_inflation(self) -> float:
        """``inflation``, by default 4 with ``"sir"`` (the random walk's likelihood widened as in Jha et al.
        (2016)) and 1 with ``"resample-move"`` (the noise as measured)."""
        if self.inflation is not None:
            return self.inflation
        return 4.0 if self.method == "sir" else 1.0

    @property
    def rul_horizon(self) -> float:
        """``horizon``, by default :data:`HORIZON_STEPS` filter steps (of a given ``dt``)."""
        return HORIZON_STEPS * self.dt if self.horizon is None else self.horizon

    def changed(self, **changes) -> "IsolationSettings":
        """A copy with ``changes``, checked; an unknown name is refused with the known ones."""
        names = [f.name for f in dataclasses.fields(self)]
        unknown = [name for name in changes if name not in names]
        if unknown:
            raise SettingError(unknown[0], f"unknown setting {{setting}} (settings: {', '.join(names)})")
        return dataclasses.replace(self, **changes) if changes else self


def _real(value) -> bool:
    return not isinstance(value, (bool, np.bool_)) and isinstance(value, numbers.Real) and math.isfinite(value)


def _positive(value, name: str, what: str) -> float:
    if not (_real(value) and value > 0):
        raise SettingError(name, f"{{setting}} must be a positive {what}, got {value!r}")
    return float(value)


def _interval(value, name: str, positive: bool = False) -> tuple[float, float]:
    """Two finite numbers ``lo < hi`` (both > 0 with ``positive``), as floats."""
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise SettingError(name, f"{{setting}} must be two numbers (lo, hi), got {value!r}") from None
    if not (_real(lo) and _real(hi) and lo < hi and (lo > 0 or not positive)):
        need = "0 < lo < hi" if positive else "lo < hi"
        raise SettingError(name, f"{{setting}} must be two finite numbers with {need}, got {value!r}")
    return float(lo), float(hi)


#: a fleet's settings by default: its random-walk filter, the laws with one rate, parameters only
FLEET_SETTINGS = IsolationSettings(laws=FLEET_LAWS, sensors=False, method="sir")
