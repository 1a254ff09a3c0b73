"""Streaming evaluation: the same samples as evaluate() on the whole record, for any split into micro-batches."""

import io
import itertools
import pickle
import warnings

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import cumulative_trapezoid

from bondgraph import simulate
from bondgraph.library import rlc_circuit, torsion_bar_monitorable
from diagnosis import ARR, Evaluation, RecordError, RecordWarning, StreamChunk, StreamingEvaluation, derive_arrs
from diagnosis.deltas import delta
from diagnosis.detection import evaluate
from diagnosis.records import add_noise, as_record

ANTIDERIVATIVES = {"omega_m": "theta_m", "omega_Ld": "theta_Ld"}  # encoder angles
FIELDS = ("t", "residual", "lower", "upper", "bglft")


# -- records and ARRs ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def rlc():
    """The RLC loop and capacitor ARRs; a noisy record whose resistance steps from 10 to 13 ohm at 0.1 s."""
    bg = rlc_circuit()
    t = np.linspace(0.0, 0.2, 201)
    clean = simulate(bg, (0.0, 0.2), {"V": lambda t: 1.0 + 0.5 * np.sin(40 * t)}, t_eval=t,
                     parameters={"R": lambda t: 10.0 if t < 0.1 else 13.0}).record()
    return derive_arrs(bg), add_noise(as_record(clean), {"i": 2e-4}, seed=1)


@pytest.fixture(scope="module")
def torsion():
    """The torsion bar's ARR at junction 1_1 with its shaft integral kept, and a record with encoder angles.

    The record is synthetic (smooth speeds and torque with noise, angles integrated and quantized to 2000
    counts per revolution): the stream must reproduce evaluate() on any data, and simulating the rig
    would cost more than the whole test.
    """
    arr = next(a for a in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")
               if a.junction == "1_1")
    n = 160
    t = np.arange(n) * 0.01
    rng = np.random.default_rng(3)
    columns = {"t": t, "omega_m": 50 * np.sin(2 * t) + 0.01 * rng.standard_normal(n),
               "omega_Ld": 13 * np.sin(2 * t - 0.1) + 0.01 * rng.standard_normal(n),
               "tau_m": 0.1 * np.cos(3 * t) + 0.01 * rng.standard_normal(n)}
    count = 2 * np.pi / 2000
    for speed, angle in ANTIDERIVATIVES.items():
        columns[angle] = np.round(cumulative_trapezoid(columns[speed], t, initial=0.0) / count) * count + 0.3
    return arr, as_record(columns)


def oscillator() -> ARR:
    """``m x'' + k x - u + c int_0^t x' u = 0``: a second derivative, and an integral of a derivative."""
    t = sp.Symbol("t")
    x, u = sp.Function("x")(t), sp.Function("u")(t)
    m, k, c = sp.symbols("m k c")
    nominal = m * x.diff(t, 2) + k * x - u + c * sp.Integral(x.diff(t) * u, (t, 0, t))
    term = delta("k") * k * x
    return ARR("ARR_osc", "J", nominal, term, {"k": term}, frozenset({"m", "k", "c"}),
               {"m": 0.5, "k": 2.0, "c": 0.1}, {"k": (-0.1, 0.1)})


def algebraic() -> ARR:
    """``k x - u = 0``: no derivative, every sample is final as it arrives."""
    t = sp.Symbol("t")
    x, u = sp.Function("x")(t), sp.Function("u")(t)
    term = delta("k") * sp.Symbol("k") * x
    return ARR("ARR_alg", "J", sp.Symbol("k") * x - u, term, {"k": term}, frozenset({"k"}), {"k": 2.0},
               {"k": (-0.1, 0.1)})


def oscillator_record(n: int = 120, gaps: tuple = ()) -> dict:
    t = np.arange(n) * 0.01
    x = np.sin(3 * t) + 1e-3 * np.random.default_rng(0).standard_normal(n)
    x[list(gaps)] = np.nan
    return as_record({"t": t, "x": x, "u": 2.0 * np.sin(3 * t)})


