"""Detectability against closed forms: a current source into a parallel RC, held at steady state.

With a constant current I0 the voltage sits at v = I0 R, so the junction's ARR ``I - C dv/dt - v/R`` and its
band are constant and every figure has a closed form, written here from the circuit, not from the library.
"""

import numpy as np
import pytest

from bondgraph import BondGraph
from diagnosis import derive_arrs
from diagnosis.detectability import NOISE_ALLOWANCE, detectability

I0, R, C, MARGIN = 0.01, 100.0, 1e-3, 2e-4


def parallel_rc() -> BondGraph:
    bg = BondGraph(name="parallel RC on a current source")
    bg.add("I", "Sf")
    bg.add("0", "0")
    bg.add("C", "C", value=C, uncertainty=(-0.05, 0.05))
    bg.add("R", "R", value=R, uncertainty=(-0.05, 0.05))
    bg.add("v", "De")
    for head in ("C", "R", "v"):
        bg.bond("0", head)
    bg.bond("I", "0")
    return bg


def steady_record(r_true: float) -> dict:
    t = np.linspace(0.0, 1.0, 1001)
    return {"t": t, "I": np.full_like(t, I0), "v": np.full_like(t, I0 * r_true)}


@pytest.fixture(scope="module")
def arr():
    (only,) = derive_arrs(parallel_rc())
    assert {"R", "C"} <= only.parameters
    return only


def evaluation_of(arr, r_true: float):
    return arr.evaluate(steady_record(r_true), exact_derivatives={"v": np.zeros(1001)}, margin=MARGIN,
                        persistence=5)


def test_the_claim_takes_the_larger_of_the_first_order_and_the_finite_figure(arr):
    healthy = evaluation_of(arr, R)
    d = detectability(healthy, arr)
    # -r_n = v/R_n - I0 must clear the band's upper edge (a rise of R) or its lower edge (a fall) by 1.5 margins
    upper = float(np.median(healthy.upper)) + (1 + NOISE_ALLOWANCE) * MARGIN
    lower = -float(np.median(healthy.lower)) + (1 + NOISE_ALLOWANCE) * MARGIN
    x_up, x_down = upper / I0, lower / I0     # first order: -r_n moves by I0 * epsilon
    # on the record's own signals a rise eps moves -r_n by I0 eps / (1 + eps), a fall by I0 eps / (1 - eps)
    assert d.rise["R"] == pytest.approx(x_up / (1 - x_up), rel=0.01)    # the finite figure is the larger
    assert d.fall["R"] == pytest.approx(x_down, rel=0.01)              # here first order is the larger
    assert d.rise["R"] > x_up * 1.02


def test_a_change_of_the_claimed_size_raises_the_alarm_and_a_smaller_one_in_the_box_does_not(arr):
    d = detectability(evaluation_of(arr, R), arr)
    for claimed, sign in ((d.rise["R"], 1.0), (d.fall["R"], -1.0)):
        faulty = evaluation_of(arr, R * (1 + sign * claimed))   # the physics: v = I0 R_true
        assert faulty.detection_time is not None
    assert evaluation_of(arr, R * 1.04).detection_time is None   # inside the box of +-5 %


def test_a_parameter_the_arr_does_not_see_on_this_record_is_not_claimed(arr):
    d = detectability(evaluation_of(arr, R), arr)
    assert d.rise["C"] == np.inf and d.fall["C"] == np.inf   # dv/dt = 0: C leaves no trace
    assert not d.blind
