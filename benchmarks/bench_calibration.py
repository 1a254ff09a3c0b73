"""Parameter calibration from healthy records, measured on the model zoo: coverage, errors, detection before/after.

    python benchmarks/bench_calibration.py [--json] [--seeds 20] [--cases NAME ...] [--fit all|perturbed]

A machine is never its datasheet.  For each system and seed (``numpy.random.default_rng([seed, crc32(name)])``:
every seed another machine and another noise), the machine's true parameters are the model's nominal
(datasheet) values times factors drawn uniform in [0.7, 1.3] on the system's ``faults`` parameters (those
whose 30 % change its step record shows; every uncertain parameter when it names none), the others at their
datasheet values.  The machine is simulated ONLY from the zoo's own physics, written by hand beside each
model and integrated by scipy (``tests/zoo/reference.py``), never by the library: the zoo's step inputs
played twice in a row, with the zoo's realistic sensor noise.  The first play is the training record:
:func:`diagnosis.estimate_parameters` fits the datasheet model on it (every parameter the record identifies;
``--fit perturbed``: only the case's ``faults``, as a user naming the uncertain ones would).  The second
play is the held-out record, never seen by the fit.

Per seed and estimated parameter: whether the truth lies inside the reported 95 % interval, the relative
error of the estimate, the interval's half-width relative to the truth.  A parameter the fit estimates as
part of a combination (another member kept at its datasheet value) is scored against the value that gives
the combination its true value: a scaling of its members along the group's direction that leaves every ARR
unchanged (a symmetry: ``b/J, k_m/J``, ``C_1*R_1, ...``) or a two-member expression; any
other combination whose kept member is off its datasheet value leaves its carriers unscored (``scored``
says how many seeds count).

Detection, before (the datasheet model with its datasheet boxes) and after (:meth:`ParameterEstimate.model`
with the ``confidence`` boxes of :func:`diagnosis.uncertainty_boxes`, each cut to its parameter's domain:
a model refuses a positive parameter's box that reaches below zero; ``boxes_cut`` counts them):
:func:`diagnosis.detect` with the library's defaults (forms, windows, ``k``, persistence) on the two plays
as one record, the calibration stretch being the training play.  The margins come from the record the
parameters were fitted on and judge the held-out play, as a machine commissioned on one run is then watched;
calibrated on the held-out record's own first part, the datasheet model's margins would absorb its own
error wherever that part resembles the rest.  That default use (``bgphm detect`` on the held-out play
alone, its first 20 % the stretch) is reported beside it (``false_alarm_own_stretch_*``).  A false alarm
is any ARR in alarm on the held-out play; a calibration stretch the detection refuses as not fault-free
(its split-half check) counts as one too, and apart (``refused_*``).  The library's own check of a
calibration, :func:`diagnosis.validate_calibration` (margins from the training play, one derivative window,
alarms after the held-out play's start-up), is reported beside them (``validation_*``).  The smallest
detectable changes are the detection's own (``Detection.smallest_changes``): per parameter, the smallest
relative change any ARR would detect on the held-out play at those margins; above 100 % (a blind ARR's
mark) it counts as 100 %.

Per system, over the seeds: the coverage of each parameter's interval (the share of the seeds in which
it was scored), the worst parameter's and those below 90 %, the mean and worst relative error (and per
parameter its bias, the mean signed error; ``miss``, the median of |error| / half-width: about 0.35
for intervals as wide as the errors' spread asks, above 1 for intervals that mostly miss; and
``toward_datasheet``, the share of the seeds whose error points from the truth towards the datasheet value:
a half when the fit is unbiased, near 1 when the prior or noisy regressors pull it back), the mean
(and median) relative half-width, the combinations reported, the false-alarm rates before/after, per drawn
parameter the mean smallest detectable change before/after and the share of seeds in which a 30 % change
is detectable (and ``lost_30%``: per drawn parameter, the seeds in which a 30 % change detectable before
calibration is not after), the CPU seconds.  The acceptance (issue 35): coverage >= 90 % of the identified
parameters, the non-identifiable ones reported as combinations, no false alarm after calibration and no
30 % change lost.  Nothing of the truth reaches the fit or the detection: the truth only scores them.
``--json`` prints one JSON object per system, one per line.

Systems (``--cases``, default :data:`DEFAULT_CASES`): the library's DC motor, its physics (two ODEs)
written here as a zoo case, and zoo models of six domains whose step records show a 30 % change of (almost)
every drawn parameter (docs/zoo.md's table): a buck converter, an RC ladder measured by its voltages only,
a transformer with a load (a combination of resistances), a pipe feeding a tank, two tanks through
orifices (a square-root law), a heat exchanger, a flywheel's speed loop with quadratic drag (a closed
loop), and a pump drive (its gear seen only through k_m/r_g, J/r_g**2 and b_m/r_g**2).  The other zoo
models run with ``--cases``: among them level_loop (an orifice whose law reaches the ARRs as
``Abs(Q/a)/a``), gas_accumulator (a gas law fitted through its numerator: its intervals miss), and
pressure_vessel_fill (the calibrated model raises false alarms where the orifice's noise gain grows as
the pressure difference closes: the detection's margin is one number for the whole record).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
import warnings
import zlib
from collections import Counter
from pathlib import Path

import numpy as np
import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bondgraph import PHMError, SettingError  # noqa: E402
from bondgraph.library import dc_motor  # noqa: E402
from diagnosis import (DetectionSettings, as_record, derive_arrs, detect, estimate_parameters,  # noqa: E402
                       uncertainty_boxes, validate_calibration)
from tests.zoo.case import ZooCase  # noqa: E402
from tests.zoo.chain import cases as zoo_cases  # noqa: E402
from tests.zoo.reference import record, simulate_reference  # noqa: E402

#: The default systems: one or two per domain, each excited by its step record (see the module docstring).
DEFAULT_CASES = ("dc_motor", "buck_averaged", "rc_ladder2", "transformer_load", "pipe_tank", "two_tank_orifice",
                 "heat_exchanger", "flywheel_speed_loop", "pump_drive")
#: The truth's factors on the drawn parameters: uniform in [1 - SPREAD, 1 + SPREAD].
SPREAD = 0.3
#: A change of this size should be detectable (issue 35: "the same faults are detected").
FAULT = 0.3
#: A smallest detectable change above this (the library's blind ARR) counts as this in the means.
BLIND = 1.0
#: Significant digits of the figures printed.
DIGITS = 4

# --------------------------------------------------------------------------------------------- the DC motor

_p_L, _p_J = sp.symbols("p_L p_J")          # flux linkage of the armature, angular momentum of the shaft
_U, _R_a, _L_a, _k_m, _J, _b, _t = sp.symbols("U R_a L_a k_m J b t")
_i, _omega = _p_L / _L_a, _p_J / _J

#: The library's permanent-magnet DC motor (``bondgraph.library.dc_motor``), its physics written here:
#: L_a di/dt = U - R_a i - k_m omega, J domega/dt = k_m i - b omega.  A voltage that steps up, down and
#: reverses excites the armature's (1 ms) and the shaft's (80 ms) dynamics.
DC_MOTOR = ZooCase(
    name="dc_motor",
    domain="mixed",
    source="bondgraph.library.dc_motor: armature circuit and shaft through k_m, two ODEs written here",
    build=dc_motor,
    states=(_p_L, _p_J),
    rhs=(_U - _R_a * _i - _k_m * _omega, _k_m * _i - _b * _omega),
    outputs={"i": _i, "omega": _omega},
    smooth_inputs={"U": 12 * sp.sin(2 * sp.pi * _t) * (1 - sp.exp(-_t / 0.05))},
    step_inputs={"U": ((0.0, 0.0), (0.05, 12.0), (0.6, 6.0), (1.0, -6.0), (1.5, 12.0))},
    t_end=2.0,
    dt=5e-4,
    noise={"i": 0.01, "omega": 0.2},
    faults=("R_a", "L_a", "J", "b"),
)


def all_cases() -> dict:
    """Name -> case: every zoo model and the DC motor."""
    return {c.name: c for c in [*zoo_cases(), DC_MOTOR]}


def played_twice(case: ZooCase) -> ZooCase:
    """The case with its step profile played twice in a row (``t_end`` doubled): a training play, a held-out
    one, the machine running on between them."""
    span = case.t_end
    profiles = {name: tuple(profile) + tuple((span + s, level) for s, level in profile)
                for name, profile in case.step_inputs.items()}
    return dataclasses.replace(case, step_inputs=profiles, t_end=2 * span)


# --------------------------------------------------------------------------------------------- one seed

def drawn(case: ZooCase, bg) -> tuple:
    """The parameters whose true values differ from the datasheet: the case's faults, else its uncertain ones."""
    return tuple(case.faults) or tuple(bg.uncertainties)


