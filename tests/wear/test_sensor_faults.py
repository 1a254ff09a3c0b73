"""Sensor faults: a biased or drifting encoder of the torsion bar, simulated from the physics, then read
through the faulty sensor.  No law of any parameter with a failure value explains the residuals, so the
answer must not claim one: it names the faults, the sensor among them, consistent with the ARRs that
fired, and gives no RUL.
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


@pytest.mark.slow  # a 100 s record and bgphm prognose with the resample-move filter: about 25 s of CPU
def test_a_biased_encoder_is_named_among_the_faults_consistent_and_no_rul_is_claimed():
    scenario = Scenario("torsion_bar", "sensor omega_Ld", "bias", "noisy")
    answer = run(scenario, seed=4, particles=100, rul_every=50, method="resample-move")
    assert answer["exit"] == 0, answer.get("error")
    figures = score(scenario, answer)
    assert figures["found"], (answer["candidate"], answer["status"])
    assert answer["status"] in ("undecided", "rejected") and "sensor omega_Ld" in answer["reason"]
    assert answer["last"].get("rul_median") is None   # no band for a fault without an end of life
