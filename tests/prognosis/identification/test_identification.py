"""prognosis.identification, the method of Gasperin et al. (2011): Kalman smoother, EM, online identification,
trend detection, prediction."""

import warnings

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from prognosis.identification import (IdentificationWarning, LinearGaussianModel, OnlineEM, detect_trend, em_step,
                                      fault_trend, fit_em, initial_model, kalman_smoother, log_likelihood,
                                      predict_feature)

# A 2-state model with inputs and a correlated [w; v] (S != 0): the general case of eqs. (2)-(3)
_PI = np.array([[0.20, 0.05, 0.08],
                [0.05, 0.10, 0.03],
                [0.08, 0.03, 0.30]])
CORRELATED = LinearGaussianModel(A=[[0.8, 0.2], [-0.1, 0.6]], B=[[1.0, -0.5], [0.3, 0.4]], C=[[1.0, 0.5]],
                                 D=[[0.3, -0.2]], Q=_PI[:2, :2], R=_PI[2:, 2:], S=_PI[:2, 2:], mu1=[0.5, -1.0],
                                 P1=[[0.4, 0.1], [0.1, 0.3]])
NAMES = ("A", "B", "C", "D", "Q", "R", "S", "mu1", "P1")


def dense_joint(model, u, steps):
    """Mean and covariance of (x_1..x_{T+1}, y_1..y_T) built directly from eqs. (2)-(3), no recursion.

    Every x_t and y_t is a linear map of the sources (x_1 - mu1, [w_1; v_1], ..., [w_T; v_T]), whose
    covariance is block-diagonal(P1, Pi, ..., Pi).
    """
    n, m = model.n_states, model.n_outputs
    k = n + steps * (n + m)
    noise = [slice(n + t * (n + m), n + (t + 1) * (n + m)) for t in range(steps)]
    gx, mx = [np.zeros((n, k))], [model.mu1.copy()]
    gx[0][:, :n] = np.eye(n)
    gy, my = [], []
    for t in range(steps):
        g = model.C @ gx[t]
        g[:, noise[t]] += np.hstack([np.zeros((m, n)), np.eye(m)])
        gy.append(g)
        my.append(model.C @ mx[t] + model.D @ u[t])
        g = model.A @ gx[t]
        g[:, noise[t]] += np.hstack([np.eye(n), np.zeros((n, m))])
        gx.append(g)
        mx.append(model.A @ mx[t] + model.B @ u[t])
    sources = np.zeros((k, k))
    sources[:n, :n] = model.P1
    for block in noise:
        sources[block, block] = model.noise_covariance
    g = np.vstack(gx + gy)
    return np.concatenate(mx + my), g @ sources @ g.T


def condition(mean, cov, x_index, y_index, y_values):
    """E[x | y] and Cov[x | y] for jointly Gaussian (x, y)."""
    sxy = cov[np.ix_(x_index, y_index)]
    syy = cov[np.ix_(y_index, y_index)]
    gain = np.linalg.solve(syy, sxy.T).T
    return (mean[x_index] + gain @ (y_values - mean[y_index]),
            cov[np.ix_(x_index, x_index)] - gain @ sxy.T)


