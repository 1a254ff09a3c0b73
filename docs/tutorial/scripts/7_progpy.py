"""7. NASA's ProgPy on our models (docs/tutorial/7-progpy.md), as a script.

Run it with `python docs/tutorial/scripts/7_progpy.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% A wearing motor as a ProgPy model
import numpy as np

from bondgraph import Degradation, simulate
from bondgraph.library import dc_motor
from prognosis import to_progpy

motor = dc_motor()
b_n, b_fail = 1e-4, 2e-3
wear = Degradation("exponential", 0.8, onset=1.0)       # b = b_n exp(0.8 (t - 1)) from t = 1 s
model = to_progpy(motor, degradation={"b": wear}, failures={"b": b_fail})
print(model.states)
print(model.inputs, model.outputs, model.events)

# %% Simulate to the threshold
def full_voltage(t, x=None):
    return model.InputContainer({"U": 12.0})


run = model.simulate_to_threshold(full_voltage, dt=1e-3, save_freq=0.01)
eol = wear.onset + np.log(b_fail / b_n) / wear.rate
print(round(run.times[-1], 3), round(float(eol), 3))
times = np.array(run.times)
ours = simulate(motor, (0.0, times[-1]), {"U": 12.0}, parameters={"b": wear.truth(b_n)}, t_eval=times)
omega = np.array([z["omega"] for z in run.outputs])
print(bool(np.max(np.abs(omega - ours["omega"])) < 1e-4 * np.ptp(ours["omega"])))

# %% ProgPy's particle filter
from progpy.state_estimators import ParticleFilter
from progpy.uncertain_data import UnweightedSamples

t = np.linspace(0.0, 3.5, 3501)
bench = simulate(motor, (0.0, 3.5), {"U": 12.0}, parameters={"b": wear.truth(b_n)}, t_eval=t)
rng = np.random.default_rng(0)
i_meas = bench["i"] + rng.normal(0.0, 0.01, t.size)
omega_meas = bench["omega"] + rng.normal(0.0, 0.5, t.size)

tracker = to_progpy(motor, degradation={"b": "exponential"}, failures={"b": b_fail},
                    process_noise={"p_L_a": 1e-3, "p_J": 1e-2, "b": 2e-4, "b_rate": 2.0})
np.random.seed(1)                       # ProgPy draws from numpy's global generator
n, start = 400, 1700                    # from the alarm of tutorial 2, t = 1.7 s
x0 = UnweightedSamples({"p_L_a": np.full(n, 1.34e-3 * i_meas[start]), "p_J": np.full(n, 1e-4 * omega_meas[start]),
                        "b": np.random.uniform(1.0, 4.0, n) * b_n, "b_rate": np.random.uniform(0.0, 2.0, n)},
                       _type=tracker.StateContainer)
pf = ParticleFilter(tracker, x0, num_particles=n, t0=t[start], dt=1e-3, measurement_noise={"i": 0.02, "omega": 1.0})
for k in range(start + 10, t.size, 10):
    pf.estimate(t[k], {"U": 12.0}, {"i": i_meas[k], "omega": omega_meas[k]})
b, rate = pf.particles["b"], pf.particles["b_rate"]
print(round(float(np.mean(b) / b_n), 2), round(float(wear.truth(b_n)(3.5) / b_n), 2), round(float(np.mean(rate)), 3))

# %% ProgPy's Monte Carlo prediction
from progpy.predictors import MonteCarlo

predictor = to_progpy(motor, degradation={"b": "exponential"}, failures={"b": b_fail})   # rates held
prediction = MonteCarlo(predictor).predict(pf.x, lambda time, x=None: predictor.InputContainer({"U": 12.0}),
                                           dt=2.5e-3, n_samples=20, t0=3.5, events=["b failure"], save_freq=10.0)
toe = prediction.time_of_event
print(round(float(np.median(toe.key("b failure"))), 3), round(float(eol), 3))

# %% ProgPy's metrics on our RUL
from progpy.metrics import prob_success

from prognosis import ExponentialDegradation, predict_rul, to_progpy_samples

from dataclasses import replace

rul = predict_rul(ExponentialDegradation(), b[None], rate[None, :, None], np.full((1, n), 1.0 / n), dt=0.01,
                  theta_fail=b_fail, gamma_std=0.0, horizon=20.0, rng=np.random.default_rng(2))
rul = replace(rul, origin=3.5)                    # times of event are t = 3.5 s + RUL
ours_as_progpy = to_progpy_samples(rul, "b failure")
metrics = ours_as_progpy.metrics()["b failure"]
their_median, their_mean = metrics["percentiles"]["50"], metrics["mean"]
print(round(float(rul.median[0]) + 3.5, 3), round(float(their_median), 3), round(float(their_mean), 3))
print(prob_success(ours_as_progpy, 4.7), round(1.0 - float(rul.probability_before(4.7 - 3.5)[0]), 4))
