"""The wandering-offset likelihood against the exact Gaussian density of the whole record.

Under ``u_j = b_j + e_j`` with ``b`` a random walk of variance ``lam`` per step started from its
steady-state spread, the gaps are jointly Gaussian with covariance ``I + p 1 1^T + lam min(i, j)``
(indices from 0): the sum of the innovations' log-densities must equal that density, the smoothing
in blocks must equal the step-by-step Kalman filter, and the resample-move filter's evidence for a
line seen through such an offset must equal the closed-form generalized-least-squares integral.
"""

import math

import numpy as np
import pytest
import sympy as sp
from scipy.stats import multivariate_normal

from bondgraph.library import TORSION_BAR, torsion_bar_monitorable
from diagnosis import derive_arrs
from diagnosis.records import add_noise, as_record
from prognosis.degradation import LinearDegradation
from prognosis.hypotheses import integral_increments
from prognosis.likelihood import ResidualNoise, integral_walk
from prognosis.resample_move import ResampleMoveFilter
from prognosis.wander import BLOCK, innovations, steady_state
from bondgraph.scenarios import TORSION_DT, torsion_bar_record


def walk_covariance(steps: int, lam: float, p: float) -> np.ndarray:
    """Cov of the gaps: white unit noise, the offset's start spread p, its walk lam per step."""
    i = np.arange(steps)
    return np.eye(steps) + p + lam * np.minimum.outer(i, i)


