"""Sensor placement (diagnosis.sensor_placement): minimal sets that reach the structural goal, checked by the
ARRs, on library models and zoo models it was not designed around."""

from __future__ import annotations

import pytest

from bondgraph import BondGraph, SettingError
from bondgraph.library import dc_motor, three_tank, torsion_bar
from diagnosis import structural_model
from diagnosis.sensor_placement import element_detectors, junction_detectors, place_sensors, with_sensors
from tests.zoo.chain import cases


def reach(bg, sensors, goal="isolate"):
    """What the structure of ``bg`` with ``sensors`` (fallible) detects and tells apart, written out here."""
    model = structural_model(with_sensors(bg, sensors))
    detects = model.detectable()
    pairs = {(a, b) for a in detects for b in model.faults if a != b and model.isolable(a, b)}
    return detects, pairs if goal == "isolate" else set()


def assert_minimal_and_reaching(bg, placements, goal):
    everything = reach(bg, junction_detectors(bg), goal)
    for placement in placements:
        sensors = placement.sensors
        own = {f"sensor {'e' if s.startswith('De') else 'f'}_{s.split(' ', 1)[1]}" for s in sensors}
        detects, pairs = reach(bg, sensors, goal)
        base = set(structural_model(bg).faults)
        faults = base | own
        assert {f for f in everything[0] if f in faults} <= detects
        # the model's faults told from every fault; an added sensor's own fault need only be detected
        assert {(a, b) for a, b in everything[1] if a in base and b in faults} <= pairs
        for dropped in sensors:  # minimal: no sensor can be dropped
            fewer = tuple(s for s in sensors if s != dropped)
            fewer_own = own - {f"sensor {'e' if dropped.startswith('De') else 'f'}_{dropped.split(' ', 1)[1]}"}
            d, p = reach(bg, fewer, goal)
            aims = set(structural_model(bg).faults) | fewer_own
            assert not ({f for f in everything[0] if f in aims} <= d
                        and {(a, b) for a, b in everything[1] if a in base and b in aims} <= p), (bg.name, dropped)


@pytest.mark.slow
def test_the_torsion_bar_gets_minimal_sets_checked_by_its_arrs():
    placements = place_sensors(torsion_bar(), goal="isolate")
    assert placements and all(len(p.sensors) == 2 for p in placements)
    assert_minimal_and_reaching(torsion_bar(), placements, "isolate")
    for placement in placements:  # the ARRs reach no more than the structure allows, and see every fault it does
        assert placement.derived["isolates"] <= placement.isolates
        assert placement.derived["detects"] == placement.detects


def test_a_motor_with_its_speed_sensor_only_gets_the_current():
    graph = dc_motor().graph.copy()
    graph.remove_node("i")
    bg = BondGraph(graph, name="speed only")
    (placement,) = place_sensors(bg, goal="isolate")
    assert placement.sensors == ("Df 1_e",) and placement.cost == 1.0
    assert len(placement.isolates) > len(reach(bg, ())[1])
    assert place_sensors(dc_motor(), goal="isolate") == []  # the bench motor has it already


@pytest.mark.parametrize("name", ["rc_ladder2", "quarter_car", "gear_belt_drivetrain", "wheatstone_rc",
                                  "throttle_body"])
def test_zoo_placements_are_minimal(name):
    case = next(c for c in cases() if c.name == name)
    bg = case.build()
    assert place_sensors(bg, goal="isolate", check=False)  # each of these gains from a detector
    for goal in ("detect", "isolate"):
        assert_minimal_and_reaching(bg, place_sensors(bg, goal=goal, check=False), goal)


def test_costs_order_the_alternatives():
    bg = torsion_bar()
    cheap = place_sensors(bg, goal="isolate", cost={"Df 1_Md": 0.5}, check=False)
    assert cheap[0].sensors == ("Df 1_e", "Df 1_Md") and cheap[0].cost == 1.5
    assert [p.cost for p in cheap] == sorted(p.cost for p in cheap)


@pytest.mark.parametrize("options, setting, words", [
    ({"goal": "locate"}, "goal", "detect, isolate"),
    ({"cost": {"De 9_9": 1.0}}, "cost", "'De 9_9' is not a detector"),
    ({"faults": ["R_x"]}, "faults", "no fault 'R_x'"),
    ({"max_sensors": 0}, "max_sensors", ">= 1"),
])
def test_bad_settings_name_the_setting(options, setting, words):
    with pytest.raises(SettingError, match=words) as error:
        place_sensors(three_tank(), **options)
    assert error.value.setting == setting


def test_too_few_sensors_allowed_is_said_not_taken_for_nothing_to_add():
    with pytest.raises(SettingError, match="no set of at most 1 of the 4 detectors") as error:
        place_sensors(torsion_bar(), goal="isolate", max_sensors=1, check=False)
    assert error.value.setting == "max_sensors"


def test_a_sensor_inside_an_element_bond_changes_no_dynamics_and_reads_the_elements_flow():
    bg = three_tank()
    assert "Df az2" in element_detectors(bg) and "Df az2" not in junction_detectors(bg)
    before = str(bg.state_equations()).splitlines()
    after = str(with_sensors(bg, ["Df az2"]).state_equations()).splitlines()
    assert after[:len(before)] == before   # the same state equations and outputs
    (reading,) = after[len(before):]
    outflow = before[1].split(" = ")[1].split(" + ")[0]   # tank 2's balance: its valve's outflow, negated
    assert reading == f"f_az2 = {outflow.removeprefix('-')}"


def test_the_three_tanks_reach_full_isolability_with_one_flow_inside_a_valve_or_tank_bond():
    bg = three_tank()
    assert place_sensors(bg, goal="isolate", check=False) == []   # junction detectors add nothing
    placements = place_sensors(bg, goal="isolate", inside_elements=True, check=False)
    assert [p.sensors for p in placements] == [("Df A_2",), ("Df az2",)]
    faults = len(structural_model(bg).faults) + 1
    assert all(len(p.isolates) == faults * (faults - 1) for p in placements)   # every ordered pair


@pytest.mark.slow
def test_the_three_tanks_full_isolability_is_realised_by_the_arrs_of_the_valve_flow():
    (tank, valve) = place_sensors(three_tank(), goal="isolate", inside_elements=True)
    assert valve.derived["isolates"] == valve.isolates   # every ordered pair, by the ARRs themselves
    assert tank.derived["isolates"] <= tank.isolates and tank.derived["detects"] == tank.detects
