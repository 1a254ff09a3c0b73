"""The Fault Diagnosis Toolbox on our models (diagnosis.fdt_export, the ``fdt`` extra): its minimal
overdetermined sets, less the differential constraints, are ours on the library and every zoo model."""

import time

import pytest

from bondgraph.library import dc_motor, friction_drive, tank_cascade, three_tank, torsion_bar
from diagnosis import structural_model
from diagnosis.fdt_export import fdt_definition, to_fdt
from tests.zoo.chain import cases

pytestmark = [pytest.mark.interop, pytest.mark.slow]   # FDT imports matplotlib and scikit-learn: seconds

MODELS = {"three_tank": three_tank, "torsion_bar": torsion_bar, "dc_motor": dc_motor,
          "friction_drive": friction_drive, "cascade_sparse_5": lambda: tank_cascade(5, every=2),
          **{case.name: case.build for case in cases()}}


def fdt_msos(bg) -> tuple[set, float]:
    """FDT's minimal sets of ``bg``, each without its differential constraints, and FDT's CPU seconds."""
    n = len(structural_model(bg).equations)   # FDT appends the differential constraints after our equations
    model = to_fdt(bg)
    start = time.process_time()
    found = model.MSO()
    return {frozenset(int(i) for i in rows if i < n) for rows in found}, time.process_time() - start


@pytest.mark.parametrize("name", sorted(MODELS))
def test_the_toolbox_finds_our_minimal_sets(name):
    bg = MODELS[name]()
    ours = set(map(frozenset, structural_model(bg).mso_sets()))
    theirs, _ = fdt_msos(bg)
    assert theirs == ours


def test_the_toolbox_model_names_our_unknowns_faults_and_signals():
    bg = dc_motor()
    model = to_fdt(bg)
    definition = fdt_definition(bg)
    assert model.x == definition["x"] and model.f == definition["f"] and model.z == ["U", "i", "omega"]
    assert model.ne() == len(definition["rels"]) + len(definition["rates"])   # one constraint per state
    assert {"f_sensor_i", "f_sensor_omega"} <= set(model.f)
    assert "f_sensor_i" not in to_fdt(bg, sensor_faults=False).f
