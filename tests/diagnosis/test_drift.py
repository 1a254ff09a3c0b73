"""Residuals that do not drift: a noisy fault-free record of a 50-stage chain, along 100 s."""

import numpy as np
import pytest

from bondgraph import simulate
from bondgraph.library import mass_spring_chain
from diagnosis import add_noise, derive_arrs, robust_std


@pytest.fixture(scope="module")
def chain():
    bg = mass_spring_chain(50)
    t = np.linspace(0.0, 100.0, 10001)
    clean = simulate(bg, (0.0, 100.0), {"F": lambda s: 1.0 + 0.5 * np.sin(0.7 * s)}, t_eval=t).record()
    return bg, add_noise(clean, {f"v{i}": 1e-3 for i in range(1, 51)}, seed=11)


def _counts(bg, record, integrals):
    """(violations in the first fifth, in the last fifth, alarms), 4-sigma margins from the first fifth."""
    fifth, first, last, alarms = len(record.t) // 5, 0, 0, []
    for arr in derive_arrs(bg, integrals=integrals):
        margin = 4.0 * robust_std(arr.evaluate(record).residual[:fifth])
        result = arr.evaluate(record, margin=margin, persistence=5)
        first, last = first + int(result.violation[:fifth].sum()), last + int(result.violation[-fifth:].sum())
        alarms += [arr.name] if result.detection_time is not None else []
    return first, last, alarms


@pytest.mark.slow
def test_the_default_arrs_raise_no_alarm_and_their_violation_rate_does_not_grow(chain):
    bg, record = chain
    arrs = derive_arrs(bg)   # the junction balances, differentiated, and those isolation adds: no integral
    assert not any(arr.integrals for arr in arrs)
    assert {arr.form for arr in arrs} <= {"differentiated balance", "elimination", "differentiated elimination"}
    first, last, alarms = _counts(bg, record, "avoid")
    assert alarms == []
    assert first > 0 and last <= 2 * first


@pytest.mark.slow
def test_the_integral_form_drifts_on_the_same_record(chain):
    bg, record = chain
    first, last, alarms = _counts(bg, record, "keep")
    assert alarms and last > 20 * max(first, 1)   # the random walk of the integrated noise leaves the band
