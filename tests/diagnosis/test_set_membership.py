"""Set-membership uncertainty boxes (diagnosis.set_membership), judged on DC-motor runs simulated here from the
motor's two equations with scipy's solve_ivp (never the library's own simulate), with the sensors' noise drawn
here, and by the library's own detection."""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bondgraph import BondGraph, SettingError
from bondgraph.library import dc_motor
from diagnosis import DetectionSettings, derive_arrs, detect, evaluate, noise_margin
from diagnosis.set_membership import set_membership_boxes

#: The machine (dc_motor's parameter names: R_a, L_a, k_m on the gyrator, J, b).
TRUE = {"R_a": 1.23, "L_a": 1.34e-3, "k_m": 3.89e-2, "J": 1e-4, "b": 1e-4}
#: Sensor noise (standard deviations): a current probe's 5 mA, an encoder-derived speed's 0.05 rad/s.
NOISE = {"i": 0.005, "omega": 0.05}
TRAINING = (1, 2)
HELD_OUT = (10, 11, 12, 13, 14, 15)
#: detect's healthy stretch (the first 20 % of 2 s) and the start of it that no margin judges.
UNTIL, START = 0.4, 0.04


def voltage(t):
    """Light load over the healthy stretch (3 V), then 12 V, 8 V and a sine: the stretch alone cannot calibrate
    away a model's error, which grows with the speed."""
    return 3.0 * (t >= 0.05) + 9.0 * (t >= 0.5) - 4.0 * (t >= 1.0) + 3.0 * np.sin(7 * t) * (t >= 1.4)


@functools.cache
def clean_run() -> dict:
    """L_a di/dt = U - R_a i - k_m w and J dw/dt = k_m i - b w, integrated here."""
    p = TRUE

    def rhs(t, x):
        i, w = x
        return [(voltage(t) - p["R_a"] * i - p["k_m"] * w) / p["L_a"], (p["k_m"] * i - p["b"] * w) / p["J"]]

    t = np.linspace(0.0, 2.0, 2001)
    sol = solve_ivp(rhs, (0.0, 2.0), [0.0, 0.0], t_eval=t, method="LSODA", rtol=1e-10, atol=1e-12, max_step=1e-3)
    return {"t": t, "U": voltage(t), "i": sol.y[0], "omega": sol.y[1]}


def record(seed: int) -> dict:
    rng = np.random.default_rng(seed)
    run = clean_run()
    return {**run, **{name: run[name] + rng.normal(0.0, sigma, run[name].size) for name, sigma in NOISE.items()}}


def boxed(bg: BondGraph, boxes: dict) -> BondGraph:
    """A copy of ``bg`` with these uncertainty boxes (set on the graph here, not by the module under test)."""
    graph = bg.graph.copy()
    for name, data in graph.nodes(data=True):
        param = data.get("param", name)
        if param in boxes and data.get("kind") in ("R", "I", "C", "GY"):
            data["uncertainty"] = tuple(boxes[param])
    return BondGraph(graph, name=bg.name)


def fired(bg: BondGraph, run: dict) -> list:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return detect(bg, run).fired


#: The model with the friction 10 % low.
OFF = dc_motor(**{**TRUE, "b": 0.9 * TRUE["b"]})


@functools.cache
def off_boxes() -> dict:
    return set_membership_boxes(OFF, [record(s) for s in TRAINING], list(TRUE))


def test_the_boxes_keep_the_training_records_free_of_alarms():
    boxes = off_boxes()
    assert set(boxes) == set(TRUE)
    assert all(-1.0 < lo <= 0.0 <= hi for lo, hi in boxes.values())
    # the friction's box opens upwards (the machine's b is 11 % above the model's), by no more than that
    assert boxes["b"][0] == 0.0 and 0.02 < boxes["b"][1] <= 1 / 0.9 - 1
    for seed in TRAINING:
        assert fired(boxed(OFF, boxes), record(seed)) == [], seed