@pytest.mark.parametrize("missing", [None, 2])
def test_kalman_smoother_is_the_exact_gaussian_conditional(missing):
    """Smoothed, filtered, lag-one, one-step-ahead moments and log p(Y) against dense conditioning (S != 0)."""
    rng = np.random.default_rng(3)
    steps, n, m = 6, 2, 1
    u = rng.standard_normal((steps, 2))
    _, y = CORRELATED.simulate(u, rng)
    if missing is not None:
        y[missing] = np.nan
    observed = ~np.isnan(y[:, 0])
    mean, cov = dense_joint(CORRELATED, u, steps)
    x_at = [np.arange(t * n, (t + 1) * n) for t in range(steps + 1)]
    y_at = [(steps + 1) * n + np.arange(t * m, (t + 1) * m) for t in range(steps)]
    res = kalman_smoother(CORRELATED, y, u)

    seen = np.concatenate([y_at[t] for t in range(steps) if observed[t]])
    all_x = np.concatenate(x_at)
    post_mean, post_cov = condition(mean, cov, all_x, seen, y[observed].reshape(-1))
    block = [slice(t * n, (t + 1) * n) for t in range(steps + 1)]
    for t in range(steps):
        assert res.smoothed_means[t] == pytest.approx(post_mean[block[t]], abs=1e-10)
        assert res.smoothed_covariances[t] == pytest.approx(post_cov[block[t], block[t]], abs=1e-10)
    for t in range(steps - 1):  # Cov(x_{t+1}, x_t | Y)
        assert res.lag_one_covariances[t] == pytest.approx(post_cov[block[t + 1], block[t]], abs=1e-10)
    assert res.next_mean == pytest.approx(post_mean[block[steps]], abs=1e-10)
    assert res.next_covariance == pytest.approx(post_cov[block[steps], block[steps]], abs=1e-10)
    # filtered: conditioned on y_1..y_t only
    for t in range(steps):
        past = [y_at[s] for s in range(t + 1) if observed[s]]
        if past:
            f_mean, f_cov = condition(mean, cov, x_at[t], np.concatenate(past), y[:t + 1][observed[:t + 1]].reshape(-1))
        else:
            f_mean, f_cov = mean[x_at[t]], cov[np.ix_(x_at[t], x_at[t])]
        assert res.filtered_means[t] == pytest.approx(f_mean, abs=1e-10)
        assert res.filtered_covariances[t] == pytest.approx(f_cov, abs=1e-10)
    exact = multivariate_normal(mean[seen], cov[np.ix_(seen, seen)]).logpdf(y[observed].reshape(-1))
    assert res.log_likelihood == pytest.approx(exact, rel=1e-10)
    assert log_likelihood(CORRELATED, y, u) == pytest.approx(exact, rel=1e-10)


def test_kalman_smoother_without_inputs_and_with_a_long_stationary_stretch():
    """r = 0; a long record exercises the stationary shortcut of the covariance recursions (against T = 6 dense)."""
    model = LinearGaussianModel(A=[[0.7, 0.1], [0.0, 0.5]], B=None, C=[[1.0, 1.0], [0.0, 1.0]], D=None,
                                Q=0.1 * np.eye(2), R=0.2 * np.eye(2))
    _, y = model.simulate(steps=400, rng=4)
    y[150] = np.nan  # the recursion restarts after a missing row, then becomes stationary again
    res = kalman_smoother(model, y)
    # the same smoother on the last 6 rows, started from the exact predicted state at row 394
    tail = LinearGaussianModel(A=model.A, B=None, C=model.C, D=None, Q=model.Q, R=model.R,
                               mu1=res.predicted_means[394], P1=res.predicted_covariances[394])
    mean, cov = dense_joint(tail, np.zeros((6, 0)), 6)
    post_mean, post_cov = condition(mean, cov, np.arange(12), 14 + np.arange(12), y[394:].reshape(-1))
    assert res.smoothed_means[394:] == pytest.approx(post_mean.reshape(6, 2), abs=1e-9)
    assert res.smoothed_covariances[-1] == pytest.approx(post_cov[10:, 10:], abs=1e-9)
    assert res.smoothed_covariances[150, 1, 1] > res.smoothed_covariances[149, 1, 1]  # less known where y is missing
    assert res.predicted_covariances[150] == pytest.approx(res.filtered_covariances[150])