def kalman(u: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """Innovations and their variances by the textbook recursions, the prior at its steady state."""
    gain, spread = steady_state(np.array(lam))
    p = float(spread) - 1.0
    level, v, s = 0.0, [], []
    for value in u:
        s.append(p + 1.0)
        v.append(value - level)
        k = p / (p + 1.0)
        level += k * v[-1]
        p = p * (1 - k) + lam
    return np.array(v), np.array(s)


@pytest.mark.parametrize("lam", [0.0, 1e-4, 0.03, 1.0])
def test_innovations_give_the_exact_density_of_the_record(lam):
    steps = 3 * BLOCK + 7   # blocks and a remainder
    rng = np.random.default_rng(int(lam * 1e4) + 1)
    u = rng.standard_normal(steps) + np.cumsum(rng.normal(0, math.sqrt(lam), steps))
    gain, spread = steady_state(np.array(lam))
    v, _ = innovations(u[None, :, None], np.ones((1, steps, 1), bool), gain, np.zeros((1, 1)))
    ours = float(np.sum(-0.5 * (np.log(2 * np.pi * spread) + np.square(v[0, :, 0]) / spread)))
    exact = multivariate_normal(np.zeros(steps), walk_covariance(steps, lam, float(spread) - 1.0)).logpdf(u)
    assert ours == pytest.approx(exact, rel=1e-9, abs=1e-8)
    reference, variances = kalman(u, lam)
    assert np.allclose(v[0, :, 0], reference, rtol=0, atol=1e-10)
    assert np.allclose(variances, spread, rtol=1e-12)   # the gain is constant from the first step


def test_per_particle_gains_and_unmeasured_steps_follow_the_recursion():
    rng = np.random.default_rng(5)
    shape = (2, 6, 150, 3)
    u = rng.standard_normal(shape)
    measured = rng.random(shape) > 0.1
    gain = steady_state(10 ** rng.uniform(-6, 0, shape[:2]))[0][..., None]
    start = rng.normal(size=(2, 6, 3))
    for mask in (np.ones(shape, bool), measured):
        v, end = innovations(u, mask, gain, start)
        level, expected = start.copy(), np.zeros(shape)
        for j in range(shape[2]):
            expected[..., j, :] = np.where(mask[..., j, :], u[..., j, :] - level, 0.0)
            level = level + gain * expected[..., j, :]
        assert np.allclose(v, expected, atol=1e-10) and np.allclose(end, level, atol=1e-10)


DT, STEPS, NOISE = 0.5, 60, 0.05
BOX = ((0.0, 3.0), (-1.0, 1.0))


def offset_line(lam: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    offset = np.cumsum(rng.normal(0.0, NOISE * math.sqrt(lam), STEPS))
    return 1.0 + 0.2 * DT * np.arange(STEPS) + offset + rng.normal(0.0, NOISE, STEPS)


def test_the_evidence_of_a_line_under_a_known_wander_is_the_closed_form_integral():
    lam = 0.02
    y = offset_line(lam, seed=2)
    noise = ResidualNoise(covariance=[[NOISE**2]], walk=[lam * NOISE**2])
    f = ResampleMoveFilter(LinearDegradation(), lambda theta, points: theta, noise=noise, dt=DT, n_particles=600,
                           discrepancy=None, seed=4)
    f.initialize(BOX[0], gamma_bounds=BOX[1], assets=1)
    for value in y:
        f.step(value)
    # generalized least squares under the gaps' whole covariance, integrated over the flat prior
    x = np.column_stack([np.ones(STEPS), DT * np.arange(STEPS)])
    sigma = NOISE**2 * walk_covariance(STEPS, lam, float(steady_state(np.array(lam))[1]) - 1.0)
    inverse = np.linalg.inv(sigma)
    covariance = np.linalg.inv(x.T @ inverse @ x)
    mean = covariance @ x.T @ inverse @ y
    gap = y - x @ mean
    volume = (BOX[0][1] - BOX[0][0]) * (BOX[1][1] - BOX[1][0])
    log_z = (-0.5 * gap @ inverse @ gap - 0.5 * np.linalg.slogdet(2 * np.pi * sigma)[1]
             + 0.5 * np.linalg.slogdet(2 * np.pi * covariance)[1] - math.log(volume))
    w, gamma = f.weights[0], f.gamma[0, :, 0]
    gamma_mean = float(np.sum(w * gamma))
    gamma_sd = float(np.sqrt(np.sum(w * np.square(gamma - gamma_mean))))
    assert f.log_evidence[0] == pytest.approx(log_z, abs=0.3)
    assert gamma_mean == pytest.approx(mean[1], abs=0.25 * math.sqrt(covariance[1, 1]))
    assert gamma_sd == pytest.approx(math.sqrt(covariance[1, 1]), rel=0.15)


def test_an_integral_of_white_noise_walks_as_the_physics_says():
    """The walk read from a healthy stretch's increments: s^2 h Delta per step, the smooth part cancelled."""
    sd, h, every = 0.02, 1e-3, 50   # a sensor at 1 kHz, a filter step of 50 samples
    estimates = []
    for seed in range(12):
        rng = np.random.default_rng(seed)
        t = np.arange(0.0, 10.0, h)
        integrand = 2.0 + np.sin(0.7 * t) + np.where(t > 4.0, 0.5, 0.0) + rng.normal(0.0, sd, t.size)
        integral = np.cumsum(integrand) * h
        estimates.append(integral_walk(np.diff(integral[::every])))
    expected = sd**2 * h * every * h
    assert np.mean(estimates) == pytest.approx(expected, rel=0.1)
    assert max(estimates) < 1.6 * expected and min(estimates) > 0.5 * expected
    assert integral_walk(np.diff((2.0 + np.sin(0.7 * np.arange(0.0, 10.0, h)))[::every])) < 1e-3 * expected


def test_the_walk_read_from_a_torsion_bar_record_is_what_its_sensor_noise_integrates_to():
    """Both ARRs integrate the speeds' gap ``omega_m / k_belt - omega_Ld`` (the shaft's twist): with
    noise of sd s on each speed sampled every h, the integral walks by ``s sqrt(1 + 1/k_belt^2)
    sqrt(h Delta)`` per filter step Delta, times each ARR's gain on it (k_s in the load ARR); written
    without integrals (differentiated), they do not walk."""
    nominal = TORSION_BAR["b_Md"][0]
    record = torsion_bar_record(40.0, {"b_Md": lambda t: nominal})
    sd, every = 0.002, 10
    columns = {k: record[k] for k in ("t", "omega_m", "omega_Ld", "tau_m")}
    noisy = add_noise(as_record(columns), {"omega_m": sd, "omega_Ld": sd}, seed=3)
    k_s, k_belt = TORSION_BAR["k_s"][0], TORSION_BAR["k_belt"][0]
    twist = sd * math.sqrt(1 + 1 / k_belt**2) * math.sqrt(TORSION_DT * every * TORSION_DT)
    for form in ("keep", "avoid"):
        for arr in derive_arrs(torsion_bar_monitorable(), complete=False, integrals=form):
            evaluation = arr.evaluate(noisy)
            steps = np.flatnonzero(np.asarray(evaluation.t) > 1.0)[::every]
            walk = math.sqrt(integral_walk(integral_increments(arr, evaluation.points, steps)))
            gains = [float(sp.diff(arr.compiled.nominal, s)) for s in arr.compiled.integrals]
            if form == "avoid":
                assert not gains and walk == 0.0, arr.name
            else:
                assert len(gains) == 1 and walk == pytest.approx(abs(gains[0]) * twist, rel=0.15), arr.name
                assert arr.name != "ARR_1_2" or gains[0] == pytest.approx(k_s)
