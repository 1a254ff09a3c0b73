"""Degradation laws of a parameter (bondgraph.scenarios): drift's four laws, the spec text and its errors."""

import math

import numpy as np
import pytest

from bondgraph import Degradation, SimulationError, parse_degradation
from bondgraph.scenarios import drift

T = np.array([0.0, 0.5, 1.0, 1.5, 3.0, 7.0])


@pytest.mark.parametrize("law, exponent, formula", [
    ("linear", 1.0, lambda tau: 2.0 + 0.3 * tau),
    ("exponential", 1.0, lambda tau: 2.0 * np.exp(0.3 * tau)),
    ("power", 2.5, lambda tau: 2.0 + 0.3 * tau ** 2.5),
])
def test_each_law_is_nominal_until_the_onset_then_its_formula(law, exponent, formula):
    value = drift(2.0, 0.3, onset=1.0, law=law, exponent=exponent)(T)
    before = T <= 1.0
    assert np.all(value[before] == 2.0)
    assert value[~before] == pytest.approx(formula(T[~before] - 1.0), rel=1e-14)
    assert isinstance(drift(2.0, 0.3, 1.0, law, exponent)(3.0), float)


def test_a_step_changes_the_value_at_the_onset_itself():
    law = drift(2.0, -0.5, onset=1.5, law="step")
    assert law(T).tolist() == [2.0, 2.0, 2.0, 1.5, 1.5, 1.5]
    assert law(np.nextafter(1.5, 0.0)) == 2.0 and law(1.5) == 1.5


def test_the_linear_and_exponential_laws_keep_their_values_bit_for_bit():
    # the laws the examples and tests have simulated since drift had two: the same floats
    t = np.linspace(0.0, 10.0, 1001)
    assert np.array_equal(drift(1e-4, 0.8, 1.0, "exponential")(t), 1e-4 * np.exp(0.8 * np.maximum(t - 1.0, 0.0)))
    assert np.array_equal(drift(10.0, 6.0, 0.5)(t), 10.0 + 6.0 * np.maximum(t - 0.5, 0.0))


def test_drift_refuses_an_unknown_law_or_exponent():
    with pytest.raises(ValueError, match="law must be one of 'linear', 'exponential', 'power', 'step', got 'cubic'"):
        drift(1.0, 1.0, law="cubic")
    for exponent in (0.0, -1.0, math.inf):
        with pytest.raises(ValueError, match="exponent of a power law must be a finite number > 0"):
            drift(1.0, 1.0, law="power", exponent=exponent)


@pytest.mark.parametrize("text, expected", [
    ("exp:0.05@10", Degradation("exponential", 0.05, 10.0)),
    ("lin:-2e-3@0.5", Degradation("linear", -2e-3, 0.5)),
    ("pow:2e-4^1.5@1", Degradation("power", 2e-4, 1.0, 1.5)),
    ("step:3e-4@2", Degradation("step", 3e-4, 2.0)),
    ("exponential:0.8", Degradation("exponential", 0.8, 0.0)),          # the long name; no onset: from 0
    (" Linear : 1 @ 2 ", Degradation("linear", 1.0, 2.0)),              # spaces and case
])
def test_the_spec_text_reads_law_rate_exponent_and_onset(text, expected):
    law = parse_degradation(text)
    assert law == expected
    assert parse_degradation(str(law)) == law                            # written back as it reads


def test_a_parsed_law_is_drifts_law_on_the_nominal_value():
    law = parse_degradation("pow:2e-4^1.5@1")
    assert np.array_equal(law.truth(1e-4)(T), drift(1e-4, 2e-4, 1.0, "power", 1.5)(T))


@pytest.mark.parametrize("text, message", [
    ("exp0.05@10", "'exp0.05@10' has no law"),
    ("exq:1@1", "unknown law 'exq'"),
    ("exp:fast@10", "the rate 'fast' is not a number"),
    ("exp:0.05@soon", "the onset 'soon' is not a number"),
    ("exp:@10", "the rate '' is not a number"),
    ("exp:nan@10", "the rate must be finite, got 'nan'"),
    ("lin:1@1e999", "the onset must be finite"),
    ("pow:2e-4@1", "a power law needs its exponent: pow:RATE^EXPONENT@ONSET"),
    ("pow:2e-4^two@1", "the exponent 'two' is not a number"),
    ("pow:2e-4^-1@1", "the exponent must be > 0, got '-1'"),
    ("lin:2e-4^2@1", "only a power law has an exponent, got '2e-4^2' for the law 'linear'"),
    ("exp:__import__('os')@1", "the rate \"__import__('os')\" is not a number"),
])
def test_a_bad_spec_text_names_the_parameter_and_the_bad_part(text, message):
    with pytest.raises(SimulationError) as error:
        parse_degradation(text, where="b")
    assert str(error.value).startswith("b: ") and message in str(error.value)
    assert "\n" not in str(error.value)


def test_a_law_leaving_the_physical_domain_or_overflowing_is_refused():
    positive = (0.0, math.inf)
    Degradation("linear", -2e-5, 1.0).check_domain(1e-4, positive, 4.0, where="b")      # 4e-5 at 4 s: fine
    with pytest.raises(SimulationError, match=r"^b: the law takes the value from 0.0001 to -0.0002 by t = 4 s, "
                                              r"outside the physical domain \(0, inf\)"):
        Degradation("linear", -1e-4, 1.0).check_domain(1e-4, positive, 4.0, where="b")
    with pytest.raises(SimulationError, match="from 0.0001 to -0.0001 by t = 4 s"):
        Degradation("step", -2e-4, 3.0).check_domain(1e-4, positive, 4.0, where="b")
    Degradation("step", -2e-4, 5.0).check_domain(1e-4, positive, 4.0, where="b")       # the step comes later
    with pytest.raises(SimulationError, match="^b: the value overflows to infinity by t = 4 s"):
        Degradation("exponential", 1000.0).check_domain(1e-4, positive, 4.0, where="b")
