"""The likelihood's noise: the Gaussian density it claims, its growth with theta, and what a healthy stretch says."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from prognosis.errors import PrognosisError
from prognosis.likelihood import ResidualNoise, healthy_noise, information_excess


def test_log_density_is_the_multivariate_normal_at_each_theta():
    c = np.array([[0.04, 0.01], [0.01, 0.09]])
    x = np.array([[0.001, 0.0], [0.002, 0.003]])
    g = np.array([[1e-4, 2e-5], [2e-5, 4e-4]])
    assert np.all(np.linalg.eigvalsh(np.block([[c, x], [x.T, g]])) > 0)   # a joint covariance: kept as given
    noise = ResidualNoise(c, x, g, nominal=2.0)
    theta = np.array([[2.0, 5.0, -1.0]])
    gap = np.array([[[0.1, -0.2], [0.3, 0.1], [-0.05, 0.4]]])
    got = noise.log_density(gap, theta)
    for n, value in enumerate(theta[0]):
        d = value - 2.0
        sigma = c + d * (x + x.T) + d**2 * g + 1e-6 * np.diag(np.diag(c))   # the millionth that keeps it invertible
        assert got[0, n] == pytest.approx(multivariate_normal(np.zeros(2), sigma).logpdf(gap[0, n]), rel=1e-10)


def test_a_joint_that_is_no_covariance_is_made_one_and_overflow_has_no_density():
    c, x, g = np.eye(2), np.array([[2.0, 0.0], [0.0, 0.0]]), np.eye(2) * 1e-2   # |X| beyond sqrt(C G)
    noise = ResidualNoise(c, x, g, nominal=0.0)
    sigma = noise.covariance_at(np.array([[-3.0, 1e200]]))
    assert np.all(np.linalg.eigvalsh(sigma[0, 0]) > 0)
    log_p = noise.log_density(np.zeros((1, 2, 2)), np.array([[-3.0, 1e200]]))
    assert np.isfinite(log_p[0, 0]) and log_p[0, 1] == -np.inf


def test_a_missing_residual_leaves_the_marginal_of_the_others():
    c = np.array([[0.04, 0.01], [0.01, 0.09]])
    noise = ResidualNoise(c)
    got = noise.log_density(np.array([[[np.nan, 0.2]]]), np.zeros((1, 1)))
    assert got[0, 0] == pytest.approx(multivariate_normal(0.0, 0.09).logpdf(0.2), rel=1e-12)


def test_healthy_noise_reads_sensor_noise_through_a_swinging_signal():
    rng = np.random.default_rng(7)
    k = np.arange(5000)
    speed_noise = rng.normal(0.0, 0.02, k.size)
    speed = 100.0 + 10.0 * np.sin(2 * np.pi * k / 70) + speed_noise   # a swing of 70 steps, ten times the noise
    residual = -0.3 * speed_noise + rng.normal(0.0, 0.01, k.size)
    noise = healthy_noise(residual[:, None], speed[:, None])
    assert np.sqrt(noise["growth"][0, 0]) == pytest.approx(0.02, rel=0.1)
    assert noise["cross"][0, 0] == pytest.approx(-0.3 * 0.02**2, rel=0.15)
    assert np.sqrt(noise["covariance"][0, 0]) == pytest.approx(np.hypot(0.006, 0.01), rel=0.1)


def test_a_start_up_ring_in_the_healthy_stretch_is_no_sensor_noise():
    """An RLC circuit switched on rings at 100 rad/s for a tenth of a second: at a filter step of 11 ms its
    fourth differences are far beyond the sensor's noise.  Read as noise, they made the current's noise a
    thousand times too large; the robust reading keeps the sensor's."""
    rng = np.random.default_rng(11)
    t = np.arange(73) * 0.011                                          # a 0.8 s stretch at the filter step
    sensor = rng.normal(0.0, 1e-4, t.size)
    current = 0.5 * np.exp(-t / 0.02) * np.sin(100 * t) + 0.02 * np.sin(7 * t) + sensor   # i peaks at V / sqrt(L / C)
    residual = -10.0 * sensor + rng.normal(0.0, 2.5e-3, t.size)
    noise = healthy_noise(residual[:, None], -current[:, None])
    assert np.sqrt(noise["growth"][0, 0]) == pytest.approx(1e-4, rel=0.5)
    # the plain mean square of the same differences: the ring dominates it, 40 times the sensor's noise
    d = np.diff(-current, 4)
    assert np.sqrt(np.mean(d**2) / 70) > 20 * 1e-4


def test_bad_noise_is_named():
    with pytest.raises(PrognosisError, match="positive diagonal"):
        ResidualNoise([[0.0]])
    with pytest.raises(PrognosisError, match="usable filter steps"):
        healthy_noise(np.full((5, 1), np.nan))


