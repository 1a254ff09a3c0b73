"""FMI 2.0 (bondgraph.fmu_export, bondgraph.fmu_plant, the ``fmi`` extra): an exported FMU run by fmpy agrees
with our simulation and with each model's hand-written physics, fmpy's validation accepts it, parameters set
through fmpy act as in our simulation, an imported FMU is the plant of an EKF, and an FMU that is not ours
(pythonfmu) reproduces its analytic solution."""

import os
import subprocess
import sys
import textwrap
import zipfile

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bondgraph import FmuError, FmuPlant, simulate, simulate_fmu, to_fmu
from bondgraph.library import dc_motor
from tests.zoo.chain import cases
from tests.zoo.reference import simulate_reference

fmpy = pytest.importorskip("fmpy")   # the fmi extra
validate_fmu = pytest.importorskip("fmpy.validation").validate_fmu

pytestmark = [pytest.mark.interop, pytest.mark.slow]   # a C compilation per FMU, fmpy, pythonfmu: seconds

ZOO = {case.name: case for case in cases()}
#: DC motor: a voltage step profile written like the zoo's step inputs, and its hand-written physics
MOTOR_STEPS = {"U": ((0.0, 0.0), (0.05, 12.0), (0.3, 6.0))}
MOTOR_END, MOTOR_DT = 0.5, 1e-3
#: The three zoo models: hydraulic with orifice laws (sign, sqrt, Abs), a cubic spring, a thermal two-input model;
#: the initial states of the orifice tanks by element (the case gives them by its own state names, in order)
MODELS = {"dc_motor": None, "orifice_tanks": {"T1": 0.0225, "T2": 0.008}, "duffing_oscillator": None,
          "heat_exchanger": None}
#: The agreement asked at every output sample, relative to each signal's range
AGREEMENT = 1e-6


def profile_of(name: str) -> tuple[dict, float, float]:
    if name == "dc_motor":
        return MOTOR_STEPS, MOTOR_END, MOTOR_DT
    case = ZOO[name]
    return case.step_inputs, case.t_end, case.dt


def model_of(name: str):
    return dc_motor() if name == "dc_motor" else ZOO[name].build()


def fmpy_input_table(profile: dict, t_end: float) -> np.ndarray:
    """fmpy's input table of a step profile: each step as two rows at the same time (a discontinuity)."""
    times = sorted({0.0, t_end, *(s for steps in profile.values() for s, _ in steps)})
    rows = []
    for k, time in enumerate(times):
        before = {name: [v for s, v in steps if s < time or (k == 0 and s <= time)][-1] for name, steps in
                  profile.items()}
        after = {name: [v for s, v in steps if s <= time][-1] for name, steps in profile.items()}
        rows.append((time, *before.values()))
        if after != before:
            rows.append((time, *after.values()))
    return np.array(rows, dtype=[("time", float), *((name, float) for name in profile)])


def simulate_by_stretches(bg, profile: dict, t_end: float, t: np.ndarray, x0: dict | None,
                          parameters: dict | None = None) -> dict:
    """Our simulate, tight, restarted at each step of the inputs (no solver steps across a discontinuity); at a
    step's instant the value before it, as fmpy records an output at the end of the step that reaches it."""
    cuts = sorted({0.0, t_end, *(s for steps in profile.values() for s, _ in steps if 0 < s < t_end)})
    equations = bg.state_equations()
    columns = {name: np.full(t.size, np.nan) for name in equations.outputs}
    state = dict(x0 or {})
    for start, end in zip(cuts[:-1], cuts[1:]):
        levels = {name: [v for s, v in steps if s <= start][-1] for name, steps in profile.items()}
        mask = (t > start + 1e-12 if start > 0 else t >= start) & (t <= end + 1e-12)
        inside = np.unique(np.clip(np.concatenate([[start], t[mask], [end]]), start, end))
        result = simulate(bg, (start, end), levels, x0=state, parameters=parameters, t_eval=inside,
                          rtol=1e-12, atol=1e-15)
        for name in columns:
            columns[name][mask] = np.interp(t[mask], result.t, result[name])
        state = {str(s): result.states[str(s)][-1] for s in equations.states}
    return columns


