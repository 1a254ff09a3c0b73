"""examples/gearbox.py, the gearbox of Gasperin et al. (2011), on a short record."""

import json

import pytest

from tests.cases.conftest import load_example

pytestmark = pytest.mark.slow  # runs of an example script


def test_gearbox_example_smoke(tmp_path):
    """examples/gearbox.py on a 90 h record (one seed): results.json figures in sensible bands."""
    gearbox = load_example("gearbox")
    summary = gearbox.main(["--hours", "90", "--seeds", "1", "--out", str(tmp_path), "--quiet"])
    payload = json.loads((tmp_path / "results.json").read_text())
    assert {"setting", "true_models", "summary", "per_seed", "run_seconds"} <= set(payload)
    assert payload["setting"]["posterior"]["direct_inputs"] == [1]  # the temperature acts through D only
    seed = payload["per_seed"][0]
    assert {"detection_time_h", "detection_delay_h", "alarm_before_onset", "max_radius_before_onset",
            "predictions", "seconds"} <= set(seed)
    assert set(seed["predictions"]) == {"44h", "78h"}
    assert not seed["alarm_before_onset"] and seed["max_radius_before_onset"] < 1.0
    before, after = seed["predictions"]["44h"], seed["predictions"]["78h"]
    assert not before["fault_trend"] and abs(before["constant_load_change"]) < 0.1  # predicted stable at 44 h
    assert after["horizon_h"] == pytest.approx(12.0 - 1 / 12)  # the record ends at 89.92 h
    for p in (before, after):
        assert 0.0 <= p["coverage"] <= 1.0
        assert p["oracle_coverage"] > 0.8  # the true model's interval is calibrated (nominal 95 %)
        assert p["posterior"]["coverage_by_lead"]["0-1h"] >= 0.5  # fine one hour ahead
    assert before["coverage_by_lead"]["0-1h"] >= 0.5  # the identified model too, before the fault
    assert before["coverage_before_onset"] > 0.5
    # the posterior predictive over the window's parameters: stable before the fault, calibrated before the onset
    for p in (before["posterior"], after["posterior"]):
        assert 0.0 <= p["coverage"] <= 1.0 and 0.0 <= p["probability_unstable"] <= 1.0
        low, median, high = p["spectral_radius_quantiles"]
        assert low <= median <= high and p["interval_half_width_end"] > 0
        assert 0.0 <= p["true_radius_rank"] <= 1.0
    assert before["posterior"]["probability_unstable"] < 0.05 and before["posterior"]["coverage_before_onset"] > 0.8
    assert after["posterior"]["spectral_radius_quantiles"][2] > before["posterior"]["spectral_radius_quantiles"][2]
    assert summary["of"] == 1 and summary["alarms_before_onset"] == 0
    if (tmp_path / "fig00_record.png").exists():  # matplotlib is optional
        assert {p.name for p in tmp_path.glob("fig*.png")} == {
            "fig00_record.png", "fig01_spectral_radius.png", "fig02_prediction_44h.png", "fig03_prediction_78h.png"}
