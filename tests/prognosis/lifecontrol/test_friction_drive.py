"""The friction drive of Rodriguez Obando et al. (2021): bond graph, energy deterioration, EKF pieces, Chebyshev
bounds, innovation consistency, Monte Carlo RUL, RUL control (examples/friction_drive.py runs in tests/cases).

Expected values come from the paper's equations written by hand, closed forms or brute force.
"""

import warnings

import numpy as np
import pytest
import sympy as sp
from scipy import stats

from bondgraph.errors import PHMWarning
from bondgraph.library import friction_drive, rlc_circuit
from prognosis import RULDistribution
from prognosis.lifecontrol import (RULController, RULControlWarning, chebyshev_bounds, chebyshev_intervals,
                                   chebyshev_level, chebyshev_scale, covariance_from_bounds, energy_deterioration,
                                   monte_carlo_rul, sample_gaussian)
from prognosis.statespace import (ExtendedKalmanFilter, InnovationMonitor, StrongTracking, discretize,
                                  innovation_consistency, whiten)
from tests.scenarios import FrictionDriveRUL

J1, B1, r1, alpha, r2, J2, B2 = sp.symbols("J1 B1 r1 alpha r2 J2 B2")
w1, w2, m, D = sp.symbols("omega1 omega2 m D")
TM = sp.Function("T_m")(sp.Symbol("t"))
TABLE_1 = {"r1": 0.0315, "r2": 0.35, "B1": 6.36e-3, "B2": 0.6250, "J1": 9.9225e-04, "J2": 12.25}
STATES = ("omega1", "omega2", "alpha", "m", "D")


def is_zero(expression) -> bool:
    return sp.simplify(sp.expand(expression)) == 0


@pytest.fixture(scope="module")
def speeds():
    """State equations of the friction drive in the speeds omega1, omega2."""
    return friction_drive().state_equations().coenergy_states({"J1": "omega1", "J2": "omega2"})


@pytest.fixture(scope="module")
def augmented(speeds):
    return energy_deterioration(speeds, "alpha", rate_value=1e-6)


@pytest.fixture(scope="module")
def fd():
    return FrictionDriveRUL


# -- 1. bond graph ----------------------------------------------------------------------------------------


def test_friction_drive_state_equations_are_eq_13(speeds):
    a = sp.Matrix([[(-alpha * r1 ** 2 - B1) / J1, alpha * r1 * r2 / J1],
                   [alpha * r2 * r1 / J2, (-alpha * r2 ** 2 - B2) / J2]])  # eq. 13 / 20
    b = sp.Matrix([1 / J1, 0])  # eq. 21
    expected = a * sp.Matrix([w1, w2]) + b * TM
    assert [str(s) for s in speeds.states] == ["omega1", "omega2"]
    assert speeds.inputs == ["T_m"]
    for got, want in zip(speeds.rhs, expected):
        assert is_zero(got - want), (got, want)
    # the nominal values are Table 1's, and a builder argument reaches the equations
    for name, value in TABLE_1.items():
        assert float(speeds.parameters[name]) == pytest.approx(value, rel=1e-12)
    assert float(friction_drive(alpha=4.5, J2=3.0).state_equations().parameters["alpha"]) == 4.5


def test_momentum_states_give_the_same_dynamics():
    """In the energy variables p = J omega the equations are J * (eq. 13) with omega = p / J."""
    eqs = friction_drive().state_equations()
    p1, p2 = eqs.states
    assert [str(p1), str(p2)] == ["p_J1", "p_J2"]
    v1, v2 = p1 / J1, p2 / J2
    assert is_zero(eqs.rhs[0] - (TM - B1 * v1 - alpha * r1 * (r1 * v1 - r2 * v2)))
    assert is_zero(eqs.rhs[1] - (-B2 * v2 + alpha * r2 * (r1 * v1 - r2 * v2)))
    assert is_zero(eqs.power("alpha") - alpha * (r1 * v1 - r2 * v2) ** 2)


def test_contact_power_is_eqs_6_7_and_power_balances(speeds):
    p = (r1 * w1 - r2 * w2) ** 2  # eq. 7
    assert is_zero(speeds.power("alpha") - alpha * p)  # eq. 6: P_c = F_c v = alpha p(omega)
    assert is_zero(speeds.power("B1") - B1 * w1 ** 2)
    assert is_zero(speeds.power("B2") - B2 * w2 ** 2)
    assert is_zero(speeds.power("T_m") + TM * w1)  # power *into* the source: minus what it delivers
    # storage: power into J is d/dt (J omega^2 / 2) along the state equations
    assert is_zero(speeds.power("J1") - J1 * w1 * speeds.rhs[0])
    assert is_zero(speeds.power("J2") - J2 * w2 * speeds.rhs[1])
    kinetic_rate = J1 * w1 * speeds.rhs[0] + J2 * w2 * speeds.rhs[1]
    balance = TM * w1 - B1 * w1 ** 2 - B2 * w2 ** 2 - alpha * p - kinetic_rate
    assert is_zero(balance)
    # the junction structure is power-conserving: the powers into all one-ports sum to zero
    assert set(speeds.ports) == {"T_m", "J1", "B1", "alpha", "J2", "B2"}
    assert is_zero(sum(speeds.power(name) for name in speeds.ports))


def test_power_of_a_non_one_port_raises_key_error_naming_it(speeds):
    for name in ("0_c", "1_1", "TF_2", "nothing"):
        with pytest.raises(KeyError, match=name):
            speeds.power(name)


