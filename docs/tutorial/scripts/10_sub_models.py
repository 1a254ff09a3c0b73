"""10. Models from saved sub-models (docs/tutorial/10-sub-models.md), as a script.

Run it with `python docs/tutorial/scripts/10_sub_models.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% Three parts with named ports
import json
import tempfile
from pathlib import Path

from bondgraph import BondGraph, compose, load_model, simulate, to_json

motor = BondGraph(name="DC motor")
motor.add("U", "Se", unit="V")
motor.add("1_e", "1")
motor.add("R_a", "R", value=1.2, uncertainty=(-0.05, 0.05), unit="ohm")
motor.add("L_a", "I", value=0.003, uncertainty=(-0.05, 0.05), unit="H")
motor.add("i", "Df", unit="A")
motor.add("k_m", "GY", value=0.06, uncertainty=(-0.02, 0.02), unit="N*m/A")
motor.add("1_m", "1")
motor.add("J_m", "I", value=2e-4, uncertainty=(-0.02, 0.02), unit="kg*m^2")
motor.add("b_m", "R", value=1e-4, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
motor.add("omega", "Df", unit="rad/s")
for tail, head in [("U", "1_e"), ("1_e", "R_a"), ("1_e", "L_a"), ("1_e", "i"), ("1_e", "k_m"), ("k_m", "1_m"),
                   ("1_m", "J_m"), ("1_m", "b_m"), ("1_m", "omega")]:
    motor.bond(tail, head)
motor.port("shaft", "1_m")
print(motor.ports)

# %% Three parts with named ports
belt = BondGraph(name="belt")
belt.add("1_d", "1")
belt.add("J_d", "I", value=1e-4, uncertainty=(-0.05, 0.05), unit="kg*m^2")
belt.add("r_d", "TF", value=0.02, unit="m")                 # belt speed = r_d * drive pulley speed
belt.add("0_b", "0")                                        # the belt's tension
belt.add("1_s", "1")                                        # its stretching speed
belt.add("c_b", "C", value=1e-5, uncertainty=(-0.1, 0.1), unit="m/N")
belt.add("d_b", "R", value=20.0, uncertainty=(0.0, 0.3), unit="N*s/m")
belt.add("r_l", "TF", value=0.06, modulus="1/r_l", unit="m")  # load pulley speed = belt speed / r_l
belt.add("1_l", "1")
belt.add("J_l", "I", value=4e-4, uncertainty=(-0.05, 0.05), unit="kg*m^2")
for tail, head in [("1_d", "J_d"), ("1_d", "r_d"), ("r_d", "0_b"), ("0_b", "1_s"), ("1_s", "c_b"),
                   ("1_s", "d_b"), ("0_b", "r_l"), ("r_l", "1_l"), ("1_l", "J_l")]:
    belt.bond(tail, head)
belt.port("drive", "1_d")
belt.port("driven", "1_l")

load = BondGraph(name="load")
load.add("1_L", "1")
load.add("J_L", "I", value=0.01, uncertainty=(-0.05, 0.05), unit="kg*m^2")
load.add("b_L", "R", value=0.002, uncertainty=(0.0, 0.3), unit="N*m*s/rad")
load.add("T_L", "Se", unit="N*m")
load.add("omega_L", "Df", unit="rad/s")
for tail, head in [("1_L", "J_L"), ("1_L", "b_L"), ("1_L", "T_L"), ("1_L", "omega_L")]:
    load.bond(tail, head)
load.port("shaft", "1_L")

# %% Three parts with named ports
print(belt.state_equations())

# %% Three parts with named ports
workdir = tempfile.TemporaryDirectory()            # scratch space for the files below
folder = Path(workdir.name)
(folder / "motor.json").write_text(to_json(motor, inputs={"U": 24.0}))
(folder / "belt.json").write_text(to_json(belt))
(folder / "load.json").write_text(to_json(load, inputs={"T_L": 0.05}))
print(json.loads((folder / "belt.json").read_text())["graph"])

# %% Composing in a file
drive_file = folder / "drive.json"
drive_file.write_text(json.dumps({"graph": {
    "name": "belt drive",
    "parts": {"motor": "motor.json", "belt": "belt.json", "load": "load.json"},
    "connections": [["motor.shaft", "belt.drive"], ["belt.driven", "load.shaft"]]}}))
spec = load_model(drive_file)
drive = spec.model
print(drive)
print("inputs:", spec.inputs)
print("sensors:", drive.outputs)
print("states:", [str(x) for x in drive.state_equations().states])

# %% Composing in a file
in_python = compose({"motor": motor, "belt": belt, "load": load},
                    [("motor.shaft", "belt.drive"), ("belt.driven", "load.shaft")])
print("the same bonds:", list(in_python.graph.edges) == list(drive.graph.edges))
print("the same equations:", set(in_python.equations()) == set(drive.equations()))

# %% Diagnosis names elements by their path
from diagnosis import derive_arrs, signature_matrix

arrs = derive_arrs(drive)
signatures = signature_matrix(arrs)
for name in ["motor.R_a", "belt.c_b", "load.b_L", "sensor load.omega_L"]:
    row = signatures.matrix[signatures.rows.index(name)]
    print(f"{name:20s}", [column for column, sees in zip(signatures.columns, row) if sees])

# %% A composed model is a part in turn
drive_with_port = compose({"motor": motor, "belt": belt, "load": load},
                          [("motor.shaft", "belt.drive"), ("belt.driven", "load.shaft")],
                          ports={"output": "load.shaft"}, name="drive")
brake = BondGraph(name="brake")
brake.add("1_b", "1")
brake.add("J_b", "I", value=0.002)
brake.add("b_b", "R", value=0.05)
brake.bond("1_b", "J_b")
brake.bond("1_b", "b_b")
brake.port("disc", "1_b")
plant = compose({"drive": drive_with_port, "brake": brake}, [("drive.output", "brake.disc")], name="plant")
result = simulate(plant, (0.0, 2.0), {"drive.motor.U": 24.0, "drive.load.T_L": 0.05})
print("parameters:", len(plant.parameters), "e.g.", list(plant.parameters)[:3])
print(f"load speed at 2 s: {result['drive.load.omega_L'][-1]:.2f} rad/s")
workdir.cleanup()