def expected_complete_log_likelihood(model, res, y, u):
    """Eq. (17) averaged over p(X | Y) of the smoother ``res``: T - 1 joint terms, the y_T term and x_1."""
    xs, ps, lag = res.smoothed_means, res.smoothed_covariances, res.lag_one_covariances
    steps, n = xs.shape

    def gaussian(e_zz, e_zxi, e_xixi, gain, cov):
        inner = e_zz - gain @ e_zxi.T - e_zxi @ gain.T + gain @ e_xixi @ gain.T
        return -0.5 * (cov.shape[0] * np.log(2 * np.pi) + np.linalg.slogdet(cov)[1]
                       + np.trace(np.linalg.solve(cov, inner)))

    d0 = xs[0] - model.mu1
    total = gaussian(ps[0] + np.outer(d0, d0), np.zeros((n, 0)), np.zeros((0, 0)), np.zeros((n, 0)), model.P1)
    gamma = np.block([[model.A, model.B], [model.C, model.D]])
    for t in range(steps):
        e_xx = ps[t] + np.outer(xs[t], xs[t])
        e_xixi = np.block([[e_xx, np.outer(xs[t], u[t])], [np.outer(u[t], xs[t]), np.outer(u[t], u[t])]])
        if t < steps - 1:
            e_zz = np.block([[ps[t + 1] + np.outer(xs[t + 1], xs[t + 1]), np.outer(xs[t + 1], y[t])],
                             [np.outer(y[t], xs[t + 1]), np.outer(y[t], y[t])]])
            e_zxi = np.block([[lag[t] + np.outer(xs[t + 1], xs[t]), np.outer(xs[t + 1], u[t])],
                              [np.outer(y[t], xs[t]), np.outer(y[t], u[t])]])
            total += gaussian(e_zz, e_zxi, e_xixi, gamma, model.noise_covariance)
        else:
            e_zxi = np.hstack([np.outer(y[t], xs[t]), np.outer(y[t], u[t])])
            total += gaussian(np.outer(y[t], y[t]), e_zxi, e_xixi, gamma[n:], model.R)
    return total


@pytest.mark.slow
@pytest.mark.parametrize("cross", [True, False])
def test_m_step_maximizes_the_expected_complete_data_log_likelihood(cross):
    """No random perturbation of the new parameters does better on eq. (17) (the M-step is exact)."""
    rng = np.random.default_rng(5)
    u = rng.standard_normal((80, 2))
    _, y = CORRELATED.simulate(u, rng)
    start = initial_model(y, u, 2)
    new, _ = em_step(start, y, u, cross_covariance=cross)
    if not cross:
        assert not np.any(new.S)
    res = kalman_smoother(start, y, u)
    best = expected_complete_log_likelihood(new, res, y, u)
    tried = 0
    for k in range(135):
        name = NAMES[k % len(NAMES)]
        if name == "S" and not cross:
            continue
        values = {key: getattr(new, key) for key in NAMES}
        step = 1e-3 * rng.standard_normal(values[name].shape)
        values[name] = values[name] + (step + step.T if name in ("Q", "R", "P1") else step)
        try:
            perturbed = LinearGaussianModel(**values)
        except ValueError:  # left the positive semi-definite cone
            continue
        assert expected_complete_log_likelihood(perturbed, res, y, u) <= best + 1e-12, name
        tried += 1
    assert tried > 80


