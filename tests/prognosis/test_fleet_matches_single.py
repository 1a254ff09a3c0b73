"""The fleet and the single-asset monitor, given one IsolationSettings, tell the same story on the same records.

The two filters draw from different random streams (the fleet's keyed by asset and step), so their
numbers differ within the filters' spread: the decisions must be equal, and each RUL median inside
the other's 5-95 % band.
"""

import numpy as np
import pytest

from bondgraph.scenarios import drift, rlc_record
from bondgraph.library import rlc_circuit
from diagnosis import add_noise, derive_arrs
from prognosis.fleet import FleetMonitor
from prognosis.isolation import FLEET_SETTINGS, IsolatingMonitor

T = np.linspace(0.0, 2.0, 1001)
ONSETS = {"early": 0.3, "late": 0.5}  # R from 10 ohm, +6 ohm/s from the onset: fails (20 ohm) 1.67 s later


@pytest.fixture(scope="module")
def runs():
    bg = rlc_circuit()
    arrs = derive_arrs(bg, complete=False, integrals="keep")[:1]  # the loop: R, L and both sensors fire it
    records = {}
    for seed, (name, onset) in enumerate(ONSETS.items()):
        records[name] = add_noise(rlc_record(T, {"R": drift(10.0, 6.0, onset)}), {"i": 2e-4}, seed=seed + 1)
    settings = FLEET_SETTINGS.changed(dt=0.01, n_particles=500, rul_every=5, seed=3)
    told = dict(noise_std={arrs[0].name: 2e-3}, detection={"margin": 0.01, "persistence": 3}, settings=settings)
    fleet = FleetMonitor(arrs, {"R": 20.0}, **told).run(records)
    single = {name: IsolatingMonitor(arrs, {"R": 20.0}, **told).run(record) for name, record in records.items()}
    return fleet, single


@pytest.mark.parametrize("asset", list(ONSETS))
def test_same_alarm_and_prediction_times(runs, asset):
    fleet, single = runs
    mine, alone = fleet.for_asset(asset), single[asset]
    assert mine.alarms["t"][0] == alone.detection_time  # the same detection, bit for bit
    assert np.array_equal(mine.rul["t"], alone.rul_t) and alone.rul_t.size >= 20


@pytest.mark.parametrize("asset", list(ONSETS))
def test_same_decisions(runs, asset):
    fleet, single = runs
    rul, decisions = fleet.for_asset(asset).rul, single[asset].decisions
    # L has R's signature over the loop ARR: neither monitor may call R isolated
    assert [d.status for d in decisions] == list(rul["status"]) and set(rul["status"]) == {"indistinguishable"}
    assert all(d.candidate == name.split("/")[0] for d, name in zip(decisions, rul["hypothesis"]))
    # two laws of one candidate: a law is decided when its probability reaches min_ratio / (1 + min_ratio)
    ratio = FLEET_SETTINGS.min_ratio
    assert [d.degradation_decided for d in decisions] == list(rul["probability"] >= ratio / (1 + ratio))
    assert all(d.degradation == name.split("/")[1] for d, name in zip(decisions, rul["hypothesis"])
               if d.degradation_decided)


@pytest.mark.parametrize("asset", list(ONSETS))
def test_each_median_inside_the_others_band(runs, asset):
    fleet, single = runs
    rul, alone = fleet.for_asset(asset).rul, single[asset]
    theirs = np.array([r.quantile([0.05, 0.5, 0.95])[0] for r in alone.rul])
    late = slice(rul["t"].size // 3, None)  # once the drift shows: at the alarm both bands reach the horizon
    assert np.all((theirs[late, 0] <= rul["p50"][late]) & (rul["p50"][late] <= theirs[late, 2]))
    assert np.all((rul["p5"][late] <= theirs[late, 1]) & (theirs[late, 1] <= rul["p95"][late]))
    truth = ONSETS[asset] + 10.0 / 6.0 - rul["t"][late]
    assert np.all(np.abs(rul["p50"][late] - truth) < 0.35) and np.all(np.abs(theirs[late, 1] - truth) < 0.35)