@pytest.mark.slow
def test_coenergy_states_of_the_rlc_circuit():
    i, v_c, R, L, C = sp.symbols("i v_C R L C")
    V = sp.Function("V")(sp.Symbol("t"))
    eqs = rlc_circuit().state_equations().coenergy_states({"L": "i", "C": "v_C"})
    assert eqs.states == [i, v_c]
    assert is_zero(eqs.rhs[0] - (V - R * i - v_c) / L)
    assert is_zero(eqs.rhs[1] - i / C)
    assert is_zero(eqs.power("R") - R * i ** 2)
    # default names: f_<I>, e_<C>
    default = rlc_circuit().state_equations().coenergy_states()
    assert [str(s) for s in default.states] == ["f_L", "e_C"]
    f_l, e_c = default.states
    assert is_zero(default.rhs[1] - f_l / C)


def test_coenergy_states_rejects_an_unknown_element():
    eqs = rlc_circuit().state_equations()
    with pytest.raises(KeyError, match="Lx"):
        eqs.coenergy_states({"Lx": "i"})
    with pytest.raises(KeyError, match="R"):  # a one-port, but no storage state
        eqs.coenergy_states({"R": "i"})


# -- 2. energy deterioration ------------------------------------------------------------------------------


def test_energy_deterioration_appends_eqs_17_to_19(speeds, augmented):
    p = (r1 * w1 - r2 * w2) ** 2
    assert [str(s) for s in augmented.states] == list(STATES)
    for got, want in zip(augmented.rhs[:2], speeds.rhs):  # eq. 16 unchanged
        assert is_zero(got - want)
    assert is_zero(augmented.rhs[2] - (-m * alpha * p))  # eq. 17 with eps = 0
    assert augmented.rhs[3] == 0  # eq. 18
    assert is_zero(augmented.rhs[4] - alpha * p)  # eq. 19
    assert is_zero(augmented.power - alpha * p)
    assert "alpha" not in augmented.parameters
    assert set(augmented.parameters) == set(TABLE_1)
    assert augmented.nominal == {"alpha": 11.0, "m": 1e-6}
    assert (augmented.coefficient, augmented.rate, augmented.energy) == ("alpha", "m", "D")
    # D - D0 = (alpha0 - alpha)/m along any trajectory (eq. 10): d(alpha + m D)/dt = 0
    assert is_zero(augmented.rhs[2] + m * augmented.rhs[4])


def test_energy_deterioration_custom_names_and_default_coefficient(speeds):
    custom = energy_deterioration(speeds, "alpha", rate="k", energy="E")
    assert [str(s) for s in custom.states] == ["omega1", "omega2", "alpha", "k", "E"]
    assert is_zero(custom.rhs[2] + sp.Symbol("k") * custom.rhs[4])
    # a viscous damper: its own parameter decays with the energy it dissipates
    damper = energy_deterioration(speeds, "B1")
    assert damper.coefficient == "B1" and is_zero(damper.rhs[4] - B1 * w1 ** 2)
    assert "B1" not in damper.parameters and "alpha" in damper.parameters


@pytest.mark.parametrize("kwargs, name", [
    ({"coefficient": "beta"}, "beta"),          # not a parameter
    ({"coefficient": "B1"}, "B1"),              # the contact power does not depend on B1
    ({"rate": "omega1"}, "omega1"),             # clashes with a state
    ({"energy": "J2"}, "J2"),                   # clashes with a parameter
    ({"rate": "alpha"}, "alpha"),               # clashes with the coefficient
    ({"energy": "alpha"}, "alpha"),
    ({"rate": "E", "energy": "E"}, "E"),        # the two new states would share a name
])
def test_energy_deterioration_rejects_bad_names(speeds, kwargs, name):
    with pytest.raises(ValueError, match=f"'{name}'"):
        energy_deterioration(speeds, "alpha", **kwargs)


# -- 3. discretization and Jacobians -----------------------------------------------------------------------

X_POINT = np.array([55.0, 18.0, 8.0, 2e-6, 1.5e5])
U_POINT = [0.05]


def test_substeps_equal_repeated_small_euler_steps(augmented):
    model = discretize(augmented, dt=1.0, method="euler", substeps=10)
    assert model.substeps == 10 and model.substep == pytest.approx(0.1)
    x = X_POINT.copy()
    for _ in range(10):
        x = x + 0.1 * model.rates(x, U_POINT)
    np.testing.assert_allclose(model.transition(X_POINT, U_POINT), x, rtol=1e-12, atol=0)
    # vectorized over columns
    columns = np.column_stack([X_POINT, X_POINT * 1.01])
    out = model.transition(columns, U_POINT)
    np.testing.assert_allclose(out[:, 0], x, rtol=1e-12)
    np.testing.assert_allclose(out[:, 1], model.transition(X_POINT * 1.01, U_POINT), rtol=1e-12)
    state, _ = model.transition_with_jacobian(X_POINT, U_POINT)
    np.testing.assert_allclose(state, x, rtol=1e-12)


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_transition_jacobian_matches_central_differences(augmented, method):
    model = discretize(augmented, dt=1.0, method=method, substeps=10)
    state, jac = model.transition_with_jacobian(X_POINT, U_POINT)
    np.testing.assert_allclose(state, model.transition(X_POINT, U_POINT), rtol=1e-12)
    np.testing.assert_allclose(model.transition_jacobian(X_POINT, U_POINT), jac, rtol=1e-12)
    scale = np.abs(X_POINT)
    fd = np.empty((5, 5))
    for j in range(5):
        h = 1e-4 * scale[j]
        up, down = X_POINT.copy(), X_POINT.copy()
        up[j] += h
        down[j] -= h
        fd[:, j] = (model.transition(up, U_POINT) - model.transition(down, U_POINT)) / (2 * h)
    # compare in scaled coordinates (states span 1e-6 .. 1e5): J_ij x_j / x_i
    scaled, scaled_fd = jac * scale / scale[:, None], fd * scale / scale[:, None]
    np.testing.assert_allclose(scaled, scaled_fd, rtol=1e-5, atol=1e-5 * np.abs(scaled_fd).max())


