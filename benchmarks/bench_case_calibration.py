"""The case studies from a deliberately wrong datasheet plus calibration, against the true model (issue 35).

    python benchmarks/bench_case_calibration.py [--json] [--seeds N] [--cases torsion_bar three_tank] [--workers 2]

Issue 35's acceptance: the torsion-bar and three-tank case studies, run from a deliberately wrong datasheet
model plus calibration, reach the same detection and RUL figures as from the true model, within their
seeds' spread.  Each case runs over the same seeds three ways, the simulation (the truth) always the true
physics and the records the same:

* ``true``: the chain built from the true values (the example's default);
* ``wrong``: built from the example's ``WRONG_DATASHEET`` with its ``CALIBRATED`` parameters estimated by
  :func:`diagnosis.estimate_parameters` on the healthy calibration record of the seed alone (never the degraded
  record, never the fault-free twin the false alarms are counted on), every box the datasheet's;
* ``wrong-uncalibrated``: built from the wrong datasheet as it is, to show what the calibration does.

Cases (``--cases``):

* ``torsion_bar``: ``examples/torsion_bar.py``, case ``b-md``, preset ``auto`` (told only the failure
  values), the paper's noise; default 10 seeds (a run takes about 7 s: the 30 runs and the diagnostics took
  285 s with ``--workers 1`` on the reference machine's two cores, another job running beside).
  Figures: the detection time (first alarm of any ARR), false alarms on the nominal record, RMSE of b_Md, RA,
  RMAD of the RUL, the alpha-lambda pass rate, the median RUL within 20 % and the 5-95 % band holding the
  true RUL (the last five over the predictions after t = 52 s), and how often b_Md and its law were isolated.
* ``three_tank``: ``examples/three_tank.py``, all seven filters; default 20 seeds (130 s with ``--workers 1``).
  Figures: the detection time (first alarm of any ARR on the degraded record), false alarms on the
  fault-free twin (all ARRs), and each filter's MAE and RMSE of the 5-step-ahead prediction of az2.

Per case, way and figure: the mean over the seeds, the worst seed (the highest, or the lowest where higher
is better), the seeds' spread (sample standard deviation, ``ddof = 1``) and, for ``wrong`` and
``wrong-uncalibrated``, the verdict against ``true``: **same** when the way misses no more seeds than the
true chain and ``|mean_way - mean_true| <= std_true``, the true chain's own spread over the same seeds;
**differs** otherwise.  The per-seed (paired) difference, its mean and spread, is printed beside it for
information; it is not the verdict (the filters' random streams are the seed's in all three ways, but a
slightly different model sends a particle filter down another path, so the pairs are not a measurement
of the model alone).

The calibrated parameters are scored against the simulation's truth (error, and whether the 95 % interval
holds the truth): scoring only, nothing of the truth reaches the fit or the chain.  Diagnostics beside the
figures: for the torsion bar, the fit of every parameter with a tolerance on the same records (what the
record does not identify, and where the fit fails), and which member of the ``f_m``/``b_Md`` combination
carries it when both are fitted; for the three tanks, the fit on a noise-free record of the truth's own
model (eq. 59's Euler step at dt = 1 s) by the chain's rule (the left rectangle, ``quadrature="euler"``)
and by the trapezoid rule, beside the trapezoid fit of the same physics integrated finely (RK4, 20
substeps).
``--json`` prints one JSON object per case, one per line.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "examples"))

import three_tank as tt  # noqa: E402  (examples/, put on the path above)
import torsion_bar as tb  # noqa: E402

from bgphm.runs import over_seeds  # noqa: E402
from bondgraph.library import THREE_TANK, TORSION_BAR  # noqa: E402
from diagnosis import derive_arrs, estimate_parameters  # noqa: E402
from prognosis.statespace import discretize  # noqa: E402

WAYS = ("true", "wrong", "wrong-uncalibrated")
SEEDS = {"torsion_bar": 10, "three_tank": 20}
#: The torsion bar's figures: (key in the example's figures, label, higher is better).
TORSION_FIGURES = (("detection_time_s", "detection time (s)", False),
                   ("false_alarms_nominal", "false alarms, nominal record", False),
                   ("rmse_theta", "RMSE b_Md", False),
                   ("ra", "RA after 52 s", True),
                   ("rmad_rul", "mean RMAD RUL after 52 s", False),
                   ("alpha_lambda_pass_rate", "alpha-lambda pass rate", True),
                   ("median_within_20pct", "median RUL within 20 %", True),
                   ("band_holds_truth", "5-95 % band holds the RUL", True))
#: The torsion bar's parameters with a tolerance (Table VI), fitted all at once as a diagnostic.
TOLERANCED = tuple(p for p, (_, box) in TORSION_BAR.items() if box is not None)
TANK_TRUTH = {"az1": THREE_TANK["az1"], "az2": THREE_TANK["az2"], "az3": THREE_TANK["az3"],
              "A_1": THREE_TANK["A_s"], "A_2": THREE_TANK["A_s"], "A_3": THREE_TANK["A_s"]}


# --------------------------------------------------------------------------------------------- statistics

def stats(values: list, higher_is_better: bool = False) -> dict:
    """Mean, sample standard deviation, worst and missing seeds of one figure over seeds (None: missing)."""
    array = np.array([np.nan if v is None else v for v in values], float)
    finite = array[np.isfinite(array)]
    return {"mean": float(finite.mean()) if finite.size else None,
            "std": float(finite.std(ddof=1)) if finite.size > 1 else 0.0,
            "worst": None if not finite.size else float(finite.min() if higher_is_better else finite.max()),
            "missing": int(array.size - finite.size), "values": [None if not np.isfinite(v) else float(v)
                                                                 for v in array]}


def verdict(true: dict, other: dict) -> dict:
    """``same`` when ``other`` misses no more seeds than ``true`` and its mean is within ``true``'s spread."""
    t, o = np.array([np.nan if v is None else v for v in true["values"]], float), \
        np.array([np.nan if v is None else v for v in other["values"]], float)
    both = np.isfinite(t) & np.isfinite(o)
    paired = o[both] - t[both]
    gap = None if true["mean"] is None or other["mean"] is None else other["mean"] - true["mean"]
    same = other["missing"] <= true["missing"] and gap is not None and abs(gap) <= true["std"]
    return {"verdict": "same" if same else "differs", "mean_difference": gap,
            "paired_mean": float(paired.mean()) if paired.size else None,
            "paired_std": float(paired.std(ddof=1)) if paired.size > 1 else 0.0}


