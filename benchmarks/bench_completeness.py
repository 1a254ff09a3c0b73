"""Acceptance table of issue 36: per model, what the structure allows and what the derived ARRs reach.

For each model (the library's three_tank, torsion_bar, dc_motor and friction_drive, every zoo model, the
tank cascades of bench_arrs at 3 and 5 tanks with a level sensor on every tank and on every other one, and at 4
tanks measured at its two ends, an RC ladder of 5 sections and a mass-spring chain of 5 stages): its equations,
fault candidates and minimal structurally overdetermined (MSO) sets ("over limit" past ``MSO_SEARCH_LIMIT``);
the ARRs ``derive_arrs`` gives with the defaults and with ``max_order=None``; the ordered fault pairs the
structure can isolate (``StructuralModel.isolability``) and those the ARRs of each setting reach (the
structural pairs less ``unreached(...)["isolate"]``); the faults the structure detects and no ARR sees; the
ARRWarning messages that say why (distinct, in the order given); and the CPU seconds (``time.process_time``)
of each ``derive_arrs``.  Where ``max_order=None`` leaves pairs, the same with ``simulated=True`` (simulation
residuals for the sets no closed form realises), with no order bound and with the default one.  A model that
raises, or runs over ``--timeout`` seconds, gets its error in its row.

    python benchmarks/bench_completeness.py                  # a markdown table, then the warnings per model
    python benchmarks/bench_completeness.py --json           # one JSON object per model per line
    python benchmarks/bench_completeness.py three_tank cascade_3   # only the models named
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import time
import traceback
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_arrs import rc_ladder, sparse_tank_cascade, tank_cascade  # noqa: E402
from bondgraph.library import dc_motor, friction_drive, mass_spring_chain, three_tank, torsion_bar  # noqa: E402
from diagnosis import ARRWarning, derive_arrs  # noqa: E402
from diagnosis.elimination import arr_from_set, faults_of_arr, unreached  # noqa: E402
from diagnosis.structural import StructuralLimitError, structural_model  # noqa: E402
from tests.zoo.chain import cases  # noqa: E402

#: The settings of derive_arrs compared: the defaults, and no bound on the derivative order; then, where that
#: leaves pairs, with the sets no closed form realises simulated (``simulated=True``).
SETTINGS = {"default": {}, "max_order=None": {"max_order": None}}
SIMULATED = {"simulated": {"max_order": None, "simulated": True}, "simulated (default order)": {"simulated": True}}

#: Up to this many MSO sets, each is eliminated on its own (``arr_from_set``) to say of the pairs left with
#: ``max_order=None`` whether a closed-form MSO set tells them apart (the search missed it) or none does.
CLOSED_FORM_LIMIT = 20


class _OverTime(BaseException):   # not caught by an `except Exception` on the way
    pass


def models() -> dict:
    """Name -> builder (no argument), in the order of the table."""
    found = {"three_tank": three_tank, "torsion_bar": torsion_bar, "dc_motor": dc_motor,
             "friction_drive": friction_drive}
    found.update({case.name: case.build for case in cases()})
    for n in (3, 5):
        found[f"cascade_{n}"] = lambda n=n: tank_cascade(n)
        found[f"cascade_sparse_{n}"] = lambda n=n: sparse_tank_cascade(n)
    found["cascade_ends_4"] = lambda: tank_cascade(4, every=3)   # levels 1 and 4 measured
    found["rc_ladder_5"] = lambda: rc_ladder(5)
    found["chain_5"] = lambda: mass_spring_chain(5)
    return found


def _derive(build, options: dict) -> tuple:
    """ARRs of a fresh model, CPU seconds, what stays unreached, the distinct ARRWarning messages."""
    bg = build()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        start = time.process_time()
        arrs = derive_arrs(bg, **options)
        seconds = time.process_time() - start
        left = unreached(bg, arrs)
    messages = list(dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, ARRWarning)))
    return arrs, seconds, left, messages


def measure(name: str, build) -> dict:
    """One row of the table; an exception (or the time limit) is put in ``error``, with the figures found so far."""
    row: dict = {"model": name}
    try:
        model = structural_model(build())
        row.update(equations=len(model.equations), faults=len(model.faults))
        try:
            row["mso_sets"] = len(model.mso_sets())
        except StructuralLimitError:
            row["mso_sets"] = "over limit"
        detectable = model.detectable()
        pairs = sum(len(v) for v in model.isolability().values())
        row.update(detectable=len(detectable), isolable_pairs=pairs)
        for setting, options in SETTINGS.items():
            arrs, seconds, left, messages = _derive(build, options)
            row[setting] = {"arrs": len(arrs), "cpu_seconds": round(seconds, 3),
                            "pairs_reached": pairs - len(left["isolate"]), "undetected": left["detect"],
                            "warnings": messages}
        for setting, options in SIMULATED.items() if left["isolate"] or left["detect"] else ():
            # what simulation residuals add (nothing where max_order=None leaves nothing)
            arrs, seconds, left_simulated, messages = _derive(build, options)
            row[setting] = {"arrs": len(arrs), "simulation_arrs": sum(a.form == "simulation" for a in arrs),
                            "cpu_seconds": round(seconds, 3), "pairs_reached": pairs - len(left_simulated["isolate"]),
                            "undetected": left_simulated["detect"], "warnings": messages}
        if left["isolate"] and isinstance(row["mso_sets"], int) and row["mso_sets"] <= CLOSED_FORM_LIMIT:
            row["left_pairs"] = _left_pairs(build, left["isolate"])
    except _OverTime as exc:
        row["error"] = str(exc)
    except Exception as exc:   # reported in the row: the table goes on
        row["error"] = f"{type(exc).__name__}: {exc}"
        row["traceback"] = traceback.format_exc(limit=-3)
    return row


def _left_pairs(build, pairs: list) -> dict:
    """Of the pairs ``max_order=None`` leaves: how many some closed-form MSO set tells apart (``by_closed_form``:
    the search missed them) and how many none does; why the sets without a closed form have none."""
    bg = build()
    model = structural_model(bg)
    supports, reasons = [], {}
    for rows in model.mso_sets():
        try:
            supports.append(faults_of_arr(model, arr_from_set(bg, rows, model=model)))
        except ValueError as exc:   # "{set}: why", the why counted
            why = str(exc).rsplit("}: ", 1)[-1]
            reasons[why] = reasons.get(why, 0) + 1
    closable = [(a, b) for a, b in pairs if any(a in s and b not in s for s in supports)]
    return {"left": len(pairs), "by_closed_form": len(closable), "examples": [list(p) for p in pairs[:3]],
            "closed_form_sets": len(supports), "without_closed_form": reasons}


def _cells(row: dict) -> list:
    def setting(key, field, show=str):
        return show(row[key][field]) if key in row else "-"
    reached = [setting(key, "pairs_reached") for key in SETTINGS]
    return [row["model"], str(row.get("equations", "-")), str(row.get("faults", "-")), str(row.get("detectable", "-")),
            str(row.get("mso_sets", "-")),
            setting("default", "arrs"), setting("max_order=None", "arrs"), str(row.get("isolable_pairs", "-")),
            reached[0], reached[1],
            setting("default", "undetected", lambda v: ", ".join(v) or "0"),
            setting("max_order=None", "undetected", lambda v: ", ".join(v) or "0"),
            setting("default", "cpu_seconds"), setting("max_order=None", "cpu_seconds"), _left_cell(row),
            *(_simulated_cell(row, key) for key in SIMULATED), row.get("error", "")]


def _simulated_cell(row: dict, key: str) -> str:
    if key not in row:
        return "-" if "max_order=None" not in row else "(nothing left)"
    sim = row[key]
    return (f"{sim['pairs_reached']} pairs, {len(sim['undetected'])} undetected, {sim['simulation_arrs']} simulated "
            f"ARRs, {sim['cpu_seconds']} s")


def _left_cell(row: dict) -> str:
    if "left_pairs" not in row:
        return "-"
    left = row["left_pairs"]
    return (f"{left['left']} left, {left['by_closed_form']} of them told apart by a closed-form MSO set "
            f"({left['closed_form_sets']} of {row['mso_sets']} sets have one)")


HEADER = ["model", "equations", "faults", "detectable", "MSO sets", "ARRs", "ARRs (max_order=None)", "isolable pairs",
          "pairs reached", "pairs reached (max_order=None)", "undetected", "undetected (max_order=None)", "CPU s",
          "CPU s (max_order=None)", "pairs left (max_order=None)", "simulated=True (max_order=None)",
          "simulated=True (default order)", "error"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", metavar="NAME", help="only these models (default: all)")
    parser.add_argument("--json", action="store_true", help="one JSON object per model per line")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds (wall clock) allowed per model")
    args = parser.parse_args()
    table = models()
    unknown = [name for name in args.names if name not in table]
    if unknown:
        parser.error(f"unknown model(s) {', '.join(unknown)}; known: {', '.join(table)}")
    names = args.names or list(table)

    def over_time(signum, frame):
        raise _OverTime(f"over the time limit of {args.timeout:g} s")

    signal.signal(signal.SIGALRM, over_time)
    rows = []
    for name in names:
        signal.setitimer(signal.ITIMER_REAL, args.timeout)
        try:
            row = measure(name, table[name])
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        rows.append(row)
        if args.json:
            print(json.dumps(row), flush=True)
    if args.json:
        return
    print("| " + " | ".join(HEADER) + " |")
    print("|" + "---|" * len(HEADER))
    for row in rows:
        print("| " + " | ".join(cell.replace("|", "\\|") for cell in _cells(row)) + " |")
    print()
    for row in rows:
        said = [(key, m) for key in SETTINGS if key in row for m in row[key]["warnings"]]
        why = row.get("left_pairs", {}).get("without_closed_form", {})
        if said or why:
            print(f"- {row['model']}:")
            for key, message in said:
                print(f"  - ({key}) {message}")
            for reason, count in why.items():
                print(f"  - {count} MSO set(s) without a closed form: {reason}")


if __name__ == "__main__":
    main()
