"""Prognosis: degradation models, observation equation, particle filter, variance adaptation, RUL."""

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from bondgraph.library import torsion_bar_monitorable, torsion_bar_with_load
from diagnosis import derive_arrs
from prognosis.degradation import (CustomDegradation, ExponentialDegradation, LinearDegradation, PowerDegradation,
                                   degradation_model)
from prognosis.particle_filter import ParticleFilter, VarianceAdaptation
from prognosis.observation import observation_model
from prognosis.rul import RULPredictor, predict_rul

ROOT = Path(__file__).resolve().parents[2]
t = sp.Symbol("t")
B_N, K_BELT, OMEGA = 5.025e-3, 3.75, 112.5


@pytest.fixture(scope="module")
def torsion_arr():
    return next(a for a in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")
                if a.junction == "1_1")


# -- degradation ---------------------------------------------------------------------------------

@pytest.mark.parametrize("model", [LinearDegradation(process_noise=1e-3), ExponentialDegradation(process_noise=1e-3),
                                   CustomDegradation(lambda th, g, dt: th * np.exp(g[..., 0] * dt),
                                                     process_noise=1e-3)])
def test_horizon_path_equals_stepping(model):
    rng = np.random.default_rng(0)
    theta = rng.uniform(0.5, 1.0, (2, 4))
    gamma = rng.normal(0.1, 0.05, (2, 4, 6, 1))
    noise = rng.normal(0, 1e-3, (2, 4, 6))
    path = model.path(theta, gamma, noise, 0.1)
    current = theta
    for step in range(6):
        current = model.step(current, gamma[..., step, :], 0.1) + noise[..., step]
        assert np.allclose(path[..., step], current, rtol=1e-12)


def test_unknown_degradation_model_names_the_choices():
    with pytest.raises(ValueError, match="linear.*exponential|exponential.*linear"):
        degradation_model("quadratic")


# -- observation equation -----------------------------------------------------------------------

def test_observation_equation_for_b_md_is_eq_52(torsion_arr):
    model = observation_model(torsion_arr, "b_Md")
    b, k, w = sp.Symbol("b_Md"), sp.Symbol("k_belt"), sp.Function("omega_m")(t)
    assert sp.simplify(model.expression - (b - B_N) * (-w / k**2)) == 0
    assert sp.simplify(model.coefficient - (-w / k**2)) == 0  # a_1 = d r_n / d b_Md (eq. 27)
    compiled = torsion_arr.compiled
    points = [np.array([OMEGA if str(p) == "omega_m" else 0.0]) for p in compiled.points]
    theta = np.array([[B_N, 2 * B_N, 0.45]])
    assert np.allclose(model(theta, points), (theta - B_N) * (-OMEGA / K_BELT**2))


def test_observation_equation_for_the_mass_is_eq_62():
    arr = derive_arrs(torsion_bar_with_load(M=0.2), complete=False, integrals="keep")[0]
    model = observation_model(arr, "M")
    M, mu, g, r, k = sp.symbols("M mu g r_Md k_belt")
    w = sp.Function("omega_m")(t)
    expected = (M - 0.2) * (-mu * g * r * sp.sign(w / k) / k)
    assert sp.simplify(model.expression - expected) == 0


def test_mu_uncertainty_enters_the_mass_arr_as_in_eq_58():
    arr = next(a for a in derive_arrs(torsion_bar_with_load(M=0.2), complete=False, integrals="keep")
               if a.junction == "1_1")
    M, mu, g, r, k, d = sp.symbols("M mu g r_Md k_belt delta_mu")
    w = sp.Function("omega_m")(t)
    assert arr.uncertainties["mu"] == (-0.1, 0.1)
    assert sp.simplify(arr.terms["mu"] - (-d * mu * M * g * r * sp.sign(w / k) / k)) == 0