def test_continuous_jacobian_is_eq_31(augmented):
    model = discretize(augmented, dt=1.0, method="euler", substeps=1)
    x = X_POINT
    _, jac = model.transition_with_jacobian(x, U_POINT)
    f = jac - np.eye(5)  # Euler, one substep of dt = 1: F_k = I + dt F
    o1, o2, a, mm, _ = x
    p = TABLE_1
    v = p["r1"] * o1 - p["r2"] * o2
    expected = np.zeros((5, 5))
    expected[0, :3] = [-(a * p["r1"] ** 2 + p["B1"]) / p["J1"], a * p["r1"] * p["r2"] / p["J1"],
                       (p["r1"] * p["r2"] * o2 - p["r1"] ** 2 * o1) / p["J1"]]
    expected[1, :3] = [a * p["r1"] * p["r2"] / p["J2"], -(a * p["r2"] ** 2 + p["B2"]) / p["J2"],
                       (p["r1"] * p["r2"] * o1 - p["r2"] ** 2 * o2) / p["J2"]]
    expected[2, :4] = [-2 * a * mm * p["r1"] * v, 2 * a * mm * p["r2"] * v, -mm * v ** 2, -a * v ** 2]
    expected[4, :3] = [2 * a * p["r1"] * v, -2 * a * p["r2"] * v, v ** 2]
    tolerance = 1e-12 * np.maximum(1.0, np.abs(expected))  # (I + F) - I keeps ~1e-16 absolute accuracy
    assert np.all(np.abs(f - expected) <= tolerance + 1e-9 * np.abs(expected)), f - expected


@pytest.mark.parametrize("substeps", [0, 1.5, -2, True])
def test_substeps_must_be_a_positive_integer(augmented, substeps):
    with pytest.raises(ValueError, match="substeps"):
        discretize(augmented, dt=1.0, substeps=substeps)


def test_ekf_reinitialize_restarts_from_the_new_estimate(augmented):
    model = discretize(augmented, dt=1.0, method="euler", substeps=10)
    p0 = np.diag([5.29, 0.04, 0.25, 1e-14, 2.5e9])
    q, r = np.diag([0.1, 0.001, 0, 0, 0]), np.diag([33.33, 0.33])
    ekf = ExtendedKalmanFilter(model, [0, 0, 11, 1.1e-6, 0], p0, q, r, fading=StrongTracking())
    for _ in range(5):
        ekf.step([1.0, 0.1], U_POINT)
    mean = ekf.mean
    p_new = np.diag([1.0, 2.0, 0.04, 4e-14, 1e8])
    ekf.reinitialize(covariance=p_new)
    np.testing.assert_array_equal(ekf.mean, mean)  # the estimate is kept
    np.testing.assert_array_equal(ekf.covariance, p_new)
    assert ekf.fading._v is None  # strong tracking starts afresh
    ekf.predict(U_POINT)  # P = F P_new F^T + Q from the new covariance
    state, f = model.transition_with_jacobian(mean, U_POINT)
    np.testing.assert_allclose(ekf.mean, state, rtol=1e-12)
    expected = f @ p_new @ f.T + q
    np.testing.assert_allclose(ekf.covariance, 0.5 * (expected + expected.T), rtol=1e-9,
                               atol=1e-12 * np.abs(expected).max())
    new_mean = np.array([1.0, 2.0, 9.0, 2e-6, 10.0])
    ekf.reinitialize(mean=new_mean)
    np.testing.assert_array_equal(ekf.mean, new_mean)
    with pytest.raises(ValueError):
        ekf.reinitialize(mean=[1.0, 2.0])
    with pytest.raises(ValueError):
        ekf.reinitialize(covariance=np.eye(4))


# -- 4. Chebyshev bounds -----------------------------------------------------------------------------------


def test_covariance_from_the_seed_bounds_eq_57():
    bounds = [23.0, 2.0, 5.0, 1e-6, 5e5]
    p0 = covariance_from_bounds(bounds, c=10.0)
    expected = [(23 / 10) ** 2, (2 / 10) ** 2, (5 / 10) ** 2, (1e-6 / 10) ** 2, (5e5 / 10) ** 2]
    assert np.allclose(np.diag(p0), [5.29, 0.04, 0.25, 1e-14, 2.5e9], rtol=1e-12, atol=0)  # eq. 58, D corrected
    np.testing.assert_allclose(np.diag(p0), expected, rtol=1e-12)
    assert np.count_nonzero(p0 - np.diag(np.diag(p0))) == 0
    np.testing.assert_allclose(chebyshev_bounds(p0, 10.0), bounds, rtol=1e-12)
    low, high = chebyshev_intervals([0, 0, 11, 1.1e-6, 0], p0, 10.0)
    np.testing.assert_allclose(low, [-23, -2, 6, 1e-7, -5e5], rtol=1e-12)
    np.testing.assert_allclose(high, [23, 2, 16, 2.1e-6, 5e5], rtol=1e-12)
    # a stack of covariances
    stack = np.stack([p0, 4 * p0])
    np.testing.assert_allclose(chebyshev_bounds(stack, 10.0), [bounds, 2 * np.array(bounds)], rtol=1e-12)


