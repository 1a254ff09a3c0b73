"""6. The Fault Diagnosis Toolbox on our models (docs/tutorial/6-fault-diagnosis-toolbox.md), as a script.

Run it with `python docs/tutorial/scripts/6_fault_diagnosis_toolbox.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% A bond graph as an FDT model
from bondgraph.library import three_tank
from diagnosis import structural_model, to_fdt

bg = three_tank()
model = to_fdt(bg)
print(model.name, "-", model.ne(), "relations,", len(model.x), "unknowns")
print("known signals:", model.z)
print("faults:", model.f)

# %% The same minimal sets
msos = model.MSO()
ours = structural_model(bg)
n = len(ours.equations)   # FDT appends one differential constraint per state after our equations
theirs = {frozenset(int(i) for i in rows if i < n) for rows in msos}
print(len(msos), "minimal sets in FDT,", len(ours.mso_sets()), "in diagnosis.structural")
print("the same sets:", theirs == set(map(frozenset, ours.mso_sets())))

# %% Isolability, both ways
import numpy as np

isolability = model.IsolabilityAnalysis()
print("faults FDT isolates from every other:", int(np.sum(isolability.sum(axis=1) == 1)), "of", len(model.f))
print("ordered pairs told apart, FDT:", int(np.sum(isolability == 0)))
print("ordered pairs told apart, diagnosis:", sum(len(v) for v in ours.isolability().values()))
