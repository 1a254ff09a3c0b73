"""One prognosis scenario, run as a user would: a model file, a CSV, ``bgphm prognose --fail ...``.

A scenario names a system (:data:`SYSTEMS`: the torsion bar, and from the model zoo a DC motor driving a
pump and a pipe feeding a tank), the parameter that wears (or two at once, ``"R_a + c_p"``, or a sensor),
its law and the noise.  The truth (the
parameter's law, hence the end of life) comes from the scenario, the answer from the command's
``prognosis.json``; :func:`score` compares them: whether the degrading parameter was named (or honestly
called undecided or indistinguishable), the share of the second half of life where the median RUL is
within 20 % of the truth, and how often the 5-95 % and 25-75 % bands hold the truth.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import io
import json
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bgphm.cli import main as bgphm
from bgphm.files import csv_text
from bondgraph import to_json
from bondgraph.library import torsion_bar_monitorable
from tests.zoo.check import load_case

from . import torsion, zoo
from .laws import LAWS

WITHIN = 0.2                    # the median RUL is "within" when off by at most this share of the truth


@dataclass(frozen=True)
class System:
    """What a scenario needs of a system: the user's model, the physics, the life and the sensors' noise.

    Attributes
    ----------
    model : callable
        ``model() -> BondGraph``: the model the user writes (as JSON for ``bgphm prognose``).
    simulate : callable
        ``simulate(parameters, *, t_end, dt, noise, seed) -> columns``, written from the physics;
        ``parameters`` maps a name to a value or a law ``theta(t)``.
    nominal : mapping
        Parameter -> nominal value (where every law starts).
    failures : mapping
        ``--fail`` values, one for every parameter an ARR sees; the law reaches its parameter's at ``eol``.
    wearing : tuple of str
        The parameters the scenarios wear.
    onset, eol : float
        s: the wear runs from ``onset`` to ``eol``, where the parameter reaches its failure value.
    t_end, dt : float
        s: the record's length and sample time.
    calibrate : float
        s: the healthy stretch given as ``--calibrate`` (before the onset).
    noise : mapping
        ``"clean"`` and ``"noisy"`` -> signal -> standard deviation of its Gaussian noise.
    sensors : mapping
        Signal -> the offset a faulty sensor reaches (a bias from the onset, or a drift to it at the
        end of life, :data:`SENSOR_LAWS`): sensor faults have no failure value and no end of life;
        a scenario asks only that the sensor be named.
    concurrent : mapping
        ``"a + b"`` -> ``((a, law, eol), (b, law, eol))``: two parameters wearing at once from the onset,
        each by its law to its failure value at its own end of life; the scenario's end of life is the
        first failure.
    """

    model: Callable
    simulate: Callable
    nominal: Mapping
    failures: Mapping
    wearing: tuple
    onset: float
    eol: float
    t_end: float
    dt: float
    calibrate: float
    noise: Mapping
    sensors: Mapping = dataclasses.field(default_factory=dict)
    concurrent: Mapping = dataclasses.field(default_factory=dict)


SENSOR_LAWS = {
    "bias": lambda size, onset, eol: lambda t: size * (np.asarray(t, float) >= onset),
    "drift": lambda size, onset, eol: lambda t: size * np.clip((np.asarray(t, float) - onset) / (eol - onset), 0, None),
}


def _zoo(name: str, **facts) -> System:
    """A zoo case's model and physics (:mod:`tests.wear.zoo`) under its smooth inputs (a start-up, then
    periodic swings that keep every term of its ARRs excited over the whole life); every parameter fails
    at twice nominal, as tests/zoo/test_cli_chain.py gives them."""
    case = load_case(name)
    nominal = zoo.nominal(case)
    physics = functools.partial(zoo.simulate, case, inputs=case.smooth_inputs, breaks=(facts["onset"],))
    return System(model=case.build, simulate=physics, nominal=nominal,
                  failures={p: 2 * v for p, v in nominal.items()}, **facts)


_TORSION_NOISE = {"clean": {k: v for k, v in torsion.NOISE.items() if k != "tau_m"}, "noisy": dict(torsion.NOISE)}

SYSTEMS = {
    # Jha et al. (2016), 6.3: the motor disk's friction b_Md to the paper's 0.45; ten times nominal for the
    # other frictions (what an engineer would call worn out).  "clean": the encoders' noise on the speeds
    # only; "noisy": the measured torque too, which enters the residual undifferentiated.
    "torsion_bar": System(
        model=torsion_bar_monitorable, simulate=torsion.simulate, nominal=torsion.NOMINAL,
        failures={"b_Md": 0.45, "b_Ld": 10 * torsion.NOMINAL["b_Ld"], "f_m": 10 * torsion.NOMINAL["f_m"]},
        wearing=("b_Md",), onset=10.0, eol=100.0, t_end=100.0, dt=0.01, calibrate=8.0, noise=_TORSION_NOISE,
        # an encoder of the load speed (30 rad/s) off by 0.5 rad/s from the onset (a slipped code disc's
        # count), and the motor's (110 rad/s) drifting to 2 rad/s at the end (a tachogenerator's brushes)
        sensors={"omega_Ld": ("bias", 0.5), "omega_m": ("drift", 2.0)}),
    # (The zoo's heat exchanger, whose wall fouls, was tried first: six of its ARRs see the wall, with four
    # sensors, and their healthy covariance is singular; bgphm prognose --filter resample-move then stops,
    # exit 1 or 2, on some seeds.)
    # Brush and commutator wear: the armature circuit's resistance R_a doubles, and the drive loses its
    # torque reserve; the other parameters fail at twice nominal too.  Noise: the armature voltage is the
    # drive's command, known; the pump's speed from a tachogenerator, 0.3 rad/s (0.2 % of 160 rad/s, its
    # ripple); the current 0.03 A for "clean", a Hall-effect transducer (0.2 % of 15 A), 0.1 A for
    # "noisy", a shunt amplifier sampled inside the PWM period, where the switching ripple aliases into
    # the samples (0.7 % of the 14 A peak).  The armature's ARR sees both (k_m omega_p / r_g; R_a i and
    # L_a di/dt), the noisy current then most of its noise.
    # Two faults at once: the brushes wear linearly while the pump's impeller fouls (its load coefficient
    # c_p doubles, faster and faster) and fails first, at 1.6 s; the brushes' ARR fires first.
    "pump_drive": _zoo(
        "pump_drive", wearing=("R_a",), onset=0.2, eol=2.0, t_end=2.0, dt=5e-4, calibrate=0.15,
        noise={"clean": {"i": 0.03, "omega_p": 0.3}, "noisy": {"i": 0.1, "omega_p": 0.3}},
        concurrent={"R_a + c_p": (("R_a", "linear", 2.0), ("c_p", "exponential", 1.6))}),
    # Clogging of the pipe's strainer: R_f rises to twice its clean value, the usual change criterion (the
    # pressure drop at rated flow doubled); the other parameters at twice nominal too.  Noise: the supply
    # and tank pressures are 0.1 %-class transmitters on a 25 kPa span, 20 Pa; the flow, 3e-4 m^3/s, is
    # read by an electromagnetic meter at 0.3 % of reading, 1e-6 m^3/s, for "clean", by a turbine meter at
    # 1 %, 3e-6 m^3/s, for "noisy": the flow carries the residual's noise (R_f Q and L_f dQ/dt, where the
    # derivative amplifies it).
    # Two faults at once: the strainer clogs linearly while the tank's outlet orifice scales up (R_o doubles,
    # faster and faster) and fails first, at 240 s; the strainer's ARR fires first.
    "pipe_tank": _zoo(
        "pipe_tank", wearing=("R_f",), onset=30.0, eol=300.0, t_end=300.0, dt=0.05, calibrate=25.0,
        noise={"clean": {"P_s": 20.0, "p_t": 20.0, "Q": 1e-6}, "noisy": {"P_s": 20.0, "p_t": 20.0, "Q": 3e-6}},
        concurrent={"R_f + R_o": (("R_f", "linear", 300.0), ("R_o", "exponential", 240.0))}),
}


@dataclass(frozen=True)
class Scenario:
    """A system's parameter wearing by a law, with a "clean" or a "noisy" residual (:data:`SYSTEMS`)."""

    system: str
    parameter: str
    law: str
    noise: str

    @property
    def name(self) -> str:
        return f"{self.system}/{self.parameter}/{self.law}/{self.noise}"

    @property
    def wearing(self) -> tuple:
        """(parameter, law, end of life) of each wearing parameter: one, or two for concurrent faults."""
        if self.parameter in self.facts.concurrent:
            return self.facts.concurrent[self.parameter]
        return ((self.parameter, self.law, self.facts.eol),) if not self.sensor else ()

    @property
    def sensor(self) -> str | None:
        """The faulty sensor's signal, for a sensor fault (``parameter`` ``"sensor <signal>"``)."""
        return self.parameter[len("sensor "):] if self.parameter.startswith("sensor ") else None

    @property
    def facts(self) -> System:
        return SYSTEMS[self.system]

    @property
    def onset(self) -> float:
        return self.facts.onset

    @property
    def eol(self) -> float:
        """The end of life: the first failure."""
        return min((eol for _, _, eol in self.wearing), default=self.facts.eol)


