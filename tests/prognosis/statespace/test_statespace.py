"""prognosis.statespace: the discrete three-tank model of Du et al. (eqs. 58-59, 62), Jacobians, errors."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from bondgraph.library import three_tank
from prognosis.statespace import discretize

# Du et al., section 6.1
A_S, S_N, G = 0.0154, 5e-5, 9.81
AZ = {"az1": 0.5, "az2": 0.6, "az3": 0.5}
Q_IN = 4.5e-5
U = {"Q1": Q_IN, "Q2": Q_IN}
# a generic point: all level differences non-zero, az2 off its nominal value
LEVELS = np.array([0.8, 0.55, 0.7])
AZ2 = 0.63
X = np.r_[A_S * LEVELS, AZ2]


@pytest.fixture(scope="module")
def equations():
    return three_tank().state_equations()


def tanks(equations, dt=1.0, method="euler", **options):
    return discretize(equations, dt=dt, augment=["az2"], outputs=["h1", "h2", "h3"], method=method, **options)


@pytest.fixture(scope="module")
def euler(equations):
    return tanks(equations)


@pytest.fixture(scope="module")
def rk4(equations):
    return tanks(equations, method="rk4")


def valve(az, dh):
    """Eq. (58): Q = az S_n sgn(dh) sqrt(2 g |dh|)."""
    return az * S_N * np.sign(dh) * np.sqrt(2 * G * abs(dh))


def eq59(h, az2, dt=1.0, az1=AZ["az1"], az3=AZ["az3"], q1=Q_IN, q2=Q_IN):
    """Eq. (59) by hand: h_k = h_{k-1} + dt A x_{k-1} + dt B u_{k-1}, x = (h1, h2, h3)."""
    h1, h2, h3 = h
    q13, q32, q20 = valve(az1, h1 - h3), valve(az3, h3 - h2), valve(az2, h2)
    return np.array([h1 + dt * (-q13 + q1) / A_S, h2 + dt * (q32 - q20 + q2) / A_S, h3 + dt * (q13 - q32) / A_S])


def central_differences(function, x, relative=1e-6):
    step = relative * np.abs(x)
    columns = []
    for j in range(x.size):
        e = np.zeros_like(x)
        e[j] = step[j]
        columns.append((function(x + e) - function(x - e)) / (2 * step[j]))
    return np.column_stack(columns)


def test_model_layout(euler, equations):
    assert euler.states == ("q_A_1", "q_A_2", "q_A_3", "az2")
    assert euler.outputs == ("h1", "h2", "h3") and euler.inputs == ("Q1", "Q2")
    assert euler.augmented == ("az2",) and euler.dt == 1.0 and euler.method == "euler"
    assert "az2" not in euler.parameters and euler.parameters["az1"] == 0.5
    assert euler.n_states == 4 and euler.n_outputs == 3 and euler.index("az2") == 3
    with pytest.raises(KeyError, match="'az9' is not a state"):
        euler.index("az9")
    # every output by default
    assert discretize(equations, dt=1.0).outputs == ("h1", "h2", "h3")


@pytest.mark.parametrize("h", [LEVELS, np.array([0.6, 0.9, 0.75]), np.array([1.0, 0.95, 0.9])])
def test_transition_is_seed_eq59_from_eq58(euler, h):
    """Volumes q = A_s h: the bond graph's Euler step equals eq. (59) in levels, az2 is carried unchanged."""
    x = np.r_[A_S * h, AZ2]
    new = euler.transition(x, U)
    np.testing.assert_allclose(new[:3] / A_S, eq59(h, AZ2), rtol=1e-13, atol=0)
    assert new[3] == AZ2  # assistant dynamics theta_k = theta_{k-1} (eq. 62)
    # the step is not the identity: the levels really move by the valve flows
    assert np.max(np.abs(new[:3] / A_S - h)) > 1e-4
    np.testing.assert_allclose(euler.measure(new), new[:3] / A_S, rtol=1e-15)


def test_rates_are_eq57_and_inputs_as_a_sequence(euler):
    h = LEVELS
    rates = euler.rates(X, [Q_IN, Q_IN])
    np.testing.assert_allclose(rates[:3] / A_S, eq59(h, AZ2) - h, rtol=1e-12)
    assert rates[3] == 0.0
    np.testing.assert_array_equal(euler.transition(X, [Q_IN, Q_IN]), euler.transition(X, U))


