"""A sensor's fault as a hypothesis: an offset of its reading (a bias or a drift) or a gain, weighed with the wear.

The observation model of an offset is judged on the torsion bar's physics written apart from the
library (:mod:`tests.wear.torsion`): the residuals of the record read through the faulty sensor,
minus those of the same record read through a healthy one, are what the model predicts from the
true offset and its rate.
"""

import math

import numpy as np
import pytest
import sympy as sp

from bondgraph.library import torsion_bar_monitorable
from diagnosis import derive_arrs
from prognosis.errors import PrognosisError
from prognosis.hypotheses import (SENSOR_LAWS, Hypothesis, HypothesisObservation, candidate_model, sees,
                                  sensor_signal)
from prognosis.isolation import IsolatingMonitor
from prognosis.observation import sensor_model
from tests.wear import torsion
from tests.zoo.models.quarter_car import build as quarter_car

ONSET, T_END, DT = 2.0, 6.0, 0.01


@pytest.fixture(scope="module")
def arrs():
    return derive_arrs(torsion_bar_monitorable())


@pytest.fixture(scope="module")
def healthy():
    return torsion.simulate({}, t_end=T_END, dt=DT, noise={}, seed=0)


@pytest.mark.parametrize("signal, size, slope, kind", [
    ("omega_Ld", 0.5, 0.0, "offset"),     # a slipped code disc: a bias from the onset
    ("omega_m", 0.0, 0.8, "offset"),      # a tachogenerator's brushes: a drift from the onset, 0.8 rad/s per s
    ("omega_m", -0.3, -0.2, "offset"),    # both, downward
    ("omega_Ld", 0.02, 0.0, "gain"),      # an encoder's line count 2 % off: a gain from the onset
    ("omega_m", 0.0, 0.01, "gain"),       # an amplifier's gain ageing, 1 % of the reading per s
])
def test_the_sensor_model_predicts_what_the_faulty_reading_does_to_every_residual(arrs, healthy, signal, size,
                                                                                  slope, kind):
    t = healthy["t"]
    error = np.where(t >= ONSET, size + slope * (t - ONSET), 0.0)
    # an offset adds to the true signal; a gain's share g of the reading is error: reading = s / (1 - g)
    reading = healthy[signal] + error if kind == "offset" else healthy[signal] / (1 - error)
    faulty = {**healthy, signal: reading}
    # away from the onset's kink, where the derivative stencils straddle it
    settled = (t > ONSET + 0.2) & (t < T_END - 0.2)
    for arr in arrs:
        if signal not in arr.signals:
            continue
        before, after = arr.evaluate(healthy), arr.evaluate(faulty)
        change = -(after.residual - before.residual)   # y = -r_n, against the healthy reading's
        model = sensor_model(arr, signal, kind)
        points = [np.asarray(p)[settled] for p in after.points]
        predicted = model(error[settled][:, None], points, rate=np.full((settled.sum(), 1), slope))[:, 0]
        scale = max(np.max(np.abs(change[settled])), 1e-9)
        assert np.max(np.abs(predicted - change[settled])) <= 1e-3 * scale, (arr.name, signal)


def test_a_sensor_is_a_candidate_of_the_arrs_that_read_it(arrs):
    for arr in arrs:
        assert sees(arr, "sensor omega_m") == ("omega_m" in arr.signals)
        assert sees(arr, "b_Md") == ("b_Md" in arr.parameters)
    assert sensor_signal("sensor tau_m") == "tau_m" and sensor_signal("J_m") is None
    model = candidate_model(arrs[0], "sensor omega_m")
    assert model.candidate == "sensor omega_m" and model.nominal == 0.0
    with pytest.raises(PrognosisError, match="does not read 'speed'"):
        sensor_model(arrs[0], "speed")


def test_sensor_hypotheses_have_no_failure_value_and_any_sign():
    bias, drift, gain = (Hypothesis.of_sensor("omega_m", law) for law in SENSOR_LAWS)
    assert (bias.law, drift.law, gain.law) == ("bias", "drift", "gain")
    assert bias.sensor and not Hypothesis("k", "linear", 2, 1).sensor
    assert math.isnan(drift.failure) and drift.domain == (-math.inf, math.inf)
    with pytest.raises(PrognosisError, match="a sensor's law is one of bias, drift, gain, got 'linear'"):
        Hypothesis.of_sensor("omega_m", "linear")


