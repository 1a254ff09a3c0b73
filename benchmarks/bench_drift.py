"""Drift benchmark: violation rates along a fault-free noisy record of an n-stage mass-spring-damper chain.

The junction ARRs of the chain hold the spring forces; written with integrals (Jha et al. (2016),
eq. 45 style, ``integrals="keep"``) they integrate the noisy measured speeds into a random walk, and
the residual leaves any band calibrated at the start of the record.  Written without them
(``integrals="avoid"``, the default: each balance differentiated once) the residual noise stays
stationary.  For each form: a 100 s record at 100 Hz (force ``1 + 0.5 sin(0.7 t)`` from rest, speed
noise 1e-3), a margin of 4 robust standard deviations of each ARR's residual on the first fifth, an
alarm after ``persistence`` consecutive violations; prints the violation rates of the first and last
fifths (pooled over the ARRs) and the alarms.

    python benchmarks/bench_drift.py            # table
    python benchmarks/bench_drift.py --json     # {"avoid": {...}, "keep": {...}}

Target: no alarm with the default form, last-fifth violation rate within 2x the first's.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from bondgraph import simulate
from bondgraph.library import mass_spring_chain
from diagnosis import add_noise, derive_arrs, robust_std

NOISE = 1e-3
SIGMAS = 4.0


def chain_record(n: int, seed: int, t_end: float = 100.0, samples: int = 10001):
    """A fault-free noisy record of the n-stage chain, driven from rest."""
    bg = mass_spring_chain(n)
    t = np.linspace(0.0, t_end, samples)
    clean = simulate(bg, (0.0, t_end), {"F": lambda s: 1.0 + 0.5 * np.sin(0.7 * s)}, t_eval=t).record()
    return bg, add_noise(clean, {f"v{i}": NOISE for i in range(1, n + 1)}, seed=seed)


def violation_rates(bg, record, integrals: str, persistence: int) -> dict:
    """First- and last-fifth violation rates over every ARR, with each ARR's margin from the first fifth."""
    fifth = len(record.t) // 5
    first = last = 0
    alarms = []
    arrs = derive_arrs(bg, integrals=integrals)
    for arr in arrs:
        residual = arr.evaluate(record).residual
        margin = SIGMAS * robust_std(residual[:fifth])
        result = arr.evaluate(record, margin=margin, persistence=persistence)
        first += int(result.violation[:fifth].sum())
        last += int(result.violation[-fifth:].sum())
        if result.detection_time is not None:
            alarms.append([arr.name, float(result.detection_time)])
    samples = fifth * len(arrs)
    return {"arrs": len(arrs), "first_fifth_rate": first / samples, "last_fifth_rate": last / samples,
            "ratio": (last / first) if first else (0.0 if not last else float("inf")), "alarms": alarms}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--stages", type=int, default=50)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--persistence", type=int, default=5)
    args = parser.parse_args()
    bg, record = chain_record(args.stages, args.seed)
    figures = {"stages": args.stages, "seed": args.seed, "persistence": args.persistence,
               **{form: violation_rates(bg, record, form, args.persistence) for form in ("avoid", "keep")}}
    if args.json:
        print(json.dumps(figures))
        return
    for form in ("avoid", "keep"):
        f = figures[form]
        print(f"{form:>6}: {f['arrs']} ARRs, violation rate first fifth {f['first_fifth_rate']:.2e}, last fifth "
              f"{f['last_fifth_rate']:.2e} (x{f['ratio']:.2f}), {len(f['alarms'])} alarm(s)")


if __name__ == "__main__":
    main()
