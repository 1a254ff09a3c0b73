"""prognose: the library's whole chain equals the command line's, and its settings are checked by name."""

import json

import numpy as np
import pytest

from bgphm.cli import main
from bgphm.files import csv_text
from bondgraph import SettingError, simulate
from bondgraph.io import to_json
from bondgraph.library import rlc_circuit
from diagnosis import DetectionSettings, Record, add_noise, as_record, derive_arrs, read_csv
from prognosis import (IsolationSettings, PrognosisSettings, check_candidate, check_failures, filter_step, prognose,
                       rul_horizon)
from prognosis.isolation import LAWS


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The RLC circuit's model file and a record of R drifting up linearly from t = 1 s (4 ohm/s), noisy current."""
    folder = tmp_path_factory.mktemp("rlc")
    bg = rlc_circuit()
    t = np.linspace(0.0, 3.0, 3001)
    run = simulate(bg, (0.0, 3.0), {"V": lambda t: 5 + np.sin(7 * t)}, t_eval=t,
                   parameters={"R": lambda t: 10.0 + 4.0 * max(0.0, t - 1.0)})
    record = add_noise(as_record(run.record()), {"i": 1e-4}, seed=4)
    model, data = folder / "rlc.json", folder / "rlc.csv"
    model.write_text(to_json(bg, inputs={"V": 5.0}))
    data.write_text(csv_text({"t": record.t, **record.columns}))
    return bg, model, data


@pytest.mark.slow   # a second of CPU: the fast tier stays under a minute
def test_the_library_and_the_command_line_give_the_same_numbers(files, tmp_path):
    bg, model, data = files
    out = tmp_path / "out"
    code = main(["--quiet", "prognose", str(model), str(data), "--fail", "R=20", "--calibrate", "0.8",
                 "--degradation", "linear", "--particles", "100", "--no-sensors", "--seed", "3", "--out", str(out)])
    assert code == 0
    cli = json.loads((out / "prognosis.json").read_text())
    settings = PrognosisSettings(detection=DetectionSettings(calibrate=0.8),
                                 isolation=IsolationSettings(laws=("linear",), n_particles=100, sensors=False, seed=3))
    result = prognose(derive_arrs(bg), read_csv(data), {"R": 20.0}, settings, domains=bg.domains)
    python = json.loads(json.dumps(result.as_dict(), default=float))
    assert python["candidate"] == cli["candidate"] == "R" and python["status"] == cli["status"]
    assert python["predictions"] and python["predictions"] == cli["predictions"]  # every figure, to the last bit
    for key in ("filter_step", "residual_noise_std", "margins", "calibration_end", "evidence", "decisions", "pairs"):
        assert python[key] == cli[key], key
    assert cli["pairs"] == "not weighed"   # R explains the residuals
    assert 1.0 < python["detection_time"] == cli["detection_time"] < 2.0  # R drifts from t = 1 s


@pytest.mark.parametrize("settings, setting", [
    ({"n_particles": 1}, "n_particles"), ({"n_particles": 10**6}, "n_particles"), ({"rul_every": 0}, "rul_every"),
    ({"horizon": -1.0}, "horizon"), ({"dt": float("nan")}, "dt"), ({"seed": -1}, "seed"),
    ({"method": "kalman"}, "method"), ({"laws": ()}, "laws"), ({"rate": (2.0, 1.0)}, "rate"),
    ({"pairs": True, "method": "sir"}, "pairs"), ({"pairs": True, "candidates": ("R",)}, "pairs"),
])
def test_bad_settings_are_refused_naming_the_setting(settings, setting):
    with pytest.raises(SettingError) as caught:
        PrognosisSettings(isolation=IsolationSettings(**settings))
    assert caught.value.setting == setting and str(caught.value).startswith(setting)


def test_the_filter_step_and_the_horizon_are_checked_against_the_record():
    record = Record(np.arange(0.0, 2.0, 0.01), {})
    assert filter_step(record) == pytest.approx(0.11) and filter_step(record, window=21) == pytest.approx(0.21)
    assert filter_step(record, dt=0.05) == 0.05
    with pytest.raises(SettingError, match=r"^dt 0.055: the filter step must be a multiple of the record's step"):
        filter_step(record, dt=0.055)
    with pytest.raises(SettingError, match=r"^dt 5: the filter step is not shorter than the record"):
        filter_step(record, dt=5.0)
    assert rul_horizon(0.1, None, 500, 3) == pytest.approx(200.0)
    with pytest.raises(SettingError, match=r"^horizon 1e\+12: .*MAX_HORIZON_STEPS"):
        rul_horizon(0.1, 1e12, 500, 3)


def test_failure_values_and_candidates_are_checked_by_the_library(files):
    bg = files[0]
    arrs = derive_arrs(bg)
    parameters = bg.parameters
    for failures, domains, laws, message in [
            ({"R": 10.0}, bg.domains, LAWS, "equals the nominal value of 'R'"),
            ({"R": -5.0}, bg.domains, LAWS, r"outside the physical domain \(0, inf\)"),
            ({"R": -5.0}, None, ("exponential",), "an exponential degradation keeps the sign"),
            ({"Q": 1.0}, bg.domains, LAWS, "the model has no parameter 'Q'")]:
        with pytest.raises(SettingError, match=message) as caught:
            check_failures(failures, parameters, domains, laws)
        assert caught.value.setting == "failures"
    with pytest.raises(SettingError, match=r"^candidates 'R': give its failure value \(failures R=VALUE\)"):
        check_candidate("R", arrs, {"L": 2.0})
    with pytest.raises(SettingError, match=r"wrong side of the nominal value 10 of 'R' for direction down") as caught:
        check_candidate("R", arrs, {"R": 20.0}, "down")
    assert caught.value.setting == "direction"
    assert check_candidate("R", arrs, {"R": 20.0}) == "up" and check_candidate("R", arrs, {"R": 5.0}) == "down"
    with pytest.raises(SettingError, match="failures R=10 equals the nominal value"):  # prognose checks them too
        prognose(arrs, {"t": np.linspace(0, 1, 101), "V": np.ones(101), "i": np.zeros(101), "v_C": np.ones(101)},
                 {"R": 10.0})