def compare(per_way: dict, figures: tuple) -> dict:
    """Per figure: each way's statistics and, for the wrong datasheets, the verdict against ``true``."""
    out = {}
    for key, label, higher in figures:
        row = {"label": label, "higher_is_better": higher}
        for way, values in per_way.items():
            row[way] = stats([v.get(key) for v in values], higher)
        for way in per_way:
            if way != "true":
                row[way].update(verdict(row["true"], row[way]))
        out[key] = row
    return out


def score(fits: list, truth: dict) -> dict:
    """Per calibrated parameter, over seeds: relative error of the estimate against the truth (mean |error|,
    worst, bias) and the share of the seeds whose 95 % interval holds the truth (scoring only)."""
    out = {}
    for p in dict.fromkeys(p for fit in fits if fit for p in fit["parameters"]):
        rows = [fit["parameters"][p] for fit in fits if fit and p in fit["parameters"]]
        errors = np.array([r["estimate"] / truth[p] - 1.0 for r in rows])
        held = [r["interval"][0] <= truth[p] <= r["interval"][1] for r in rows]
        out[p] = {"seeds": len(rows), "datasheet_error": rows[0]["datasheet"] / truth[p] - 1.0,
                  "error_mean_abs": float(np.mean(np.abs(errors))),
                  "error_worst": float(errors[np.argmax(np.abs(errors))]),
                  "bias": float(errors.mean()), "coverage": float(np.mean(held)),
                  "half_width_median": float(np.median([(r["interval"][1] - r["interval"][0]) / 2 / truth[p]
                                                        for r in rows]))}
    return out


