"""Our models in other tools, over the whole zoo: FMI (fmpy) and ProgPy agreement with our own figures.

    python benchmarks/bench_interop.py [--json] [--only fmi|progpy] [NAME ...]

Needs the ``fmi`` and ``progpy`` extras (and a C compiler for the FMUs).  Per zoo model (tests/zoo) and the
DC motor, with each input held at its smooth input's peak value (a constant, so that an FMU's inputs held over a
communication step are exact):

* ``fmi``: :func:`bondgraph.to_fmu` exports the model (C compiled here), fmpy runs it through
  :func:`bondgraph.simulate_fmu` on 201 samples of the case's horizon, and every output is compared with
  :func:`bondgraph.simulate` at rtol 1e-12, atol 1e-15: ``worst_rel`` is the largest difference relative to
  the signal's range; ``export_s`` the seconds the export takes (code generation and the compiler);
* ``progpy``: the case's first fault parameter (or its first parameter) degrades linearly, at a rate that
  doubles it over the horizon, and fails at 1.5 times its nominal value (half the horizon); ProgPy's
  ``simulate_to_threshold`` on :func:`prognosis.to_progpy` (rk4, 2000 steps to the failure) gives the failure
  time, compared with the law's closed form: ``time_rel``.

* ``progpy_filter`` (once, not per model): ProgPy's ``ParticleFilter`` (400 particles) and ``MonteCarlo``
  predictor (20 samples) on the DC motor exported by :func:`prognosis.to_progpy`, its friction wearing as
  ``b_n exp(0.8 (t - 1))``, from noisy ``i`` and ``omega`` (seed ``100 + s``) with the filter's own draws
  (numpy's global generator, seed ``1000 + s``), for ``--seeds`` seeds: the relative error of the mean ``b``
  and of the median RUL at t = 3.5 s, the rate's error, the CPU seconds.

A model a stage cannot handle is reported with its error, not left out.  Mean and worst over the models
(and over the seeds) are printed at the end (``summary``).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np
import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bondgraph import Degradation, simulate, simulate_fmu, to_fmu  # noqa: E402
from bondgraph.library import dc_motor  # noqa: E402
from prognosis import to_progpy  # noqa: E402
from tests.interop.progpy_wear import progpy_filter_run  # noqa: E402
from tests.zoo.chain import cases  # noqa: E402

SAMPLES = 201


def models() -> dict:
    """name -> (model builder, constant inputs, horizon, fault parameters)."""
    found = {"dc_motor": (dc_motor, {"U": 12.0}, 2.0, ("b",))}
    for case in cases():
        peaks = {name: _peak(expr, case.t_end) for name, expr in case.smooth_inputs.items()}
        found[case.name] = (case.build, peaks, case.t_end, case.faults)
    return found


def _peak(expression, horizon: float) -> float:
    """A smooth input's (a sympy expression of the time, or a number) value of largest magnitude over the horizon."""
    expression = sp.sympify(expression)
    values = [float(expression.subs({symbol: time for symbol in expression.free_symbols}))
              for time in np.linspace(0.0, horizon, 997)]   # a prime count: no grid on a sine's zeros
    return max(values, key=abs)


def fmi_row(build, inputs: dict, horizon: float) -> dict:
    bg = build()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "model.fmu"
        started = time.perf_counter()   # the compiler runs in a process of its own
        to_fmu(bg, path, inputs=inputs)
        export = time.perf_counter() - started
        t = np.linspace(0.0, horizon, SAMPLES)
        theirs = simulate_fmu(path, t, inputs)
    # the reference must be the tighter one: at atol 1e-12 a state of order 1e-5 (a charge) is only good to 1e-6
    ours = simulate(bg, (0.0, horizon), inputs, t_eval=t, rtol=1e-12, atol=1e-15)
    worst = 0.0
    for signal in bg.outputs:
        scale = max(float(np.ptp(ours[signal])), float(np.max(np.abs(ours[signal]))), 1e-300)
        worst = max(worst, float(np.max(np.abs(np.asarray(theirs[signal]) - ours[signal]))) / scale)
    return {"worst_rel": worst, "export_s": export, "outputs": len(bg.outputs)}


