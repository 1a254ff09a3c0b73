"""Throughput of a compiled interval function (diagnosis.intervals.compile_interval) on 10^6 samples.

The expression is the uncertain part of an ARR with four multiplicative uncertainties on three point
signals, ``-(d1 a x1 + d2 b x2 + (d3 c x1 + d4 d x3) / 3.75)``, the case tests/diagnosis/intervals
checks for soundness.  Baseline, in the same process: the point value of the same expression at the
box's midpoint, lambdified with numpy (what a threshold without intervals would cost).  Best of
``--repeat`` runs each, after one warm-up call.

    python benchmarks/bench_intervals.py            # table
    python benchmarks/bench_intervals.py --json     # {"seconds": ..., "ratio_vs_point": ..., ...}

Target (moved here from the test suite): 10^6 samples in under 1 s.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import sympy as sp

from diagnosis.intervals import compile_interval


def best_of(function, arguments, repeat: int) -> float:
    function(*arguments)  # warm-up: compilation caches, page faults
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        function(*arguments)
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    x1, x2, x3 = sp.symbols("x1 x2 x3")
    d1, d2, d3, d4 = sp.symbols("delta_1 delta_2 delta_3 delta_4")
    a, b, c, d = 0.5, 1.3, 2.7, 0.01
    expr = -(d1 * a * x1 + d2 * b * x2 + (d3 * c * x1 + d4 * d * x3) / 3.75)
    box = {d1: (-0.05, 0.05), d2: (0.0, 0.2), d3: (-0.1, 0.1), d4: (-0.02, 0.03)}
    samples = [np.random.default_rng(i).standard_normal(args.samples) for i in range(3)]

    interval = best_of(compile_interval(expr, [x1, x2, x3], box), samples, args.repeat)
    point = sp.lambdify([x1, x2, x3], expr.subs({s: (lo + hi) / 2 for s, (lo, hi) in box.items()}), "numpy")
    baseline = best_of(point, samples, args.repeat)

    figures = {
        "samples": args.samples,
        "seconds": round(interval, 4),
        "samples_per_second": round(args.samples / interval),
        "point_seconds": round(baseline, 4),
        "ratio_vs_point": round(interval / baseline, 1),
        "target_seconds_per_million": 1.0,
        "meets_target": interval * 1e6 / args.samples < 1.0,
    }
    if args.json:
        print(json.dumps(figures))
        return
    print(f"compiled interval function, 3 signals and 4 uncertainties, {args.samples:,} samples")
    print(f"  interval enclosure: {interval:.3f} s ({figures['samples_per_second']:,.0f} samples/s)")
    print(f"  point value at the box midpoint (numpy lambdify): {baseline:.3f} s")
    print(f"  interval / point: {figures['ratio_vs_point']}x; target 10^6 samples < 1 s: "
          f"{'met' if figures['meets_target'] else 'NOT met'}")


if __name__ == "__main__":
    main()
