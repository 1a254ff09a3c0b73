"""Two parameters wearing at once: the pump drive's brushes (R_a, linearly to 2.0 s) and its impeller's
load (c_p, exponentially, failing first at 1.6 s), simulated from the physics and run through
``bgphm prognose --filter resample-move`` as a user would.  The brushes' ARR fires first; the answer must
name both, and the RUL must be the first failure's, not the brushes'.
"""

import numpy as np
import pytest

from tests.wear.run import SYSTEMS, Scenario, fault_of, laws, record, run, same_fault, score

PAIR = Scenario("pump_drive", "R_a + c_p", "linear + exponential", "noisy")


@pytest.mark.slow   # a second of CPU: the fast tier stays under a minute
def test_the_concurrent_scenario_wears_both_parameters_each_to_its_failure_at_its_own_end_of_life():
    facts = SYSTEMS["pump_drive"]
    theta = laws(PAIR)
    assert set(theta) == {"R_a", "c_p"} and PAIR.eol == 1.6
    for name, _, eol in PAIR.wearing:
        assert theta[name](facts.onset) == facts.nominal[name]
        assert theta[name](eol) == pytest.approx(facts.failures[name], rel=1e-12)
    # both change the record: each alone gives another one
    both = record(PAIR, seed=0, noise={})
    alone = facts.simulate({"R_a": theta["R_a"]}, t_end=facts.t_end, dt=facts.dt, noise={}, seed=0)
    late = both["t"] > 1.0
    assert np.max(np.abs(both["omega_p"][late] - alone["omega_p"][late])) > 1.0   # rad/s: the pump slows
    assert same_fault("c_p + R_a", PAIR.parameter) and fault_of("R_a/linear + c_p/exponential") == "R_a + c_p"


@pytest.mark.slow  # a 2 s record of the pump's physics and bgphm prognose, twice: about 70 s of CPU
def test_two_parameters_wearing_at_once_are_named_together_and_the_first_failure_is_predicted():
    # by default: single faults first, and since none explains the residuals, pairs on the whole record
    answer = run(PAIR, seed=5, particles=60, rul_every=80, method="resample-move")
    assert answer["exit"] == 0, answer.get("error")
    assert answer["pairs"] == "weighed: no single fault explained the residuals"
    figures = score(PAIR, answer)
    # named, alone or with a pair the record cannot tell from it (the bearing's friction b_m omega acts
    # nearly like the impeller's c_p omega^2 at a steady speed), never a single parameter
    assert figures["found"], (answer["candidate"], answer["status"])
    named = answer["candidate"] if isinstance(answer["candidate"], list) else [answer["candidate"]]
    assert all(" + " in c for c in named) and len(named) <= 2, named
    top = answer["evidence"][figures["top"]]
    assert " + " in figures["top"] and set(top["parameters"]) == set(fault_of(figures["top"]).split(" + "))
    # the RUL is c_p's (at 1.6 s), not the brushes' (at 2.0 s): over the last third of c_p's life the
    # band holds the first failure and its median is far from the brushes' end
    late = [p for p in answer["predictions"] if 1.1 < p["t"] < PAIR.eol and not p.get("withheld")]
    assert late
    for p in late:
        first, brushes = PAIR.eol - p["t"], 2.0 - p["t"]
        assert p["rul_p5"] <= first <= p["rul_p95"], p
        assert abs(p["rul_median"] - first) < abs(p["rul_median"] - brushes), p


@pytest.mark.slow  # 300 s of the pipe's physics and bgphm prognose with pairs: about 20 s of CPU
def test_a_single_wear_weighed_with_pairs_is_not_called_two_faults():
    # the pipe's strainer clogging alone, the noisy flow meter's derivative in the residual: a pair of
    # it with the pipe's inertance beat it on evidence, the inertance kept within its tolerance
    single = Scenario("pipe_tank", "R_f", "linear", "noisy")
    answer = run(single, seed=20261127, particles=60, rul_every=80, method="resample-move", pairs=True)
    assert answer["exit"] == 0, answer.get("error")
    assert answer["candidate"] == "R_f" and " + " not in score(single, answer)["top"], answer["candidate"]
    # a pair held back has probability 0; one that loses on evidence, a negligible one (1e-70 here)
    held = [name for name, e in answer["evidence"].items() if " + " in name and e["probability"] > 1e-9]
    assert not held, held


