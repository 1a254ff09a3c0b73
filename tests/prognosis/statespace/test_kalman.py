"""prognosis.statespace: the Kalman filters, the bootstrap filter and lookahead on a linear-Gaussian model and the
three-tank system."""

from types import SimpleNamespace

import numpy as np
import pytest
import sympy as sp

from prognosis.statespace.bootstrap import BootstrapParticleFilter
from prognosis._linalg import psd_sqrt, tria
from prognosis.statespace import (CubatureKalmanFilter, ExtendedKalmanFilter, FilterWarning, StrongTracking,
                                  UnscentedKalmanFilter)
from prognosis.statespace.lookahead import look_ahead, predict_ahead
from prognosis.statespace import discretize
from tests.scenarios import ThreeTanks

# A damped oscillator (m p'' = -k p - c p' + F) with a force bias b estimated as a state.  The bias
# enters additively, so the Euler step is exactly linear in (p, v, b):
#   x_k = PHI x_{k-1} + GAMMA F_{k-1},   z_k = H x_k + v_k  (position and velocity measured).
P, V, K, C, MASS, BIAS = sp.symbols("p v k c m b")
FORCE = sp.Function("F")(sp.Symbol("t"))
PARAMETERS = {"k": 2.0, "c": 0.4, "m": 1.5, "b": 0.0}
DT = 0.1
OSCILLATOR = SimpleNamespace(states=[P, V], rhs=[V, (-K * P - C * V + FORCE) / MASS + BIAS], inputs=["F"],
                             outputs={"y": P, "s": V}, parameters=PARAMETERS)
PHI = np.array([[1.0, DT, 0.0],
                [-DT * 2.0 / 1.5, 1.0 - DT * 0.4 / 1.5, DT],
                [0.0, 0.0, 1.0]])
GAMMA = np.array([0.0, DT / 1.5, 0.0])
H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
Q = np.diag([1e-6, 1e-5, 1e-6])
R = np.array([[1e-3, 5e-4], [5e-4, 4e-3]])  # correlated, so a reduced R is not just a diagonal entry
X0 = np.array([1.0, 0.0, 0.0])
P0 = np.diag([0.05, 0.05, 0.1])
TRUTH0 = np.array([1.1, -0.2, 0.3])


@pytest.fixture(scope="module")
def model():
    return discretize(OSCILLATOR, dt=DT, augment=["b"], method="euler")


def forces(steps):
    return np.sin(0.3 * np.arange(steps))


def simulate(steps, seed, *, ramp=0.0, q=Q, noise=True):
    """Truth and measurements of the linear system; with ``ramp`` the bias drifts by that much per step."""
    rng = np.random.default_rng(seed)
    u, x = forces(steps), TRUTH0.copy()
    states, z = np.empty((steps, 3)), np.empty((steps, 2))
    root_r = np.linalg.cholesky(R)
    for k in range(steps):
        x = PHI @ x + GAMMA * u[k] + (np.sqrt(np.diag(q)) * rng.standard_normal(3) if noise else 0.0)
        x[2] += ramp
        states[k] = x
        z[k] = H @ x + (root_r @ rng.standard_normal(2) if noise else 0.0)
    return u, states, z


def kalman(z, u, x=X0, p=P0, q=Q, rho=None):
    """The textbook Kalman filter, means and covariances after each update.

    With ``rho``, Zhou's strong tracking filter (Du et al., eqs. 7-11, beta = 1): the propagated part of the
    prior covariance is multiplied by ``lambda_k = max(1, tr N_k / tr M_k)``; the factors are returned too.
    """
    x, p = np.array(x, float), np.array(p, float)
    means, covariances, factors, v = [], [], [], None
    for zk, uk in zip(z, u):
        x = PHI @ x + GAMMA * uk
        spread = PHI @ p @ PHI.T
        factor = 1.0
        if rho is not None:
            residual = zk - H @ x
            v = np.outer(residual, residual) if v is None else (rho * v + np.outer(residual, residual)) / (1 + rho)
            n = v - H @ q @ H.T - R  # eq. 8
            m = H @ spread @ H.T  # eq. 9
            factor = max(1.0, np.trace(n) / np.trace(m))  # eq. 7
        factors.append(factor)
        p = factor * spread + q
        gain = np.linalg.solve(H @ p @ H.T + R, H @ p).T
        x = x + gain @ (zk - H @ x)
        joseph = np.eye(3) - gain @ H
        p = joseph @ p @ joseph.T + gain @ R @ gain.T
        means.append(x)
        covariances.append(p)
    if rho is not None:
        return np.array(means), np.array(covariances), np.array(factors)
    return np.array(means), np.array(covariances)


