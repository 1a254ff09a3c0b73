"""Simulation: inputs of t, feedback inputs, controllers, time-varying parameters, bad input."""

import numpy as np
import pytest

from bondgraph import BondGraph, PIController, SimulationError, simulate
from bondgraph.library import dc_motor, rlc_circuit, torsion_bar, torsion_bar_controller


def test_result_holds_every_effort_flow_and_signal():
    bg = rlc_circuit()
    result = simulate(bg, (0.0, 0.2), {"V": lambda t: np.sin(50 * t)})
    power_bonds = [b for b in bg.bonds if not b.is_signal]
    assert set(result.efforts) == set(result.flows) == {b.label for b in power_bonds}
    assert set(result.signals) == {"V", "i", "v_C"}
    assert np.allclose(result.signals["V"], np.sin(50 * result.t))
    # Kirchhoff on the 1-junction: V = v_R + v_L + v_C at every sample
    e = result.efforts
    assert np.allclose(e[1], e[2] + e[3] + e[4], atol=1e-12)
    assert np.allclose(result["i"], result.flows[2])
    record = result.record()
    assert list(record)[0] == "t" and record["v_C"] is result.signals["v_C"]


def test_feedback_input_of_time_and_outputs():
    # proportional speed loop u = K (w_ref - w) on the DC motor: steady speed from the algebra
    K, w_ref = 2.0, 100.0
    bg = dc_motor()
    p = bg.parameters
    result = simulate(bg, (0.0, 3.0), {"U": lambda t, y: K * (w_ref - y["omega"])})
    km, Ra, b = p["k_m"], p["R_a"], p["b"]
    # k_m i = b w and U = Ra i + k_m w with U = K (w_ref - w)
    w = K * w_ref / (K + km + Ra * b / km)
    assert result["omega"][-1] == pytest.approx(w, rel=1e-5)


@pytest.mark.slow
def test_pi_controller_tracks_the_set_point_and_saturates():
    result = simulate(torsion_bar(), (0.0, 5.0), {"U": torsion_bar_controller()})
    assert result["omega_m"][-1] == pytest.approx(112.5, rel=1e-4)
    assert np.all(np.abs(result["U"]) <= 12.0 + 1e-12)
    heavy = simulate(torsion_bar(), (0.0, 5.0), {"U": torsion_bar_controller()}, parameters={"b_Md": 0.05})
    assert heavy["U"][-1] == pytest.approx(12.0)  # saturated: the speed cannot be held
    assert heavy["omega_m"][-1] < 100.0
    assert heavy.controller_states["U"].shape == (heavy.t.size, 1)


def test_pi_controller_derivative_is_vectorized_and_safe_without_integral_action():
    pi = PIController("omega", setpoint=10.0, kp=0.5, ki=2.0, limits=(-1.0, 1.0))
    omega, z = np.array([9.5, 0.0, 30.0]), np.array([[0.1, 0.0, -0.2]])
    together = pi.derivative(0.0, z, {"omega": omega})
    one_by_one = [pi.derivative(0.0, z[:, k], {"omega": omega[k]})[0] for k in range(3)]
    assert together.shape == (1, 3) and np.allclose(together[0], one_by_one)
    assert one_by_one[0] == pytest.approx(0.5)  # unsaturated: dz/dt = err
    assert one_by_one[1] == pytest.approx(10.0 + (1.0 - 5.0) / (2.0 * 0.25))  # saturated: bled by (u - v)/(ki T_t)
    proportional = PIController("omega", setpoint=10.0, kp=0.5, ki=0.0, limits=(-1.0, 1.0))
    assert proportional.derivative(0.0, np.zeros(1), {"omega": 0.0}).tolist() == [10.0]  # no 0/0
    with pytest.raises(ValueError, match="'omega': limits must be"):
        PIController("omega", setpoint=1.0, kp=1.0, ki=1.0, limits=(1.0, -1.0))
    with pytest.raises(ValueError, match="'omega': tracking_time must be positive"):
        PIController("omega", setpoint=1.0, kp=1.0, ki=1.0, limits=(-1.0, 1.0), tracking_time=0.0)


def test_time_varying_parameter():
    ramp = simulate(dc_motor(), (0.0, 2.0), {"U": 12.0}, parameters={"b": lambda t: 1e-4 * (1 + 4 * t)})
    fixed = simulate(dc_motor(), (0.0, 2.0), {"U": 12.0})
    assert ramp["omega"][-1] < fixed["omega"][-1]
    km, Ra = 3.89e-2, 1.23
    b_end = 1e-4 * 9
    assert ramp["omega"][-1] == pytest.approx(12.0 * km / (km**2 + Ra * b_end), rel=0.02)


