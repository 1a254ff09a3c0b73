"""Derivatives and integrals of recorded signals: Savitzky-Golay and central differences, gaps."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from diagnosis.derivatives import cumulative_integral, default_window, derivative
from diagnosis.records import RecordError, RecordWarning, as_record

from tests.diagnosis.sample_records import T, sine_record, uneven_grid


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
