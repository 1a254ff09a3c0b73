"""Sensor faults injected into a record (diagnosis.records): bias, drift and gain from an onset, then noise."""

import numpy as np
import pytest

from diagnosis import Record, RecordError, SensorFault, add_noise, add_sensor_faults, as_record

T = np.linspace(0.0, 4.0, 401)


def true_record() -> Record:
    x = 100.0 + 5.0 * np.sin(3.0 * T)
    x[50:53] = np.nan                                   # a gap stays a gap
    return as_record({"t": T, "x": x, "y": np.cos(T)}, name="bench")


@pytest.mark.parametrize("kind, size, formula", [
    ("bias", 2.5, lambda t, x: x + 2.5),
    ("drift", 0.75, lambda t, x: x + 0.75 * (t - 1.5)),
    ("gain", 1.05, lambda t, x: 1.05 * x),
])
def test_each_fault_reads_its_formula_from_the_onset_on(kind, size, formula):
    record = true_record()
    kept = record["x"].copy()
    faulty = add_sensor_faults(record, [SensorFault("x", kind, size, onset=1.5)])
    after = T >= 1.5
    np.testing.assert_array_equal(faulty["x"][~after], kept[~after])
    np.testing.assert_allclose(faulty["x"][after], formula(T[after], kept[after]), rtol=1e-15)
    assert faulty.gaps("x") == record.gaps("x")
    assert np.array_equal(faulty["y"], record["y"]) and np.array_equal(faulty.t, record.t)
    assert np.array_equal(record["x"], kept, equal_nan=True)           # the given record is untouched
    assert faulty.name == "bench"


def test_faults_of_one_sensor_add_up_with_the_gain_first():
    record = true_record()
    faults = [SensorFault("x", "drift", 0.5, onset=2.0), SensorFault("x", "bias", -1.0, onset=1.0),
              SensorFault("x", "gain", 0.9, onset=3.0)]
    x = record["x"]
    expected = np.where(T >= 3.0, 0.9 * x, x) + np.where(T >= 1.0, -1.0, 0.0) + np.where(T >= 2.0, 0.5 * (T - 2.0), 0)
    np.testing.assert_allclose(add_sensor_faults(record, faults)["x"], expected, rtol=1e-14)
    assert np.array_equal(add_sensor_faults(record, faults[::-1])["x"], add_sensor_faults(record, faults)["x"],
                          equal_nan=True)                                # the order given does not matter


def test_noise_after_the_faults_is_the_same_draws_as_without_them():
    record = true_record()
    faults = [SensorFault("x", "bias", 3.0, onset=1.0), SensorFault("y", "gain", 2.0)]
    faulty = add_sensor_faults(record, faults)
    noisy_faulty = add_noise(faulty, {"x": 0.2, "y": 0.1}, seed=4)
    noisy = add_noise(record, {"x": 0.2, "y": 0.1}, seed=4)
    for signal in ("x", "y"):
        np.testing.assert_allclose(noisy_faulty[signal] - faulty[signal], noisy[signal] - record[signal], atol=1e-12)
        assert np.nanstd(noisy_faulty[signal] - faulty[signal]) > 0.05


@pytest.mark.parametrize("fault, message", [
    (lambda: SensorFault("x", "offset", 1.0), "sensor 'x': unknown fault 'offset' (expected one of bias, drift, gain)"),
    (lambda: SensorFault("x", "bias", float("nan")), "sensor 'x': the size of its bias must be a finite number"),
    (lambda: SensorFault("x", "gain", True), "the size of its gain must be a finite number, got True"),
    (lambda: SensorFault("x", "drift", 1.0, onset=float("inf")), "the onset of its drift must be a finite number"),
    (lambda: SensorFault("x", "bias", "2"), "the size of its bias must be a finite number, got '2'"),
])
def test_a_bad_fault_is_refused_naming_the_sensor(fault, message):
    with pytest.raises(RecordError) as error:
        fault()
    assert message in str(error.value)


def test_a_fault_of_a_signal_the_record_lacks_is_refused():
    with pytest.raises(RecordError, match=r"bench: no signal\(s\) \['z'\] for a sensor fault; signals: \['x', 'y'\]"):
        add_sensor_faults(true_record(), [SensorFault("z", "bias", 1.0)])