def test_m_step_is_eqs_19_20_over_the_pairs_t_1_to_T_minus_1():
    """With y_T missing and S = 0, [A B; C D] = Psi Sigma^-1 and Q, R = the diagonal blocks of eq. (20)."""
    rng = np.random.default_rng(6)
    u = rng.standard_normal((80, 2))
    _, y = CORRELATED.simulate(u, rng)
    y[-1] = np.nan
    start = initial_model(y, u, 2)
    new, _ = em_step(start, y, u, cross_covariance=False)
    res = kalman_smoother(start, y, u)
    xs, ps, lag = res.smoothed_means, res.smoothed_covariances, res.lag_one_covariances
    n, pairs = 2, 79
    phi, psi, sigma = np.zeros((3, 3)), np.zeros((3, 4)), np.zeros((4, 4))
    for t in range(pairs):  # eqs. (21)-(23)
        z = np.concatenate([xs[t + 1], y[t]])
        xi = np.concatenate([xs[t], u[t]])
        e_zz = np.outer(z, z)
        e_zz[:n, :n] += ps[t + 1]
        e_zxi = np.outer(z, xi)
        e_zxi[:n, :n] += lag[t]
        e_xixi = np.outer(xi, xi)
        e_xixi[:n, :n] += ps[t]
        phi, psi, sigma = phi + e_zz / pairs, psi + e_zxi / pairs, sigma + e_xixi / pairs
    gamma = psi @ np.linalg.inv(sigma)  # eq. (19)
    pi = phi - psi @ np.linalg.inv(sigma) @ psi.T  # eq. (20)
    assert np.hstack([new.A, new.B]) == pytest.approx(gamma[:n], abs=1e-9)
    assert np.hstack([new.C, new.D]) == pytest.approx(gamma[n:], abs=1e-9)
    assert new.Q == pytest.approx(pi[:n, :n], abs=1e-9)
    assert new.R == pytest.approx(pi[n:, n:], abs=1e-9)
    assert new.mu1 == pytest.approx(xs[0]) and new.P1 == pytest.approx(ps[0])


@pytest.mark.parametrize("cross, inputs, missing", [(True, True, False), (False, True, False), (True, False, False),
                                                    (False, False, False), (False, True, True)])
def test_em_log_likelihood_never_decreases(cross, inputs, missing):
    rng = np.random.default_rng(11)
    u = rng.standard_normal((150, 2))
    model = CORRELATED if inputs else LinearGaussianModel(A=CORRELATED.A, B=None, C=CORRELATED.C, D=None,
                                                          Q=CORRELATED.Q, R=CORRELATED.R, S=CORRELATED.S)
    _, y = model.simulate(u if inputs else None, rng, steps=None if inputs else 150)
    if missing:
        y[rng.choice(150, 15, replace=False)] = np.nan
    fit = fit_em(y, u if inputs else None, 2, max_iter=40, tol=0.0, cross_covariance=cross)
    ll = fit.log_likelihood
    assert ll.shape == (41,) and fit.iterations == 40 and not fit.converged
    assert np.all(np.diff(ll) >= -1e-9 * np.abs(ll[1:]))
    assert ll[-1] > ll[0] + 1.0  # and it does climb
    assert ll[-1] == pytest.approx(log_likelihood(fit.model, y, u if inputs else None))
    assert np.any(fit.model.S) == cross


@pytest.mark.slow  # EM on a simulated record: about 1.5 s
def test_em_recovers_eigenvalues_and_markov_parameters():
    """State basis is not identifiable: compare eig(A), D and the Markov parameters C A^k B only."""
    truth = LinearGaussianModel(A=[[0.9, 0.15], [0.0, 0.5]], B=[[1.0, 0.0], [0.5, 1.0]], C=[[1.0, 0.6]],
                                D=[[0.2, -0.1]], Q=np.diag([0.01, 0.02]), R=[[0.02]])
    rng = np.random.default_rng(7)
    u = rng.standard_normal((1000, 2))
    _, y = truth.simulate(u, rng)
    fit = fit_em(y, u, 2, cross_covariance=False, max_iter=150, tol=1e-9)
    assert np.sort(fit.model.eigenvalues.real) == pytest.approx([0.5, 0.9], abs=0.04)
    assert np.allclose(fit.model.eigenvalues.imag, 0.0)

    def markov(m):
        return np.array([m.C @ np.linalg.matrix_power(m.A, k) @ m.B for k in range(8)])

    assert np.abs(markov(fit.model) - markov(truth)).max() < 0.05
    assert fit.model.D == pytest.approx(truth.D, abs=0.03)
    assert fit.model.R[0, 0] == pytest.approx(0.02, rel=0.5)
    assert fit.log_likelihood[-1] >= log_likelihood(truth, y, u) - 1.0  # as likely as the truth, or more


