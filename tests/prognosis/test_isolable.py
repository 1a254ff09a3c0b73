""""isolated" means isolable in the model: no other parameter or sensor fault has the candidate's signature."""

import numpy as np
import pytest

from bgphm.cli import main
from bgphm.files import csv_text
from bondgraph import simulate
from bondgraph.library import dc_motor, three_tank
from diagnosis import add_noise, as_record, derive_arrs, signature_matrix
from prognosis.hypotheses import Hypothesis, same_signature
from prognosis.isolation import decide
from tests.zoo.models.quarter_car import build as quarter_car


@pytest.mark.parametrize("arrs", [
    pytest.param(lambda: derive_arrs(quarter_car(), complete=False, integrals="keep"), id="quarter-car-junctions"),
    pytest.param(lambda: derive_arrs(quarter_car(), integrals="keep"), id="quarter-car-keep"),
    pytest.param(lambda: derive_arrs(dc_motor(), max_order=2), id="dc-motor-second-order"),
    pytest.param(lambda: derive_arrs(three_tank()), id="three-tank"),
])
@pytest.mark.slow
def test_same_signature_is_empty_exactly_for_the_isolable_rows(arrs):
    arrs = arrs()
    signatures = signature_matrix(arrs)
    for row, detectable, isolable in zip(signatures.rows, signatures.detectable, signatures.isolable):
        twins = same_signature(arrs, row)
        assert row not in twins
        if detectable:
            assert (not twins) == bool(isolable), (row, twins)
        for twin in twins:
            assert signatures.row(twin) == signatures.row(row)


def test_the_quarter_car_damper_shares_its_signature_with_the_spring():
    arrs = derive_arrs(quarter_car(), complete=False, integrals="keep")   # ARR_1_u, ARR_1_s
    assert {"C_s", "sensor v_u", "sensor v_s"} <= set(same_signature(arrs, "c_s"))
    assert same_signature(arrs, "m_s") == []   # only ARR_1_s sees the body's mass
    assert same_signature(arrs, "not_a_parameter") == []


def test_a_decision_names_the_faults_that_share_the_signature():
    hs = [Hypothesis(c, "linear", 2.0, 1.0) for c in ("a", "b")]
    log_z = np.array([0.0, -20.0])
    alone = decide(hs, log_z, [["a"], ["b"]])
    assert alone.status == "isolated" and alone.same_signature == ()
    shared = decide(hs, log_z, [["a"], ["b"]], signatures={"a": ["k", "sensor x"], "b": []})
    assert shared.candidate == "a" and shared.status == "indistinguishable"
    assert shared.same_signature == ("k", "sensor x") and shared.as_dict()["same_signature"] == ["k", "sensor x"]
    close = decide(hs, np.array([0.0, -1.0]), [["a"], ["b"]], signatures={"a": ["k"]})
    assert close.status == "undecided" and close.same_signature == ()   # nothing declared, nothing to qualify


@pytest.mark.slow
def test_prognose_does_not_call_the_quarter_car_damper_isolated(tmp_path, capsys):
    """The damper wears from t = 2 s; ARR_1_s alone sees it, and sees the spring, the body and both sensors too."""
    bg = quarter_car()
    t = np.arange(0.0, 6.0 + 1e-9, 1e-3)
    record = simulate(bg, (0.0, 6.0), {"v_r": lambda t: 0.05 * np.sin(9.4 * t) + 0.03 * np.sin(25.8 * t)}, t_eval=t,
                      parameters={"c_s": lambda t: 1500.0 - 150.0 * max(0.0, t - 2.0)}).record()
    noisy = add_noise(as_record(record), {"v_u": 1e-4, "v_s": 1e-4}, seed=1)
    (tmp_path / "data.csv").write_text(csv_text({"t": noisy.t, **noisy.columns}))
    (tmp_path / "model.py").write_text("from tests.zoo.models.quarter_car import build\nmodel = build\n")
    code = main(["--quiet", "prognose", str(tmp_path / "model.py"), str(tmp_path / "data.csv"), "--arr", "ARR_1_s",
                 "--integrals", "keep", "--fail", "c_s=750", "--calibrate", "1.5", "--particles", "100",
                 "--rul-every", "100"])   # the test is about the status: few RUL predictions
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "candidate c_s (indistinguishable from C_s, m_s, sensor v_u, sensor v_s (same signature))" in out
    assert "(isolated)" not in out