def test_invert_recovers_theta_for_linear_and_nonlinear_observations(torsion_arr):
    from bondgraph import BondGraph

    linear = observation_model(torsion_arr, "b_Md")
    omega = np.array([112.5, 60.0])
    points = [omega if str(p) == "omega_m" else np.zeros(2) for p in torsion_arr.compiled.points]
    theta = np.array([0.01, 0.2])
    y = (theta - B_N) * (-omega / K_BELT**2)  # eq. 52
    assert np.allclose(linear.invert(y, points), theta)  # exact: no bracket needed
    # e = f / k: y = R(k) - R(k_n) = i (1/k_n - 1/k) is not linear in k; a bracketed root search inverts it
    bg = BondGraph()
    bg.add("u", "MSe")
    bg.add("J", "1")
    bg.add("R", "R", param="k", value=2.0, uncertainty=(-0.1, 0.1), law="e - f/k")
    bg.add("i", "Df")
    for tail, head in [("u", "J"), ("J", "R"), ("J", "i")]:
        bg.bond(tail, head)
    model = observation_model(derive_arrs(bg, complete=False, integrals="keep")[0], "k")
    assert model.coefficient is None
    current = np.array([1.0, 3.0, 1.0])
    k_true = np.array([2.5, 4.0, 50.0])
    y = current * (1 / 2.0 - 1 / k_true)
    names = [str(p) for p in model.arr.compiled.points]
    values = [current if n == "i" else np.zeros(3) for n in names]
    assert np.allclose(model(k_true[:, None], values)[:, 0], y)
    found = model.invert(y, values, (2.0, 10.0))
    assert np.allclose(found[:2], k_true[:2]) and np.isnan(found[2])  # k = 50 lies outside the bracket
    with pytest.raises(ValueError, match="'k' is not linear in it: invert needs a bracket"):
        model.invert(y, values)


def test_candidate_the_arr_is_not_sensitive_to(torsion_arr):
    with pytest.raises(ValueError, match="J_Ld"):
        observation_model(torsion_arr, "J_Ld")


# -- particle filter -------------------------------------------------------------------------------

def linear_observation(theta, points):
    """y = -8 (theta - 1): a stand-in observation with a known slope."""
    return -8.0 * (theta - 1.0)


def make_filter(**options):
    defaults = dict(n_particles=400, dt=0.1, noise_std=0.05, inflation=4.0, gamma_std=0.01, seed=3)
    defaults.update(options)
    return ParticleFilter(LinearDegradation(process_noise=1e-3), linear_observation, **defaults)


def test_initialisation_is_uniform_over_the_interval():
    pf = make_filter()
    pf.initialize((0.9, 1.2), assets=3)
    assert pf.theta.shape == (3, 400) and pf.gamma.shape == (3, 400, 1)
    assert pf.theta.min() >= 0.9 and pf.theta.max() <= 1.2
    assert np.allclose(pf.weights.sum(axis=1), 1.0)


def test_fleet_of_assets_is_filtered_in_one_step():
    rates = np.array([0.1, 0.2, 0.4])  # three machines degrading at different speeds
    pf = make_filter(gamma_std=0.02)
    pf.initialize((1.0, 1.0), assets=3)
    rng = np.random.default_rng(0)
    for k in range(1, 301):
        truth = 1.0 + rates * 0.1 * k
        pf.step(-8.0 * (truth - 1.0) + rng.normal(0, 0.05, 3))
    estimate = pf.estimate()
    assert np.allclose(estimate["theta_mean"], 1.0 + rates * 30.0, rtol=0.02)
    assert np.allclose(estimate["gamma_mean"][:, 0], rates, rtol=0.15)


def test_log_weights_survive_hopeless_likelihoods():
    pf = make_filter(resample_below=0.0)
    pf.initialize((0.9, 1.1))
    diagnostics = pf.step(np.array([1e6]))  # every particle is ~1e13 sigma away
    assert not diagnostics.degenerate.any()  # finite log-likelihoods: the best particle wins
    assert np.all(np.isfinite(pf.weights)) and np.isclose(pf.weights.sum(), 1.0)
    assert np.all(np.isfinite(pf.theta))


@pytest.mark.parametrize("options, message", [
    ({"noise_std": -1.0}, r"noise_std must be finite and > 0, got -1.0$"),
    ({"noise_std": 0.0}, r"noise_std must be finite and > 0, got 0.0$"),
    ({"noise_std": [0.1, np.nan]}, r"noise_std must be finite and > 0, got nan in \[0.1, nan\]"),
    ({"noise_std": "x"}, r"noise_std must be a number or an array of numbers, got 'x'"),
    ({"dt": 0.0}, r"dt must be a finite number > 0, got 0.0"),
    ({"dt": np.nan}, r"dt must be a finite number > 0, got nan"),
])
def test_particle_filter_refuses_a_noise_or_step_it_cannot_use(options, message):
    # the likelihood divides by noise_std**2: 0 or NaN used to give NaN weights, -1 a silently squared sign
    with pytest.raises(ValueError, match=message):
        ParticleFilter(LinearDegradation(), lambda theta, points: theta, n_particles=10, **options)