def test_the_all_ones_start_of_the_seed_keeps_the_states_exchangeable():
    """Why fit_em does not start from the all-ones matrices of Gasperin et al. (2011).

    EM keeps the symmetry, the rank stays 1.
    """
    truth = LinearGaussianModel(A=[[0.9, 0.0], [0.0, 0.4]], B=[[1.0], [1.0]], C=[[1.0, 1.0]], D=[[0.0]],
                                Q=0.05 * np.eye(2), R=[[0.05]])
    rng = np.random.default_rng(8)
    u = rng.standard_normal((300, 1))
    _, y = truth.simulate(u, rng)
    ones = LinearGaussianModel(A=np.ones((2, 2)), B=np.ones((2, 1)), C=np.ones((1, 2)), D=np.ones((1, 1)),
                               Q=np.ones((2, 2)) + np.eye(2), R=np.ones((1, 1)), mu1=np.ones(2),
                               P1=np.ones((2, 2)) + np.eye(2))  # all ones (Q, P1 made positive definite)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)
        stuck = fit_em(y, u, 2, initial=ones, max_iter=30, cross_covariance=False).model
        ours = fit_em(y, u, 2, max_iter=30, cross_covariance=False).model
    assert stuck.A[0, 0] == pytest.approx(stuck.A[1, 1]) and stuck.A[0, 1] == pytest.approx(stuck.A[1, 0])
    assert abs(stuck.eigenvalues[1]) < 1e-6 * abs(stuck.eigenvalues[0])  # one mode only
    assert sorted(abs(ours.eigenvalues)) == pytest.approx([0.4, 0.9], abs=0.1)


def test_degenerate_noise_is_floored_with_a_warning():
    u = np.random.default_rng(9).standard_normal((100, 1))
    y = 2.0 * u  # the output is an exact function of the input: R -> 0 in one M-step
    with pytest.warns(IdentificationWarning, match="R"):
        new, _ = em_step(initial_model(y, u, 1), y, u, cross_covariance=False)
    assert new.R[0, 0] > 0.0 and new.D[0, 0] == pytest.approx(2.0, abs=1e-6)


@pytest.mark.slow
def test_simulate_draws_the_joint_noise_and_initial_state():
    rng = np.random.default_rng(10)
    u = rng.standard_normal((20000, 2))
    x, y = CORRELATED.simulate(u, rng)
    w = x[1:] - x[:-1] @ CORRELATED.A.T - u[:-1] @ CORRELATED.B.T
    v = y[:-1] - x[:-1] @ CORRELATED.C.T - u[:-1] @ CORRELATED.D.T
    assert np.cov(np.hstack([w, v]), rowvar=False) == pytest.approx(CORRELATED.noise_covariance, abs=0.01)
    starts = np.array([CORRELATED.simulate(u[:1], seed)[0][0] for seed in range(3000)])
    assert starts.mean(axis=0) == pytest.approx(CORRELATED.mu1, abs=0.05)
    assert np.cov(starts, rowvar=False) == pytest.approx(CORRELATED.P1, abs=0.05)
    assert np.array_equal(CORRELATED.simulate(u[:50], 1)[1], CORRELATED.simulate(u[:50], 1)[1])


@pytest.mark.slow
def test_predict_feature_interval_covers_95_percent_of_futures():
    """Monte Carlo over independent records: filter y_1..y_T, predict y_{T+1..T+H}, count hits per lead (S != 0)."""
    rng = np.random.default_rng(12)
    steps, horizon, runs = 25, 15, 600
    hits = np.zeros(horizon)
    errors = np.zeros((runs, horizon))
    stds = None
    for i in range(runs):
        u = rng.standard_normal((steps + horizon, 2))
        _, y = CORRELATED.simulate(u, rng)
        res = kalman_smoother(CORRELATED, y[:steps], u[:steps])
        p = predict_feature(CORRELATED, res.next_mean, res.next_covariance, u[steps:])
        hits += (y[steps:, 0] >= p.lower[:, 0]) & (y[steps:, 0] <= p.upper[:, 0])
        errors[i] = y[steps:, 0] - p.mean[:, 0]
        stds = p.std[:, 0]  # the same for every run: it does not depend on the data
    coverage = hits / runs
    assert np.all(np.abs(coverage - 0.95) < 0.035)  # 4.5 binomial standard errors at n = 600
    assert abs(coverage.mean() - 0.95) < 0.015
    assert np.abs(errors.mean(axis=0)).max() < 4 * stds.max() / np.sqrt(runs)
    assert errors.std(axis=0) == pytest.approx(stds, rel=0.12)
    assert np.all(np.diff(stds) >= -1e-12)  # uncertainty grows with the lead