FILTERS = {
    "EKF": (ExtendedKalmanFilter, {}),
    "UKF": (UnscentedKalmanFilter, {}),  # alpha = 1e-3: weights of -1e6 cost digits
    "UKF-alpha1": (UnscentedKalmanFilter, {"alpha": 1.0}),
    "SCKF": (CubatureKalmanFilter, {}),
}


def build(name, model, fading=None, **overrides):
    cls, options = FILTERS[name]
    settings = {"mean": X0, "covariance": P0, "process_noise": Q, "measurement_noise": R, **overrides}
    return cls(model, settings["mean"], settings["covariance"], settings["process_noise"],
               settings["measurement_noise"], fading=fading, **options)


# ---------------------------------------------------------------- linear-Gaussian exactness


def test_the_euler_model_is_the_linear_system(model):
    assert model.states == ("p", "v", "b")
    np.testing.assert_allclose(model.transition_jacobian(X0, [0.3]), PHI, rtol=0, atol=1e-15)
    x = np.array([0.3, -1.2, 0.7])
    np.testing.assert_allclose(model.transition(x, [0.3]), PHI @ x + GAMMA * 0.3, rtol=1e-15)
    np.testing.assert_array_equal(model.measurement_jacobian(x), H)


@pytest.mark.parametrize("name, tolerance", [("EKF", 1e-12), ("UKF", 1e-8), ("UKF-alpha1", 1e-12), ("SCKF", 1e-12)])
def test_linear_gaussian_filters_equal_the_kalman_filter(model, name, tolerance):
    """Measured worst relative error over 50 steps: EKF, SCKF, UKF(alpha=1) 1e-14; UKF(alpha=1e-3) 6e-10."""
    u, _, z = simulate(50, seed=0)
    means, covariances = kalman(z, u)
    f = build(name, model)
    for k in range(50):
        f.step(z[k], [u[k]])
        assert np.linalg.norm(f.mean - means[k]) <= tolerance * np.linalg.norm(means[k])
        assert np.linalg.norm(f.covariance - covariances[k]) <= tolerance * np.linalg.norm(covariances[k])
    # the filter learned something: the posterior is far tighter than the prior
    assert np.trace(f.covariance) < 0.05 * np.trace(P0)


def test_square_root_factor_is_the_covariance(model):
    u, _, z = simulate(20, seed=1)
    ckf = build("SCKF", model)
    for k in range(20):
        ckf.step(z[k], [u[k]])
        s = ckf.sqrt_covariance
        np.testing.assert_array_equal(s, np.tril(s))
        np.testing.assert_allclose(s @ s.T, ckf.covariance, rtol=1e-15)


def test_normalized_innovations_are_chi_square_on_a_consistent_model(model):
    """Two measured outputs: E[NIS] = 2.  Measured over 400 steps, seeds 0-3: 1.93 to 2.15."""
    u, _, z = simulate(400, seed=2)
    ekf = build("EKF", model)
    nis = np.array([ekf.step(z[k], [u[k]]).nis for k in range(400)])
    assert 1.7 < nis[50:].mean() < 2.3


def test_variances_may_be_given_as_a_vector(model):
    u, _, z = simulate(5, seed=3)
    a = build("SCKF", model, process_noise=np.diag(Q), covariance=np.diag(P0))
    b = build("SCKF", model)
    for k in range(5):
        a.step(z[k], [u[k]])
        b.step(z[k], [u[k]])
    np.testing.assert_array_equal(a.mean, b.mean)


# ---------------------------------------------------------------- strong tracking


def fading_factors(f, u, z):
    return np.array([f.step(z[k], [u[k]]).fading for k in range(len(z))])


@pytest.mark.parametrize("name", ["EKF", "SCKF"])
def test_strong_tracking_equals_the_hand_written_strong_tracking_filter(model, name):
    """STEKF and STSCKF against eqs. 7-11 written out above, on a drifting bias (measured agreement 1e-14)."""
    u, _, z = simulate(150, seed=13, ramp=1e-2)
    means, covariances, factors = kalman(z, u, rho=0.95)
    f = build(name, model, fading=StrongTracking(forgetting=0.95))
    fading = np.array([f.step(z[k], [u[k]]).fading for k in range(150)])
    np.testing.assert_allclose(fading, factors, rtol=1e-10)
    np.testing.assert_allclose(f.mean, means[-1], rtol=1e-10)
    np.testing.assert_allclose(f.covariance, covariances[-1], rtol=1e-9)
    assert np.mean(factors > 1.0) > 0.25  # the factor mattered


