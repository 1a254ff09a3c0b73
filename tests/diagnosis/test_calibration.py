"""The healthy stretch: its end, the margins and noise it gives, the split-half check, the settings' checks."""

import numpy as np
import pytest

from bondgraph import SettingError, simulate
from bondgraph.library import rlc_circuit
from diagnosis.calibration import stays_in_alarm
from diagnosis.detection import CalibrationError
from diagnosis import (DetectionSettings, add_noise, as_record, calibrate, calibration_end, derive_arrs,
                       pooled_calibration)

NOISE = 2e-4  # current sensor noise, A


def rlc_record(seed: int, fault_at: float | None = None, noise: float = NOISE, faulty: float = 14.0):
    """The RLC loop driven by a sine, 2 s at 1 kHz, R stepping from 10 ohm to ``faulty`` at ``fault_at``."""
    bg = rlc_circuit()
    t = np.linspace(0.0, 2.0, 2001)
    parameters = {} if fault_at is None else {"R": lambda t: 10.0 if t < fault_at else faulty}
    run = simulate(bg, (0.0, 2.0), {"V": lambda t: 1.0 + np.sin(20 * t)}, t_eval=t, parameters=parameters)
    return add_noise(as_record(run.record()), {"i": noise}, seed=seed)


@pytest.fixture(scope="module")
def arrs():
    return derive_arrs(rlc_circuit())


@pytest.mark.parametrize("settings, setting", [
    ({"persistence": 0}, "persistence"), ({"persistence": 2.5}, "persistence"), ({"margin": -1.0}, "margin"),
    ({"margin": float("nan")}, "margin"), ({"k": 0.0}, "k"), ({"k": float("inf")}, "k"),
    ({"calibrate": float("nan")}, "calibrate"), ({"window": 4}, "window"), ({"window": 1}, "window"),
])
def test_bad_settings_are_refused_naming_the_setting(settings, setting):
    with pytest.raises(SettingError) as caught:
        DetectionSettings(**settings)
    assert caught.value.setting == setting and str(caught.value).startswith(setting)


def test_the_default_stretch_is_a_fifth_and_a_bad_one_is_named():
    record = rlc_record(0)
    assert calibration_end(record) == pytest.approx(0.4)
    with pytest.raises(SettingError, match=r"^calibrate 2: at or past the end of the record \(t = 2 s\)"):
        calibration_end(record, 2.0)
    with pytest.raises(SettingError, match=r"calibrate 0.01: only 11 samples before it; at least 20"):
        calibration_end(record, 0.01)


def test_margins_are_k_times_the_residual_noise_on_a_healthy_record(arrs):
    healthy = calibrate(arrs, rlc_record(1), DetectionSettings(calibrate=0.8, k=4.0))
    assert healthy.until == 0.8 and [e.name for e in healthy.evaluations] == [a.name for a in arrs]
    for arr in arrs:
        # the same robust spread, of the residual on the stretch alone and within the record
        assert healthy.margin[arr.name] == pytest.approx(4.0 * healthy.noise_std[arr.name], rel=0.1)
        assert healthy.evaluations[[a.name for a in arrs].index(arr.name)].detection_time is None
    loop = healthy.noise_std["ARR_J1"]
    louder = calibrate(arrs, rlc_record(1, noise=4 * NOISE), DetectionSettings(calibrate=0.8))
    assert louder.noise_std["ARR_J1"] == pytest.approx(4 * loop, rel=0.1)  # the residual is linear in the noise


def test_a_stretch_holding_a_fault_is_refused_naming_the_arr(arrs):
    record = rlc_record(2, fault_at=0.6)
    with pytest.raises(SettingError, match=r"calibrate 1 is not fault-free: .*ARR_J1 is in alarm from t = ") as caught:
        calibrate(arrs, record, DetectionSettings(calibrate=1.0))
    assert "give a shorter calibrate (or a fixed margin)" in str(caught.value)
    assert caught.value.naming(lambda s: "--" + s).startswith("--calibrate 1 is not fault-free")
    healthy = calibrate(arrs, record, DetectionSettings(calibrate=0.5))  # before the fault: taken, and it fires
    assert 0.6 <= healthy.evaluations[0].detection_time < 0.62
    fixed = calibrate(arrs, record, DetectionSettings(calibrate=1.0, margin=0.05))  # a fixed margin: not checked
    assert fixed.margin["ARR_J1"] == 0.05


def test_a_fleet_pools_the_median_and_names_the_asset_at_fault(arrs):
    records = [(f"m{i}", rlc_record(10 + i, noise=NOISE * scale)) for i, scale in enumerate((1.0, 2.0, 8.0))]
    pooled, first = pooled_calibration(arrs, records, DetectionSettings(calibrate=0.8))
    alone = calibrate(arrs, records[1][1], DetectionSettings(calibrate=0.8))
    assert pooled.noise_std == alone.noise_std and pooled.margin == alone.margin  # the median asset's
    assert first is records[0][1]
    bad = records + [("m9", rlc_record(20, fault_at=0.5))]
    with pytest.raises(SettingError, match=r"^asset 'm9': calibrate 0.8 is not fault-free"):
        pooled_calibration(arrs, bad, DetectionSettings(calibrate=0.8))


def test_a_fault_starting_where_the_stretch_ends_is_not_held_against_it(arrs):
    """The derivative window of the stretch's last samples reads past its end: a fault starting there shows a
    few samples early, in estimates that are not the stretch's own."""
    record = rlc_record(3, fault_at=1.0, faulty=100.0)
    healthy = calibrate(arrs, record, DetectionSettings(calibrate=1.0, persistence=1))
    assert 0.99 <= healthy.evaluations[0].detection_time < 1.0  # seen a few samples early, the stretch kept


def test_only_an_alarm_that_stays_marks_a_fault():
    t = np.arange(10.0)
    assert stays_in_alarm(np.zeros(10, bool), t) is None
    assert stays_in_alarm(np.array([1, 1, 1, 0, 0, 0, 0, 0, 0, 0], bool), t) is None  # a transient that ends
    assert stays_in_alarm(np.array([0, 0, 0, 0, 0, 0, 1, 1, 1, 1], bool), t) == 6.0  # a fault that stays


def test_an_arr_the_stretch_gives_no_residual_for_is_left_out_and_named(arrs):
    """The source voltage's logger starts only after the stretch: the ARR reading it cannot be calibrated, so it
    is left out (as detect leaves it out), the other calibrated as before."""
    record = rlc_record(4)
    late = record.columns["V"].copy()
    late[record.t <= 0.8] = np.nan
    waking = as_record({"t": record.t, **{**record.columns, "V": late}})
    reading = {a.name for a in arrs if "V" in a.signals}
    assert reading and reading != {a.name for a in arrs}
    healthy = calibrate(arrs, waking, DetectionSettings(calibrate=0.8))
    assert set(healthy.undecided) == reading and set(healthy.margin) == {a.name for a in arrs} - reading
    assert all("fewer than 2 finite residual values" in why for why in healthy.undecided.values())
    pooled, _ = pooled_calibration(arrs, [("a1", waking), ("a2", waking)], DetectionSettings(calibrate=0.8))
    assert set(pooled.undecided) == reading and set(pooled.noise_std) == set(healthy.noise_std)
    dead = as_record({"t": record.t, **{name: np.full(record.t.size, np.nan) for name in record.columns}})
    with pytest.raises(CalibrationError, match="no ARR gives a residual on the healthy stretch"):
        calibrate(arrs, dead, DetectionSettings(calibrate=0.8))
