"""ROS-ELM (Du et al., eqs. 47-56) and the per-variable series forecaster (Du et al., section 5)."""

import numpy as np
import pytest

from prognosis.statespace.elm import ROSELM, SeriesForecaster


def rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def ridge_reference(model, X, T, lam):
    """Eq. 53 computed independently: sigmoid hidden layer and normal equations with numpy."""
    H = 1.0 / (1.0 + np.exp(-(X @ model.input_weights.T + model.biases)))
    A = H.T @ H + lam * np.eye(model.n_hidden)
    return np.linalg.solve(A, H.T @ T), np.linalg.inv(A), H


@pytest.fixture
def regression_data():
    rng = np.random.default_rng(3)
    X = rng.uniform(-1, 1, size=(160, 3))
    T = np.column_stack([np.sin(2 * X[:, 0]) + X[:, 1] * X[:, 2], np.cos(X.sum(axis=1))])
    return X, T + 0.01 * rng.standard_normal(T.shape)


@pytest.mark.parametrize("one_output", [False, True])
def test_online_rows_and_blocks_equal_batch_ridge(regression_data, one_output):
    X, T = regression_data
    if one_output:
        T = T[:, 0]
    lam = 1e-3  # keeps cond(H^T H + lambda I) ~ 1e6, so 1e-8 agreement is a fair demand
    beta_ref, K_ref, H = ridge_reference(ROSELM(3, 30, lam, seed=1), X, T, lam)

    rows = ROSELM(3, 30, lam, seed=1).fit(X[:40], T[:40])
    for x, t in zip(X[40:], T[40:]):
        rows.partial_fit(x, t)
    blocks = ROSELM(3, 30, lam, seed=1).fit(X[:40], T[:40])
    for start, stop in [(40, 41), (41, 48), (48, 80), (80, 160)]:
        blocks.partial_fit(X[start:stop], T[start:stop])

    for model in (rows, blocks):
        assert model.beta.shape == beta_ref.shape
        assert rel(model.beta, beta_ref) < 1e-8  # measured ~3e-13
        assert rel(model.K, K_ref) < 1e-8
        assert rel(model.predict(X), H @ beta_ref) < 1e-8
        assert model.predict(X).shape == T.shape
        assert model.n_samples_seen == 160


def test_ridge_formula_with_fewer_samples_than_nodes():
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, size=(47, 3))  # the N0 = 47 pairs of Du et al. for L = 50 nodes
    T = np.sin(X.sum(axis=1))
    model = ROSELM(3, 50, 1e-3, seed=2).fit(X, T)
    beta_ref, K_ref, H = ridge_reference(model, X, T, 1e-3)
    assert rel(model.beta, beta_ref) < 1e-8  # measured ~1e-11
    assert rel(model.K, K_ref) < 1e-8
    # dual form of eq. 53, H^T (H H^T + lambda I)^-1 T, valid for N0 < L
    assert rel(model.beta, H.T @ np.linalg.solve(H @ H.T + 1e-3 * np.eye(47), T)) < 1e-8

    seed_setting = ROSELM(3, 50, 1e-8, seed=2).fit(X, T)  # cond(H0^T H0 + lambda I) ~ 1e11
    assert np.isfinite(seed_setting.beta).all() and np.isfinite(seed_setting.K).all()
    assert np.abs(seed_setting.predict(X) - T).max() < 1e-2  # nearly interpolates: measured 1.7e-3
    with pytest.raises(ValueError, match="regularization=0"):
        ROSELM(3, 50, 0.0).fit(X, T)