# -- helpers ------------------------------------------------------------------------------------------


def stream(arr, record, sizes, **options) -> StreamChunk:
    """Push the record in batches of ``sizes`` (an iterable of ints, cycled), flush, and join the chunks."""
    evaluation = StreamingEvaluation(arr, **options)
    chunks, start = [], 0
    for size in itertools.cycle(sizes):
        if start >= len(record):
            break
        window = slice(start, start + size)
        chunks.append(evaluation.push(record.t[window], {c: record[c][window] for c in evaluation.columns}))
        start += size
    chunks.append(evaluation.flush())
    return StreamChunk.concatenate(chunks)


def assert_same(chunk: Evaluation, batch: Evaluation, rtol: float = 1e-12) -> None:
    """Equal samples: NaN and inf where the batch has them, finite values to ``rtol`` of the array's scale
    (bitwise for ``rtol=0``), violations and alarms exactly."""
    pairs = [(f, getattr(chunk, f), getattr(batch, f)) for f in FIELDS]
    pairs += [(f"points[{k}]", p, q) for k, (p, q) in enumerate(zip(chunk.points, batch.points, strict=True))]
    for name, got, want in pairs:
        assert got.shape == want.shape, name
        assert np.array_equal(np.isfinite(got), np.isfinite(want)), name
        assert np.array_equal(got[~np.isfinite(want)], want[~np.isfinite(want)], equal_nan=True), name
        finite = np.isfinite(want)
        scale = np.max(np.abs(want[finite]), initial=0.0)
        assert np.all(np.abs(got[finite] - want[finite]) <= rtol * scale), name
    assert np.array_equal(chunk.violation, batch.violation)
    assert np.array_equal(chunk.alarm, batch.alarm)


SPLITS = {"one at a time": [1], "seven at a time": [7], "uneven": [3, 1, 30, 2, 11, 5, 1, 60],
          "whole": [10_000]}


# -- equality with evaluate() --------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("split", SPLITS.values(), ids=SPLITS.keys())
def test_rlc_stream_equals_the_batch_evaluation(rlc, split):
    arrs, record = rlc
    options = {"margin": 2e-3, "persistence": 5}
    for arr in arrs:
        batch = evaluate(arr, record, **options)
        assert_same(stream(arr, record, split, **options), batch)
        if arr.name == "ARR_J1":  # the loop sees the resistance step, after violations that do not persist
            assert 0.1 < batch.detection_time < 0.11 and batch.violation.sum() > batch.alarm.sum() > 0


def test_with_the_records_step_savgol_values_are_bitwise_the_batch_ones(rlc):
    arrs, record = rlc
    for arr in arrs:
        assert_same(stream(arr, record, [7], window=21, dt=record.dt), evaluate(arr, record, window=21), rtol=0.0)


@settings(max_examples=15, deadline=None)
@given(sizes=st.lists(st.integers(1, 40), min_size=1, max_size=12),
       method=st.sampled_from(["savgol", "central"]))
def test_any_split_gives_the_batch_values(rlc, sizes, method):
    arrs, record = rlc
    short = record.between(end=0.1)
    options = {"method": method, "margin": 2e-3, "persistence": 3}
    assert_same(stream(arrs[0], short, sizes, **options), evaluate(arrs[0], short, **options), rtol=1e-11)


@pytest.mark.parametrize("split", [[1], [7], [13, 2, 40]], ids=["1", "7", "uneven"])
@pytest.mark.parametrize("method", ["savgol", "central"])
def test_torsion_bar_stream_with_encoder_antiderivatives(torsion, split, method):
    arr, record = torsion
    options = {"method": method, "antiderivatives": ANTIDERIVATIVES, "persistence": 4}
    options["margin"] = float(np.median(np.abs(evaluate(arr, record, **options).residual)))
    batch = evaluate(arr, record, **options)
    assert 0 < batch.violation.sum() < len(record) and batch.alarm.any()
    assert_same(stream(arr, record, split, **options), batch, rtol=1e-12 if method == "savgol" else 1e-11)


