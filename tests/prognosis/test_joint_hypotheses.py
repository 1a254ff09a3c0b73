"""Two parameters degrading at once: a joint hypothesis, weighed with the single ones in one filter.

The joint observation model is judged on the pump drive's physics written apart from the library
(:mod:`tests.wear.zoo`): with the brushes' resistance and the pump's load coefficient both wearing,
every residual of the noise-free record is the sum of what each change predicts alone.
"""

import numpy as np
import pytest

from diagnosis import derive_arrs
from prognosis.degradation import JointDegradation, LinearDegradation, PerAssetDegradation
from prognosis.hypotheses import Hypothesis, HypothesisObservation, JointHypothesis, JointObservation, additive
from prognosis.isolation import IsolatingMonitor, IsolationResult, held_back
from prognosis.resample_move import ResampleMoveFilter
from tests.wear.laws import LAWS
from tests.wear.run import SYSTEMS

FACTS = SYSTEMS["pump_drive"]


@pytest.fixture(scope="module")
def arrs():
    return derive_arrs(FACTS.model())


def test_the_joint_model_predicts_what_two_wearing_parameters_do_to_every_residual(arrs):
    laws = {"R_a": LAWS["linear"](FACTS.nominal["R_a"], FACTS.failures["R_a"], 0.2, 2.0),
            "c_p": LAWS["exponential"](FACTS.nominal["c_p"], FACTS.failures["c_p"], 0.2, 1.6)}
    record = FACTS.simulate(laws, t_end=1.6, dt=FACTS.dt, noise={}, seed=0)
    healthy = FACTS.simulate({}, t_end=1.6, dt=FACTS.dt, noise={}, seed=0)
    t = record["t"]
    settled = (t > 0.3) & (t < 1.5)   # away from the onset's kink and the record's ends
    joint = JointObservation([HypothesisObservation(arrs, [Hypothesis("R_a", "linear", 1.0, FACTS.nominal["R_a"])]),
                              HypothesisObservation(arrs, [Hypothesis("c_p", "linear", 1.0,
                                                                      FACTS.nominal["c_p"])])])
    theta = np.stack([laws["R_a"](t[settled]), laws["c_p"](t[settled])], axis=-1)[None, None]   # (1, 1, K, 2)
    rate = np.gradient(np.stack([laws["R_a"](t), laws["c_p"](t)], axis=-1), t, axis=0)[settled][None, None]
    evaluations = [a.evaluate(record) for a in arrs]
    steps = [[[np.asarray(p)[k] for p in e.points] for e in evaluations] for k in np.flatnonzero(settled)]
    predicted = joint.trajectory(theta, steps, rate=rate)[0, 0]   # (K, M)
    for m, (arr, e) in enumerate(zip(arrs, evaluations)):
        change = -e.residual[settled]
        floor = np.max(np.abs(arr.evaluate(healthy).residual[settled]))   # the healthy record's own residual
        scale = np.max(np.abs(change))
        assert scale > 100 * floor, arr.name   # both faults show well above it
        assert np.max(np.abs(predicted[:, m] - change)) <= 1e-3 * scale + 2 * floor, arr.name


def test_two_parameters_in_one_product_are_not_weighed_as_a_pair(arrs):
    assert additive(arrs, "R_a", "c_p") == ""
    assert "one product" in additive(arrs, "k_m", "r_g")   # k_m omega_p / r_g: their changes do not add


def test_a_joint_filter_follows_two_parameters_with_distinct_particles():
    # y = (theta_1, theta_1 + theta_2): both rates are identifiable, measured with noise 0.02
    bank = PerAssetDegradation((LinearDegradation(),), (0,))
    model = JointDegradation((bank, bank))
    f = ResampleMoveFilter(model, lambda theta, points: np.stack([theta[..., 0], theta.sum(-1)], axis=-1),
                           noise=[0.02, 0.02], dt=1.0, n_particles=300, seed=3)
    f.initialize((np.zeros((1, 2)), np.ones((1, 2))), gamma_bounds=(np.zeros((1, 2)), np.full((1, 2), 0.2)),
                 components=2)
    rng = np.random.default_rng(0)
    for k in range(40):
        first, second = 0.5 + 0.05 * k, 0.2 + 0.1 * k
        step = f.step(np.array([[first, first + second]]) + rng.normal(0, 0.02, (1, 2)))
    estimate = f.estimate()
    assert estimate["gamma_mean"][0] == pytest.approx([0.05, 0.1], abs=0.005)
    assert [c["theta_mean"][0] for c in estimate["components"]] == pytest.approx([2.45, 4.1], abs=0.05)
    assert f.theta.shape == (1, 300, 2) and not step.collapsed[0]
    assert np.unique(f.gamma[0, :, 1]).size > 100


