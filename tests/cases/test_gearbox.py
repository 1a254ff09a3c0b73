"""examples/gearbox.py, the gearbox of Gasperin et al. (2011), on a short record."""

import json

import numpy as np
import pytest

from tests.cases.conftest import load_example


@pytest.fixture(scope="module")
def gearbox():
    return load_example("gearbox")


def test_divergence_flags_impossible_predictions_only(gearbox):
    """A negative sideband energy or an overflow is a failure; growth, however fast, is a fault trend."""
    leads = np.arange(504)
    growing = 1.0 + 0.05 * 1.003 ** leads  # the true damage pole: admissible
    assert gearbox.divergence(growing, np.full(504, 1.0)) is None
    # an unstable complex pair: an oscillation of growing amplitude that swings below zero
    swinging = 1.0 + 1.011 ** leads * np.cos(0.006 * leads + 1.0)
    reason = gearbox.divergence(np.full(504, 1.0), swinging)
    assert reason is not None and reason.startswith("below FEATURE_MIN")
    assert gearbox.divergence(np.array([1.0, np.nan])) == "non-finite"
    assert gearbox.divergence(np.array([1.0, np.inf])) == "non-finite"
    assert gearbox.divergence(np.array([gearbox.FEATURE_MIN])) is None  # the bound itself is admissible


def test_change_statistics_leave_out_and_name_the_divergent_windows(gearbox):
    """The statistics of the change are over the admissible windows; the divergent ones are counted by seed."""
    changes = [9.5, 14.7, -429.3, 13.9, 43.4]
    reasons = [None, None, "below FEATURE_MIN (min -428)", None, "non-finite"]
    rows = [{"constant_load_change": c, "divergent": r} for c, r in zip(changes, reasons)]
    out = gearbox.change_statistics(rows, [10, 11, 12, 13, 14])
    kept = [9.5, 14.7, 13.9]
    assert (out["n"], out["of"], out["divergent"], out["divergent_seeds"]) == (3, 5, 2, [12, 14])
    assert out["median"] == pytest.approx(np.median(kept)) and out["mean"] == pytest.approx(np.mean(kept))
    assert (out["min"], out["max"]) == (min(kept), max(kept))
    text = gearbox._change_text(out)
    assert "over 3 of 5 windows" in text and "2 divergent windows (seeds 12, 14)" in text
    none_left = gearbox.change_statistics(rows[2:3], [12])
    assert none_left["n"] == 0 and none_left["median"] is None and none_left["divergent_seeds"] == [12]
    assert "no admissible window" in gearbox._change_text(none_left)
    clean = gearbox.change_statistics(rows[:2], [10, 11])
    assert clean["divergent"] == 0 and "divergent" not in gearbox._change_text(clean)


@pytest.mark.slow  # a run of the example script
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
    assert before["divergent"] is None  # a stable model's prediction stays a possible energy
    for name, entry in payload["summary"]["predictions"].items():
        change = entry["constant_load_change"]
        assert change["n"] + change["divergent"] == change["of"] == 1
        assert change["divergent_seeds"] == ([0] if seed["predictions"][name]["divergent"] else [])
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