def test_predict_feature_interval_and_level():
    model = LinearGaussianModel(A=[[1.0]], B=[[1.0]], C=[[2.0]], D=[[0.5]], Q=[[0.3]], R=[[0.1]])
    p90 = predict_feature(model, [1.0], [[0.2]], np.ones((4, 1)), level=0.9)
    assert p90.mean[:, 0] == pytest.approx([2.5, 4.5, 6.5, 8.5])
    assert p90.std[:, 0] ** 2 == pytest.approx(4 * (0.2 + 0.3 * np.arange(4)) + 0.1)
    assert p90.upper - p90.mean == pytest.approx(1.6448536 * p90.std)
    p99 = predict_feature(model, [1.0], [[0.2]], np.ones((4, 1)), level=0.99)
    assert np.all(p99.upper > p90.upper) and np.all(p99.lower < p90.lower)
    assert p90.coverage(p90.mean) == 1.0 and p90.coverage(p90.upper + 1.0) == 0.0


def test_fault_trend_reads_the_spectral_radius():
    def model(a):
        return LinearGaussianModel(A=a, B=None, C=[[1.0, 0.0]], D=None, Q=np.eye(2), R=[[1.0]])

    rotation = model([[0.0, -1.01], [1.01, 0.0]])  # eigenvalues +-1.01 i: unstable without a real eigenvalue > 1
    assert rotation.spectral_radius == pytest.approx(1.01) and fault_trend(rotation) and not rotation.is_stable
    assert not fault_trend(rotation, margin=0.02)
    stable = model([[0.99, 5.0], [0.0, -0.5]])  # large off-diagonal, still stable
    assert not fault_trend(stable) and stable.is_stable and stable.spectral_radius == pytest.approx(0.99)


def test_detect_trend_rule():
    radii = [0.95, 1.02, 0.99, 1.01, 1.03, 1.05, 0.9, 1.1]
    assert detect_trend(radii, persistence=1) == 1
    assert detect_trend(radii, persistence=3) == 5  # the run 3..5 completes at index 5
    assert detect_trend(radii, persistence=4) is None
    assert detect_trend(radii, threshold=1.04, persistence=1) == 5
    assert detect_trend([], persistence=2) is None
    with pytest.raises(ValueError, match="persistence"):
        detect_trend(radii, persistence=0)


