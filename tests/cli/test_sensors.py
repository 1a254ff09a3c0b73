"""``bgphm sensors``: the alternatives on stdout and as JSON, bad input exit 2 in one line, no input overwritten."""

from __future__ import annotations

import json

import pytest

from bondgraph import BondGraph
from bondgraph.io import to_json
from bondgraph.library import dc_motor
from tests.cli.test_calibrate import run


@pytest.fixture
def speed_only(tmp_path):
    graph = dc_motor().graph.copy()
    graph.remove_node("i")
    path = tmp_path / "speed_only.json"
    path.write_text(to_json(BondGraph(graph, name="DC motor, speed sensor only"), inputs={"U": 12.0}))
    return path


def test_the_current_is_what_a_speed_only_motor_lacks(speed_only, tmp_path):
    out = tmp_path / "sensors.json"
    code, stdout, stderr = run("--quiet", "sensors", speed_only, "--out", out)
    assert code == 0, stderr
    assert stdout.splitlines()[0].startswith("Df 1_e  (cost 1): detects 7 faults")
    found = json.loads(out.read_text())
    (alternative,) = found["alternatives"]
    assert found["goal"] == "isolate" and alternative["sensors"] == ["Df 1_e"]
    assert set(map(tuple, alternative["derived"]["isolates"])) <= set(map(tuple, alternative["isolates"]))


def test_a_model_that_reaches_the_goal_says_so():
    code, stdout, _ = run("--quiet", "sensors", "dc-motor", "--goal", "detect", "--no-check")
    assert code == 0 and stdout.strip() == "the model's sensors reach the goal (detect): nothing to add"


@pytest.mark.parametrize("extra, words", [
    (["--cost", "Df 9=1"], ["--cost", "'Df 9' is not a detector the model lacks"]),
    (["--cost", "cheap"], ["--cost", "invalid DETECTOR=COST value: 'cheap'"]),
    (["--goal", "locate"], ["--goal", "invalid choice"]),
    (["--max-sensors", "0"], ["--max-sensors", ">= 1"]),
])
def test_bad_options_exit_2_in_one_line(speed_only, extra, words):
    code, stdout, stderr = run("--quiet", "sensors", speed_only, "--no-check", *extra)
    assert code == 2 and stdout == "" and len(stderr.strip().splitlines()) == 1
    assert all(w in stderr for w in words), stderr


def test_an_existing_out_file_is_kept_without_force(speed_only, tmp_path):
    out = tmp_path / "kept.json"
    out.write_text("mine")
    code, _, stderr = run("--quiet", "sensors", speed_only, "--no-check", "--out", out)
    assert code == 2 and "--force" in stderr and out.read_text() == "mine"
    assert run("--quiet", "sensors", speed_only, "--no-check", "--out", out, "--force")[0] == 0
    assert json.loads(out.read_text())["alternatives"][0]["derived"] is None


def test_a_sensor_inside_a_valve_bond_is_offered_when_asked(tmp_path):
    from bondgraph.library import three_tank

    model = tmp_path / "three_tank.json"
    model.write_text(to_json(three_tank()))
    out = tmp_path / "placements.json"
    code, _, err = run("sensors", str(model), "--inside-elements", "--no-check", "--out", str(out))
    assert code == 0, err
    alternatives = json.loads(out.read_text())["alternatives"]
    assert [a["sensors"] for a in alternatives] == [["Df A_2"], ["Df az2"]]