def test_chebyshev_level_and_scale_are_inverse():
    assert chebyshev_level(5, 10.0) == pytest.approx(0.95, abs=1e-15)
    assert chebyshev_level(5, 2.0) == 0.0  # 1 - 5/4 < 0: clipped
    assert chebyshev_scale(5, 0.95) == pytest.approx(10.0, rel=1e-12)
    for n, c in [(1, 1.5), (2, 3.0), (5, 7.0), (9, 30.0)]:
        assert chebyshev_scale(n, chebyshev_level(n, c)) == pytest.approx(c, rel=1e-12)
        assert chebyshev_level(n, c) == pytest.approx(1 - n / c ** 2, rel=1e-12)


def _random_spd(rng, n):
    a = rng.normal(size=(n, n))
    scales = 10.0 ** rng.uniform(-3, 3, size=n)
    return (a @ a.T + 0.1 * np.eye(n)) * np.outer(scales, scales)


@pytest.mark.parametrize("family", ["gaussian", "student3"])
def test_chebyshev_box_probability_holds_for_any_distribution(family):
    rng = np.random.default_rng(2024 if family == "gaussian" else 7)
    n, count = 5, 40_000
    p = _random_spd(rng, n)
    lower = np.linalg.cholesky(p)
    z = rng.standard_normal((count, n))
    if family == "student3":  # multivariate t, 3 dof, scaled so that its covariance is P
        dof = 3.0
        z = z * np.sqrt((dof - 2) / rng.chisquare(dof, size=(count, 1)))
    errors = z @ lower.T
    inverse = np.linalg.inv(p)
    quadratic = np.einsum("ki,ij,kj->k", errors, inverse, errors)
    for c in (2.5, 3.0, 4.0, 6.0, 10.0):
        half = chebyshev_bounds(p, c)
        inside = np.all(np.abs(errors) <= half, axis=1).mean()
        assert inside >= chebyshev_level(n, c), (family, c, inside)
        assert np.mean(quadratic > c ** 2) <= n / c ** 2  # eq. 37
        # the ellipsoid lies inside the box
        assert np.all(np.all(np.abs(errors[quadratic <= c ** 2]) <= half * (1 + 1e-12), axis=1))


def test_chebyshev_errors():
    with pytest.raises(ValueError):
        covariance_from_bounds([1.0, -2.0], 10.0)
    with pytest.raises(ValueError):
        covariance_from_bounds([1.0, np.inf], 10.0)
    with pytest.raises(ValueError):
        covariance_from_bounds([1.0, 2.0], 0.0)
    with pytest.raises(ValueError):
        chebyshev_bounds(np.ones((2, 3)), 10.0)
    with pytest.raises(ValueError):
        chebyshev_bounds(np.ones(3), 10.0)
    with pytest.raises(ValueError):
        chebyshev_bounds(np.diag([1.0, -1.0]), 10.0)
    with pytest.raises(ValueError):
        chebyshev_bounds(np.eye(2), -1.0)
    with pytest.raises(ValueError):
        chebyshev_intervals([0.0, 0.0, 0.0], np.eye(2), 3.0)
    for n, c in [(0, 10.0), (5, 0.0), (5, -1.0)]:
        with pytest.raises(ValueError):
            chebyshev_level(n, c)
    for n, level in [(0, 0.5), (5, 1.0), (5, -0.1)]:
        with pytest.raises(ValueError):
            chebyshev_scale(n, level)


# -- 5. innovation consistency -----------------------------------------------------------------------------


def _covariance_stack(rng, count, m=2):
    a = rng.normal(size=(count, m, m))
    return a @ np.swapaxes(a, 1, 2) + 0.5 * np.eye(m)


