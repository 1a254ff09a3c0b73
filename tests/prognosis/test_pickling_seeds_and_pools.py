"""Objects that travel: standard pickling, independent random streams per seed, own adaptation copies, no nested pools.

A fleet ships monitors and their parts to pool and Dask workers: they must pickle with the standard
library and compute the same thing on the other side; two seeds must not share a random stream
(the RUL of seed s drew the filter noise of seed s + 1); a monitor inside a daemonic worker cannot
start processes of its own.
"""

import multiprocessing
import pickle
import sys
import warnings

import numpy as np
import pytest

from bondgraph import simulate
from bondgraph.errors import PHMWarning
from bondgraph.library import rlc_circuit
from diagnosis import derive_arrs
from diagnosis.records import add_noise, as_record
from prognosis.degradation import ExponentialDegradation, LinearDegradation
from prognosis.hypotheses import Hypothesis, HypothesisObservation
from prognosis.isolation import IsolatingMonitor
from prognosis.health_monitor import HealthMonitor
from prognosis.observation import observation_model
from prognosis.particle_filter import KernelSmoothing, ParticleFilter, VarianceAdaptation
from prognosis.rul import ParallelRUL, ParallelWarning, RULPredictor
from prognosis.statespace.discrete_model import discretize


def r_drift(t):
    """R from 10 ohm, up 4 ohm/s from t = 0.5 s."""
    return 10.0 + 4.0 * max(0.0, t - 0.5)


@pytest.fixture(scope="module")
def rlc():
    """The RLC circuit's loop ARR and a 2 s record of R drifting up from 0.5 s (noisy current)."""
    bg = rlc_circuit()
    t = np.linspace(0.0, 2.0, 1001)
    clean = simulate(bg, (0.0, 2.0), {"V": lambda t: 5 + np.sin(7 * t)}, t_eval=t, parameters={"R": r_drift})
    record = add_noise(as_record(clean.record()), {"i": 1e-4}, seed=0)
    return bg, derive_arrs(bg, complete=False, integrals="keep")[0], record


@pytest.fixture(scope="module")
def rlc_arrs(rlc):
    """Every ARR of the RLC circuit and a noise-free 1.5 s record of the same drift, for isolation."""
    bg, _, _ = rlc
    t = np.linspace(0.0, 1.5, 1501)
    record = simulate(bg, (0.0, 1.5), {"V": lambda t: 5 + np.sin(7 * t)}, t_eval=t, parameters={"R": r_drift}).record()
    return derive_arrs(bg), record


def make_monitor(arr, **options):
    settings = dict(theta_fail=20.0, dt=0.01, n_particles=100, noise_std=1e-3, gamma_bounds=(0.0, 10.0), rul_every=5,
                    horizon=5.0, detection={"margin": 0.01, "persistence": 5}, seed=3)
    settings.update(options)
    return HealthMonitor(arr, "R", LinearDegradation(), **settings)


def same_results(one, other) -> bool:
    """Bitwise equal estimates and RUL samples of two MonitorResults."""
    arrays = [(one.t, other.t), (one.rul_t, other.rul_t)]
    arrays += [(one.theta[k], other.theta[k]) for k in ("mean", "rmad", "quantiles")]
    arrays += [(one.gamma[k], other.gamma[k]) for k in ("mean", "rmad", "quantiles")]
    arrays += [(a.samples, b.samples) for a, b in zip(one.rul, other.rul)]
    return (one.detection_time == other.detection_time and len(one.rul) == len(other.rul) and one.t.size > 0
            and all(np.array_equal(a, b) for a, b in arrays))


def round_trip(obj):
    return pickle.loads(pickle.dumps(obj))


# -- pickling ------------------------------------------------------------------------------------