def test_a_pair_is_held_back_until_it_beats_each_of_its_parameters_alone():
    a, b = Hypothesis("a", "power", 2.0, 1.0), Hypothesis("b", "power", 2.0, 1.0)
    pair = JointHypothesis((a, b))
    hypotheses = [a, b, pair]
    assert set(held_back(hypotheses, np.array([0.0, -1.0, 4.0]))) == {pair.name}   # e^4 < 100
    assert held_back(hypotheses, np.array([0.0, -1.0, 4.0]), min_ratio=10.0) == {}
    # a rejected single does not count against the pair, and a rejected pair is not held back again
    assert held_back(hypotheses, np.array([0.0, -1.0, 0.5]), rejected={a.name: "", b.name: ""}) == {}
    assert held_back(hypotheses, np.array([0.0, -1.0, 0.5]), rejected={pair.name: ""}) == {}


def test_a_pair_with_a_parameter_estimated_within_its_healthy_values_is_no_two_faults():
    a, b = Hypothesis("a", "power", 2.0, 1.0), Hypothesis("b", "linear", 4.0, 2.0)
    pair = JointHypothesis((a, b))
    hypotheses, decisive = [a, b, pair], np.array([0.0, -50.0, 30.0])   # e^30 over a alone
    healthy = {"a": (0.9, 1.1), "b": (1.9, 2.1)}
    assert held_back(hypotheses, decisive, estimates={pair.name: {"a": 1.6, "b": 2.4}}, healthy=healthy) == {}
    # b within its tolerance: the pair only uses it to absorb a misfit of a's law
    why = held_back(hypotheses, decisive, estimates={pair.name: {"a": 1.6, "b": 2.05}}, healthy=healthy)
    assert set(why) == {pair.name} and why[pair.name].startswith("b's estimate 2.05 lies within")
    # on either side of the box, and at its edges
    for value in (1.9, 2.1):
        assert pair.name in held_back(hypotheses, decisive, estimates={pair.name: {"a": 1.6, "b": value}},
                                      healthy=healthy)
    assert held_back(hypotheses, decisive, estimates={pair.name: {"a": 1.6, "b": 1.85}}, healthy=healthy) == {}
    # a parameter without a box of healthy values (or no estimate) is not judged by it
    inside = {pair.name: {"a": 1.6, "b": 2.05}}
    assert held_back(hypotheses, decisive, estimates=inside, healthy={"a": (0.9, 1.1)}) == {}
    # the decision of a result uses the estimates at that time
    result = IsolationResult(1.0, candidates=["a", "b"], groups=[["a"], ["b"]], hypotheses=hypotheses,
                             healthy=healthy)
    assert result.decide_at(decisive, 2.0, [["a"], ["b"]], {pair.name: {"a": 1.6, "b": 2.4}}).candidate == "a + b"
    decision = result.decide_at(decisive, 2.0, [["a"], ["b"]], {pair.name: {"a": 1.6, "b": 2.0}})
    assert decision.candidate == "a" and decision.probabilities[pair.name] == 0.0


def test_a_pair_is_claimed_only_when_each_parameter_is_seen_apart_from_the_other():
    """b acts in r1, where a acts, and alone in r2: while r2 shows b's change by less than the decisive ratio,
    b's part of the pair is seen only where a acts, as a misfit of a's law would be."""
    a, b = Hypothesis("a", "power", 2.0, 1.0), Hypothesis("b", "power", 2.0, 1.0)
    pair = JointHypothesis((a, b))
    hypotheses, decisive = [a, b, pair], np.array([0.0, -50.0, 30.0])
    seen_by = {"a": ["r1"], "b": ["r1", "r2"]}
    why = held_back(hypotheses, decisive, seen_by=seen_by, apart={pair.name: {"a": 50.0, "b": 4.0}})
    assert set(why) == {pair.name}
    assert why[pair.name].startswith("b's estimated change fits its own ARRs (r2), blind to a")
    assert held_back(hypotheses, decisive, seen_by=seen_by, apart={pair.name: {"a": 0.0, "b": 4.7}}) == {}
    # the same ARRs for both, no ARR of its own: a second fault is no more than another law of the first
    assert set(held_back(hypotheses, decisive, seen_by={"a": ["r1"], "b": ["r1"]})) == {pair.name}
    # without the ARRs seeing each, judged by the evidence and the healthy values alone
    assert held_back(hypotheses, decisive) == {}
    result = IsolationResult(1.0, candidates=["a"], groups=[["a"], ["b"]], hypotheses=hypotheses, seen_by=seen_by)
    before = result.decide_at(decisive, 4.9, [["a"], ["b"]], apart={pair.name: {"b": 1.0}})
    assert before.candidate == "a" and before.probabilities[pair.name] == 0.0
    assert result.decide_at(decisive, 5.0, [["a"], ["b"]], apart={pair.name: {"b": 9.0}}).candidate == "a + b"


