"""Posterior predictive of an identified window (prognosis.identification.predictive)."""

import numpy as np
import pytest
from scipy import special

from prognosis.identification.predictive import (PosteriorPrediction, _mixture_quantile, sample_posterior,
                                                 window_log_posterior)


def _companion(c):
    n = len(c)
    A = np.zeros((n, n))
    A[:, 0] = c
    A[np.arange(n - 1), np.arange(1, n)] = 1.0
    return A


def _residuals(a, f, beta, y, u):
    """The one-step predictor's errors, written out with explicit matrices (the reference)."""
    n, r = len(a), u.shape[1]
    A, F = _companion(a), _companion(f)
    K = A[:, 0] - F[:, 0]
    x1, B, D = beta[:n], beta[n:n + n * r].reshape(n, r), beta[n + n * r:]
    x, e = x1.copy(), np.empty(y.size)
    for t in range(y.size):
        e[t] = y[t] - x[0] - D @ u[t]
        x = A @ x + B @ u[t] + K * e[t]
    return e


def _window(seed=0, N=120, direct=False):
    """Two states, two inputs: a slow and a fast mode, y = x_0 + D u + e in innovations form.

    ``direct``: the second input acts through D only (its column of B is zero).
    """
    rng = np.random.default_rng(seed)
    u = np.column_stack([rng.uniform(0.5, 1.5, N), np.sin(np.arange(N) / 7.0) + 2.0])
    a, f = np.array([1.3, -0.4]), np.array([0.9, -0.2])   # poles 0.8 and 0.5
    beta = np.array([0.3, -0.1, 0.2, 0.0 if direct else 0.05, -0.1, 0.0 if direct else 0.02, 0.4, -0.3])
    A, K = _companion(a), a - f
    B, D = beta[2:6].reshape(2, 2), beta[6:]
    x, y = beta[:2].copy(), np.empty(N)
    for t in range(N):
        e = 0.05 * rng.standard_normal()
        y[t] = x[0] + D @ u[t] + e
        x = A @ x + B @ u[t] + K * e
    return y, u, a, f


def test_log_posterior_is_the_profiled_regression_of_the_explicit_predictor():
    y, u, a, f = _window()
    p = 8
    for theta in ([1.3, -0.4, 0.9, -0.2], [1.1, -0.2, 0.3, 0.1], [0.5, 0.3, -0.4, 0.2]):
        th = np.array(theta)
        # the errors are affine in beta: build the design from unit vectors, then least squares
        e0 = _residuals(th[:2], th[2:], np.zeros(p), y, u)
        design = np.column_stack([e0 - _residuals(th[:2], th[2:], np.eye(p)[j], y, u) for j in range(p)])
        _, rss, *_ = np.linalg.lstsq(design, e0, rcond=None)
        expected = -0.5 * (y.size - p) * np.log(rss[0])
        assert window_log_posterior(th[None], y, u)[0] == pytest.approx(expected, rel=1e-9)


def test_a_direct_input_drops_its_column_of_B_from_the_regression():
    y, u, a, f = _window(direct=True)
    keep = [0, 1, 2, 4, 6, 7]  # beta = (x_1, B[0, 0], B[0, 1], B[1, 0], B[1, 1], D): no B[:, 1]
    th = np.r_[a, f]
    e0 = _residuals(a, f, np.zeros(8), y, u)
    design = np.column_stack([e0 - _residuals(a, f, np.eye(8)[j], y, u) for j in keep])
    _, rss, *_ = np.linalg.lstsq(design, e0, rcond=None)
    expected = -0.5 * (y.size - len(keep)) * np.log(rss[0])
    assert window_log_posterior(th[None], y, u, direct_inputs=[1])[0] == pytest.approx(expected, rel=1e-9)
    # the full model fits at least as well but pays two more degrees of freedom
    assert window_log_posterior(th[None], y, u)[0] != pytest.approx(expected, rel=1e-6)


