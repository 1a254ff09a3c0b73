"""A drifting parameter in a differentiated ARR: the rate's term, checked on physics we simulate ourselves.

The torsion bar's ARR_1_1 is the time derivative of the motor-side balance, so a friction b_Md
wearing at a rate b' adds ``b' omega_m / k^2`` to its residual: a wear that is linear in time
shows as a step in this residual, not as a ramp.  The record comes from tests/wear (the mechanics
under a digital PI loop integrated exactly), not from the library's simulate.
"""

import pytest
import numpy as np
import sympy as sp

from bondgraph.library import torsion_bar_monitorable
from diagnosis import derive_arrs
from prognosis.observation import observation_model
from tests.wear import run as wear


def test_rate_coefficient_is_the_antiderivative_and_only_for_differentiated_arrs():
    arrs = {a.name: a for a in derive_arrs(torsion_bar_monitorable())}
    t = sp.Symbol("t")
    differentiated = observation_model(arrs["ARR_1_1"], "b_Md")
    assert sp.simplify(sp.diff(differentiated.rate_coefficient, t) - differentiated.coefficient) == 0
    assert observation_model(arrs["ARR_MSO_1"], "b_Md").rate_coefficient is None   # a balance as it stands
    assert observation_model(arrs["ARR_1_1"], "k_s").rate_coefficient is None   # the twist is not measured


@pytest.mark.slow
def test_a_linear_wear_is_explained_by_value_and_rate_on_an_independent_simulation():
    scenario = wear.Scenario("torsion_bar", "b_Md", "linear", "clean")
    record = wear.record(scenario, seed=3)
    arr = next(a for a in derive_arrs(torsion_bar_monitorable()) if a.name == "ARR_1_1")
    evaluation = arr.evaluate(record)
    h = observation_model(arr, "b_Md")
    nominal, failure, onset = h.nominal, scenario.facts.failures["b_Md"], scenario.onset
    rate = (failure - nominal) / (scenario.eol - onset)
    t = evaluation.t
    theta = nominal + rate * np.clip(t - onset, 0.0, None)
    points = [np.asarray(p) for p in evaluation.points]
    with_rate = h(theta[:, None], points, rate=np.where(t > onset, rate, 0.0)[:, None])[:, 0]
    static = h(theta[:, None], points)[:, 0]
    y = -evaluation.residual
    for lo, hi in ((10.5, 12.0), (20.0, 30.0)):
        window = (t >= lo) & (t < hi)
        measured = float(np.mean(y[window]))
        assert abs(float(np.mean(with_rate[window])) - measured) < 0.25 * abs(measured) + 2e-4
        assert abs(float(np.mean(static[window])) - measured) > 5 * abs(float(np.mean(with_rate[window])) - measured)