def scenarios() -> list[Scenario]:
    """Every system's wearing parameters under every law, with a clean and a noisy residual."""
    wear = [Scenario(system, parameter, law, noise) for system, facts in SYSTEMS.items()
            for parameter in facts.wearing for law in LAWS for noise in ("clean", "noisy")]
    sensors = [Scenario(system, f"sensor {signal}", law, noise) for system, facts in SYSTEMS.items()
               for signal, (law, _) in facts.sensors.items() for noise in ("clean", "noisy")]
    concurrent = [Scenario(system, pair, " + ".join(law for _, law, _ in wearing), noise)
                  for system, facts in SYSTEMS.items() for pair, wearing in facts.concurrent.items()
                  for noise in ("clean", "noisy")]
    return wear + sensors + concurrent


def truth(scenario: Scenario) -> Callable:
    """The wearing parameter's law ``theta(t)``: nominal up to the onset, the failure value at the end of life
    (a sensor's offset for a sensor fault; the first parameter's law for concurrent faults, :func:`laws`)."""
    facts = scenario.facts
    if scenario.sensor:
        law, size = facts.sensors[scenario.sensor]
        return SENSOR_LAWS[law](size, facts.onset, facts.eol)
    return laws(scenario)[scenario.wearing[0][0]]


def laws(scenario: Scenario) -> dict:
    """Each wearing parameter's law ``theta(t)``, from nominal at the onset to failure at its end of life."""
    facts = scenario.facts
    return {name: LAWS[law](facts.nominal[name], facts.failures[name], facts.onset, eol)
            for name, law, eol in scenario.wearing}