def targets(fit, truth: dict, arrs) -> dict:
    """Estimated parameter -> the value its estimate aims at (None: not written here, not scored).

    A parameter in no combination aims at its truth, and so does one whose combination's kept member (held
    at its datasheet value by the fit) is at its datasheet value in the truth too.  Otherwise the others
    carry the kept member's error: where the group's direction is a symmetry of every ARR that holds it
    (:func:`_symmetry`), they move along it until the kept member sits at its datasheet value; in a
    combination of two members, the carrier aims at the value that gives the expression its true value with
    the kept one at its datasheet value.
    """
    aim = {p: truth[p] for p in fit.estimated}
    for group in fit.identifiability.combinations:
        kept, members = group["kept"], group["parameters"]
        carriers = [m for m in members if m != kept and m in aim]
        if math.isclose(truth[kept], fit.datasheet[kept], rel_tol=1e-12) or not carriers:
            continue
        powers = _symmetry(arrs, group.get("direction", {}))
        if powers:
            for m in carriers:
                aim[m] = None if aim[m] is None else aim[m] * (fit.datasheet[kept] / truth[kept]) ** powers[m]
            continue
        aim.update(dict.fromkeys(carriers))  # unless the two-member expression below writes it
        if len(members) != 2 or len(carriers) != 1:
            continue
        (m,) = carriers
        try:
            formula = sp.sympify(group["expression"])
        except (sp.SympifyError, TypeError, SyntaxError):
            continue
        if not {sp.Symbol(m), sp.Symbol(kept)} <= formula.free_symbols:
            continue
        goal = float(formula.xreplace({sp.Symbol(p): v for p, v in truth.items()}))
        equation = formula.xreplace({**{sp.Symbol(p): v for p, v in truth.items() if p not in (m, kept)},
                                     sp.Symbol(kept): fit.datasheet[kept]}) - goal
        roots = [float(r) for r in sp.solve(equation, sp.Symbol(m)) if r.is_real]
        aim[m] = min(roots, key=lambda r: abs(r - truth[m])) if roots else None
    return aim