def test_a_bias_has_rate_zero_and_a_drift_the_sign_of_the_offset_seen(arrs):
    monitor = IsolatingMonitor(arrs, {"b_Md": 0.45}, noise_std={a.name: 0.1 for a in arrs}, n_particles=50,
                               dt=0.1)
    bias, drift, _ = (Hypothesis.of_sensor("omega_Ld", law) for law in SENSOR_LAWS)
    rng = np.random.default_rng(1)
    assert (monitor.priors.rate_particles(bias, rng, offset=0.4) == 0).all()
    down = monitor.priors.rate_particles(drift, rng, offset=-0.4)[:, 0]
    life = np.array(monitor.settings.life) * monitor.settings.dt
    assert (down < 0).all() and 0.4 / life[1] <= -down.max() and -down.min() <= 0.4 / life[0]
    assert monitor.priors.gamma_bounds(bias, 2, offset=0.4) == ([0.0, 1.0], [0.0, 1.0])


def test_the_observation_of_a_sensor_row_predicts_on_the_arrs_reading_it(arrs):
    hypotheses = [Hypothesis.of_sensor("tau_m", "bias"), Hypothesis("b_Md", "linear", 0.45, 0.005025),
                  Hypothesis.of_sensor("tau_m", "gain")]
    observation = HypothesisObservation(arrs, hypotheses)
    reads = [("tau_m" in a.signals) for a in arrs]
    assert [m is not None for m in observation.models[0]] == reads
    points = [[2.0] * len(a.compiled.points) for a in arrs]
    y = observation(np.array([[0.2], [0.005025], [0.1]]), points)
    mso = [a.name for a in arrs].index("ARR_MSO_1")
    assert y[0, 0, mso] == pytest.approx(-0.2)   # the torque's reading 0.2 high: the balance is 0.2 short
    assert np.allclose(y[1], 0.0)                # b_Md at nominal moves nothing
    assert y[2, 0, mso] == pytest.approx(-0.2)   # a tenth of a 2 N.m reading in error: the same 0.2


def test_a_sensor_read_inside_an_integral_is_named_and_not_weighed():
    arrs = derive_arrs(quarter_car(), complete=False, integrals="keep")
    # an ARR that integrates a reading (a spring's deflection, the integral of a speed difference)
    integrated, signal = next((a, f.func.__name__) for a in arrs for i in a.nominal.atoms(sp.Integral)
                              for f in i.atoms(sp.core.function.AppliedUndef))
    with pytest.raises(PrognosisError, match=f"the sensor of '{signal}' is read inside Integral"):
        sensor_model(integrated, signal)
    assert IsolatingMonitor._unmodelled(f"sensor {signal}", arrs).startswith(integrated.name)
    assert IsolatingMonitor._unmodelled("b_Md", arrs) == ""


def test_an_unknown_sensor_candidate_is_refused_by_name(arrs):
    with pytest.raises(PrognosisError, match="candidate 'sensor speed' has no failure value and is no sensor"):
        IsolatingMonitor(arrs, {"b_Md": 0.45}, noise_std={a.name: 0.1 for a in arrs}, dt=0.1,
                         candidates=["b_Md", "sensor speed"])
    monitor = IsolatingMonitor(arrs, {"b_Md": 0.45}, noise_std={a.name: 0.1 for a in arrs}, dt=0.1,
                               candidates=["b_Md", "sensor omega_m"])
    assert [h.name for h in monitor.priors.hypotheses_for(list(monitor.settings.candidates))[0]][-3:] == [
        "sensor omega_m/bias", "sensor omega_m/drift", "sensor omega_m/gain"]


def test_observation_equations_are_derived_once_per_arr_content_and_anew_for_a_changed_arr():
    import dataclasses

    from bondgraph.library import rlc_circuit
    from diagnosis import derive_arrs
    from prognosis.hypotheses import candidate_model

    first, again = derive_arrs(rlc_circuit())[0], derive_arrs(rlc_circuit())[0]
    assert candidate_model(first, "R") is candidate_model(again, "R")   # equal content, one derivation
    assert candidate_model(first, "sensor i", "gain") is not candidate_model(first, "sensor i", "bias")
    other = dataclasses.replace(first, values={**first.values, "L": 2 * first.values["L"]})
    model = candidate_model(other, "R")
    assert model is not candidate_model(first, "R") and model.arr.values["L"] == 2 * first.values["L"]
