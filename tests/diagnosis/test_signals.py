"""Recorded signals: validation, Savitzky-Golay and central derivatives, integrals, gaps, noise."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diagnosis.csv_reading import read_csv
from diagnosis.derivatives import cumulative_integral, default_window, derivative
from diagnosis.records import Record, RecordError, RecordWarning, add_noise, as_record
from diagnosis.uniform_grid import resample

DT = 0.01
T = np.arange(0.0, 10.0 + DT / 2, DT)


def sine_record(**extra):
    return as_record({"t": T, "x": np.sin(T), **extra}, name="sine")


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


# --- derivatives ----------------------------------------------------------------------------


def test_savgol_first_derivative_of_sine():
    half = default_window() // 2
    error = np.abs(derivative(sine_record(), "x") - np.cos(T))
    assert error[half:-half].max() < 1e-6
    assert error.max() < 1e-4


def test_savgol_second_derivative_of_sine():
    # a cubic fit gives second derivatives to O(window^2): ~(5 dt)^2 / 10
    half = default_window() // 2
    error = np.abs(derivative(sine_record(), "x", order=2) + np.sin(T))
    assert error[half:-half].max() < 5e-4
    assert error.max() < 1e-3


def test_savgol_is_exact_for_polynomials_within_polyorder():
    t = np.linspace(-1.0, 2.0, 31)
    assert np.allclose(derivative(t, t**3 - t, order=1), 3 * t**2 - 1, atol=1e-10)
    assert np.allclose(derivative(t, t**3 - t, order=2), 6 * t, atol=1e-8)
    assert np.allclose(derivative(t, t**5, order=1, window=7, polyorder=5), 5 * t**4, atol=1e-8)


def test_default_window():
    assert default_window() == 11
    assert default_window(9) == 11
    assert default_window(10) == 13
    assert default_window(11) == 13


def uneven_grid(n):
    s = np.linspace(0.0, 3.0, n)
    return s + 0.1 * np.sin(3 * s)  # smooth map, steps vary by ~30 %


def central_errors(order, exact, sizes=(101, 201, 401)):
    """Max error of central differences of sin on finer and finer uneven grids, end samples apart."""
    interior, ends = [], []
    for n in sizes:
        t = uneven_grid(n)
        error = np.abs(derivative(t, np.sin(t), order=order, method="central") - exact(t))
        interior.append(error[2:-2].max())
        ends.append(max(error[:2].max(), error[-2:].max()))
    return np.array(interior), np.array(ends)


def convergence_rates(errors):
    return np.log2(errors[:-1] / errors[1:])


def test_central_first_derivative_on_uneven_grid_is_second_order():
    interior, ends = central_errors(1, np.cos)
    assert np.all(convergence_rates(interior) > 1.9), interior
    assert np.all(convergence_rates(ends) > 1.9), ends
    assert max(interior[-1], ends[-1]) < 1e-4


def test_central_second_derivative_on_uneven_grid():
    # applying np.gradient twice: second order inside, first order in the end samples
    interior, ends = central_errors(2, lambda t: -np.sin(t))
    assert np.all(convergence_rates(interior) > 1.9), interior
    assert np.all(convergence_rates(ends) > 0.9), ends
    assert interior[-1] < 1e-4 and ends[-1] < 1e-2


def test_central_differences_are_exact_for_quadratics_on_any_grid():
    t = np.cumsum(np.random.default_rng(0).uniform(0.01, 0.1, 50))
    x = 2 * t**2 - 3 * t + 1
    assert np.allclose(derivative(t, x, method="central"), 4 * t - 3, atol=1e-9)
    assert np.allclose(derivative(t, x, order=2, method="central"), 4.0, atol=1e-7)


def test_central_differences_leave_a_gaps_own_sample_unknown_on_exactly_equal_steps_too():
    """numpy's formula for exactly equal steps gives the middle sample weight 0; the gap must not depend on it."""
    exact, rounded = np.arange(21) * 0.5, np.linspace(0.0, 1.0, 21)
    assert np.all(np.diff(exact) == 0.5) and not np.all(np.diff(rounded) == np.diff(rounded)[0])
    for t in (exact, rounded):
        x = t.copy()
        x[10] = np.nan
        assert np.flatnonzero(np.isnan(derivative(t, x, method="central"))).tolist() == [9, 10, 11]
        assert np.flatnonzero(np.isnan(derivative(t, x, order=2, method="central"))).tolist() == [8, 9, 10, 11, 12]


def test_savgol_refuses_uneven_sampling_and_suggests_central():
    t = uneven_grid(101)
    with pytest.raises(RecordError, match=r"'v'.*uniform sampling.*method='central'.*diagnosis.resample\(record\) "
                                          r"\(bgphm: --resample\)"):
        derivative(t, np.sin(t), name="v")


