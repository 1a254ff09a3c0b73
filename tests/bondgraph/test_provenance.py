"""Provenance of generated documents: the tool's version, the date (SOURCE_DATE_EPOCH), the model's hash."""

from __future__ import annotations

import json
import re
from datetime import datetime, timezone
from importlib import metadata

import pytest

from bondgraph import BondGraph
from bondgraph.errors import PHMError, SettingError
from bondgraph.io import model_from_json, to_json
from bondgraph.library import dc_motor, rlc_circuit
from bondgraph.provenance import DISTRIBUTION, generated_at, model_sha256, provenance, tool_version


def test_the_distribution_is_the_one_pyproject_names():
    from pathlib import Path

    pyproject = (Path(__file__).resolve().parents[2] / "pyproject.toml").read_text()
    assert re.search(rf'^name = "{re.escape(DISTRIBUTION)}"$', pyproject, re.M)
    try:
        installed = metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        installed = "unknown"
    assert tool_version() == installed


@pytest.mark.parametrize("epoch", [0, 86399, 1_700_000_000])
def test_source_date_epoch_sets_the_date(epoch, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", str(epoch))
    expected = datetime.fromtimestamp(epoch, timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    assert generated_at() == expected and provenance(rlc_circuit()).generated == expected


def test_without_source_date_epoch_the_date_is_now(monkeypatch):
    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    before = datetime.now(timezone.utc).replace(microsecond=0)
    stamp = datetime.strptime(generated_at(), "%Y-%m-%d %H:%M:%S UTC").replace(tzinfo=timezone.utc)
    after = datetime.now(timezone.utc)
    assert before <= stamp <= after


@pytest.mark.parametrize("value", ["yesterday", "-5", "1.5", "1e9", " 12", "٣", "9" * 30])
def test_a_bad_source_date_epoch_is_a_one_line_error_naming_it(value):
    with pytest.raises(SettingError) as caught:
        generated_at({"SOURCE_DATE_EPOCH": value})
    message = str(caught.value)
    assert message.startswith("environment variable SOURCE_DATE_EPOCH: ") and "\n" not in message
    assert isinstance(caught.value, PHMError)
    assert "{setting}" not in caught.value.template  # a command line cannot rename it into an option


def test_the_hash_is_of_the_model_not_of_the_order_it_was_built_in():
    bg = dc_motor()
    data = json.loads(to_json(bg))
    data["nodes"].reverse()
    data["links"].reverse()
    shuffled = model_from_json(json.dumps(data)).model
    assert list(shuffled.elements) != list(bg.elements)
    assert model_sha256(shuffled) == model_sha256(bg)
    assert re.fullmatch(r"[0-9a-f]{64}", model_sha256(bg))


@pytest.mark.parametrize("change", ["value", "uncertainty", "name", "bond"])
def test_the_hash_changes_with_the_model(change):
    def build(variant=None):
        bg = BondGraph(name="RC" if variant != "name" else "RC 2")
        bg.add("V", "Se")
        bg.add("J", "1")
        bg.add("R", "R", value=2.0 if variant != "value" else 2.5,
               uncertainty=(-0.1, 0.1) if variant != "uncertainty" else (-0.1, 0.2))
        bg.add("C", "C", value=1e-3)
        bg.bond("V", "J")
        bg.bond("J", "R")
        bg.bond("J", "C") if variant != "bond" else bg.bond("C", "J")
        return bg

    assert model_sha256(build()) == model_sha256(build())
    assert model_sha256(build(change)) != model_sha256(build())
