"""9. BondGraphTools files (docs/tutorial/9-bondgraphtools.md), as a script.

Run it with `python docs/tutorial/scripts/9_bondgraphtools.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% A motor saved by BondGraphTools
from pathlib import Path

Path("motor.bg").write_text("""\
version: 0.1
root: motor
models:
  /:
    components:
    - U    base/Se
    - elec base/1
    - R_a  base/R   r=1.23
    - L_a  base/I   L=0.00134
    - k_m  base/GY  R=0.0389
    - mech base/1
    - J    base/I   L=0.0001
    - b    base/R   r=0.0001
    netlist:
    - U elec.non_inverting
    - elec.inverting R_a
    - elec.inverting L_a
    - elec.inverting k_m.1
    - k_m.0 mech.non_inverting
    - mech.inverting J
    - mech.inverting b
""")

# %% Reading it
from bondgraph import read_bgt

bg = read_bgt("motor.bg")
print(bg)
print(bg.parameters)

# %% Reading it
print(bg.state_equations())

# %% ARRs after adding sensors
from diagnosis import derive_arrs, signature_matrix

bg.add("i", "Df")
bg.bond("elec", "i")
bg.add("omega", "Df")
bg.bond("mech", "omega")
arrs = derive_arrs(bg)
for arr in arrs:
    print(arr)
print(signature_matrix(arrs))

# %% Writing one
from bondgraph import write_bgt

text = write_bgt(bg)
print("\n".join(line for line in text.splitlines() if "SS" in line or "k_m" in line))
print(read_bgt("motor.bg", text=text).outputs)

# %% What is not read
from bondgraph import ModelError

try:
    read_bgt("cell.bg", text="version: 0.1\nroot: cell\nmodels:\n  /:\n    components:\n    - A BioChem/Ce\n")
except ModelError as error:
    print(error)