def _innovations(rng, s):
    return np.einsum("kij,kj->ki", np.linalg.cholesky(s), rng.standard_normal(s.shape[:2]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_consistent_innovations_pass_every_check(seed):
    rng = np.random.default_rng(seed)
    s = _covariance_stack(rng, 4000)
    e = _innovations(rng, s)
    report = innovation_consistency(e, s, level=0.999)
    assert report.samples == 4000
    # var(e_i) / mean(S_ii): the sample variance of e_i estimates mean(S_ii); 5 standard errors
    assert np.all(np.abs(report.variance_ratio - 1.0) < 0.15)
    assert np.all(np.abs(report.bias_z) < 3.9)
    assert abs(report.nis_mean - 2.0) < 5 * np.sqrt(4.0 / 4000)  # chi2(2) has variance 4
    assert report.variance_consistent and report.unbiased and report.white and report.nis_consistent
    assert report.consistent


def test_inconsistent_innovations_fail_the_matching_check():
    rng = np.random.default_rng(11)
    count = 3000
    s = _covariance_stack(rng, count)
    e = _innovations(rng, s)
    sigma = np.sqrt(np.diagonal(s, axis1=1, axis2=2))
    biased = innovation_consistency(e + 0.3 * sigma * [1, 0], s)
    assert not biased.unbiased and not biased.consistent
    assert biased.bias_z[0] > 0.3 * np.sqrt(count) / 2  # about 0.3 sqrt(K) = 16
    inflated = innovation_consistency(1.5 * e, s)
    assert not inflated.variance_consistent and not inflated.nis_consistent and not inflated.consistent
    assert np.all(inflated.variance_ratio > 1.5)
    # AR(1), phi = 0.5, with the stationary variance kept at S
    nu = rng.standard_normal((count, 2))
    ar = np.empty_like(nu)
    ar[0] = nu[0]
    for k in range(1, count):
        ar[k] = 0.5 * ar[k - 1] + np.sqrt(1 - 0.25) * nu[k]
    correlated = innovation_consistency(ar, np.broadcast_to(np.eye(2), (count, 2, 2)))
    assert not correlated.white and not correlated.consistent
    assert np.all(np.abs(correlated.autocorrelation[0] - 0.5) < 0.1)
    assert correlated.variance_consistent


def test_whiten_a_stack_of_covariances():
    rng = np.random.default_rng(5)
    count = 20_000
    s = _covariance_stack(rng, count, m=3)
    w = rng.standard_normal((count, 3))
    e = np.einsum("kij,kj->ki", np.linalg.cholesky(s), w)
    nu = whiten(e, s)
    np.testing.assert_allclose(nu, w, rtol=1e-8, atol=1e-8)  # L_k^{-1} L_k w_k
    assert np.allclose(np.cov(nu.T), np.eye(3), atol=0.05)
    # a row with NaN stays NaN, the others are untouched
    e[3, 1] = np.nan
    out = whiten(e, s)
    assert np.all(np.isnan(out[3])) and np.allclose(out[4], w[4])
    with pytest.raises(ValueError):
        whiten(e, s[:, :2, :2])


def test_innovation_monitor_alarms_on_a_bias_only():
    rng = np.random.default_rng(3)
    window, persistence = 400, 10
    monitor = InnovationMonitor(window=window, threshold=5.0, persistence=persistence)
    s = np.array([[2.0, 0.6], [0.6, 0.5]])
    lower = np.linalg.cholesky(s)
    alarms = [monitor.update(lower @ rng.standard_normal(2), s) for _ in range(5000)]
    assert not any(alarms)
    assert np.isfinite(monitor.statistic) and monitor.statistic < 5.0
    # a bias of half a standard deviation on channel 1
    bias = np.array([0.5 * np.sqrt(s[0, 0]), 0.0])
    delay = None
    for k in range(1, 3 * window):
        if monitor.update(lower @ rng.standard_normal(2) + bias, s):
            delay = k
            break
    # whitened bias 0.5: the window statistic reaches 0.5 sqrt(W) = 10 > 5 once the window is full
    assert delay is not None and persistence <= delay <= window + persistence
    monitor.reset()
    assert np.isnan(monitor.statistic)
    # an empty window cannot alarm, even on biased data, until it is full again
    refill = [monitor.update(lower @ rng.standard_normal(2) + bias, s) for _ in range(window - 1)]
    assert not any(refill) and np.isnan(monitor.statistic)


def test_innovation_monitor_ignores_nan_residuals():
    rng = np.random.default_rng(8)
    a = InnovationMonitor(window=50, threshold=5.0, persistence=3)
    b = InnovationMonitor(window=50, threshold=5.0, persistence=3)
    s = np.diag([4.0, 0.25])
    for k in range(300):
        e = rng.normal(size=2) * [2.0, 0.5]
        if k % 7 == 0:
            assert a.update([np.nan, 1.0], s) is False
            assert a.update([np.nan, np.nan], s) is False
        assert a.update(e, s) == b.update(e, s)
        assert a.statistic == pytest.approx(b.statistic, nan_ok=True, rel=1e-12)


# -- 6. Monte Carlo RUL ------------------------------------------------------------------------------------

A0, A_F, M_RATE, FORCE = 10.0, 4.0, 0.01, 2.0


def _held_speed(x, _t):
    """d alpha/dt = -m F^2 / alpha: the contact under a held driven speed (eq. 45, F = B2 omega2 / r2)."""
    return np.vstack([-x[1] * FORCE ** 2 / x[0], np.zeros_like(x[1])])


def _closed_form(a0, af, rate):
    return (a0 ** 2 - af ** 2) / (2 * rate * FORCE ** 2)  # alpha^2 = alpha0^2 - 2 m F^2 t


def test_monte_carlo_rul_matches_the_closed_form():
    dt = 1.0
    rul = monte_carlo_rul(_held_speed, [A0, M_RATE], np.zeros((2, 2)), lambda x: x[0] - A_F,
                          horizon=5000.0, dt=dt, origin=100.0, n_samples=7, seed=0)
    expected = _closed_form(A0, A_F, M_RATE)  # 1050
    assert np.all(np.abs(rul.samples - expected) <= dt)
    np.testing.assert_allclose(rul.eol, 100.0 + rul.samples)
    np.testing.assert_array_equal(rul.initial, np.tile([[A0], [M_RATE]], 7))
    # already failed at the origin: RUL 0
    failed = monte_carlo_rul(_held_speed, [A0, M_RATE], np.zeros((2, 2)), lambda x: x[0] - 20.0,
                             horizon=10.0, dt=dt, n_samples=3, seed=0)
    np.testing.assert_array_equal(failed.samples, 0.0)


def test_monte_carlo_rul_distribution_follows_the_rate():
    dt, n = 1.0, 2001
    sigma = 0.1 * M_RATE
    rul = monte_carlo_rul(_held_speed, [A0, M_RATE], np.diag([0.0, sigma ** 2]), lambda x: x[0] - A_F,
                          horizon=5000.0, dt=dt, n_samples=n, seed=4, lower=[0.0, 0.0])
    rates = rul.initial[1]
    assert np.all(rul.initial[0] == A0)  # zero variance: alpha0 is not drawn
    # every sample fails at its own closed form; RUL is decreasing in m, so the medians correspond
    np.testing.assert_allclose(rul.samples, _closed_form(A0, A_F, rates), atol=dt, rtol=0)
    assert abs(rul.median - _closed_form(A0, A_F, np.median(rates))) <= dt
    # and against the population median m = 0.01 (sample median of m: standard error 1.25 sigma / sqrt(n))
    tolerance = 4 * 1.2533 * sigma / np.sqrt(n) * _closed_form(A0, A_F, M_RATE) / M_RATE + dt
    assert abs(rul.median - _closed_form(A0, A_F, M_RATE)) <= tolerance


def test_monte_carlo_rul_summaries_are_those_of_the_samples():
    rul = monte_carlo_rul(_held_speed, [A0, M_RATE], np.diag([0.25, (0.15 * M_RATE) ** 2]),
                          lambda x: x[0] - A_F, horizon=1500.0, dt=2.0, origin=50.0, n_samples=500, seed=9,
                          lower=[A_F, 1e-4])
    samples = rul.samples
    assert np.any(np.isinf(samples)) and np.any(np.isfinite(samples))  # some outlive the horizon
    assert np.all(samples[np.isfinite(samples)] <= 1500.0 + 2.0)
    np.testing.assert_array_equal(rul.eol, 50.0 + samples)
    for r in (600.0, 900.0, 1200.0, 1e9):
        assert rul.probability_before(r) == np.count_nonzero(samples <= r) / samples.size
    for q in (0.05, 0.5, 0.8):
        value = rul.quantile(q)
        assert value in samples  # an observed sample (inverted CDF)
        assert np.mean(samples <= value) >= q and np.mean(samples < value) < q
    assert rul.quantile(0.999) == np.inf
    finite = samples[np.isfinite(samples)]
    assert rul.mean == pytest.approx(finite.mean()) and rul.std == pytest.approx(finite.std())  # over the failed ones
    assert rul.censored_weight == np.count_nonzero(np.isinf(samples)) / samples.size
    # same seed, same draws and failure times; another seed, other draws
    again = monte_carlo_rul(_held_speed, [A0, M_RATE], np.diag([0.25, (0.15 * M_RATE) ** 2]),
                            lambda x: x[0] - A_F, horizon=1500.0, dt=2.0, origin=50.0, n_samples=500, seed=9,
                            lower=[A_F, 1e-4])
    np.testing.assert_array_equal(again.initial, rul.initial)
    np.testing.assert_array_equal(again.samples, rul.samples)
    other = monte_carlo_rul(_held_speed, [A0, M_RATE], np.diag([0.25, (0.15 * M_RATE) ** 2]),
                            lambda x: x[0] - A_F, horizon=1500.0, dt=2.0, n_samples=500, seed=10, lower=[A_F, 1e-4])
    assert not np.array_equal(other.initial, rul.initial)


def test_no_failure_within_the_horizon_gives_infinite_rul():
    rul = monte_carlo_rul(_held_speed, [A0, M_RATE], np.zeros((2, 2)), lambda x: x[0] - A_F,
                          horizon=500.0, dt=1.0, n_samples=4, seed=0)  # closed form: 1050 > 500
    assert np.all(np.isinf(rul.samples)) and rul.probability_before(1e12) == 0.0
    assert rul.quantile(0.05) == np.inf


def test_sample_gaussian_with_variances_from_1e_minus_14_to_1e9():
    std = np.array([0.5, 1e-7, 3.0e4])  # alpha, m, D (P_00 = 0.25, P_11 = 1e-14, P_22 = 9e8)
    corr = np.array([[1.0, -0.6, 0.3], [-0.6, 1.0, -0.4], [0.3, -0.4, 1.0]])
    p = corr * np.outer(std, std)
    mean = np.array([8.0, 2e-6, 3e6])
    draws = sample_gaussian(mean, p, 30_000, np.random.default_rng(1))
    assert draws.shape == (3, 30_000)
    np.testing.assert_allclose(draws.std(axis=1, ddof=1), std, rtol=0.03)
    np.testing.assert_allclose(np.corrcoef(draws), corr, atol=0.03)
    np.testing.assert_allclose((draws.mean(axis=1) - mean) / std, 0.0, atol=0.03)
    same = sample_gaussian(mean, p, 30_000, np.random.default_rng(1))
    np.testing.assert_array_equal(draws, same)
    # bounds are respected, even on the 1e-7 and 3e4 scales
    lower, upper = mean - [0.5, 0.5e-7, 1e4], mean + [1.0, 2e-7, 6e4]
    bounded = sample_gaussian(mean, p, 5000, np.random.default_rng(2), lower=lower, upper=upper)
    assert np.all(bounded >= lower[:, None]) and np.all(bounded <= upper[:, None])
    # a zero-variance direction stays at its mean
    flat = sample_gaussian([1.0, 2.0], np.diag([0.0, 1.0]), 100, np.random.default_rng(0))
    assert np.all(flat[0] == 1.0)


def test_bounded_draws_follow_the_truncated_normal():
    """1-D N(0, 1) kept in [-1, 2]: mean (phi(-1) - phi(2)) / (Phi(2) - Phi(-1))."""
    draws = sample_gaussian([0.0], [[1.0]], 40_000, np.random.default_rng(6), lower=[-1.0], upper=[2.0])[0]
    mass = stats.norm.cdf(2.0) - stats.norm.cdf(-1.0)
    expected_mean = (stats.norm.pdf(-1.0) - stats.norm.pdf(2.0)) / mass
    assert draws.min() >= -1.0 and draws.max() <= 2.0
    assert abs(draws.mean() - expected_mean) < 4 * draws.std() / np.sqrt(draws.size)
    # the share below 0 is (Phi(0) - Phi(-1)) / mass
    share = (0.5 - stats.norm.cdf(-1.0)) / mass
    assert abs(np.mean(draws < 0) - share) < 4 * np.sqrt(share * (1 - share) / draws.size)


def test_sample_gaussian_errors():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError):
        sample_gaussian([0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]], 10, rng)  # not PSD
    with pytest.raises(ValueError):
        sample_gaussian([5.0], [[1.0]], 10, rng, lower=[0.0], upper=[1.0])  # mean outside the bounds
    with pytest.raises(RuntimeError):
        sample_gaussian([0.0], [[1.0]], 10, rng, lower=[0.0], upper=[1e-12], max_rounds=3)
    with pytest.raises(ValueError):
        monte_carlo_rul(_held_speed, [A0, M_RATE], np.zeros((2, 2)), lambda x: x[0], horizon=10.0, dt=0.0)


