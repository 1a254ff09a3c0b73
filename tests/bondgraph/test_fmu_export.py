"""The FMU's texts without a compiler or fmpy (bondgraph.fmu_export.fmu_sources), and the import's missing extra:
the FMI 2.0 model description read back as XML, the C model's sizes and GUID, escaping, and bad options."""

import sys
import xml.etree.ElementTree as ET
import zipfile

import pytest

from bondgraph import BondGraph, FmuError, FmuPlant, fmu_sources, to_fmu
from bondgraph.library import rlc_circuit


def rc_with_a_free_text_name() -> BondGraph:
    bg = BondGraph(name='RC <"filter"> & \'load\'\x01')
    bg.add("V", "Se", value=5.0)
    bg.add("J", "1")
    bg.add("R", "R", value=100.0)
    bg.add("C", "C", value=1e-6)
    bg.add("v_C", "De")
    bg.add("J0", "0")
    for tail, head in [("V", "J"), ("J", "R"), ("J", "J0"), ("J0", "C"), ("J0", "v_C")]:
        bg.bond(tail, head)
    return bg


def test_the_model_description_lists_parameters_inputs_states_and_signals_in_value_reference_order():
    files = fmu_sources(rc_with_a_free_text_name(), "rc", x0={"C": 2e-6}, parameters={"R": 220.0}, step=1e-4)
    root = ET.fromstring(files["modelDescription.xml"])
    assert root.get("fmiVersion") == "2.0" and root.get("modelName") == 'RC <"filter"> & \'load\'?'
    assert root.find("CoSimulation").get("modelIdentifier") == "rc"
    assert [f.get("name") for f in root.iter("File")] == ["rc.c"]
    rows = [(v.get("name"), v.get("valueReference"), v.get("causality"), v.get("variability"), v.get("initial"),
             v.find("Real").get("start")) for v in root.iter("ScalarVariable")]
    assert rows == [("R", "0", "parameter", "tunable", "exact", "220.0"),
                    ("C", "1", "parameter", "tunable", "exact", "1e-06"),
                    ("V", "2", "input", "continuous", None, "5.0"),
                    ("q_C", "3", "output", "continuous", "exact", "2e-06"),
                    ("v_C", "4", "output", "continuous", None, None)]
    assert [u.get("index") for u in root.find("ModelStructure/Outputs")] == ["4", "5"]
    assert [u.get("index") for u in root.find("ModelStructure/InitialUnknowns")] == ["5"]
    assert root.find("DefaultExperiment").get("stepSize") == "0.0001"
    c = files["sources/rc.c"]
    assert f'#define BG_GUID "{root.get("guid")}"' in c
    assert [f"#define BG_N{kind} {n}" in c for kind, n in zip("PUXY", (2, 1, 1, 1))] == [True] * 4
    assert "dx[0] = " in c and "y[0] = x[0]/p[1];" in c   # v_C = q_C / C
    assert "filter" not in c   # the free-text name stays in the XML, escaped there


def test_the_same_model_gives_the_same_texts_and_another_start_another_guid():
    first, again = fmu_sources(rlc_circuit(), "rlc"), fmu_sources(rlc_circuit(), "rlc")
    other = fmu_sources(rlc_circuit(), "rlc", inputs={"V": 2.0})
    assert first == again
    guid = ET.fromstring(first["modelDescription.xml"]).get("guid")
    assert guid != ET.fromstring(other["modelDescription.xml"]).get("guid")


@pytest.mark.parametrize("options, message", [
    ({"inputs": {"U": 1.0}}, r"^to_fmu: input 'U' is not an input of the model; its inputs are \['V'\]$"),
    ({"x0": {"q_X": 1.0}}, r"^to_fmu: x0 names 'q_X', which is not a state; states are \['p_L', 'q_C'\]"),
    ({"parameters": {"R": float("nan")}}, r"^to_fmu: parameter 'R' must be a finite number, got nan$"),
    ({"step": 0}, r"^to_fmu: step must be a positive number, got 0$"),
    ({"tolerance": 1.5}, r"^to_fmu: tolerance must be below 1, got 1.5$"),
])
def test_bad_options_are_named(options, message):
    with pytest.raises(FmuError, match=message):
        fmu_sources(rlc_circuit(), "rlc", **options)


def test_bad_paths_and_identifiers_are_named(tmp_path):
    with pytest.raises(FmuError, match=r"^to_fmu: model_identifier '9lives' is not a C identifier$"):
        fmu_sources(rlc_circuit(), "9lives")
    with pytest.raises(FmuError, match=r"^to_fmu: path 'rlc.zip' must end in .fmu$"):
        to_fmu(rlc_circuit(), "rlc.zip")
    with pytest.raises(FmuError, match=r"^to_fmu: the folder of path '.*/missing/rlc.fmu' does not exist$"):
        to_fmu(rlc_circuit(), tmp_path / "missing" / "rlc.fmu")


def test_running_an_fmu_without_fmpy_names_the_extra(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "fmpy", None)   # as if fmpy were not installed
    archive = tmp_path / "any.fmu"
    with zipfile.ZipFile(archive, "w") as fmu:
        fmu.writestr("modelDescription.xml", "<fmiModelDescription/>")
    with pytest.raises(ImportError, match=r"^running an FMU needs fmpy: pip install 'bondgraph-phm\[fmi\]'$"):
        FmuPlant(archive)


def test_units_are_written_in_si_base_units_and_states_take_their_bonds_times_a_second():
    from bondgraph.library import dc_motor

    root = ET.fromstring(fmu_sources(dc_motor(), "dc_motor")["modelDescription.xml"])
    bases = {unit.get("name"): unit.find("BaseUnit").attrib for unit in root.iter("Unit")}
    units = {v.get("name"): v.find("Real").get("unit") for v in root.iter("ScalarVariable")}
    assert units == {"R_a": "Ohm", "L_a": "H", "k_m": "N*m/A", "J": "kg*m^2", "b": "N*m*s/rad", "U": "V",
                     "p_L_a": "V*s", "p_J": "N*m*s", "i": "A", "omega": "rad/s"}
    assert bases["Ohm"] == {"kg": "1", "m": "2", "s": "-3", "A": "-2"} and bases["rad/s"] == {"s": "-1", "rad": "1"}
    assert [child.tag for child in root][:3] == ["CoSimulation", "UnitDefinitions", "LogCategories"]   # schema order


def test_an_output_lists_the_inputs_it_reads_at_once():
    """A voltage sensor across the source reads the input itself; the current through the coil, its state."""
    bg = BondGraph(name="source, load and coil")
    bg.add("V", "Se")
    bg.add("0_a", "0")
    bg.add("R", "R", value=10.0)
    bg.add("v", "De")
    bg.add("1_b", "1")
    bg.add("L", "I", value=0.1)
    bg.add("R_2", "R", value=1.0)
    bg.add("i", "Df")
    for tail, head in [("V", "0_a"), ("0_a", "R"), ("0_a", "v"), ("0_a", "1_b"), ("1_b", "L"), ("1_b", "R_2"),
                       ("1_b", "i")]:
        bg.bond(tail, head)
    root = ET.fromstring(fmu_sources(bg, "rl")["modelDescription.xml"])
    index = {v.get("name"): str(k) for k, v in enumerate(root.iter("ScalarVariable"), start=1)}
    dependencies = {u.get("index"): u.get("dependencies") for u in root.find("ModelStructure/Outputs")}
    assert dependencies == {index["p_L"]: "", index["v"]: index["V"], index["i"]: ""}
