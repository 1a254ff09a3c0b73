"""``bgphm demo``: the whole chain on a built-in example, through the same commands a user runs.

A demo builds a noisy record of the example with a parameter degrading from a known time, writes the
model (JSON) and the record (CSV) to the output directory, then runs ``bgphm arr``, ``bgphm detect`` and
``bgphm prognose`` on those files, printing each command so it can be rerun by hand, and writes
``truth.json`` with the degradation it injected and the true end of life beside the prediction.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bondgraph.io import to_json
from bondgraph.library import example
from bondgraph.simulation import simulate
from diagnosis.signals import add_noise, as_record


@dataclass(frozen=True)
class Demo:
    """A degradation scenario on a library example."""

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
    inputs: dict = field(default_factory=dict)  # overrides of the example's inputs

    def theta(self, nominal: float):
        """The candidate's true value as a function of time."""
        return lambda t: nominal * math.exp(self.rate * max(0.0, t - self.onset))

    def eol(self, nominal: float) -> float:
        return self.onset + math.log(self.fail_factor) / self.rate


DEMOS = {
    "dc-motor": Demo("dc-motor", "b", rate=0.8, onset=1.0, fail_factor=20.0, t_end=4.0, samples=4001,
                     noise={"i": 0.01, "omega": 0.5}, calibrate=0.9),
}


def run_demo(name: str, out: Path, progress, *, seed: int = 0) -> int:
    """Run the demo ``name`` into ``out``; returns the exit code of the last command."""
    from bgphm.cli import _csv_text, main

    if name not in DEMOS:
        from bgphm.cli import UsageError

        raise UsageError(f"demo {name!r} is not available yet (available: {', '.join(sorted(DEMOS))})")
    demo = DEMOS[name]
    ex = example(demo.example)
    model = ex.model
    nominal = float(model.parameters[demo.candidate])
    out.mkdir(parents=True, exist_ok=True)
    progress(f"demo {name}: simulating {model.name!r} over [0, {demo.t_end:g}] s with {demo.candidate} degrading "
             f"from t = {demo.onset:g} s")
    inputs = {**ex.inputs, **demo.inputs}
    t = np.linspace(0.0, demo.t_end, demo.samples)
    result = simulate(model, (0.0, demo.t_end), inputs, x0=ex.x0, parameters={demo.candidate: demo.theta(nominal)},
                      t_eval=t, max_step=demo.t_end / demo.samples * 5)
    record = add_noise(as_record(result.record(), name=name), demo.noise, seed=seed)
    model_path, data_path = out / "model.json", out / "data.csv"
    constant = {k: v for k, v in inputs.items() if not callable(v)}
    model_path.write_text(to_json(model, inputs=constant, t_end=demo.t_end))
    data_path.write_text(_csv_text({"t": record.t, **record.columns}))
    fail = nominal * demo.fail_factor
    truth = {"candidate": demo.candidate, "nominal": nominal, "degradation": "exponential", "rate": demo.rate,
             "onset": demo.onset, "failure_value": fail, "eol": demo.eol(nominal), "noise_std": demo.noise,
             "seed": seed}
    (out / "truth.json").write_text(json.dumps(truth, indent=2))
    print(f"wrote {model_path}, {data_path} and {out / 'truth.json'} (true end of life {truth['eol']:.3g} s)")
    quiet = ["--quiet"] if progress.quiet else []
    commands = [
        ["arr", str(model_path), "--format", "html", "--out", str(out / "report.html")],
        ["detect", str(model_path), str(data_path), "--calibrate", f"{demo.calibrate:g}", "--out", str(out / "detect")],
        ["prognose", str(model_path), str(data_path), "--candidate", demo.candidate, "--degradation", "exponential",
         "--fail", f"{fail:g}", "--calibrate", f"{demo.calibrate:g}", "--particles", str(demo.particles),
         "--seed", str(seed), "--out", str(out / "prognose")],
    ]
    code = 0
    for command in commands:
        print("$ bgphm " + " ".join(command))
        code = main(quiet + command)
        if code:
            return code
    summary = json.loads((out / "prognose" / "prognosis.json").read_text())
    if summary.get("detection_time") is not None:
        last = summary["last"]
        true_rul = truth["eol"] - last["t"]
        print(f"truth: at t = {last['t']:g} s the RUL is {true_rul:.3g} s and {demo.candidate} = "
              f"{demo.theta(nominal)(last['t']):.4g}")
    return code
