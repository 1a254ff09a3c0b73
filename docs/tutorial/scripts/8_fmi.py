"""8. FMI: the motor as an FMU, and an FMU as a plant (docs/tutorial/8-fmi.md), as a script.

Run it with `python docs/tutorial/scripts/8_fmi.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% The DC motor as an FMU
import tempfile
import zipfile
from pathlib import Path

from bondgraph import to_fmu
from bondgraph.library import dc_motor

folder = tempfile.TemporaryDirectory()
bg = dc_motor()
path = to_fmu(bg, Path(folder.name) / "dc_motor.fmu", inputs={"U": 12.0}, step=1e-3)
for name in sorted(zipfile.ZipFile(path).namelist()):
    print(name)

# %% The DC motor as an FMU
import fmpy

description = fmpy.read_model_description(str(path), validate=True)
print(description.fmiVersion, description.coSimulation.modelIdentifier)
for variable in description.modelVariables:
    print(f"{variable.name:6} {variable.causality:9} start={variable.start}")

# %% fmpy runs it; `simulate` agrees
import numpy as np

from bondgraph import simulate

result = fmpy.simulate_fmu(str(path), stop_time=0.5, output_interval=1e-3, start_values={"b": 2e-4})
ours = simulate(bg, (0.0, 0.5), {"U": 12.0}, parameters={"b": 2e-4}, t_eval=result["time"], rtol=1e-12,
                atol=1e-15)
print(f"speed at 0.5 s: {result['omega'][-1]:.2f} rad/s (FMU), {ours['omega'][-1]:.2f} rad/s (simulate)")
for name in ("i", "omega"):
    gap = np.max(np.abs(result[name] - ours[name])) / np.ptp(ours[name])
    print(f"{name}: within 1e-8 of its range: {bool(gap < 1e-8)}")

# %% The FMU as the plant of an EKF
from bondgraph import FmuPlant
from prognosis.statespace import ExtendedKalmanFilter, discretize

model = discretize(bg.state_equations(), dt=1e-3, method="rk4", augment=["R_a"])
noise = np.array([0.05, 0.5])   # current (A) and speed (rad/s) sensors
rng = np.random.default_rng(1)
ekf = ExtendedKalmanFilter(model, [0.0, 0.0, 1.23], np.diag([1e-5, 1e-4, 0.1]), np.diag([1e-12, 1e-12, 1e-10]),
                           np.diag(noise**2))
with FmuPlant(path, parameters={"R_a": 1.5}) as plant:
    for k in range(400):
        plant_output = plant.step(1e-3, {"U": 12.0})
        reading = np.array([plant_output["i"], plant_output["omega"]]) + noise * rng.standard_normal(2)
        ekf.step(reading, {"U": 12.0})
    truth = np.array([plant_output["p_L_a"], plant_output["p_J"]])
print(f"R_a estimate: {ekf.mean[2]:.2f} ohm (plant: 1.5 ohm)")
print("state estimates within 1 % of the plant's:", bool(np.all(np.abs(ekf.mean[:2] - truth) < 0.01 * truth)))
folder.cleanup()
