"""Tutorial 3: prognosis, from the residual to the remaining useful life (docs/tutorial/3-prognosis.md), as a script.

Run it with `python docs/tutorial/scripts/3_prognosis.py`.
Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
"""
# each cell imports what it first needs, as the tutorial does:
# ruff: noqa: E402

# %% The wear scenario
import numpy as np

from bondgraph import simulate
from bondgraph.library import dc_motor
from diagnosis import add_noise, as_record, derive_arrs, noise_margin

motor = dc_motor()
b_n, rate, onset, b_fail = 1e-4, 0.8, 1.0, 2e-3


def b_true(t):
    return b_n * np.exp(rate * np.maximum(np.asarray(t, float) - onset, 0.0))


eol = onset + np.log(b_fail / b_n) / rate
print(round(float(eol), 3))
t = np.linspace(0.0, 4.0, 4001)
bench = simulate(motor, (0.0, 4.0), {"U": 12.0}, parameters={"b": b_true}, t_eval=t)
record = add_noise(as_record(bench.record(), name="wearing motor"), {"i": 0.01, "omega": 0.5}, seed=0)
print(round(float(bench["omega"][-1]), 1))          # the motor slows down as the friction grows

# %% Detection first
arr = derive_arrs(motor, complete=False, integrals="keep")[1]                 # ARR_1_m, the one sensitive to b
healthy = t < 0.9
calibration = {"t": t[healthy], "i": record["i"][healthy], "omega": record["omega"][healthy]}
sigma = noise_margin(arr, calibration, k=1, window=21)   # one robust std of r_n
detection = {"margin": 4 * sigma, "persistence": 5, "window": 21}
evaluation = arr.evaluate(record, **detection)
print(evaluation.detection_time, round(float(b_true(evaluation.detection_time) / b_n), 2))

# %% The observation equation
from prognosis import observation_model

observation = observation_model(arr, "b")
print(observation.expression)
print(observation.coefficient, observation.nominal)

# %% The observation equation
samples = np.searchsorted(t, [2.0, 3.0, 3.5])
one_sample = observation.invert(-evaluation.residual[samples], [p[samples] for p in evaluation.points])
print((one_sample / b_n).round(2).tolist(), (b_true(t[samples]) / b_n).round(2).tolist())

# %% The degradation model
from prognosis import ExponentialDegradation, LinearDegradation

print(ExponentialDegradation().step(np.array([1.0]), np.array([[0.8]]), dt=1.0).round(4))
print(LinearDegradation().step(np.array([1.0]), np.array([[0.8]]), dt=1.0))

# %% The particle filter, step by step
from prognosis import ParticleFilter

pf = ParticleFilter(ExponentialDegradation(), observation, n_particles=300, dt=0.01, noise_std=sigma,
                    inflation=4.0, gamma_std=0.05, seed=0)
pf.initialize((b_n, 1.2 * b_n), gamma_bounds=(0.0, 2.0))
print(pf.theta.shape, pf.gamma.shape)

# %% The particle filter, step by step
start = int(np.flatnonzero(evaluation.alarm)[0])
for k in range(start, 3001, 10):             # from the alarm to t = 3 s
    pf.step(-evaluation.residual[k], [p[k:k + 1] for p in evaluation.points])
estimate = pf.estimate()
print(round(float(estimate["theta_mean"][0] / b_n), 2), round(float(b_true(3.0) / b_n), 2))
print(round(float(estimate["gamma_mean"][0, 0]), 2))

# %% The RUL distribution
from prognosis import RULPredictor

predictor = RULPredictor(ExponentialDegradation(), dt=0.01, theta_fail=b_fail, direction="up", horizon=20.0,
                         seed=1)
rul = predictor.predict(pf.theta, pf.gamma, pf.weights, gamma_std=0.0)
print(rul.samples.shape)
print(round(float(rul.median[0]), 2), rul.percentile([5, 95]).round(2).tolist(), round(float(eol) - 3.0, 2))

# %% The health monitor
from prognosis import HealthMonitor, VarianceAdaptation


def make_monitor():
    return HealthMonitor(arr, "b", ExponentialDegradation(), theta_fail=b_fail, direction="up", dt=0.01,
                         n_particles=300, noise_std=sigma, inflation=4.0, gamma_std=0.4,
                         gamma_bounds=(0.0, 2.0),
                         adaptation=VarianceAdaptation(band=(0.0, 2.0), reference=0.02, gain=0.01, floor=1e-3),
                         prediction_walk=0.0, rul_every=10, horizon=20.0, detection=detection, seed=0)


monitor = make_monitor()
result = monitor.run(record)
print(result.detection_time, result.t.size, len(result.rul))

# %% The health monitor
p5, p95 = result.rul_percentiles((5, 95)).T
for j in range(3, len(result.rul), 5):
    k = 10 * j                                  # the filter step of prediction j
    when = result.rul_t[j]
    print(f"t = {when:.2f} s: b = {result.theta['mean'][k] / b_n:4.2f} b_n (true {b_true(when) / b_n:4.2f}), "
          f"rate {result.gamma['mean'][k]:.2f}, RUL {result.rul_median[j]:.2f} s "
          f"[{p5[j]:.2f}, {p95[j]:.2f}] (true {eol - when:.2f})")

# %% The health monitor
first = result.rul[0]
print(round(float(first.censored_weight[0]), 2), first.percentile(95).tolist())
print(round(float(first.mean[0]), 2))                  # mean over the particles that do fail

# %% The health monitor
import tempfile
from pathlib import Path

from bgphm.plotting import plot_estimate, plot_rul, pyplot, save_figure

workdir = tempfile.TemporaryDirectory()          # scratch space for the figure
tmp = Path(workdir.name)
plt = pyplot("Agg")                              # files only, no window
figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
plot_estimate(result, "theta", truth=b_true, ax=left)
plot_rul(result, eol=eol, alpha=0.2, ax=right)
right.set_ylim(0.0, 6.0)                         # the first 95 % percentiles reach the 20 s horizon
print(save_figure(figure, tmp / "prognosis.png").name)
workdir.cleanup()

# %% Metrics
scores = monitor.result.metrics(b_true, lambda time: rate, eol=eol, after=2.5, alpha=0.2, beta=0.5)
print({key: round(value, 2) for key, value in scores.items()})

# %% Metrics
from prognosis import metrics

true_rul = eol - result.rul_t
ra = metrics.relative_accuracy(true_rul, result.rul_mean)
print(round(float(metrics.mean_relative_accuracy(ra[result.rul_t >= 2.5])), 2))
samples = np.array([p.samples[0] for p in result.rul])
weights = np.array([p.weights[0] for p in result.rul])
mass, passed = metrics.alpha_lambda(samples, weights, true_rul, alpha=0.2, beta=0.5)
print(round(float(mass[-1]), 2), passed[-1])

# %% Online, one sample at a time
online = make_monitor()
for k in np.flatnonzero(t <= 2.5):
    latest = online.update({"t": t[k], "i": record["i"][k], "omega": record["omega"][k]})
print(latest.detection_time, float(latest.t[-1]))
print(np.allclose(latest.theta["mean"], result.theta["mean"][:latest.t.size]))