def test_parameter_override_and_dt(equations):
    model = tanks(equations, dt=2.5, parameters={"az1": 0.4, "az3": 0.55})
    assert model.parameters["az1"] == 0.4 and model.parameters["az3"] == 0.55
    np.testing.assert_allclose(model.transition(X, U)[:3] / A_S, eq59(LEVELS, AZ2, dt=2.5, az1=0.4, az3=0.55),
                               rtol=1e-13)


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_columns_are_evaluated_like_single_points(equations, euler, rk4, method):
    model = euler if method == "euler" else rk4
    rng = np.random.default_rng(7)
    points = X[:, None] * (1 + 0.1 * rng.standard_normal((4, 9)))
    batch = model.transition(points, U)
    assert batch.shape == (4, 9)
    for j in range(points.shape[1]):
        np.testing.assert_array_equal(batch[:, j], model.transition(points[:, j], U))
    np.testing.assert_array_equal(batch[3], points[3])  # az2 unchanged column by column, RK4 included
    measured = model.measure(points)
    assert measured.shape == (3, 9)
    np.testing.assert_allclose(measured, points[:3] / A_S, rtol=1e-15)
    rates = model.rates(points, U)
    for j in range(points.shape[1]):
        np.testing.assert_array_equal(rates[:, j], model.rates(points[:, j], U))


@pytest.mark.parametrize("method", ["euler", "rk4"])
@pytest.mark.parametrize("dt", [1.0, 10.0])
def test_transition_jacobian_matches_central_differences(equations, method, dt):
    model = tanks(equations, dt=dt, method=method)
    jacobian = model.transition_jacobian(X, U)
    numeric = central_differences(lambda x: model.transition(x, U), X)
    moving = jacobian - np.eye(4)  # the part that is not the identity carries the model
    assert np.abs(moving).max() > 1e-3 * dt
    # measured: max |J - FD| / max |J - I| about 1e-8 (Euler and RK4, dt = 1 and 10)
    np.testing.assert_allclose(jacobian - np.eye(4), numeric - np.eye(4), rtol=1e-6,
                               atol=1e-6 * np.abs(moving).max())
    np.testing.assert_array_equal(jacobian[3], [0, 0, 0, 1])
    if method == "euler":  # d q2_k / d az2 = -dt S_n sqrt(2 g h2) by hand
        assert jacobian[1, 3] == pytest.approx(-dt * S_N * np.sqrt(2 * G * LEVELS[1]), rel=1e-12)


def test_rk4_jacobian_chains_the_stages(euler, rk4):
    """RK4's Jacobian is not Euler's: the stage rule matters (difference far above the FD agreement)."""
    difference = np.abs(rk4.transition_jacobian(X, U) - euler.transition_jacobian(X, U)).max()
    assert difference > 1e-6


@pytest.mark.parametrize("dt, rk4_tolerance, ratio", [(1.0, 1e-8, 1e4), (10.0, 1e-4, 1e2)])
def test_rk4_step_matches_a_fine_ode_solution(equations, dt, rk4_tolerance, ratio):
    """Measured: dt = 1, RK4 error 2e-14 vs Euler 1e-7 (|dx| = 1.6e-5); dt = 10, 1.8e-9 vs 9.4e-6."""
    euler = tanks(equations, dt=dt)
    rk4 = tanks(equations, dt=dt, method="rk4")
    reference = solve_ivp(lambda t, y: euler.rates(y, U), (0.0, dt), X, method="DOP853", rtol=1e-13,
                          atol=1e-16).y[:, -1]
    change = np.abs(reference - X).max()
    rk4_error = np.abs(rk4.transition(X, U) - reference).max()
    euler_error = np.abs(euler.transition(X, U) - reference).max()
    assert rk4_error < rk4_tolerance * change
    assert euler_error > ratio * rk4_error
    assert rk4.transition(X, U)[3] == AZ2


def test_measurement_jacobian_is_diag_inverse_area_with_a_zero_az2_column(euler, rk4):
    expected = np.hstack([np.eye(3) / A_S, np.zeros((3, 1))])
    for model in (euler, rk4):
        np.testing.assert_allclose(model.measurement_jacobian(X), expected, rtol=1e-15)
        np.testing.assert_allclose(model.measurement_jacobian(X, U), expected, rtol=1e-15)
    numeric = central_differences(euler.measure, X)
    np.testing.assert_allclose(numeric, expected, rtol=1e-6, atol=1e-9)


