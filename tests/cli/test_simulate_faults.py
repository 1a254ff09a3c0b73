"""``bgphm simulate``'s fault injection: degradations, sensor faults and noise, inputs as expressions or a CSV file.

The records are checked against the world: a degradation against an integration of the DC motor's two
equations written here from the physics (not the library's simulate), a sensor's fault against its formula
on the noise-free record, an input's step against the time invariance of the motor.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bgphm.cli import build_parser, main
from bondgraph.io import to_json
from bondgraph.library import dc_motor
from diagnosis import add_noise, read_csv

R_A, L_A, K_M, J, B, U = 1.23, 1.34e-3, 3.89e-2, 1e-4, 1e-4, 12.0   # the library's DC motor at 12 V
T_END, SAMPLES = 4.0, 401
T = np.linspace(0.0, T_END, SAMPLES)


def run(capsys, *argv):
    code = main(["--quiet", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def simulated(tmp_path, *options, model="dc-motor", name="run.csv"):
    """The record ``bgphm simulate`` writes with these options (4 s, 401 samples)."""
    path = tmp_path / name
    assert main(["--quiet", "simulate", model, "--t-end", str(T_END), "--samples", str(SAMPLES), *options,
                 "--out", str(path), "--force"]) == 0
    return read_csv(path)


def motor(b, breaks=(), voltage=lambda s: U):
    """i and omega at T from L di/dt = U - R_a i - k_m omega, J domega/dt = k_m i - b(t) omega, from rest,
    integrated piece by piece between the ``breaks`` (where b or U jumps or bends)."""
    def rhs(s, y):
        i, omega = y
        return [(voltage(s) - R_A * i - K_M * omega) / L_A, (K_M * i - b(s) * omega) / J]

    edges, state, columns = [0.0, *breaks, T_END], [0.0, 0.0], []
    for start, stop in zip(edges[:-1], edges[1:]):
        piece = solve_ivp(rhs, (start, stop), state, method="Radau", rtol=1e-11, atol=1e-12, dense_output=True)
        inside = (T >= start) & ((T < stop) if stop < T_END else (T <= stop))
        columns.append(piece.sol(T[inside]))
        state = piece.y[:, -1]
    i, omega = np.concatenate(columns, axis=1)
    return i, omega


# ------------------------------------------------------------------------------------------- --degrade


@pytest.mark.parametrize("law, b, onset", [
    ("lin:3e-4@1", lambda s: B + 3e-4 * max(s - 1.0, 0.0), 1.0),
    # the other laws in the slow tier: each a whole simulate command (a second of the fast tier's budget)
    pytest.param("exp:0.8@1", lambda s: B * np.exp(0.8 * max(s - 1.0, 0.0)), 1.0, marks=pytest.mark.slow),
    pytest.param("pow:5e-4^2@1.5", lambda s: B + 5e-4 * max(s - 1.5, 0.0) ** 2, 1.5, marks=pytest.mark.slow),
    pytest.param("step:4e-4@2", lambda s: B + (4e-4 if s >= 2.0 else 0.0), 2.0, marks=pytest.mark.slow),
])
def test_a_degradation_follows_the_motors_equations(tmp_path, law, b, onset):
    record = simulated(tmp_path, "--degrade", f"b={law}")
    i, omega = motor(b, breaks=(onset,))
    np.testing.assert_allclose(record["omega"], omega, rtol=1e-6, atol=1e-6 * omega.max())
    np.testing.assert_allclose(record["i"], i, rtol=1e-6, atol=1e-6 * i.max())
    _, healthy = motor(lambda s: B)
    assert np.abs(healthy - omega).max() > 1e3 * 1e-6 * omega.max()       # the wear shows, far above the tolerance
    before = T < onset                                                   # the solver's steps differ, not the motor
    np.testing.assert_allclose(record["omega"][before], healthy[before], rtol=1e-6, atol=1e-6 * omega.max())


@pytest.mark.slow   # a second of CPU: the fast tier stays under a minute
def test_degradations_of_two_parameters_act_together(tmp_path):
    record = simulated(tmp_path, "--degrade", "b=exp:0.5@1", "--degrade", "R_a=lin:0.1@2")
    i, omega = motor(lambda s: B * np.exp(0.5 * max(s - 1.0, 0.0)), breaks=(1.0, 2.0))
    assert np.abs(record["omega"] - omega).max() > 1.0                    # R_a's wear is there too
    resistance = lambda s: R_A + 0.1 * max(s - 2.0, 0.0)                 # noqa: E731

    def rhs(s, y):
        b = B * np.exp(0.5 * max(s - 1.0, 0.0))
        return [(U - resistance(s) * y[0] - K_M * y[1]) / L_A, (K_M * y[0] - b * y[1]) / J]
    both = solve_ivp(rhs, (0.0, T_END), [0.0, 0.0], method="Radau", rtol=1e-11, atol=1e-12, t_eval=T)
    np.testing.assert_allclose(record["omega"], both.y[1], rtol=1e-6, atol=1e-6 * both.y[1].max())


# ------------------------------------------------------------------------------------------- sensor faults


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    return simulated(tmp_path_factory.mktemp("clean"))


@pytest.mark.parametrize("option, item, formula", [
    ("--bias", "omega=5@2", lambda t, x: np.where(t >= 2.0, x + 5.0, x)),
    ("--bias", "i=-0.2", lambda t, x: x - 0.2),                                   # no onset: from 0
    ("--drift", "omega=1.5@1", lambda t, x: np.where(t >= 1.0, x + 1.5 * (t - 1.0), x)),
    ("--gain", "i=1.1@0.5", lambda t, x: np.where(t >= 0.5, 1.1 * x, x)),
])
def test_a_sensor_fault_is_its_formula_on_the_noise_free_record(tmp_path, clean, option, item, formula):
    signal = item.split("=")[0]
    record = simulated(tmp_path, option, item)
    np.testing.assert_allclose(record[signal], formula(T, clean[signal]), rtol=1e-15, atol=1e-15)
    other = {"i": "omega", "omega": "i"}[signal]
    assert np.array_equal(record[other], clean[other]) and np.array_equal(record["U"], clean["U"])


def test_a_sensors_gain_bias_drift_and_noise_combine(tmp_path, clean):
    record = simulated(tmp_path, "--drift", "omega=2@3", "--bias", "omega=-4@1", "--gain", "omega=0.95@2",
                       "--noise", "omega=0.5", "--noise", "i=0.01", "--seed", "7")
    x = clean["omega"]
    faulty = np.where(T >= 2.0, 0.95 * x, x) + np.where(T >= 1.0, -4.0, 0.0) + np.where(T >= 3.0, 2.0 * (T - 3.0), 0)
    draws = add_noise(clean, {"omega": 0.5, "i": 0.01}, seed=7)
    np.testing.assert_allclose(record["omega"] - faulty, draws["omega"] - x, atol=1e-9)
    assert np.array_equal(record["i"], draws["i"])


def test_noise_is_bitwise_the_librarys_add_noise_with_the_same_seed(tmp_path, clean):
    record = simulated(tmp_path, "--noise", "omega=0.5", "--seed", "3")
    expected = add_noise(clean, {"omega": 0.5}, seed=3)
    assert np.array_equal(record["omega"], expected["omega"]) and np.array_equal(record["i"], clean["i"])
    default = simulated(tmp_path, "--noise", "omega=0.5", name="seed0.csv")
    assert np.array_equal(default["omega"], add_noise(clean, {"omega": 0.5}, seed=0)["omega"])
    assert not np.array_equal(default["omega"], record["omega"])
    assert 0.45 < np.std(record["omega"] - clean["omega"]) < 0.55


def test_without_injection_the_csv_keeps_its_format(tmp_path, clean):
    path = tmp_path / "plain.csv"
    assert main(["--quiet", "simulate", "dc-motor", "--t-end", "4", "--samples", "401", "--out", str(path)]) == 0
    header, first = path.read_text().splitlines()[:2]
    assert header == "t,U,i,omega" and first == "0.0,12.0,0.0,0.0"
    assert np.array_equal(read_csv(path)["omega"], clean["omega"])


# ------------------------------------------------------------------------------------------- inputs


def test_an_input_expression_steps_the_motor_as_a_shifted_start(tmp_path, clean):
    record = simulated(tmp_path, "--input", "U=12*step(t - 1)")
    assert np.all(record["U"][T < 1.0] == 0.0) and np.all(record["U"][T >= 1.0] == 12.0)
    assert np.all(record["omega"][T < 1.0] == 0.0)
    shift = 100                                                           # 1 s of 0.01 s samples
    # the motor is time-invariant: started at 1 s, it runs as the clean run started at 0
    np.testing.assert_allclose(record["omega"][shift:], clean["omega"][:-shift], rtol=1e-6, atol=1e-4)
    i, omega = motor(lambda s: B, breaks=(1.0,), voltage=lambda s: 12.0 if s >= 1.0 else 0.0)
    np.testing.assert_allclose(record["omega"], omega, rtol=1e-6, atol=1e-6 * omega.max())


def test_inputs_from_a_csv_file_are_interpolated_and_held(tmp_path):
    table = tmp_path / "voltage.csv"
    table.write_text("t,U\n0.5,0\n1.0,12\n2.0,12\n3.0,6\n")
    record = simulated(tmp_path, "--inputs", str(table))
    np.testing.assert_allclose(record["U"], np.interp(T, [0.5, 1.0, 2.0, 3.0], [0.0, 12.0, 12.0, 6.0]), rtol=1e-14)
    ramp = simulated(tmp_path, "--input", "U=Min(Max(24*(t - 0.5), 0), 12, Max(12 - 6*(t - 2), 6))", name="ramp.csv")
    np.testing.assert_allclose(record["U"], ramp["U"], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(record["omega"], ramp["omega"], rtol=1e-6, atol=1e-6 * ramp["omega"].max())


def test_a_json_model_may_hold_its_input_as_an_expression(tmp_path):
    model = tmp_path / "motor.json"
    model.write_text(to_json(dc_motor(), inputs={"U": "12*step(t - 1)"}))
    from_file = simulated(tmp_path, model=str(model), name="file.csv")
    from_option = simulated(tmp_path, "--input", "U=12*step(t - 1)", name="option.csv")
    assert np.array_equal(from_file["omega"], from_option["omega"]) and from_file["U"][-1] == 12.0
    overridden = simulated(tmp_path, "--input", "U=6", model=str(model), name="six.csv")  # the option wins
    assert np.all(overridden["U"] == 6.0)


def test_the_inputs_file_is_never_overwritten(tmp_path, capsys):
    table = tmp_path / "voltage.csv"
    table.write_text("t,U\n0,12\n1,12\n2,12\n")
    code, _, err = run(capsys, "simulate", "dc-motor", "--inputs", str(table), "--out", str(table), "--force")
    assert code == 2 and "voltage.csv" in err and table.read_text() == "t,U\n0,12\n1,12\n2,12\n"


# ------------------------------------------------------------------------------------------- bad options


@pytest.mark.parametrize("options, message", [
    (["--degrade", "b"], "--degrade 'b': expected PARAM=LAW:RATE@ONSET"),
    (["--degrade", "zeta=exp:0.1@1"], "--degrade 'zeta=exp:0.1@1': the model has no parameter 'zeta' (parameters: R_a"),
    (["--degrade", "b=exq:0.1@1"], "--degrade b=exq:0.1@1: unknown law 'exq'"),
    (["--degrade", "b=exp:fast@1"], "--degrade b=exp:fast@1: the rate 'fast' is not a number"),
    (["--degrade", "b=exp:0.1@soon"], "--degrade b=exp:0.1@soon: the onset 'soon' is not a number"),
    (["--degrade", "b=pow:1e-4@1"], "--degrade b=pow:1e-4@1: a power law needs its exponent"),
    (["--degrade", "b=exp:0.1@1", "--set", "b=2e-4"], "--degrade 'b=exp:0.1@1': b is also set by --set"),
    (["--degrade", "b=exp:0.1@1", "--degrade", "b=lin:1e-4@1"], "--degrade 'b=lin:1e-4@1': b has a degradation"),
    (["--degrade", "b=lin:-1e-4@1"], "--degrade b=lin:-1e-4@1: the law takes the value from 0.0001 to -0.0002 by "
                                     "t = 4 s, outside the physical domain (0, inf)"),
    (["--degrade", "b=exp:1000"], "--degrade b=exp:1000: the value overflows to infinity by t = 4 s"),
    (["--noise", "omega"], "--noise 'omega': expected SIGNAL=STD"),
    (["--noise", "speed=0.5"], "--noise 'speed=0.5': the record has no signal 'speed' (signals: U, i, omega)"),
    (["--noise", "omega=loud"], "--noise 'omega=loud': the standard deviation 'loud' is not a number"),
    (["--noise", "omega=-0.5"], "--noise 'omega=-0.5': the standard deviation must be >= 0, got -0.5"),
    (["--noise", "omega=inf"], "--noise 'omega=inf': the standard deviation must be finite"),
    (["--noise", "omega=0.5@1"], "--noise 'omega=0.5@1': the noise has no onset"),
    (["--noise", "omega=0.5", "--noise", "omega=1"], "--noise 'omega=1': omega has a noise already"),
    (["--bias", "omega"], "--bias 'omega': expected SIGNAL=VALUE@ONSET"),
    (["--bias", "speed=1@2"], "--bias 'speed=1@2': the record has no signal 'speed'"),
    (["--bias", "omega=big@2"], "--bias 'omega=big@2': the value 'big' is not a number"),
    (["--bias", "omega=1@later"], "--bias 'omega=1@later': the onset 'later' is not a number"),
    (["--bias", "omega=1@2", "--bias", "omega=2@3"], "--bias 'omega=2@3': omega has a bias already"),
    (["--drift", "i=nan@1"], "--drift 'i=nan@1': the rate must be finite, got 'nan'"),
    (["--drift", "i"], "--drift 'i': expected SIGNAL=RATE@ONSET"),
    (["--gain", "omega=x2"], "--gain 'omega=x2': the factor 'x2' is not a number"),
    (["--gain", "i"], "--gain 'i': expected SIGNAL=FACTOR@ONSET"),
    (["--input", "U"], "--input 'U': expected SIGNAL=EXPR"),
    (["--input", "V=12"], "--input 'V=12': 'V' is not an input signal of the model (inputs: U)"),
    (["--input", "U=12*x"], "--input U: unknown name 'x' (allowed: t)"),
    (["--input", "U=__import__('os').system('x')"], "--input U: call to \"__import__('os').system\" not allowed"),
    (["--input", "U=1/t"], "--input U: 1/t is not finite at t = 0"),
    (["--input", "U=12", "--input", "U=6"], "--input 'U=6': U is given twice"),
    (["--seed", "-1", "--noise", "omega=1"], "--seed must be a whole number >= 0, got -1"),
    (["--degrade", "b=exp:\x1b[2J@1"], "--degrade b=exp:\\x1b[2J@1: the rate '\\x1b[2J' is not a number"),
])
def test_a_bad_option_exits_2_with_one_line_naming_it(capsys, options, message):
    code, out, err = run(capsys, "simulate", "dc-motor", "--t-end", "4", *options)
    assert code == 2 and out == ""
    assert message in err and err.count("\n") == 1 and err.startswith("bgphm: error: ")
    assert "\x1b" not in err                                           # the user's text is shown, never obeyed


@pytest.mark.parametrize("table, message", [
    ("t,V\n0,1\n1,1\n2,1\n", "--inputs {path}: column 'V': 'V' is not an input signal of the model (inputs: U)"),
    ("t\n0\n1\n2\n", "--inputs {path}: no column but t"),
    ("t,U\n0,1\n1,\n2,1\n", "--inputs {path}: column 'U': no value at t = 1 (a gap)"),
    ("t,U\n0,1\n1,abc\n2,1\n", "--inputs: {path} line 3, column 'U': 'abc' is not a number"),
    ("time,U\n0,1\n1,1\n2,1\n", "--inputs: {path}"),
])
def test_a_bad_inputs_file_exits_2_naming_the_option_file_and_column(tmp_path, capsys, table, message):
    path = tmp_path / "inputs.csv"
    path.write_text(table)
    code, _, err = run(capsys, "simulate", "dc-motor", "--inputs", str(path))
    assert code == 2 and message.format(path=path) in err and err.count("\n") == 1


def test_an_input_in_the_file_and_an_option_is_refused(tmp_path, capsys):
    path = tmp_path / "inputs.csv"
    path.write_text("t,U\n0,1\n1,1\n2,1\n")
    code, _, err = run(capsys, "simulate", "dc-motor", "--inputs", str(path), "--input", "U=12")
    assert code == 2 and f"--input 'U=12': U is a column of --inputs {path} too; give one of them" in err


def test_the_help_lists_the_injection_options():
    text = build_parser()._subparsers._group_actions[0].choices["simulate"].format_help()
    for option in ("--degrade PARAM=LAW:RATE@ONSET", "--noise SIGNAL=STD", "--bias SIGNAL=VALUE@ONSET",
                   "--drift SIGNAL=RATE@ONSET", "--gain SIGNAL=FACTOR@ONSET", "--input SIGNAL=EXPR",
                   "--inputs FILE.csv", "--seed SEED"):
        assert option in text, option
    assert "exp:RATE" in text and "step" in text


def test_the_injected_faults_are_reported_on_stderr(tmp_path, capsys):
    code = main(["simulate", "dc-motor", "--t-end", "1", "--degrade", "b=exp:0.8@0.5", "--bias", "omega=2@0.5",
                 "--noise", "omega=0.5", "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert code == 0
    assert "b exp:0.8@0.5" in err and "omega bias 2 from 0.5 s" in err and "sensor noise (seed 0): omega std 0.5" in err
