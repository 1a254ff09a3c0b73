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
from prognosis import PrognosisSettings, filter_step, prognose, rul_horizon


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


def test_the_library_and_the_command_line_give_the_same_numbers(files, tmp_path):
    bg, model, data = files
    out = tmp_path / "out"
    code = main(["--quiet", "prognose", str(model), str(data), "--fail", "R=20", "--calibrate", "0.8",
                 "--degradation", "linear", "--particles", "100", "--no-sensors", "--seed", "3", "--out", str(out)])
    assert code == 0
    cli = json.loads((out / "prognosis.json").read_text())
    settings = PrognosisSettings(detection=DetectionSettings(calibrate=0.8), laws=("linear",), particles=100,
                                 sensors=False, seed=3)
    result = prognose(derive_arrs(bg), read_csv(data), {"R": 20.0}, settings, domains=bg.domains)
    python = json.loads(json.dumps(result.as_dict(), default=float))
    assert python["candidate"] == cli["candidate"] == "R" and python["status"] == cli["status"]
    assert python["predictions"] and python["predictions"] == cli["predictions"]  # every figure, to the last bit
    for key in ("filter_step", "residual_noise_std", "margins", "calibration_end", "evidence", "decisions"):
        assert python[key] == cli[key], key
    assert 1.0 < python["detection_time"] == cli["detection_time"] < 2.0  # R drifts from t = 1 s


@pytest.mark.parametrize("settings, setting", [
    ({"particles": 1}, "particles"), ({"particles": 10**6}, "particles"), ({"rul_every": 0}, "rul_every"),
    ({"horizon": -1.0}, "horizon"), ({"dt": float("nan")}, "dt"), ({"seed": -1}, "seed"),
    ({"method": "kalman"}, "method"), ({"laws": ()}, "laws"), ({"rate": (2.0, 1.0)}, "rate"),
    ({"pairs": True, "method": "sir"}, "pairs"), ({"pairs": True, "candidates": ("R",)}, "pairs"),
])
def test_bad_settings_are_refused_naming_the_setting(settings, setting):
    with pytest.raises(SettingError) as caught:
        PrognosisSettings(**settings)
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