def test_a_parts_change_fits_its_own_arrs_only_where_their_residuals_have_it(arrs):
    """The pump: the brushes' R_a is seen by the motor's ARR alone, which also sees the gear ratio r_g, seen by
    the pump's ARR too; the impeller's c_p by the pump's ARR alone.  A change of c_p fits the pump's ARR, by
    about d^2/2 times its information, on the record of the physics with that change; on the healthy record,
    the same change is as much evidence against it."""
    change = 0.3 * FACTS.nominal["c_p"]
    records = {worn: FACTS.simulate({"c_p": FACTS.nominal["c_p"] + (change if worn else 0.0)}, t_end=1.6,
                                    dt=FACTS.dt, noise={}, seed=0) for worn in (True, False)}
    p = FACTS.failures
    pairs = [JointHypothesis((Hypothesis("R_a", "linear", p["R_a"], FACTS.nominal["R_a"]),
                              Hypothesis(other, "linear", 2 * FACTS.nominal[other], FACTS.nominal[other])))
             for other in ("c_p", "r_g")]
    with_c_p, with_r_g = (pair.name for pair in pairs)
    steps = range(int(0.3 / FACTS.dt), int(1.5 / FACTS.dt), 20)   # past the start-up
    fit = {}
    for worn, record in records.items():
        terms = IsolatingMonitor.apart_terms(pairs, arrs, [a.evaluate(record) for a in arrs], np.full(len(arrs), 0.05),
                                             steps)
        likelihood, _, information = terms[(with_c_p, "c_p")]
        fit[worn] = (sum(likelihood(k, np.array([change]))[0] for k in range(len(steps))),
                     0.5 * change ** 2 * information.sum())
        assert (terms[(with_c_p, "R_a")][2] > 0).all() and (terms[(with_r_g, "r_g")][2] > 0).all()
        assert (terms[(with_r_g, "R_a")][2] == 0).all() and terms[(with_r_g, "r_g")][2].shape == (len(steps),)
    (worn, plain), (healthy, plain_healthy) = fit[True], fit[False]
    assert plain > 100 and worn == pytest.approx(plain, rel=0.02)
    assert healthy == pytest.approx(-plain_healthy, rel=1e-3)


def test_a_large_change_is_weighed_by_what_it_does_not_by_its_slope_at_nominal():
    """The tank's outlet resistance R_o doubled, in the physics of the pipe and tank: its ARR reads the
    outflow ``p / R_o``, halved, where the slope at nominal predicts it gone.  The doubling fits the tank's
    ARR, blind to the strainer's R_f, by half its squared shift over the noise; the slope would make it a
    wash (a predicted shift twice the real one scores 0)."""
    pipe = SYSTEMS["pipe_tank"]
    arrs = derive_arrs(pipe.model())
    nominal = pipe.nominal["R_o"]
    record = pipe.simulate({"R_o": 2 * nominal}, t_end=60.0, dt=pipe.dt, noise={}, seed=0)
    pair = JointHypothesis((Hypothesis("R_f", "linear", pipe.failures["R_f"], pipe.nominal["R_f"]),
                            Hypothesis("R_o", "linear", pipe.failures["R_o"], nominal)))
    steps = range(int(20.0 / pipe.dt), int(60.0 / pipe.dt), 10)   # the tank settled at its new level
    sd = np.full(len(arrs), 1e-6)
    likelihood, score, information = IsolatingMonitor.apart_terms([pair], arrs, [a.evaluate(record) for a in arrs],
                                                                  sd, steps)[(pair.name, "R_o")]
    exact = sum(likelihood(k, np.array([nominal]))[0] for k in range(len(steps)))
    slope = nominal * score.sum() - 0.5 * nominal ** 2 * information.sum()
    assert exact > 100 and abs(slope) < 0.05 * exact