def test_observation_models_pickle_after_use_and_predict_the_same(rlc):
    _, arr, _ = rlc
    h = observation_model(arr, "R")
    points = [np.ones(3), np.array([0.5, 1.0, 2.0]), np.zeros(3), np.full(3, 0.1)]
    theta = np.array([9.0, 11.0, 12.0])
    before = h(theta[None, :], [p[:1] for p in points])   # builds the lambdified h
    copy = round_trip(h)
    assert copy._function is None   # left out, rebuilt on first use
    assert np.array_equal(copy(theta[None, :], [p[:1] for p in points]), before)
    assert np.array_equal(copy.invert(np.array([-0.5, -1.0, 0.3]), points), h.invert(np.array([-0.5, -1.0, 0.3]),
                                                                                     points))
    hypotheses = HypothesisObservation([arr], [Hypothesis("R", "linear", 20.0, 10.0)])
    used = hypotheses(np.array([[9.0, 11.0]]), [[1.0, 0.5, 0.0, 0.0]])
    assert np.array_equal(round_trip(hypotheses)(np.array([[9.0, 11.0]]), [[1.0, 0.5, 0.0, 0.0]]), used)


def test_a_fresh_monitor_pickled_gives_bitwise_the_same_results(rlc):
    _, arr, record = rlc
    arr.evaluate(record, margin=0.01)   # a used ARR: its lambdified residual and thresholds are cached
    monitor = make_monitor(arr, adaptation=VarianceAdaptation(band=(0.0, 10.0)))
    copy = round_trip(monitor)
    assert same_results(monitor.run(record), copy.run(record))


def test_a_monitor_after_run_pickles_small_without_the_result(rlc):
    """200 particles over a 500-step horizon: the RUL bank alone is 1.6 MB; the monitor pickles to tens of kB."""
    _, arr, record = rlc
    monitor = make_monitor(arr, n_particles=200, rul_every=25)
    result = monitor.run(record)
    assert monitor.predictor._bank["Z"].nbytes == 200 * 500 * 4 and len(result.rul) == 3
    assert len(pickle.dumps(monitor)) < 50_000 < len(pickle.dumps(result))
    again = round_trip(monitor)
    assert again.result.detection_time is None and monitor.result is result   # the original keeps its result
    assert same_results(again.run(record), monitor.run(record))   # the filter goes on from where it stood


def test_a_streaming_monitor_pickles_whole_and_goes_on(rlc):
    _, arr, record = rlc
    samples = [{name: record[name][row] for name in ("t", *arr.compiled.signals)} for row in range(550, 720)]
    monitor, whole = make_monitor(arr, n_particles=30), make_monitor(arr, n_particles=30)
    for sample in samples[:120]:   # past the alarm (1.26 s)
        monitor.update(sample)
        whole.update(sample)
    assert monitor.result.t.size > 0
    copy = round_trip(monitor)
    for sample in samples[120:]:
        copy.update(sample)
        expected = whole.update(sample)
    assert same_results(copy.result, expected) and copy.result.t.size > monitor.result.t.size


def test_a_predictor_pickles_without_its_bank_and_predicts_the_same():
    predictor = RULPredictor(ExponentialDegradation(1e-4), dt=0.1, theta_fail=0.45, horizon=20.0, seed=4)
    rng = np.random.default_rng(0)
    theta, gamma = rng.uniform(0.01, 0.02, (1, 300)), rng.uniform(0.04, 0.06, (1, 300, 1))
    weights = np.full((1, 300), 1 / 300)
    predictor.predict(theta, gamma, weights, 0.002, key=0)   # a bank of 300 rows
    copy = round_trip(predictor)
    assert copy._bank is None and len(pickle.dumps(predictor)) < 10_000 < predictor._bank["Z"].nbytes
    # fewer particles afterwards: the rebuilt bank keeps its 300 rows, so the permutations are the same
    for key in (None, 5):
        one = predictor.predict(theta[:, :100], gamma[:, :100], weights[:, :100], 0.002, key=key)
        other = copy.predict(theta[:, :100], gamma[:, :100], weights[:, :100], 0.002, key=key)
        assert np.array_equal(one.samples, other.samples)
    assert copy._bank["Z"].shape == (300, 200) and np.array_equal(copy._bank["CV"], predictor._bank["CV"])


def test_a_discrete_model_pickles_and_computes_the_same():
    model = discretize(rlc_circuit().state_equations(), dt=1e-3, augment=["R"], method="rk4")
    x = np.array([0.01, 5e-4, 10.0])
    expected = (model.transition(x, [1.0]), model.transition_jacobian(x, [1.0]), model.measurement_jacobian(x))
    copy = round_trip(model)
    assert not copy._functions
    got = (copy.transition(x, [1.0]), copy.transition_jacobian(x, [1.0]), copy.measurement_jacobian(x))
    assert all(np.array_equal(a, b) for a, b in zip(got, expected))