def motor_physics(t: np.ndarray, parameters: dict) -> dict:
    """The DC motor written by hand: L di/dt = U - R i - k w, J dw/dt = k i - b w (scipy, per input stretch)."""
    R, L, k, J, b = (parameters[n] for n in ("R_a", "L_a", "k_m", "J", "b"))
    state, out = np.zeros(2), {"i": np.full(t.size, np.nan), "omega": np.full(t.size, np.nan)}
    cuts = [0.0, 0.05, 0.3, MOTOR_END]
    for (start, end), U in zip(zip(cuts[:-1], cuts[1:]), (0.0, 12.0, 6.0)):
        def rhs(_, y, U=U):
            return [(U - R * y[0] - k * y[1]) / L, (k * y[0] - b * y[1]) / J]
        mask = (t >= start - 1e-12) & (t <= end + 1e-12)
        solution = solve_ivp(rhs, (start, end), state, method="Radau", rtol=1e-12, atol=1e-14, t_eval=t[mask])
        out["i"][mask], out["omega"][mask] = solution.y
        state = solve_ivp(rhs, (start, end), state, method="Radau", rtol=1e-12, atol=1e-14).y[:, -1]
    return out


def worst(reference: dict, measured, names, skip: np.ndarray | None = None) -> float:
    """The largest error over every sample (but those ``skip`` marks) and signal, relative to each signal's range."""
    keep = slice(None) if skip is None else ~skip
    return max(float(np.max(np.abs(np.asarray(measured[n])[keep] - reference[n][keep])) / np.ptp(reference[n]))
               for n in names)


def step_instants(t: np.ndarray, profile: dict) -> np.ndarray:
    """The samples at an input's step, where an output the input drives directly has two values."""
    return np.isin(np.round(t, 9), np.round([s for steps in profile.values() for s, _ in steps if s > 0], 9))


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The four models exported once (the orifice tanks from their initial levels)."""
    folder = tmp_path_factory.mktemp("fmus")
    return {name: to_fmu(model_of(name), folder / f"{name}.fmu", x0=x0, step=profile_of(name)[2])
            for name, x0 in MODELS.items()}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_an_exported_fmu_run_by_fmpy_agrees_with_simulate_and_the_physics(name, exported):
    path = exported[name]
    assert validate_fmu(str(path)) == []
    description = fmpy.read_model_description(str(path), validate=True, validate_variable_names=True,
                                              validate_model_structure=True)
    bg = model_of(name)
    equations = bg.state_equations()
    assert [v.name for v in description.modelVariables if v.causality == "output"] == \
        [*map(str, equations.states), *equations.outputs]
    profile, t_end, dt = profile_of(name)
    result = fmpy.simulate_fmu(str(path), stop_time=t_end, output_interval=dt, input=fmpy_input_table(profile, t_end))
    t = result["time"]
    assert t.size == round(t_end / dt) + 1 and np.allclose(t, np.arange(t.size) * dt)
    ours = simulate_by_stretches(bg, profile, t_end, t, MODELS[name])
    assert worst(ours, result, equations.outputs) < AGREEMENT
    physics = motor_physics(t, bg.parameters) if name == "dc_motor" else \
        simulate_reference(ZOO[name], inputs="step", order=0).columns
    # the reference takes the value after a step at its instant; the FMU's record, before
    assert worst(physics, result, equations.outputs, step_instants(t, profile)) < AGREEMENT


def test_parameters_set_through_fmpy_change_the_trajectory_as_simulate_does(exported):
    path, changed = str(exported["dc_motor"]), {"R_a": 2.0, "b": 5e-4, "J": 2e-4}
    table = fmpy_input_table(MOTOR_STEPS, MOTOR_END)
    nominal = fmpy.simulate_fmu(path, stop_time=MOTOR_END, output_interval=MOTOR_DT, input=table)
    result = fmpy.simulate_fmu(path, stop_time=MOTOR_END, output_interval=MOTOR_DT, input=table, start_values=changed)
    ours = simulate_by_stretches(dc_motor(), MOTOR_STEPS, MOTOR_END, result["time"], None, parameters=changed)
    assert worst(ours, result, ["i", "omega"]) < AGREEMENT
    assert worst(ours, nominal, ["omega"]) > 0.1   # the change is seen: the trajectories are far apart
    physics = motor_physics(result["time"], {**dc_motor().parameters, **changed})
    assert worst(physics, result, ["i", "omega"]) < AGREEMENT


def test_an_imported_fmu_is_the_plant_of_an_ekf(tmp_path):
    """The FMU (the DC motor, from a spinning start, with an armature resistance the filter does not know)
    makes noisy current and speed readings; the EKF on our discretized bond-graph model, the resistance an
    augmented state, tracks the FMU's own states and finds its resistance."""
    from prognosis.statespace import ExtendedKalmanFilter, discretize

    bg, dt, steps, true_r = dc_motor(), 1e-3, 400, 1.5   # the model's nominal R_a is 1.23 ohm
    path = to_fmu(bg, tmp_path / "motor.fmu", x0={"L_a": 1e-3, "J": 3e-3}, inputs={"U": 12.0})
    model = discretize(bg.state_equations(), dt=dt, method="rk4", augment=["R_a"])
    noise = np.array([0.05, 0.5])   # A, rad/s
    rng = np.random.default_rng(7)
    ekf = ExtendedKalmanFilter(model, [0.0, 0.0, bg.parameters["R_a"]], np.diag([1e-5, 1e-4, 0.1]),
                               np.diag([1e-12, 1e-12, 1e-10]), np.diag(noise**2))
    errors, read_errors, truth = [], [], []
    gains = np.array([bg.parameters["L_a"], bg.parameters["J"]])   # a reading as a state: p = L i, p = J omega
    with FmuPlant(path, parameters={"R_a": true_r}) as plant:
        start = np.array([plant.read()["p_L_a"], plant.read()["p_J"]])
        for _ in range(steps):
            out = plant.step(dt, {"U": 12.0})
            z = np.array([out["i"], out["omega"]]) + noise * rng.standard_normal(2)
            ekf.step(z, {"U": 12.0})
            truth.append([out["p_L_a"], out["p_J"]])
            errors.append(ekf.mean[:2] - truth[-1])
            read_errors.append(z * gains - truth[-1])
    span = np.ptp(truth, axis=0)
    assert np.all(np.abs(start) / span > 0.1)   # the filter starts at rest, far from the plant
    assert np.all(np.abs(errors[-100:]).max(axis=0) / span < 0.005)   # it ends within 0.5 % of each range
    rms = np.sqrt(np.mean(np.square(errors[-200:]), axis=0))
    assert np.all(rms < 0.25 * np.sqrt(np.mean(np.square(read_errors[-200:]), axis=0)))   # it filters the noise
    assert abs(ekf.mean[2] - true_r) < 0.01 * true_r < abs(bg.parameters["R_a"] - true_r)


