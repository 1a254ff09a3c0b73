"""Scale benchmark: the ARRs and the fault signatures of an n-stage mass-spring-damper chain or RC ladder.

For each n, builds the chain (a velocity sensor on every mass; ``--model ladder``: an RC ladder, a voltage
sensor on every capacitor, whose ARRs come from the minimal-set search, not the junctions; ``--model cascade``:
n gravity-drained tanks in series with orifice (square-root) laws, a level sensor on every tank;
``--model cascade_sparse``: the same with a level sensor on every other tank, whose ARRs must invert orifice
laws to reach the unmeasured levels), derives its ARRs (``diagnosis.derive_arrs``, isolation on as by
default, ``--max-order`` passed on) and the signature matrix.  Prints CPU seconds (mean over ``--repeat``
runs, and the worst) and the growth exponent (slope of log time against log n).  Baseline, in the same
process and on the same model: the state equations (``bg.state_equations()``).

    python benchmarks/bench_arrs.py            # table
    python benchmarks/bench_arrs.py --json     # {"n": [...], "cpu_seconds": [...], "growth_exponent": ...}
    python benchmarks/bench_arrs.py --sizes 200 --max-order none --pairs   # every isolable pair reached?
    python benchmarks/bench_arrs.py --model ladder --sizes 50 200
    python benchmarks/bench_arrs.py --model cascade_sparse --sizes 5 10 20 50
    python benchmarks/bench_arrs.py --model cascade_sparse --sizes 10 --pairs --simulated   # simulation residuals

Every fault must be seen by an ARR: the table (or JSON) is printed with the count of those no ARR sees, and
the run then exits with an error naming them if there are any.  ``--pairs`` adds the structurally isolable
ordered pairs (every minimal set) and those the ARRs leave (``diagnosis.elimination.unreached``).

Targets (issue 36): a 200-stage chain with isolation on and ``--max-order none`` reaches every structurally
isolable pair in under 60 s; the HTML ARR report (``diagnosis.report.arr_report``, what ``bgphm arr`` adds)
over the derivation (``report_over_derive``: ``bgphm arr`` within 2x of ``derive_arrs`` alone means under 1).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from sympy.core.cache import clear_cache

from bondgraph import BondGraph
from bondgraph.library import mass_spring_chain, tank_cascade
from diagnosis import derive_arrs, signature_matrix
from diagnosis.elimination import unreached
from diagnosis.report import arr_report
from diagnosis.structural import structural_model


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


def sparse_tank_cascade(n: int) -> BondGraph:
    """:func:`tank_cascade` with a level sensor on every other tank (and the last): the hard case."""
    return tank_cascade(n, every=2)


#: The models measured (``--model``).
MODELS = {"chain": mass_spring_chain, "ladder": rc_ladder, "cascade": tank_cascade,
          "cascade_sparse": sparse_tank_cascade}


def time_stages(n: int, build=mass_spring_chain, max_order="auto", pairs: bool = False,
                simulated: bool = False) -> dict:
    """CPU seconds spent building the model, deriving its ARRs (isolation on, the default) and their signature
    matrix, and the HTML report on top; with ``pairs``, the structurally isolable ordered pairs and those the
    ARRs leave (not timed).

    sympy's cache is cleared first, so that a size is not helped by the previous one.
    """
    clear_cache()
    start = time.process_time()
    bg = build(n)
    built = time.process_time()
    arrs = derive_arrs(bg, max_order=max_order, simulated=simulated)
    derived = time.process_time()
    signatures = signature_matrix(arrs)
    signed = time.process_time()
    arr_report(bg, "html", arrs=arrs)  # what `bgphm arr` adds to the derivation (its signature table was cubic)
    reported = time.process_time()
    row = {"build": built - start, "arrs": derived - built, "signatures": signed - derived, "total": signed - start,
           "report": reported - signed, "count": len(arrs), "simulated": sum(a.form == "simulation" for a in arrs),
           "undetected": [fault for fault, seen in zip(signatures.rows, signatures.detectable) if not seen]}
    if pairs:
        row["structural_pairs"] = sum(len(v) for v in structural_model(bg).isolability().values())
        row["unreached_pairs"] = len(unreached(bg, arrs)["isolate"])
    return row


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
    parser.add_argument("--sizes", type=int, nargs="+", default=[50, 200])
    parser.add_argument("--repeat", type=int, default=1, help="runs per size: the mean and the worst are reported")
    parser.add_argument("--model", choices=sorted(MODELS), default="chain")
    parser.add_argument("--max-order", default="auto",
                        help="derive_arrs' max_order: 'auto' (default), 'none' (no bound) or an integer")
    parser.add_argument("--pairs", action="store_true",
                        help="count the structurally isolable ordered pairs and those left (slow on large models)")
    parser.add_argument("--simulated", action="store_true",
                        help="derive_arrs(simulated=True): simulation residuals where no closed form is kept")
    args = parser.parse_args()
    build = MODELS[args.model]
    max_order = {"auto": "auto", "none": None}.get(args.max_order.lower(), None)
    if args.max_order.lower() not in ("auto", "none"):
        max_order = int(args.max_order)

    time_stages(4, build)   # warm sympy's caches so the first size is not charged for them
    runs = [[time_stages(n, build, max_order, args.pairs, args.simulated) for _ in range(args.repeat)]
            for n in args.sizes]
    rows = [{**r[-1], **{k: float(np.mean([x[k] for x in r])) for k in ("build", "arrs", "signatures", "total",
                                                                           "report")}} for r in runs]
    seconds = [row["total"] for row in rows]
    slope = float(np.polyfit(np.log(args.sizes), np.log(seconds), 1)[0]) if len(args.sizes) > 1 else None
    baselines = [state_equation_seconds(n, build) for n in args.sizes]
    figures = {
        "model": args.model,
        "max_order": args.max_order,
        "simulated": args.simulated,
        "n": args.sizes,
        "cpu_seconds": [round(s, 4) for s in seconds],
        "cpu_seconds_worst": [round(max(x["total"] for x in r), 4) for r in runs],
        "growth_exponent": None if slope is None else round(slope, 3),
        "breakdown": [{k: round(row[k], 4) for k in ("build", "arrs", "signatures", "total", "report")}
                      for row in rows],
        "arrs": [row["count"] for row in rows],
        "simulation_arrs": [row["simulated"] for row in rows],
        "undetected": [row["undetected"] for row in rows],   # faults no ARR sees: the run fails on any
        "baseline": {"state_equations_seconds": [round(b, 4) for b in baselines],
                     "ratio_to_state_equations": [round(s / b, 2) for s, b in zip(seconds, baselines)]},
        # issue 36: the report on top of the derivation, against the derivation alone (target: under 1)
        "report_over_derive": [round(row["report"] / row["arrs"], 2) for row in rows],
    }
    if args.pairs:
        figures["structural_pairs"] = [row["structural_pairs"] for row in rows]
        figures["unreached_pairs"] = [row["unreached_pairs"] for row in rows]
    missed = {n: row["undetected"] for n, row in zip(args.sizes, rows) if row["undetected"]}
    if args.json:
        print(json.dumps(figures))
    else:
        print(f"{'n':>5} {'build':>8} {'arrs':>8} {'signatures':>11} {'total':>8} {'state eqs':>10} {'ratio':>6} "
              f"{'ARRs':>5} {'undetected':>10}")
        for n, row, base in zip(args.sizes, rows, baselines):
            print(f"{n:>5} {row['build']:>8.3f} {row['arrs']:>8.3f} {row['signatures']:>11.3f} {row['total']:>8.3f} "
                  f"{base:>10.3f} {row['total'] / base:>6.1f} {row['count']:>5} {len(row['undetected']):>10}")
        if slope is not None:
            print(f"growth exponent (log-log slope): {slope:.2f}")
        if args.pairs:
            print("structurally isolable ordered pairs:", figures["structural_pairs"], "left by the ARRs:",
                  figures["unreached_pairs"])
    if missed:   # printed first, then failed: every fault must be seen
        raise SystemExit(f"faults no ARR sees: {json.dumps(missed)}")


if __name__ == "__main__":
    main()
