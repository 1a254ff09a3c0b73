"""Scale benchmark: the ARRs and the fault signatures of an n-stage mass-spring-damper chain or RC ladder.

For each n, builds the chain (a velocity sensor on every mass; ``--model ladder``: an RC ladder, a voltage
sensor on every capacitor, whose ARRs come from the minimal-set search, not the junctions), derives its ARRs
(``diagnosis.derive_arrs``: one per sensor junction, nominal and uncertain parts split
term by term) and the signature matrix.  Prints the times and the growth exponent (slope
of log time against log n).  Baseline, in the same process and on the same chain: the
state equations (``bg.state_equations()``), which the ARR route must stay within a small
factor of.

    python benchmarks/bench_arrs.py            # table
    python benchmarks/bench_arrs.py --json     # {"n": [...], "seconds": [...], "growth_exponent": ...}
    python benchmarks/bench_arrs.py --model ladder --sizes 50 200

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

from bondgraph import BondGraph
from bondgraph.library import mass_spring_chain
from diagnosis import derive_arrs, signature_matrix
from diagnosis.report import arr_report


def rc_ladder(n: int) -> BondGraph:
    """``n`` RC sections, ``U -> 1_i (R_i) -> 0_i (C_i, De v_i) -> 1_(i+1) ...``: every capacitor's voltage
    measured, no current."""
    bg = BondGraph(name=f"{n}-section RC ladder")
    bg.add("U", "Se", unit="V")
    previous = "U"
    for i in range(1, n + 1):
        bg.add(f"1_{i}", "1")
        bg.add(f"R{i}", "R", value=100.0, uncertainty=(-0.05, 0.05), unit="Ohm")
        bg.add(f"0_{i}", "0")
        bg.add(f"C{i}", "C", value=1e-3, uncertainty=(-0.1, 0.1), unit="F")
        bg.add(f"v{i}", "De", unit="V")
        for tail, head in [(previous, f"1_{i}"), (f"1_{i}", f"R{i}"), (f"1_{i}", f"0_{i}"), (f"0_{i}", f"C{i}"),
                           (f"0_{i}", f"v{i}")]:
            bg.bond(tail, head)
        previous = f"0_{i}"
    return bg


#: The models measured (``--model``).
MODELS = {"chain": mass_spring_chain, "ladder": rc_ladder}


def time_stages(n: int, build=mass_spring_chain) -> dict:
    """Seconds spent building the chain, deriving its ARRs and their signature matrix.

    sympy's cache is cleared first, so that a size is not helped by the previous one.
    """
    clear_cache()
    start = time.perf_counter()
    bg = build(n)
    built = time.perf_counter()
    arrs = derive_arrs(bg)
    derived = time.perf_counter()
    signatures = signature_matrix(arrs)
    signed = time.perf_counter()
    assert signatures.detectable.all(), "a fault no ARR sees"
    arr_report(bg, "html", arrs=arrs)  # what `bgphm arr` adds to the derivation (its signature table was cubic)
    reported = time.perf_counter()
    return {"build": built - start, "arrs": derived - built, "signatures": signed - derived, "total": signed - start,
            "report": reported - signed}


def state_equation_seconds(n: int, build=mass_spring_chain) -> float:
    """Baseline: the state equations of the same model (integral causality), from a clear cache."""
    bg = build(n)
    clear_cache()
    start = time.perf_counter()
    bg.state_equations()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--sizes", type=int, nargs="+", default=[50, 200, 400])
    parser.add_argument("--repeat", type=int, default=1, help="best of this many runs per size")
    parser.add_argument("--model", choices=sorted(MODELS), default="chain")
    args = parser.parse_args()
    build = MODELS[args.model]

    # warm sympy's caches so the first size is not charged for them; 16 stages have 64 fault candidates,
    # over diagnosis.elimination.ISOLATION_LIMIT like every size measured
    time_stages(16, build)
    rows = [min((time_stages(n, build) for _ in range(args.repeat)), key=lambda row: row["total"])
            for n in args.sizes]
    seconds = [row["total"] for row in rows]
    slope = float(np.polyfit(np.log(args.sizes), np.log(seconds), 1)[0])
    baselines = [state_equation_seconds(n, build) for n in args.sizes]
    figures = {
        "model": args.model,
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
