"""examples/friction_drive.py, the friction drive of Rodriguez Obando et al. (2021): four scenarios, fast run."""

import json

import numpy as np
import pytest

from prognosis.lifecontrol import RULControlWarning
from tests.cases.conftest import load_example

pytestmark = pytest.mark.slow  # runs of an example script


@pytest.fixture(scope="module")
def fd():
    return load_example("friction_drive")


@pytest.fixture(scope="module")
def example_run(fd, tmp_path_factory):
    out = tmp_path_factory.mktemp("friction_drive")
    summary = fd.main(["--seeds", "1", "--speedup", "10", "--out", str(out), "--quiet"])
    return summary, json.loads((out / "results.json").read_text())


def test_example_runs_the_three_scenarios(example_run):
    summary, data = example_run
    assert "summary" in data and data["summary"]["seeds"] == 1
    assert data["summary"]["restarts_before_change"] == summary["restarts_before_change"] == 0
    seed = data["seeds"][0]
    assert seed["restart_h"] and seed["restart_h"][0] > 4.0  # restarted after the change of m at 4 h
    assert seed["box_coverage"]["before_change"] >= 0.95  # eqs. 37-43 with c = 10
    true_eol = seed["true_eol_h"]
    assert true_eol is not None
    assert seed["scenario_1"]["eol_mean_h"] > true_eol  # without restart the m change is missed: too late
    assert seed["controlled_true_eol_h"] is not None and seed["controlled_true_eol_h"] > true_eol
    assert seed["scenario_3"]["p_eol_before_8h"] <= 0.05 + 1e-9
    assert seed["scenario_3"]["omega2_star"] < 20.0
    # every decision of the controller is recorded with its status, and the fallbacks are counted
    decisions = seed["scenario_3"]["decisions"]
    statuses = {"converged", "not converged", "no feasible setting found", "mission met"}
    assert {d["status"] for d in decisions} <= statuses
    fallbacks = data["summary"]["controller_fallbacks"]
    assert fallbacks["decisions"] == sum(d["status"] != "mission met" for d in decisions) >= 1
    assert fallbacks["count"] == len(fallbacks["at"]) == sum(d["status"] not in ("converged", "mission met")
                                                            for d in decisions)
    assert data["settings"]["control"]["max_iterations"] == 60


def test_example_records_and_reports_each_decision_the_controller_did_not_converge_on(fd, monkeypatch):
    """A budget of one iteration cannot locate the boundary; the example applies the controller's
    fallback (the largest feasible theta met), records when and what, and prints it."""
    monkeypatch.setitem(fd.CONTROL, "max_iterations", 1)
    s = fd.Scenario().scaled(10)
    drive = fd.Drive(s, 0, twin=False)
    drive.run_until(s.control_start)
    with pytest.warns(RULControlWarning, match="did not converge in 1 iterations") as caught:
        decisions = fd.rul_control(drive, 0)
    fell_back = [d for d in decisions if d["status"] == "not converged"]
    assert fell_back and all(d["feasible"] and d["probability"] <= 0.05 for d in fell_back)
    assert len(caught) == len(fell_back)
    first_warning = str(caught[0].message)
    assert f"at t = {fell_back[0]['t_h'] * fd.HOUR / 10:g}:" in first_warning  # scenario seconds
    assert f"using theta = {fell_back[0]['theta']:.6g}" in first_warning
    fallbacks = fd.controller_fallbacks([{"seed": 0, "scenario_3": {"decisions": decisions}}])
    assert fallbacks["count"] == len(fell_back) and fallbacks["at"][0]["t_h"] == pytest.approx(5.0)
    line = fd.report_fallbacks(fallbacks)
    assert f"{len(fell_back)} of {fallbacks['decisions']} decisions fell back" in line
    assert "seed 0 at 5.00 h not converged, applied omega2* = " in line
    assert fd.report_fallbacks({"decisions": 3, "count": 0, "at": []}).endswith("(every decision converged)")


def test_example_scenario_2_predicts_after_the_restart(example_run):
    """Scenario 2 (section 6.2) is the prediction at 5.0 h *with* the EKF restarted after the m change."""
    _, data = example_run
    seed = data["seeds"][0]
    assert seed["restart_h"] and 4.0 < seed["restart_h"][0] < seed["scenario_2"]["origin_h"] == pytest.approx(5.0)


def test_scenario_4_truth_is_random_and_differs_between_seeds(fd):
    """Scenario 4 (m random): each seed draws its own m sequence and its own measurement noise."""
    s = fd.Scenario().scaled(10)
    drives = [fd.random_m_truth(seed, s) for seed in (0, 1)]
    for drive in drives:
        drive.run_until(3 * s.m_period)
    draws = [np.array([m for _, m, _ in drive.m_draws]) for drive in drives]
    assert [d.size for d in draws] == [4, 4]  # at 0 and after each of the 3 periods
    assert not np.allclose(draws[0], draws[1]) and np.ptp(draws[0]) > 0  # m changes, and not as the other seed
    floor = fd.RANDOM_M["floor_fraction"] * s.m_initial
    assert all(np.all(d >= floor) for d in draws)  # m stays positive
    noises = [drive.rng.standard_normal(3) for drive in drives]
    assert not np.allclose(noises[0], noises[1])
    assert not np.allclose(noises[0], fd.Drive(s, 0, twin=False).rng.standard_normal(3))  # apart from scenarios 1-3


def test_example_scenario_4_tracks_the_mean_of_a_random_m(fd, example_run):
    """The EKF, whose model keeps m constant, follows the mean of the random m and keeps D in its box."""
    summary, data = example_run
    s4 = data["seeds"][0]["scenario_4"]
    spread = s4["m_truth"]["relative_std"]
    assert s4["m_truth"]["draws"] >= 30 and spread > 0.5 * fd.RANDOM_M["std_fraction"]  # the truth does vary
    for window in ("before_change", "before_end"):
        assert s4["m_relative_error"][window]["vs_mean"] < spread  # closer to the mean than the draws are
    box = s4["box_coverage"]
    assert box["before_change"]["m_mean"] >= 0.95 and box["before_change"]["alpha"] >= 0.95
    for regime in ("before_change", "after_restart"):
        assert box[regime]["D"] >= 0.95  # eqs. 37-43 with c = 10
    assert s4["restarts_before_change"] == 0 and s4["restart_h"][0] > 4.0  # restarted after the mean changes
    assert s4["origin_h"] == pytest.approx(5.0) and s4["true_eol_h"] is not None
    assert summary["scenario_4"]["true_eol_h"]["n"] == 1
