"""Detection: thresholds, margin, persistence, NaN handling, bad records."""

import numpy as np
import pytest

from bondgraph import simulate
from bondgraph.library import rlc_circuit
from diagnosis import derive_arrs
from diagnosis.detection import evaluate, noise_margin, persistent
from diagnosis.records import RecordError, RecordWarning


@pytest.fixture(scope="module")
def rlc():
    bg = rlc_circuit()
    record = simulate(bg, (0, 0.5), {"V": lambda t: 1.0 + 0.5 * np.sin(40 * t)},
                      t_eval=np.linspace(0, 0.5, 2001)).record()
    return derive_arrs(bg), record


def test_interval_band_is_exact_for_the_linear_form(rlc):
    arrs, record = rlc
    arr = arrs[0]  # -L di/dt - R i + V - v_C: Psi_2 = -delta_L L di/dt - delta_R R i
    result = arr.evaluate(record, margin=1e-5)
    L, R = arr.values["L"], arr.values["R"]
    from diagnosis.residuals import read_record

    compiled = arr.compiled
    points = compiled.point_values(read_record(arr, record))
    di = points[compiled.points.index(next(s for s in compiled.derivatives))]
    i = np.asarray(record["i"])
    corners = np.array([-dl * L * di - dr * R * i for dl in (-0.05, 0.05) for dr in (-0.05, 0.05)])
    assert np.all(result.lower <= corners.min(axis=0)) and np.all(result.upper >= corners.max(axis=0))
    assert np.allclose(result.lower, corners.min(axis=0), rtol=1e-12, atol=1e-15)
    assert np.allclose(result.upper, corners.max(axis=0), rtol=1e-12, atol=1e-15)
    # BG-LFT: sum of worst-case |w_i|, never narrower
    assert np.allclose(result.bglft, 0.05 * L * np.abs(di) + 0.05 * R * np.abs(i))
    assert np.all(result.upper - result.lower <= 2 * result.bglft * (1 + 1e-12))


def test_fault_raises_an_alarm_and_threshold_choice_matters(rlc):
    arrs, _ = rlc
    bg = rlc_circuit()
    faulty = simulate(bg, (0, 0.5), {"V": lambda t: 1.0 + 0.5 * np.sin(40 * t)}, parameters={"R": 12.0},
                      t_eval=np.linspace(0, 0.5, 2001)).record()
    result = arrs[0].evaluate(faulty, margin=1e-5, persistence=3)
    assert result.detection_time is not None and result.detection_time < 0.1
    assert arrs[1].evaluate(faulty, margin=1e-5).alarm.sum() == 0  # R is not in ARR_J0
    bglft = arrs[0].evaluate(faulty, margin=1e-5, persistence=3, threshold="bglft")
    assert bglft.alarm.sum() <= result.alarm.sum()


def test_persistence_counts_consecutive_violations():
    v = np.array([1, 0, 1, 1, 1, 0, 1, 1], bool)
    assert persistent(v, 1).tolist() == v.tolist()
    assert persistent(v, 3).astype(int).tolist() == [0, 0, 0, 0, 1, 0, 0, 0]


def test_nan_gap_is_undecided_not_an_alarm(rlc):
    arrs, record = rlc
    gappy = {k: np.array(v, float) for k, v in record.items()}
    gappy["i"][1000:1010] = np.nan
    result = arrs[0].evaluate(gappy, margin=1e-5)
    assert np.isnan(result.residual[1000:1010]).all()
    assert not result.violation[np.isnan(result.residual)].any()
    assert not result.alarm.any()


def test_noise_margin_is_robust_to_outliers(rlc):
    arrs, record = rlc
    rng = np.random.default_rng(0)
    noisy = dict(record, i=record["i"] + rng.normal(0, 1e-4, record["i"].size))
    margin = noise_margin(arrs[1], noisy, k=3)  # ARR_J0 = i - C dv_C/dt: sigma of r_n ~ 1e-4
    assert 2e-4 < margin < 4e-4


@pytest.mark.parametrize("record, message", [
    ({"time": [0, 1, 2]}, "'t'"),
    ({"t": [0, 1, 2, 3], "V": [0, 1, 2, 3], "i": [0, 1, 2, 3]}, "v_C"),
    ({"t": [0, 2, 1, 3], "V": [0] * 4, "i": [0] * 4, "v_C": [0] * 4}, "increasing"),
])
def test_bad_records_name_the_arr_and_column(rlc, record, message):
    arrs, _ = rlc
    with pytest.raises(RecordError, match=rf"ARR_J1.*{message}"):
        arrs[0].evaluate(record)


def test_bad_options_are_rejected(rlc):
    arrs, record = rlc
    with pytest.raises(ValueError, match="persistence"):
        evaluate(arrs[0], record, persistence=0)
    with pytest.raises(ValueError, match="margin"):
        evaluate(arrs[0], record, margin=-1.0)
    with pytest.raises(ValueError, match="threshold"):
        evaluate(arrs[0], record, threshold="loose")