@pytest.mark.slow   # a second of CPU: the fast tier stays under a minute
def test_an_isolating_monitor_pickles_and_gives_the_same_decision_and_rul(rlc_arrs):
    arrs, record = rlc_arrs
    monitor = IsolatingMonitor(arrs, {"R": 20.0, "L": 2.0}, noise_std={a.name: 1e-3 for a in arrs}, dt=0.01,
                               n_particles=20, detection={"margin": 0.01}, horizon=2.0, seed=2)
    first = monitor.run(record)
    second = round_trip(monitor).run(record)
    assert first.decision.candidate == second.decision.candidate == "R"
    assert np.array_equal(first.log_evidence, second.log_evidence)
    assert all(np.array_equal(a.samples, b.samples) for a, b in zip(first.rul, second.rul)) and first.rul


# -- independent streams ---------------------------------------------------------------------------

def streams_of(run, monkeypatch) -> list:
    """The initial state of every numpy generator that ``run()`` creates, in order.

    Left out: ``default_rng(generator)``, which returns the generator itself, and the probes of
    :func:`~prognosis.hypotheses.indistinguishable_groups`, the same for every seed by design (a
    deterministic test of proportional sensitivities, not a draw of the monitor's).
    """
    created = []
    default_rng = np.random.default_rng

    def recording(*args, **kwargs):
        rng = default_rng(*args, **kwargs)
        if not isinstance(args[0], np.random.Generator) and \
                sys._getframe(1).f_code.co_name != "indistinguishable_groups":
            state = rng.bit_generator.state["state"]
            created.append((state["state"], state["inc"]))
        return rng
    with monkeypatch.context() as patch:
        patch.setattr(np.random, "default_rng", recording)
        run()
    return created


def test_health_monitors_of_neighbouring_seeds_share_no_stream(rlc, monkeypatch):
    """Seed s's RUL bank and predictions, and seed s + 1's filter, once drew from the same generator."""
    _, arr, record = rlc
    used = {seed: streams_of(lambda: make_monitor(arr, seed=seed).run(record), monkeypatch) for seed in (3, 4)}
    # the filter, the bank's two halves, the unkeyed draws and one stream per prediction (15 of them)
    assert all(len(streams) == 19 and len(set(streams)) == 19 for streams in used.values())
    assert not set(used[3]) & set(used[4])


def test_isolating_monitors_of_neighbouring_seeds_share_no_stream(rlc_arrs, monkeypatch):
    arrs, record = rlc_arrs

    def run(seed):
        IsolatingMonitor(arrs, {"R": 20.0}, noise_std={a.name: 1e-3 for a in arrs}, dt=0.01, n_particles=20,
                         rul_every=20, detection={"margin": 0.01}, horizon=2.0, seed=seed).run(record)
    used = {seed: streams_of(lambda: run(seed), monkeypatch) for seed in (0, 1)}
    assert all(len(streams) > 5 and len(set(streams)) == len(streams) for streams in used.values())
    assert not set(used[0]) & set(used[1])


@pytest.mark.parametrize("seed", [-1, 1.5, True, "0"])
def test_a_bad_seed_is_named(rlc, seed):
    _, arr, _ = rlc
    with pytest.raises(ValueError, match="seed must be a whole number >= 0"):
        make_monitor(arr, seed=seed)


def test_a_seed_sequence_is_a_seed_too(rlc):
    _, arr, record = rlc
    one = make_monitor(arr, seed=np.random.SeedSequence(3)).run(record)
    assert same_results(one, make_monitor(arr, seed=3).run(record))


# -- adaptation objects ------------------------------------------------------------------------------

@pytest.mark.parametrize("adaptation", [lambda: VarianceAdaptation(band=(0.0, 1.0), gain=0.05, window=3),
                                        lambda: KernelSmoothing(0.9)])
