"""NASA's ProgPy on our models (prognosis.progpy_export, the ``progpy`` extra): its simulation to threshold
fails when our law says and follows our simulation; its particle filter and Monte Carlo predictor find the
wear; its metrics score our own RUL predictions as computed by hand."""

import importlib

import numpy as np
import pytest

from bondgraph import Degradation, simulate
from bondgraph.library import torsion_bar
from prognosis import ExponentialDegradation, RULDistribution, alpha_lambda, predict_rul, to_progpy, to_progpy_samples
from tests.interop.progpy_wear import progpy_filter_run

pytestmark = [pytest.mark.interop, pytest.mark.slow]   # ProgPy imports pandas and matplotlib; runs take seconds


def zoo(name):
    return importlib.import_module(f"tests.zoo.models.{name}").CASE.build


# model, degrading parameter, its law, failure value, constant inputs, ProgPy's step (1/2000 of the life or less)
RUNS = {
    "rc_ladder2": (zoo("rc_ladder2"), "R_1", Degradation("linear", 1900.0), 3000.0, {"V_s": 5.0}, 5e-4),
    "two_mass_drive": (zoo("two_mass_drive"), "b1", Degradation("exponential", 1.0, onset=0.2), 15.0, {"F": 4.0},
                       8e-4),
    # q_i, the heat through the inner film, depends on the input T_i: ProgPy's output reads the held input
    "wall_two_layer": (zoo("wall_two_layer"), "R_m", Degradation("linear", -5e-6), 0.5, {"T_i": 293.0, "T_o": 273.0},
                       60.0),
    "torsion_bar": (torsion_bar, "b_Md", Degradation("exponential", 2.0, onset=0.5), 20 * 5.025e-3, {"U": 6.0},
                    1e-3),
}


def failure_time(law: Degradation, nominal: float, failure: float) -> float:
    """When the law reaches the failure value, from its closed form (not from a simulation)."""
    if law.law == "exponential":
        return law.onset + np.log(failure / nominal) / law.rate
    return law.onset + (failure - nominal) / law.rate


@pytest.mark.parametrize("name", sorted(RUNS))
def test_progpy_fails_when_our_law_says_and_follows_our_simulation(name):
    build, parameter, law, failure, inputs, dt = RUNS[name]
    bg = build()
    model = to_progpy(bg, degradation={parameter: law}, failures={parameter: failure})
    nominal = bg.parameters[parameter]
    result = model.simulate_to_threshold(lambda t, x=None: model.InputContainer(inputs), dt=dt, save_freq=50 * dt)
    truth = failure_time(law, nominal, failure)
    assert abs(result.times[-1] - truth) <= 1e-3 * truth                         # 0.1 %: one step at most
    assert result.event_states[-1][f"{parameter} failure"] == 0.0
    times = np.array(result.times)
    ours = simulate(bg, (0.0, times[-1]), inputs, parameters={parameter: law.truth(nominal)}, t_eval=times)
    for signal in model.outputs:
        theirs = np.array([z[signal] for z in result.outputs])
        assert np.max(np.abs(theirs - ours[signal])) <= 2e-4 * np.ptp(ours[signal]), signal


def test_an_output_of_an_input_reads_the_input_last_given():
    bg = zoo("wall_two_layer")()
    model = to_progpy(bg, degradation={"R_m": "linear"}, failures={"R_m": 0.5})
    indoor = lambda t: 293.0 + 5.0 * np.sin(2 * np.pi * t / 86400.0)        # noqa: E731, a daily heating cycle
    dt, x = 60.0, model.initialize()
    times, heat = np.arange(1, 721) * dt, []
    for t in times:
        u = model.InputContainer({"T_i": indoor(t - dt / 2), "T_o": 273.0})   # ProgPy's own midpoint load
        x = model.next_state(x, u, dt)
        heat.append(model.output(x)["q_i"])
        assert model.held_input == [indoor(t - dt / 2), 273.0]
    ours = simulate(bg, (0.0, times[-1]), {"T_i": indoor, "T_o": 273.0}, t_eval=times)
    assert np.max(np.abs(np.array(heat) - ours["q_i"])) <= 2e-3 * np.ptp(ours["q_i"])


def test_progpy_particle_filter_and_monte_carlo_find_the_wear():
    run = progpy_filter_run(noise_seed=0, filter_seed=1)
    assert abs(run["b"] / run["b_true"] - 1.0) < 0.03
    assert abs(run["rate"] - run["rate_true"]) < 0.05
    assert abs(run["rul"] / run["rul_true"] - 1.0) < 0.1


@pytest.fixture(scope="module")
def our_rul():
    """Our predict_rul from weighted particles of (b, rate) at t = 3 s, the tutorial's friction."""
    rng = np.random.default_rng(7)
    n = 200
    theta = (4.95e-4 * (1.0 + 0.02 * rng.standard_normal(n)))[None]
    gamma = (0.8 + 0.05 * rng.standard_normal(n))[None, :, None]
    weights = rng.dirichlet(np.full(n, 5.0))[None]
    rul = predict_rul(ExponentialDegradation(), theta, gamma, weights, dt=0.01, theta_fail=2e-3, gamma_std=0.0,
                      horizon=20.0, rng=np.random.default_rng(8))
    return RULDistribution(samples=rul.samples, weights=rul.weights, horizon=rul.horizon, origin=3.0)


def test_progpy_metrics_on_our_rul_are_those_computed_by_hand(our_rul):
    from progpy.metrics import prob_success
    from progpy.predictors import ToEPredictionProfile

    equal = RULDistribution(samples=our_rul.samples[0], origin=3.0)          # equal weights: samples as they are
    toe = to_progpy_samples(equal, "b failure")
    eol = np.sort(3.0 + equal.samples)
    n = eol.size
    metrics = toe.metrics()["b failure"]
    assert metrics["mean"] == pytest.approx(np.mean(eol), rel=1e-12)
    assert metrics["percentiles"]["10"] == eol[n // 10] and metrics["percentiles"]["75"] == eol[3 * n // 4]
    # ProgPy's median of samples is the sample nearest their mean (least sum of squared distances)
    assert metrics["median"] == eol[np.argmin(np.abs(eol - np.mean(eol)))]
    for time in (4.5, 4.75, 5.0):
        assert prob_success(toe, time)["b failure"] == pytest.approx(np.mean(eol > time), abs=1e-15)
        assert prob_success(toe, time)["b failure"] == pytest.approx(1.0 - equal.probability_before(time - 3.0))
    weighted = np.sort([s["b failure"] for s in to_progpy_samples(our_rul, "b failure", size=400, relative=True)])
    assert np.array_equal(weighted, np.sort(our_rul.quantile((np.arange(400) + 0.5) / 400)[0]))
    profile = ToEPredictionProfile()
    profile.add_prediction(3.0, toe)
    from progpy.metrics import alpha_lambda as their_alpha_lambda
    truth = 1.0 + np.log(20.0) / 0.8
    for alpha in (0.05, 0.2):
        theirs = their_alpha_lambda(profile, {"b failure": truth}, 3.0, alpha, 0.5)["b failure"]
        _, passed = alpha_lambda(equal.samples[None], np.full((1, n), 1.0 / n), np.array([truth - 3.0]),
                                 alpha=alpha, beta=0.5)
        inside = np.mean(np.abs(eol - truth) <= alpha * (truth - 3.0))
        assert theirs == bool(passed[0]) == (inside >= 0.5)
