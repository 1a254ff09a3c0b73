"""Throughput of residual and threshold evaluation on the torsion-bar ARR (Jha et al. (2016), eqs. 48-49).

Evaluates ARR_1_1 of the torsion bar's monitorable part over a record of
10^6 samples: nominal residual r_n (with Savitzky-Golay derivatives and the
cumulative integral of the shaft twist) and the interval threshold
[B_lo, B_hi] of Psi_2, all vectorized.  Baseline, in the same process: the
same interval range computed sample by sample with mpmath's ``iv`` context on
a subsample, extrapolated per sample.

    python benchmarks/bench_thresholds.py            # table
    python benchmarks/bench_thresholds.py --json     # {"samples_per_second": ..., "speedup_vs_mpmath": ...}

Target: >= 10^6 samples per second.
"""

from __future__ import annotations

import argparse
import json
import time

import mpmath
import numpy as np
import sympy as sp

from bondgraph.library import torsion_bar_monitorable
from diagnosis import derive_arrs
from diagnosis.residuals import read_record
from diagnosis.thresholds import interval_threshold


def synthetic_record(n: int, dt: float = 1e-3) -> dict:
    """Smooth torsion-bar-like signals: speeds near 112.5 and 30 rad/s, a motor torque."""
    t = np.arange(n) * dt
    omega_m = 112.5 * (1 - np.exp(-t / 0.2)) + 0.5 * np.sin(3.0 * t)
    omega_ld = omega_m / 3.75 - 0.01 * np.sin(40.0 * t) * np.exp(-t)
    tau_m = 0.02 + 0.005 * np.cos(3.0 * t)
    return {"t": t, "omega_m": omega_m, "omega_Ld": omega_ld, "tau_m": tau_m}


def mpmath_seconds_per_sample(compiled, points, samples: int) -> float:
    """Interval range of Psi_2 sample by sample with mpmath.iv (a scalar interval library)."""
    deltas = {sp.Symbol(f"delta_{p}"): mpmath.iv.mpf(list(box)) for p, box in compiled.arr.uncertainties.items()}
    function = sp.lambdify([*compiled.points, *deltas], compiled.uncertain, modules=[{"Abs": abs}, mpmath.iv])
    index = np.linspace(0, points[0].size - 1, samples).astype(int)
    start = time.perf_counter()
    for k in index:
        function(*[mpmath.iv.mpf(float(p[k])) for p in points], *deltas.values())
    return (time.perf_counter() - start) / samples


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--baseline-samples", type=int, default=2000)
    args = parser.parse_args()

    arr = {a.junction: a for a in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")}["1_1"]
    record = synthetic_record(args.samples)
    arr.evaluate(synthetic_record(1000))  # compile once, outside the timing

    start = time.perf_counter()
    arr.evaluate(record)  # synthetic signals are not a physical trajectory: only the time counts
    total = time.perf_counter() - start

    compiled = arr.compiled
    points = compiled.point_values(read_record(arr, record))
    start = time.perf_counter()
    interval_threshold(compiled, points)
    threshold_only = time.perf_counter() - start
    baseline = mpmath_seconds_per_sample(compiled, points, args.baseline_samples)

    figures = {
        "samples": args.samples,
        "seconds": round(total, 4),
        "samples_per_second": round(args.samples / total),
        "threshold_seconds": round(threshold_only, 4),
        "threshold_samples_per_second": round(args.samples / threshold_only),
        "mpmath_seconds_per_sample": baseline,
        "speedup_vs_mpmath": round(baseline * args.samples / threshold_only, 1),
        "speedup_vs_mpmath_end_to_end": round(baseline * args.samples / total, 1),
    }
    if args.json:
        print(json.dumps(figures))
        return
    print(f"ARR_1_1 of the torsion bar over {args.samples:,} samples")
    print(f"  residual + derivatives + integral + interval and BG-LFT thresholds: {total:.3f} s "
          f"({figures['samples_per_second']:,.0f} samples/s)")
    rate = figures["threshold_samples_per_second"]
    print(f"  interval threshold alone: {threshold_only:.3f} s ({rate:,.0f} samples/s)")
    print(f"  mpmath.iv scalar loop: {baseline * 1e6:.1f} us per sample (on {args.baseline_samples} samples)")
    print(f"  speed-up vs mpmath: {figures['speedup_vs_mpmath']:,.0f}x (threshold), "
          f"{figures['speedup_vs_mpmath_end_to_end']:,.0f}x (end to end)")


if __name__ == "__main__":
    main()