def test_filters_sharing_an_adaptation_object_work_as_with_their_own(adaptation):
    """Two filters stepped in turn: with one shared object, each adapted on the other's averages too."""
    def filters(first, second):
        pair = [ParticleFilter(LinearDegradation(), lambda theta, points: theta, n_particles=200, dt=1.0,
                               noise_std=0.05, gamma_std=0.05, adaptation=a, seed=seed)
                for a, seed in ((first, 1), (second, 2))]
        for pf, start in zip(pair, (0.0, 5.0)):
            pf.initialize((start, start + 1.0), gamma0=0.1)
        for k in range(1, 15):
            for pf, rate in zip(pair, (0.1, 0.6)):
                pf.step(rate * k + (0.0 if rate < 0.5 else 5.0))
        return pair
    shared = adaptation()
    together, apart = filters(shared, shared), filters(adaptation(), adaptation())
    for one, other in zip(together, apart):
        assert np.array_equal(one.gamma, other.gamma) and np.array_equal(one.variance, other.variance)
    assert together[0].adaptation is not shared   # each filter works on its own copy


@pytest.mark.slow
def test_monitors_sharing_an_adaptation_object_give_the_results_of_separate_ones(rlc):
    """Two monitors fed sample by sample in turn (a stream of two assets)."""
    _, arr, record = rlc
    short = record.between(end=1.4)

    def pair(first, second):
        monitors = [make_monitor(arr, adaptation=a, n_particles=30, rul_every=50, seed=s)
                    for a, s in ((first, 1), (second, 2))]
        results = [None, None]
        for row in range(550, len(short)):   # from 1.1 s; the alarm comes at 1.26 s
            for i, m in enumerate(monitors):
                results[i] = m.update({name: short[name][row] for name in ("t", *arr.compiled.signals)})
        return results
    shared = KernelSmoothing(0.9)   # each move pulls the rates toward the mean it stored last
    together, apart = pair(shared, shared), pair(KernelSmoothing(0.9), KernelSmoothing(0.9))
    assert all(same_results(a, b) for a, b in zip(together, apart))


# -- no nested pools -----------------------------------------------------------------------------

def _run_in_worker(arr, record):
    """A monitor with two RUL workers, inside a pool worker (daemonic): its results and warnings."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = make_monitor(arr).run(record, workers=2)
    return result, [w.category.__name__ for w in caught]


@pytest.mark.slow
def test_run_with_workers_inside_a_daemonic_pool_worker_predicts_in_the_worker(rlc):
    _, arr, record = rlc
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else None)
    with context.Pool(1) as pool:
        result, caught = pool.apply(_run_in_worker, (arr, record))
    assert caught == ["ParallelWarning"]
    assert same_results(result, make_monitor(arr).run(record))


def test_parallel_rul_in_a_daemonic_process_runs_in_it_with_a_warning(monkeypatch):
    monkeypatch.setattr(multiprocessing.current_process(), "daemon", True, raising=False)
    args = (np.zeros((1, 3)), np.ones((1, 3, 1)), np.full((1, 3), 1 / 3), 0.0)
    with pytest.warns(ParallelWarning, match="daemonic"):
        pool = ParallelRUL(LinearDegradation(), dt=0.1, theta_fail=2.0, workers=2)
    with pool:
        assert pool.submit(*args, key=0).result().samples.tolist() == [[2.0, 2.0, 2.0]]
        failed = pool.submit(*args, key=-1)
        with pytest.raises(ValueError, match="key must be a whole number"):
            failed.result()   # raised when asked for, as a worker's error would be


def test_parallel_rul_forks_where_it_can_else_uses_the_default_start(monkeypatch):
    asked = []
    get_context = multiprocessing.get_context

    def recording(method=None):
        asked.append(method)
        return get_context(method)
    monkeypatch.setattr(multiprocessing, "get_context", recording)
    ParallelRUL(LinearDegradation(), dt=0.1, theta_fail=2.0, workers=1).__exit__(None, None, None)
    monkeypatch.setattr(multiprocessing, "get_all_start_methods", lambda: ["spawn"])
    ParallelRUL(LinearDegradation(), dt=0.1, theta_fail=2.0, workers=1).__exit__(None, None, None)
    assert asked == ["fork", None]
    assert issubclass(ParallelWarning, PHMWarning)
