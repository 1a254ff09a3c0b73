"""Sensor faults: a biased or drifting encoder of the torsion bar, simulated from the physics, then read
through the faulty sensor.  The sensors' offsets compete with the parameters' wear as hypotheses: the
answer names the sensor (with the one whose signature it shares) and its law, and gives no RUL, since
nothing wears.
"""

import pytest

from tests.wear.run import SYSTEMS, Scenario, record, run, score, truth


@pytest.mark.slow  # three 100 s records of the torsion bar's physics: about 20 s of CPU
def test_the_sensor_scenarios_offset_only_their_sensor_from_the_onset():
    facts = SYSTEMS["torsion_bar"]
    healthy = facts.simulate({}, t_end=facts.t_end, dt=facts.dt, noise={}, seed=2)
    for signal, (law, size) in facts.sensors.items():
        scenario = Scenario("torsion_bar", f"sensor {signal}", law, "clean")
        faulty = record(scenario, seed=2, noise={})
        offset = faulty[signal] - healthy[signal]
        assert (offset[faulty["t"] < facts.onset] == 0).all() and offset[-1] == pytest.approx(size, rel=1e-9)
        assert offset == pytest.approx(truth(scenario)(faulty["t"]), abs=1e-9)
        for other in set(faulty) - {signal, "t"}:   # the machine itself stays healthy
            assert (faulty[other] == healthy[other]).all()


@pytest.mark.slow  # a 100 s record and bgphm prognose, each filter: about 60 s of CPU in all
@pytest.mark.parametrize("signal, method", [("omega_Ld", "resample-move"), ("omega_m", "sir")])
def test_a_faulty_encoder_and_its_law_are_named_and_no_rul_is_claimed(signal, method):
    law = SYSTEMS["torsion_bar"].sensors[signal][0]
    scenario = Scenario("torsion_bar", f"sensor {signal}", law, "noisy")
    answer = run(scenario, seed=4, particles=100, rul_every=50, method=method)
    assert answer["exit"] == 0, answer.get("error")
    figures = score(scenario, answer)
    assert figures["found"], (answer["candidate"], answer["status"])
    assert answer["status"] in ("isolated", "indistinguishable") and answer["degradation"] == law
    probabilities = {name: e["probability"] for name, e in answer["evidence"].items()}
    best = max(probabilities, key=probabilities.get)
    assert best.endswith(f"/{law}"), probabilities
    # the two encoders act nearly in proportion at a steady speed: either is named with the reason
    assert best == f"sensor {signal}/{law}" or answer["indistinguishable_on_record"], probabilities
    assert answer["last"].get("rul_median") is None   # no band for a fault without an end of life