def record(scenario: Scenario, seed: int, *, noise: Mapping | None = None) -> dict:
    """The scenario's record (the CSV's columns); ``noise`` replaces the scenario's (``{}``: noise-free)."""
    facts = scenario.facts
    noise = facts.noise[scenario.noise] if noise is None else noise
    if not scenario.sensor:
        return facts.simulate(laws(scenario), t_end=facts.t_end, dt=facts.dt, noise=noise, seed=seed)
    columns = facts.simulate({}, t_end=facts.t_end, dt=facts.dt, noise=noise, seed=seed)
    columns[scenario.sensor] = columns[scenario.sensor] + truth(scenario)(columns["t"])
    return columns


def run(scenario: Scenario, seed: int, *, particles: int = 300, rul_every: int = 10, method: str = "sir",
        degradation: str | tuple = (), sensors: bool = True, pairs: bool | None = None,
        window: int | None = None, extra: tuple = ()) -> dict:
    """``prognosis.json`` of ``bgphm prognose`` on the scenario's record (exit code under ``"exit"``).

    ``degradation``: the competing laws (``--degradation``, a name or several; default the command's);
    ``sensors=False``: the sensors' faults are not weighed (``--no-sensors``); ``pairs=True``: two
    parameters wearing at once are, from the first alarm (``--pairs``, with ``method="resample-move"``),
    ``False``: never (``--no-pairs``), None: the command's default (when no single fault explains the
    residuals); ``window``: the derivative window (``--window``, default the command's); ``extra``: more
    arguments of the command, as given.
    """
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        facts = scenario.facts
        (folder / "model.json").write_text(to_json(facts.model()))
        (folder / "data.csv").write_text(csv_text(record(scenario, seed)))
        fails = [f"--fail={p}={v:g}" for p, v in facts.failures.items()]
        argv = ["--quiet", "prognose", str(folder / "model.json"), str(folder / "data.csv"), *fails,
                "--calibrate", f"{facts.calibrate:g}", "--particles", str(particles), "--rul-every", str(rul_every),
                "--seed", str(seed), "--filter", method, "--out", str(folder / "out"),
                *(f"--degradation={law}" for law in ([degradation] if isinstance(degradation, str) else degradation)),
                *([] if sensors else ["--no-sensors"]), *({True: ["--pairs"], False: ["--no-pairs"]}.get(pairs, [])),
                *([] if window is None else ["--window", str(window)]), *extra]
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()) as err:
            code = bgphm(argv)
        if code != 0:
            return {"exit": code, "error": err.getvalue().strip()}
        return {"exit": 0, **json.loads((folder / "out" / "prognosis.json").read_text())}