@pytest.mark.slow
def test_a_direct_input_moves_the_prediction_at_once_and_only_through_D():
    y, u, *_ = _window(direct=True, N=200)
    post = sample_posterior(y, u, 2, particles=400, direct_inputs=(1,), seed=0)
    assert post.direct_inputs == (1,)
    base = np.column_stack([np.ones(30), np.full(30, 2.0)])
    stepped = base.copy()
    stepped[10:, 1] += 1.0
    change = post.predict(stepped).mean - post.predict(base).mean
    assert np.all(np.abs(change[:10]) < 1e-12)
    assert np.allclose(change[10:], change[10], atol=1e-12)   # no transient: the state does not see it
    assert change[10] == pytest.approx(-0.3, abs=0.1)         # the window's D for that input
    full = sample_posterior(y, u, 2, particles=400, seed=0)
    free = full.predict(stepped).mean - full.predict(base).mean
    assert not np.allclose(free[10:], free[10], atol=1e-6)     # with a column of B it has dynamics


def test_log_posterior_is_minus_inf_outside_the_prior():
    y, u, *_ = _window()
    lp = window_log_posterior([[1.3, -0.4, 1.51, -0.505],    # predictor poles 1.01 and 0.5
                               [2.2, -1.21, 0.9, -0.2],     # A with a double pole at 1.1
                               [2.08, -1.0816, 0.9, -0.2],  # double pole at 1.04: inside max_radius 1.05
                               [1.3, -0.4, 0.9, -0.2]], y, u)
    assert lp[0] == -np.inf and lp[1] == -np.inf
    assert np.isfinite(lp[2]) and np.isfinite(lp[3])
    assert window_log_posterior([[2.2, -1.21, 0.9, -0.2]], y, u, max_radius=1.2)[0] > -np.inf


@pytest.mark.slow
def test_the_posterior_concentrates_on_the_true_poles():
    y, u, a, f = _window(N=300)
    post = sample_posterior(y, u, 2, particles=800, seed=3)
    poles = np.sort(np.abs(np.roots(np.r_[1.0, -np.median(post.theta[:, :2], axis=0)])))
    assert poles == pytest.approx([0.5, 0.8], abs=0.1)
    assert np.quantile(post.spectral_radii, 0.05) < 0.8 < np.quantile(post.spectral_radii, 0.95)
    assert post.stages >= 2 and 0.05 < post.acceptance.mean() < 0.6
    assert np.unique(post.theta, axis=0).shape[0] > 400


@pytest.mark.slow
def test_same_seed_same_particles():
    y, u, *_ = _window()
    one = sample_posterior(y, u, 2, particles=200, seed=7)
    two = sample_posterior(y, u, 2, particles=200, seed=7)
    three = sample_posterior(y, u, 2, particles=200, seed=8)
    np.testing.assert_array_equal(one.theta, two.theta)
    assert one.log_evidence == two.log_evidence
    assert not np.array_equal(one.theta, three.theta)


def test_mixture_quantile_solves_the_mixture_cdf():
    rng = np.random.default_rng(0)
    loc, scale = rng.normal(0.0, 3.0, (40, 50)), rng.uniform(0.1, 2.0, (40, 50))
    for q in (0.025, 0.5, 0.975):
        x = _mixture_quantile(q, loc, scale, nu=12)
        assert np.abs(special.stdtr(12, (x[:, None] - loc) / scale).mean(axis=1) - q).max() < 1e-9
    # one component: the t quantile itself
    x = _mixture_quantile(0.975, np.full((1, 1), 2.0), np.full((1, 1), 0.5), nu=5)
    assert x[0] == pytest.approx(2.0 + 0.5 * special.stdtrit(5, 0.975))