def test_degenerate_weights_are_reset_and_reported():
    pf = ParticleFilter(LinearDegradation(), lambda theta, points: np.full(theta.shape, np.nan), n_particles=50, seed=0)
    pf.initialize((0.9, 1.1))
    diagnostics = pf.step(np.array([0.0]))
    assert diagnostics.degenerate.all()
    assert np.allclose(pf.weights, 1 / 50) and np.all(np.isfinite(pf.theta))


def test_missing_measurement_predicts_without_update():
    pf = make_filter(resample_below=0.0)
    pf.initialize((0.9, 1.1))
    before = pf.weights.copy()
    diagnostics = pf.step(np.array([np.nan]))
    assert not diagnostics.updated.any()
    assert np.allclose(pf.weights, before)


def test_resampling_only_when_ess_is_low():
    pf = make_filter(resample_below=0.5, resampling="stratified")
    pf.initialize((0.99, 1.01))
    diagnostics = pf.step(np.array([0.0]))  # every particle explains y = 0: the ESS stays high
    assert diagnostics.ess[0] >= 0.5 * 400 and not diagnostics.resampled.any()
    assert not np.allclose(pf.weights, 1 / 400)  # the weights carry over, no resampling reset them
    pf.initialize((0.0, 2.0))
    diagnostics = pf.step(np.array([0.0]))  # y = 0 favours theta near 1: the ESS collapses
    assert diagnostics.resampled.all() and diagnostics.ess[0] < 0.5 * 400


def test_filter_is_deterministic_for_a_seed():
    runs = []
    for _ in range(2):
        pf = make_filter(seed=11)
        pf.initialize((0.9, 1.1))
        for y in np.linspace(0, -2, 20):
            pf.step(np.array([y]))
        runs.append(pf.theta.copy())
    assert np.array_equal(*runs)


def test_bad_filter_settings():
    with pytest.raises(ValueError, match="gamma_std"):
        ParticleFilter(LinearDegradation(), linear_observation, gamma_std=[0.1, 0.2])
    with pytest.raises(ValueError, match="inflation"):
        ParticleFilter(LinearDegradation(), linear_observation, inflation=0.0)
    with pytest.raises(ValueError, match="systematic"):
        ParticleFilter(LinearDegradation(), linear_observation, resampling="best")
    fresh = ParticleFilter(LinearDegradation(), linear_observation)
    for use in (lambda: fresh.step(np.array([0.0])), lambda: fresh.weights, lambda: fresh.assets):
        with pytest.raises(RuntimeError, match="call initialize"):
            use()


def test_rul_percentiles_keep_their_columns_without_any_prediction():
    from prognosis.health_monitor import MonitorResult

    assert MonitorResult(detection_time=None).rul_percentiles((5, 50, 95)).shape == (0, 3)
    one = RULPredictor(LinearDegradation(), dt=0.1, theta_fail=2.0, seed=0).predict(
        np.zeros((1, 4)), np.ones((1, 4, 1)), np.full((1, 4), 0.25), 0.0)
    assert MonitorResult(detection_time=0.0, rul=[one, one]).rul_percentiles(50).shape == (2, 1)


# -- variance adaptation (Table III with the sign of docs/design.md) -------------------------------

def test_adaptation_shrinks_a_too_wide_random_walk_inside_the_band():
    adaptation = VarianceAdaptation(band=(0.03, 0.07), reference=0.10, gain=0.01, window=3)
    adaptation.reset()
    rng = np.random.default_rng(0)
    gamma = rng.normal(0.05, 0.02, (1, 1000, 1))  # spread RMAD ~ 27 % > 10 %
    weights = np.full((1, 1000), 1e-3)
    initial = np.array([4e-4])
    variance = adaptation(gamma, weights, initial[None, :].copy(), initial)
    assert variance[0, 0] < initial[0]
    narrow = rng.normal(0.05, 0.001, (1, 1000, 1))  # spread ~1.3 % < 10 %: grow back, capped at the initial value
    assert adaptation(narrow, weights, variance, initial)[0, 0] > variance[0, 0]


