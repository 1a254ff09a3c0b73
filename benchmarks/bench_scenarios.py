"""Prognosis scenarios: wear laws simulated from the physics, run through ``bgphm prognose``.

    python benchmarks/bench_scenarios.py [--json] [--seeds 10] [--seed-from 0] [--particles 300]
                                         [--rul-every 10] [--jobs 2] [--filter sir|resample-move]
                                         [--pairs | --no-pairs] [--system NAME]
                                         [--degradation LAW ...] [--window N [--step-samples M]]
                                         [--runs] [NAME ...]
    python benchmarks/bench_scenarios.py --pool RUNS.jsonl ... [--json] [NAME ...]

Each scenario (tests/wear/run.py) is a parameter wearing by a law (linear, exponential, power,
logistic, step then drift, intermittent) on one of three systems, each simulated from its physics, never
by the library: the torsion bar's mechanics under a digital PI loop (tests/wear/torsion.py; the motor
disk's friction wears), and two systems of the model zoo integrated from their hand-written equations
(tests/wear/zoo.py): a DC motor driving a pump whose brushes wear, a pipe feeding a tank whose strainer
clogs.  Each runs with a clean residual (small noise on the sensors a real machine always has) or a
noisy one (more noise on the signal that carries the residual's noise).  Every seed draws its own noise
and the filter's own streams.  The user's side is a model file, a CSV and ``--fail`` values, nothing of
the truth.

A sensor scenario offsets one encoder's reading of the torsion bar (a bias, a drift), the machine
healthy: the sensor and its law must be named, and no RUL is due.  A concurrent scenario wears two
parameters at once (the pump's brushes and impeller, the pipe's strainer and the tank's outlet), the
second failing first: both must be named (``"R_a + c_p"``) and the RUL is the first failure's.  Pairs
are weighed as ``bgphm prognose`` weighs them by default: when no single fault explains the residuals,
on the whole record again (``pairs_weighed``: the share of runs where that happened); ``--pairs`` weighs
them from the alarm in every scenario, ``--no-pairs`` never.

Per scenario, over the seeds: the share of runs that name the degrading parameter or the faulty
sensor (or an honest indistinguishable group holding it), the share whose most probable hypothesis
at the end is that fault itself (``top_is_true``), the statuses and laws said, over the second half of life the
share of predictions whose median RUL is within 20 % of the truth (mean and worst over the seeds),
the pooled coverage of the 5-95 % and 25-75 % bands, the PIT histogram per quarter of the life (the
truth's place among the predicted 5, 25, 50, 75 and 95 % quantiles: 5, 20, 25, 25, 20, 5 % when
calibrated), and the relative accuracy (mean and worst).  The
targets: found in every run, within-20 % >= 0.8, coverage 0.85-0.97 and 0.40-0.65.
``--json`` prints one JSON object per scenario, one per line.

A sweep of 10 seeds over the whole suite costs hours of CPU; it can be cut by seeds and spread over
machines or sessions at one commit: ``--runs`` prints each run's figures (one JSON line per scenario and
seed) as it ends, so that an interrupted sweep keeps what it ran; ``--seed-from K`` starts at the K-th
seed; ``--pool`` pools the runs of such files per scenario (a run given twice counts once).

``--window N`` reads the residuals with a derivative window of N samples (``bgphm prognose --window``),
``--step-samples M`` steps the filter every M samples of each system's record (``--dt``): the derivative
window's measurement in docs/design.md is ``--window 31 --step-samples 11``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.wear.run import SYSTEMS, fault_of, run, same_fault, scenarios, score  # noqa: E402

SEED_BASE = 20261126   # seeds SEED_BASE + k: each its own noise and its own filter streams


def one(arguments: tuple) -> dict:
    scenario, seed, particles, rul_every, method, laws, pairs, window, step_samples = arguments
    started = time.process_time()
    step = () if step_samples is None else ("--dt", f"{step_samples * scenario.facts.dt:.12g}")
    figures = score(scenario, run(scenario, seed, particles=particles, rul_every=rul_every, method=method,
                                  degradation=laws, pairs=pairs, window=window, extra=step))
    return {"scenario": scenario.name, **figures, "seed": seed, "filter": method, "pairs": pairs,
            **({} if window is None else {"window": window}),
            **({} if step_samples is None else {"step_samples": step_samples}),
            "cpu_s": round(time.process_time() - started, 1)}


def pooled(name: str, rows: list[dict]) -> dict:
    """The scenario's line: shares over the seeds, mean and worst (never best) of the per-seed figures."""
    def values(key):
        return [r[key] for r in rows if r.get(key) is not None]

    within, ra = values("within_20pct_second_half"), values("ra")
    return {
        "scenario": name, "seeds": len(rows), "filter": rows[0]["filter"] if rows else None,
        "pairs": rows[0]["pairs"] if rows else None,
        "pairs_weighed": float(np.mean([str(r.get("pairs_weighed", "")).startswith("weighed") for r in rows])),
        "found": float(np.mean([r["found"] for r in rows])),
        "statuses": dict(Counter(str(r.get("status")) for r in rows)),
        "laws": dict(Counter(str(r.get("degradation")) for r in rows)),
        # the share of runs whose most probable hypothesis is the true fault (parameter or sensor)
        "top_is_true": float(np.mean([same_fault(fault_of(r.get("top")), name.split("/")[1]) for r in rows])),
        # predictions withheld as undecided (every probable law contradicted by the data): no figure
        "withheld": _share_withheld(rows),
        "within_20pct_mean": float(np.mean(within)) if within else None,
        "within_20pct_worst": float(np.min(within)) if within else None,
        # pooled: every prediction of every seed counts once
        "coverage_90": _pooled(rows, "coverage_90"), "coverage_50": _pooled(rows, "coverage_50"),
        "ra_mean": float(np.mean(ra)) if ra else None, "ra_worst": float(np.min(ra)) if ra else None,
        # the truth's place among the 5, 25, 50, 75, 95 % quantiles (six bins), per quarter of the life
        "pit_by_quarter": np.sum([r["pit"] for r in rows if "pit" in r], axis=0).tolist()
        if any("pit" in r for r in rows) else None,
        "cpu_s": float(sum(r["cpu_s"] for r in rows)),
    }


