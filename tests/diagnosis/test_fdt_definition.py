"""diagnosis.fdt_export without the toolbox: the definition it hands over, and the message when it is missing."""

import sys

import pytest
import sympy as sp

from bondgraph.library import dc_motor, tank_cascade
from diagnosis import structural_model, to_fdt
from diagnosis.fdt_export import fdt_definition


def test_every_equation_is_a_relation_with_its_faults_added_and_states_split_from_their_rates():
    bg = tank_cascade(3, every=2)
    model = structural_model(bg)
    definition = fdt_definition(bg)
    assert len(definition["rels"]) == len(model.equations)
    assert definition["z"] == ["q_in", "h1", "h3"]
    assert definition["rates"] == {"q_T1": "dq_T1", "q_T2": "dq_T2", "q_T3": "dq_T3"}
    known = set(definition["x"]) | set(definition["f"]) | set(definition["z"]) | set(definition["parameters"])
    for i, relation in enumerate(definition["rels"]):
        assert {s.name for s in relation.free_symbols} <= known
        assert not relation.atoms(sp.Derivative) and not relation.atoms(sp.core.function.AppliedUndef)
        acting = {f"f_{name}".replace(" ", "_") for name, rows in model.faults.items() if i in rows}
        assert {s.name for s in relation.free_symbols if s.name in definition["f"]} == acting
    assert "f_sensor_h1" in definition["f"] and "f_sensor_h1" not in fdt_definition(bg, sensor_faults=False)["f"]


def test_without_the_toolbox_the_message_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "faultdiagnosistoolbox", None)   # as if not installed
    with pytest.raises(ImportError, match=r"pip install 'bondgraph-phm\[fdt\]'"):
        to_fdt(dc_motor())