def drifting_record(seed, steps=700, onset=350):
    """y = x + v with x_{t+1} = a x_t + 0.5 u_t + w_t, a = 0.7 before ``onset`` and 1.01 after."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.5, 1.5, steps)
    x, y = 1.0, np.empty(steps)
    for t in range(steps):
        y[t] = x + 0.05 * rng.standard_normal()
        x = (0.7 if t < onset else 1.01) * x + 0.5 * u[t] + 0.05 * rng.standard_normal()
    return y, u[:, None], onset


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_online_identification_detects_the_instability_after_the_onset_only(seed):
    y, u, onset = drifting_record(seed)
    online = OnlineEM(n_states=1, window=100, every=10, iterations=5)
    for t in range(y.size):
        online.update(y[t], u[t])
    times, radii = online.radii()
    alarm = detect_trend(radii, persistence=3)
    assert alarm is not None and onset < times[alarm] < onset + 150
    assert detect_trend(radii[times < onset], persistence=3) is None
    assert np.all(radii[times < onset] < 0.95)
    assert np.median(radii[times > onset + 150]) == pytest.approx(1.01, abs=0.01)


def test_online_em_first_window_and_warm_start():
    y, u, _ = drifting_record(3, steps=260, onset=1000)
    online = OnlineEM(n_states=1, window=200, every=20, iterations=3, initial_iterations=50)
    models = [online.update(y[t], u[t]) for t in range(240)]
    assert all(m is None for m in models[:199]) and models[199] is not None
    assert models[200] is models[199] and models[218] is models[199] and models[219] is not models[199]
    assert [h.time for h in online.history] == [199, 219, 239]
    assert online.samples == 240
    first = fit_em(y[:200], u[:200], 1, max_iter=50, tol=1e-8, cross_covariance=False).model
    assert online.history[0].model.A == pytest.approx(first.A) and online.history[0].model.R == pytest.approx(first.R)
    # the warm start beats a cold start with the same number of EM steps on the same window
    window_y, window_u = online.window_data()
    assert window_y[:, 0] == pytest.approx(y[40:240])
    cold = fit_em(window_y, window_u, 1, max_iter=3, cross_covariance=False)
    assert log_likelihood(online.model, window_y, window_u) > cold.log_likelihood[-1]
    # between identifications the smoother starts from the state at the moved window's first sample
    online.update(y[240], u[240])
    assert online.smoother().smoothed_means.shape == (200, 1)
    shifted = online.smoother().log_likelihood
    stale = kalman_smoother(online.model, *online.window_data()).log_likelihood
    assert shifted > stale


def test_a_change_of_state_basis_keeps_the_outputs_and_the_likelihood():
    t = np.array([[2.0, 0.5], [-0.3, 1.5]])
    moved = CORRELATED.transformed(t)
    u = np.random.default_rng(5).standard_normal((40, 2))
    _, y = CORRELATED.simulate(u, rng=5)
    assert log_likelihood(moved, y, u) == pytest.approx(log_likelihood(CORRELATED, y, u), rel=1e-12)
    assert np.sort_complex(moved.eigenvalues) == pytest.approx(np.sort_complex(CORRELATED.eigenvalues))
    # same noise-free response: the Markov parameters C A^k B agree
    for k in range(4):
        assert moved.C @ np.linalg.matrix_power(moved.A, k) @ moved.B == pytest.approx(
            CORRELATED.C @ np.linalg.matrix_power(CORRELATED.A, k) @ CORRELATED.B)
    assert moved.transformed(np.linalg.inv(t)).A == pytest.approx(CORRELATED.A)
    with pytest.raises(ValueError, match="T must have shape"):
        CORRELATED.transformed(np.eye(3))


def test_online_em_warm_start_is_in_a_whitened_state_basis():
    """EM leaves the basis free; the warm start puts the window's smoothed states at unit second moment."""
    from prognosis.identification.online import whitened_model

    y, u, _ = drifting_record(3, steps=200, onset=1000)
    model = fit_em(y, u, 1, max_iter=20, cross_covariance=False).model.transformed([[1e4]])
    res = kalman_smoother(model, y, u)
    white = whitened_model(model, res, 50)
    again = kalman_smoother(white, y, u)
    second = np.mean(again.smoothed_means[50:] ** 2) + np.mean(again.smoothed_covariances[50:])
    assert second == pytest.approx(1.0, rel=1e-6)
    assert again.log_likelihood == pytest.approx(res.log_likelihood, rel=1e-10)


def test_online_em_accepts_missing_samples():
    y, u, _ = drifting_record(4, steps=260, onset=1000)
    y[[210, 225]] = np.nan
    online = OnlineEM(n_states=1, window=200, every=10, iterations=2, initial_iterations=20)
    for t in range(260):
        online.update(y[t], u[t])
    assert len(online.history) == 7 and np.isfinite(online.history[-1].log_likelihood)