# -- 7. RUL controller -------------------------------------------------------------------------------------


def _base_life(n=1000):
    return np.random.default_rng(12).uniform(5.0, 15.0, n)


def _synthetic(base):
    def predict(theta):
        return RULDistribution(base / (1.0 + 0.1 * theta))
    return predict


@pytest.mark.parametrize("n", [999, 1000, 1001])  # eta * n = 49.95, 50 (an integer), 50.05
def test_rul_controller_finds_the_smallest_change(n):
    base_life = _base_life(n)
    predict = _synthetic(base_life)
    ref, eta = 7.0, 0.05
    assert predict(0.0).probability_before(ref) > eta  # the nominal operation is not enough
    decision = RULController(rul_ref=ref, eta=eta, gain=1.0, lower=-5.0, tolerance=1e-6).decide(predict)
    assert decision.feasible and decision.theta < 0
    pr = np.mean(base_life / (1.0 + 0.1 * decision.theta) <= ref)  # computed here, not by the controller
    assert pr <= eta and decision.probability == pr
    # minimality: a slightly larger theta (a smaller change) violates the constraint Pr(RUL <= ref) <= eta
    assert np.mean(base_life / (1.0 + 0.1 * (decision.theta + 1e-3)) <= ref) > eta


def test_rul_controller_keeps_theta_zero_when_feasible_and_reports_infeasible():
    base_life = _base_life()
    predict = _synthetic(base_life)
    decision = RULController(rul_ref=3.0, eta=0.05, lower=-5.0).decide(predict)
    assert decision.theta == 0.0 and decision.feasible and len(decision.history) == 1
    assert decision.probability == np.mean(base_life <= 3.0) == 0.0
    # even theta = -1 (lives / 0.9) cannot give Pr(RUL <= 10) <= 5 %
    with pytest.warns(RULControlWarning, match="no feasible setting found"):
        infeasible = RULController(rul_ref=10.0, eta=0.05, lower=-1.0).decide(predict)
    assert not infeasible.feasible and infeasible.theta == -1.0 and infeasible.status == "no feasible setting found"
    assert infeasible.probability == np.mean(base_life / 0.9 <= 10.0) > 0.05
    with pytest.raises(ValueError):
        RULController(rul_ref=1.0, eta=1.5)
    with pytest.raises(ValueError):
        RULController(rul_ref=1.0, lower=1.0)


