"""ProgPy's own particle filter and Monte Carlo predictor on the DC motor of tutorial 3 exported by to_progpy:
its friction grows as ``b_n exp(0.8 (t - 1))`` and fails at 20 ``b_n``; ``i`` and ``omega`` are read with noise.
One run, shared by tests/interop/test_progpy.py (one seed) and benchmarks/bench_interop.py (ten)."""

import numpy as np

from bondgraph import Degradation, simulate
from bondgraph.library import dc_motor
from prognosis import to_progpy

B_NOMINAL, B_FAIL = 1e-4, 2e-3
LAW = Degradation("exponential", 0.8, onset=1.0)
T = np.linspace(0.0, 3.5, 3501)
START = 1700   # the alarm of tutorial 3, t = 1.7 s


def progpy_filter_run(noise_seed: int, filter_seed: int, particles: int = 400) -> dict:
    """The filter's mean friction and rate at t = 3.5 s, the predictor's median RUL, and the truth of each."""
    from progpy.predictors import MonteCarlo
    from progpy.state_estimators import ParticleFilter
    from progpy.uncertain_data import UnweightedSamples

    bg, n = dc_motor(), particles
    bench = simulate(bg, (0.0, T[-1]), {"U": 12.0}, parameters={"b": LAW.truth(B_NOMINAL)}, t_eval=T)
    rng = np.random.default_rng(noise_seed)
    measured = {"i": bench["i"] + rng.normal(0.0, 0.01, T.size), "omega": bench["omega"] + rng.normal(0.0, 0.5, T.size)}
    model = to_progpy(bg, degradation={"b": "exponential"}, failures={"b": B_FAIL},
                      process_noise={"p_L_a": 1e-3, "p_J": 1e-2, "b": 2e-4, "b_rate": 2.0})
    np.random.seed(filter_seed)   # ProgPy and filterpy draw from numpy's global generator
    x0 = UnweightedSamples({"p_L_a": np.full(n, 1.34e-3 * measured["i"][START]),
                            "p_J": np.full(n, 1e-4 * measured["omega"][START]),
                            "b": np.random.uniform(1.0, 4.0, n) * B_NOMINAL, "b_rate": np.random.uniform(0.0, 2.0, n)},
                           _type=model.StateContainer)
    pf = ParticleFilter(model, x0, num_particles=n, t0=T[START], dt=1e-3, measurement_noise={"i": 0.02, "omega": 1.0})
    for k in range(START + 10, T.size, 10):
        pf.estimate(T[k], {"U": 12.0}, {"i": measured["i"][k], "omega": measured["omega"][k]})
    predictor = to_progpy(bg, degradation={"b": "exponential"}, failures={"b": B_FAIL})   # the rate held
    prediction = MonteCarlo(predictor).predict(pf.x, lambda time, x=None: predictor.InputContainer({"U": 12.0}),
                                               dt=2.5e-3, n_samples=20, t0=T[-1], events=["b failure"],
                                               save_freq=10.0)
    eol = LAW.onset + np.log(B_FAIL / B_NOMINAL) / LAW.rate
    return {"b": float(np.mean(pf.particles["b"])), "b_true": float(LAW.truth(B_NOMINAL)(T[-1])),
            "rate": float(np.mean(pf.particles["b_rate"])), "rate_true": LAW.rate,
            "rul": float(np.median(prediction.time_of_event.key("b failure")) - T[-1]), "rul_true": eol - T[-1]}