def test_savgol_refuses_a_record_shorter_than_the_window():
    record = as_record({"t": np.arange(9.0), "p": np.arange(9.0)})
    with pytest.raises(RecordError, match="'p' has 9 samples, fewer than the Savitzky-Golay window of 11"):
        derivative(record, "p")
    assert np.allclose(derivative(record, "p", window=5), 1.0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"method": "spline"}, "'x': unknown method 'spline'"),
        ({"order": 0}, "'x': derivative order must be an integer >= 1, got 0"),
        ({"order": 1.5}, "'x': derivative order"),
        ({"order": 4}, "'x': polyorder must be an integer >= the derivative order 4"),
        ({"window": 10}, "'x': window must be an odd number of samples > polyorder 3, got 10"),
        ({"window": 3}, "'x': window must be an odd number"),
        ({"exact": np.zeros(T.size)}, "'x': exact= is only used with method='exact'"),
        ({"method": "exact"}, "'x': method='exact' needs the derivative as exact="),
        ({"method": "exact", "exact": np.zeros(5)}, "exact derivative of x' has 5 samples, 't' has 1001"),
    ],
)
def test_bad_derivative_settings(kwargs, message):
    with pytest.raises(RecordError, match=message):
        derivative(sine_record(), "x", **kwargs)


def test_exact_derivative_is_a_checked_float_copy():
    known = [int(v) for v in np.round(np.cos(T))]
    d = derivative(sine_record(), "x", method="exact", exact=known)
    assert d.dtype == float and d.tolist() == [float(v) for v in known]
    with pytest.raises(RecordError, match="infinite value inf at row 2"):
        derivative(sine_record(), "x", method="exact", exact=[0.0, 0.0, np.inf] + [0.0] * (T.size - 3))


def test_signal_arrays_are_checked_against_the_record():
    record = sine_record()
    with pytest.raises(RecordError, match="signal 'w' has 3 samples, 't' has 1001"):
        derivative(record, [1.0, 2.0, 3.0], name="w")
    with pytest.raises(RecordError, match="'w' has a non-numeric value 'a' at row 0"):
        cumulative_integral(record, ["a"] * T.size, name="w")
    with pytest.raises(RecordError, match="'x' given by name, but no Record"):
        derivative(T, "x")
    assert np.array_equal(derivative(record, np.sin(T)), derivative(record, "x"))


# --- gaps -----------------------------------------------------------------------------------


def with_gap(x, start, stop):
    x = x.copy()
    x[start:stop] = np.nan
    return x


def test_savgol_gap_is_nan_within_half_a_window_and_exact_elsewhere():
    half = default_window() // 2
    clean = derivative(T, np.sin(T))
    gapped = derivative(T, with_gap(np.sin(T), 500, 503))
    nan = np.isnan(gapped)
    assert np.array_equal(np.flatnonzero(nan), np.arange(500 - half, 503 + half))
    assert np.allclose(gapped[~nan], clean[~nan], rtol=0, atol=1e-12)


def test_savgol_runs_shorter_than_the_window_are_nan():
    x = np.sin(T)
    x[[100, 110]] = np.nan  # a run of 9 samples between them
    x[[300, 320]] = np.nan  # a run of 19 samples: 9 of them far enough from both gaps
    d = derivative(T, x)
    assert np.all(np.isnan(d[95:116]))
    assert np.array_equal(np.flatnonzero(~np.isnan(d[295:326])) + 295, np.arange(306, 315))


