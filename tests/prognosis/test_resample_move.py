"""The resample-move filter against closed forms: a straight line seen through Gaussian noise.

With ``theta_k = theta_0 + gamma k dt`` measured directly, the posterior of ``(theta_0, gamma)`` under
a flat prior is the least-squares Gaussian and the evidence is its closed-form integral: the filter
must find both, keep distinct particles when the noise is tiny, and say so when it cannot.
"""

import math

import numpy as np
import pytest

from prognosis.degradation import ExponentialDegradation, LinearDegradation
from prognosis.errors import PrognosisError
from prognosis.resample_move import ResampleMoveFilter

DT, STEPS = 0.5, 40
THETA0, GAMMA = 1.0, 0.2
BOX = ((0.0, 3.0), (-1.0, 1.0))


def line(noise: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return THETA0 + GAMMA * DT * np.arange(STEPS) + rng.normal(0.0, noise, STEPS)


def run(y: np.ndarray, noise: float, seed: int, particles: int = 400, discrepancy=None) -> ResampleMoveFilter:
    f = ResampleMoveFilter(LinearDegradation(), lambda theta, points: theta, noise=noise, dt=DT,
                           n_particles=particles, discrepancy=discrepancy, seed=seed)
    f.initialize(BOX[0], gamma_bounds=BOX[1], assets=1)
    for value in y:
        f.step(value)
    return f


def least_squares(y: np.ndarray, noise: float, excess: float = 1.0):
    """Posterior mean and covariance of (theta_0, gamma), and log p(y) under the flat prior on BOX,
    the log-likelihood divided by ``excess``."""
    x = np.column_stack([np.ones(y.size), DT * np.arange(y.size)])
    precision = x.T @ x / noise**2
    covariance = np.linalg.inv(precision)
    mean = covariance @ x.T @ y / noise**2
    rss = float(np.sum(np.square(y - x @ mean)))
    volume = (BOX[0][1] - BOX[0][0]) * (BOX[1][1] - BOX[1][0])
    log_z = (-0.5 * rss / noise**2 / excess - 0.5 * y.size * math.log(2 * math.pi * noise**2) / excess
             + 0.5 * math.log(np.linalg.det(2 * math.pi * excess * covariance)) - math.log(volume))
    return mean, excess * covariance, log_z


def gamma_sd(f: ResampleMoveFilter, row: int = 0) -> tuple[float, float]:
    w, gamma = f.weights[row], f.gamma[row, :, 0]
    mean = float(np.sum(w * gamma))
    return mean, float(np.sqrt(np.sum(w * np.square(gamma - mean))))


def test_posterior_and_evidence_match_least_squares():
    noise = 0.05
    y = line(noise, seed=3)
    f = run(y, noise, seed=11)
    mean, covariance, log_z = least_squares(y, noise)
    gamma = f.gamma[0, :, 0]
    w = f.weights[0]
    g_mean = float(np.sum(w * gamma))
    g_std = float(np.sqrt(np.sum(w * np.square(gamma - g_mean))))
    assert abs(g_mean - mean[1]) < 0.25 * math.sqrt(covariance[1, 1])
    assert 0.8 < g_std / math.sqrt(covariance[1, 1]) < 1.25
    assert abs(float(f.log_evidence[0]) - log_z) < 0.5


def test_noise_understated_threefold_is_divided_out_and_the_evidence_follows_the_temperature():
    """Told 0.05 for noise of 0.15, the plain filter is three times too sure; dividing the likelihood
    by the gaps' long-run variance (about 9) gives back the width of the right noise, and the evidence
    is the closed form of the tempered posterior at the final excess (the path telescopes)."""
    told, true = 0.05, 0.15
    y = line(true, seed=21)
    plain, corrected = run(y, told, seed=22), run(y, told, seed=22, discrepancy="each")
    _, right, _ = least_squares(y, true)
    assert gamma_sd(plain)[1] < 0.5 * math.sqrt(right[1, 1])
    assert 4.0 < corrected.excess[0, 0] < 20.0
    assert 0.6 < gamma_sd(corrected)[1] / math.sqrt(right[1, 1]) < 1.6
    mean, covariance, log_z = least_squares(y, told, float(corrected.excess[0, 0]))
    assert abs(gamma_sd(corrected)[0] - mean[1]) < 0.5 * math.sqrt(covariance[1, 1])
    assert 0.75 < gamma_sd(corrected)[1] / math.sqrt(covariance[1, 1]) < 1.3
    assert abs(float(corrected.log_evidence[0]) - log_z) < 1.0


@pytest.mark.slow
def test_shared_rows_take_the_excess_of_the_most_probable_row():
    told = 0.05
    y = np.stack([line(0.05, seed=31), line(0.2, seed=32)])   # row 1's noise is four times what it is told
    f = ResampleMoveFilter(LinearDegradation(), lambda theta, points: theta, noise=told, dt=DT, n_particles=200,
                           discrepancy="shared", seed=33)
    f.initialize(BOX[0], gamma_bounds=BOX[1], assets=2)
    for k in range(STEPS):
        f.step(y[:, k])
    assert f.log_evidence[0] > f.log_evidence[1] and f.excess[0, 0] == f.excess[1, 0] < 3.0
    each = run(y[1], told, seed=33, particles=200, discrepancy="each")
    assert each.excess[0, 0] > 5.0


def test_a_clean_line_keeps_distinct_particles_and_finds_the_rate():
    noise = 1e-6  # six orders of magnitude below the change: the case that collapsed the SIR filter
    y = line(noise, seed=4)
    f = ResampleMoveFilter(LinearDegradation(), lambda theta, points: theta, noise=noise, dt=DT, n_particles=300,
                           seed=5)
    f.initialize(BOX[0], gamma_bounds=BOX[1], assets=1)
    collapsed = [bool(f.step(value).collapsed[0]) for value in y]
    assert not any(collapsed)
    assert np.unique(f.gamma[0, :, 0]).size > 0.3 * f.n
    mean, covariance, _ = least_squares(y, noise)
    w = f.weights[0]
    assert abs(float(np.sum(w * f.gamma[0, :, 0])) - mean[1]) < 3 * math.sqrt(covariance[1, 1])
    assert abs(float(np.sum(w * f.theta[0])) - (THETA0 + GAMMA * DT * (STEPS - 1))) < 1e-5


@pytest.mark.slow
def test_the_90_percent_interval_of_the_rate_covers_at_its_level():
    noise, runs, covered = 0.05, 60, 0
    for seed in range(runs):
        f = run(line(noise, seed=100 + seed), noise, seed=200 + seed, particles=300)
        w, gamma = f.weights[0], f.gamma[0, :, 0]
        order = np.argsort(gamma)
        cdf = np.cumsum(w[order])
        lo, hi = gamma[order][np.searchsorted(cdf, 0.05)], gamma[order][np.searchsorted(cdf, 0.95)]
        covered += lo <= GAMMA <= hi
    assert 0.8 * runs <= covered <= 0.98 * runs   # binomial(60, 0.9): 47-59 at the 1 % level


@pytest.mark.slow
def test_told_a_third_of_the_noise_the_corrected_interval_still_covers():
    runs, covered, plain_covered = 40, 0, 0
    for seed in range(runs):
        y = line(0.15, seed=300 + seed)
        for discrepancy in ("each", None):
            f = run(y, 0.05, seed=400 + seed, particles=300, discrepancy=discrepancy)
            w, gamma = f.weights[0], f.gamma[0, :, 0]
            order = np.argsort(gamma)
            cdf = np.cumsum(w[order])
            lo, hi = gamma[order][np.searchsorted(cdf, 0.05)], gamma[order][np.searchsorted(cdf, 0.95)]
            if discrepancy:
                covered += lo <= GAMMA <= hi
            else:
                plain_covered += lo <= GAMMA <= hi
    assert plain_covered < 0.6 * runs            # three times too sure: about 45 %
    assert 0.75 * runs <= covered <= runs        # the excess is estimated from 40 steps: a little either way


def test_assets_are_independent_and_log_uniform_rates_keep_their_sign():
    y = np.stack([line(0.01, seed=1), 2.0 * np.exp(-0.1 * DT * np.arange(STEPS))])
    f = ResampleMoveFilter(ExponentialDegradation(), lambda theta, points: theta, noise=0.03, dt=DT,
                           n_particles=100, seed=2)
    f.initialize((0.5, 3.0), gamma_bounds=(np.array([1e-3, -1.0]), np.array([1.0, -1e-3])), assets=2,
                  log_gamma=True)
    assert np.all(f.gamma[0] > 0) and np.all(f.gamma[1] < 0)
    for k in range(STEPS):
        f.step(y[:, k])
    estimate = f.estimate()
    assert abs(float(estimate["gamma_mean"][1, 0]) + 0.1) < 0.01
    assert np.all(f.gamma[1] < 0)


def test_bad_settings_are_named():
    with pytest.raises(PrognosisError, match="moves"):
        ResampleMoveFilter(LinearDegradation(), lambda t, p: t, noise=0.1, dt=1.0, moves=0)
    with pytest.raises(PrognosisError, match="discrepancy"):
        ResampleMoveFilter(LinearDegradation(), lambda t, p: t, noise=0.1, dt=1.0, discrepancy="all")
    with pytest.raises(PrognosisError, match="ess_target"):
        ResampleMoveFilter(LinearDegradation(), lambda t, p: t, noise=0.1, dt=1.0, ess_target=1.5)
    f = ResampleMoveFilter(LinearDegradation(), lambda t, p: t, noise=0.1, dt=1.0)
    with pytest.raises(PrognosisError, match="one sign"):
        f.initialize((0.0, 1.0), gamma_bounds=(-1.0, 1.0), log_gamma=True)
    with pytest.raises(RuntimeError, match="initialize"):
        f.step(1.0)


def test_replaying_the_history_in_chunks_changes_nothing(monkeypatch):
    import prognosis.resample_move as module

    y = line(0.05, seed=8)
    whole = run(y, 0.05, seed=9, particles=100)
    monkeypatch.setattr(module, "CHUNK", 7)   # 40 steps in six chunks, the last one short
    chunked = run(y, 0.05, seed=9, particles=100)
    # the same particles up to the order of summation (the past is summed chunk by chunk)
    assert np.allclose(whole.z, chunked.z, rtol=0, atol=1e-12)
    assert np.allclose(whole.log_evidence, chunked.log_evidence, rtol=1e-10)


def test_particles_without_density_stay_without_it_when_the_temperature_changes():
    """A covariance growing with theta overflows far out: those particles have no density (-inf).  Re-tempering
    the past for the information excess must leave them at -inf, not make NaN weights (0 x -inf)."""
    from prognosis.likelihood import ResidualNoise

    noise = ResidualNoise(covariance=[[0.05**2]], growth=[[1e-6]], nominal=1.0)
    y = line(0.05, seed=41) + 0.3 * np.sin(np.arange(STEPS))   # gaps that persist: the excess moves
    f = ResampleMoveFilter(LinearDegradation(), lambda theta, points: theta, noise=noise, dt=DT, n_particles=200,
                           seed=42)
    f.initialize((0.0, 1e200), gamma_bounds=BOX[1], assets=1)   # the prior's far end overflows the covariance
    f.z[0, :100, 0] = np.linspace(0.0, 3.0, 100)                 # half the cloud where the line is
    f.theta = f.z[..., 0].copy()
    f.frozen[:] = True   # weighed, never resampled or moved: the particles without density stay in the cloud
    for value in y:
        f.step(value)
    assert np.isfinite(f.log_evidence[0]) and np.all(np.isfinite(f.weights))
    assert np.all(np.isneginf(f.past[0, 100:].sum(axis=-1))) and np.all(np.isfinite(f.past[0, :100]))
    assert np.all(f.weights[0, 100:] == 0.0)


class _Rows:
    """Each row sees its own theta: an observation that can be cut to rows (as hypotheses' observations can)."""

    def __call__(self, theta, points):
        return theta

    def rows(self, index):
        return self


def test_replaying_only_the_rows_a_move_needs_changes_nothing():
    """Rows whose cloud is healthy, or frozen, are not replayed: the same particles, bit for bit."""
    from prognosis.degradation import PerAssetDegradation
    from prognosis.likelihood import ResidualNoise

    y = np.stack([line(0.05, seed=41), line(0.002, seed=42), line(0.05, seed=43)])
    bank = PerAssetDegradation((LinearDegradation(), ExponentialDegradation()), laws=(0, 0, 1))
    noise = ResidualNoise.independent([[0.05], [0.002], [0.05]])
    runs = []
    for observation in (lambda theta, points: theta, _Rows()):   # without rows(): every row is replayed
        f = ResampleMoveFilter(bank, observation, noise=noise, dt=DT, n_particles=100, seed=44)
        f.initialize(BOX[0], gamma_bounds=((-1.0, -1.0, 0.01), (1.0, 1.0, 1.0)), assets=3)
        partly = 0   # steps at which some rows moved and others not
        for k in range(STEPS):
            f.frozen = np.array([False, False, k > 20])   # the last row weighed, no longer moved
            partly += 0 < f.step(y[:, k]).resampled.sum() < 3
        runs.append((f, partly))
    (whole, partly), (cut, _) = runs
    assert partly >= 5
    assert np.array_equal(whole.z, cut.z) and np.array_equal(whole.log_evidence, cut.log_evidence)
