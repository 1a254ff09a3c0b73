"""FleetMonitor.update takes a micro-batch whole or not at all: a refused batch moves no stream and can be re-sent."""

import numpy as np
import pytest

from prognosis.errors import PrognosisError
from prognosis.fleet import FleetResult
from tests.prognosis.test_fleet import circuit, fleet, same, stream  # noqa: F401 (circuit: a fixture)
from tests.prognosis.test_fleet_checkpoint import _equal

AT, SIZE = 600, 50  # the batch that goes wrong: c3 alarms in it (t = 1.246 s), c1 and c4 are filtering


def batch(records: dict, start: int = AT, size: int = SIZE, **changes) -> dict:
    """The samples start..start+size of every asset, as one micro-batch; ``changes`` rewrite columns."""
    columns = {"asset": [], "t": [], "V": [], "i": [], "v_C": []}
    for asset, record in records.items():
        for name in ("t", "V", "i", "v_C"):
            columns[name] += list(np.asarray(record[name])[start:start + size])
        columns["asset"] += [asset] * size
    columns = {k: np.array(v, dtype=object if k == "asset" else float) for k, v in columns.items()}
    for name, change in changes.items():
        columns = change(columns) if name == "whole" else {**columns, name: change(columns)}
    return columns


def of(columns: dict, asset: str) -> np.ndarray:
    return np.flatnonzero(columns["asset"] == asset)


def back_in_time(columns):   # c3's samples out of order
    t = columns["t"].copy()
    rows = of(columns, "c3")
    t[rows[10]], t[rows[11]] = t[rows[11]], t[rows[10]]
    return t


def infinite_current(columns):
    i = columns["i"].copy()
    i[of(columns, "c4")[5]] = np.inf
    return i


BAD = {
    "a sample back in time": ({"t": back_in_time}, r"update: asset 'c3': .*t must increase"),
    "an infinite current": ({"i": infinite_current}, r"update: asset 'c4': .*'i'"),
    "a signal column missing": ({"whole": lambda c: {k: v for k, v in c.items() if k != "v_C"}},
                                r"update: asset 'c1': .*missing signal\(s\) \['v_C'\]"),
}


@pytest.mark.parametrize("fault", sorted(BAD))
def test_a_refused_batch_moves_nothing_and_the_corrected_one_goes_on(circuit, fault):  # noqa: F811
    arr, records = circuit
    changes, message = BAD[fault]
    monitor = fleet(arr)
    before = stream(monitor, records, sizes=[SIZE], stop=AT)
    state = monitor.checkpoint()
    with pytest.raises(PrognosisError, match=message):
        monitor.update(batch(records, **changes))
    assert _equal(monitor.checkpoint(), state)   # no stream moved, not even the assets before the bad one
    resent = monitor.update(batch(records))
    after = stream(monitor, records, sizes=[SIZE], start=AT + SIZE)
    uninterrupted = stream(fleet(arr), records, sizes=[SIZE])
    for asset in ("c1", "c3", "c4"):
        assert same(uninterrupted, FleetResult.concat([before, resent, after]), asset)
    assert "c3" in set(resent.alarms["asset"])   # the alarm that the refused batch held is not lost


def test_ids_that_print_the_same_are_refused_and_numpy_integers_are_their_python_selves(circuit):  # noqa: F811
    arr, records = circuit
    two = {7: records["c1"], "7": records["c1"]}
    monitor = fleet(arr)
    with pytest.raises(PrognosisError, match=r"asset ids 7 and '7' collide|asset ids '7' and 7 collide"):
        monitor.update(batch(two, start=0))
    assert monitor.assets == []
    monitor.update(batch({7: records["c1"]}, start=0))
    with pytest.raises(PrognosisError, match="collide: ids are compared as text"):
        monitor.update(batch({"7": records["c1"]}, start=SIZE))
    columns = batch({7: records["c1"]}, start=SIZE)
    columns["asset"] = np.full(SIZE, 7, dtype=np.int64)   # an integer column: the same asset 7
    monitor.update(columns)
    assert monitor.assets == [7]
    with pytest.raises(KeyError, match="no asset '7'"):
        monitor.retire("7")
    monitor.retire(np.int64(7))
    assert monitor.assets == []
