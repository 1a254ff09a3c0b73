"""Generated residual code against the library: cost per sample and agreement, on three zoo models.

    python benchmarks/bench_codegen.py            # table
    python benchmarks/bench_codegen.py --json     # one JSON document
    python benchmarks/bench_codegen.py --samples 1000 rc_ladder2

Per model (rc_ladder2, orifice_tanks, loudspeaker: derivatives everywhere, a square-root orifice law, an
integral and a cubic spring), on its noisy step record from the independent reference simulator
(tests/zoo/reference.py), every ARR of the set is evaluated sample by sample, with the same dt, margin
and persistence:

* ``library_us``: :class:`diagnosis.StreamingEvaluation` fed one sample at a time (``push`` of a
  one-sample slice), on the first ``--samples`` samples;
* ``python_us``: the generated Python module (``ARRStream.push``), one sample at a time, same samples;
* ``c_us``: the generated C compiled with ``cc -O2 -std=c99 -ffp-contract=off``, the whole record pushed
  sample by sample by a loop inside C (``<module>_<ARR>_run``, one ctypes call per ARR and repeat), the
  best of ``--repeat`` runs.

Each figure is microseconds per sample for the whole ARR set (the sum over its ARRs).  ``speedup`` is
``library_us / c_us`` (target >= 100).  ``residual_rel``: the largest difference of a generated residual
(Python or C) from the library's, relative to the magnitude of its terms; ``bounds_rel``: the largest
relative difference of a bound; ``alarms_equal``: every alarm the same.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from diagnosis import StreamingEvaluation, derive_arrs, generate_code  # noqa: E402
from tests.diagnosis.generated_code import (CStream, compile_c, differences, library_run, load_python,  # noqa: E402
                                            python_run, write)
from tests.zoo.reference import record, simulate_reference  # noqa: E402

MODELS = ("rc_ladder2", "orifice_tanks", "loudspeaker")
OPTIONS = {"margin": 1e-6, "persistence": 3}


def bench(name: str, samples: int, repeat: int, folder: Path) -> dict:
    case = importlib.import_module(f"tests.zoo.models.{name}").CASE
    arrs = derive_arrs(case.build())
    data = record(simulate_reference(case, inputs="step"), noise=case.noise, seed=7)
    t, n = data["t"], data["t"].size
    write(generate_code(arrs, "python", dt=case.dt, name=name, **OPTIONS), folder)
    write(generate_code(arrs, "c", dt=case.dt, name=name, **OPTIONS), folder)
    python, (lib, _) = load_python(folder, name), compile_c(folder, name)
    m = min(samples, n)
    library_s = python_s = c_s = 0.0
    residual_rel = bounds_rel = 0.0
    alarms_equal = True
    for arr in arrs:
        stream = StreamingEvaluation(arr, dt=case.dt, **OPTIONS)
        columns = {c: data[c] for c in stream.columns}
        started = time.perf_counter()
        for k in range(m):
            stream.push(t[k:k + 1], {c: v[k:k + 1] for c, v in columns.items()})
        library_s += (time.perf_counter() - started) / m
        generated = python.ARRStream(arr.name)
        rows = [data[c] for c in generated.columns]
        started = time.perf_counter()
        for k in range(m):
            generated.push(t[k], [c[k] for c in rows])
        python_s += (time.perf_counter() - started) / m
        best = np.inf
        for _ in range(repeat):
            c_stream = CStream(lib, name, arr.name)
            started = time.perf_counter()
            got = c_stream.run(t, rows)
            best = min(best, time.perf_counter() - started)
        c_s += best / n
        reference = library_run(arr, data, dt=case.dt, **OPTIONS)
        for result in (got, python_run(python.ARRStream(arr.name), t, rows)):
            d = differences(arr, reference, result)
            residual_rel, bounds_rel = max(residual_rel, d["residual"]), max(bounds_rel, d["bounds"])
            alarms_equal &= d["alarms"].size == 0
    return {"model": name, "arrs": len(arrs), "samples": n, "timed_library_samples": m,
            "library_us": library_s * 1e6, "python_us": python_s * 1e6, "c_us": c_s * 1e6,
            "speedup": library_s / c_s, "python_speedup": library_s / python_s,
            "residual_rel": residual_rel, "bounds_rel": bounds_rel, "alarms_equal": bool(alarms_equal)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="*", default=list(MODELS), metavar="MODEL")
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.add_argument("--samples", type=int, default=2000, help="samples timed one by one (library, Python)")
    parser.add_argument("--repeat", type=int, default=5, help="C runs over the whole record, the best kept")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        rows = [bench(name, args.samples, args.repeat, Path(folder) / name) for name in args.models]
    if args.json:
        print(json.dumps({"benchmark": "codegen", "target_speedup": 100, "models": rows}, indent=1))
        return 0
    print(f"{'model':<15}{'ARRs':>5}{'library us':>12}{'Python us':>11}{'C us':>9}{'speed-up':>10}"
          f"{'residual':>11}{'bounds':>10}  alarms")
    for r in rows:
        print(f"{r['model']:<15}{r['arrs']:>5}{r['library_us']:>12.1f}{r['python_us']:>11.1f}{r['c_us']:>9.3f}"
              f"{r['speedup']:>10.0f}{r['residual_rel']:>11.1e}{r['bounds_rel']:>10.1e}  "
              f"{'equal' if r['alarms_equal'] else 'DIFFER'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