def test_adaptation_resets_outside_the_band():
    adaptation = VarianceAdaptation(band=(0.03, 0.07), window=0)
    adaptation.reset()
    gamma = np.full((1, 100, 1), 0.2)  # moving average far above the band
    variance = adaptation(gamma, np.full((1, 100), 0.01), np.array([[1e-6]]), np.array([4e-4]))
    assert variance[0, 0] == 4e-4


# -- RUL ----------------------------------------------------------------------------------------------

def test_deterministic_linear_and_exponential_rul():
    theta, gamma, weights = np.array([[1.0, 2.0]]), np.array([[[0.5], [0.5]]]), np.array([[0.5, 0.5]])
    linear = predict_rul(LinearDegradation(), theta, gamma, weights, dt=0.1, theta_fail=3.0, gamma_std=0.0,
                         rng=np.random.default_rng(0))
    assert np.allclose(linear.samples, [[4.0, 2.0]])  # (3 - theta) / 0.5
    exponential = predict_rul(ExponentialDegradation(), np.array([[0.005025]]), np.array([[[0.05]]]), np.array([[1.0]]),
                              dt=0.1, theta_fail=0.45, gamma_std=0.0, rng=np.random.default_rng(0))
    assert exponential.samples[0, 0] == pytest.approx(np.log(0.45 / 0.005025) / 0.05, abs=0.1)


@pytest.mark.parametrize("model", [LinearDegradation(),
                                   CustomDegradation(lambda theta, gamma, dt: theta + gamma[..., 0] * dt)])
def test_crossing_time_is_interpolated_within_the_step(model):
    # theta = 1 + 0.5 t crosses 1.337 at t = 0.674, between the steps at 0.6 and 0.7; also in a later chunk
    for fail, expected in [(1.337, 0.674), (1.0 + 0.5 * 123.456, 123.456)]:
        rul = predict_rul(model, np.array([[1.0]]), np.array([[[0.5]]]), np.array([[1.0]]), dt=0.1,
                          theta_fail=fail, gamma_std=0.0, rng=np.random.default_rng(0))
        assert rul.samples[0, 0] == pytest.approx(expected, rel=1e-5)


def test_downward_failure_and_censoring():
    theta, weights = np.array([[1.0, 1.0, 1.0]]), np.full((1, 3), 1 / 3)
    gamma = np.array([[[-0.5], [-0.25], [0.0]]])  # the last particle never degrades
    rul = predict_rul(LinearDegradation(), theta, gamma, weights, dt=0.1, theta_fail=0.5, gamma_std=0.0,
                      direction="down", horizon=10.0, rng=np.random.default_rng(0))
    assert np.allclose(rul.samples[0, :2], [1.0, 2.0]) and np.isinf(rul.samples[0, 2])
    assert rul.censored_weight[0] == pytest.approx(1 / 3)
    assert rul.mean[0] == pytest.approx(1.5)  # over crossed particles, reported with the censored weight
    assert rul.median[0] == pytest.approx(2.0)


@pytest.mark.slow
def test_stepwise_and_closed_form_predictions_agree_in_distribution():
    rng = np.random.default_rng(5)
    theta = np.full((1, 4000), 0.05)
    gamma = rng.normal(0.05, 0.005, (1, 4000, 1))
    weights = np.full((1, 4000), 1 / 4000)
    closed = RULPredictor(ExponentialDegradation(1e-4), dt=0.1, theta_fail=0.45, seed=1).predict(theta, gamma, weights,
                                                                                                 0.002)
    custom = CustomDegradation(lambda th, g, dt: th * np.exp(g[..., 0] * dt), process_noise=1e-4)
    stepwise = RULPredictor(custom, dt=0.1, theta_fail=0.45, seed=2).predict(theta, gamma, weights, 0.002)
    a, b = closed.samples[np.isfinite(closed.samples)], stepwise.samples[np.isfinite(stepwise.samples)]
    standard_error = np.hypot(a.std() / np.sqrt(a.size), b.std() / np.sqrt(b.size))
    assert abs(a.mean() - b.mean()) < 4 * standard_error
    assert abs(np.median(a) - np.median(b)) < 4 * 1.2533 * standard_error  # SE of a median ~ 1.25 SE of a mean


