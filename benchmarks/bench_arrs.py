"""Scale benchmark: the ARRs and the fault signatures of an n-stage mass-spring-damper chain.

For each n, builds the chain (a velocity sensor on every mass), derives its ARRs
(``diagnosis.derive_arrs``: one per sensor junction, nominal and uncertain parts split
term by term) and the signature matrix.  Prints the times and the growth exponent (slope
of log time against log n).  Baseline, in the same process and on the same chain: the
state equations (``bg.state_equations()``), which the ARR route must stay within a small
factor of.

    python benchmarks/bench_arrs.py            # table
    python benchmarks/bench_arrs.py --json     # {"n": [...], "seconds": [...], "growth_exponent": ...}

Target: n = 200 in under 5 s, growth exponent under 1.3.  Beside them, the time of the HTML ARR report
(``diagnosis.report.arr_report``, what ``bgphm arr`` adds) over the derivation's (``report_over_derive``:
``bgphm arr`` within 2x of ``derive_arrs`` alone means under 1).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from sympy.core.cache import clear_cache

from bondgraph.library import mass_spring_chain
from diagnosis import derive_arrs, signature_matrix
from diagnosis.report import arr_report


def time_stages(n: int) -> dict:
    """Seconds spent building the chain, deriving its ARRs and their signature matrix.

    sympy's cache is cleared first, so that a size is not helped by the previous one.
    """
    clear_cache()
    start = time.perf_counter()
    bg = mass_spring_chain(n)
    built = time.perf_counter()
    arrs = derive_arrs(bg)
    derived = time.perf_counter()
    signatures = signature_matrix(arrs)
    signed = time.perf_counter()
    assert len(arrs) == n and signatures.matrix.shape[1] == n   # no fault the junction ARRs miss
    arr_report(bg, "html", arrs=arrs)  # what `bgphm arr` adds to the derivation (its signature table was cubic)
    reported = time.perf_counter()
    return {"build": built - start, "arrs": derived - built, "signatures": signed - derived, "total": signed - start,
            "report": reported - signed}


def state_equation_seconds(n: int) -> float:
    """Baseline: the state equations of the same chain (integral causality), from a clear cache."""
    bg = mass_spring_chain(n)
    clear_cache()
    start = time.perf_counter()
    bg.state_equations()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--sizes", type=int, nargs="+", default=[50, 200, 400])
    parser.add_argument("--repeat", type=int, default=1, help="best of this many runs per size")
    args = parser.parse_args()

    # warm sympy's caches so the first size is not charged for them; 16 stages have 64 fault candidates,
    # over diagnosis.elimination.ISOLATION_LIMIT like every size measured
    time_stages(16)
    rows = [min((time_stages(n) for _ in range(args.repeat)), key=lambda row: row["total"]) for n in args.sizes]
    seconds = [row["total"] for row in rows]
    slope = float(np.polyfit(np.log(args.sizes), np.log(seconds), 1)[0])
    baselines = [state_equation_seconds(n) for n in args.sizes]
    figures = {
        "n": args.sizes,
        "seconds": [round(s, 4) for s in seconds],
        "growth_exponent": round(slope, 3),
        "breakdown": [{k: round(v, 4) for k, v in row.items()} for row in rows],
        "baseline": {"state_equations_seconds": [round(b, 4) for b in baselines],
                     "ratio_to_state_equations": [round(s / b, 2) for s, b in zip(seconds, baselines)]},
        # issue 36: the report on top of the derivation, against the derivation alone (target: under 1)
        "report_over_derive": [round(row["report"] / row["arrs"], 2) for row in rows],
    }
    if args.json:
        print(json.dumps(figures))
        return
    print(f"{'n':>5} {'build':>8} {'arrs':>8} {'signatures':>11} {'total':>8} {'state eqs':>10} {'ratio':>6}")
    for n, row, base in zip(args.sizes, rows, baselines):
        print(f"{n:>5} {row['build']:>8.3f} {row['arrs']:>8.3f} {row['signatures']:>11.3f} {row['total']:>8.3f} "
              f"{base:>10.3f} {row['total'] / base:>6.1f}")
    print(f"growth exponent (log-log slope): {slope:.2f}")


if __name__ == "__main__":
    main()