@pytest.mark.parametrize("options, message", [
    ({"margin": "x"}, r"margin: the noise margin must be a finite number >= 0, got 'x'"),
    ({"margin": np.nan}, r"margin: the noise margin must be a finite number >= 0, got nan"),
    ({"margin": np.inf}, r"margin: .* got inf"),
    ({"margin": -1e-3}, r"margin: .* got -0.001"),
    ({"margin": True}, r"margin: .* got True"),
    ({"persistence": 2.5}, r"persistence must be a whole number of samples >= 1, got 2.5"),
    ({"persistence": "3"}, r"persistence must be a whole number of samples >= 1, got '3'"),
    ({"persistence": 0}, r"persistence must be a whole number .* got 0"),
    ({"method": "spline"}, r"ARR_J1: unknown derivative method 'spline'; choose 'savgol' or 'central'"),
])
def test_bad_detection_settings_name_the_option(rlc, options, message):
    # margin='x' used to fail inside numpy, persistence=2.5 inside np.ones
    arrs, record = rlc
    with pytest.raises(ValueError, match=message):
        evaluate(arrs[0], record, **options)


def test_an_arr_name_instead_of_an_arr_is_a_type_error_naming_it(rlc):
    arrs, record = rlc
    with pytest.raises(TypeError, match=r"noise_margin: arr must be an ARR from diagnosis.derive_arrs, got the str "
                                        r"'ARR_J1' \(look the ARR up by its name"):
        noise_margin("ARR_J1", record)
    with pytest.raises(TypeError, match=r"evaluate: arr must be an ARR .* got the dict \{'name': 'ARR_J1'\}"):
        evaluate({"name": "ARR_J1"}, record)


@pytest.mark.parametrize("k", [-1.0, 0.0, np.nan, np.inf, "3", None])
def test_noise_margin_needs_a_finite_positive_k(rlc, k):
    arrs, record = rlc
    with pytest.raises(ValueError, match=r"k: the number of standard deviations must be a finite number > 0, got"):
        noise_margin(arrs[1], record, k=k)


def test_noise_margin_on_a_record_without_residual_is_a_record_error(rlc):
    arrs, record = rlc
    empty = dict(record, i=np.full(record["i"].size, np.nan))
    with pytest.raises(RecordError, match="ARR_J0: the nominal record gives fewer than 2 finite residual values"):
        noise_margin(arrs[1], empty)


def test_an_uneven_record_takes_central_differences_or_a_resampling(rlc):
    from diagnosis import resample

    arrs, _ = rlc
    t = np.sort(np.random.default_rng(1).uniform(0.0, 0.5, 1500))
    uneven = simulate(rlc_circuit(), (0.0, 0.5), {"V": lambda t: 1.0 + 0.5 * np.sin(40 * t)}, t_eval=t).record()
    with pytest.raises(RecordError, match=r"method='central'.*diagnosis.resample\(record\)"):
        evaluate(arrs[1], uneven)
    central = evaluate(arrs[1], uneven, method="central", margin=1e-4)
    assert central.t.size == t.size and np.isfinite(central.residual).all() and not central.alarm.any()
    with pytest.warns(RecordWarning, match="straight-line interpolations"):  # steps far longer than the median
        uniform = resample(uneven)
    resampled = evaluate(arrs[1], uniform, margin=1e-2)
    assert uniform.is_uniform and np.isfinite(resampled.residual).all()


def test_nonlinear_uncertainty_uses_a_sound_natural_extension():
    # the C stays in integral causality: e = q/(C(1+delta)) contributes delta/(1+delta) * q/C, not linear in delta
    from bondgraph import BondGraph

    bg = BondGraph()
    bg.add("u", "Sf"), bg.add("j", "1"), bg.add("R", "R", value=2.0)
    bg.add("C", "C", value=0.5, uncertainty=(-0.2, 0.2))
    bg.add("y", "Df"), bg.add("j0", "0"), bg.add("v", "De")
    for tail, head in [("u", "j0"), ("j0", "j"), ("j", "R"), ("j", "C"), ("j", "y"), ("j0", "v")]:
        bg.bond(tail, head)
    arr = next(a for a in derive_arrs(bg, integrals="keep") if "C" in a.terms)
    t = np.linspace(0, 2, 4001)
    true = simulate(bg, (0, 2), {"u": lambda s: 1 + np.sin(3 * s)}, parameters={"C": 0.5 * 1.2}, t_eval=t,
                    rtol=1e-10, atol=1e-12).record()
    result = arr.evaluate(true, method="central")
    assert not result.violation.any()  # sound: the true system at the box edge stays inside
    charge = np.abs(result.residual) * 1.2 / 0.2  # |q/C| from -r_n = 0.2/1.2 q/C
    exact_hi = 0.2 / 1.2 * charge  # exact range of delta/(1+delta) over [-0.2, 0.2] is [-0.25, 0.1667]
    late = t > 0.5
    assert np.all(result.upper[late] >= exact_hi[late] * (1 - 1e-6))
    assert np.all(result.upper[late] > 1.4 * exact_hi[late])  # natural extension overestimates (0.25 vs 0.1667)


