"""The tank cascade of benchmarks/bench_arrs.py at three tanks: its ARRs see every fault the structure detects.

With a level sensor on tanks 1 and 3 only, the level of tank 2 is known only through an orifice law
inverted (``dh = (q / a)^2`` with its sign), so the ARRs that see tank 2's area need that inversion.
"""

import importlib.util
import warnings
from pathlib import Path

import pytest

from diagnosis import ARRWarning, derive_arrs, structural_model
from diagnosis.elimination import faults_of_arr, unreached

PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_arrs.py"
SPEC = importlib.util.spec_from_file_location("bench_arrs", PATH)
bench_arrs = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(bench_arrs)


def test_the_builder_places_a_sensor_on_every_tank_or_every_other_one_and_the_last():
    def sensors(bg):
        return sorted(name for name, element in bg.structure().elements.items() if element.kind == "De")
    assert sensors(bench_arrs.tank_cascade(3)) == ["h1", "h2", "h3"]
    assert sensors(bench_arrs.sparse_tank_cascade(3)) == ["h1", "h3"]
    assert sensors(bench_arrs.sparse_tank_cascade(4)) == ["h1", "h3", "h4"]
    assert set(bench_arrs.MODELS) >= {"cascade", "cascade_sparse"}


@pytest.mark.slow
@pytest.mark.parametrize("build", ["tank_cascade", "sparse_tank_cascade"])
def test_the_arrs_of_three_tanks_detect_every_fault_the_structure_detects(build):
    bg = getattr(bench_arrs, build)(3)
    model = structural_model(bg)
    assert model.detectable() == set(model.faults)   # every area, orifice and sensor is in a redundant set
    with warnings.catch_warnings():
        warnings.simplefilter("error", ARRWarning)   # no gap left to warn about
        arrs = derive_arrs(bg)
    assert unreached(bg, arrs)["detect"] == []
    assert set().union(*(faults_of_arr(model, arr) for arr in arrs)) == set(model.faults)
    if build == "sparse_tank_cascade":   # tank 2's area is seen through h1 and h3 alone: an orifice inverted
        assert all(set(arr.signals) <= {"q_in", "h1", "h3"} for arr in arrs)
        assert any("A2" in arr.parameters for arr in arrs)