def _share_withheld(rows: list[dict]) -> float | None:
    given = sum(r.get("predictions", 0) + r.get("withheld", 0) for r in rows)
    return float(sum(r.get("withheld", 0) for r in rows) / given) if given else None


def _pooled(rows: list[dict], key: str) -> float | None:
    weights = [(r[key], r["predictions"]) for r in rows if r.get(key) is not None and r.get("predictions")]
    total = sum(n for _, n in weights)
    return float(sum(v * n for v, n in weights) / total) if total else None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="scenario names (default: all), e.g. torsion_bar/b_Md/linear/clean")
    parser.add_argument("--system", action="append", choices=sorted(SYSTEMS),
                        help="only this system's scenarios (repeatable; default: every system)")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--seed-from", type=int, default=0, help="the first seed's index (seeds SEED_BASE + K on)")
    parser.add_argument("--runs", action="store_true", help="print each run's figures as it ends, not the pooled ones")
    parser.add_argument("--pool", nargs="+", type=Path, metavar="RUNS",
                        help="pool the runs of these files (printed by --runs) per scenario instead of running")
    parser.add_argument("--particles", type=int, default=300)
    parser.add_argument("--rul-every", type=int, default=10)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--filter", choices=("resample-move", "sir"), default="resample-move",
                        help="bgphm prognose --filter")
    parser.add_argument("--pairs", action=argparse.BooleanOptionalAction, default=None,
                        help="bgphm prognose --pairs: weigh two parameters wearing at once from the alarm (with "
                             "resample-move); --no-pairs: never (default: the command's, when no single fault "
                             "explains the residuals)")
    parser.add_argument("--degradation", action="append", default=[],
                        choices=("linear", "exponential", "power", "saturating"),
                        help="bgphm prognose --degradation (repeatable; default the command's laws)")
    parser.add_argument("--window", type=int, help="bgphm prognose --window: the derivative window in samples "
                                                   "(default the command's, 11)")
    parser.add_argument("--step-samples", type=int, metavar="M",
                        help="the filter step in samples of each system's record (bgphm prognose --dt; default one "
                             "derivative window)")
    args = parser.parse_args()
    unknown = sorted(set(args.names) - {s.name for s in scenarios()})
    if unknown:   # a name mistyped would otherwise leave its scenario out without a word
        parser.error(f"no scenario {unknown[0]!r} (the names are those of tests/wear/run.py's scenarios())")
    chosen = [s for s in scenarios() if (not args.names or s.name in args.names)
              and (not args.system or s.system in args.system)]
    if args.pool:
        try:
            runs = read_runs(args.pool)
        except (OSError, ValueError) as error:
            parser.error(str(error))
    else:
        tasks = [(s, SEED_BASE + k, args.particles, args.rul_every, args.filter, tuple(args.degradation),
                  args.pairs, args.window, args.step_samples)
                 for s in chosen for k in range(args.seed_from, args.seed_from + args.seeds)]
        with ProcessPoolExecutor(args.jobs) as pool:
            runs = []
            for row in (pool.map(one, tasks) if args.jobs > 1 else map(one, tasks)):
                runs.append(row)
                if args.runs:
                    print(json.dumps(row), flush=True)
        if args.runs:
            return 0
    for s in chosen:
        rows = [r for r in runs if r["scenario"] == s.name]
        if not rows:   # not among the pooled runs
            continue
        line = pooled(s.name, rows)
        if args.json:
            print(json.dumps(line))
        else:
            print(f"{line['scenario']:48s} found {line['found']:.0%}  withheld {_pct(line['withheld'])}  "
                  f"within20 {_pct(line['within_20pct_mean'])} "
                  f"(worst {_pct(line['within_20pct_worst'])})  cov90 {_pct(line['coverage_90'])}  "
                  f"cov50 {_pct(line['coverage_50'])}  RA {_pct(line['ra_mean'])} (worst {_pct(line['ra_worst'])})  "
                  f"{line['statuses']} {line['laws']}")
    return 0


def read_runs(paths: list[Path]) -> list[dict]:
    """The runs printed by ``--runs`` in these files, each (scenario, seed, filter, pairs) once."""
    runs = {}
    for path in paths:
        for number, text in enumerate(path.read_text().splitlines(), 1):
            if text.strip():
                try:
                    row = json.loads(text)
                    key = (row["scenario"], row["seed"], row["filter"], row["pairs"])
                except (ValueError, KeyError, TypeError) as error:
                    raise ValueError(f"{path}:{number}: not a run printed by --runs (no {error})") from None
                runs.setdefault(key, row)
    return list(runs.values())


def _pct(value) -> str:
    return "  -  " if value is None else f"{value:5.0%}"


if __name__ == "__main__":
    sys.exit(main())