def test_a_collapsing_path_is_never_counted_as_a_failure():
    # gamma far below zero: exp(dt * sum gamma) underflows in single precision without the clip
    theta, weights = np.full((1, 50), 0.05), np.full((1, 50), 0.02)
    gamma = np.full((1, 50, 1), -5.0)
    rul = RULPredictor(ExponentialDegradation(1e-4), dt=0.1, theta_fail=0.45, horizon=300.0, seed=0).predict(
        theta, gamma, weights, 0.0)
    assert rul.censored.all()


def test_keyed_predictions_do_not_depend_on_call_order():
    theta, gamma, weights = np.full((1, 200), 0.05), np.full((1, 200, 1), 0.05), np.full((1, 200), 1 / 200)
    forward = RULPredictor(ExponentialDegradation(1e-4), dt=0.1, theta_fail=0.45, seed=7)
    backward = RULPredictor(ExponentialDegradation(1e-4), dt=0.1, theta_fail=0.45, seed=7)
    a = [forward.predict(theta, gamma, weights, 0.01, key=k).samples for k in range(3)]
    b = [backward.predict(theta, gamma, weights, 0.01, key=k).samples for k in reversed(range(3))][::-1]
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert not np.array_equal(a[0], a[1])


def test_successive_predictions_differ_but_are_reproducible():
    theta, gamma, weights = np.full((1, 200), 0.05), np.full((1, 200, 1), 0.05), np.full((1, 200), 1 / 200)
    predictor = RULPredictor(ExponentialDegradation(1e-4), dt=0.1, theta_fail=0.45, seed=7)
    first, second = predictor.predict(theta, gamma, weights, 0.01), predictor.predict(theta, gamma, weights, 0.01)
    again = RULPredictor(ExponentialDegradation(1e-4), dt=0.1, theta_fail=0.45, seed=7).predict(theta, gamma, weights,
                                                                                                0.01)
    assert not np.array_equal(first.samples, second.samples)
    assert np.array_equal(first.samples, again.samples)


@pytest.mark.slow  # a child interpreter and its worker pool: 2-2.5 s
def test_ctrl_c_during_parallel_predictions_reaches_only_the_caller(tmp_path):
    """Ctrl-C signals the whole process group; the prediction workers must leave it to the caller."""
    script = tmp_path / "interrupted.py"
    script.write_text(textwrap.dedent(f"""
        import os, signal, sys, time
        sys.path.insert(0, {str(ROOT)!r})
        signal.signal(signal.SIGINT, signal.default_int_handler)  # a background shell may have ignored it
        import numpy as np
        from prognosis.degradation import LinearDegradation
        from prognosis.rul import ParallelRUL
        try:
            with ParallelRUL(LinearDegradation(), dt=0.1, theta_fail=2.0, workers=2) as pool:
                pool.submit(np.zeros((1, 3)), np.ones((1, 3, 1)), np.full((1, 3), 1 / 3), 0.0, key=0).result()
                os.killpg(os.getpgid(0), signal.SIGINT)
                time.sleep(30.0)
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr)
    """))
    run = subprocess.run([sys.executable, str(script)], start_new_session=True, capture_output=True, text=True,
                         timeout=300)  # guards a hang only: a worker that ignored the interrupt fails the assert
    assert run.stderr.splitlines() == ["interrupted"]  # no KeyboardInterrupt traceback from a worker


