"""A record put on a uniform step: the median step, never across a gap, warnings, bad settings."""

import warnings

import numpy as np
import pytest

from diagnosis.derivatives import derivative
from diagnosis.records import RecordError, RecordWarning, as_record
from diagnosis.uniform_grid import resample

from tests.diagnosis.sample_records import uneven_grid


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
