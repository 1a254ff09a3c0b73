"""The zoo systems of the scenario suite: the records hold the law, and ``bgphm prognose`` names what wears.

The fast test reads the wearing parameter back from a noise-free record through the system's own
physics (not through the library): nominal up to the onset, the failure value at the end of life.  The
slow one runs a scenario of each system through the command line as the benchmark does.
"""

import numpy as np
import pytest

from tests.wear.laws import LAWS
from tests.wear.run import SYSTEMS, Scenario, record, run, score, truth

ZOO = ["pump_drive", "pipe_tank"]


def _read_back(system: str, columns: dict, nominal: dict) -> np.ndarray:
    """The wearing parameter at every sample, solved from the equation of its element in the record.

    A derivative comes from second-order differences: its error, dt^2/6 times the third derivative, stays
    under 1e-4 of the resistance's drop away from the start-up and the onset.
    """
    def slope(name):
        return np.gradient(columns[name], columns["t"], edge_order=2)

    if system == "pump_drive":   # the armature: u = R_a i + L_a di/dt + k_m omega_p / r_g
        back_emf = nominal["k_m"] * columns["omega_p"] / nominal["r_g"]
        return (columns["u"] - nominal["L_a"] * slope("i") - back_emf) / columns["i"]
    # the pipe: P_s - p_t = L_f dQ/dt + R_f Q
    return (columns["P_s"] - columns["p_t"] - nominal["L_f"] * slope("Q")) / columns["Q"]


@pytest.mark.slow
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
    # and follows the law, but about the jump, where the differences straddle a kink of the current or flow
    away = np.abs(t - facts.onset) > 0.01 * (facts.eol - facts.onset)
    assert np.allclose(seen[away], truth(scenario)(t[away]), rtol=1e-4)


@pytest.mark.slow  # about 5 s of CPU for the two: a record from the physics and bgphm prognose on it
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
