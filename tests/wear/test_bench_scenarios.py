"""benchmarks/bench_scenarios.py cut by seeds: the runs of two sweeps pooled as one (no scenario is run here)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_scenarios.py"
SPEC = importlib.util.spec_from_file_location("bench_scenarios", PATH)
bench_scenarios = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(bench_scenarios)

NAME = "pipe_tank/R_f/linear/clean"


def a_run(seed: int, predictions: int, coverage: float, ra: float) -> dict:
    return {"scenario": NAME, "seed": seed, "filter": "resample-move", "pairs": None, "found": True,
            "status": "indistinguishable", "degradation": "linear", "top": "R_f/linear", "predictions": predictions,
            "withheld": 0, "within_20pct_second_half": 1.0, "coverage_90": coverage, "coverage_50": 0.5, "ra": ra,
            "pit": [[0, 1, 0, 0, 0, 0]] * 4, "cpu_s": 1.0}


def test_runs_of_two_sweeps_pool_as_one_each_run_once(tmp_path):
    first, second = tmp_path / "first.jsonl", tmp_path / "second.jsonl"
    first.write_text("\n".join(json.dumps(a_run(s, 10, 1.0, 0.9)) for s in (1, 2)) + "\n")
    # the second sweep ran seed 2 again (an interrupted sweep resumed) and seed 3, with 30 predictions
    second.write_text(json.dumps(a_run(2, 10, 1.0, 0.9)) + "\n\n" + json.dumps(a_run(3, 30, 0.0, 0.5)) + "\n")
    runs = bench_scenarios.read_runs([first, second])
    assert sorted(r["seed"] for r in runs) == [1, 2, 3]
    line = bench_scenarios.pooled(NAME, runs)
    # pooled over the predictions, not the seeds: 20 of 50 covered; the worst seed's RA, not the best
    assert line["seeds"] == 3 and line["coverage_90"] == pytest.approx(0.4)
    assert line["ra_worst"] == 0.5 and line["ra_mean"] == pytest.approx(2.3 / 3)


def test_a_line_that_is_no_run_names_its_file_and_line(tmp_path):
    path = tmp_path / "runs.jsonl"
    path.write_text(json.dumps(a_run(1, 10, 1.0, 0.9)) + "\n" + json.dumps({"scenario": NAME}) + "\n")
    with pytest.raises(ValueError, match=r"runs.jsonl:2: not a run printed by --runs \(no 'seed'\)"):
        bench_scenarios.read_runs([path])


def test_a_mistyped_scenario_is_refused_not_left_out(monkeypatch, capsys):
    monkeypatch.setattr("sys.argv", ["bench_scenarios.py", NAME, NAME + "x"])
    with pytest.raises(SystemExit) as stop:
        bench_scenarios.main()
    assert stop.value.code == 2 and f"no scenario '{NAME}x'" in capsys.readouterr().err
