"""Records: as_record's checks and copies, Record, gaps marked by NaN, noise."""


import numpy as np
import pytest

from diagnosis.derivatives import derivative
from diagnosis.records import Record, RecordError, add_noise, as_record

from tests.diagnosis.sample_records import DT, T, sine_record


# --- as_record: accepted input ---------------------------------------------------------------


def test_dict_is_copied_and_left_untouched():
    t = np.array([0.0, 0.1, 0.2, 0.3])
    x = np.array([1.0, np.nan, 3.0, 4.0])
    data = {"t": t, "x": x, "n": [1, 2, 3, 4]}
    record = as_record(data, name="run")
    assert record.signals == ("x", "n") and record.name == "run"
    assert record["n"].dtype == float and record["n"].tolist() == [1.0, 2.0, 3.0, 4.0]
    record["x"][0] = -1.0
    record.t[0] = -1.0
    assert x[0] == 1.0 and t[0] == 0.0 and np.isnan(x[1])
    assert set(data) == {"t", "x", "n"} and data["n"] == [1, 2, 3, 4]


def test_signals_select_columns_and_leave_others_unchecked():
    data = {"t": [0, 1, 2], "u": [1, 2, 3], "y": [4, 5, 6], "label": ["a", "b", "c"]}
    assert as_record(data, ["y"]).signals == ("y",)
    assert as_record(data, "u").signals == ("u",)  # one name, not its letters
    assert as_record(data, ["u", "y", "u"]).signals == ("u", "y")
    with pytest.raises(RecordError, match="'label'.*'a' at row 0"):
        as_record(data)


def test_record_is_accepted_and_copied():
    record = sine_record()
    again = as_record(record, name="again")
    assert again.name == "again" and np.array_equal(again["x"], record["x"])
    assert again["x"] is not record["x"]


class FakeFrame:
    """Enough of a DataFrame for duck typing: .columns and [] giving objects with to_numpy()."""

    class Column:
        def __init__(self, values):
            self.values = values

        def to_numpy(self):
            return np.array(self.values, dtype=object)

    def __init__(self, columns):
        self._data = columns
        self.columns = list(columns)

    def __getitem__(self, key):
        return self.Column(self._data[key])


def test_duck_typed_dataframe_without_pandas():
    frame = FakeFrame({"t": [0.0, 0.5, 1.0], "x": [1.0, 2.0, 3.0]})
    assert as_record(frame)["x"].tolist() == [1.0, 2.0, 3.0]
    frame = FakeFrame({"t": [0.0, 0.5, 1.0], "x": [1.0, "2.0", 3.0]})
    with pytest.raises(RecordError, match="column 'x'.*'2.0' at row 1"):
        as_record(frame)


@pytest.mark.slow
@pytest.mark.extras   # pandas
def test_pandas_dataframe():
    pd = pytest.importorskip("pandas")
    frame = pd.DataFrame({"t": [0.0, 0.1, 0.2, 0.3], "x": [1.0, np.nan, 3.0, 4.0], "k": ["a", "b", "c", "d"]})
    before = frame.copy()
    record = as_record(frame, ["x"])
    record["x"][0] = 99.0
    assert record.gaps("x") == [(0.1, 0.1)]
    pd.testing.assert_frame_equal(frame, before)
    with pytest.raises(RecordError, match="column 'k'.*'a' at row 0"):
        as_record(frame)


# --- as_record: errors ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("data", "signals", "message"),
    [
        ({"time": [0, 1, 2], "x": [1, 2, 3]}, (), r"missing column\(s\) \['t'\]; columns present: \['time', 'x'\]"),
        ({"t": [0, 1, 2], "x": [1, 2, 3]}, ["x", "y", "z"], r"missing column\(s\) \['y', 'z'\].*\['t', 'x'\]"),
        ({"t": [0, 1, 2], "x": [1.0, "oops", 3.0]}, (), r"column 'x' has a non-numeric value 'oops' at row 1"),
        ({"t": [0, 1, 2], "x": [1.0, 2.0, True]}, (), r"column 'x' has a non-numeric value True at row 2"),
        ({"t": [0, 1, 2], "x": np.array([True, False, True])}, (), r"column 'x'.*True at row 0"),
        ({"t": [0, 1, 2], "x": [1.0, None, 3.0]}, (), r"column 'x'.*None at row 1"),
        ({"t": [0, 1, 2], "x": [1.0, [2.0], 3.0]}, (), r"column 'x'.*\[2.0\] at row 1"),
        ({"t": [0, 1, "2"], "x": [1, 2, 3]}, (), r"column 't'.*'2' at row 2"),
        ({"t": [0, 1, 2], "x": 7.0}, (), r"column 'x' must be one-dimensional"),
        ({"t": [0, 1, 2, 3], "x": [1, 2, 3], "y": [1, 2, 3, 4]}, (),
         r"different lengths: 't' has 4 samples, 'x' has 3"),
        ({"t": [0.0, 0.1, 0.2, 0.2], "x": [1, 2, 3, 4]}, (),
         r"'t' is not strictly increasing: t\[3\] = 0.2 follows t\[2\] = 0.2"),
        ({"t": [0.0, 0.3, 0.2], "x": [1, 2, 3]}, (),
         r"'t' is not strictly increasing: t\[2\] = 0.2 follows t\[1\] = 0.3"),
        ({"t": [0.0, np.nan, 0.2], "x": [1, 2, 3]}, (), r"column 't' has a non-finite value nan at row 1"),
        ({"t": [0.0, 0.1, np.inf], "x": [1, 2, 3]}, (), r"column 't' has a non-finite value inf at row 2"),
        ({"t": [0.0, 0.1], "x": [1, 2]}, (), r"column 't' has 2 samples; at least 3"),
        ({"t": [0.0, 0.1, 0.2], "x": [1.0, -np.inf, 3.0]}, (),
         r"column 'x' has an infinite value -inf at row 1 \(t = 0.1\)"),
        ({"t": [0, 1, 2], "x": [1, 2, 3]}, ["t"], r"'t' is the time column"),
        ({"t": [0.0, 0.1, 0.2], "x": [1.0, -1e200, 3.0]}, (),
         r"column 'x' has a value -1e\+200 at row 1 \(t = 0.1\) larger in magnitude than 1e\+150 \(MAX_MAGNITUDE\)"),
        ({"t": [0.0, 0.1, 1e300], "x": [1.0, 2.0, 3.0]}, (), r"column 't' has a value 1e\+300 at row 2"),
    ],
)
def test_bad_records_are_refused_with_the_column_named(data, signals, message):
    with pytest.raises(RecordError, match=message):
        as_record(data, signals)


