"""``bgphm demo``: the whole chain on a built-in example, through the same commands a user runs.

A demo simulates the example with one parameter degrading exponentially from a known time, adds sensor
noise, writes the model and the record (``data.csv``) to the output directory with ``truth.json``, the
degradation it injected and the true end of life to set beside the prediction.  :func:`prepare_demo`
does that and returns the ``bgphm arr``, ``bgphm detect`` and ``bgphm prognose`` command lines on
those files; the CLI's ``demo`` command runs them, printing each one so that it can be rerun by hand
with the same results.

* ``dc-motor``: rotor friction ``b`` x20 from t = 1 s, at 12 V (ARR of the mechanical junction).
* ``torsion-bar``: load-disk bearing friction ``b_Ld`` under the PI speed loop, at the rate of Jha et al. (2016)
  (0.05 1/s from t = 10 s), failing at 90 x nominal at t = 100 s (ARR of the load disk, ``1_2``).
* ``three-tank``: outlet valve ``az2`` of tank 2 opening up (erosion) at 2e-3 1/s from t = 200 s,
  failing at 2 x nominal (ARR of tank 2, ``0_2``), sampled every second as in Du et al. (n.d.).

The model file is JSON (data, no code) when every input of the example is a number.  The torsion
bar's voltage comes from a PI speed loop, which JSON cannot hold: that demo writes ``model.py``,
which rebuilds the library example with its controller, so that ``bgphm simulate model.py`` gives
the nominal closed-loop run.  ``detect`` and ``prognose`` take every signal from the record and
nothing from the model's inputs, so the file type does not change their results.

Torsion bar.  Jha et al. (2016) degrade the motor-disk friction ``b_Md``; without a current sensor no ARR of
the complete torsion bar contains it (the paper measures the motor torque as an extra input), so the
demo degrades the bearing friction its ARR does see, with the paper's onset, rate and end of life.
That ARR integrates the shaft's twist rate from the two speeds, and the CLI has no encoder angles
to take that integral from: the record is sampled at 1 kHz (at 100 Hz the trapezoidal rule misses
2.8 mrad of twist in the start-up, a 5 mN.m offset) with 1e-3 rad/s speed noise.  With the paper's
0.01 rad/s, the integrated noise (about 5 mN.m over the record) and a margin ten times wider hide
the fault until t = 65-70 s; with 1e-3 rad/s the alarm comes at t = 30-36 s, b_Ld at 3-4 x nominal.
"""

from __future__ import annotations

import json
import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bgphm.errors import UsageError
from bgphm.files import csv_text, write_text
from bondgraph.io import to_json
from bondgraph.library import Example, example
from diagnosis.records import add_noise, as_record

__all__ = ["Demo", "DEMOS", "DemoPlan", "prepare_demo"]


@dataclass(frozen=True)
class Demo:
    """A degradation scenario on a library example.

    The candidate follows ``nominal * exp(rate * (t - onset))`` after ``onset`` (a negative
    ``rate`` with ``fail_factor < 1`` for a parameter that decreases) and fails at
    ``nominal * fail_factor``.
    """

    example: str
    candidate: str
    rate: float  # exponential rate of the candidate after the onset (1/s)
    onset: float  # s
    fail_factor: float  # failure value = nominal * fail_factor
    t_end: float  # s
    samples: int
    noise: dict = field(default_factory=dict)  # signal -> std
    calibrate: float = 0.0  # s of the record assumed fault-free for the noise margin
    particles: int = 300
    inputs: dict = field(default_factory=dict)  # overrides of the example's inputs (numbers)
    persistence: int | None = None  # consecutive violations for an alarm (None: the CLI's default)
    integrals: str = "avoid"  # the CLI's --integrals
    dt: float | None = None  # the CLI's --dt (None: its default, one derivative window of samples)
    description: str = ""

    def theta(self, nominal: float):
        """The candidate's true value as a function of time."""
        return lambda t: nominal * math.exp(self.rate * max(0.0, t - self.onset))

    def eol(self, nominal: float) -> float:
        """True end of life (s): when the candidate reaches its failure value.

        >>> round(DEMOS["three-tank"].eol(0.6), 1)  # az2 doubles 346.6 s after the onset
        546.6
        """
        return self.onset + math.log(self.fail_factor) / self.rate