# --------------------------------------------------------------------------------------------- torsion bar

def torsion_run(seed: int, way: str, scenario) -> dict:
    """One seed of the b-md case, preset auto, built from ``way``'s model."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        figures = tb.run("b-md", "auto", seed, scenario=scenario, workers=1, datasheet=way).figures
    keep = [k for k, _, _ in TORSION_FIGURES] + ["found", "law", "seed", "model", "calibration", "wall_time_s"]
    return {k: figures.get(k) for k in keep}


def torsion_diagnostics(seed: int, scenario) -> dict:
    """On the seed's calibration record: the fit of every toleranced parameter (from the wrong datasheet), and
    which of b_Md and f_m carries their combination when both are fitted."""
    case = tb.CASES["b-md"]
    calibration = tb.detection_setup(case, scenario, seed)[5]
    wrong, _ = tb.monitored_model(case, "wrong-uncalibrated", calibration)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        every = estimate_parameters(wrong, [calibration], list(TOLERANCED))
        pair = estimate_parameters(wrong, [calibration], ["b_Md", "f_m"])
    carrier = [c for c in pair.identifiability.combinations if set(c["parameters"]) == {"b_Md", "f_m"}]
    return {"every": every.as_dict(),
            "every_combinations": [c["expression"] for c in every.identifiability.combinations],
            "pair_carrier": [p for p in ("b_Md", "f_m") if p in pair.intervals] if carrier else ["both"],
            "pair_values": {p: pair.values[p] / TORSION_BAR[p][0] - 1.0 for p in ("b_Md", "f_m")}}


def bench_torsion(seeds: list, workers: int) -> dict:
    start = time.perf_counter()
    scenario = tb.simulate_case(tb.CASES["b-md"])
    per_way = {way: over_seeds(torsion_run, [(seed, way, scenario) for seed in seeds], workers=workers)
               for way in WAYS}
    figures = compare(per_way, TORSION_FIGURES)
    diagnostics = [torsion_diagnostics(seed, scenario) for seed in seeds]
    truth = {p: v for p, (v, _) in TORSION_BAR.items()}
    every = score([d["every"] for d in diagnostics], truth)
    carriers = {}
    for d in diagnostics:
        key = "+".join(d["pair_carrier"])
        carriers[key] = carriers.get(key, 0) + 1
    return {"case": "torsion_bar", "example": "examples/torsion_bar.py --case b-md --preset auto",
            "seeds": seeds, "wrong_datasheet": dict(tb.WRONG_DATASHEET), "calibrated": list(tb.CALIBRATED),
            "figures": figures,
            "isolated": {way: {"b_Md": sum(r["found"] == "b_Md" for r in runs),
                               "exponential": sum(r["law"] == "exponential" for r in runs)}
                         for way, runs in per_way.items()},
            "calibration": score([r["calibration"] for r in per_way["wrong"]], truth),
            "diagnostic_every_toleranced": every,
            "diagnostic_every_combinations": sorted({c for d in diagnostics for c in d["every_combinations"]}),
            "diagnostic_b_Md_f_m_carrier": carriers,
            "wall_s": round(time.perf_counter() - start, 1)}


# --------------------------------------------------------------------------------------------- three tanks

def tank_run(seed: int, way: str) -> dict:
    """One seed of the three tanks, every filter, built from ``way``'s model: the figures compared."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = tt.run_seed(seed, datasheet=way)
    times = [d["detection_time_s"] for d in r["detection"].values() if d["detection_time_s"] is not None]
    out = {"seed": seed, "model": r["model"], "calibration": r["calibration"],
           "detection_time_s": min(times) if times else None,
           "false_alarms_nominal": sum(d["false_alarms_nominal"] for d in r["detection"].values()),
           "alarms": {name: d["detection_time_s"] for name, d in r["detection"].items()}}
    for name, m in r["methods"].items():
        out[f"{name}_mae"], out[f"{name}_rmse"] = m["mae"], m["rmse"]
    return out


