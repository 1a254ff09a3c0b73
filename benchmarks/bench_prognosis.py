"""Speed of estimation and RUL prediction on the torsion-bar fault model (Jha et al. (2016), section 6.3).

b_Md degrades as b_Md,n exp(0.05 (t - 10)); the filter (N = 500, dt = 0.1 s)
runs 900 steps from t = 10 s to 100 s on y = (b_Md - b_Md,n)(-omega_m / k_belt^2)
+ noise (eq. 52-53, observation equation derived from the ARR), with a full
RUL prediction at every step.  In the same run, NASA's ProgPy (installed in
its own virtualenv, benchmarks/.venv-progpy, not a dependency of the toolkit)
filters the same model and predicts the RUL at a handful of points with its
Monte-Carlo predictor; the ratios compare the two.

    python benchmarks/bench_prognosis.py            # table
    python benchmarks/bench_prognosis.py --json     # {"total_s", "rul_speedup_vs_progpy",
                                                    #  "filter_step_ratio_vs_progpy", ...}
    python benchmarks/bench_prognosis.py --no-progpy

Targets (issue 4): whole run under 3 s on this 2-core machine (the RUL
predictions run in worker processes beside the filter: they are independent
given the particles, and keyed by step so the results equal the one-process
run, which is checked); RUL prediction >= 500x faster than ProgPy's per
prediction (measured in one process); filter step no slower than ProgPy's.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from bondgraph.library import torsion_bar_monitorable
from diagnosis import derive_arrs
from prognosis.degradation import ExponentialDegradation
from prognosis.particle_filter import ParticleFilter, VarianceAdaptation
from prognosis.observation import observation_model
from prognosis.rul import ParallelRUL, RULPredictor

B_N, K_BELT, OMEGA_M, GAMMA_TRUE, SIGMA_W = 5.025e-3, 3.75, 112.5, 0.05, 0.01


def measurements(steps: int, dt: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    t = 10.0 + dt * np.arange(1, steps + 1)
    truth = B_N * np.exp(GAMMA_TRUE * (t - 10.0))
    y = (truth - B_N) * (-OMEGA_M / K_BELT**2) + np.random.default_rng(seed).normal(0.0, SIGMA_W, t.size)
    return t, y


def ours(steps: int, particles: int, dt: float, seed: int, workers: int = 1) -> dict:
    arr = next(a for a in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")
               if a.junction == "1_1")
    observation = observation_model(arr, "b_Md")
    compiled = arr.compiled
    points = [np.array([OMEGA_M if str(p) == "omega_m" else 0.0]) for p in compiled.points]
    model = ExponentialDegradation(process_noise=1e-5)
    pf = ParticleFilter(model, observation, n_particles=particles, dt=dt, noise_std=SIGMA_W, inflation=4.0,
                        gamma_std=0.02, adaptation=VarianceAdaptation(band=(0.03, 0.07), reference=0.10, gain=0.001),
                        seed=seed)
    predictor = RULPredictor(model, dt=dt, theta_fail=0.45, horizon=200.0, seed=seed + 1)
    t, y = measurements(steps, dt, seed)
    observation(np.full((1, 2), B_N), points)  # compile the observation function outside the timing
    start = time.perf_counter()  # the total includes drawing the predictor's noise bank
    pf.initialize((B_N, B_N * 1.2))
    filter_time = rul_time = 0.0
    ruls = []
    if workers > 1:  # predictions in worker processes, overlapping with the filter
        with ParallelRUL(model, workers=workers, dt=dt, theta_fail=0.45, horizon=200.0, seed=seed + 1) as pool:
            futures = []
            for k in range(steps):
                tick = time.perf_counter()
                pf.step(y[k:k + 1], points)
                filter_time += time.perf_counter() - tick
                futures.append(pool.submit(pf.theta, pf.gamma, pf.weights, np.sqrt(pf.variance), key=k))
            ruls = [float(f.result().mean[0]) for f in futures]
        rul_time = float("nan")
    else:
        for k in range(steps):
            tick = time.perf_counter()
            pf.step(y[k:k + 1], points)
            tock = time.perf_counter()
            prediction = predictor.predict(pf.theta, pf.gamma, pf.weights, np.sqrt(pf.variance), key=k)
            rul_time += time.perf_counter() - tock
            filter_time += tock - tick
            ruls.append(float(prediction.mean[0]))
    total = time.perf_counter() - start
    return {"total_s": total, "filter_seconds_per_step": filter_time / steps, "rul_seconds_each": rul_time / steps,
            "final_estimate_b": float(np.sum(pf.weights * pf.theta)),
            "rul_at_50s": ruls[int(round((50 - 10) / dt)) - 1],
            "true_rul_at_50s": 100.0 - 50.0, "ruls": ruls}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--steps", type=int, default=900)
    parser.add_argument("--particles", type=int, default=500)
    parser.add_argument("--predictions", type=int, default=3, help="ProgPy prediction points")
    parser.add_argument("--no-progpy", action="store_true", help="skip the ProgPy baseline")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2,
                        help="processes for the RUL predictions (this machine: 2 cores)")
    args = parser.parse_args()

    # per-prediction time in one process (for the ratio to ProgPy), whole run with the prediction workers
    single = ours(args.steps, args.particles, 0.1, args.seed, workers=1)
    parallel = ours(args.steps, args.particles, 0.1, args.seed, workers=args.workers)
    if not np.allclose(single.pop("ruls"), parallel.pop("ruls"), equal_nan=True):
        raise SystemExit("RUL predictions differ between one process and the workers")
    figures = {**single, "total_s_one_process": single["total_s"], "total_s": parallel["total_s"],
               "workers": args.workers}
    if not args.no_progpy:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from progpy_baseline import run_baseline

        baseline = run_baseline(steps=args.steps, predictions=args.predictions, particles=args.particles)
        figures["progpy"] = baseline
        figures["rul_speedup_vs_progpy"] = baseline["prediction_seconds_each"] / figures["rul_seconds_each"]
        step_ratio = figures["filter_seconds_per_step"] / baseline["filter_seconds_per_step"]
        figures["filter_step_ratio_vs_progpy"] = step_ratio
    if args.json:
        print(json.dumps(figures))
        return
    print(f"torsion-bar fault model, N = {args.particles}, {args.steps} filter steps, RUL at every step")
    print(f"  whole run: {figures['total_s']:.2f} s with {args.workers} prediction worker(s) (target < 3 s); "
          f"{figures['total_s_one_process']:.2f} s in one process")
    print(f"  filter step: {figures['filter_seconds_per_step'] * 1e3:.3f} ms; RUL prediction: "
          f"{figures['rul_seconds_each'] * 1e3:.3f} ms each")
    print(f"  final b_Md estimate {figures['final_estimate_b']:.4f} (true 0.452); RUL at t = 50 s: "
          f"{figures['rul_at_50s']:.1f} s (true 50)")
    if "progpy" in figures:
        p = figures["progpy"]
        print(f"  ProgPy {p['progpy_version']}: filter step {p['filter_seconds_per_step'] * 1e3:.3f} ms, "
              f"prediction {p['prediction_seconds_each']:.2f} s each")
        print(f"  RUL prediction speed-up vs ProgPy: {figures['rul_speedup_vs_progpy']:.0f}x (target >= 500x); "
              f"filter step ours/ProgPy: {figures['filter_step_ratio_vs_progpy']:.2f} (target <= 1)")


if __name__ == "__main__":
    main()
