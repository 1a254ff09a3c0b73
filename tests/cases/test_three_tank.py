"""The three-tank system of Du et al. (examples/three_tank.py): diagnosis and estimation."""

import json

import numpy as np
import pytest

from tests.cases.conftest import load_example

pytestmark = pytest.mark.slow  # runs of an example script


@pytest.fixture(scope="module")
def tank():
    return load_example("three_tank")


@pytest.fixture(scope="module")
def seed0(tank):
    return tank.run_seed(0, methods=("SCKF", "STSCKF", "STUKF", "EKF"), keep=True)


def test_simulation_follows_eq_61_through_the_bond_graph_model(tank):
    drift = tank.az2_drift()
    assert drift[9] == pytest.approx(0.6) and drift[10] == pytest.approx(0.6001)  # k = 10, 11
    assert drift[-1] == pytest.approx(0.6 + 1e-4 * 190 * 191 / 2)
    states, measured = tank.simulate_tanks(0)
    assert states.shape == (200, 4) and measured.shape == (200, 3)
    assert np.array_equal(states[:, 3], drift)
    assert np.all(states[:, :3] > 0)  # the tanks never run dry in the 200 steps
    assert np.std(measured - states[:, :3] / tank.AREA) == pytest.approx(tank.NOISE_STD, rel=0.1)
    again, _ = tank.simulate_tanks(0)
    assert np.array_equal(states, again)


def test_az2_drift_detected_by_its_own_arr_only(seed0):
    detection = seed0["detection"]
    assert {name: d["false_alarms_nominal"] for name, d in detection.items()} == {
        "ARR_0_1": 0, "ARR_0_2": 0, "ARR_0_3": 0}
    assert detection["ARR_0_1"]["detection_time_s"] is None and detection["ARR_0_3"]["detection_time_s"] is None
    # az2 must leave its +-5 % box plus the areas' +-2 %: az2 = 0.6 + 1e-4 (k - 10)(k - 9)/2 reaches +10 % near k = 45
    assert 35 <= detection["ARR_0_2"]["detection_time_s"] <= 55


def test_strong_tracking_predicts_the_drift_the_plain_filters_miss(seed0):
    methods = seed0["methods"]
    assert methods["STSCKF"]["mae"] < 0.5 * methods["SCKF"]["mae"]
    assert methods["STUKF"]["mae"] < 0.5 * methods["SCKF"]["mae"]
    assert methods["STSCKF"]["mae"] < 0.06
    # the look-ahead on ROS-ELM forecasts beats holding the filtered az2_k as the prediction of az2_{k+5}
    assert methods["STSCKF"]["mae"] < methods["STSCKF"]["held_mae"]
    assert methods["STSCKF"]["max_fading"] > 1.0 and methods["SCKF"]["max_fading"] == 1.0
    run = seed0["runs"]["STSCKF"]
    assert run.target[0] == 55 and run.target[-1] == 200 and run.origin[0] == 50


def test_elm_forecasts_track_the_levels(seed0):
    rmse = seed0["elm_rmse_by_step"]
    assert len(rmse) == 5 and rmse[0] < 1e-3 and rmse[-1] < 5e-3
    assert all(a < b for a, b in zip(rmse, rmse[1:]))  # errors grow with the horizon


@pytest.mark.extras   # the plots: matplotlib, the plot extra
def test_main_writes_the_table_and_plots(tank, tmp_path, capsys):
    summary = tank.main(["--seeds", "2", "--methods", "SCKF", "STSCKF", "STUKF", "PF", "--workers", "1", "--quiet",
                         "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "| STSCKF |" in out and "paper 'RMSE'" in out
    data = json.loads((tmp_path / "results.json").read_text())
    assert data["seeds"] == [0, 1] and len(data["per_seed"]) == 2
    assert set(data["table"]) == {"SCKF", "STSCKF", "STUKF", "PF"}
    for row in data["table"].values():
        assert row["rmse"] >= row["mae"] > 0 and row["rmse"] ** 2 <= row["mse"] * (1 + 1e-12) and row["seconds"] > 0
    # STSCKF and STUKF differ by about 1e-9 in every seed: a tie, printed and written as one
    groups = data["ranking_by_mae"]
    assert groups[-1][-1] == "SCKF" and sorted(sum(groups, [])) == ["PF", "SCKF", "STSCKF", "STUKF"]
    assert any({"STSCKF", "STUKF"} <= set(group) for group in groups)
    assert f"ranking by MAE: {data['ranking_by_mae_text']} (=:" in out and "STSCKF < STUKF" not in out
    assert data["ranking_by_mae_text"] == tank.format_ranking(groups) and data["not_ranked"] == []
    assert data["setting"]["ranking"] == {"rtol": 1e-3, "confidence": 0.95}
    assert summary["detection"]["ARR_0_2"]["detected_in"] == 2
    assert data["signature_matrix"]["az2"] == {"ARR_0_1": 0, "ARR_0_2": 1, "ARR_0_3": 0}
    rows = (tmp_path / "predictions.csv").read_text().splitlines()
    assert rows[0] == "k,az2_true,az2_SCKF,az2_STSCKF,az2_STUKF,az2_PF" and len(rows) == 1 + 146
    for name in ("fig00_detection.png", "fig01_elm_forecasts.png", "fig02_az2_prediction.png",
                 "fig03_fading_factor.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_unknown_method_is_named(tank):
    with pytest.raises(ValueError, match="'SCKFX'"):
        tank.estimator("SCKFX")
