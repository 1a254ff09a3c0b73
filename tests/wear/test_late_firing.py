"""A second fault after the first: an ARR that fires later and that no candidate sees is named, with the
faults that could have fired it, and the decision about the first fault stands.

The torsion bar simulated from its physics (tests/wear/torsion.py): the motor disk's friction b_Md
wears linearly from t = 10 s, and from t = 40 s the load disk's friction b_Ld wears too, to a hundred
times its nominal value at t = 100 s.  The user gives a failure value for b_Md only, so the
candidates come from the first signature (the motor side) and the load side's ARR, blind to b_Md,
fires later.  It is written with the integral of the speeds, which sees a friction at steady speed
(differentiated, it sees it only through the speed's swings); on this record it fires already at
about 17 s, before b_Ld wears, from the integral's drift under the margin calibrated on the first
8 s: another fault than b_Md either way, and reported as one.
"""

import json

import pytest

from bgphm.cli import main as bgphm
from bgphm.files import csv_text
from bondgraph import to_json
from bondgraph.library import torsion_bar_monitorable
from tests.wear import torsion
from tests.wear.laws import LAWS


@pytest.mark.slow  # a 100 s record from the physics and bgphm prognose on it: about 20 s of CPU
def test_an_arr_firing_later_that_no_candidate_sees_is_named_with_the_faults_that_could_fire_it(tmp_path):
    nominal = torsion.NOMINAL
    wear = {"b_Md": LAWS["linear"](nominal["b_Md"], 0.45, 10.0, 100.0),
            "b_Ld": LAWS["linear"](nominal["b_Ld"], 100 * nominal["b_Ld"], 40.0, 100.0)}
    columns = torsion.simulate(wear, t_end=100.0, dt=0.01, noise=torsion.NOISE, seed=3)
    (tmp_path / "model.json").write_text(to_json(torsion_bar_monitorable()))
    (tmp_path / "data.csv").write_text(csv_text(columns))
    code = bgphm(["--quiet", "prognose", str(tmp_path / "model.json"), str(tmp_path / "data.csv"), "--fail",
                  "b_Md=0.45", "--calibrate", "8", "--integrals", "keep", "--particles", "100", "--rul-every", "50",
                  "--seed", "3", "--filter", "resample-move", "--out", str(tmp_path / "out")])
    assert code == 0
    answer = json.loads((tmp_path / "out" / "prognosis.json").read_text())
    assert answer["candidate"] == "b_Md" and 10.0 < answer["detection_time"] < 40.0
    late = {name: when for name, when in answer["late"].items() if name in answer["unexplained"]}
    assert late, answer["late"]
    for name, when in late.items():
        assert answer["detection_time"] < when < 100.0
        assert "b_Ld" in answer["unexplained"][name] and "b_Md" not in answer["unexplained"][name]
    # before the load side fired, the decisions had nothing to add
    first = min(late.values())
    assert all(not d["unexplained"] for d in answer["decisions"] if d["t"] < first)
    assert answer["decisions"][-1]["unexplained"] == sorted(late)