@pytest.mark.parametrize("changes, match", [
    ({"A": np.ones((2, 3))}, "A must be square"),
    ({"B": np.ones((3, 2))}, "B must have 2 rows"),
    ({"C": np.ones((1, 3))}, "C must have shape"),
    ({"D": np.ones((2, 2))}, "D must have 1 rows"),
    ({"D": np.ones((1, 3))}, "D must have shape"),
    ({"Q": [[1.0, 0.5], [0.0, 1.0]]}, "Q must be symmetric"),
    ({"Q": [[1.0, 0.0], [0.0, -1.0]]}, "Q must be positive semi-definite"),
    ({"R": [[0.0]]}, "R must be positive definite"),
    ({"S": np.ones((1, 2))}, "S must have shape"),
    ({"S": [[5.0], [5.0]]}, r"\[\[Q, S\], \[S\^T, R\]\]"),
    ({"mu1": [0.0]}, "mu1"),
    ({"P1": np.ones((3, 3))}, "P1 must have shape"),
    ({"A": [[np.nan, 0.0], [0.0, 1.0]]}, "A has non-finite"),
])
def test_model_validation_names_the_matrix(changes, match):
    values = {key: getattr(CORRELATED, key) for key in NAMES}
    values.update(changes)
    with pytest.raises(ValueError, match=match):
        LinearGaussianModel(**values)


def test_data_validation_names_the_argument():
    u = np.zeros((10, 2))
    y = np.zeros(10)
    with pytest.raises(ValueError, match="y has 2 columns"):
        kalman_smoother(CORRELATED, np.zeros((10, 2)), u)
    with pytest.raises(ValueError, match="u has 9 rows"):
        kalman_smoother(CORRELATED, y, u[:9])
    with pytest.raises(ValueError, match="u has 1 columns"):
        log_likelihood(CORRELATED, y, u[:, :1])
    with pytest.raises(ValueError, match="u is required"):
        kalman_smoother(CORRELATED, y, None)
    with pytest.raises(ValueError, match="y has infinite"):
        kalman_smoother(CORRELATED, np.r_[np.inf, y[1:]], u)
    with pytest.raises(ValueError, match="u has non-finite"):
        kalman_smoother(CORRELATED, y, np.r_[[[np.nan, 0.0]], u[1:]])
    with pytest.raises(ValueError, match="cross_covariance=False"):
        em_step(CORRELATED, np.r_[np.nan, y[1:]], u)
    with pytest.raises(ValueError, match="n_states"):
        fit_em(y, u, 0)
    with pytest.raises(ValueError, match="mean"):
        predict_feature(CORRELATED, [0.0], np.eye(2), u)
    with pytest.raises(ValueError, match="covariance"):
        predict_feature(CORRELATED, [0.0, 0.0], np.eye(3), u)
    with pytest.raises(ValueError, match="u_future has 1 columns"):
        predict_feature(CORRELATED, [0.0, 0.0], np.eye(2), u[:, :1])
    with pytest.raises(ValueError, match="level"):
        predict_feature(CORRELATED, [0.0, 0.0], np.eye(2), u, level=1.0)
    with pytest.raises(ValueError, match="every"):
        OnlineEM(1, window=5)  # every = 12 would skip whole windows
    online = OnlineEM(1, window=5, every=2)
    online.update(1.0, [0.0])
    with pytest.raises(ValueError, match="y_t, u_t"):
        online.update([1.0, 2.0], [0.0])
    with pytest.raises(RuntimeError, match="no model yet"):
        online.smoother()


def test_repr_and_read_only_arrays():
    text = repr(CORRELATED)
    assert text.startswith("LinearGaussianModel(n_states=2, n_inputs=2, n_outputs=1, spectral_radius=")
    assert "S=" in text and "A=[[" in text
    with pytest.raises(ValueError):
        CORRELATED.A[0, 0] = 1.0