def test_scalar_only_callables_give_the_same_record_as_vectorized_ones():
    """Post-processing calls inputs and parameters with all samples at once when they accept arrays,
    and once per sample when they do not (``if``, ``math``, ``float``); both give the same record."""
    import math

    t_eval = np.linspace(0.0, 2.0, 401)
    vectorized = simulate(dc_motor(), (0.0, 2.0), {"U": lambda t: 12.0 * np.minimum(t, 1.0)}, t_eval=t_eval,
                          parameters={"b": lambda t: 1e-4 * np.exp(t)})
    scalar = simulate(dc_motor(), (0.0, 2.0), {"U": lambda t: 12.0 * t if t < 1.0 else 12.0}, t_eval=t_eval,
                      parameters={"b": lambda t: 1e-4 * math.exp(t)})
    for name in ("U", "omega", "i"):
        assert np.allclose(vectorized[name], scalar[name], rtol=1e-6, atol=1e-9), name
    assert vectorized["U"][-1] == 12.0 and scalar["U"][200] == pytest.approx(12.0)
    # a callable that accepts arrays but ignores them (one scalar for all samples) is caught by the spot check
    calls = []
    def stateful(t):
        calls.append(t)
        return 12.0 if np.ndim(t) == 0 else 0.0
    odd = simulate(dc_motor(), (0.0, 1.0), {"U": stateful}, t_eval=np.linspace(0.0, 1.0, 11))
    assert np.all(odd["U"] == 12.0)


def test_initial_state_by_element_or_state_name():
    a = simulate(rlc_circuit(), (0.0, 0.01), {"V": 0.0}, x0={"C": 1e-3})
    b = simulate(rlc_circuit(), (0.0, 0.01), {"V": 0.0}, x0={"q_C": 1e-3})
    assert a["v_C"][0] == pytest.approx(1.0) and np.allclose(a["v_C"], b["v_C"])


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"inputs": {"W": 1.0}}, "'W'"),
        ({"inputs": {}}, "no value for input 'V'"),
        ({"inputs": {"V": "high"}}, "input 'V'"),
        ({"inputs": {"V": 1.0}, "parameters": {"Rx": 1.0}}, "'Rx'"),
        ({"inputs": {"V": 1.0}, "x0": {"C9": 1.0}}, "'C9'"),
    ],
)
def test_bad_simulation_input_names_the_culprit(kwargs, message):
    with pytest.raises(SimulationError, match=message):
        simulate(rlc_circuit(), (0.0, 0.1), **kwargs)


def test_pi_on_unknown_signal_is_a_clear_error():
    with pytest.raises(KeyError, match="omega_x"):
        simulate(dc_motor(), (0.0, 0.1), {"U": PIController("omega_x", 1.0, 1.0, 1.0)})


def test_feedback_through_a_direct_feedthrough_is_refused():
    bg = BondGraph()
    bg.add("V", "Se"), bg.add("j", "0"), bg.add("R", "R", value=1.0), bg.add("v", "De")
    bg.bond("V", "j"), bg.bond("j", "R"), bg.bond("j", "v")
    with pytest.raises(SimulationError, match="'v' depends directly on a feedback input"):
        simulate(bg, (0.0, 1.0), {"V": lambda t, y: 1.0 - y["v"]})


def test_input_derivative_needed_is_a_clear_error():
    bg = BondGraph()
    bg.add("V", "Se"), bg.add("j", "0"), bg.add("C", "C", value=1.0), bg.add("R", "R", value=1.0)
    bg.bond("V", "j"), bg.bond("j", "C"), bg.bond("j", "R")
    with pytest.raises(SimulationError, match=r"Derivative\(V\(t\), t\)"):
        simulate(bg, (0.0, 1.0), {"V": np.sin})


# --- argument checks and resource guards ------------------------------------------------------------