def test_without_boxes_the_same_records_raise_alarms():
    """Not a vacuous test: with no box on the parameters, the model's error shows."""
    assert "ARR_1_m" in fired(boxed(OFF, dict.fromkeys(TRUE, (0.0, 0.0))), record(TRAINING[0]))


@pytest.mark.slow   # a second of CPU: the fast tier stays under a minute
def test_held_out_records_of_the_same_machine_raise_few_alarms():
    """The boxes are the smallest for the training noise: another draw may leave them now and then, but its own
    calibrated margin covers its noise.  At most one of six held-out records in alarm."""
    model = boxed(OFF, off_boxes())
    alarms = [seed for seed in HELD_OUT if fired(model, record(seed))]
    assert len(alarms) <= 1, alarms


def test_the_detection_settings_are_those_the_boxes_keep():
    """A fixed derivative window and a shorter healthy stretch: sized with them, the boxes keep detect with them
    quiet on the training records (and without boxes it is not)."""
    settings = DetectionSettings(calibrate=0.3, window=41)
    runs = [record(s) for s in TRAINING]
    boxes = set_membership_boxes(OFF, runs, ["b", "J"], settings=settings)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert detect(boxed(OFF, {"b": (0.0, 0.0), "J": (0.0, 0.0)}), runs[0], settings).fired
        assert [detect(boxed(OFF, boxes), run, settings).fired for run in runs] == [[], []]


