"""Tutorial 2: robust fault detection with interval ARRs (docs/tutorial/2-diagnosis.md), as a script.

Run it with `python docs/tutorial/scripts/2_diagnosis.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% ARRs from the bond graph
from bondgraph.library import dc_motor
from diagnosis import derive_arrs

motor = dc_motor()
arrs = derive_arrs(motor)
print([(arr.name, arr.junction) for arr in arrs])
print(arrs[0])
print(arrs[1])

# %% ARRs from the bond graph
arr = arrs[1]
print(arr.signals)                      # the columns a record must have (besides t)
print(sorted(arr.parameters))           # the parameters its nominal part depends on
print(arr.uncertainties)

# %% Nominal and uncertain parts
import sympy as sp

from bondgraph import signal_function
from diagnosis import delta

t = sp.Symbol("t")
i, omega = signal_function("i"), signal_function("omega")
k_m, J, b = sp.symbols("k_m J b")
true_balance = (k_m * (1 + delta("k_m")) * i - J * (1 + delta("J")) * sp.Derivative(omega, t)
                - b * (1 + delta("b")) * omega)
print(sp.expand(arr.nominal + arr.uncertain - true_balance))
print(arr.terms["b"])                   # the BG-LFT uncertain effort of R:b, w_b = -delta_b * b * omega

# %% Thresholds
from diagnosis import Interval

band = -1e-4 * 285.3 * Interval(0.0, 0.2) + 0.0389 * 0.733 * Interval(-0.02, 0.02)
print(round(band.lo, 5), round(band.hi, 5))

# %% Thresholds
import numpy as np

from bondgraph import simulate

healthy_run = simulate(motor, (0.0, 1.0), {"U": 12.0}, t_eval=np.linspace(0.0, 1.0, 1001))
steady = arr.evaluate(healthy_run.record())
print(round(float(steady.lower[-1]), 5), round(float(steady.upper[-1]), 5), round(float(steady.bglft[-1]), 5))
print(abs(float(steady.residual[-1])) < 1e-8)

# %% Fault signatures
from diagnosis import signature_matrix

signatures = signature_matrix(arrs)
print(signatures)
print(signatures.row("b"))

# %% Fault signatures
print(signature_matrix(arrs, sensor_faults=False))

# %% Fault signatures
from diagnosis import unreached

print(("k_m", "sensor i") in unreached(motor, arrs)["isolate"])
more = derive_arrs(motor, max_order=2)
print([(relation.name, relation.derivatives) for relation in more[2:]])
print(signature_matrix(more).row("k_m"))
print(unreached(motor, more))

# %% A faulty record
from diagnosis import add_noise, as_record


def friction(time):
    return np.where(time < 1.0, 1e-4, 3e-4)


t = np.linspace(0.0, 2.0, 2001)
bench = simulate(motor, (0.0, 2.0), {"U": 12.0}, parameters={"b": friction}, t_eval=t, max_step=1e-3)
record = add_noise(as_record(bench.record(), name="bench"), {"i": 0.01, "omega": 0.5}, seed=1)
print(record)

# %% A faulty record
from diagnosis.records import RecordError

try:
    arr.evaluate({"t": [0.0, 0.001, 0.002], "i": [0.7, 0.7, 0.7]})
except RecordError as error:
    print(error)

# %% Detection
bare = arr.evaluate(record)
print(int(bare.violation[t < 1.0].sum()), bare.detection_time)

# %% Detection
from diagnosis import noise_margin

healthy = t < 0.9
calibration = {"t": t[healthy], "i": record["i"][healthy], "omega": record["omega"][healthy]}
margin = noise_margin(arr, calibration, k=4)
print(round(margin, 4))
result = arr.evaluate(record, margin=margin, persistence=5)
print(result.detection_time, result.false_alarms(before=1.0))

# %% The derivative window
for window in (11, 21, 51):
    m = noise_margin(arr, calibration, k=4, window=window)
    run = arr.evaluate(record, margin=m, persistence=5, window=window)
    print(f"window {window}: margin {m:.4f}, alarm at {run.detection_time} s, "
          f"{run.false_alarms(before=1.0)} alarm(s) before the fault")

# %% Both relations: which fault?
options = {"persistence": 5, "window": 21}
evaluations = []
for relation in arrs:
    nominal = {"t": t[healthy], **{s: record[s][healthy] for s in relation.signals}}
    m = noise_margin(relation, nominal, k=4, window=21)
    evaluations.append(relation.evaluate(record, margin=m, **options))
print([(e.name, e.detection_time) for e in evaluations])
observed = {e.name: int(e.detection_time is not None) for e in evaluations}
print([p for p in signatures.rows if signatures.row(p) == observed])

# %% What an evaluation holds
result = evaluations[1]
k = int(np.searchsorted(t, 1.5))
print(float(t[k]), round(float(-result.residual[k]), 3), round(float(result.lower[k] - result.margin), 3))
print(result.alarm[k])

# %% What an evaluation holds
import tempfile
from pathlib import Path

from bgphm.plotting import plot_evaluation, pyplot, save_figure

workdir = tempfile.TemporaryDirectory()           # scratch space for the files below
tmp = Path(workdir.name)
plt = pyplot("Agg")                               # files only, no window
ax = plot_evaluation(result, title="ARR_1_m: friction tripled at t = 1 s")
print(save_figure(ax.figure, tmp / "residual.png").name)

# %% Recorded data from a file
from diagnosis.csv_reading import read_csv

path = tmp / "bench.csv"
columns = np.column_stack([record.t, record["U"], record["i"], record["omega"]])
np.savetxt(path, columns, delimiter=",", header="t,U,i,omega", comments="")
from_file = read_csv(path)
print(from_file.signals)
print(arr.evaluate(from_file, margin=result.margin, **options).detection_time)
workdir.cleanup()
