"""Models composed of saved sub-models (bondgraph.composition, graph.parts in JSON).

The belt drive of examples/drive: a DC motor, an elastic belt between two pulleys and an inertial load,
each a JSON file of its own with named ports, composed by drive.json.  The judge of the composition is
the same system written flat by hand (same names, so the equations must be the very same) and the
physics written from scratch and integrated by scipy."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from bondgraph import BondGraph, compose, load_model, simulate, to_json
from bondgraph.errors import ModelError
from bondgraph.io import MAX_PART_DEPTH, ModelFileError, model_from_json

DRIVE = Path(__file__).resolve().parents[2] / "examples" / "drive"
PARTS = {"motor": "motor.json", "belt": "belt.json", "load": "load.json"}


def parts() -> dict:
    return {name: load_model(DRIVE / file).model for name, file in PARTS.items()}


def flat_drive() -> BondGraph:
    """motor + belt + load written as one model by hand, with the composed model's names and labels (each
    part's bonds numbered as the part numbers them: in networkx's edge order, by tail node)."""
    bg = BondGraph(name="belt drive, flat")
    add = bg.add
    add("motor.U", "Se", unit="V")
    add("motor.1_e", "1")
    add("motor.R_a", "R", value=1.2, uncertainty=(-0.05, 0.05), unit="ohm")
    add("motor.L_a", "I", value=0.003, uncertainty=(-0.05, 0.05), unit="H")
    add("motor.i", "Df", unit="A")
    add("motor.k_m", "GY", value=0.06, uncertainty=(-0.02, 0.02), unit="N*m/A")
    add("motor.1_m", "1")
    add("motor.J_m", "I", value=2e-4, uncertainty=(-0.02, 0.02), unit="kg*m^2")
    add("motor.b_m", "R", value=1e-4, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    add("motor.omega", "Df", unit="rad/s")
    add("belt.1_d", "1")
    add("belt.J_d", "I", value=1e-4, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    add("belt.r_d", "TF", value=0.02, unit="m")
    add("belt.0_b", "0")
    add("belt.1_s", "1")
    add("belt.c_b", "C", value=1e-5, uncertainty=(-0.1, 0.1), unit="m/N")
    add("belt.d_b", "R", value=20.0, uncertainty=(0.0, 0.3), unit="N*s/m")
    add("belt.r_l", "TF", value=0.06, modulus="1/belt.r_l", unit="m")
    add("belt.1_l", "1")
    add("belt.J_l", "I", value=4e-4, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    add("load.1_L", "1")
    add("load.J_L", "I", value=0.01, uncertainty=(-0.05, 0.05), unit="kg*m^2")
    add("load.b_L", "R", value=0.002, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
    add("load.T_L", "Se", unit="N*m")
    add("load.omega_L", "Df", unit="rad/s")
    bonds = {"motor": [("U", "1_e"), ("1_e", "R_a"), ("1_e", "L_a"), ("1_e", "k_m"), ("k_m", "1_m"), ("1_m", "J_m"),
                       ("1_m", "b_m")],
             "belt": [("1_d", "J_d"), ("1_d", "r_d"), ("r_d", "0_b"), ("0_b", "1_s"), ("0_b", "r_l"), ("1_s", "c_b"),
                      ("1_s", "d_b"), ("r_l", "1_l"), ("1_l", "J_l")],
             "load": [("1_L", "J_L"), ("1_L", "b_L"), ("1_L", "T_L")]}
    for part, pairs in bonds.items():
        for number, (tail, head) in enumerate(pairs, start=1):
            bg.bond(f"{part}.{tail}", f"{part}.{head}", label=f"{part}.{number}")
    for tail, head in [("motor.1_e", "motor.i"), ("motor.1_m", "motor.omega"), ("load.1_L", "load.omega_L")]:
        bg.bond(tail, head)
    bg.bond("motor.1_m", "belt.1_d", label=1)
    bg.bond("belt.1_l", "load.1_L", label=2)
    return bg


def test_the_parts_are_models_of_their_own_with_named_ports():
    found = parts()
    assert {name: model.ports for name, model in found.items()} == {
        "motor": {"shaft": "1_m"}, "belt": {"drive": "1_d", "driven": "1_l"}, "load": {"shaft": "1_L"}}
    # the belt alone: two pulleys and the belt's spring, a free system whose states are its own
    assert [str(x) for x in found["belt"].state_equations().states] == ["p_J_d", "q_c_b", "p_J_l"]


def test_the_composed_file_gives_the_equations_of_the_system_written_flat():
    composed, flat = load_model(DRIVE / "drive.json").model, flat_drive()
    assert set(composed.equations()) == set(flat.equations())
    ours, theirs = composed.state_equations(), flat.state_equations()
    assert ours.states == theirs.states
    assert all(sp.simplify(a - b) == 0 for a, b in zip(ours.rhs, theirs.rhs))
    assert composed.parameters == flat.parameters and composed.uncertainties == flat.uncertainties
    assert composed.inputs == ["motor.U", "load.T_L"] and composed.outputs == ["motor.i", "motor.omega",
                                                                                "load.omega_L"]


def test_the_dsl_and_the_json_composition_build_the_same_graph():
    by_file = load_model(DRIVE / "drive.json").model
    in_python = compose(parts(), [("motor.shaft", "belt.drive"), ("belt.driven", "load.shaft")])
    assert list(by_file.graph.nodes(data=True)) == list(in_python.graph.nodes(data=True))
    assert list(by_file.graph.edges(data=True)) == list(in_python.graph.edges(data=True))


def test_the_composed_model_moves_as_the_physics_says():
    """Motor, rigid couplings to the pulleys, a Kelvin-Voigt belt, the load: integrated here by scipy."""
    spec = load_model(DRIVE / "drive.json")
    p = spec.model.parameters
    U, T_L = spec.inputs["motor.U"], spec.inputs["load.T_L"]
    r_d, r_l, c_b, d_b = p["belt.r_d"], p["belt.r_l"], p["belt.c_b"], p["belt.d_b"]

    def physics(t, z):
        i, w_m, x, w_L = z
        stretch = r_d * w_m - r_l * w_L
        tension = x / c_b + d_b * stretch
        return [(U - p["motor.R_a"] * i - p["motor.k_m"] * w_m) / p["motor.L_a"],
                (p["motor.k_m"] * i - p["motor.b_m"] * w_m - r_d * tension) / (p["motor.J_m"] + p["belt.J_d"]),
                stretch,
                (r_l * tension - p["load.b_L"] * w_L - T_L) / (p["belt.J_l"] + p["load.J_L"])]

    t = np.linspace(0.0, 0.5, 251)
    reference = solve_ivp(physics, (0.0, 0.5), [0.0] * 4, t_eval=t, method="LSODA", rtol=1e-10, atol=1e-12)
    ours = simulate(spec.model, (0.0, 0.5), spec.inputs, t_eval=t, rtol=1e-10, atol=1e-12)
    for name, row in [("motor.i", 0), ("motor.omega", 1), ("load.omega_L", 3)]:
        scale = np.ptp(reference.y[row])
        assert scale > 0 and np.max(np.abs(ours[name] - reference.y[row])) < 1e-6 * scale


def test_run_settings_come_from_the_parts_under_their_paths_and_the_file_overrides_them(tmp_path):
    for file in PARTS.values():
        shutil.copy(DRIVE / file, tmp_path / file)
    drive = json.loads((DRIVE / "drive.json").read_text())
    drive["graph"].update(inputs={"load.T_L": 0.0}, x0={"p_load.J_L": 0.0, "motor.L_a": 1e-3})
    (tmp_path / "drive.json").write_text(json.dumps(drive))
    spec = load_model(tmp_path / "drive.json")
    assert spec.inputs == {"motor.U": 24.0, "load.T_L": 0.0} and spec.t_end == 2.0
    assert spec.x0 == {"p_load.J_L": 0.0, "motor.L_a": 1e-3}


def test_a_composed_model_written_out_reads_back_flat_with_its_ports():
    composed = compose(parts(), [("motor.shaft", "belt.drive"), ("belt.driven", "load.shaft")],
                       ports={"out": "load.shaft"}, name="drive")
    back = model_from_json(to_json(composed)).model
    assert back.ports == {"out": "load.1_L"} and set(back.equations()) == set(composed.equations())


def test_a_composed_model_is_a_part_in_turn():
    drive = compose(parts(), [("motor.shaft", "belt.drive"), ("belt.driven", "load.shaft")],
                    ports={"shaft": "load.shaft"})
    brake = BondGraph(name="brake")
    brake.add("1_b", "1")
    brake.add("b", "R", value=0.01)
    brake.add("J_b", "I", value=1e-3)
    brake.bond("1_b", "b")
    brake.bond("1_b", "J_b")
    brake.port("disc", "1_b")
    plant = compose({"drive": drive, "brake": brake}, [("drive.shaft", "brake.disc")])
    assert "drive.motor.R_a" in plant.parameters and "brake.b" in plant.parameters
    assert plant.outputs == ["drive.motor.i", "drive.motor.omega", "drive.load.omega_L"]
    assert str(plant.state_equations().states[0]) == "p_drive.motor.L_a"


def test_laws_constants_and_modulating_signals_follow_the_path():
    tank = BondGraph(name="tank")
    tank.add("Q", "Sf", unit="m^3/s")
    tank.add("0_t", "0")
    tank.add("A", "C", value=0.1)
    tank.add("valve", "R", value=1e-4, law="f - valve*sqrt(Abs(e)/rho)", params={"rho": 1000.0},
             uncertainties={"rho": (-0.01, 0.01)})
    tank.add("h", "De")
    for tail, head in [("Q", "0_t"), ("0_t", "A"), ("0_t", "valve"), ("0_t", "h")]:
        tank.bond(tail, head)
    tank.port("outlet", "0_t")
    composed = compose({"upper": tank, "lower": tank}, [("upper.outlet", "lower.outlet")])
    laws = {str(e.law) for e in composed.elements.values() if e.law is not None}
    assert laws == {"f - upper.valve*sqrt(1/upper.rho)*sqrt(Abs(e))", "f - lower.valve*sqrt(1/lower.rho)*sqrt(Abs(e))"}
    assert composed.uncertainties["upper.rho"] == (-0.01, 0.01) and composed.parameters["lower.rho"] == 1000.0
    assert tank.parameters == {"A": 0.1, "valve": 1e-4, "rho": 1000.0}   # the part itself is unchanged

    lever = BondGraph(name="lever")
    lever.add("F", "Se")
    lever.add("1_a", "1")
    lever.add("arm", "MTF", signal="x", param="r", value=2.0, modulus="r*x")
    lever.add("1_b", "1")
    lever.add("m", "I", value=1.0)
    for tail, head in [("F", "1_a"), ("1_a", "arm"), ("arm", "1_b"), ("1_b", "m")]:
        lever.bond(tail, head)
    arm = compose({"left": lever}).elements["left.arm"]
    assert str(arm.modulus) == "left.r*left.x(t)" and arm.signal == "left.x"


@pytest.mark.parametrize("connections, message", [
    ([("motor.shaft", "belt.nowhere")], r"connections\[0\]: 'belt.nowhere': part 'belt' has no port 'nowhere' "
                                        r"\(its ports: drive, driven\)"),
    ([("motor.shaft", "gearbox.in")], r"connections\[0\]: 'gearbox.in': no part 'gearbox'"),
    ([("motor.shaft",)], r"connections\[0\]: expected a pair of ports"),
    (["motor.shaft"], r"connections\[0\]: expected a pair of ports"),
    ([("motor.shaft", "belt.drive"), ("belt.drive", "motor.shaft")], r"connections\[1\]: .* already bonded"),
])
def test_a_wrong_connection_is_named(connections, message):
    with pytest.raises(ModelError, match=message):
        compose(parts(), connections)


def test_wrong_parts_and_ports_are_named():
    with pytest.raises(ModelError, match="part name 'a.b' has a '.'"):
        compose({"a.b": parts()["motor"]})
    with pytest.raises(TypeError, match="compose: part 'motor' must be a BondGraph, got str 'motor.json'"):
        compose({"motor": "motor.json"})
    bad = parts()["motor"]
    bad.graph.graph["ports"] = {"shaft": "J_m"}
    with pytest.raises(ModelError, match=r"part 'motor': port 'shaft': node 'J_m' \(I\) is not a 0- or 1-junction"):
        compose({"motor": bad})
    with pytest.raises(ModelError, match="port 'shaft' already exists"):
        parts()["motor"].port("shaft", "1_e")


def test_part_files_are_data_found_beside_the_composing_file_and_never_include_themselves(tmp_path):
    def write(name, graph, nodes=None):
        (tmp_path / name).write_text(json.dumps({"graph": graph, **({"nodes": nodes} if nodes else {})}))
        return tmp_path / name

    with pytest.raises(ModelFileError, match=r"graph.parts\['m'\]: a part is a JSON model file .* 'motor.py'"):
        load_model(write("a.json", {"parts": {"m": "motor.py"}}))
    with pytest.raises(ModelFileError, match=r"graph.parts\['m'\]: no such file"):
        load_model(write("b.json", {"parts": {"m": "missing.json"}}))
    write("c.json", {"parts": {"d": "d.json"}})
    write("d.json", {"parts": {"c": "c.json"}})
    with pytest.raises(ModelFileError, match=r"c.json includes itself \(c.json -> d.json -> c.json\)"):
        load_model(tmp_path / "c.json")
    with pytest.raises(ModelFileError, match="graph.parts names files; read the model with load_model"):
        model_from_json(json.dumps({"graph": {"parts": {"m": "motor.json"}}}))
    with pytest.raises(ModelFileError, match="graph.connections without graph.parts"):
        model_from_json(json.dumps({"graph": {"connections": []}, "nodes": [{"id": "x", "kind": "0"}]}))
    chain = [write(f"n{k}.json", {"parts": {"inner": f"n{k + 1}.json"}}) for k in range(MAX_PART_DEPTH + 1)]
    shutil.copy(DRIVE / "load.json", tmp_path / f"n{MAX_PART_DEPTH + 1}.json")
    with pytest.raises(ModelFileError, match=f"parts nest deeper than {MAX_PART_DEPTH} files"):
        load_model(chain[0])
    assert load_model(chain[1]).model.outputs == ["inner." * MAX_PART_DEPTH + "omega_L"]


def test_a_composing_file_adds_its_own_sensors_on_the_parts_nodes(tmp_path):
    for file in PARTS.values():
        shutil.copy(DRIVE / file, tmp_path / file)
    drive = json.loads((DRIVE / "drive.json").read_text())
    drive["nodes"] = [{"id": "F_belt", "kind": "De"}]
    drive["links"] = [{"source": "belt.0_b", "target": "F_belt"}]
    drive["graph"]["ports"] = {"load": "load.shaft", "hub": "belt.1_s"}
    (tmp_path / "drive.json").write_text(json.dumps(drive))
    model = load_model(tmp_path / "drive.json").model
    assert model.outputs == ["motor.i", "motor.omega", "load.omega_L", "F_belt"]
    assert model.ports == {"load": "load.1_L", "hub": "belt.1_s"}
    drive["graph"]["ports"] = {"load": "load.axle"}
    (tmp_path / "drive.json").write_text(json.dumps(drive))
    with pytest.raises(ModelFileError, match=r"graph.ports\['load'\]: 'load.axle' is neither a node nor a port"):
        load_model(tmp_path / "drive.json")