def _symmetry(arrs, direction: dict) -> dict:
    """The group's direction as exact powers, when every ARR that holds a member is unchanged but for a
    constant factor by scaling each member ``p`` to ``p * c**power`` (a symmetry: only the products of powers
    it leaves alone are seen); else {}."""
    powers = {m: sp.Rational(v).limit_denominator(4) for m, v in direction.items()}
    if not powers or any(abs(float(powers[m]) - v) > 1e-3 for m, v in direction.items()):
        return {}
    factor = sp.Dummy("c", positive=True)
    for arr in arrs:
        expression = arr.nominal
        if not expression.free_symbols & {sp.Symbol(m) for m in powers}:
            continue
        scaled = expression.xreplace({sp.Symbol(m): factor ** q * sp.Symbol(m) for m, q in powers.items()})
        if sp.simplify(scaled / expression).free_symbols - {factor}:
            return {}
    return {m: float(q) for m, q in powers.items()}


def detection(bg, record, until: float | None = None) -> dict:
    """Detection on ``record`` with margins from ``t <= until`` (default: the library's stretch): whether it
    raised a false alarm, the ARRs in alarm, the smallest detectable changes."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found = detect(bg, record, DetectionSettings(calibrate=until))
    except SettingError as exc:
        if exc.setting != "calibrate":
            raise
        return {"false_alarm": True, "refused": str(exc)[:200], "fired": [], "smallest": {}}
    return {"false_alarm": bool(found.fired), "refused": None, "fired": list(found.fired),
            "smallest": {p: float(v) for p, v in found.smallest_changes.items()}}


def one_seed(case: ZooCase, seed: int, fit_only: str = "all") -> dict:
    """Draw a machine, simulate it, fit the datasheet model on the training play, detect on the held-out one."""
    started = time.process_time()
    sheet = case.build()
    datasheet = dict(sheet.parameters)
    rng = np.random.default_rng([seed, zlib.crc32(case.name.encode())])
    chosen = drawn(case, sheet)
    factors = dict(zip(chosen, rng.uniform(1 - SPREAD, 1 + SPREAD, len(chosen)).tolist()))
    truth = {**datasheet, **{p: datasheet[p] * f for p, f in factors.items()}}
    run = simulate_reference(played_twice(case), parameters={p: truth[p] for p in chosen}, inputs="step", order=0)
    whole = as_record(record(run, noise=case.noise, seed=int(rng.integers(2**63))))
    training = whole.between(end=case.t_end - case.dt / 2)
    held_out = whole.between(start=case.t_end - case.dt / 2)
    row = {"seed": seed, "factors": factors, "parameters": {}, "combinations": [], "unseen": [], "cut": [],
           "error": None}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = estimate_parameters(sheet, [training], parameters=list(chosen) if fit_only == "perturbed" else None)
    except (PHMError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:  # reported per seed, not hidden
        row["error"] = f"{type(exc).__name__}: {exc}"[:300]
        row["cpu_s"] = time.process_time() - started
        return row
    aim = targets(fit, truth, derive_arrs(sheet))
    for p in fit.estimated:
        lo, hi = fit.intervals[p]
        goal = aim[p]
        row["parameters"][p] = {
            "inside": None if goal is None else bool(lo <= goal <= hi),
            "error": None if goal is None else fit.values[p] / goal - 1.0,
            # to the value aimed at (the estimate itself may sit at its domain's edge, near zero)
            "half_width": (hi - lo) / 2 / abs(goal if goal is not None else truth[p]),
            # an error towards the datasheet value (a prior's or an attenuation's mark), where the two differ
            "toward": None if goal is None or math.isclose(goal, fit.datasheet[p], rel_tol=1e-9)
            else bool((fit.values[p] - goal) * (fit.datasheet[p] - goal) > 0)}
    row["combinations"] = [f"{g['expression']} (kept {g['kept']})" for g in fit.identifiability.combinations]
    row["unseen"] = list(fit.identifiability.unseen)
    raw = uncertainty_boxes(fit)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        boxes = uncertainty_boxes(fit, model=sheet)  # each cut to its parameter's domain
    row["cut"] = [p for p in raw if raw[p] != boxes[p]]
    calibrated = fit.model(sheet, boxes)
    until = float(training.t[-1])
    for name, model in (("before", sheet), ("after", calibrated)):
        row[name] = detection(model, whole, until)
        # the library's default stretch on the held-out play alone (its first 20 %): for comparison
        row[f"{name}_own"] = detection(model, held_out)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        checked = validate_calibration(sheet, calibrated, [training], [held_out])
    for name, figures in (("before", checked.before), ("after", checked.after)):
        row[f"{name}_validation"] = {"false_alarm": bool(figures.false_alarms), "refused": None, "fired": [],
                                     "smallest": {p: float(v) for p, v in figures.smallest_changes.items()}}
    row["cpu_s"] = time.process_time() - started
    return row


# --------------------------------------------------------------------------------------------- over the seeds

def _mean(values) -> float | None:
    values = [v for v in values if v is not None]
    return float(np.mean(values)) if values else None


def _clean(value):
    """Plain JSON: a non-finite float becomes None, a float keeps :data:`DIGITS` significant digits."""
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, float):
        return float(f"{value:.{DIGITS}g}") if math.isfinite(value) else None
    return value


def _changes(rows: list[dict], when: str, chosen: list) -> dict:
    """Drawn parameter -> mean smallest detectable change (capped at BLIND), share within FAULT, blind seeds."""
    out = {}
    for p in chosen:
        seen = [r[when]["smallest"].get(p, math.inf) for r in rows if not r[when]["refused"]]
        out[p] = {"mean": _mean([min(v, BLIND) for v in seen]),
                  "within_fault": _mean([float(v <= FAULT) for v in seen]),
                  "blind": sum(v > BLIND for v in seen)}
    return out


def pooled(case: ZooCase, rows: list[dict]) -> dict:
    """The system's line: shares over the seeds, mean and worst (never best) of the per-seed figures."""
    fitted = [r for r in rows if r["error"] is None]
    names = list(dict.fromkeys(p for r in fitted for p in r["parameters"]))
    coverage, scored, errors, widths = {}, {}, {}, {}
    for p in names:
        seen = [r["parameters"][p] for r in fitted if p in r["parameters"]]
        inside = [s["inside"] for s in seen if s["inside"] is not None]
        coverage[p] = _mean([float(i) for i in inside])
        scored[p] = f"{len(inside)}/{len(seen)}"
        size = [abs(s["error"]) for s in seen if s["error"] is not None]
        # bias: the mean signed error; miss: the median of |error| / half-width (1 at the interval's edge, 0.35
        # for errors that a 95 % interval's normal spread would give)
        errors[p] = {"mean": _mean(size), "worst": max(size, default=None),
                     "bias": _mean([s["error"] for s in seen if s["error"] is not None]),
                     "miss": float(np.median([abs(s["error"]) / s["half_width"] for s in seen
                                              if s["error"] is not None and s["half_width"]]))
                     if any(s["error"] is not None and s["half_width"] for s in seen) else None,
                     "toward_datasheet": _mean([float(s["toward"]) for s in seen if s.get("toward") is not None])}
        widths[p] = _mean([s["half_width"] for s in seen])
    covered = {p: c for p, c in coverage.items() if c is not None}
    worst = min(covered, key=covered.get) if covered else None
    every = [abs(s["error"]) for r in fitted for s in r["parameters"].values() if s["error"] is not None]
    chosen = list(rows[0]["factors"]) if rows else []
    line = {
        "case": case.name, "domain": case.domain, "seeds": len(rows), "fitted": len(fitted),
        "errors": dict(Counter(r["error"] for r in rows if r["error"] is not None)),
        "drawn": chosen,
        "coverage": coverage, "scored": scored,
        "coverage_worst": None if worst is None else {"parameter": worst, "coverage": covered[worst]},
        "below_90pct": [p for p, c in covered.items() if c < 0.9],
        "relative_error_mean": _mean(every), "relative_error_worst": max(every, default=None),
        "relative_error": errors,
        "half_width_mean": _mean(widths.values()),
        "half_width_median": float(np.median([w for w in widths.values() if w is not None])) if widths else None,
        "half_width": widths,
        "combinations": dict(Counter(c for r in fitted for c in r["combinations"])),
        "unseen": sorted({p for r in fitted for p in r["unseen"]}),
        "boxes_cut": dict(Counter(p for r in fitted for p in r["cut"])),
    }
    for when in ("before", "after"):
        changes = _changes(fitted, when, chosen)
        line[f"false_alarm_{when}"] = _mean([float(r[when]["false_alarm"]) for r in fitted])
        line[f"refused_{when}"] = sum(bool(r[when]["refused"]) for r in fitted)
        line[f"fired_{when}"] = dict(Counter(a for r in fitted for a in r[when]["fired"]))
        line[f"smallest_change_mean_{when}"] = _mean(c["mean"] for c in changes.values())
        line[f"within_{FAULT:.0%}_{when}"] = _mean(c["within_fault"] for c in changes.values())
        line[f"smallest_change_{when}"] = changes
        line[f"false_alarm_own_stretch_{when}"] = _mean([float(r[f"{when}_own"]["false_alarm"]) for r in fitted])
        line[f"refused_own_stretch_{when}"] = sum(bool(r[f"{when}_own"]["refused"]) for r in fitted)
    # a change detectable before calibration and not after: lost (issue 35: "the same faults are detected")
    both = [r for r in fitted if not r["before"]["refused"] and not r["after"]["refused"]]
    lost = {p: sum(r["before"]["smallest"].get(p, math.inf) <= FAULT < r["after"]["smallest"].get(p, math.inf)
                   for r in both) for p in chosen}
    line[f"lost_{FAULT:.0%}"] = {p: n for p, n in lost.items() if n}
    for when in ("before", "after"):
        changes = _changes(fitted, f"{when}_validation", chosen)
        line[f"validation_false_alarm_{when}"] = _mean([float(r[f"{when}_validation"]["false_alarm"])
                                                        for r in fitted])
        line[f"validation_smallest_change_mean_{when}"] = _mean(c["mean"] for c in changes.values())
        line[f"validation_within_{FAULT:.0%}_{when}"] = _mean(c["within_fault"] for c in changes.values())
    line["cpu_s"] = round(sum(r["cpu_s"] for r in rows), 1)
    return _clean(line)