def test_simulate_fmu_runs_an_fmu_that_is_not_ours(tmp_path):
    """A mass-spring-damper written with pythonfmu (its own RK4 inside each step) against the analytic step
    response: the import works on any FMI 2.0 co-simulation FMU, not only on ours."""
    source = tmp_path / "msd.py"
    source.write_text(textwrap.dedent('''
        from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


        class msd(Fmi2Slave):
            description = "mass-spring-damper: m x'' + c x' + k x = F"

            def __init__(self, **kwargs):
                super().__init__(**kwargs)
                self.m, self.c, self.k, self.F, self.x, self.v = 2.0, 0.8, 50.0, 0.0, 0.0, 0.0
                for name in ("m", "c", "k"):
                    self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                                variability=Fmi2Variability.tunable))
                self.register_variable(Real("F", causality=Fmi2Causality.input))
                self.register_variable(Real("x", causality=Fmi2Causality.output))
                self.register_variable(Real("v", causality=Fmi2Causality.output))

            def do_step(self, current_time, step_size):
                h = step_size / 20
                for _ in range(20):
                    def rate(x, v):
                        return v, (self.F - self.c * v - self.k * x) / self.m
                    a = rate(self.x, self.v)
                    b = rate(self.x + h / 2 * a[0], self.v + h / 2 * a[1])
                    c = rate(self.x + h / 2 * b[0], self.v + h / 2 * b[1])
                    d = rate(self.x + h * c[0], self.v + h * c[1])
                    self.x += h / 6 * (a[0] + 2 * b[0] + 2 * c[0] + d[0])
                    self.v += h / 6 * (a[1] + 2 * b[1] + 2 * c[1] + d[1])
                return True
    '''))
    subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", str(source), "-d", str(tmp_path)], check=True,
                   capture_output=True)
    t = np.linspace(0.0, 3.0, 301)
    record = simulate_fmu(tmp_path / "msd.fmu", t, {"F": 10.0}, parameters={"k": 40.0})
    assert sorted(record) == ["F", "t", "v", "x"]
    m, c, k, force = 2.0, 0.8, 40.0, 10.0
    wn, zeta = np.sqrt(k / m), c / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - zeta**2)
    x = force / k * (1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * t)))
    assert np.max(np.abs(record["x"] - x)) / np.ptp(x) < AGREEMENT
    with pytest.raises(FmuError, match=r"FMU 'msd.fmu' has no output 'a'; its outputs are \['x', 'v'\]"):
        simulate_fmu(tmp_path / "msd.fmu", t, outputs=["a"])