@pytest.mark.slow
def test_filter_and_rul_on_the_seed_b_md_problem(torsion_arr):
    """The fault model of Jha et al. (2016), section 6.3, on synthetic y (eqs. 52-53): estimate and predict."""
    observation = observation_model(torsion_arr, "b_Md")
    compiled = torsion_arr.compiled
    points = [np.array([OMEGA if str(p) == "omega_m" else 0.0]) for p in compiled.points]
    pf = ParticleFilter(ExponentialDegradation(1e-5), observation, n_particles=500, dt=0.1, noise_std=0.01,
                        inflation=4.0, gamma_std=0.02, adaptation=VarianceAdaptation(band=(0.03, 0.07)), seed=0)
    pf.initialize((B_N, 1.2 * B_N))
    rng = np.random.default_rng(0)
    predictor = RULPredictor(ExponentialDegradation(1e-5), dt=0.1, theta_fail=0.45, seed=1)
    for k in range(1, 701):  # t = 10.1 .. 80 s
        truth = B_N * np.exp(0.05 * 0.1 * k)
        pf.step(np.array([(truth - B_N) * (-OMEGA / K_BELT**2) + rng.normal(0, 0.01)]), points)
    estimate = pf.estimate()
    assert estimate["theta_mean"][0] == pytest.approx(B_N * np.exp(3.5), rel=0.05)
    rul = predictor.predict(pf.theta, pf.gamma, pf.weights, np.sqrt(pf.variance))
    assert 10.0 < rul.median[0] < 35.0  # true RUL at t = 80 s: 20 s


def test_two_progression_parameters_through_filter_and_rul():
    # theta_k = theta_{k-1} (1 + gamma_1 dt + gamma_2 dt^2): two random-walk progression parameters
    model = CustomDegradation(lambda th, g, dt: th * (1 + g[..., 0] * dt + g[..., 1] * dt**2), n_gamma=2,
                              process_noise=1e-4)
    pf = ParticleFilter(model, linear_observation, n_particles=300, dt=0.1, noise_std=0.05, gamma_std=[0.01, 0.01],
                        seed=2)
    pf.initialize((1.0, 1.0))
    truth = 1.0
    rng = np.random.default_rng(1)
    for _ in range(200):
        truth *= 1 + 0.05 * 0.1
        pf.step(np.array([-8.0 * (truth - 1.0) + rng.normal(0, 0.05)]))
    assert pf.gamma.shape == (1, 300, 2)
    assert pf.estimate()["theta_mean"][0] == pytest.approx(truth, rel=0.05)
    rul = RULPredictor(model, dt=0.1, theta_fail=2 * truth, seed=0).predict(pf.theta, pf.gamma, pf.weights,
                                                                              np.sqrt(pf.variance))
    assert np.isfinite(rul.median[0]) and rul.median[0] > 0


def test_initial_gamma_drawn_over_bounds():
    pf = ParticleFilter(LinearDegradation(), linear_observation, n_particles=400, seed=3)
    pf.initialize((1.0, 1.2), gamma_bounds=(0.03, 0.07), assets=2)
    assert pf.gamma.shape == (2, 400, 1)
    assert pf.gamma.min() >= 0.03 and pf.gamma.max() <= 0.07 and pf.gamma.std() > 0.01
    with pytest.raises(ValueError, match="gamma bounds have lo > hi"):
        pf.initialize((1.0, 1.2), gamma_bounds=(0.07, 0.03))


@pytest.mark.parametrize("law, gamma", [
    (LinearDegradation(), [[0.02], [0.05], [-0.01], [0.0]]),
    (ExponentialDegradation(), [[0.01], [0.04], [-0.02], [0.0]]),
    (PowerDegradation(origin=1.0, span=1.0), [[0.01, 0.7], [0.03, 3.0], [0.02, 1.0], [0.0, 2.0]]),
])
def test_a_noise_free_law_crosses_when_the_same_law_stepped_by_hand_does(law, gamma):
    # the closed-form crossing (noise-free laws, as the resample-move filter's) against the same step
    # function hidden in a CustomDegradation, which the predictor can only step through
    theta = np.array([[1.2, 1.5, 1.1, 1.3]])
    gamma = np.array(gamma, float)[None]
    weights = np.full((1, 4), 0.25)
    stepped = CustomDegradation(law.step, n_gamma=law.n_gamma)
    exact, by_steps = (RULPredictor(m, dt=0.01, theta_fail=2.0, horizon=80.0, seed=0)
                       .predict(theta, gamma, weights, 0.0) for m in (law, stepped))
    assert np.array_equal(np.isfinite(exact.samples), np.isfinite(by_steps.samples))
    assert np.isfinite(exact.samples).sum() >= 2   # at least two particles fail within the horizon
    np.testing.assert_allclose(exact.samples[np.isfinite(exact.samples)],
                               by_steps.samples[np.isfinite(by_steps.samples)], atol=1e-4)
