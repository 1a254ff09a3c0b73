"""The zoo systems of the scenario suite: the records hold the law, and ``bgphm prognose`` names what wears.

The fast test reads the wearing parameter back from a noise-free record through the system's own
physics (not through the library): nominal up to the onset, the failure value at the end of life.  The
slow one runs a scenario of each system through the command line as the benchmark does.
"""

import numpy as np
import pytest

from tests.wear.laws import LAWS
from tests.wear.run import SYSTEMS, Scenario, record, run, score, truth

ZOO = ["heat_exchanger", "pipe_tank"]


def _read_back(system: str, columns: dict, nominal: dict) -> np.ndarray:
    """The wearing parameter at every sample, solved from the equation of its element in the record."""
    if system == "heat_exchanger":   # the wall: q_w = (T_h - T_c) / R_w
        return (columns["T_h"] - columns["T_c"]) / columns["q_w"]
    # the pipe: P_s - p_t = L_f dQ/dt + R_f Q; the flow's derivative by second-order differences, whose
    # error (dt^2 Q''' / 6, largest in the start-up's swings) stays under 1e-4 of the friction's drop
    slope = np.gradient(columns["Q"], columns["t"], edge_order=2)
    return (columns["P_s"] - columns["p_t"] - nominal["L_f"] * slope) / columns["Q"]


@pytest.mark.parametrize("system", ZOO)
def test_the_record_holds_the_nominal_value_before_the_onset_and_the_failure_value_at_the_end_of_life(system):
    facts = SYSTEMS[system]
    parameter = facts.wearing[0]
    nominal, failure = facts.nominal[parameter], facts.failures[parameter]
    before = np.linspace(0.0, facts.onset, 7)
    for law in LAWS:
        theta = truth(Scenario(system, parameter, law, "clean"))
        assert np.all(theta(before) == nominal) and theta(facts.eol) == pytest.approx(failure, rel=1e-12)
    # the step then drift law jumps at the onset: the integration restarts there
    scenario = Scenario(system, parameter, "step_then_drift", "noisy")
    columns = record(scenario, seed=0, noise={})
    assert columns["t"][-1] == facts.t_end == facts.eol
    # from the start-up's end: the system starts at rest, with no flow to read a resistance from
    late = columns["t"] >= 0.2 * facts.onset
    columns = {k: v[late] for k, v in columns.items()}
    t, seen = columns["t"], _read_back(system, columns, facts.nominal)
    assert np.allclose(seen[t < facts.onset], nominal, rtol=1e-4)
    assert seen[-1] == pytest.approx(failure, rel=1e-4)
    # and follows the law, but for a second about the jump, which the flow's differences straddle
    away = np.abs(t - facts.onset) > 1.0
    assert np.allclose(seen[away], truth(scenario)(t[away]), rtol=1e-4)


@pytest.mark.slow  # about 10 s of CPU for the two: a record from the physics and bgphm prognose on it
@pytest.mark.parametrize("system", ZOO)
def test_prognose_names_the_wearing_parameter_of_a_zoo_system(system):
    facts = SYSTEMS[system]
    scenario = Scenario(system, facts.wearing[0], "linear", "noisy")
    answer = run(scenario, seed=1, particles=100, rul_every=50)
    assert answer["exit"] == 0, answer.get("error")
    figures = score(scenario, answer)
    # named, or an honest "indistinguishable" / "undecided" group that holds it
    assert figures["found"], (figures["candidate"], figures["status"])
    assert answer["detection_time"] is not None and facts.onset < answer["detection_time"] < facts.eol