def test_non_differentiable_point_names_the_state_columns(euler, rk4):
    """h1 == h3: the valve law sqrt(|h1 - h3|) has an infinite slope; the columns of q_A_1 and q_A_3 say so."""
    x = np.r_[A_S * np.array([0.7, 0.5, 0.7]), 0.6]
    for model in (euler, rk4):
        with pytest.raises(FloatingPointError, match=r"transition Jacobian is not finite.*'q_A_1', 'q_A_3'"):
            model.transition_jacobian(x, U)
        step = model.transition(x, U)  # the step itself is fine there
        assert np.all(np.isfinite(step))


def test_discretize_errors(equations):
    with pytest.raises(ValueError, match="parameter 'az7' is not in the model"):
        discretize(equations, dt=1.0, augment=["az7"])
    with pytest.raises(ValueError, match="parameter 'leak' is not in the model"):
        discretize(equations, dt=1.0, parameters={"leak": 0.1})
    with pytest.raises(ValueError, match="augment lists a parameter twice"):
        discretize(equations, dt=1.0, augment=["az2", "az2"])
    with pytest.raises(ValueError, match="parameter 'az1' needs a finite number"):
        discretize(equations, dt=1.0, parameters={"az1": np.nan})
    for dt in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="dt must be a positive number"):
            discretize(equations, dt=dt)
    with pytest.raises(ValueError, match=r"method must be one of \('euler', 'rk4'\), got 'midpoint'"):
        discretize(equations, dt=1.0, method="midpoint")
    with pytest.raises(ValueError, match="output 'h4' is not a measured signal"):
        discretize(equations, dt=1.0, outputs=["h1", "h4"])


def test_evaluation_errors(euler):
    with pytest.raises(ValueError, match=r"x: expected shape \(4,\) or \(4, M\), got \(3,\)"):
        euler.transition(X[:3], U)
    with pytest.raises(ValueError, match=r"got \(3, 5\)"):
        euler.measure(np.zeros((3, 5)))
    with pytest.raises(ValueError, match=r"one point of shape \(4,\), got \(4, 2\)"):
        euler.transition_jacobian(np.column_stack([X, X]), U)
    with pytest.raises(ValueError, match=r"missing \['Q2'\], unknown \[\]"):
        euler.transition(X, {"Q1": Q_IN})
    with pytest.raises(ValueError, match=r"missing \[\], unknown \['Q3'\]"):
        euler.transition(X, {**U, "Q3": 0.0})
    with pytest.raises(ValueError, match=r"expected 2 values for \['Q1', 'Q2'\], got shape \(1,\)"):
        euler.transition(X, [Q_IN])
    with pytest.raises(ValueError, match="inputs: expected 2 values"):
        euler.transition(X)  # the dynamics need the inputs
    # the measurement does not use them: None is allowed there, a bad mapping is not
    assert euler.measure(X).shape == (3,)
    with pytest.raises(ValueError, match=r"missing \['Q1'\]"):
        euler.measure(X, {"Q2": Q_IN})


def test_implicit_equations_are_rejected():
    x, y = sp.symbols("x y")
    loose = type("Eq", (), {"states": [x], "rhs": [-y * x], "inputs": [], "outputs": {"x": x}, "parameters": {}})
    with pytest.raises(ValueError, match=r"dx/dt depends on \['y'\]"):
        discretize(loose, dt=0.1)


def test_a_deep_copy_shares_the_compiled_functions_and_steps_alike():
    # a filter's look-ahead deep-copies the filter, model included, at every step: recompiling the
    # functions with sympy each time made the three-tank example's look-ahead 15x slower
    import copy

    model = discretize(three_tank().state_equations(), dt=1.0, augment=["az2"])
    twin = copy.deepcopy(model)
    assert twin._functions is model._functions and twin.parameters is not model.parameters
    x = np.array([0.3, 0.2, 0.1, 0.6])
    assert np.array_equal(twin.transition(x, model.input_vector({n: 1e-4 for n in model.inputs})),
                          model.transition(x, model.input_vector({n: 1e-4 for n in model.inputs})))