def _violations(bg: BondGraph, seed: int, persistence: bool = False) -> int:
    """Samples after the start-up outside the band plus detect's noise margin (k = 4 robust deviations on the
    healthy stretch), over the windows detect tries on 2001 samples; or, ``persistence``, samples in alarm."""
    run = record(seed)
    healthy = {name: column[run["t"] <= UNTIL] for name, column in run.items()}
    count = 0
    for arr in derive_arrs(bg):
        for window in (None, 21):
            options = {"steps": ["U", "i", "omega"], "ends": True, **({"window": window} if window else {})}
            margin = noise_margin(arr, healthy, k=4.0, **options)
            # detect's persistence: 5 samples, and at least half the derivative window (11 by default)
            evaluation = evaluate(arr, run, margin=margin, persistence=max(5, (window or 11) // 2), **options)
            late = evaluation.t > START
            count += int(np.count_nonzero((evaluation.alarm if persistence else evaluation.violation) & late))
    return count


def test_the_boxes_are_smallest_shrunk_by_a_tenth_a_training_sample_leaves_the_threshold():
    boxes = off_boxes()
    shrunk = {p: (0.9 * lo, 0.9 * hi) for p, (lo, hi) in boxes.items()}
    for seed in TRAINING:
        assert _violations(boxed(OFF, boxes), seed, persistence=True) == 0
    assert sum(_violations(boxed(OFF, shrunk), s) for s in TRAINING) > sum(
        _violations(boxed(OFF, boxes), s) for s in TRAINING)


def test_the_threshold_is_the_sum_of_sensitivities_times_the_half_widths():
    """Psi_2 of the mechanical balance, by hand: delta_k k_m i - delta_J J dw/dt - delta_b b w; over an asymmetric
    box the band's upper end takes hi where a sensitivity is positive and -lo where it is negative."""
    boxes = {"k_m": (-0.03, 0.01), "J": (-0.05, 0.2), "b": (-0.1, 0.3)}
    model = boxed(OFF, boxes)
    (arr,) = [a for a in derive_arrs(model) if a.name == "ARR_1_m"]
    evaluation = evaluate(arr, record(1), window=21)
    points = dict(zip(map(str, arr.compiled.points), evaluation.points))
    p = model.parameters
    g = {"k_m": p["k_m"] * points["i"], "J": -p["J"] * points["d1_omega"], "b": -p["b"] * points["omega"]}
    upper = sum(np.where(g[q] > 0, hi * g[q], lo * g[q]) for q, (lo, hi) in boxes.items())
    lower = sum(np.where(g[q] > 0, lo * g[q], hi * g[q]) for q, (lo, hi) in boxes.items())
    assert np.allclose(evaluation.upper, upper, rtol=1e-9, atol=0.0)
    assert np.allclose(evaluation.lower, lower, rtol=1e-9, atol=0.0)


def test_the_exact_model_needs_much_smaller_boxes_than_one_a_fifth_off():
    runs = [record(s) for s in TRAINING]

    def width(boxes):
        return sum(hi - lo for lo, hi in boxes.values())

    exact = set_membership_boxes(dc_motor(**TRUE), runs, ["b", "J", "k_m"])
    off = set_membership_boxes(dc_motor(**{**TRUE, "b": 0.8 * TRUE["b"]}), runs, ["b", "J", "k_m"])
    assert off["b"][1] > 0.1
    assert width(exact) < 0.2 * width(off)


def test_an_unknown_parameter_is_named():
    with pytest.raises(SettingError, match="no parameter 'B_m'") as error:
        set_membership_boxes(OFF, [record(1)], ["b", "B_m"])
    assert error.value.setting == "parameters"


def test_records_without_a_usable_sample_are_refused():
    run = record(1)
    blank = {**run, "i": np.full(run["t"].size, np.nan), "omega": np.full(run["t"].size, np.nan)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(SettingError, match="no sample") as error:
            set_membership_boxes(OFF, [blank], ["b"])
    assert error.value.setting == "records"
    with pytest.raises(SettingError, match="at least one"):
        set_membership_boxes(OFF, [], ["b"])


def test_a_residual_no_box_of_these_parameters_explains_names_the_arr_and_the_record():
    """A voltage probe reading 0.5 V while the motor rests (the noise-free current and speed are zero): no box of
    the winding's resistance, whose term is R_a i, can explain it."""
    t = clean_run()["t"]
    resting = {"t": t, "U": np.full(t.size, 0.5), "i": np.zeros(t.size), "omega": np.zeros(t.size)}
    with pytest.raises(SettingError, match=r"records\[1\]: ARR_1_e leaves its threshold at t = ") as error:
        set_membership_boxes(dc_motor(**TRUE), [record(1), resting], ["R_a"])
    assert "R_a" in str(error.value) and "\n" not in str(error.value)


def test_a_parameter_not_linear_in_its_uncertainty_is_refused():
    """A resistance in parallel with a capacitor enters as v / (R (1 + delta_R)): its band is no linear function of
    the box, so no linear program sizes it; the capacitor's term, C delta_C dv/dt, is linear."""
    bg = BondGraph(name="parallel RC")
    bg.add("Q", "Sf", unit="A")
    bg.add("J0", "0")
    bg.add("R", "R", value=10.0, uncertainty=(-0.05, 0.05), unit="Ohm")
    bg.add("C", "C", value=1e-3, uncertainty=(-0.1, 0.1), unit="F")
    bg.add("v", "De", unit="V")
    for tail, head in [("Q", "J0"), ("J0", "R"), ("J0", "C"), ("J0", "v")]:
        bg.bond(tail, head)
    t = np.linspace(0.0, 1.0, 1001)
    rng = np.random.default_rng(0)
    # Q = C dv/dt + v / R for v = sin(10 t) (written here), measured with 1 mV of noise
    run = {"t": t, "Q": 1e-3 * 10 * np.cos(10 * t) + np.sin(10 * t) / 10.0,
           "v": np.sin(10 * t) + rng.normal(0.0, 1e-3, t.size)}
    with pytest.raises(SettingError, match="ARR_J0 is not linear in the uncertainty of 'R'"):
        set_membership_boxes(bg, [run], ["R", "C"])
    (lo, hi), = set_membership_boxes(bg, [run], ["C"]).values()
    assert -1.0 < lo <= 0.0 <= hi