def bench(case: ZooCase, seeds: int, fit_only: str = "all") -> dict:
    """The system's line over seeds 0 .. seeds - 1."""
    return pooled(case, [one_seed(case, seed, fit_only) for seed in range(seeds)])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    known = all_cases()
    parser.add_argument("--cases", nargs="+", default=list(DEFAULT_CASES), choices=sorted(known), metavar="NAME",
                        help="zoo models (and dc_motor) to run; default: " + ", ".join(DEFAULT_CASES))
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--fit", choices=("all", "perturbed"), default="all",
                        help="estimate every parameter the records identify (default) or only the drawn ones")
    parser.add_argument("--json", action="store_true", help="one JSON object per system, one per line")
    args = parser.parse_args()
    for name in args.cases:
        line = bench(known[name], args.seeds, args.fit)
        if args.json:
            print(json.dumps(line), flush=True)
            continue
        worst = line["coverage_worst"] or {}
        within = f"within_{FAULT:.0%}"
        lost = ", ".join(f"{p} {n}" for p, n in line[f"lost_{FAULT:.0%}"].items()) or "none"
        print(f"{name} ({line['domain']}): fitted on {line['fitted']} of {line['seeds']} seeds, {line['cpu_s']} s CPU"
              f"{'; ' + '; '.join(line['errors']) if line['errors'] else ''}")
        print(f"  coverage: worst {worst.get('parameter')} {_pct(worst.get('coverage'))}, below 90 %: "
              f"{', '.join(line['below_90pct']) or 'none'}; |error| mean {_pct(line['relative_error_mean'])}, worst "
              f"{_pct(line['relative_error_worst'])}; half-width median {_pct(line['half_width_median'])}")
        for p, c in line["coverage"].items():
            print(f"    {p:10s} {'drawn' if p in line['drawn'] else '     '}  coverage {_pct(c)} ({line['scored'][p]})"
                  f"  |error| mean {_pct(line['relative_error'][p]['mean'])}"
                  f" worst {_pct(line['relative_error'][p]['worst'])}  bias {_pct(line['relative_error'][p]['bias'])}"
                  f"  half-width {_pct(line['half_width'][p])}  |error|/half-width median "
                  f"{_num(line['relative_error'][p]['miss'])}  towards the datasheet "
                  f"{_pct(line['relative_error'][p]['toward_datasheet'])}")
        for expression, count in line["combinations"].items():
            print(f"    combination {expression}: {count} seeds")
        print(f"  false alarms on the held-out play: {_pct(line['false_alarm_before'])} -> "
              f"{_pct(line['false_alarm_after'])} (refused {line['refused_before']} -> {line['refused_after']}); "
              f"with its own first 20 %: {_pct(line['false_alarm_own_stretch_before'])} -> "
              f"{_pct(line['false_alarm_own_stretch_after'])}")
        print(f"  smallest detectable change, mean: {_pct(line['smallest_change_mean_before'])} -> "
              f"{_pct(line['smallest_change_mean_after'])}; {FAULT:.0%} changes detectable "
              f"{_pct(line[within + '_before'])} -> {_pct(line[within + '_after'])}; lost (seeds): {lost}")
        for p in line["drawn"]:
            b, a = line["smallest_change_before"][p], line["smallest_change_after"][p]
            print(f"    {p:10s} {_pct(b['mean'])} -> {_pct(a['mean'])}")
        print(f"  validate_calibration: false alarms {_pct(line['validation_false_alarm_before'])} -> "
              f"{_pct(line['validation_false_alarm_after'])}; smallest change, mean "
              f"{_pct(line['validation_smallest_change_mean_before'])} -> "
              f"{_pct(line['validation_smallest_change_mean_after'])}; {FAULT:.0%} changes detectable "
              f"{_pct(line['validation_' + within + '_before'])} -> {_pct(line['validation_' + within + '_after'])}")
    return 0


def _num(value) -> str:
    return "-" if value is None else f"{value:.2f}"


def _pct(value) -> str:
    if value is None:
        return "-"
    return f"{value:.2%}" if abs(value) < 0.1 else f"{value:.0%}"


if __name__ == "__main__":
    sys.exit(main())