@pytest.mark.slow  # 2 s of the pump's physics and bgphm prognose with pairs: about 40 s of CPU
def test_a_wear_no_law_fits_is_not_bent_into_two_faults():
    # the pump's brushes wearing by a logistic curve, which no law follows: a second parameter bends the brushes'
    # law into it (the gear ratio, whose own ARR, the pump's, never fires; the inductance, seen by the brushes'
    # ARR alone), and "R_a + r_g" was claimed, isolated, with R_a past its failure value and the RUL 0 from mid-life
    single = Scenario("pump_drive", "R_a", "logistic", "noisy")
    answer = run(single, seed=20261126, particles=60, rul_every=80, method="resample-move", pairs=True)
    assert answer["exit"] == 0, answer.get("error")
    figures = score(single, answer)
    assert figures["found"] and " + " not in str(answer["candidate"]) and " + " not in figures["top"], figures
    held = {name: e for name, e in answer["evidence"].items() if " + " in name and e["probability"] > 1e-9}
    assert not held, held


@pytest.mark.slow  # 2 s of the pump's physics and two single-fault runs of bgphm prognose: about 30 s of CPU
def test_a_second_wear_below_the_thresholds_contradicts_the_first_one_alone():
    # at this seed the impeller's ARR (the pump's) never fires: c_p's wear stays below its thresholds, and the
    # brushes' laws, which predict that ARR healthy, follow their own; it drifts off by about 3 sd
    both = Scenario("pump_drive", "R_a + c_p", "linear + exponential", "clean")
    answer = run(both, seed=20261134, particles=60, rul_every=80, method="resample-move", pairs=False)
    assert answer["exit"] == 0 and answer["fired"] == ["ARR_1_e"] and not answer["late"], answer.get("error")
    reasons = [e["inadequate"] or "" for name, e in answer["evidence"].items() if name.startswith("R_a/")]
    assert reasons and all("blind to R_a" in r and "another fault acts there" in r for r in reasons), reasons
    # the brushes wearing alone, the same noise: the pump's ARR stays healthy, and no law of R_a is told otherwise
    alone = run(Scenario("pump_drive", "R_a", "linear", "clean"), seed=20261134, particles=60, rul_every=80,
                method="resample-move", pairs=False)
    reasons = [e["inadequate"] or "" for name, e in alone["evidence"].items() if name.startswith("R_a/")]
    assert reasons and not any("blind to" in r for r in reasons), reasons
    assert alone["candidate"] == "R_a"


@pytest.mark.slow  # 300 s of the pipe's physics and bgphm prognose, four times: about 9 s of CPU
def test_two_wears_firing_more_arrs_than_one_parameter_sees_are_weighed_as_a_pair():
    # the strainer clogging and the tank's outlet scaling at once, read with a wider derivative window (a
    # user's --window 61, residuals five times quieter): both ARRs fire at the alarm, which no single
    # parameter sees, and alone only the flow and pressure sensors' faults are weighed
    pair = Scenario("pipe_tank", "R_f + R_o", "linear + exponential", "clean")
    alone = run(pair, seed=20261127, particles=60, rul_every=80, method="resample-move", window=61, pairs=False)
    assert alone["exit"] == 0, alone.get("error")
    assert set(alone["fired"]) == {"ARR_1_p", "ARR_0_t"}
    assert alone["candidates"] == ["sensor Q", "sensor p_t"]
    assert not score(pair, alone)["found"]    # a sensor's fault is named for two wears
    # by default the pair is weighed beside them, and named
    answer = run(pair, seed=20261127, particles=60, rul_every=80, method="resample-move", window=61)
    assert answer["pairs"] == "weighed: no single parameter sees every ARR fired"
    assert score(pair, answer)["found"] and answer["status"] == "isolated", (answer["candidate"], answer["status"])
    # with the sensors healthy, no single fault is weighed at all ("no candidate" before): the pair is
    blind = run(pair, seed=20261127, particles=60, rul_every=80, method="resample-move", window=61, sensors=False)
    assert blind["candidates"] == [] and blind["pairs"] == "weighed: no single parameter sees every ARR fired"
    assert score(pair, blind)["found"], (blind["candidate"], blind["status"])
    # a single wear firing one ARR with the same window weighs no pair: one parameter sees it
    strainer = Scenario("pipe_tank", "R_f", "linear", "clean")
    single = run(strainer, seed=20261127, particles=60, rul_every=80, method="resample-move", window=61)
    assert single["pairs"] == "not weighed" and score(strainer, single)["found"]