def test_activations_are_stable_and_bounded():
    X = np.array([[1e4, -1e4, 0.0], [-800.0, 800.0, 3.0]])
    with np.errstate(over="raise", invalid="raise"):  # the naive 1 / (1 + exp(-x)) overflows here
        H = ROSELM(3, 20, weight_range=(-1, 1)).hidden(X)
    assert ((H >= 0) & (H <= 1)).all() and (H.min() < 1e-10) and (H.max() > 1 - 1e-10)
    assert (ROSELM(3, 20, activation="tanh").hidden(X) < 0).any()
    assert np.allclose(ROSELM(1, 1, weight_range=(1, 1), bias_range=(0, 0)).hidden([[np.log(3.0)]]), 0.75)


def test_seeds_are_deterministic():
    assert np.array_equal(ROSELM(3, 10, seed=4).input_weights, ROSELM(3, 10, seed=4).input_weights)
    assert not np.allclose(ROSELM(3, 10, seed=4).input_weights, ROSELM(3, 10, seed=5).input_weights)

    t = np.arange(60.0)
    Z = np.column_stack([np.sin(t / 5), np.cos(t / 7)])
    a, b, c = (SeriesForecaster(seed=s).fit(Z) for s in (7, 7, 8))
    assert np.array_equal(a.forecast(4), b.forecast(4))
    assert not np.allclose(a.models[0].input_weights, c.models[0].input_weights)
    assert not np.allclose(a.models[0].input_weights, a.models[1].input_weights)  # one seed per variable


def sine_ramp(n):
    t = np.arange(float(n))
    return np.column_stack([np.sin(2 * np.pi * t / 40) + 0.005 * t, 1.0 + 0.5 * np.cos(2 * np.pi * t / 40) - 0.003 * t])


def test_forecaster_learns_smooth_series_and_forecast_is_pure():
    Z = sine_ramp(65)
    forecaster = SeriesForecaster(names=["a", "b"]).fit(Z[:50])
    # max |error| over the 5 steps, measured over seeds 0-19: <= 8.0e-3 after fit and after 10 updates
    assert np.abs(forecaster.forecast(5) - Z[50:55]).max() < 0.03
    for row in Z[50:60]:
        forecaster.update(row)
    beta, history = forecaster.models[1].beta, forecaster.history
    first = forecaster.forecast(5)
    assert first.shape == (5, 2)
    assert np.abs(first - Z[60:65]).max() < 0.03
    assert np.array_equal(forecaster.forecast(5), first)
    assert np.array_equal(forecaster.models[1].beta, beta) and np.array_equal(forecaster.history, history)


def test_update_appends_the_newest_pair():
    # unscaled, fit on 50 rows + 10 updates trains on exactly the pairs of a fit on 60 rows
    Z = sine_ramp(60)
    online = SeriesForecaster(regularization=1e-3).fit(Z[:50])
    for row in Z[50:]:
        online.update(row)
    batch = SeriesForecaster(regularization=1e-3).fit(Z)
    assert np.array_equal(online.history, Z)
    for mo, mb in zip(online.models, batch.models):
        assert rel(mo.beta, mb.beta) < 1e-8
    assert rel(online.forecast(3), batch.forecast(3)) < 1e-8


def test_one_variable_history_gives_vector_forecasts():
    z = sine_ramp(55)[:, 0]
    forecaster = SeriesForecaster(scale=True).fit(z[:50])
    forecaster.update(z[50])
    assert forecaster.forecast(4).shape == (4,)
    assert np.abs(forecaster.forecast(4) - z[51:55]).max() < 0.03


def rolling_rmse(z, truth, scale, seed, n0=50, horizon=5):
    """1-step and horizon-step RMSE against the noiseless truth, updating online after each forecast."""
    forecaster = SeriesForecaster(scale=scale, seed=seed).fit(z[:n0])
    first, last = [], []
    for k in range(n0, len(z) - horizon + 1):
        path = forecaster.forecast(horizon)
        first.append(path[0] - truth[k])
        last.append(path[-1] - truth[k + horizon - 1])
        forecaster.update(z[k])
    return np.sqrt(np.mean(np.square(first))), np.sqrt(np.mean(np.square(last)))