def _crawl_life(theta):
    """Lives 10 / (1 + theta), origin 7: Pr(RUL <= 12) <= 5 % needs theta <= -1/6."""
    return RULDistribution(np.full(100, 10.0 / (1.0 + theta)), origin=7.0)


def test_rul_controller_crawling_from_the_infeasible_side_still_converges():
    """With a small gain, eq. 53 from just above the boundary converges to it from the infeasible side
    (each step multiplies the distance by 1 - K |dq/dtheta| = 0.86) and never crosses it; the bracket stayed
    [lower, ~theta*] and the lower bound came back after 60 iterations (theta = -15 on the friction drive)."""
    controller = RULController(rul_ref=12.0, eta=0.05, gain=0.01, lower=-0.9)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RULControlWarning)
        decision = controller.decide(_crawl_life, theta0=-0.1)
    assert decision.status == "converged" and decision.converged and decision.feasible
    assert decision.theta == pytest.approx(-1.0 / 6.0, abs=1e-3) and decision.quantile > 12.0
    assert len(decision.history) < 40  # the safeguard bisects: well inside the budget of 60


def test_rul_controller_out_of_iterations_says_so_and_keeps_the_largest_feasible_setting():
    controller = RULController(rul_ref=12.0, eta=0.05, gain=0.01, lower=-0.9, max_iterations=3)
    with pytest.warns(RULControlWarning, match=r"at t = 7: .*did not converge in 3 iterations.*using theta = -0\.") \
            as caught:
        decision = controller.decide(_crawl_life, theta0=-0.1)
    assert issubclass(caught[0].category, PHMWarning)
    assert decision.status == "not converged" and not decision.converged
    # the setting returned meets the constraint (lives 10 / (1 + theta) > 12) and is the largest such one met
    assert decision.feasible and 10.0 / (1.0 + decision.theta) > 12.0
    met = [theta for theta, q in decision.history if q > 12.0]
    assert decision.theta == max(met) and decision.theta > -0.9  # not the bracket's lower bound
    assert f"{decision.theta:.6g}" in str(caught[0].message)


def test_rul_controller_with_no_feasible_setting_falls_back_to_the_most_life_extending_one():
    with pytest.warns(RULControlWarning, match=r"at t = 7: no feasible setting found.*using theta = -0\.1, the most "
                                               "life-extending admissible setting"):
        decision = RULController(rul_ref=12.0, eta=0.05, lower=-0.1).decide(_crawl_life)
    assert decision.status == "no feasible setting found" and not decision.feasible and not decision.converged
    assert decision.theta == -0.1 and decision.probability == 1.0
    with pytest.raises(ValueError, match="max_iterations"):
        RULController(rul_ref=1.0, max_iterations=0)


