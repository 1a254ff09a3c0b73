"""How fast bondgraph.laws rejects hostile law strings (the speed claims moved out of tests/bondgraph/test_laws.py).

Each hostile input is parsed (or, for the valve law, solved for the effort) and must raise LawError;
the time of the rejection is compared with the time of parsing an ordinary nonlinear law, the valve law
``f - a*sign(e)*sqrt(Abs(e))``, measured in the same process: best of ``--repeat`` calls against best of
``--repeat`` calls.  The targets apply to the first call (sympy's caches cold, what a user meets).

    python benchmarks/bench_laws.py            # table
    python benchmarks/bench_laws.py --json     # {"cases": [...], "baseline_seconds": ..., "worst_ratio": ...}

Targets: every rejection under 1 s (huge exponents, power towers, strings over 2000 characters, deep
nesting), refusing to solve the valve law for the effort under 10 s.  The tests check that these inputs
are rejected, and that the huge exponents do not hang (in a child process with a deadline).
"""

from __future__ import annotations

import argparse
import json
import time

import networkx as nx
import sympy as sp

from bondgraph import BondGraph, LawError
from bondgraph.laws import parse_expression, solve_for

e, f, a = sp.symbols("e f a")
NAMES = {"e": e, "f": f, "a": a}
WHERE = "R 'valve' law"
VALVE = "f - a*sign(e)*sqrt(Abs(e))"


def parse(text):
    return parse_expression(text, NAMES, where=WHERE)


def element(law):
    graph = nx.DiGraph()
    graph.add_node("P", kind="Se", signal="P_in")
    graph.add_node("J", kind="1")
    graph.add_node("valve", kind="R", param="a", value=0.3, law=law)
    graph.add_edges_from([("P", "J"), ("J", "valve")])
    return BondGraph(graph)


def long_string(length: int) -> str:
    return ("e + " * length)[: length - 1] + "e"


#: (label, callable, target in seconds); every callable must raise LawError.
CASES = [
    *[(f"parse {text}", lambda text=text: parse(text), 1.0)
      for text in ["9**9**9**9", "2**1000", "e**1e6", "10**-1000", "e**(9**99)", "(e + 1)**100000", "2**-1000",
                   "(((9**99)**99)**99)**99", "((((2**99)**99)**99)**99)*e"]],
    *[(f"element law {text}", lambda text=text: element(text), 1.0)
      for text in ["f - 9**9**9**9*e", "f - e**1e6", "f - a*e**2**1000"]],
    *[(f"parse a {length:,}-character sum", lambda length=length: parse(long_string(length)), 1.0)
      for length in (2_001, 10_000, 1_000_000)],
    ("parse 1999 unary minus signs", lambda: parse("-" * 1999 + "e"), 1.0),
    ("parse 300 nested parentheses", lambda: parse("(" * 300 + "e" + ")" * 300), 1.0),
    ("parse 300 nested sqrt", lambda: parse("sqrt(" * 300 + "e" + ")" * 300), 1.0),
    ("solve the valve law for e", lambda: solve_for(parse(VALVE), e, where="R 'valve'"), 10.0),
]


def timed(function, repeat: int, rejected: bool) -> tuple[float, float]:
    """(first, best) wall time of ``repeat`` calls; ``rejected``: the call must raise LawError."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        try:
            function()
        except LawError:
            if not rejected:
                raise
        else:
            if rejected:
                raise AssertionError("accepted a hostile law")
        times.append(time.perf_counter() - start)
    return times[0], min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    _, baseline = timed(lambda: parse(VALVE), args.repeat, rejected=False)
    cases = []
    for label, function, target in CASES:
        seconds, best = timed(function, args.repeat, rejected=True)
        cases.append({"case": label, "seconds": round(seconds, 5), "best_seconds": round(best, 5),
                      "ratio_vs_valve_parse": round(best / baseline, 2), "target_seconds": target,
                      "meets_target": seconds < target})
    figures = {"baseline_seconds": round(baseline, 6), "cases": cases,
               "worst_ratio": max(c["ratio_vs_valve_parse"] for c in cases),
               "all_meet_targets": all(c["meets_target"] for c in cases)}
    if args.json:
        print(json.dumps(figures))
        return
    print(f"baseline: parsing {VALVE!r} takes {baseline * 1e3:.3f} ms (best)")
    width = max(len(c["case"]) for c in cases)
    print(f"  {'rejected input':<{width}}  {'first':>9}     {'best':>9}     {'best / baseline':>8}")
    for c in cases:
        print(f"  {c['case']:<{width}}  {c['seconds'] * 1e3:9.2f} ms  {c['best_seconds'] * 1e3:9.2f} ms  "
              f"{c['ratio_vs_valve_parse']:16.2f}x  "
              f"(target < {c['target_seconds']:g} s: {'met' if c['meets_target'] else 'NOT met'})")


if __name__ == "__main__":
    main()