def tank_figures() -> tuple:
    rows = [("detection_time_s", "detection time, first alarm (k)", False),
            ("false_alarms_nominal", "false alarms, fault-free twin", False)]
    for name in tt.METHODS:
        rows += [(f"{name}_mae", f"{name} MAE", False), (f"{name}_rmse", f"{name} RMSE", False)]
    return tuple(rows)


def noise_free_fits() -> dict:
    """The calibration on noise-free records, from the wrong datasheet: the truth's own model (Euler at dt = 1 s,
    eq. 59) fitted by the chain's rule (``quadrature="euler"``) and by the trapezoid rule meant for continuous
    machines, and the same physics integrated finely (RK4, 20 substeps) by the trapezoid rule: relative errors
    against the truth."""
    wrong = tt.bond_graph("wrong")
    arrs = list(derive_arrs(wrong, complete=False))
    models = {"euler_dt1": tt.model(),
              "rk4_20_substeps": discretize(tt.bond_graph().state_equations(), dt=tt.DT, augment=["az2"],
                                            outputs=["h1", "h2", "h3"], method="rk4", substeps=20)}
    fits = (("euler_dt1", "euler"), ("euler_dt1", "trapezoid"), ("rk4_20_substeps", "trapezoid"))
    out = {}
    for label, quadrature in fits:
        m = models[label]
        x = np.array([*(tt.AREA * h for h in tt.LEVELS_0), THREE_TANK["az2"]])
        states = []
        for _ in range(tt.STEPS):
            x = m.transition(x, tt.INPUTS)
            states.append(x.copy())
        levels = m.measure(np.array(states).T).T
        t = tt.DT * np.arange(1, tt.STEPS + 1)
        record = {"t": t, **{n: np.full(t.size, v) for n, v in tt.INPUTS.items()},
                  **{f"h{i + 1}": levels[:, i] for i in range(3)}}
        fit = estimate_parameters(wrong, [record], list(tt.CALIBRATED), arrs=arrs, quadrature=quadrature)
        out[f"{label}_{quadrature}_rule"] = {p: fit.values[p] / TANK_TRUTH[p] - 1.0 for p in tt.CALIBRATED}
    return out


def bench_tanks(seeds: list, workers: int) -> dict:
    start = time.perf_counter()
    per_way = {way: over_seeds(tank_run, [(seed, way) for seed in seeds], workers=workers) for way in WAYS}
    return {"case": "three_tank", "example": "examples/three_tank.py", "seeds": seeds,
            "wrong_datasheet": dict(tt.WRONG_DATASHEET), "calibrated": list(tt.CALIBRATED),
            "figures": compare(per_way, tank_figures()),
            "detected_by": {way: {name: sum(r["alarms"][name] is not None for r in runs) for name in runs[0]["alarms"]}
                            for way, runs in per_way.items()},
            "calibration": score([r["calibration"] for r in per_way["wrong"]], TANK_TRUTH),
            "diagnostic_noise_free_fit": noise_free_fits(),
            "wall_s": round(time.perf_counter() - start, 1)}


# --------------------------------------------------------------------------------------------- output

def _num(value, digits: int = 4) -> str:
    if value is None:
        return "-"
    if value == 0 or not math.isfinite(value):
        return f"{value:g}"
    return f"{value:.{digits}g}"


def _pct(value) -> str:
    return "-" if value is None else f"{100 * value:+.2f} %"