@pytest.mark.parametrize("softening, share", [(1.0, 0.55), (3.0, 0.9)])
def test_fading_factor_is_mostly_one_on_a_consistent_model(model, softening, share):
    """Correct model and noises.  Measured share of steps with lambda = 1 over 400 steps (seeds 0-4):
    0.63-0.67 with beta = 1 (V_k weighs the newest innovation by 1 / (1 + rho) = 0.51, so tr V_k exceeds
    its mean tr P_zz about a third of the time), 0.955-0.975 with beta = 3."""
    u, _, z = simulate(400, seed=0)
    fading = fading_factors(build("SCKF", model, fading=StrongTracking(softening=softening)), u, z)
    assert np.all(fading >= 1.0)
    assert np.mean(fading == 1.0) >= share
    assert np.median(fading) == 1.0


@pytest.mark.parametrize("name, tolerance", [("SCKF", 1e-10), ("UKF-alpha1", 1e-10), ("UKF", 1e-6)])
def test_derivative_free_fading_equals_the_jacobian_form_on_a_linear_model(model, name, tolerance):
    """Eq. (17) H = P_xz^T P*^-1 recovers the Jacobian: STSCKF/STUKF and STEKF see the same lambda_k.

    Measured worst relative difference over these 200 steps: STSCKF and STUKF(alpha=1) 4e-14, STUKF(1e-3)
    2e-8; lambda_k > 1 at 40 % of the steps, up to 16.
    """
    u, _, z = simulate(200, seed=4, ramp=1e-2)  # the bias drifts while the filters assume a random walk
    stekf = build("EKF", model, fading=StrongTracking())
    other = build(name, model, fading=StrongTracking())
    fading = []
    for k in range(200):
        a, b = stekf.step(z[k], [u[k]]), other.step(z[k], [u[k]])
        assert b.fading == pytest.approx(a.fading, rel=tolerance)
        np.testing.assert_allclose(other.mean, stekf.mean, rtol=100 * tolerance, atol=1e-12)
        fading.append(a.fading)
    # the comparison is not trivial: the factor was active at many steps
    fading = np.array(fading)
    assert np.mean(fading > 1.0) > 0.25 and fading.max() > 5.0


@pytest.mark.slow
def test_strong_tracking_follows_a_drift_the_plain_filter_lags(model):
    """Bias ramp of 0.01 per step, random walk of std 1e-3 assumed.  Measured bias RMSE over the last 100 of
    200 steps: SCKF 0.51, STSCKF 0.12."""
    u, states, z = simulate(200, seed=5, ramp=1e-2)
    plain, tracking = build("SCKF", model), build("SCKF", model, fading=StrongTracking())
    capped = build("SCKF", model, fading=StrongTracking(max_factor=2.0))
    error, capped_fading = {"plain": [], "tracking": []}, []
    for k in range(200):
        plain.step(z[k], [u[k]])
        tracking.step(z[k], [u[k]])
        capped_fading.append(capped.step(z[k], [u[k]]).fading)
        error["plain"].append(plain.mean[2] - states[k, 2])
        error["tracking"].append(tracking.mean[2] - states[k, 2])
    rmse = {key: np.sqrt(np.mean(np.square(value[-100:]))) for key, value in error.items()}
    assert rmse["tracking"] < 0.5 * rmse["plain"]
    assert min(capped_fading) == 1.0 and max(capped_fading) == 2.0  # max_factor clips lambda_k


@pytest.fixture(scope="module")
def tank():
    return ThreeTanks


@pytest.mark.slow
def test_stsckf_tracks_the_az2_ramp_of_eq61_better_than_sckf(tank):
    """Du et al., section 6: az2 follows eq. (61), both filters assume az2_k = az2_{k-1} + d, std(d) = 1e-3.

    Measured az2 RMSE over k = 101..200 (seeds 0-5): SCKF 0.200-0.204, STSCKF 0.042-0.045; the fading
    factor reaches 8-21.
    """
    states, z = tank.simulate_tanks(0)
    assert states[-1, 3] > 2.0  # eq. (61): 0.6 + 1e-4 * sum(1..190)
    rmse, fading = {}, {}
    for name in ("SCKF", "STSCKF"):
        f = tank.estimator(name)
        assert f.process_noise[3, 3] == pytest.approx(1e-6)
        run = [(f.step(z[k], tank.INPUTS).fading, f.mean[3]) for k in range(z.shape[0])]
        fading[name] = np.array([r[0] for r in run])
        estimate = np.array([r[1] for r in run])
        rmse[name] = np.sqrt(np.mean((estimate[-100:] - states[-100:, 3]) ** 2))
    assert rmse["STSCKF"] < 0.35 * rmse["SCKF"]
    assert rmse["STSCKF"] < 0.08 and rmse["SCKF"] > 0.15
    assert np.all(fading["SCKF"] == 1.0)
    assert fading["STSCKF"].max() > 2.0 and np.all(fading["STSCKF"] >= 1.0)