def test_friction_drive_predictor_matches_the_closed_form(fd):
    """Held omega2*: d alpha/dt = -m F^2/alpha with F = B2 omega2*/r2, D - D0 = (alpha0 - alpha)/m."""
    a0, rate, d0, omega = 8.0, 2e-6, 4e6, 20.0
    mean = np.array([40.0, omega, a0, rate, d0])
    force2 = (TABLE_1["B2"] * omega / TABLE_1["r2"]) ** 2
    alpha_fail = max(0.0, a0 - rate * (fd.D_MAX - d0))  # D reaches D_max first: alpha = 6
    expected = (a0 ** 2 - alpha_fail ** 2) / (2 * rate * force2)
    rul = fd.predict_rul(mean, np.zeros((5, 5)), 100.0, omega, seed=0)
    assert alpha_fail == pytest.approx(6.0)
    assert np.all(np.abs(rul.samples - expected) <= fd.MONTE_CARLO["dt"])
    np.testing.assert_allclose(rul.eol, 100.0 + rul.samples)


@pytest.fixture(scope="module")
def estimate():
    std = np.array([0.3, 2e-7, 4e4])
    corr = np.array([[1.0, -0.5, -0.3], [-0.5, 1.0, 0.2], [-0.3, 0.2, 1.0]])
    covariance = np.zeros((5, 5))
    covariance[:2, :2] = np.diag([4.0, 0.01])
    covariance[2:, 2:] = corr * np.outer(std, std)
    return np.array([40.0, 20.0, 7.0, 2e-6, 3e6]), covariance


def test_friction_drive_predictor_is_monotone_in_the_speed(fd, estimate):
    mean, covariance = estimate
    runs = {w: fd.predict_rul(mean, covariance, 0.0, w, seed=5) for w in (20.0, 18.0, 16.0)}
    q = {w: r.quantile(0.05) for w, r in runs.items()}
    assert q[20.0] < q[18.0] < q[16.0]
    # common random numbers: the same draws, and every draw lives longer at a lower speed
    np.testing.assert_array_equal(runs[20.0].initial, runs[16.0].initial)
    assert np.all(runs[16.0].samples >= runs[18.0].samples) and np.all(runs[18.0].samples >= runs[20.0].samples)
    # the wear rate scales with omega2*^2, so lives scale with 1/omega2*^2 (up to the 30 s step)
    finite = np.isfinite(runs[18.0].samples)
    np.testing.assert_allclose(runs[18.0].samples[finite] * (18.0 / 20.0) ** 2, runs[20.0].samples[finite],
                               atol=2 * fd.MONTE_CARLO["dt"])
    lo, hi = chebyshev_intervals(mean[2:], covariance[2:, 2:], fd.C)
    initial = runs[20.0].initial
    assert np.all(initial >= np.maximum(lo, 0.0)[:, None]) and np.all(initial <= hi[:, None])


@pytest.mark.slow  # about 1-2 s
def test_rul_controller_on_the_friction_drive(fd, estimate):
    mean, covariance = estimate

    def predict(theta):
        return fd.predict_rul(mean, covariance, 0.0, 20.0 + theta, seed=5)

    nominal = predict(0.0)
    ref = 1.2 * nominal.quantile(0.05)
    controller = RULController(rul_ref=ref, eta=0.05, gain=1e-3, lower=-15.0)
    decision = controller.decide(predict)
    assert decision.feasible and decision.theta < 0
    assert predict(decision.theta).probability_before(ref) <= 0.05
    # lives scale as 1/omega^2: the required speed is about 20 / sqrt(1.2)
    assert 20.0 + decision.theta == pytest.approx(20.0 / np.sqrt(1.2), abs=0.05)


@pytest.mark.slow  # about 1 s: a dozen Monte Carlo predictions of 1000 draws over 1 h
def test_rul_controller_on_seed_2_at_7_hours_finds_the_boundary_not_the_lower_bound(fd):
    """A regression case: examples/friction_drive.py, seed 2, the decision at 7.0 h (RUL_ref = 1 h, from
    theta0 = -2.895).  The EKF's (alpha, m, D) estimate then, as the example had it; the controller used to crawl
    to theta* = -2.999 from above for 60 iterations and return theta = -15, applied for 30 min."""
    mean = np.array([416.6, 17.10, 4.2640583403589662, 2.0063625341882931e-06, 3.8849438543091100e+06])
    covariance = np.zeros((5, 5))
    covariance[2:, 2:] = [[6.0865917907219113e-05, -6.2601345885228054e-11, -3.4139858486346614e-01],
                          [-6.2601345885228054e-11, 1.0096101212019218e-16, -2.0102670657348255e-06],
                          [-3.4139858486346614e-01, -2.0102670657348255e-06, 2.5009896688421607e+09]]

    def predict(theta):
        return fd.predict_rul(mean, covariance, 25200.0, 20.0 + theta, seed=2 + 7919 * 4)

    controller = RULController(rul_ref=3600.0, eta=0.05, gain=1e-3, lower=-15.0, tolerance=36.0)
    decision = controller.decide(predict, theta0=-2.8952952206151576)
    assert decision.status == "converged" and decision.feasible
    # the boundary, theta* = -2.999, to the tolerance of 36 s on the quantile (about 0.06 rad/s)
    assert -3.1 < decision.theta < -2.99 and 3600.0 < decision.quantile <= 3636.0
    assert decision.probability <= 0.05 < predict(decision.theta + 0.1).probability_before(3600.0)


def test_rul_distribution_moments_are_over_the_failed_draws_with_the_censored_weight_beside():
    import warnings

    from prognosis import RULDistribution

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no 'invalid value' RuntimeWarning from inf - inf or 0 / 0
        censored = RULDistribution(np.array([1.0, 3.0, np.inf, np.inf]))
        assert censored.mean == 2.0 and censored.std == 1.0 and censored.censored_weight == 0.5
        assert censored.median == 3.0 and censored.quantile(0.75) == np.inf
        never = RULDistribution(np.array([np.inf, np.inf]))
        assert np.isnan(never.mean) and np.isnan(never.std) and never.censored_weight == 1.0
    assert RULDistribution(np.array([1.0, 3.0])).std == 1.0
