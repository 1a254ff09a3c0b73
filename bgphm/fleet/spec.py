"""The description of a fleet job that travels to the workers, and the monitor each worker builds from it.

A :class:`FleetSpec` holds only names, numbers and paths: the model (a file path or a built-in name),
the failure values, the laws, the residual noise and detection options per ARR, and the settings of
:class:`~prognosis.fleet.FleetMonitor`.  It pickles to a few hundred bytes, so it is what the driver
ships with every shard; ARRs and monitors never travel (they hold lambdified functions and, once
run, large arrays).  :func:`monitor_for` builds the ARRs and the monitor from a spec once per worker
thread and keeps them for the next shards of the same job.

Examples
--------
>>> spec = FleetSpec("rlc", {"R": 20.0}, noise_std={"ARR_J1": 1e-3}, laws=("linear",), dt=0.01, arrs=["ARR_J1"],
...                  detection={"margin": 0.01})
>>> dict(spec.failures), spec.laws
({'R': 20.0}, ('linear',))
>>> import pickle
>>> pickle.loads(pickle.dumps(spec)) == spec, len(pickle.dumps(spec)) < 2000
(True, True)
"""

from __future__ import annotations

import math
import threading
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from bgphm.errors import UsageError

__all__ = ["FleetSpec", "Built", "model_reference", "monitor_for"]

CACHE_SIZE = 4  # specs kept per worker thread: a long-lived remote worker may serve several jobs


def model_reference(model: str | Path) -> str:
    """The model as a worker can load it: an existing file as an absolute path, else the name as given.

    A relative path would be resolved against the worker's working directory, not the driver's.

    >>> model_reference("dc-motor")
    'dc-motor'
    """
    text = str(model)
    path, sep, attribute = text.rpartition(":") if ".py:" in text else (text, "", "")
    return str(Path(path).resolve()) + sep + attribute if Path(path).is_file() else text


@dataclass(frozen=True)
class FleetSpec:
    """A fleet job: the model, what can fail, the noise and detection per ARR, the monitor's settings.

    Parameters
    ----------
    model : str
        A model file (JSON or Python, see :func:`bondgraph.io.load_model`; give an absolute path, or
        use :func:`model_reference`) or a built-in example name.
    failures : mapping
        Failure value per parameter that can fail.
    noise_std : mapping
        Standard deviation of each ARR's residual on healthy data (by ARR name).
    detection : mapping, optional
        Options of the detection (``margin``, ``persistence``, ``window``), shared or per ARR name.
    laws : sequence of str
        Built-in law names competing per candidate (``"linear"``, ``"exponential"``).
    candidates : sequence of str, optional
        Only these candidates.
    arrs : sequence of str, optional
        Only the ARRs of these names (default: all the model gives).
    integrals : {"avoid", "keep"}
        As :func:`diagnosis.derive_arrs`.
    dt, n_particles, rul_every, report_every, horizon, rate, healthy_until, seed
        As :class:`~prognosis.fleet.FleetMonitor`.
    process_noise : float, optional
        Absolute standard deviation of each law's process noise per filter step (the ``process_noise``
        of :func:`prognosis.degradation.degradation_model`), the same for every candidate: the monitor
        gets ``{law: degradation_model(law, process_noise)}``.  None (default): the monitor's own
        sigma_v, a fraction of each candidate's resolution (FleetMonitor's relative ``process_noise``).

    Notes
    -----
    Mappings are stored read-only and compared by value, so a spec can key a cache.
    """

    model: str
    failures: Mapping[str, float]
    noise_std: Mapping[str, float]
    detection: Mapping = field(default_factory=dict)
    laws: Sequence[str] = ("linear", "exponential")
    candidates: Sequence[str] | None = None
    arrs: Sequence[str] | None = None
    integrals: str = "avoid"
    dt: float = 0.1
    n_particles: int = 500
    rul_every: int = 10
    report_every: int | None = None
    horizon: float | None = None
    rate: tuple[float, float] | None = None
    healthy_until: float | None = None
    seed: int = 0
    process_noise: float | None = None

    def __post_init__(self):
        if not isinstance(self.model, (str, Path)):
            raise UsageError(f"FleetSpec model must be a path or a built-in name, got {type(self.model).__name__}")
        if not isinstance(self.laws, (list, tuple)) or not all(isinstance(law, str) for law in self.laws):
            raise UsageError(f"FleetSpec laws must be built-in law names (e.g. ['linear']), got {self.laws!r}: "
                             "a law object would have to travel to every worker")
        object.__setattr__(self, "model", str(self.model))
        if self.process_noise is not None:
            object.__setattr__(self, "process_noise", _noise(self.process_noise))
        for name in ("failures", "noise_std", "detection"):
            object.__setattr__(self, name, _frozen(getattr(self, name), name))
        for name in ("laws", "candidates", "arrs", "rate"):
            value = getattr(self, name)
            object.__setattr__(self, name, None if value is None else tuple(value))

    def __hash__(self) -> int:
        return hash(self.key())

    def __eq__(self, other: object) -> bool:
        return isinstance(other, FleetSpec) and self.key() == other.key()

    def __reduce__(self):
        # plain dicts on the wire (a mappingproxy does not pickle); __post_init__ freezes them again
        return _rebuild, (self.as_dict(),)

    def key(self) -> str:
        """The spec as canonical text (sorted keys): equal specs, equal keys."""
        return repr(sorted(self.as_dict().items()))

    def as_dict(self) -> dict:
        """The spec as plain data (for ``summary.json``)."""
        out = {}
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            out[name] = _thawed(value) if isinstance(value, Mapping) else value
        return out