def test_savgol_gap_at_the_record_ends():
    half = default_window() // 2
    clean = derivative(T, np.sin(T))
    d = derivative(T, with_gap(with_gap(np.sin(T), 0, 3), T.size - 2, T.size))
    assert np.all(np.isnan(d[: 3 + half])) and np.all(np.isnan(d[-2 - half:]))
    assert np.allclose(d[3 + half: -2 - half], clean[3 + half: -2 - half], rtol=0, atol=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_central_gap_is_nan_where_the_stencil_touches_it(order):
    t = uneven_grid(200)
    clean = derivative(t, np.sin(t), order=order, method="central")
    gapped = derivative(t, with_gap(np.sin(t), 100, 102), order=order, method="central")
    nan = np.isnan(gapped)
    assert np.array_equal(np.flatnonzero(nan), np.arange(100 - order, 102 + order))
    assert np.array_equal(gapped[~nan], clean[~nan])


def savgol_stencil(i, n, window):
    """Samples the full-record Savitzky-Golay value at i uses (scipy mode='interp')."""
    start = min(max(i - window // 2, 0), n - window)
    return slice(start, start + window)


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(11, 60),
    nan_rows=st.sets(st.integers(0, 59), max_size=6),
    window=st.sampled_from([5, 7, 11]),
)
def test_nan_exactly_where_the_stencil_touches_a_gap(n, nan_rows, window):
    t = 0.5 + 0.1 * np.arange(n)
    x = np.cos(2 * t) + t**2
    gapped = x.copy()
    gapped[[i for i in nan_rows if i < n]] = np.nan
    clean_d = derivative(t, x, window=window)
    d = derivative(t, gapped, window=window)
    for i in range(n):
        touches = np.isnan(gapped[savgol_stencil(i, n, window)]).any()
        assert np.isnan(d[i]) == touches, i
        if not touches:
            assert d[i] == pytest.approx(clean_d[i], abs=1e-9)


def test_integral_of_a_polynomial_on_an_uneven_grid():
    t = uneven_grid(301)
    assert np.allclose(cumulative_integral(t, 3 * t + 1), 1.5 * t**2 + t - (1.5 * t[0] ** 2 + t[0]), atol=1e-12)
    # trapezoid error for t^2 is exactly sum(h^3)/6 over the steps taken
    y = cumulative_integral(t, t**2)
    h = np.diff(t)
    error = y - (t**3 - t[0] ** 3) / 3
    assert error[0] == 0.0
    assert np.allclose(error[1:], np.cumsum(h**3) / 6, rtol=1e-9, atol=1e-14)


def test_integral_is_nan_from_a_gap_on_with_a_warning():
    record = as_record({"t": T, "i": with_gap(np.cos(T), 250, 260)})
    clean = cumulative_integral(T, np.cos(T))
    with pytest.warns(RecordWarning, match=r"integral of 'i' is unknown from t = 2\.5 on"):
        y = cumulative_integral(record, "i")
    assert np.array_equal(y[:250], clean[:250])
    assert np.all(np.isnan(y[250:]))


def test_integral_without_gap_does_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        y = cumulative_integral(sine_record(), "x")
    assert y[0] == 0.0 and abs(y[-1] - (1 - np.cos(T[-1]))) < 1e-4


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


# --- read_csv -------------------------------------------------------------------------------


def write(tmp_path, text, name="run.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_read_csv_ignores_a_text_column_it_does_not_read_with_one_warning(tmp_path):
    path = write(tmp_path, "t,x,label,note,y\n0,1,a,,5\n1,2,b,ok,6\n2,3,c,1,7\n")
    with pytest.warns(RecordWarning) as caught:
        record = read_csv(path, ["x"])
    assert record.signals == ("x",) and record["x"].tolist() == [1.0, 2.0, 3.0]
    assert len(caught) == 1  # one warning for every such column; 'y' is numeric, so not named
    assert str(caught[0].message) == (f"{path}: columns 'label', 'note' are not numeric and not among the signals "
                                      "read: ignored")
    with pytest.warns(RecordWarning, match=r"column 'label' is not numeric"):
        read_csv(write(tmp_path, "t,x,label\n0,1,a\n1,2,b\n2,3,c\n"), "x")


def test_read_csv_numeric_columns_it_does_not_read_are_not_checked(tmp_path):
    path = write(tmp_path, "t,x,big\n0,1,1e300\n1,2,inf\n2,3,\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_csv(path, ["x"]).signals == ("x",)
    with pytest.raises(RecordError, match=r"line 2, column 'big': '1e300' is larger in magnitude than 1e\+150"):
        read_csv(path)  # every column is read by default


def test_read_csv_text_in_a_column_it_reads_stays_an_error(tmp_path):
    path = write(tmp_path, "t,x,y\n0,1,1\n1,2,b\n2,3,3\n")
    with pytest.raises(RecordError, match=r"run.csv line 3, column 'y': 'b' is not a number$"):
        read_csv(path, ["x", "y"])
    with pytest.raises(RecordError, match=r"line 3, column 'y': 'b' is not a number"):
        read_csv(path)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("t;x\n0;1\n1;2\n2;3\n", r"line 1: the file seems to be separated by ';', but read_csv expects commas"),
        ("t\tx\n0\t1\n1\t2\n2\t3\n", r"line 1: the file seems to be separated by tabs, but read_csv expects commas"),
        ("t|x\n0|1\n1|2\n2|3\n", r"line 1: the file seems to be separated by '\|'"),
        ("t,x\n0,1\n1;2\n2,3\n", r"line 3: 1 cells for 2 columns, as if separated by ';', but read_csv expects commas"),
        ("t,x\n0,1\n1,2,3\n2,3\n", r"line 3: 3 cells for 2 columns$"),
        ("t,x\n0,1_000\n1,2\n2,3\n", r"line 2, column 'x': '1_000' is not a number \(digit separators such as '_' "
                                     r"are not allowed\)"),
        ("t,x\n0,1\n1,\u0661\u0662\n2,3\n", r"line 3, column 'x': '\u0661\u0662' is not a number$"),
        ("t,x\n0,1\n1,0x10\n2,3\n", r"line 3, column 'x': '0x10' is not a number"),
        ("t,x\n0,1\n1,1e308\n2,3\n", r"line 3, column 'x': '1e308' is larger in magnitude than 1e\+150 "
                                     r"\(MAX_MAGNITUDE\): the residuals would overflow"),
        ("t,x\n0,1\n1e200,2\n2e200,3\n", r"line 3, column 't': '1e200' is larger in magnitude"),
        ("t,x\n0,1\n1,-Infinity\n2,3\n", r"line 3, column 'x': '-Infinity' is infinite \(leave the cell empty"),
        ("t,x\n0,1\n1,1e999\n2,3\n", r"line 3, column 'x': '1e999' is infinite"),
    ],
)
def test_read_csv_bad_files_name_file_line_and_column(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(RecordError, match=r"run.csv " + message):
        read_csv(path)


def test_read_csv_number_formats_and_gaps(tmp_path):
    path = write(tmp_path, "t,x\n0, 1.5e-3 \n1,.5\n2,3.\n3,-nan\n4,NA\n5,+2E+2\n")
    assert read_csv(path)["x"].tolist()[:3] == [1.5e-3, 0.5, 3.0]
    assert np.isnan(read_csv(path)["x"][3:5]).all() and read_csv(path)["x"][5] == 200.0


# --- resample -------------------------------------------------------------------------------


def test_resample_puts_an_uneven_record_on_its_median_step():
    t = uneven_grid(201)
    record = as_record({"t": t, "x": 2.0 * t + 1.0, "y": t**2}, name="jittery")
    assert not record.is_uniform
    uniform = resample(record)
    assert uniform.is_uniform and uniform.name == "jittery" and uniform.signals == ("x", "y")
    assert uniform.dt == pytest.approx(record.dt) and uniform.t[0] == t[0] and uniform.t[-1] <= t[-1]
    assert np.allclose(uniform["x"], 2.0 * uniform.t + 1.0)  # linear interpolation is exact for lines
    assert np.all(uniform["y"] >= uniform.t**2 - 1e-15)  # and overestimates a convex function
    # the savgol estimator refused the record; it takes the resampled one
    assert np.allclose(derivative(uniform, "x"), 2.0)


def test_resample_never_interpolates_across_a_gap():
    record = as_record({"t": np.arange(0.0, 1.01, 0.1), "x": [0, 1, 2, np.nan, 4, 5, 6, 7, 8, 9, 10]})
    out = resample(record, 0.05)
    # grid times 0.25 .. 0.35 touch the NaN sample at 0.3; 0.2 and 0.4 fall on samples and keep them
    nan_times = np.round(out.t[np.isnan(out["x"])], 6).tolist()
    assert nan_times == [0.25, 0.3, 0.35]
    assert out["x"][4] == 2.0 and out["x"][8] == 4.0 and out["x"][1] == pytest.approx(0.5)


def test_resample_warns_where_the_record_steps_are_much_longer():
    t = np.concatenate([np.arange(0.0, 1.0, 0.01), np.arange(1.2, 2.0, 0.01)])  # 0.2 s without samples
    record = as_record({"t": t, "x": np.sin(t)}, name="dropout")
    with pytest.warns(RecordWarning, match=r"dropout: resampled to a step of 0.01 s, but the record has steps up "
                                           r"to 0.21 s \(from t = 0.99\): values up to 0.1 s from the nearest sample"):
        resample(record)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        resample(as_record({"t": uneven_grid(51), "x": np.zeros(51)}))  # jitter alone: no warning


@pytest.mark.parametrize(
    ("step", "method", "message"),
    [
        (0.0, "linear", r"resample step must be a finite number of seconds > 0, got 0.0"),
        (np.nan, "linear", r"resample step must be a finite number"),
        ("0.1", "linear", r"resample step must be a finite number"),
        (1.5, "linear", r"resample step 1.5 s gives 2 sample\(s\) over the record's 2 s; at least 3"),
        (1e-12, "linear", r"resample step 1e-12 s gives 2000000000001 samples .* more than the limit of 10000000"),
        (None, "cubic", r"resample method 'cubic' is not one of \['linear'\]"),
    ],
)
def test_resample_refuses_bad_settings(step, method, message):
    with pytest.raises(RecordError, match=message):
        resample({"t": [0.0, 1.0, 2.0], "x": [1.0, 2.0, 3.0]}, step, method=method)
