"""5. Calibration: from a datasheet to the machine (docs/tutorial/5-calibration.md), as a script.

Run it with `python docs/tutorial/scripts/5_calibration.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% 5. Calibration: from a datasheet to the machine
import numpy as np
from bondgraph import simulate
from bondgraph.library import dc_motor
from diagnosis import (DetectionSettings, add_noise, as_record, detect, estimate_parameters, identifiability,
                       uncertainty_boxes)

datasheet = dc_motor(R_a=1.5, L_a=1.1e-3, k_m=4.5e-2, J=0.8e-4, b=1.4e-4)   # the catalogue's values
machine = dc_motor()                                                       # the bench's (unknown to us)
print({name: f"{value:.4g}" for name, value in datasheet.parameters.items()})

# %% 5. Calibration: from a datasheet to the machine
def voltage(t):
    """Two steps, then a sine: the electrical and the mechanical dynamics both show."""
    return 12.0 * (t >= 0.05) - 6.0 * (t >= 0.6) + 4.0 * np.sin(9.0 * t) * (t >= 1.0)


def bench_run(seed, **wear):
    """Two seconds at 2 kHz, current and speed sensors with noise; ``wear``: parameters changing in time."""
    t = np.linspace(0.0, 2.0, 4001)
    run = simulate(machine, (0.0, 2.0), {"U": voltage}, t_eval=t, parameters=wear)
    return add_noise(as_record(run.record()), {"i": 0.01, "omega": 0.2}, seed=seed)


training, held_out = bench_run(seed=1), bench_run(seed=2)   # a day of healthy data, and another run to check on
print(len(training), "samples of", list(training.columns))

# %% 5. Calibration: from a datasheet to the machine
found = identifiability(datasheet, [training])
print("identified:", found.identified)
print("only in combination:", found.combinations)

# %% 5. Calibration: from a datasheet to the machine
fit = estimate_parameters(datasheet, [training])
for name in fit.estimated:
    lo, hi = fit.intervals[name]
    print(f"{name:4} datasheet {fit.datasheet[name]:<8.4g} estimate {fit.values[name]:<10.4g} "
          f"95 % [{lo:.4g}, {hi:.4g}]   (bench {machine.parameters[name]:.4g})")

# %% 5. Calibration: from a datasheet to the machine
boxes = uncertainty_boxes(fit)                   # the intervals as multiplicative boxes about the estimates
calibrated = fit.model(datasheet, boxes)         # a new model; the datasheet model is left as it was
for name, (lo, hi) in boxes.items():
    print(f"{name:4} uncertainty ({lo:+.2%}, {hi:+.2%})")

# %% 5. Calibration: from a datasheet to the machine
settings = DetectionSettings(calibrate=0.9)      # margins from the first 0.9 s of the record
for label, model in [("datasheet", datasheet), ("calibrated", calibrated)]:
    result = detect(model, held_out, settings)
    alarms = [e.name for e in result.evaluations if e.detection_time is not None]
    smallest = {p: "blind" if np.isinf(v) else f"{v:.0%}" for p, v in sorted(result.smallest_changes.items())}
    print(f"{label:10} alarms on healthy data: {alarms or 'none'}; smallest detectable change: {smallest}")

# %% 5. Calibration: from a datasheet to the machine
worn = bench_run(seed=3, b=lambda t: 1e-4 * (1.0 + 0.5 * max(t - 1.0, 0.0)))   # friction +50 % per second from 1 s
for label, model in [("datasheet", datasheet), ("calibrated", calibrated)]:
    result = detect(model, worn, settings)
    first = [(e.name, e.detection_time) for e in result.evaluations if e.detection_time is not None]
    print(f"{label:10} alarm: {first or 'none'}; consistent faults: {result.candidates or 'none'}")
