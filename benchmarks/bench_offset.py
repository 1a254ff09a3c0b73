"""Would a slowly wandering offset in the likelihood calibrate the torsion-bar demo's RUL band?

The resample-move filter's band on ``bgphm demo torsion-bar`` is too narrow: the residual of
ARR_1_2 (the integral form of Jha et al. (2016)) carries, besides its white noise, an offset that
wanders over tens of seconds (the twist integral's drift), which a white likelihood reads as wear.
This script computes the exact posterior of the exponential law's two unknowns, theta at the alarm
and the rate, on a grid (no filter, no sampling), from the demo's record at one filter step per
0.1 s, under a likelihood of white noise (q = 0) and of white noise plus a random-walk offset of
sd ``q`` per filter step (a Kalman filter per grid point), and prints per seed, q and time the RUL
median and 5-95 % band against the true RUL (one JSON line each, then a summary line).

Nothing comes from the truth but the scoring: the white noise is measured on the healthy stretch
(t < 9.5 s), the nominal value is the model file's, the grid is re-centred on each likelihood's own
posterior mean, and the q values are a fixed sweep.

    python benchmarks/bench_offset.py                 # seeds 0-2, q = 0, 1e-5, 3e-5
    python benchmarks/bench_offset.py --seeds 5 --q 0 1e-5
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
from pathlib import Path

import numpy as np

from bgphm.demo_cases import prepare_demo
from bondgraph.io import load_model
from diagnosis import derive_arrs
from diagnosis.csv_reading import read_csv
from prognosis.weighted import weighted_quantiles

HEALTHY = (1.0, 9.5)   # s: the demo's --calibrate stretch (after the start-up second)
STEP = 100             # samples per filter step (0.1 s at 1 kHz, the demo's --dt)
TIMES = (50.0, 70.0, 89.3)
GRID = 201


def residual(out: Path):
    """t, r_n of ARR_1_2 and omega_Ld at every sample of the demo's record, and b_Ld's nominal value."""
    model = load_model(out / "model.py").model
    arr = next(a for a in derive_arrs(model, integrals="keep") if a.name == "ARR_1_2")
    evaluation = arr.evaluate(read_csv(out / "data.csv"), margin=1.0)
    names = [str(p) for p in arr.compiled.points]
    speed = evaluation.points[names.index("omega_Ld")]
    return (np.asarray(evaluation.t), np.asarray(evaluation.residual), np.asarray(speed),
            float(model.parameters["b_Ld"]))


def log_likelihood(theta0, rate, t, y, w, start, nominal, sd, q):
    """log p(y) over the grid (theta0 (P, 1), rate (1, R)): y = (theta0 e^(rate (t - start)) - nominal) w + b + e."""
    total = np.zeros(np.broadcast_shapes(theta0.shape, rate.shape))
    offset = np.zeros_like(total)
    variance = (3 * q) ** 2   # the offset at the alarm: a few steps' worth of its walk
    for tk, yk, wk in zip(t, y, w):
        predicted = (theta0 * np.exp(rate * (tk - start)) - nominal) * wk
        variance += q * q
        spread = variance + sd * sd
        gap = yk - predicted - offset
        total += -0.5 * (gap * gap / spread + np.log(spread))
        gain = variance / spread
        offset = offset + gain * gap
        variance *= 1 - gain
    return total


def posterior_rul(t, y, w, start, nominal, fail, sd, q, until):
    """RUL 5, 50, 95 % at ``until`` from the grid posterior, the grid refined twice about its mean."""
    keep = t <= until
    t, y, w = t[keep], y[keep], w[keep]
    # start: theta at the alarm from the first residuals, the rate over two decades
    first = float(np.median(y[:20] / w[:20])) + nominal
    theta_span, rate_span = (0.5 * first, 1.5 * first), (1e-3, 1.0)
    for _ in range(3):
        theta0 = np.linspace(*theta_span, GRID)[:, None]
        rate = np.linspace(*rate_span, GRID)[None, :]
        ll = log_likelihood(theta0, rate, t, y, w, start, nominal, sd, q)
        p = np.exp(ll - ll.max())
        p /= p.sum()
        # the next grid: ten posterior sd about the mean (at least two cells of this one)
        mt, mr = float(np.sum(p * theta0)), float(np.sum(p * rate))
        st = max(float(np.sqrt(np.sum(p * (theta0 - mt) ** 2))), 2 * (theta_span[1] - theta_span[0]) / GRID)
        sr = max(float(np.sqrt(np.sum(p * (rate - mr) ** 2))), 2 * (rate_span[1] - rate_span[0]) / GRID)
        theta_span, rate_span = (mt - 10 * st, mt + 10 * st), (max(mr - 10 * sr, 1e-6), mr + 10 * sr)
    now = theta0 * np.exp(rate * (until - start))
    with np.errstate(divide="ignore", invalid="ignore"):
        rul = np.where(now < fail, np.log(fail / now) / rate, 0.0)
    return weighted_quantiles(rul.ravel(), p.ravel(), (0.05, 0.5, 0.95)).tolist()


def run(seed: int, qs, alarm: float) -> list[dict]:
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        with contextlib.redirect_stdout(io.StringIO()):  # its "wrote ..." line: only JSON on stdout
            plan = prepare_demo("torsion-bar", out, progress=lambda line: None, seed=seed)
        t, r, w, nominal = residual(out)
    truth = plan.truth
    sd = float(np.std(r[(t > HEALTHY[0]) & (t < HEALTHY[1])][::STEP]))
    k = np.flatnonzero(t >= alarm)[::STEP]
    rows = []
    for q in qs:
        for until in TIMES:
            lo, median, hi = posterior_rul(t[k], r[k], w[k], alarm, nominal, truth["failure_value"], sd, q,
                                           until)
            true = truth["eol"] - until
            rows.append({"seed": seed, "q": q, "t": until, "true_rul": true, "median": median, "p5": lo, "p95": hi,
                         "covered": lo <= true <= hi, "median_error": (median - true) / true})
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--q", type=float, nargs="+", default=[0.0, 1e-5, 3e-5])
    parser.add_argument("--alarm", type=float, default=31.3, help="filter start (s): the demo's alarm at seed 0")
    args = parser.parse_args(argv)
    rows = [row for seed in range(args.seeds) for row in run(seed, args.q, args.alarm)]
    for row in rows:
        print(json.dumps(row))
    summary = {str(q): {"coverage_90": float(np.mean([r["covered"] for r in rows if r["q"] == q])),
                        "median_error_mean": float(np.mean([abs(r["median_error"]) for r in rows if r["q"] == q])),
                        "median_error_worst": float(np.max([abs(r["median_error"]) for r in rows if r["q"] == q])),
                        "band_width_mean": float(np.mean([(r["p95"] - r["p5"]) / r["true_rul"]
                                                          for r in rows if r["q"] == q]))}
               for q in args.q}
    print(json.dumps({"summary": summary, "seeds": args.seeds, "times": TIMES}))


if __name__ == "__main__":
    main()