def test_torsion_bar_stream_integrating_the_speeds(torsion):
    """Without antiderivatives the shaft integral is a running trapezoid sum, continued across batches."""
    arr, record = torsion
    batch = evaluate(arr, record, margin=1e-3)
    assert_same(stream(arr, record, [1, 9, 4], margin=1e-3), batch)
    assert stream(arr, record, [5], margin=1e-3, dt=record.dt).points[-1].tolist() == batch.points[-1].tolist()


@pytest.mark.parametrize("method", ["savgol", "central"])
def test_second_derivatives_are_undecided_at_both_ends_as_in_the_batch(method):
    arr, record = oscillator(), oscillator_record()
    batch = evaluate(arr, record, method=method)
    edge = 5 if method == "savgol" else 2
    d2 = batch.points[arr.compiled.points.index(sp.Symbol("d2_x"))]
    assert np.isnan(d2[:edge]).all() and np.isnan(d2[-edge:]).all() and np.isfinite(d2[edge:-edge]).all()
    for split in ([1], [6, 1, 17]):
        assert_same(stream(arr, record, split, method=method), batch, rtol=1e-10)


def test_gaps_give_the_batch_nan_and_the_same_warning_once():
    arr = oscillator()
    record = oscillator_record(gaps=(3, 60, 61, 115))  # in the first window, inside, and in the last window
    with warnings.catch_warnings(record=True) as batch_warnings:
        warnings.simplefilter("always")
        batch = evaluate(arr, record)
    with warnings.catch_warnings(record=True) as stream_warnings:
        warnings.simplefilter("always")
        chunk = stream(arr, record, [4])
    assert_same(chunk, batch)
    assert np.isnan(batch.residual[:10]).all()  # the integral of x' u is unknown from the first gap on
    assert [str(w.message) for w in stream_warnings] == [str(w.message) for w in batch_warnings]
    assert len(stream_warnings) == 1 and issubclass(stream_warnings[0].category, RecordWarning)
    assert stream_warnings[0].filename == __file__  # the warning points at the caller's push


def test_gaps_near_the_ends_of_a_derivative_window(rlc):
    arrs, record = rlc
    columns = {"t": record.t, **record.columns}
    columns["i"] = columns["i"].copy()
    columns["i"][[2, 100, 190, 199]] = np.nan
    gappy = as_record(columns)
    for method, start, end in (("savgol", 8, 16), ("central", 4, 3)):  # NaN within the stencil's reach
        batch = evaluate(arrs[0], gappy, method=method)
        assert np.isnan(batch.residual[:start]).all() and np.isnan(batch.residual[-end:]).all()
        assert np.isfinite(batch.residual[start]) and np.isfinite(batch.residual[-end - 1])
        assert_same(stream(arrs[0], gappy, [1, 5], method=method), batch)


def test_an_arr_without_derivatives_finalizes_every_sample_at_once():
    arr, record = algebraic(), oscillator_record(12)
    evaluation = StreamingEvaluation(arr)
    chunk = evaluation.push(record.t[:5], {"x": record["x"][:5], "u": record["u"][:5]})
    assert chunk.t.tolist() == record.t[:5].tolist() and evaluation.final == 5
    assert_same(stream(arr, record, [1]), evaluate(arr, record))


def test_central_differences_take_uneven_steps(rlc):
    arrs, record = rlc
    keep = np.ones(len(record), bool)
    keep[[10, 11, 50, 120]] = False
    uneven = as_record({"t": record.t[keep], **{c: v[keep] for c, v in record.columns.items()}})
    assert_same(stream(arrs[0], uneven, [3], method="central"), evaluate(arrs[0], uneven, method="central"),
                rtol=1e-11)


# -- persistence, the lag, bounded memory -----------------------------------------------------------