def test_more_arrs_than_sensors_give_a_covariance_that_stays_invertible():
    """Three residuals over two sensors: the third is the sum of the others, a singular correlation on
    the healthy stretch.  The likelihood keeps a hundredth of each combination's variance its own."""
    rng = np.random.default_rng(3)
    a, b = rng.normal(0, 0.1, 2000), rng.normal(0, 0.2, 2000)
    residuals = np.column_stack([a, b, a + b])
    estimate = healthy_noise(residuals, np.column_stack([a, b, a + b]) + 1.0)
    covariance = estimate["covariance"]
    scale = np.sqrt(np.diagonal(covariance))
    values = np.linalg.eigvalsh(covariance / np.outer(scale, scale))
    assert values.min() >= 0.0099 and np.allclose(np.diagonal(covariance / np.outer(scale, scale)), 1.0)
    noise = ResidualNoise(covariance, estimate["cross"], estimate["growth"], nominal=1.0)
    log_p = noise.log_density(np.zeros((1, 2, 3)), np.array([[1.0, 3.0]]))
    assert np.all(np.isfinite(log_p))
    # the correlations themselves are kept, up to the floor
    assert np.corrcoef(a + b, a)[0, 1] == pytest.approx(covariance[0, 2] / (scale[0] * scale[2]), abs=0.02)


def test_the_noise_of_two_parameters_grows_with_each_as_their_sensitivities_side_by_side_say():
    # Cov(y - h) = C + X D^T + D X^T + D G D^T with D = [d_1 I, d_2 I]: the sensitivities' noise of both
    rng = np.random.default_rng(0)
    assets, m = 3, 2
    # the joint covariance of the residuals' and both sensitivities' noise, positive definite
    factor = rng.normal(0, 0.1, (assets, 3 * m, 3 * m))
    joint = factor @ np.swapaxes(factor, -1, -2) + 0.01 * np.eye(3 * m)
    covariance, cross, growth = joint[:, :m, :m], joint[:, :m, m:], joint[:, m:, m:]
    noise = ResidualNoise(covariance, cross, growth, nominal=np.ones((assets, 2)))
    assert noise.components == 2
    theta = rng.normal(1.0, 0.3, (assets, 5, 4, 2))
    sigma = noise.covariance_at(theta)
    for a, i, k in [(0, 0, 0), (2, 4, 3), (1, 2, 1)]:
        d = theta[a, i, k] - 1.0
        D = np.hstack([d[0] * np.eye(m), d[1] * np.eye(m)])
        expected = noise.covariance[a] + noise.cross[a] @ D.T + D @ noise.cross[a].T + D @ noise.growth[a] @ D.T
        healthy = np.diag(noise.covariance[a])
        expected += np.diag(np.maximum(0.25 * healthy - np.diag(expected), 0.0) + 1e-6 * healthy)
        assert sigma[a, i, k] == pytest.approx(expected, abs=1e-14)
    # a second parameter at its nominal value: the noise of the first alone
    single = ResidualNoise(covariance, cross[:, :, :m], growth[:, :m, :m], nominal=np.ones(assets))
    at_first = np.stack([theta[..., 0], np.ones(theta.shape[:-1])], axis=-1)
    assert noise.covariance_at(at_first) == pytest.approx(single.covariance_at(theta[..., 0]), abs=1e-14)


@pytest.mark.parametrize("m", [1, 2, 3, 5, 6, 8])
def test_the_density_is_the_multivariate_normal_for_every_number_of_residuals(m):
    # up to 5 residuals the factor is written out over the entries, above that LAPACK's: both must agree
    rng = np.random.default_rng(m)
    root = rng.normal(size=(m, m))
    c = root @ root.T + 0.1 * np.eye(m)
    noise = ResidualNoise(c)
    gap = rng.normal(size=(2, 3, m))
    got = noise.log_density(gap, np.zeros((2, 3)))
    want = multivariate_normal(np.zeros(m), c).logpdf(gap.reshape(-1, m)).reshape(2, 3)
    np.testing.assert_allclose(got, want, rtol=1e-10)


def test_a_covariance_short_of_positive_definite_gets_a_ridge_not_an_error():
    v = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
    singular = np.eye(3) - np.outer(v, v)   # rank 2: a zero pivot without the ridge
    noise = ResidualNoise(singular)
    along, across = noise.log_density(np.array([[[0.1, -0.1, 0.0], [0.1, 0.1, 0.1]]]), np.zeros((1, 2)))[0]
    # a gap in the covariance's range is likely; one along its null direction is all but impossible
    assert np.isfinite(along) and np.isfinite(across) and along > across + 1e4


def test_an_offset_wandering_over_hundreds_of_steps_counts_in_the_information_excess():
    # gaps white but for an offset of 0.3 sd swinging over 300 steps (an integral's drift): short batches
    # of sqrt(K) = 25 steps average it out; batches of K / 8 see it, while white gaps stay near 1
    rng = np.random.default_rng(1)
    steps = 588
    white = rng.standard_normal((200, steps, 1))
    swing = 0.3 * np.sin(2 * np.pi * np.arange(steps) / 300 + rng.uniform(0, 2 * np.pi, (200, 1)))
    assert information_excess(white).mean() < 1.4
    assert information_excess(white + swing[..., None]).mean() > 3.0
