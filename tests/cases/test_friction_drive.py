"""examples/friction_drive.py, the friction drive of Rodriguez Obando et al. (2021): three scenarios, fast run."""

import json

import pytest

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


def test_example_scenario_2_predicts_after_the_restart(example_run):
    """Scenario 2 (section 6.2) is the prediction at 5.0 h *with* the EKF restarted after the m change."""
    _, data = example_run
    seed = data["seeds"][0]
    assert seed["restart_h"] and 4.0 < seed["restart_h"][0] < seed["scenario_2"]["origin_h"] == pytest.approx(5.0)