def score(scenario: Scenario, answer: dict) -> dict:
    """The scenario's figures from one answer: found, status, within 20 %, both coverages, RA."""
    if answer.get("exit") != 0:
        return {"found": False, "status": f"exit {answer.get('exit')}", "predictions": 0}
    named = answer.get("candidate")
    # an honest "indistinguishable" names a group; a decided answer names the parameter
    group = set(named) if isinstance(named, list) else {named} | set(answer.get("same_signature") or [])
    if named is None:  # no candidate with a failure value: the faults consistent with the ARRs that fired
        group, named = set(answer.get("consistent") or []), answer.get("consistent")
    found = named is not None and any(same_fault(g, scenario.parameter) for g in group)
    onset, eol = scenario.onset, scenario.eol
    given = [p for p in answer.get("predictions", []) if onset < p["t"] < eol]
    # a withheld prediction ("undecided: no law fits") is honest but gives no figure: counted apart
    predictions = [p for p in given if not p.get("withheld")]
    truth = np.array([eol - p["t"] for p in predictions])
    figures = {"found": bool(found), "candidate": named, "status": answer.get("status"),
               "degradation": answer.get("degradation"), "detection_time": answer.get("detection_time"),
               "predictions": len(predictions), "withheld": len(given) - len(predictions),
               "pairs_weighed": answer.get("pairs"),
               # the most probable hypothesis at the end: the faulty parameter or sensor itself, and its law
               "top": _top(answer)}
    if not predictions or scenario.sensor:  # a sensor fault has no end of life: any RUL given is counted, not scored
        return figures
    median = np.array([_number(p["rul_median"]) for p in predictions])
    p5, p95 = (np.array([_number(p[k]) for p in predictions]) for k in ("rul_p5", "rul_p95"))
    second = np.array([p["t"] >= (onset + eol) / 2 for p in predictions])
    within = np.abs(median - truth) <= WITHIN * truth
    figures.update({
        "within_20pct_second_half": float(np.mean(within[second])) if second.any() else None,
        "coverage_90": float(np.mean((p5 <= truth) & (truth <= p95))),
        "ra": float(np.mean(1 - np.abs(truth - np.array([_number(p["rul_mean"]) for p in predictions])) / truth)),
    })
    if all("rul_p25" in p for p in predictions):
        p25, p75 = (np.array([_number(p[k]) for p in predictions]) for k in ("rul_p25", "rul_p75"))
        figures["coverage_50"] = float(np.mean((p25 <= truth) & (truth <= p75)))
        figures["pit"] = pit_histogram(predictions, truth, onset=onset, eol=eol)
    return figures


def _top(answer: dict) -> str | None:
    """The most probable hypothesis ``"candidate/law"`` at the end of the record (None without evidence)."""
    evidence = answer.get("evidence") or {}
    return max(evidence, key=lambda name: evidence[name]["probability"]) if evidence else None


def same_fault(named: str, fault: str) -> bool:
    """``named`` (a candidate, ``"a + b"`` for two at once, in any order) is the fault ``fault``.

    >>> same_fault("c_p + R_a", "R_a + c_p"), same_fault("R_a", "R_a + c_p")
    (True, False)
    """
    return set(str(named).split(" + ")) == set(fault.split(" + "))


def fault_of(hypothesis: str | None) -> str | None:
    """The fault of a hypothesis' name: ``"R_a/power + c_p/power"`` -> ``"R_a + c_p"``."""
    return None if hypothesis is None else " + ".join(part.split("/")[0] for part in hypothesis.split(" + "))


PIT_EDGES = (0.05, 0.25, 0.5, 0.75, 0.95)  # the predicted quantiles: six bins of the PIT between them
QUARTERS = 4


def pit_histogram(predictions: list[dict], truth: np.ndarray, *, onset: float, eol: float) -> list[list[int]]:
    """Counts of the truth's place among the predicted quantiles, per quarter of the life after onset.

    Row q: predictions made in the q-th quarter of (onset, eol); column b: the truth below the 5 %
    quantile (b = 0), between the 5 and 25 % ones (1), ..., above the 95 % one (5).  A calibrated
    band fills the bins as 5, 20, 25, 25, 20, 5 % in every quarter.
    """
    keys = ("rul_p5", "rul_p25", "rul_median", "rul_p75", "rul_p95")
    counts = np.zeros((QUARTERS, len(PIT_EDGES) + 1), int)
    for p, true in zip(predictions, truth):
        quarter = min(QUARTERS - 1, int((p["t"] - onset) / (eol - onset) * QUARTERS))
        counts[quarter, int(np.searchsorted([_number(p[k]) for k in keys], true))] += 1
    return counts.tolist()


def _number(value) -> float:
    return float("inf") if value is None else float(value)