@pytest.mark.parametrize(
    "t_span, message",
    [
        (5, r"t_span: expected a pair \(t_start, t_end\) of numbers, got 5"),
        ("01", "t_span: expected a pair"),
        ((0.0, 1.0, 2.0), "t_span: expected a pair"),
        ((0.0, "1"), r"t_span\[1\]: expected a number, got '1'"),
        ((0.0, float("nan")), r"t_span\[1\]: nan is not a finite number"),
        ((-np.inf, 1.0), r"t_span\[0\]: -inf is not a finite number"),
        ((1.0, 0.0), "t_span: t_end = 0.0 is not after t_start = 1.0"),
        ((1.0, 1.0), "t_span: t_end = 1.0 is not after t_start = 1.0"),
        ((0.0, 1e-300), r"t_span: the span 1e-300 s from t = 0 is shorter than 1e-12 s \(MIN_SPAN"),
        ((1e9, 1e9 + 0.5), r"t_span: the span 0.5 s from t = 1e\+09 is shorter than 1 s"),
    ],
)
def test_a_bad_time_span_is_refused_before_the_solver_runs(t_span, message):
    # reversed and too-short spans used to hang LSODA; a number gave a TypeError
    with pytest.raises(SimulationError, match=message):
        simulate(dc_motor(), t_span, {"U": 12.0})


@pytest.mark.parametrize(
    "t_eval, message",
    [
        ([0.0, 2.0], r"t_eval: t_eval\[1\] = 2.0 is outside t_span \[0.0, 1.0\]"),
        ([0.0, 0.5, 0.5], r"t_eval: not strictly increasing: t_eval\[2\] = 0.5 follows t_eval\[1\] = 0.5"),
        ([0.5, 0.2], "t_eval: not strictly increasing"),
        ([0.0, np.nan], r"t_eval: t_eval\[1\] = nan is not finite"),
        ([[0.0, 0.5]], r"t_eval: expected a one-dimensional array of times, got shape \(1, 2\)"),
        ("abc", "t_eval: expected an array of times, got str"),
        ([], "t_eval: the number of samples must be a whole number >= 1, got 0"),
    ],
)
def test_bad_output_times_name_t_eval(t_eval, message):
    with pytest.raises(SimulationError, match=message):
        simulate(dc_motor(), (0.0, 1.0), {"U": 12.0}, t_eval=t_eval)


def test_the_sample_limit_is_one_public_check(monkeypatch):
    from bondgraph import simulation

    assert simulation.check_sample_count(simulation.MAX_SAMPLES) == simulation.MAX_SAMPLES
    assert simulation.check_sample_count(501.0) == 501
    for bad in (0, -3, 2.5, True, "10"):
        with pytest.raises(SimulationError, match="--samples: the number of samples must be a whole number"):
            simulation.check_sample_count(bad, "--samples")
    with pytest.raises(SimulationError, match=r"--samples: 100000000 samples is more than the limit of 10000000"):
        simulation.check_sample_count(10**8, "--samples")
    # simulate applies the same limit to t_eval (lowered here, so the test builds no huge array)
    monkeypatch.setattr(simulation, "MAX_SAMPLES", 10)
    with pytest.raises(SimulationError, match=r"t_eval: 11 samples is more than the limit of 10 \(MAX_SAMPLES\)"):
        simulate(dc_motor(), (0.0, 1.0), {"U": 12.0}, t_eval=np.linspace(0.0, 1.0, 11))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"inputs": {"U": "12"}}, r"input 'U': expected a number, a callable u\(t\) or u\(t, y\), or a controller, "
                                  r"got '12' \(str\)"),
        ({"inputs": {"U": True}}, "input 'U': expected a number"),
        ({"inputs": {"U": np.inf}}, "input 'U': inf is not a finite number"),
        ({"inputs": {"U": 12.0}, "parameters": {"J": "1e-4"}}, "parameter 'J': expected a number or a callable of t"),
        ({"inputs": {"U": 12.0}, "parameters": {"J": np.nan}}, "parameter 'J': nan is not a finite number"),
        ({"inputs": {"U": 12.0}, "x0": {"J": "1"}}, r"x0\['J'\]: expected a number, got '1'"),
        ({"inputs": {"U": 12.0}, "max_step": 0.0}, "max_step: expected a positive number of seconds"),
        ({"inputs": {"U": 12.0}, "max_step": 1e-20}, r"max_step: 1e-20 s needs at least 1e\+20 steps"),
        ({"inputs": {"U": 12.0}, "max_evaluations": 0}, "max_evaluations: expected a whole number >= 1"),
    ],
)
def test_bad_constants_and_solver_limits_are_named(kwargs, message):
    with pytest.raises(SimulationError, match=message):
        simulate(dc_motor(), (0.0, 1.0), **kwargs)