def test_bad_fmus_outputs_inputs_and_parameters_are_named(tmp_path, exported):
    path, t = exported["dc_motor"], np.linspace(0.0, 0.01, 11)
    text = tmp_path / "notes.fmu"
    text.write_text("not a zip")
    empty = tmp_path / "empty.fmu"
    with zipfile.ZipFile(empty, "w") as archive:
        archive.writestr("readme.txt", "no model description")
    cases = [((text, t), r"^'notes.fmu' is not an FMU: not a zip archive$"),
             ((empty, t), r"^'empty.fmu' is not an FMU: it holds no modelDescription.xml$"),
             ((tmp_path / "missing.fmu", t), r"^FMU 'missing.fmu': no such file"),
             ((path, t, None, {"R": 1.0}), r"^FMU 'dc_motor.fmu' has no parameter 'R' to set; its parameters"),
             ((path, t, {"V": 1.0}), r"^FMU 'dc_motor.fmu' has no input 'V'; its inputs are \['U'\]$"),
             ((path, t, {"U": "12"}), r"^input 'U' of FMU 'dc_motor.fmu' must be a number, got '12'$")]
    for arguments, message in cases:
        with pytest.raises(FmuError, match=message):
            simulate_fmu(*arguments)
    with pytest.raises(FmuError, match=r"^FMU 'dc_motor.fmu' has no output 'torque'; its outputs are \['p_L_a', "):
        simulate_fmu(path, t, outputs=["torque"])
    with pytest.raises(FmuError, match=r"fmi2DoStep failed at t = 0: .*the derivative of p_L_a is NaN"):
        simulate_fmu(path, t, {"U": 1.0}, parameters={"J": 0.0})   # 0/0: the FMU's own message is passed on
    with pytest.raises(FmuError, match=r"^to_fmu: parameter 'R' is not in the model; it has \['R_a', "):
        to_fmu(dc_motor(), tmp_path / "x.fmu", parameters={"R": 1.0})
    with pytest.raises(FmuError, match=r"^to_fmu: the C compiler 'no-such-cc' is not on the PATH$"):
        to_fmu(dc_motor(), tmp_path / "x.fmu", compiler="no-such-cc")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty.fmu", "notes.fmu"]   # no FMU half written


def test_the_plant_steps_a_tunable_parameter_and_frees_its_files(exported):
    """A parameter changed between steps acts from then on, as our simulate with a parameter of time does."""
    dt = 1e-3
    with FmuPlant(exported["dc_motor"]) as plant:
        omega = [plant.step(dt, {"U": 12.0})["omega"] for _ in range(200)]
        plant.set_parameter("b", 1e-3)
        omega += [plant.step(dt, {"U": 12.0})["omega"] for _ in range(200)]
        folder = plant._unpacked
    t = np.arange(1, 401) * dt
    ours = simulate(dc_motor(), (0.0, 0.4), {"U": 12.0}, parameters={"b": lambda s: 1e-4 if s < 0.2 else 1e-3},
                    t_eval=t, rtol=1e-12, atol=1e-15, max_step=1e-4)
    assert np.max(np.abs(np.array(omega) - ours["omega"])) / np.ptp(ours["omega"]) < 1e-5
    assert not os.path.exists(folder)