# ---------------------------------------------------------------- square root over a long run


@pytest.fixture(scope="module")
def long_record(tank):
    return tank.simulate_tanks(3, drift=False, steps=10_000)


@pytest.mark.slow  # 10^4 filter steps: about 2.5 s each
@pytest.mark.parametrize("name", ["SCKF", "STSCKF"])
def test_square_root_stays_a_positive_definite_factor_over_ten_thousand_steps(tank, long_record, name):
    """Every one of 10^4 steps: S lower triangular with a positive diagonal, P = S S^T positive definite.

    Measured on 2 cores: 4.2 s (SCKF) and 5.8 s (STSCKF) for the 10^4 steps; the smallest
    eigenvalue of P stays about 2e-12 (volumes in m^3: level variances times A_s^2).
    """
    states, z = long_record
    f = tank.estimator(name)
    u = np.array([tank.INPUTS[signal] for signal in f.model.inputs])
    steps = z.shape[0]
    factors, fading = np.empty((steps, 4, 4)), np.empty(steps)
    for k in range(steps):
        fading[k] = f.step(z[k], u).fading
        factors[k] = f.sqrt_covariance
    upper = np.triu(np.ones((4, 4), bool), 1)
    bad = np.nonzero(np.any(factors[:, upper] != 0.0, axis=1))[0]
    assert bad.size == 0, f"S not lower triangular at steps {bad[:5] + 1}"
    diagonal = np.diagonal(factors, axis1=1, axis2=2)
    bad = np.nonzero(np.any(~(diagonal > 0.0), axis=1))[0]
    assert bad.size == 0, f"S has a non-positive diagonal entry at steps {bad[:5] + 1}"
    smallest = np.linalg.eigvalsh(factors @ factors.transpose(0, 2, 1)).min(axis=1)
    bad = np.nonzero(~(smallest > 0.0))[0]
    assert bad.size == 0, f"P = S S^T not positive definite at steps {bad[:5] + 1}: {smallest[bad[:5]]}"
    np.testing.assert_allclose(factors[-1] @ factors[-1].T, f.covariance, rtol=1e-15)
    assert np.linalg.eigvalsh(f.covariance).min() > 0.0
    assert np.all(np.isfinite(f.mean)) and abs(f.mean[3] - 0.6) < 0.05
    np.testing.assert_allclose(f.mean[:3], states[-1, :3], rtol=1e-3)
    assert np.any(fading > 1.0) == (name == "STSCKF")


# ---------------------------------------------------------------- missing measurements


@pytest.mark.parametrize("name", ["EKF", "UKF", "SCKF", "ST-SCKF", "PF"])
def test_all_nan_measurement_skips_the_update(model, name):
    if name == "PF":
        f = BootstrapParticleFilter(model, X0, P0, Q, R, n_particles=200, seed=0)
    else:
        f = build(name.removeprefix("ST-"), model, fading=StrongTracking() if name.startswith("ST") else None)
    u, _, z = simulate(3, seed=6)
    f.step(z[0], [u[0]])
    f.predict([u[1]])
    mean, covariance = f.mean, f.covariance
    innovation = f.update([np.nan, np.nan])
    np.testing.assert_array_equal(f.mean, mean)
    np.testing.assert_array_equal(f.covariance, covariance)
    assert np.all(np.isnan(innovation.residual)) and np.all(np.isnan(innovation.covariance))
    assert np.isnan(innovation.nis) and innovation.fading == 1.0
    # step() with no measurement is a prediction only
    twin = f.copy()
    f.step([np.nan, np.nan], [u[2]])
    twin.predict([u[2]])
    np.testing.assert_array_equal(f.mean, twin.mean)


