"""Speed of estimation and RUL prediction on the torsion-bar fault model (Jha et al. (2016), section 6.3).

b_Md degrades as b_Md,n exp(0.05 (t - 10)); the filter (N = 500, dt = 0.1 s)
runs 900 steps from t = 10 s to 100 s on y = (b_Md - b_Md,n)(-omega_m / k_belt^2)
+ noise (eq. 52-53, observation equation derived from the ARR), with a full
RUL prediction at every step.  In the same run, NASA's ProgPy (installed in
its own virtualenv, benchmarks/.venv-progpy, not a dependency of the toolkit)
filters the same model and predicts the RUL at a handful of points with its
Monte-Carlo predictor; the ratios compare the two.

Multi-hypothesis prognosis: the filter of
:class:`prognosis.isolation.IsolatingMonitor`, whose rows are hypotheses (candidate x law), runs on
the same b_Md data with H = 1, 2, 4, 6 hypotheses (b_Md, J_Md, b_Ld x exponential, linear; N = 500
particles each), a RUL prediction of every hypothesis every 10 steps.  Its times are given as ratios
to the single-hypothesis filter above, measured in the same process, and the cost of an extra
hypothesis is the slope of a least-squares line through time vs H.

    python benchmarks/bench_prognosis.py            # table
    python benchmarks/bench_prognosis.py --json     # {"total_s", "rul_speedup_vs_progpy",
                                                    #  "filter_step_ratio_vs_progpy", "hypotheses", ...}
    python benchmarks/bench_prognosis.py --no-progpy
    python benchmarks/bench_prognosis.py --hypotheses ""   # skip the multi-hypothesis sweep

Targets: whole run under 3 s on this 2-core machine (the RUL
predictions run in worker processes beside the filter: they are independent
given the particles, and keyed by step so the results equal the one-process
run, which is checked); RUL prediction >= 500x faster than ProgPy's per
prediction (measured in one process); filter step no slower than ProgPy's; a RUL prediction of one
hypothesis in the multi-hypothesis filter within 2x of the single-hypothesis
filter's.
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
from prognosis.degradation import ExponentialDegradation, PerAssetDegradation, degradation_model
from prognosis.hypotheses import Hypothesis, HypothesisObservation, rate_prior
from prognosis.particle_filter import KernelSmoothing, ParticleFilter, VarianceAdaptation
from prognosis.observation import observation_model
from prognosis.rul import ParallelRUL, RULPredictor

B_N, K_BELT, OMEGA_M, GAMMA_TRUE, SIGMA_W = 5.025e-3, 3.75, 112.5, 0.05, 0.01
# The hypotheses of the sweep, in the order they are added: the true one first, so H = 1 is the
# single-hypothesis problem.  Failure values: b_Md as above, J_Md and b_Ld as in the CLI's tests.
HYPOTHESES = [("b_Md", "exponential"), ("b_Md", "linear"), ("J_Md", "exponential"), ("J_Md", "linear"),
              ("b_Ld", "exponential"), ("b_Ld", "linear")]
FAILURES = {"b_Md": 0.45, "J_Md": 1.8e-3, "b_Ld": 2.5e-4}


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


def hypotheses(count: int, steps: int, particles: int, dt: float, seed: int, rul_every: int) -> dict:
    """Time the multi-hypothesis filter with the first ``count`` of :data:`HYPOTHESES` on the b_Md data.

    Built as :meth:`prognosis.isolation.IsolatingMonitor._filter` builds it: a
    :class:`~prognosis.degradation.PerAssetDegradation` with one law per row, a
    :class:`~prognosis.hypotheses.HypothesisObservation` predicting both residuals, measurements
    (H, M), rates from :func:`~prognosis.hypotheses.rate_prior`, kernel smoothing, and a
    :class:`~prognosis.rul.RULPredictor` per row predicting from that row alone with no random walk
    on the rate (the monitor's ``_mixture``).

    The ARRs are the junction ones of ``derive_arrs(complete=False, integrals="keep")``: ARR_1_1 is
    the one the single-hypothesis filter uses, and each candidate of the sweep is in exactly one of
    the two, so every hypothesis costs one residual function over N particles as the single filter
    does, and the ratio at H = 1 measures the filter's machinery, not a different residual (the
    default ARRs put b_Md, J_Md and b_Ld in two ARRs each, with second derivatives).  Both ARRs are
    used at every H, so the slope counts hypotheses only, not ARRs joining the sweep.

    Every hypothesis is predicted at each prediction (the monitor skips those below its mixture floor),
    so the RUL time is the cost of all H; the filter step time covers :meth:`ParticleFilter.step` only,
    as for the single filter.

    Parameters
    ----------
    count : int
        Number of hypotheses H (at most ``len(HYPOTHESES)``).
    steps, particles : int
        Filter steps; particles per hypothesis.
    dt : float
    seed : int
    rul_every : int
        Predict the RUL every this many steps (the monitor's default is 10).

    Returns
    -------
    dict
        ``filter_seconds_per_step``, ``rul_seconds_per_prediction`` (all H rows), ``rul_seconds_each``
        (per hypothesis), ``predictions``, and for consistency ``best`` (the hypothesis with the most
        evidence at the end) and ``final_estimate_b`` (b_Md/exponential's estimate).
    """
    arrs = [a for a in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")
            if a.junction in ("1_1", "1_2")]
    chosen = [Hypothesis(c, law, FAILURES[c], float(next(a.values[c] for a in arrs if c in a.parameters)))
              for c, law in HYPOTHESES[:count]]
    # sigma_v as the single filter's (1e-5 for b_Md), on the scale of each candidate
    models = tuple(degradation_model(h.law, 1e-5 * h.nominal / B_N) for h in chosen)
    observation = HypothesisObservation(arrs, chosen)
    pf = ParticleFilter(PerAssetDegradation(models, tuple(range(count))), observation, n_particles=particles, dt=dt,
                        noise_std=np.full(len(arrs), SIGMA_W), inflation=4.0, gamma_std=0.0,
                        adaptation=KernelSmoothing(0.98), seed=seed)
    predictors = [RULPredictor(m, dt=dt, theta_fail=h.failure, direction=h.direction, horizon=200.0,
                               seed=seed + 1 + row) for row, (m, h) in enumerate(zip(models, chosen))]
    # constant motor speed and the load at the belt's ratio: the data of the single filter for
    # ARR_1_1 (b_Md's term does not see omega_Ld), and b_Ld's term of ARR_1_2 is observed
    speeds = {"omega_m": OMEGA_M, "omega_Ld": OMEGA_M / K_BELT}
    points = [[speeds.get(str(p), 0.0) for p in a.compiled.points] for a in arrs]  # one value each: one sample
    t, first = measurements(steps, dt, seed)
    quiet = np.random.default_rng([seed, 2]).normal(0.0, SIGMA_W, steps)  # ARR_1_2 is blind to b_Md
    y = np.stack([first, quiet], axis=1)
    observation(np.full((count, 2), B_N), points)  # compile the residual functions outside the timing
    rng = np.random.default_rng([seed, 1])
    gamma0 = np.stack([rate_prior(h, dt, particles, rng) for h in chosen])[..., None]
    pf.initialize((np.array([h.nominal for h in chosen]), np.array([1.2 * h.nominal for h in chosen])),
                  gamma0=gamma0, assets=count)
    filter_time = rul_time = 0.0
    predictions = 0
    for k in range(steps):
        tick = time.perf_counter()
        pf.step(np.broadcast_to(y[k], (count, y.shape[1])), points)
        tock = time.perf_counter()
        filter_time += tock - tick
        if k % rul_every == 0:
            weights = pf.weights
            for row, predictor in enumerate(predictors):
                predictor.predict(pf.theta[row:row + 1], pf.gamma[row:row + 1], weights[row:row + 1], 0.0, key=k)
            rul_time += time.perf_counter() - tock
            predictions += 1
    return {"filter_seconds_per_step": filter_time / steps, "rul_seconds_per_prediction": rul_time / predictions,
            "rul_seconds_each": rul_time / predictions / count, "predictions": predictions,
            "best": chosen[int(np.argmax(pf.log_evidence))].name,
            "final_estimate_b": float(np.sum(pf.weights[0] * pf.theta[0]))}


def sweep(counts: list[int], single: dict, steps: int, particles: int, dt: float, seed: int, rul_every: int) -> dict:
    """The multi-hypothesis filter for each H in ``counts``, with ratios to the single filter ``single``.

    ``single`` is :func:`ours`'s result in this process (the baseline).  Slopes are least-squares
    fits of time vs H; ``*_ratio_vs_single`` divide by the single filter's time, ``*_ratio_vs_h1``
    by the multi-hypothesis filter's at H = 1 (when 1 is among ``counts``).  ``rul_ratio_vs_single``
    compares a prediction of all H hypotheses with one of the single filter;
    ``rul_one_hypothesis_ratio_vs_single`` is its value at H = 1, the multi-hypothesis filter's
    acceptance figure (target <= 2).
    """
    runs = [hypotheses(h, steps, particles, dt, seed, rul_every) for h in counts]
    step = np.array([r["filter_seconds_per_step"] for r in runs])
    rul = np.array([r["rul_seconds_per_prediction"] for r in runs])
    h = np.asarray(counts, float)
    out = {"counts": list(counts), "hypotheses": ["/".join(pair) for pair in HYPOTHESES[:max(counts)]],
           "arrs": ["ARR_1_1", "ARR_1_2"], "particles_per_hypothesis": particles, "rul_every": rul_every,
           "runs": runs}
    for name, times, base in (("filter_step", step, single["filter_seconds_per_step"]),
                              ("rul", rul, single["rul_seconds_each"])):
        out[f"{name}_ratio_vs_single"] = (times / base).tolist()
        if len(counts) > 1:
            slope = float(np.polyfit(h, times, 1)[0])
            out[f"{name}_seconds_per_extra_hypothesis"] = slope
            out[f"{name}_extra_hypothesis_ratio_vs_single"] = slope / base
            if 1 in counts:
                out[f"{name}_extra_hypothesis_ratio_vs_h1"] = slope / times[counts.index(1)]
    if 1 in counts:  # the multi-hypothesis filter's acceptance figure
        out["rul_one_hypothesis_ratio_vs_single"] = out["rul_ratio_vs_single"][counts.index(1)]
    return out


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
    parser.add_argument("--hypotheses", default="1,2,4,6",
                        help=f"numbers of hypotheses of the multi-hypothesis sweep (at most {len(HYPOTHESES)}; "
                             "empty: skip it)")
    parser.add_argument("--rul-every", type=int, default=10, help="multi-hypothesis RUL prediction interval (steps)")
    args = parser.parse_args()
    counts = [int(c) for c in args.hypotheses.split(",") if c.strip()]
    if any(not 1 <= c <= len(HYPOTHESES) for c in counts):
        parser.error(f"--hypotheses: each number between 1 and {len(HYPOTHESES)}, got {args.hypotheses!r}")

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
    if counts:  # after the single filter, in the same process: it is the baseline of the ratios
        figures["hypotheses"] = sweep(counts, single, args.steps, args.particles, 0.1, args.seed, args.rul_every)
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
    if "hypotheses" in figures:
        m = figures["hypotheses"]
        print(f"multi-hypothesis filter ({', '.join(m['hypotheses'])}), N = {m['particles_per_hypothesis']} per "
              f"hypothesis, ARRs {', '.join(m['arrs'])}, RUL of every hypothesis every {m['rul_every']} steps")
        print("      H  filter step (ms)  x single   RUL, all H (ms)  per hypothesis (ms)  x single   best")
        for h, run, step_ratio, rul_ratio in zip(m["counts"], m["runs"], m["filter_step_ratio_vs_single"],
                                                 m["rul_ratio_vs_single"]):
            print(f"  {h:5d}  {run['filter_seconds_per_step'] * 1e3:16.3f}  {step_ratio:8.2f}"
                  f"  {run['rul_seconds_per_prediction'] * 1e3:15.3f}  {run['rul_seconds_each'] * 1e3:19.3f}"
                  f"  {rul_ratio / h:8.2f}   {run['best']}")
        if "rul_one_hypothesis_ratio_vs_single" in m:
            print(f"  RUL prediction of one hypothesis / single filter's: {m['rul_one_hypothesis_ratio_vs_single']:.2f}"
                  " (target <= 2)")
        if "filter_step_seconds_per_extra_hypothesis" in m:
            print(f"  per extra hypothesis: filter step +{m['filter_step_seconds_per_extra_hypothesis'] * 1e3:.3f} ms "
                  f"({m['filter_step_extra_hypothesis_ratio_vs_single']:.2f} x single filter's step), RUL prediction "
                  f"+{m['rul_seconds_per_extra_hypothesis'] * 1e3:.3f} ms "
                  f"({m['rul_extra_hypothesis_ratio_vs_single']:.2f} x single filter's)")
        if "rul_extra_hypothesis_ratio_vs_h1" in m:
            print(f"  per extra hypothesis / H = 1: filter step {m['filter_step_extra_hypothesis_ratio_vs_h1']:.2f}, "
                  f"RUL prediction {m['rul_extra_hypothesis_ratio_vs_h1']:.2f}")


if __name__ == "__main__":
    main()