@pytest.mark.slow
def test_posterior_predictive_is_calibrated_on_its_own_model():
    """Windows and futures drawn from one first-order model: 95 % intervals cover about 95 %."""
    inside, total = 0, 0
    for rep in range(24):
        rng = np.random.default_rng(100 + rep)
        N, H = 80, 20
        u = rng.uniform(0.0, 2.0, (N + H, 1))
        x, y = 1.0, np.empty(N + H)
        for t in range(N + H):
            y[t] = x + 0.1 * rng.standard_normal()
            x = 0.9 * x + 0.1 * u[t, 0] + 0.05 * rng.standard_normal()
        post = sample_posterior(y[:N], u[:N], 1, particles=300, moves=3, seed=rep)
        p = post.predict(u[N:], draws=150)
        inside += int(np.sum((y[N:] >= p.lower) & (y[N:] <= p.upper)))
        total += H
    assert 0.88 <= inside / total <= 0.99


@pytest.mark.slow
def test_prediction_interval_widens_with_the_lead_for_a_slow_pole():
    rng = np.random.default_rng(1)
    N = 150
    u = rng.uniform(0.0, 1.0, (N, 1))
    x, y = 0.0, np.empty(N)
    for t in range(N):
        y[t] = x + 0.05 * rng.standard_normal()
        x = 0.98 * x + 0.05 * u[t, 0] + 0.02 * rng.standard_normal()
    p = sample_posterior(y, u, 1, particles=400, seed=0).predict(np.full((60, 1), 0.5), level=0.9)
    width = p.upper - p.lower
    assert width[-1] > 2 * width[0]
    assert np.all(p.lower <= p.median) and np.all(p.median <= p.upper)
    assert p.level == 0.9 and p.mean.shape == (60,)


def test_coverage_counts_the_observed_leads():
    p = PosteriorPrediction(np.zeros(4), np.zeros(4), -np.ones(4), np.ones(4), 0.95)
    assert p.coverage([0.0, 2.0]) == 0.5
    assert p.coverage([0.0, np.nan, -1.0, 1.5]) == pytest.approx(2 / 3)


@pytest.mark.parametrize("kwargs, message", [
    (dict(y=np.ones((50, 2))), "one output"),
    (dict(y=np.r_[np.ones(49), np.nan]), "must be finite"),
    (dict(y=np.ones(7), u=np.ones((7, 2))), "too short"),
    (dict(y=np.ones(30), u=np.zeros((30, 1))), "rank deficient"),
    (dict(n_states=0), "n_states"),
    (dict(target_ess=1.5), "target_ess"),
])
def test_bad_window_is_named(kwargs, message):
    args = dict(y=np.linspace(0.0, 1.0, 50), u=np.ones((50, 1)), n_states=1)
    args.update(kwargs)
    if "u" not in kwargs and np.shape(args["y"])[0] != 50:
        args["u"] = np.ones((np.shape(args["y"])[0], 1))
    with pytest.raises(ValueError, match=message):
        sample_posterior(args.pop("y"), args.pop("u"), args.pop("n_states"), particles=50, **args)


@pytest.mark.parametrize("direct, message", [
    ((2,), "names input column 2, but u has 2 columns"),
    ((1, 1), "repeats an input column"),
])
def test_bad_direct_inputs_are_named(direct, message):
    y, u, *_ = _window()
    with pytest.raises(ValueError, match=message):
        sample_posterior(y, u, 2, particles=50, direct_inputs=direct)
    with pytest.raises(ValueError, match=message):
        window_log_posterior([[1.3, -0.4, 0.9, -0.2]], y, u, direct_inputs=direct)


@pytest.mark.slow
def test_bad_future_inputs_are_named():
    y, u, *_ = _window()
    post = sample_posterior(y, u, 2, particles=100, seed=0)
    with pytest.raises(ValueError, match="u_future has 3 columns but the model has 2 inputs"):
        post.predict(np.ones((5, 3)))
    with pytest.raises(ValueError, match=r"u_future has non-finite entries"):
        post.predict(np.full((5, 2), np.nan))
    with pytest.raises(ValueError, match="predict needs u_future"):
        post.predict(None)
    with pytest.raises(ValueError, match="level"):
        post.predict(np.ones((5, 2)), level=1.2)