def test_not_a_table():
    with pytest.raises(RecordError, match="expected a mapping or a DataFrame"):
        as_record([[0, 1, 2], [1, 2, 3]])


def test_nan_in_a_signal_is_a_gap():
    record = as_record({"t": np.arange(8.0), "x": [0, np.nan, np.nan, 3, 4, np.nan, 6, np.nan]})
    assert record.gaps("x") == [(1.0, 2.0), (5.0, 5.0), (7.0, 7.0)]


# --- Record ---------------------------------------------------------------------------------


def test_record_step_uniformity_and_lookup():
    record = sine_record()
    assert record.dt == pytest.approx(DT) and record.is_uniform and len(record) == T.size
    assert record["t"] is record.t and "x" in record and "t" in record and "y" not in record
    assert record.gaps("x") == []
    uneven = as_record({"t": [0.0, 1.0, 2.0, 3.5], "x": [0, 0, 0, 0]})
    assert uneven.dt == 1.0 and not uneven.is_uniform
    with pytest.raises(RecordError, match=r"no signal 'y'; signals: \['x'\]"):
        record["y"]
    with pytest.raises(RecordError, match="no signal 'y'"):
        record.gaps("y")


# --- noise ----------------------------------------------------------------------------------


def test_add_noise_is_deterministic_with_the_requested_std():
    n = 100_000
    t = np.arange(n) * 1e-3
    record = as_record({"t": t, "x": np.zeros(n), "y": np.ones(n), "z": np.zeros(n)}, name="clean")
    noisy = add_noise(record, {"z": 0.05, "x": 0.2}, seed=7)
    again = add_noise(record, {"x": 0.2, "z": 0.05}, seed=7)
    other = add_noise(record, {"x": 0.2, "z": 0.05}, seed=8)
    assert isinstance(noisy, Record) and noisy.name == "clean"
    assert np.array_equal(noisy["x"], again["x"]) and np.array_equal(noisy["z"], again["z"])
    assert not np.array_equal(noisy["x"], other["x"])
    assert np.std(noisy["x"]) == pytest.approx(0.2, rel=0.02)
    assert np.std(noisy["z"]) == pytest.approx(0.05, rel=0.02)
    assert abs(np.mean(noisy["x"])) < 0.01
    assert np.array_equal(noisy["y"], record["y"]) and noisy["y"] is not record["y"]
    assert np.array_equal(noisy.t, record.t)
    assert not record["x"].any()  # the given record is untouched


def test_add_noise_keeps_gaps_and_refuses_unknown_signals():
    record = as_record({"t": [0, 1, 2, 3], "x": [0, np.nan, 0, 0]})
    noisy = add_noise(record, {"x": 1.0}, seed=0)
    assert noisy.gaps("x") == [(1.0, 1.0)]
    with pytest.raises(RecordError, match=r"no signal\(s\) \['q', 't'\].*signals: \['x'\]"):
        add_noise(record, {"q": 0.1, "t": 0.1, "x": 0.1}, seed=0)
    with pytest.raises(RecordError, match="std of signal 'x' must be a finite number >= 0, got -0.1"):
        add_noise(record, {"x": -0.1}, seed=0)


def test_a_value_beyond_max_magnitude_is_refused_in_signal_arrays_too():
    # 1e308 used to pass and overflow the residual, leaving its samples silently undecided
    with pytest.raises(RecordError, match=r"column 'v' has a value 1e\+308 at row 1 .*MAX_MAGNITUDE"):
        derivative([0.0, 1.0, 2.0], [0.0, 1e308, 0.0], method="central", name="v")
    assert as_record({"t": [0, 1, 2], "x": [1e150, -1e150, 0.0]})["x"][0] == 1e150  # the limit itself is fine