DEMOS = {
    "dc-motor": Demo("dc-motor", "b", rate=0.8, onset=1.0, fail_factor=20.0, t_end=4.0, samples=4001,
                     noise={"i": 0.01, "omega": 0.5}, calibrate=0.9,
                     description="rotor friction b x20 at 12 V"),
    # the rate and onset of Jha et al. (2016); b_Ld fails at 90 x nominal at t = 100 s (b_Md at 0.45 is 89.6 x nominal)
    "torsion-bar": Demo("torsion-bar", "b_Ld", rate=0.05, onset=10.0, fail_factor=90.0, t_end=90.0, samples=90001,
                        noise={"omega_m": 1e-3, "omega_Ld": 1e-3}, calibrate=9.5, particles=200,
                        # the paper's form (eq. 45): at 1 kHz a second derivative of 1e-3 rad/s noise is about
                        # 30 rad/s^3, while over 90 s the integral's random walk stays near 3e-4 rad
                        integrals="keep", dt=0.1,  # the filter step of Jha et al. (2016)
                        description="load-disk bearing friction b_Ld x90, PI speed loop, rate of Jha et al. (2016)"),
    "three-tank": Demo("three-tank", "az2", rate=2e-3, onset=200.0, fail_factor=2.0, t_end=500.0, samples=501,
                       noise={"h1": 2e-4, "h2": 2e-4, "h3": 2e-4}, calibrate=190.0, particles=500,
                       description="outlet valve az2 of tank 2 opening up x2 (erosion)"),
}


@dataclass(frozen=True)
class DemoPlan:
    """A demo ready to run: its files are written, its ``bgphm`` command lines are listed.

    Attributes
    ----------
    demo : Demo
        The scenario.
    commands : list of list of str
        The ``bgphm`` argument lists to run in order (without ``bgphm`` and its global options).
    truth : dict
        What ``truth.json`` holds: the injected degradation and the true end of life ``eol``.
    out : Path
        The output directory; ``prognose`` writes ``out / "prognose" / "prognosis.json"``.
    """

    demo: Demo
    commands: list
    truth: dict
    out: Path

    def truth_line(self) -> str | None:
        """The true RUL and candidate value at the last prediction of ``prognose``; None without an alarm.

        Read after the commands ran, from the ``prognosis.json`` they wrote.
        """
        summary = json.loads((self.out / "prognose" / "prognosis.json").read_text())
        if summary.get("detection_time") is None:
            return None
        t = summary["last"]["t"]
        theta = self.demo.theta(self.truth["nominal"])(t)
        return (f"truth: at t = {t:g} s the RUL is {self.truth['eol'] - t:.4g} s and {self.demo.candidate} = "
                f"{theta:.4g}")


def prepare_demo(name: str, out: Path, progress: Callable[[str], None], *, seed: int = 0) -> DemoPlan:
    """Write the model, the record and ``truth.json`` of the demo ``name`` into ``out``; return its commands.

    ``progress`` receives a progress line (the CLI prints it on stderr unless ``--quiet``).
    Raises :class:`~bgphm.errors.UsageError` for an unknown demo, naming the available ones.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp())
    >>> plan = prepare_demo("three-tank", out, progress=lambda line: None)  # doctest: +ELLIPSIS
    wrote ...model.json, ...data.csv and ...truth.json (true end of life 546.6 s)
    >>> [command[0] for command in plan.commands], plan.truth["candidate"]
    (['arr', 'detect', 'prognose'], 'az2')
    >>> import shutil; shutil.rmtree(out)
    """
    if name not in DEMOS:
        raise UsageError(f"unknown demo {name!r} (available: {', '.join(DEMOS)})")
    demo = DEMOS[name]
    ex = example(demo.example)
    nominal = float(ex.model.parameters[demo.candidate])
    out.mkdir(parents=True, exist_ok=True)
    progress(f"demo {name}: simulating {ex.model.name!r} over [0, {demo.t_end:g}] s with {demo.candidate} degrading "
             f"from t = {demo.onset:g} s")
    model_path = _write_model(demo, ex, out)
    data_path = _write_record(demo, ex, nominal, out / "data.csv", seed)
    truth = {"candidate": demo.candidate, "nominal": nominal, "degradation": "exponential", "rate": demo.rate,
             "onset": demo.onset, "failure_value": nominal * demo.fail_factor, "eol": demo.eol(nominal),
             "noise_std": demo.noise, "seed": seed}
    write_text(out / "truth.json", json.dumps(truth, indent=2))
    print(f"wrote {model_path}, {data_path} and {out / 'truth.json'} (true end of life {truth['eol']:.4g} s)")
    commands = _commands(demo, model_path, data_path, truth["failure_value"], out, seed)
    return DemoPlan(demo, commands, truth, out)