def test_a_parts_offset_from_the_start_is_no_second_fault_a_change_is(arrs):
    """The pump's physics with the impeller's c_p 30 % high from the start, as a model's mismatch reads, and with
    c_p wearing from nominal to 1.6 times it: the pair's estimate following each, c_p's own ARR (the pump's) fits
    the first no better than a constant offset does, the second by far more than the decisive ratio."""
    nominal, dt = FACTS.nominal["c_p"], FACTS.dt
    laws = {"offset": lambda t: np.full_like(np.asarray(t, float), 1.3 * nominal),
            "wear": lambda t: nominal * (1.0 + 0.6 * np.clip((np.asarray(t, float) - 0.3) / 1.2, 0.0, None))}
    pair = JointHypothesis((Hypothesis("R_a", "linear", FACTS.failures["R_a"], FACTS.nominal["R_a"]),
                            Hypothesis("c_p", "linear", 2 * nominal, nominal)))
    steps = range(int(0.3 / dt), int(1.5 / dt), 20)
    apart = {}
    for name, law in laws.items():
        record = FACTS.simulate({"c_p": law}, t_end=1.6, dt=dt, noise={}, seed=0)
        own = IsolatingMonitor.apart_terms([pair], arrs, [a.evaluate(record) for a in arrs], np.full(len(arrs), 0.05),
                                           steps)
        result = IsolationResult(0.3, hypotheses=[pair])
        result.apart = {pair.name: {"R_a": 0.0, "c_p": 0.0}}
        fits = {key: np.zeros(3) for key in own}
        for k, sample in enumerate(steps):
            parts = {pair.name: {"R_a": FACTS.nominal["R_a"], "c_p": float(law(record["t"][sample]))}}
            IsolatingMonitor._weigh_apart(result, [pair], parts, own, fits, k)
        apart[name] = (result.apart[pair.name]["c_p"], fits[(pair.name, "c_p")][0])
    (offset, over_none), (wear, _) = apart["offset"], apart["wear"]
    assert over_none > 100 and abs(offset) < 1.0   # plain against no change, not against an offset
    assert wear > 10 * np.log(100)


def test_the_pairs_of_a_first_candidate_are_with_every_other_parameter_that_adds(arrs):
    monitor = IsolatingMonitor(arrs, FACTS.failures, noise_std={a.name: 1.0 for a in arrs},
                               method="resample-move", pairs=True, dt=0.1)
    result = IsolationResult(0.5, fired=["ARR_1_e"], candidates=["R_a", "L_a"])
    pairs, groups = monitor.pairs_for(result)
    assert ("R_a", "c_p") in pairs and ("L_a", "c_p") in pairs and ("R_a", "L_a") in pairs
    assert ("L_a", "R_a") not in pairs   # one pair once
    assert not any({"k_m", "r_g"} <= set(p) for p in pairs)
    hypotheses = monitor.pair_hypotheses(("R_a", "c_p"))
    assert len(hypotheses) == 9 and "R_a/linear + c_p/exponential" in [h.name for h in hypotheses]
    assert hypotheses[0].parts[1].failure == FACTS.failures["c_p"]
    assert all(len(g) > 1 for g in groups)


def test_without_a_single_candidate_the_pairs_are_those_whose_arrs_hold_every_fired_one(arrs):
    monitor = IsolatingMonitor(arrs, FACTS.failures, noise_std={a.name: 1.0 for a in arrs},
                               method="resample-move", pairs=True, dt=0.1)
    pairs, _ = monitor.pairs_for(IsolationResult(0.5, fired=["ARR_1_e", "ARR_1_p"], candidates=[]))
    assert ("R_a", "c_p") in pairs or ("c_p", "R_a") in pairs
    seen = {a.name: set(a.parameters) for a in arrs}
    for pair in pairs:   # each fired ARR sees one of the two
        assert all(set(pair) & seen[name] for name in ("ARR_1_e", "ARR_1_p")), pair
    assert not any(set(pair) <= seen["ARR_1_e"] - seen["ARR_1_p"] for pair in pairs)   # R_a with L_a: not both