def test_numpy_numbers_are_accepted_as_constant_inputs():
    result = simulate(rlc_circuit(), (0.0, 0.01), {"V": np.float32(2.0)}, x0={"C": np.array(1e-3)},
                      t_eval=[0.0, 0.01])
    assert result["V"].tolist() == [2.0, 2.0] and result["v_C"][0] == pytest.approx(1.0)


def test_a_nan_derivative_stops_the_integration_naming_the_state():
    # L_a = 0 divides by zero at once; LSODA used to call the model forever on NaN derivatives
    with pytest.raises(SimulationError, match=r"dp_L_a/dt is nan at t = 0; check the laws and parameters"):
        simulate(dc_motor(), (0.0, 1.0), {"U": 12.0}, parameters={"L_a": 0.0})


def test_a_stalled_or_endless_integration_ends_with_an_error(monkeypatch):
    from bondgraph import simulation

    with pytest.raises(SimulationError, match=r"max_evaluations: the integration evaluated the model 50 times "
                                              r"and reached only t = [0-9.e-]+ of 1"):
        simulate(dc_motor(), (0.0, 1.0), {"U": 12.0}, max_evaluations=50)
    # a step below the spacing of floats at t = 1e6 cannot advance the time: LSODA retries forever
    monkeypatch.setattr(simulation, "STALL_EVALUATIONS", 200)
    with pytest.raises(SimulationError, match=r"the integration makes no progress at t = 1000000.0: 200 evaluations"):
        simulate(dc_motor(), (1e6, 1e6 + 1e-3), {"U": 12.0}, max_step=1e-12,
                 max_evaluations=10**10)


def test_lsoda_failing_on_a_very_stiff_model_is_retried_with_radau():
    from bondgraph.simulation import SimulationWarning

    # an open circuit: R = 1e12 makes L/R = 1e-12 s; LSODA fails with repeated convergence failures
    with pytest.warns(SimulationWarning, match=r"LSODA failed at t = \S+ of 0.5: Repeated convergence failures.*"
                                               r"integrated with Radau instead"):
        result = simulate(rlc_circuit(), (0.0, 0.5), {"V": 2.0}, parameters={"R": 1e12})
    assert result.solver.success
    # after the L/R transient the current is V/R, minus the capacitor's share that still charges by V/R
    assert result["i"][-1] == pytest.approx(2.0 / 1e12, rel=1e-3)
    assert np.all(np.abs(result["i"][1:]) <= 2.0 / 1e12 * (1 + 1e-6))


def test_a_failure_of_both_methods_names_both(monkeypatch):
    from bondgraph import simulation

    monkeypatch.setattr(simulation, "FALLBACK_METHOD", "LSODA")  # a retry that fails the same way
    with pytest.raises(SimulationError, match=r"the integration LSODA failed at t = \S+ of 0.5: Repeated "
                                              r"convergence failures.*, and LSODA failed at t = "):
        simulate(rlc_circuit(), (0.0, 0.5), {"V": 1.0}, parameters={"C": 1e-300})


@pytest.mark.slow
def test_a_hopeless_pace_stops_the_integration_early():
    from bondgraph import simulation

    # an undamped LC circuit (period 2 pi sqrt(LC)) over a million seconds: about 1e9 evaluations
    equations = rlc_circuit().state_equations()
    with pytest.raises(SimulationError, match=rf"max_evaluations: {simulation.PACE_START} evaluations of the model "
                                              r"reached only t = \S+ of 1e\+06; at that pace the span needs about"):
        simulate(equations, (0.0, 1e6), {"V": 1.0}, parameters={"R": 0.0})
    # the same circuit over a span it can finish is not stopped: the pace check does not misjudge it
    result = simulate(equations, (0.0, 20.0), {"V": 1.0}, parameters={"R": 0.0}, t_eval=[0.0, 20.0])
    assert result.solver.nfev > simulation.PACE_START


def test_a_warning_of_an_input_is_passed_on_once_per_pass():
    import warnings

    calls = []

    def drive(t):
        calls.append(t)
        warnings.warn("input clipped", UserWarning)
        return 1.0

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        simulate(rlc_circuit(), (0.0, 0.01), {"V": drive}, t_eval=[0.0, 0.01])
    # called at every evaluation of the model; its warning shown once by the integration and at most once
    # more by the evaluation of the result
    assert len(calls) > 10
    assert {str(w.message) for w in caught} == {"input clipped"} and len(caught) <= 2