def report(line: dict) -> str:
    seeds = line["seeds"]
    out = [f"{line['case']} ({line['example']}), seeds {seeds[0]}-{seeds[-1]} ({len(seeds)}), {line['wall_s']} s",
           "  wrong datasheet: " + ", ".join(f"{p} x{f:g}" for p, f in line["wrong_datasheet"].items())
           + "; calibrated: " + ", ".join(line["calibrated"]),
           f"  {'figure':<34} {'true: mean (worst) +- std':>30} "
           f"{'wrong + calibration':>30} {'':>8} {'wrong, uncalibrated':>30} {'':>8}"]
    for row in line["figures"].values():
        cells = []
        for way in WAYS:
            s = row[way]
            text = f"{_num(s['mean'])} ({_num(s['worst'])}) +- {_num(s['std'], 2)}"
            if s["missing"]:
                text += f" [{s['missing']} missing]"
            cells.append(f"{text:>30}")
            if way != "true":
                cells.append(f"{s['verdict']:>8}")
        out.append(f"  {row['label']:<34} " + " ".join(cells))
    out.append("  verdict: same when |mean - mean_true| <= std_true (the true chain's sample std over the same seeds) "
               "and no more seeds missing")
    for way in WAYS[1:]:
        paired = ", ".join(f"{row['label']} {_num(row[way]['paired_mean'], 3)} +- {_num(row[way]['paired_std'], 2)}"
                           for row in line["figures"].values())
        out.append(f"  paired difference {way} - true (mean +- std): {paired}")
    for key in ("isolated", "detected_by"):
        if key in line:
            out.append(f"  {key.replace('_', ' ')}: " + "; ".join(f"{way} {v}" for way, v in line[key].items()))
    out.append("  calibrated parameters against the truth (scoring only):")
    for p, s in line["calibration"].items():
        out.append(f"    {p:<5} datasheet {_pct(s['datasheet_error'])} -> calibrated |error| mean "
                   f"{100 * s['error_mean_abs']:.2f} %, worst {_pct(s['error_worst'])}, bias {_pct(s['bias'])}; "
                   f"95 % interval half-width {100 * s['half_width_median']:.2f} %, holds the truth in "
                   f"{100 * s['coverage']:.0f} % of {s['seeds']} seeds")
    if "diagnostic_every_toleranced" in line:
        out.append("  diagnostic: every toleranced parameter fitted from the wrong datasheet (errors vs truth):")
        for p, s in line["diagnostic_every_toleranced"].items():
            out.append(f"    {p:<5} |error| mean {100 * s['error_mean_abs']:.1f} %, worst {_pct(s['error_worst'])}, "
                       f"half-width {100 * s['half_width_median']:.1f} %, holds the truth in "
                       f"{100 * s['coverage']:.0f} % of {s['seeds']} seeds")
        out.append(f"    combinations reported: {'; '.join(line['diagnostic_every_combinations']) or 'none'}")
        out.append(f"  diagnostic: b_Md and f_m fitted together, the combination carried by (seeds): "
                   f"{line['diagnostic_b_Md_f_m_carrier']}")
    if "diagnostic_noise_free_fit" in line:
        for label, errors in line["diagnostic_noise_free_fit"].items():
            out.append(f"  diagnostic: noise-free record, {label}: "
                       + ", ".join(f"{p} {_pct(e)}" for p, e in errors.items()))
    return "\n".join(out)


def main(argv=None) -> list:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=sorted(SEEDS), default=list(SEEDS))
    parser.add_argument("--seeds", type=int, help="seeds per case (default: torsion bar 10, three tank 20)")
    parser.add_argument("--workers", type=int, default=2, help="processes over seeds (default 2)")
    parser.add_argument("--json", action="store_true", help="one JSON object per case, one per line")
    args = parser.parse_args(argv)
    if args.seeds is not None and args.seeds < 2:
        parser.error("--seeds must be at least 2 (a spread needs two seeds)")
    lines = []
    for case in args.cases:
        seeds = list(range(args.seeds or SEEDS[case]))
        line = (bench_torsion if case == "torsion_bar" else bench_tanks)(seeds, args.workers)
        lines.append(line)
        print(json.dumps(line) if args.json else report(line), flush=True)
    return lines


if __name__ == "__main__":
    main()
