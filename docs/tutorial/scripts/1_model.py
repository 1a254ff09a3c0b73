"""Tutorial 1: a bond graph model (docs/tutorial/1-model.md), as a script.

Run it with `python docs/tutorial/scripts/1_model.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% Declaring the elements
from bondgraph import BondGraph

bg = BondGraph(name="DC motor")
bg.add("U", "Se")                          # effort source; its input signal is "U"
bg.add("1_e", "1")                         # electrical 1-junction: common current
bg.add("R_a", "R", value=1.23, uncertainty=(-0.05, 0.05))
bg.add("L_a", "I", value=1.34e-3, uncertainty=(-0.05, 0.05))
bg.add("GY", "GY", param="k_m", value=3.89e-2, uncertainty=(-0.02, 0.02))
bg.add("1_m", "1")                         # mechanical 1-junction: common speed
bg.add("J", "I", value=1e-4, uncertainty=(-0.1, 0.1))
bg.add("b", "R", value=1e-4, uncertainty=(0.0, 0.2))
bg.add("i", "Df")                          # flow sensors; their signals are "i" and "omega"
print(bg.add("omega", "Df"))               # add returns the element's name

# %% Bonds
for tail, head in [("U", "1_e"), ("1_e", "R_a"), ("1_e", "L_a"), ("1_e", "GY"), ("GY", "1_m"),
                   ("1_m", "J"), ("1_m", "b"), ("1_e", "i"), ("1_m", "omega")]:
    bg.bond(tail, head)
print(bg)

# %% Bonds
for bond in bg.bonds:
    if not bond.is_signal:
        print(bond.label, bond.tail, "->", bond.head)

# %% What the model knows
print(bg.parameters)
print(bg.uncertainties)
print(bg.inputs, bg.outputs)

# %% What the model knows
from bondgraph.library import dc_motor

print(dc_motor().parameters == bg.parameters and dc_motor().uncertainties == bg.uncertainties)

# %% What the model knows
from bondgraph.errors import ModelError

try:
    bg.add("R_x", "R", value=1.0, uncertainty=(0.1, 0.2))
except ModelError as error:
    print(error)
try:
    bg.bond("1_m", "brake")
except ModelError as error:
    print(error)

# %% The same model with networkx
import networkx as nx

G = nx.DiGraph()
for name, data in bg.graph.nodes(data=True):
    G.add_node(name, **data)
G.add_edges_from(bg.graph.edges)
print(G.nodes["b"])
print(str(BondGraph(G, name="from networkx").state_equations()) == str(bg.state_equations()))

# %% Causality
causality = bg.assign_causality("integral")
print(causality.storage)
print(causality.is_valid)
print(causality.summary())

# %% Causality
print(causality.effort_from[("1_e", "GY")], causality.stroke(("1_e", "GY")))
print(causality.effort_from[("1_m", "J")])

# %% Causality
diagnosis = bg.assign_causality("derivative")
print(diagnosis.storage, diagnosis.dualized)

# %% State equations
equations = bg.state_equations()
print(equations)
print(equations.states, equations.inputs)

# %% State equations
physical = equations.coenergy_states({"L_a": "i", "J": "omega"})
for state, rate in zip(physical.states, physical.rhs):
    print(f"d{state}/dt = {rate}")

# %% State equations
import sympy as sp

print(sp.diff(physical.rhs[1], sp.Symbol("b")))

# %% State equations
print(len(bg.equations()))
print(bg.equations()[:3])

# %% Simulation
import numpy as np

from bondgraph import simulate

t = np.linspace(0.0, 1.0, 11)
run = simulate(bg, (0.0, 1.0), {"U": 12.0}, t_eval=t)
print(run["omega"].round(1).tolist())
print(run["i"].round(3).tolist())

# %% Simulation
print(round(0.0389 * 12.0 / (0.0389**2 + 1.23 * 1e-4), 1))

# %% Simulation
print(sorted(run.signals), sorted(run.states))
torque = run.efforts[5]                    # bond 5: GY -> 1_m, the motor torque
print(np.allclose(torque, 0.0389 * run["i"]))
print(sorted(run.record()))                # what a data file would hold

# %% Inputs, parameters and initial state
later = simulate(bg, (0.0, 1.0), {"U": lambda t: 12.0 * (t >= 0.2)}, t_eval=t, max_step=1e-3)
print(later["omega"].round(1).tolist()[:5])
worn = simulate(bg, (0.0, 1.0), {"U": 12.0}, parameters={"b": 3e-4}, t_eval=t)
print(round(float(worn["omega"][-1]), 1))
spinning = simulate(bg, (0.0, 1.0), {"U": 0.0}, x0={"J": 1e-4 * 100.0}, t_eval=t)
print(spinning["omega"].round(1).tolist()[:4])

# %% A speed loop
from bondgraph import PIController

loop = PIController("omega", setpoint=200.0, kp=0.05, ki=1.0, limits=(-12.0, 12.0))
regulated = simulate(bg, (0.0, 1.0), {"U": loop}, t_eval=np.linspace(0.0, 1.0, 11))
print(regulated["omega"].round(1).tolist())
print(round(float(regulated["U"][-1]), 2))      # the voltage the loop settles on

# %% Drawing
import tempfile
from pathlib import Path

from bondgraph.drawing import to_svg, to_tikz

workdir = tempfile.TemporaryDirectory()            # scratch space for the files below
tmp = Path(workdir.name)
svg = to_svg(bg)                                   # integral causality by default
print(svg.startswith("<svg") and svg.count('class="bond"'))
(tmp / "motor.svg").write_text(svg)
(tmp / "motor-diagnosis.svg").write_text(to_svg(bg, "derivative"))
print(to_tikz(bg).splitlines()[0])

# %% Nonlinear elements
fan = dc_motor()
fan.graph.nodes["b"].update(law="e - b*f - c_d*f*Abs(f)", params={"c_d": 1e-6})
print(fan.state_equations().rhs[1])
print(round(float(simulate(fan, (0.0, 1.0), {"U": 12.0})["omega"][-1]), 1))

# %% Model files
import json

from bondgraph.io import load_model, to_json

(tmp / "motor.json").write_text(to_json(bg, inputs={"U": 12.0}, t_end=1.0))
document = json.loads((tmp / "motor.json").read_text())
print(document["graph"])
print(document["nodes"][4])
print(document["links"][0])

# %% Model files
spec = load_model(tmp / "motor.json")
print(spec.model.parameters == bg.parameters, spec.inputs, spec.t_end)
replay = simulate(spec.model, (0.0, spec.t_end), spec.inputs, t_eval=t)
print(np.allclose(replay["omega"], run["omega"]))
print(load_model("dc-motor").model.outputs)        # the built-in examples load by name
workdir.cleanup()