def progpy_row(build, inputs: dict, horizon: float, faults) -> dict:
    bg = build()
    parameter = next((f for f in faults if f in bg.parameters), next(iter(bg.parameters)))
    nominal = bg.parameters[parameter]
    law = Degradation("linear", nominal / horizon)
    failure, truth = 1.5 * nominal, 0.5 * horizon
    model = to_progpy(bg, degradation={parameter: law}, failures={parameter: failure})
    started = time.process_time()
    dt = truth / 2000
    result = model.simulate_to_threshold(lambda t, x=None: model.InputContainer(inputs), dt=dt, save_freq=truth)
    return {"parameter": parameter, "time_rel": abs(result.times[-1] - truth) / truth,
            "cpu_s": time.process_time() - started}


def progpy_filter_row(seed: int) -> dict:
    """ProgPy's particle filter and Monte Carlo predictor on the wearing motor, for one seed (see the module)."""
    started = time.process_time()
    run = progpy_filter_run(noise_seed=100 + seed, filter_seed=1000 + seed)
    return {"seed": seed, "b_rel": abs(run["b"] / run["b_true"] - 1.0), "rate_abs": abs(run["rate"] - run["rate_true"]),
            "rul_rel": abs(run["rul"] / run["rul_true"] - 1.0), "cpu_s": time.process_time() - started}


def guarded(function, *args) -> dict:
    try:
        return function(*args)
    except Exception as exc:  # reported, not hidden
        frame = traceback.extract_tb(exc.__traceback__)[-1]
        return {"error": f"{type(exc).__name__}: {exc}"[:300], "where": f"{Path(frame.filename).name}:{frame.lineno}"}


def summary(rows: list, stage: str, key: str) -> dict:
    values = [row[stage][key] for row in rows if stage in row and key in row[stage]]
    failed = [row["name"] for row in rows if stage in row and "error" in row[stage]]
    return {"models": len(values), "failed": failed, "mean": float(np.mean(values)) if values else None,
            "worst": float(np.max(values)) if values else None}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="models (default: all)")
    parser.add_argument("--only", choices=("fmi", "progpy", "progpy-filter"))
    parser.add_argument("--seeds", type=int, default=10, help="seeds of the progpy-filter stage (default 10)")
    parser.add_argument("--json", action="store_true", help="one JSON document")
    args = parser.parse_args(argv)
    available = models()
    unknown = sorted(set(args.names) - set(available))
    if unknown:
        parser.error(f"unknown model(s) {unknown}; known: {', '.join(available)}")
    rows = []
    for name in (args.names or list(available)) if args.only != "progpy-filter" else []:
        build, inputs, horizon, faults = available[name]
        row = {"name": name}
        if args.only in (None, "fmi"):
            row["fmi"] = guarded(fmi_row, build, inputs, horizon)
        if args.only in (None, "progpy"):
            row["progpy"] = guarded(progpy_row, build, inputs, horizon, faults)
        rows.append(row)
        if not args.json:
            print(json.dumps(row), flush=True)
    result = {"rows": rows, "summary": {"fmi_worst_rel": summary(rows, "fmi", "worst_rel"),
                                        "progpy_time_rel": summary(rows, "progpy", "time_rel")}}
    if args.only in (None, "progpy-filter"):
        seeds = [guarded(progpy_filter_row, seed) for seed in range(args.seeds)]
        result["progpy_filter"] = seeds
        result["summary"]["progpy_filter"] = {
            key: {"mean": float(np.mean([r[key] for r in seeds if key in r])),
                  "worst": float(np.max([r[key] for r in seeds if key in r]))}
            for key in ("b_rel", "rate_abs", "rul_rel") if any(key in r for r in seeds)}
        result["summary"]["progpy_filter"]["seeds"] = len(seeds)
        result["summary"]["progpy_filter"]["failed"] = [r.get("seed", k) for k, r in enumerate(seeds) if "error" in r]
    print(json.dumps(result if args.json else result["summary"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