def _write_record(demo: Demo, ex: Example, nominal: float, path: Path, seed: int) -> Path:
    """Simulate the degradation, add the sensor noise and write the CSV the commands read."""
    from bondgraph.simulation import simulate  # scipy's solvers: not needed to build the CLI's parser

    t = np.linspace(0.0, demo.t_end, demo.samples)
    result = simulate(ex.model, (0.0, demo.t_end), {**ex.inputs, **demo.inputs}, x0=ex.x0,
                      parameters={demo.candidate: demo.theta(nominal)}, t_eval=t,
                      max_step=demo.t_end / demo.samples * 5)
    record = add_noise(as_record(result.record(), name=demo.example), demo.noise, seed=seed)
    return write_text(path, csv_text({"t": record.t, **record.columns}))


def _write_model(demo: Demo, ex: Example, out: Path) -> Path:
    """``model.json`` when every input is a number, else ``model.py`` (see the module docstring)."""
    inputs = {**ex.inputs, **demo.inputs}
    if all(_is_number(v) for v in inputs.values()):
        return write_text(out / "model.json", to_json(ex.model, inputs=inputs, t_end=demo.t_end, x0=ex.x0))
    bad = [k for k, v in demo.inputs.items() if not _is_number(v)]
    if bad:  # a model.py can only rebuild the example's own functions of time
        raise ValueError(f"demo {demo.example!r}: input overrides {bad} must be numbers")
    overrides = {k: float(v) for k, v in demo.inputs.items()}
    inputs_line = f"inputs = {{**_example.inputs, **{overrides!r}}}" if overrides else "inputs = _example.inputs"
    return write_text(out / "model.py", "\n".join([
        f'"""The model of ``bgphm demo {demo.example}``: the library example with its inputs.',
        "",
        "Python rather than JSON because an input is a function of time or a controller, which JSON",
        'cannot hold.  ``bgphm simulate`` on this file gives the nominal (fault-free) run.',
        '"""',
        "",
        "from bondgraph.library import example",
        "",
        f"_example = example({demo.example!r})",
        "model = _example.model",
        inputs_line,
        "x0 = _example.x0",
        f"t_end = {float(demo.t_end)!r}",
        "",
    ]))


def _commands(demo: Demo, model_path: Path, data_path: Path, fail: float, out: Path, seed: int) -> list[list[str]]:
    """The ``bgphm`` command lines of the demo, as a user would type them.

    Each writes into the demo's own directory, which the demo has checked (new, empty or
    ``--force``), so each has ``--force``: rerun by hand, it replaces its own outputs.
    """
    model, data = str(model_path), str(data_path)
    detection = ["--calibrate", f"{demo.calibrate:g}"]
    if demo.integrals != "avoid":  # the CLI's default
        detection += ["--integrals", demo.integrals]
    if demo.persistence is not None:
        detection += ["--persistence", str(demo.persistence)]
    return [
        ["arr", model, "--format", "html", "--out", str(out / "report.html"), "--force"],
        ["detect", model, data, *detection, "--out", str(out / "detect"), "--force"],
        ["prognose", model, data, "--fail", f"{demo.candidate}={fail:.6g}", *detection,
         "--particles", str(demo.particles), *(["--dt", f"{demo.dt:g}"] if demo.dt else []), "--seed", str(seed),
         "--out", str(out / "prognose"), "--force"],
    ]


def _is_number(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)