def _noise(value) -> float:
    """A process noise sigma_v: a finite number >= 0 (a float, so that equal specs have equal keys)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
        raise UsageError(f"FleetSpec process_noise must be a finite number >= 0 (sigma_v per filter step), "
                         f"got {value!r}")
    return float(value)


def _rebuild(state: dict) -> FleetSpec:
    return FleetSpec(**state)


def _frozen(value, name: str) -> Mapping:
    if not isinstance(value, Mapping):
        raise UsageError(f"FleetSpec {name} must be a mapping, got {type(value).__name__}")
    return MappingProxyType({str(k): _frozen(v, name) if isinstance(v, Mapping) else v
                             for k, v in sorted(value.items())})


def _thawed(value: Mapping) -> dict:
    return {k: _thawed(v) if isinstance(v, Mapping) else v for k, v in value.items()}


@dataclass
class Built:
    """What a worker builds from a spec: the monitor, the record columns it reads (signals, antiderivatives) and
    the model (its units name the page's axes)."""

    monitor: object  # a prognosis.fleet.FleetMonitor
    signals: list
    model: object = None  # the bondgraph.BondGraph


_local = threading.local()  # FleetMonitor's streams share one generator: one monitor per thread


def monitor_for(spec: FleetSpec) -> tuple[Built, bool]:
    """The ARRs and the :class:`~prognosis.fleet.FleetMonitor` of ``spec``, built once per thread.

    Returns the built objects and whether this call built them (False when they came from the cache).

    >>> spec = FleetSpec("rlc", {"R": 20.0}, noise_std={"ARR_J1": 1e-3}, laws=("linear",), dt=0.01, arrs=["ARR_J1"])
    >>> (built, new), (again, new_again) = monitor_for(spec), monitor_for(spec)
    >>> new, new_again, again is built, built.signals
    (True, False, True, ['V', 'i', 'v_C'])
    """
    cache = _local.__dict__.setdefault("built", {})
    key = spec.key()
    if key in cache:
        return cache[key], False
    built = build(spec)
    if len(cache) >= CACHE_SIZE:
        cache.pop(next(iter(cache)))
    cache[key] = built
    return built, True


def build(spec: FleetSpec) -> Built:
    """Load the model, derive its ARRs and build the monitor of ``spec`` (no cache)."""
    from bondgraph.io import load_model
    from diagnosis.derivation import ARRWarning, derive_arrs
    from prognosis.degradation import degradation_model
    from prognosis.fleet import FleetMonitor

    loaded = load_model(spec.model)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)  # the driver showed them; a worker would repeat them per job
        arrs = derive_arrs(loaded.model, integrals=spec.integrals)
    if spec.arrs is not None:
        names = [a.name for a in arrs]
        unknown = [n for n in spec.arrs if n not in names]
        if unknown:
            raise UsageError(f"FleetSpec arrs: no ARR {unknown} in {loaded.source} (ARRs: {', '.join(names)})")
        arrs = [a for a in arrs if a.name in spec.arrs]
    # law objects carry an absolute sigma_v; names leave it to the monitor (relative to each candidate)
    laws = (list(spec.laws) if spec.process_noise is None
            else {law: degradation_model(law, spec.process_noise) for law in spec.laws})
    monitor = FleetMonitor(arrs, dict(spec.failures), noise_std=dict(spec.noise_std), laws=laws,
                           candidates=None if spec.candidates is None else list(spec.candidates), dt=spec.dt,
                           n_particles=spec.n_particles, rul_every=spec.rul_every, report_every=spec.report_every,
                           horizon=spec.horizon, rate=spec.rate, detection=_thawed(spec.detection),
                           healthy_until=spec.healthy_until,
                           domains=loaded.model.domains, seed=spec.seed)
    # the detection reads the antiderivative columns too (e.g. encoder angles): a source must read them
    signals = list(dict.fromkeys(s for arr, options in zip(monitor.arrs, monitor.options)
                                 for s in (*arr.signals, *(options.get("antiderivatives") or {}).values())))
    return Built(monitor, signals, loaded.model)

