"""Scale benchmark: causality and state equations of an n-stage mass-spring-damper chain.

For each n, builds the chain (a velocity sensor on every mass), assigns
integral and derivative causality, and derives the state equations.  Prints
the times and the growth exponent (slope of log time against log n).  As a
same-process baseline, it also solves the acausal equations of the smallest
chain directly with ``sympy.solve`` (what a naive implementation would do) and
reports how many times faster the causal route is.

    python benchmarks/bench_causality.py            # table
    python benchmarks/bench_causality.py --json     # {"n": [...], "seconds": [...], "growth_exponent": ...}

Target: 200 stages in under 5 s, near-linear growth.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import sympy as sp
from sympy.core.cache import clear_cache

from bondgraph.equations import model_equations
from bondgraph.library import mass_spring_chain


def time_stages(n: int) -> dict:
    """Seconds spent building, assigning both causalities and deriving state equations.

    sympy's cache is cleared first: a repeated run would otherwise reuse the
    expressions of the previous one and look faster than a user's first run.
    """
    clear_cache()
    start = time.perf_counter()
    bg = mass_spring_chain(n)
    built = time.perf_counter()
    integral = bg.assign_causality("integral")
    bg.assign_causality("derivative")
    assigned = time.perf_counter()
    equations = bg.state_equations(integral)
    derived = time.perf_counter()
    assert len(equations.states) == 2 * n
    return {"build": built - start, "causality": assigned - built, "equations": derived - assigned,
            "total": derived - start}


def naive_seconds(n: int) -> float:
    """Baseline: solve all acausal equations for the bond variables and state derivatives at once."""
    bg = mass_spring_chain(n)
    clear_cache()
    start = time.perf_counter()
    equations = model_equations(bg)
    derivatives = sorted({d for eq in equations for d in eq.atoms(sp.Derivative)}, key=str)
    placeholders = {d: sp.Symbol(f"d_{d.expr.func}") for d in derivatives}
    equations = [eq.xreplace(placeholders) for eq in equations]
    unknowns = sorted({s for eq in equations for s in eq.free_symbols if s.name[:2] in ("e_", "f_")}, key=str)
    unknowns += list(placeholders.values())
    measured = {sp.Function(name)(sp.Symbol("t")) for name in bg.outputs}
    balance = [eq for eq in equations if eq.lhs not in measured]  # sensor read-outs are not constraints
    solution = sp.solve(balance, unknowns, dict=True)
    assert len(solution) == 1
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 50, 200])
    parser.add_argument("--baseline-size", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs per size")
    args = parser.parse_args()

    time_stages(5)  # warm sympy's caches so the first size is not charged for them
    rows = [min((time_stages(n) for _ in range(args.repeat)), key=lambda row: row["total"]) for n in args.sizes]
    seconds = [row["total"] for row in rows]
    slope = float(np.polyfit(np.log(args.sizes), np.log(seconds), 1)[0])
    baseline = naive_seconds(args.baseline_size)
    ours = time_stages(args.baseline_size)["equations"]
    figures = {
        "n": args.sizes,
        "seconds": [round(s, 4) for s in seconds],
        "growth_exponent": round(slope, 3),
        "breakdown": [{k: round(v, 4) for k, v in row.items()} for row in rows],
        "baseline": {"n": args.baseline_size, "naive_solve_seconds": round(baseline, 4),
                     "causal_equations_seconds": round(ours, 4), "speedup": round(baseline / ours, 1)},
    }
    if args.json:
        print(json.dumps(figures))
        return
    print(f"{'n':>5} {'states':>7} {'build':>8} {'causality':>10} {'equations':>10} {'total':>8}")
    for n, row in zip(args.sizes, rows):
        print(f"{n:>5} {2 * n:>7} {row['build']:>8.3f} {row['causality']:>10.3f} "
              f"{row['equations']:>10.3f} {row['total']:>8.3f}")
    print(f"growth exponent (log-log slope): {slope:.2f}")
    print(f"baseline n={args.baseline_size}: naive sympy.solve {baseline:.3f} s, causal route {ours:.3f} s "
          f"({baseline / ours:.1f}x faster)")


if __name__ == "__main__":
    main()
