"""benchmarks/bench_calibration.py on one small zoo model and two seeds: the shape and sanity of its figures
(not their values, which the benchmark reports), and how it scores a parameter that carries a combination."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import SimpleNamespace

import pytest
import sympy as sp

PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_calibration.py"
SPEC = importlib.util.spec_from_file_location("bench_calibration", PATH)
bench_calibration = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(bench_calibration)


def share(value) -> bool:
    return value is None or 0.0 <= value <= 1.0


@pytest.mark.slow   # a whole benchmark line: 4 s of the fast tier's budget
def test_one_system_over_two_seeds_gives_a_complete_line():
    case = bench_calibration.all_cases()["flywheel_speed_loop"]
    rows = [bench_calibration.one_seed(case, seed) for seed in (0, 1)]
    # seeds that really differ: another machine, another noise
    assert rows[0]["factors"] != rows[1]["factors"]
    assert all(1 - bench_calibration.SPREAD <= f <= 1 + bench_calibration.SPREAD
               for r in rows for f in r["factors"].values())
    assert bench_calibration.one_seed(case, 1)["factors"] == rows[1]["factors"]  # and reproducible
    line = bench_calibration.pooled(case, rows)
    json.loads(json.dumps(line, allow_nan=False))  # plain JSON, no NaN or infinity
    assert line["case"] == "flywheel_speed_loop" and line["seeds"] == 2 and line["fitted"] == 2
    assert line["drawn"] == list(case.faults)
    assert set(case.faults) <= set(line["coverage"])  # every drawn parameter is estimated and scored
    assert all(share(c) for c in line["coverage"].values())
    assert line["coverage_worst"]["coverage"] == min(c for c in line["coverage"].values() if c is not None)
    assert line["relative_error_worst"] >= line["relative_error_mean"] >= 0
    assert all(w > 0 for w in line["half_width"].values())
    for p, figures in line["relative_error"].items():
        assert abs(figures["bias"]) <= figures["mean"] <= figures["worst"] and figures["miss"] >= 0, p
        assert share(figures["toward_datasheet"]), p
    assert all(line["relative_error"][p]["toward_datasheet"] is not None for p in case.faults)
    for when in ("before", "after"):
        assert share(line[f"false_alarm_{when}"]) and share(line[f"false_alarm_own_stretch_{when}"])
        assert share(line[f"validation_false_alarm_{when}"]) and share(line[f"validation_within_30%_{when}"])
        assert 0 < line[f"validation_smallest_change_mean_{when}"] <= bench_calibration.BLIND
        assert set(line[f"smallest_change_{when}"]) == set(case.faults)
        for figures in line[f"smallest_change_{when}"].values():
            assert 0 < figures["mean"] <= bench_calibration.BLIND and share(figures["within_fault"])
    assert set(line["lost_30%"]) <= set(case.faults) and all(0 < n <= 2 for n in line["lost_30%"].values())
    assert line["cpu_s"] > 0


def fit(values: dict, combinations: list) -> SimpleNamespace:
    """What targets() reads of a ParameterEstimate: the datasheet, the estimated names, the combinations."""
    kept = {c["kept"] for c in combinations}
    return SimpleNamespace(datasheet=values, estimated=[p for p in values if p not in kept],
                           identifiability=SimpleNamespace(combinations=combinations))


def arr(text: str) -> SimpleNamespace:
    x = sp.Function("x")(sp.Symbol("t"))
    return SimpleNamespace(nominal=sp.sympify(text, locals={"x": x, "dx": x.diff(sp.Symbol("t"))}))


def test_a_combination_carrier_is_scored_against_the_value_that_gives_the_combination_its_truth():
    datasheet = {"J_m": 1.0, "J_i": 8.0, "n_g": 2.0, "b": 0.1}
    truth = {"J_m": 1.5, "J_i": 8.0, "n_g": 2.0, "b": 0.2}
    arrs = [arr("(J_m + J_i/n_g**2)*dx + b*x - 3")]
    summed = {"parameters": ["J_m", "J_i"], "kept": "J_m", "expression": "-J_i/n_g**2 - J_m"}
    aim = bench_calibration.targets(fit(datasheet, [summed]), truth, arrs)
    # J_m held at 1.0 instead of 1.5: J_i / 4 carries the 0.5, so J_i aims at 10
    assert aim["J_i"] == pytest.approx(10.0) and aim["b"] == 0.2
    assert bench_calibration.targets(fit(datasheet, [summed]), dict(truth, J_m=1.0), arrs)["J_i"] == 8.0
    # a relation homogeneous in its group: only the ratios are seen, and b scales with J_m's error
    scaling = {"parameters": ["J_m", "J_i", "b"], "kept": "J_m", "expression": "J_i/J_m, b/J_m",
               "direction": {"J_m": 1.0, "J_i": 1.0, "b": 1.0}}
    homogeneous = [arr("(J_m + J_i/n_g**2)*dx + b*x")]
    aim = bench_calibration.targets(fit(datasheet, [scaling]), truth, homogeneous)
    assert aim["b"] == pytest.approx(0.2 / 1.5) and aim["J_i"] == pytest.approx(8.0 / 1.5)
    # the same group where the ARR is not homogeneous in it: the aim is not written, the carriers not scored
    aim = bench_calibration.targets(fit(datasheet, [scaling]), truth, arrs)
    assert aim["b"] is None and aim["J_i"] is None and aim["n_g"] == 2.0
    # a symmetry with powers: C up and R down alike leave C*dx + x/R unchanged but for a factor
    ladder = {"parameters": ["C", "R"], "kept": "R", "expression": "C*R", "direction": {"R": 1.0, "C": -1.0}}
    aim = bench_calibration.targets(fit({"C": 1.0, "R": 2.0}, [ladder]), {"C": 1.2, "R": 2.5},
                                    [arr("C*dx + x/R")])
    assert aim["C"] == pytest.approx(1.2 * 2.5 / 2.0)  # R held 20 % low: C carries the product C*R = 3