@pytest.mark.extras   # pandas
def test_a_pandas_dataframe_record_gives_the_same_evaluation(rlc):
    import pandas as pd

    arrs, record = rlc
    from_dict = arrs[0].evaluate(record, margin=1e-5)
    from_frame = arrs[0].evaluate(pd.DataFrame(record), margin=1e-5)
    assert np.array_equal(from_dict.residual, from_frame.residual)
    assert np.array_equal(from_dict.lower, from_frame.lower)


def test_a_signal_named_like_a_derivative_point_keeps_its_own_value():
    """A voltage sensor called d1_i next to di/dt: compiling must not merge the two into one point."""
    from bondgraph import BondGraph

    bg = BondGraph()
    for name, kind in [("U", "Se"), ("J", "1"), ("i", "Df"), ("d1_i", "De"), ("J0", "0"), ("J2", "1")]:
        bg.add(name, kind)
    for name, kind, value in [("L", "I", 2.0), ("R", "R", 1.0), ("C", "C", 0.5), ("R2", "R", 3.0)]:
        bg.add(name, kind, value=value)
    for tail, head in [("U", "J"), ("J", "L"), ("J", "R"), ("J", "J0"), ("J0", "C"), ("J0", "J2"), ("J2", "R2"),
                       ("J", "i"), ("J0", "d1_i")]:
        bg.bond(tail, head)
    t = np.linspace(0.0, 5.0, 5001)
    record = simulate(bg, (0.0, 5.0), {"U": lambda t: np.sin(2 * t)}, t_eval=t).record()
    for arr in derive_arrs(bg):
        residual = arr.evaluate(record, margin=1e-3).residual
        assert np.abs(residual[50:-50]).max() < 1e-6, arr.name  # consistent healthy data: r_n = 0


@pytest.mark.parametrize("threshold", ["interval", "bglft"])
def test_a_used_arr_pickles_and_evaluates_bitwise_the_same(rlc, threshold):
    """Its lambdified residual, BG-LFT terms and interval evaluator are left out and rebuilt on first use."""
    import pickle

    arrs, record = rlc
    arr = derive_arrs(rlc_circuit(), complete=False, integrals="keep")[0]   # one with an integral: v_C
    options = dict(margin=1e-4, persistence=3, threshold=threshold)
    before = arr.evaluate(record, **options)
    assert arr.compiled._cache   # the functions the evaluation built
    copy = pickle.loads(pickle.dumps(arrs + [arr]))[-1]
    assert not copy.compiled._cache and copy.compiled is not arr.compiled
    after = copy.evaluate(record, **options)
    for name in ("residual", "lower", "upper", "bglft", "violation", "alarm"):
        assert np.array_equal(getattr(after, name), getattr(before, name), equal_nan=True), name
    assert all(np.array_equal(a, b) for a, b in zip(after.points, before.points))


def test_a_nonlinear_arr_pickles_and_evaluates_bitwise_the_same():
    """The three-tank ARRs hold square roots and signs of level differences."""
    import pickle

    from bondgraph.library import three_tank

    bg = three_tank()
    t = np.linspace(0.0, 20.0, 401)
    record = simulate(bg, (0.0, 20.0), {"Q1": 1e-4, "Q2": 1e-4}, t_eval=t).record()
    arr = derive_arrs(bg, complete=False)[0]
    before = arr.evaluate(record, margin=1e-6)
    after = pickle.loads(pickle.dumps(arr)).evaluate(record, margin=1e-6)
    assert np.isfinite(before.lower).any()
    for name in ("residual", "lower", "upper"):
        assert np.array_equal(getattr(after, name), getattr(before, name), equal_nan=True), name


@pytest.mark.extras   # dask
def test_dask_names_a_task_holding_a_compiled_arr(rlc):
    """The compiled ARR points back to its ARR: tokenize followed the cycle without end."""
    import dataclasses

    tokenize = pytest.importorskip("dask.base").tokenize
    arrs, record = rlc
    arr = dataclasses.replace(arrs[0])   # the same relation, not compiled yet
    before = tokenize(arr)
    arr.evaluate(record)   # compiles it
    assert tokenize(arr) == before == tokenize(dataclasses.replace(arrs[0]))   # the same relation, the same name
    assert tokenize(arrs[1]) != before