def test_persistence_counts_violations_across_batch_borders(rlc):
    arrs, record = rlc
    arr = arrs[0]  # V - L di/dt - R i - v_C
    n = 12
    t = np.arange(n) * 0.01
    V = np.where((np.arange(n) >= 3) & (np.arange(n) != 8), 2.0, 1.0)  # violations at 3..7 and 9..11
    signals = {"V": V, "i": np.zeros(n), "v_C": np.ones(n)}
    evaluation = StreamingEvaluation(arr, method="central", persistence=3)
    chunks = [evaluation.push(t[a:b], {k: v[a:b] for k, v in signals.items()}) for a, b in ((0, 4), (4, 6), (6, 12))]
    chunks.append(evaluation.flush())
    assert [c.t.size for c in chunks] == [3, 2, 6, 1]  # a border inside each run of violations
    alarm = StreamChunk.concatenate(chunks).alarm
    assert np.flatnonzero(alarm).tolist() == [5, 6, 7, 11]
    # V's jumps here stand for violations: the batch must judge them as the stream does (no step mask)
    batch = evaluate(arr, {"t": t, **signals}, method="central", persistence=3, steps=False)
    assert alarm.tolist() == batch.alarm.tolist()


def test_a_push_without_thresholds_gives_the_residual_and_judges_nothing(rlc):
    """Residuals alone: the same residual bits, thresholds undecided (NaN), no violation, and the
    persistence run starts again when judging resumes."""
    arrs, record = rlc
    arr = arrs[0]  # the loop: it sees the resistance step at 0.1 s
    judged, unjudged = StreamingEvaluation(arr, persistence=2), StreamingEvaluation(arr, persistence=2)
    t = record.t
    for a, b in ((0, 90), (90, 150), (150, t.size)):
        part = {name: record[name][a:b] for name in ("V", "i", "v_C")}
        full = judged.push(t[a:b], part)
        bare = unjudged.push(t[a:b], part, thresholds="none" if a == 90 else "both")
        assert np.array_equal(full.residual, bare.residual) and np.array_equal(full.t, bare.t)
        if a == 90:  # the stretch of the step: unjudged
            assert np.isnan(bare.lower).all() and np.isnan(bare.upper).all() and np.isnan(bare.bglft).all()
            assert not bare.violation.any() and not bare.alarm.any() and full.alarm.any()
        else:
            assert np.array_equal(full.lower, bare.lower) and np.array_equal(full.violation, bare.violation)
    # the last stretch: the run of violations restarted after the unjudged one, so its first alarm comes later
    assert bare.violation[0] and full.alarm[0] and not bare.alarm[0]


@pytest.mark.parametrize("threshold", ["interval", "bglft"])
def test_the_alarm_band_alone_judges_as_both(rlc, threshold):
    """Only the band the alarm is judged on: the same residual, band, violations and alarms, the other band NaN."""
    arrs, record = rlc
    both, alone = (StreamingEvaluation(arrs[0], persistence=2, threshold=threshold) for _ in range(2))
    fired = False
    for a in range(0, record.t.size, 37):
        part = {name: record[name][a:a + 37] for name in ("V", "i", "v_C")}
        full, bare = both.push(record.t[a:a + 37], part), alone.push(record.t[a:a + 37], part, thresholds="alarm")
        assert np.array_equal(full.alarm, bare.alarm) and np.array_equal(full.violation, bare.violation)
        interval = ("lower", "upper")
        kept, dropped = (interval, ("bglft",)) if threshold == "interval" else (("bglft",), interval)
        assert all(np.array_equal(getattr(full, k), getattr(bare, k)) for k in ("residual", *kept))
        assert all(np.isnan(getattr(bare, k)).all() for k in dropped)
        fired |= bool(full.alarm.any())
    assert fired  # the resistance's step fires: alarms were compared, not only silence
    with pytest.raises(ValueError, match="thresholds must be one of"):
        alone.push(record.t[-1:] + 1.0, {name: record[name][-1:] for name in ("V", "i", "v_C")}, thresholds=True)