@pytest.mark.parametrize("seed", [0, 1])
def test_tank_level_ramp_forecasts(seed):
    t = np.arange(200.0)
    truth = 1.0 - 0.004 * t
    z = truth + 2e-4 * np.random.default_rng(seed).standard_normal(200)
    raw_1, raw_5 = rolling_rmse(z, truth, scale=False, seed=seed)
    scaled_1, scaled_5 = rolling_rmse(z, truth, scale=True, seed=seed)
    # measured over 3 noise x 5 network seeds: raw 5-step 2.2-3.1e-4, scaled 0.70-1.7e-3: the
    # raw network is nearly linear and extrapolates the ramp, scaled inputs leave the training range
    assert raw_5 < 6e-4 and raw_1 < 4e-4
    assert scaled_5 < 4e-3 and scaled_1 < 6e-4
    assert raw_5 < scaled_5


def test_bad_arguments_raise():
    X, T = np.zeros((5, 2)), np.zeros(5)
    with pytest.raises(ValueError, match="n_hidden"):
        ROSELM(2, n_hidden=0)
    with pytest.raises(ValueError, match="regularization"):
        ROSELM(2, regularization=-1.0)
    with pytest.raises(ValueError, match=r"activation .*'sigmoid', 'tanh'.*'relu'"):
        ROSELM(2, activation="relu")
    with pytest.raises(ValueError, match="weight_range"):
        ROSELM(2, weight_range=(1.0, -1.0))
    model = ROSELM(2, 5)
    with pytest.raises(ValueError, match="predict called before fit"):
        model.predict(X)
    with pytest.raises(ValueError, match="partial_fit called before fit"):
        model.partial_fit(X[0], 0.0)
    with pytest.raises(ValueError, match="X must have n_inputs=2 columns"):
        model.fit(np.zeros((5, 3)), T)
    bad = X.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="X row 3"):
        model.fit(bad, T)
    with pytest.raises(ValueError, match="T row 2"):
        model.fit(X, np.array([0, 0, np.inf, 0, 0]))
    with pytest.raises(ValueError, match="T must have shape"):
        model.fit(X, np.zeros(4))
    model.fit(X, T)
    with pytest.raises(ValueError, match="x must have n_inputs=2"):
        model.partial_fit(np.zeros(3), 0.0)
    with pytest.raises(ValueError, match="x row 1"):
        model.partial_fit(bad[2:4], np.zeros(2))
    with pytest.raises(ValueError, match="t row 0"):
        model.partial_fit(X[0], np.nan)
    with pytest.raises(ValueError, match="t must have shape"):
        model.partial_fit(X[:2], np.zeros(3))


def test_bad_series_raise():
    Z = sine_ramp(10)
    with pytest.raises(ValueError, match="embedding"):
        SeriesForecaster(embedding=0)
    with pytest.raises(ValueError, match=r"at least embedding \+ 1 = 4 rows"):
        SeriesForecaster(embedding=3).fit(Z[:3])
    Z[6, 1] = np.nan
    with pytest.raises(ValueError, match="variable 'h2' row 6"):
        SeriesForecaster(names=["h1", "h2"]).fit(Z)
    with pytest.raises(ValueError, match="column 1 row 6"):
        SeriesForecaster().fit(Z)
    with pytest.raises(ValueError, match="names has 3 entries"):
        SeriesForecaster(names=["a", "b", "c"]).fit(Z[:5])
    forecaster = SeriesForecaster(names=["h1", "h2"])
    with pytest.raises(ValueError, match="forecast called before fit"):
        forecaster.forecast(2)
    forecaster.fit(Z[:6])
    with pytest.raises(ValueError, match="z must have length 2"):
        forecaster.update([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="z variable 'h1'"):
        forecaster.update([np.inf, 0.0])
    with pytest.raises(ValueError, match="steps"):
        forecaster.forecast(0)
    assert len(forecaster.history) == 6  # rejected updates leave the history alone