@pytest.mark.parametrize("name", ["EKF", "UKF-alpha1", "SCKF"])
@pytest.mark.parametrize("kept", [0, 1])
def test_partly_nan_measurement_updates_with_the_finite_rows(model, name, kept):
    """z with one NaN row updates like a filter on the model that measures the other output only, with R
    restricted to it (R is correlated: for the second output the restriction is not a block of chol(R))."""
    output = model.outputs[kept]
    reduced = discretize(OSCILLATOR, dt=DT, augment=["b"], outputs=[output])
    full = build(name, model)
    part = build(name, reduced, measurement_noise=R[kept:kept + 1, kept:kept + 1])
    dropped = 1 - kept
    u, _, z = simulate(15, seed=7)
    for k in range(15):
        full.predict([u[k]])
        part.predict([u[k]])
        before = full.covariance
        measurement = z[k].copy()
        measurement[dropped] = np.nan
        a = full.update(measurement)
        b = part.update(z[k, kept:kept + 1])
        np.testing.assert_allclose(full.mean, part.mean, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(full.covariance, part.covariance, rtol=1e-10, atol=1e-16)
        assert a.residual[kept] == pytest.approx(b.residual[0], rel=1e-10) and np.isnan(a.residual[dropped])
        assert np.isnan(a.covariance[dropped]).all() and np.isnan(a.covariance[:, dropped]).all()
        assert a.covariance[kept, kept] == pytest.approx(b.covariance[0, 0], rel=1e-10)
        assert a.nis == pytest.approx(b.nis, rel=1e-8)
        assert full.covariance[kept, kept] < before[kept, kept]  # the measured output's state is tightened
    # and differs from a full update (the other row really was left out)
    other = build(name, model)
    for k in range(15):
        other.step(z[k], [u[k]])
    assert abs(other.mean[dropped] - full.mean[dropped]) > 1e-4


def test_unscented_and_cubature_rules_on_a_square():
    """x_k = x_{k-1}^2 with x ~ N(m, P): Var = 4 m^2 P + 2 P^2.  The scaled UT with beta = 2 is exact for any
    alpha; the third-degree cubature rule misses the 2 P^2 term.  Both get the mean m^2 + P."""
    x = sp.Symbol("x")
    square = SimpleNamespace(states=[x], rhs=[x ** 2 - x], inputs=[], outputs={"y": x}, parameters={})
    model = discretize(square, dt=1.0)
    m, p, q = 1.5, 0.2, 1e-3
    for alpha in (1e-3, 0.5, 1.0):
        ukf = UnscentedKalmanFilter(model, [m], [[p]], [[q]], [[1.0]], alpha=alpha)
        ukf.predict()
        assert ukf.mean[0] == pytest.approx(m ** 2 + p, rel=1e-8)
        assert ukf.covariance[0, 0] == pytest.approx(4 * m ** 2 * p + 2 * p ** 2 + q, rel=1e-6)
    ckf = CubatureKalmanFilter(model, [m], [[p]], [[q]], [[1.0]])
    ckf.predict()
    assert ckf.mean[0] == pytest.approx(m ** 2 + p, rel=1e-12)
    assert ckf.covariance[0, 0] == pytest.approx(4 * m ** 2 * p + q, rel=1e-12)
    ekf = ExtendedKalmanFilter(model, [m], [[p]], [[q]], [[1.0]])
    ekf.predict()
    assert ekf.mean[0] == m ** 2 and ekf.covariance[0, 0] == pytest.approx(4 * m ** 2 * p + q, rel=1e-12)


# ---------------------------------------------------------------- validation


def test_constructor_validation_names_what_is_wrong(model):
    with pytest.raises(ValueError, match=r"mean: expected 3 values for \['p', 'v', 'b'\], got shape \(2,\)"):
        build("SCKF", model, mean=[1.0, 0.0])
    with pytest.raises(ValueError, match=r"mean: non-finite value for \['v'\]"):
        build("EKF", model, mean=[1.0, np.nan, 0.0])
    with pytest.raises(ValueError, match=r"process_noise \(Q\): negative variance for \['v'\]"):
        build("SCKF", model, process_noise=np.diag([1e-6, -1e-6, 1e-6]))
    with pytest.raises(ValueError, match=r"process_noise \(Q\): not symmetric"):
        build("UKF", model, process_noise=np.array([[1.0, 0.1, 0], [0, 1.0, 0], [0, 0, 1.0]]))
    with pytest.raises(ValueError, match=r"covariance \(P0\): not positive semi-definite"):
        build("EKF", model, covariance=np.array([[1.0, 2.0, 0], [2.0, 1.0, 0], [0, 0, 1.0]]))
    with pytest.raises(ValueError, match=r"measurement_noise \(R\): expected a \(2, 2\) matrix or 2 variances "
                                         r"for \['y', 's'\], got shape \(3, 3\)"):
        build("SCKF", model, measurement_noise=np.eye(3))
    with pytest.raises(ValueError, match=r"measurement_noise \(R\): not positive semi-definite"):
        build("SCKF", model, measurement_noise=[[1.0, 2.0], [2.0, 1.0]])
    for cls in (ExtendedKalmanFilter, UnscentedKalmanFilter, CubatureKalmanFilter):
        with pytest.raises(ValueError, match=r"measurement_noise \(R\) must be positive definite"):
            cls(model, X0, P0, Q, [[1.0, 1.0], [1.0, 1.0]])  # semi-definite is not enough for R
    with pytest.raises(ValueError, match="alpha must be positive"):
        UnscentedKalmanFilter(model, X0, P0, Q, R, alpha=0.0)
    with pytest.raises(ValueError, match="n \\+ lambda"):
        UnscentedKalmanFilter(model, X0, P0, Q, R, alpha=1.0, kappa=-3.0)
    f = build("EKF", model)
    with pytest.raises(ValueError, match=r"z: expected 2 values for \['y', 's'\], got shape \(3,\)"):
        f.update([1.0, 2.0, 3.0])


def test_strong_tracking_validation():
    for forgetting in (0.0, -0.5, 1.5):
        with pytest.raises(ValueError, match=r"forgetting \(rho\) must be in \(0, 1\]"):
            StrongTracking(forgetting=forgetting)
    with pytest.raises(ValueError, match=r"softening \(beta\) must be >= 1, got 0.5"):
        StrongTracking(softening=0.5)
    with pytest.raises(ValueError, match="max_factor must be >= 1"):
        StrongTracking(max_factor=0.5)
    assert StrongTracking(forgetting=1.0).forgetting == 1.0


def test_strong_tracking_state_is_per_filter(model):
    shared = StrongTracking()
    u, _, z = simulate(10, seed=8, ramp=1e-2)
    a, b = build("SCKF", model, fading=shared), build("SCKF", model, fading=shared)
    for k in range(10):
        a.step(z[k], [u[k]])
    assert shared._v is None and b.fading._v is None and a.fading._v is not None


# ---------------------------------------------------------------- tria and psd_sqrt


@pytest.mark.parametrize("rows, columns", [(3, 7), (4, 4), (5, 2), (1, 3), (4, 1)])
def test_tria_is_a_lower_triangular_factor(rows, columns):
    c = np.random.default_rng(rows * 10 + columns).standard_normal((rows, columns))
    s = tria(c)
    assert s.shape == (rows, rows)
    np.testing.assert_allclose(s @ s.T, c @ c.T, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(np.triu(s, 1), 0.0)
    assert np.all(np.diag(s) >= 0.0)
    if columns < rows:  # rank deficient: the trailing columns of S are zero
        np.testing.assert_allclose(s[:, columns:], 0.0, atol=1e-12)


def test_tria_accepts_nested_lists():
    s = tria([[3.0, 4.0], [0.0, 2.0]])
    np.testing.assert_allclose(s @ s.T, [[25.0, 8.0], [8.0, 4.0]], rtol=1e-14)
    assert s[0, 1] == 0.0 and s[0, 0] == pytest.approx(5.0)


def test_psd_sqrt_of_definite_and_semidefinite_matrices():
    p = np.array([[4.0, 2.0], [2.0, 3.0]])
    np.testing.assert_allclose(psd_sqrt(p), np.linalg.cholesky(p))
    singular = np.array([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    root = psd_sqrt(singular)
    np.testing.assert_allclose(root @ root.T, singular, atol=1e-14)
    assert np.all(np.isfinite(root))


# ---------------------------------------------------------------- UKF repair


def test_ukf_repairs_an_indefinite_covariance_with_a_warning(model):
    ukf = build("UKF", model)
    ukf._p = np.diag([1e-2, 1e-2, -1e-14])  # what rounding can leave after a subtraction
    with pytest.warns(FilterWarning, match=r"UKF covariance was not positive definite \(smallest eigenvalue -1e-14\)"):
        ukf.predict([0.0])
    assert np.all(np.isfinite(ukf.mean)) and np.linalg.eigvalsh(ukf.covariance).min() > 0


def test_ukf_with_a_singular_initial_covariance_warns_and_runs(model):
    ukf = build("UKF", model, covariance=np.diag([0.05, 0.05, 0.0]))  # b known exactly: P0 is singular
    with pytest.warns(FilterWarning, match="UKF covariance was not positive definite"):
        ukf.predict([0.0])
    u, _, z = simulate(5, seed=9)
    ukf.update(z[0], [u[0]])
    assert np.all(np.isfinite(ukf.mean)) and np.all(np.isfinite(ukf.covariance))


# ---------------------------------------------------------------- bootstrap particle filter

PF_Q = np.diag([1e-4, 1e-4, 1e-4])  # enough process noise that 5000 particles do not collapse in 30 steps


def test_particle_filter_agrees_with_the_kalman_filter(model):
    """Measured over seeds 0-9 at k = 30: |mean - KF| at most 0.23 posterior std, std ratio 0.95-1.05."""
    u, _, z = simulate(30, seed=10, q=PF_Q)
    means, covariances = kalman(z, u, q=PF_Q)
    pf = BootstrapParticleFilter(model, X0, P0, PF_Q, R, n_particles=5000, seed=0)
    for k in range(30):
        innovation = pf.step(z[k], [u[k]])
        assert np.isfinite(innovation.nis)
    sd = np.sqrt(np.diag(covariances[-1]))
    assert np.all(np.abs(pf.mean - means[-1]) < 0.5 * sd)
    assert np.all(np.abs(np.sqrt(np.diag(pf.covariance)) / sd - 1.0) < 0.15)
    assert pf.degenerate_steps == 0 and pf.n_particles == 5000


def test_particle_filter_is_reproducible_and_its_copy_independent(model):
    u, _, z = simulate(12, seed=11, q=PF_Q)
    a = BootstrapParticleFilter(model, X0, P0, PF_Q, R, n_particles=500, seed=3)
    b = BootstrapParticleFilter(model, X0, P0, PF_Q, R, n_particles=500, seed=3)
    c = BootstrapParticleFilter(model, X0, P0, PF_Q, R, n_particles=500, seed=4)
    for k in range(6):
        for f in (a, b, c):
            f.step(z[k], [u[k]])
    np.testing.assert_array_equal(a.mean, b.mean)
    assert not np.array_equal(a.mean, c.mean)
    twin = a.copy()
    mean, particles, weights = a.mean, a.particles.copy(), a.weights
    for k in range(6, 12):
        twin.step(z[k], [u[k]])
    np.testing.assert_array_equal(a.mean, mean)
    np.testing.assert_array_equal(a.particles, particles)
    np.testing.assert_array_equal(a.weights, weights)
    assert not np.array_equal(twin.mean, mean)
    # the copy continues the random stream: stepping the original now repeats the twin
    for k in range(6, 12):
        a.step(z[k], [u[k]])
    np.testing.assert_array_equal(a.mean, twin.mean)


def test_particle_filter_survives_a_wildly_wrong_measurement(model):
    u, _, z = simulate(3, seed=12, q=PF_Q)
    pf = BootstrapParticleFilter(model, X0, P0, PF_Q, R, n_particles=500, seed=5)
    pf.step(z[0], [u[0]])
    pf.predict([u[1]])
    with np.errstate(over="ignore"):
        innovation = pf.update([1e200, z[1, 1]])  # every likelihood underflows to zero
    assert pf.degenerate_steps == 1
    np.testing.assert_allclose(pf.weights, 1.0 / 500)
    assert np.all(np.isfinite(pf.log_weights)) and np.all(np.isfinite(pf.particles))
    assert not np.isnan(innovation.nis) and not np.any(np.isnan(innovation.residual))
    # far off but not underflowing: one particle takes the weight, still no NaN, not degenerate
    pf.predict([u[2]])
    pf.update([50.0, z[2, 1]])
    assert pf.degenerate_steps == 1
    assert np.all(np.isfinite(pf.log_weights)) and np.all(np.isfinite(pf.mean))
    assert pf.weights.sum() == pytest.approx(1.0)


def test_particle_filter_validation(model):
    with pytest.raises(ValueError, match="n_particles must be at least 2"):
        BootstrapParticleFilter(model, X0, P0, PF_Q, R, n_particles=1)
    with pytest.raises(ValueError, match=r"mean: expected 3 values for \['p', 'v', 'b'\]"):
        BootstrapParticleFilter(model, X0[:2], P0, PF_Q, R)
    with pytest.raises(ValueError, match=r"measurement_noise \(R\) must be positive definite"):
        BootstrapParticleFilter(model, X0, P0, PF_Q, [[1.0, 1.0], [1.0, 1.0]])
    pf = BootstrapParticleFilter(model, X0, P0, PF_Q, R, n_particles=10)
    with pytest.raises(ValueError, match=r"z: expected 2 values for \['y', 's'\], got shape \(1,\)"):
        pf.update([1.0])


# ---------------------------------------------------------------- look-ahead

STEPS, HORIZON, START = 40, 4, 10


def noiseless():
    """A noiseless record and per-step inputs (so that a misaligned input index shows)."""
    u, states, z = simulate(STEPS, seed=0, noise=False)
    return [np.array([v]) for v in u], states, z


LOOKAHEAD_FILTERS = {
    "EKF": lambda m: build("EKF", m),
    "STSCKF": lambda m: build("SCKF", m, fading=StrongTracking()),
    "PF": lambda m: BootstrapParticleFilter(m, X0, P0, PF_Q, R, n_particles=300, seed=1),
}


@pytest.mark.parametrize("name", list(LOOKAHEAD_FILTERS))
def test_predict_ahead_on_true_forecasts_equals_the_filter_that_saw_them(model, name):
    inputs, _, z = noiseless()
    run = predict_ahead(LOOKAHEAD_FILTERS[name](model), z, horizon=HORIZON, start=START,
                        forecasts=lambda k: z[k:k + HORIZON], inputs=inputs)
    np.testing.assert_array_equal(run.origin, np.arange(START, STEPS - HORIZON + 1))
    np.testing.assert_array_equal(run.target, run.origin + HORIZON)
    assert run.predicted.shape == (STEPS - HORIZON - START + 1, 3) and run.filtered.shape == (STEPS, 3)
    assert run.fading.shape == run.nis.shape == (STEPS,) and run.seconds > 0
    # the copy that stepped through z_{k+1..k+n} ends where the real filter is at k + n
    np.testing.assert_allclose(run.predicted, run.filtered[run.target - 1], rtol=1e-12, atol=1e-15)
    # and the real run is the plain filter's run: look-aheads never touched it
    plain = LOOKAHEAD_FILTERS[name](model)
    alone = np.array([(plain.step(z[k], inputs[k]), plain.mean)[1] for k in range(STEPS)])
    np.testing.assert_array_equal(run.filtered, alone)


def test_look_ahead_leaves_the_filter_alone_and_uses_the_future_inputs(model):
    inputs, _, z = noiseless()
    main = build("SCKF", model, fading=StrongTracking())
    k = 15
    for j in range(k):
        main.step(z[j], inputs[j])
    mean, covariance, memory = main.mean, main.covariance, main.fading._v.copy()
    means = look_ahead(main, z[k:k + HORIZON], inputs[k:k + HORIZON])
    assert means.shape == (HORIZON, 3)
    np.testing.assert_array_equal(main.mean, mean)
    np.testing.assert_array_equal(main.covariance, covariance)
    np.testing.assert_array_equal(main.fading._v, memory)
    for j in range(k, k + HORIZON):
        main.step(z[j], inputs[j])
        np.testing.assert_allclose(means[j - k], main.mean, rtol=1e-12, atol=1e-15)
    # with the inputs shifted by one step the look-ahead lands elsewhere
    shifted = look_ahead(main, z[k + HORIZON:k + 2 * HORIZON], inputs[k + HORIZON + 1:k + 2 * HORIZON + 1])
    right = look_ahead(main, z[k + HORIZON:k + 2 * HORIZON], inputs[k + HORIZON:k + 2 * HORIZON])
    assert np.abs(shifted[-1] - right[-1]).max() > 1e-4
    # a mapping holds for every step
    constant = look_ahead(main, z[k:k + 2], {"F": 0.5})
    twin = main.copy()
    twin.step(z[k], [0.5])
    twin.step(z[k + 1], [0.5])
    np.testing.assert_allclose(constant[-1], twin.mean, rtol=1e-12)


def test_predict_ahead_errors(model):
    inputs, _, z = noiseless()

    def run(**options):
        settings = {"horizon": HORIZON, "start": START, "forecasts": lambda k: z[k:k + HORIZON], "inputs": inputs,
                    **options}
        return predict_ahead(build("EKF", model), settings.pop("measurements", z), **settings)

    with pytest.raises(ValueError, match=r"start must be in \[1, 36\] for 40 measurements and horizon 4, got 0"):
        run(start=0)
    with pytest.raises(ValueError, match=r"start must be in \[1, 36\].*got 37"):
        run(start=37)
    assert run(start=36).origin.tolist() == [36]
    for horizon in (0, -2):
        with pytest.raises(ValueError, match=f"horizon must be at least 1 step, got {horizon}"):
            run(horizon=horizon)
    with pytest.raises(ValueError, match=r"forecasts\(10\) returned shape \(3, 2\), expected \(4, 2\)"):
        run(forecasts=lambda k: z[k:k + HORIZON - 1])
    with pytest.raises(ValueError, match=r"forecasts\(10\) returned shape \(4,\), expected \(4, 2\)"):
        run(forecasts=lambda k: z[k:k + HORIZON, 0])
    with pytest.raises(ValueError, match=r"measurements: expected shape \(K, m\), got \(40,\)"):
        run(measurements=z[:, 0])