def test_the_newest_half_window_waits_and_the_buffer_stays_bounded(rlc):
    arrs, record = rlc
    evaluation = StreamingEvaluation(arrs[0], window=15)
    lengths = []
    for k in range(60):
        chunk = evaluation.push(record.t[k], {c: record[c][k] for c in evaluation.columns})  # one sample, scalars
        lengths.append(len(chunk))
        assert evaluation.state()["buffer"].shape == (3, min(k + 1, 15))
    assert lengths[:14] == [0] * 14 and lengths[14] == 8 and set(lengths[15:]) == {1}  # 0..7 once 15 are in
    assert (evaluation.samples, evaluation.final) == (60, 53)
    tail = evaluation.flush()
    assert tail.start == 53 and tail.t.tolist() == record.t[53:60].tolist()


def test_an_empty_batch_changes_nothing(rlc):
    arrs, record = rlc
    evaluation = StreamingEvaluation(arrs[0])
    evaluation.push(record.t[:20], {c: record[c][:20] for c in evaluation.columns})
    before = evaluation.state()
    chunk = evaluation.push([], {c: [] for c in evaluation.columns})
    assert len(chunk) == 0 and chunk.start == 15 and len(chunk.points) == 4
    assert evaluation.state()["samples"] == before["samples"] == 20


# -- surviving a restart ------------------------------------------------------------------------------


def test_state_and_restore_go_on_as_if_never_stopped(torsion):
    arr, record = torsion
    options = {"antiderivatives": ANTIDERIVATIVES, "margin": 5e-3, "persistence": 3}
    whole = stream(arr, record, [9], **options)
    first = StreamingEvaluation(arr, **options)
    head = [first.push(record.t[a:a + 9], {c: record[c][a:a + 9] for c in first.columns}) for a in range(0, 81, 9)]
    saved = pickle.loads(pickle.dumps(first.state()))  # a plain dict: no ARR inside, pickles anywhere
    assert saved["arr"] == arr.name and "ARR" not in repr(type(v) for v in saved.values())
    assert all(isinstance(v, (int, float, str, bool, list, dict, np.ndarray)) for v in saved.values())
    again = StreamingEvaluation.restore(arr, saved)
    tail = [again.push(record.t[a:a + 9], {c: record[c][a:a + 9] for c in again.columns})
            for a in range(81, len(record), 9)]
    joined = StreamChunk.concatenate([*head, *tail, again.flush()])
    assert_same(joined, whole, rtol=0.0)


class _KeepARR(pickle.Pickler):
    """Pickles everything but the ARR, which is referred to by name (ARR pickling is not this test's concern)."""

    def __init__(self, file, arr):
        super().__init__(file)
        self.arr = arr

    def persistent_id(self, obj):
        return "arr" if obj is self.arr else None


class _GiveARR(pickle.Unpickler):
    def __init__(self, file, arr):
        super().__init__(file)
        self.arr = arr

    def persistent_load(self, pid):
        return self.arr


def test_the_stream_itself_pickles_with_the_standard_library(rlc):
    arrs, record = rlc
    arr = arrs[0]
    evaluation = StreamingEvaluation(arr, margin=2e-3, persistence=4)
    head = evaluation.push(record.t[:50], {c: record[c][:50] for c in evaluation.columns})
    buffer = io.BytesIO()
    _KeepARR(buffer, arr).dump(evaluation)
    copy = _GiveARR(io.BytesIO(buffer.getvalue()), arr).load()
    assert copy.arr is arr and (copy.samples, copy.final) == (50, 45)
    rest = {c: record[c][50:] for c in evaluation.columns}
    assert_same(StreamChunk.concatenate([head, copy.push(record.t[50:], rest), copy.flush()]),
                evaluate(arr, record, margin=2e-3, persistence=4))


