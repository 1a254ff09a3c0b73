"""A JSON model's ``graph.calibration`` block (what ``bgphm calibrate`` writes): read and kept, written back,
refused when it is not an object, and no part of the model's hash."""

from __future__ import annotations

import json

import pytest

from bondgraph.errors import ModelError
from bondgraph.io import ModelFileError, load_model, model_from_json, to_json
from bondgraph.library import dc_motor
from bondgraph.provenance import model_sha256

BLOCK = {"method": {"estimator": "least squares", "level": 0.95}, "records": [{"name": "a.csv", "sha256": "ab" * 32}],
         "estimates": {"b": {"estimate": 1.2e-4, "interval": [1.1e-4, 1.3e-4]}}}


def test_the_block_is_read_kept_and_written_back(tmp_path):
    text = to_json(dc_motor(), inputs={"U": 12.0}, calibration=BLOCK)
    assert json.loads(text)["graph"]["calibration"] == BLOCK
    path = tmp_path / "calibrated.json"
    path.write_text(text)
    spec = load_model(path)
    assert spec.calibration == BLOCK and spec.inputs == {"U": 12.0}
    assert spec.model.parameters == dc_motor().parameters
    again = to_json(spec.model, inputs=spec.inputs, calibration=spec.calibration)
    assert json.loads(again) == json.loads(text)


def test_a_model_without_the_block_has_an_empty_one_and_the_hash_ignores_it():
    assert model_from_json(to_json(dc_motor())).calibration == {}
    assert "calibration" not in json.loads(to_json(dc_motor()))["graph"]
    with_block = model_from_json(to_json(dc_motor(), calibration=BLOCK)).model
    assert model_sha256(with_block) == model_sha256(dc_motor())


@pytest.mark.parametrize("value", [[1, 2], "calibrated", 3.0, None])
def test_a_block_that_is_not_an_object_is_refused_naming_it(value):
    data = json.loads(to_json(dc_motor()))
    data["graph"]["calibration"] = value
    with pytest.raises(ModelFileError, match=r"m.json: graph.calibration must be an object"):
        model_from_json(json.dumps(data), where="m.json")


def test_other_unknown_graph_fields_are_still_refused():
    data = json.loads(to_json(dc_motor()))
    data["graph"]["calibrations"] = {}
    with pytest.raises(ModelFileError, match=r"unknown field\(s\) \['calibrations'\] in 'graph'"):
        model_from_json(json.dumps(data), where="m.json")


@pytest.mark.parametrize("block, words", [({"x": float("nan")}, "finite numbers"), ({"x": object()}, "JSON data"),
                                          (["a"], "must be a mapping")])
def test_to_json_refuses_a_block_that_is_not_json_data(block, words):
    with pytest.raises(ModelError, match=words):
        to_json(dc_motor(), calibration=block)