def test_restore_refuses_another_arr_other_options_and_a_broken_state(rlc):
    arrs, record = rlc
    evaluation = StreamingEvaluation(arrs[0], margin=1e-3)
    evaluation.push(record.t[:30], {c: record[c][:30] for c in evaluation.columns})
    saved = evaluation.state()
    assert StreamingEvaluation.restore(arrs[0], saved, margin=1e-3, antiderivatives=None, window=None).final == 25
    with pytest.raises(RecordError, match="margin=0.002 differs from the stream's margin=0.001"):
        StreamingEvaluation.restore(arrs[0], saved, margin=2e-3)
    with pytest.raises(RecordError, match="state is of the stream of 'ARR_J1', not of 'ARR_J0'"):
        StreamingEvaluation.restore(arrs[1], saved)
    with pytest.raises(RecordError, match=r"the state lacks \['buffer'\]"):
        StreamingEvaluation.restore(arrs[0], {k: v for k, v in saved.items() if k != "buffer"})
    with pytest.raises(RecordError, match=r"state\['buffer'\] has shape \(2, 11\), expected \(3, 11\)"):
        StreamingEvaluation.restore(arrs[0], {**saved, "buffer": saved["buffer"][:2]})


# -- errors ---------------------------------------------------------------------------------------------


def test_times_must_increase_within_and_across_batches(rlc):
    arrs, _ = rlc
    evaluation = StreamingEvaluation(arrs[0])
    ones = {"V": np.ones(3), "i": np.zeros(3), "v_C": np.ones(3)}
    with pytest.raises(RecordError, match=r"ARR_J1 stream: t must increase: t = 0.01 follows t = 0.02 \(the previous "
                                          r"sample\)"):
        evaluation.push([0.0, 0.02, 0.01], ones)
    evaluation.push([0.0, 0.01, 0.02], ones)
    with pytest.raises(RecordError, match=r"t = 0.02 follows t = 0.02 \(the previous batch's last sample\)"):
        evaluation.push([0.02, 0.03, 0.04], ones)
    with pytest.raises(RecordError, match="column 't' has a non-finite value nan at row 1"):
        evaluation.push([0.03, np.nan, 0.05], ones)
    assert evaluation.samples == 3  # a refused batch leaves the stream as it was


def test_an_uneven_step_is_refused_with_savgol_naming_the_time(rlc):
    arrs, _ = rlc
    evaluation = StreamingEvaluation(arrs[0])
    ones = {"V": np.ones(4), "i": np.zeros(4), "v_C": np.ones(4)}
    evaluation.push([0.0, 0.01, 0.02, 0.03], ones)
    with pytest.raises(RecordError, match=r"t = 0.0505 comes 0.0105 after the previous sample, but the stream's step "
                                          r"is 0.01 \(off by 5.00%\).*use method='central'"):
        evaluation.push([0.04, 0.0505, 0.06, 0.07], ones)
    fixed = StreamingEvaluation(arrs[0], dt=0.02)
    message = "t = 0.01 comes 0.01 after the previous sample, but the stream's step is 0.02"
    with pytest.raises(RecordError, match=message):
        fixed.push([0.0, 0.01, 0.02, 0.03], ones)
    StreamingEvaluation(arrs[0], method="central").push([0.0, 0.01, 0.03, 0.07], ones)  # any steps


def test_bad_signals_are_named(rlc):
    arrs, _ = rlc
    evaluation = StreamingEvaluation(arrs[0])
    with pytest.raises(RecordError, match=r"missing signal\(s\) \['v_C'\] in this batch; every batch needs "
                                          r"\['V', 'i', 'v_C'\]"):
        evaluation.push([0.0], {"V": [1.0], "i": [0.0]})
    with pytest.raises(RecordError, match="column 'i' has an infinite value inf at row 1 .t = 0.01.; use NaN"):
        evaluation.push([0.0, 0.01], {"V": [1.0, 1.0], "i": [0.0, np.inf], "v_C": [0.0, 0.0]})
    with pytest.raises(RecordError, match="column 'V' has a non-numeric value 'high' at row 0"):
        evaluation.push([0.0], {"V": ["high"], "i": [0.0], "v_C": [0.0]})
    with pytest.raises(RecordError, match="column 'V' has a non-numeric value True at row 0"):
        evaluation.push([0.0], {"V": [True], "i": [0.0], "v_C": [0.0]})
    with pytest.raises(RecordError, match="columns of different lengths: 't' has 2 samples, 'i' has 1"):
        evaluation.push([0.0, 0.01], {"V": [1.0, 1.0], "i": [0.0], "v_C": [0.0, 0.0]})
    with pytest.raises(RecordError, match="larger in magnitude than 1e.150"):
        evaluation.push([0.0], {"V": [1e200], "i": [0.0], "v_C": [0.0]})
    with pytest.raises(RecordError, match="signals must be a mapping"):
        evaluation.push([0.0], [1.0, 0.0, 0.0])
    assert evaluation.samples == 0
    objects = np.array([1.0, 2.0], dtype=object)  # numbers in an object array are numbers
    assert evaluation.push([0.0, 0.01], {"V": objects, "i": objects, "v_C": objects}).t.size == 0


def test_options_are_checked_as_evaluate_checks_them(rlc):
    arrs, record = rlc
    for bad, match in [({"window": 10}, "signal 'i': window must be an odd number of samples > polyorder 3, got 10"),
                       ({"polyorder": 0}, "polyorder must be an integer >= the derivative order 1"),
                       ({"margin": -1.0}, "margin: the noise margin must be a finite number >= 0"),
                       ({"persistence": 0}, "persistence must be a whole number"),
                       ({"threshold": "wide"}, "threshold must be 'interval' or 'bglft'"),
                       ({"method": "spline"}, "unknown derivative method 'spline'"),
                       ({"antiderivatives": ["i"]}, "antiderivatives must map signal names to record columns")]:
        with pytest.raises(ValueError, match=match):
            evaluate(arrs[0], record, **bad)
        with pytest.raises(ValueError, match=match):
            StreamingEvaluation(arrs[0], **bad)
    with pytest.raises(RecordError, match="exact_derivatives: a stream has no exact derivative columns"):
        StreamingEvaluation(arrs[0], exact_derivatives={"i": np.zeros(3)})
    with pytest.raises(RecordError, match="dt: the sampling step must be a finite number > 0, got -0.01"):
        StreamingEvaluation(arrs[0], dt=-0.01)
    with pytest.raises(TypeError, match="StreamingEvaluation: arr must be an ARR"):
        StreamingEvaluation("ARR_J1")


def test_the_end_of_a_stream(rlc):
    arrs, record = rlc
    short = StreamingEvaluation(arrs[0])
    short.push(record.t[:6], {c: record[c][:6] for c in short.columns})
    with pytest.raises(RecordError, match="the stream has 6 samples, fewer than the 11 of the Savitzky-Golay window"):
        short.flush()
    with pytest.raises(RecordError, match="fewer than the Savitzky-Golay window of 11"):
        evaluate(arrs[0], record.between(end=0.005))  # the batch refuses the same record
    evaluation = StreamingEvaluation(arrs[0])
    evaluation.push(record.t[:20], {c: record[c][:20] for c in evaluation.columns})
    assert len(evaluation.flush()) == 5 and len(evaluation.flush()) == 0
    with pytest.raises(RecordError, match="the stream has ended .flush\\(\\) was called."):
        evaluation.push(record.t[20:21], {c: record[c][20:21] for c in evaluation.columns})


def test_chunks_join_only_in_order(rlc):
    arrs, record = rlc
    evaluation = StreamingEvaluation(arrs[0])
    a = evaluation.push(record.t[:20], {c: record[c][:20] for c in evaluation.columns})
    b = evaluation.push(record.t[20:30], {c: record[c][20:30] for c in evaluation.columns})
    assert isinstance(a, Evaluation) and (len(a), len(b), b.start) == (15, 10, 15)
    with pytest.raises(ValueError, match="a chunk starting at sample 0 does not follow one holding samples 15 to 24"):
        StreamChunk.concatenate([b, a])
