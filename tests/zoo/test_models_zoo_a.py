"""The zoo-a models: the library's simulation against each model's own physics, and every default ARR's
identity ``r_n + Psi_2 = 0`` on the physics' exact run, both at parameters inside the uncertainty box."""

import warnings

import numpy as np
import pytest

from diagnosis import ARRWarning, derive_arrs
from tests.zoo.check import inside_box, library_run, load_case, relative_errors
from tests.zoo.identity import identity_error
from tests.zoo.reference import simulate_reference

# about 1-2 s of CPU per model: the fast tier keeps tests/zoo/test_chain.py's subset
pytestmark = pytest.mark.slow

MODELS = ["rc_ladder2", "rlc_ladder3", "pi_filter", "transformer_load", "wheatstone_rc", "buck_averaged",
          "wall_two_layer", "heat_exchanger", "power_module_thermal", "tank_circuit", "loudspeaker", "dc_generator",
          "pump_drive", "piezo_stack", "throttle_body"]
# derive_arrs alone takes 2-5 s of CPU on these (elimination over six states, or many candidate sets)
SLOW_DERIVATION = {"rlc_ladder3", "wall_two_layer", "throttle_body"}
SHORT = 0.2  # share of each record used here: every mode excited, a fifth of the work


def _params(names, slow=frozenset()):
    return [pytest.param(n, marks=pytest.mark.slow) if n in slow else n for n in names]


@pytest.mark.parametrize("name", _params(MODELS, SLOW_DERIVATION))
def test_simulation_and_every_default_arr_agree_with_the_physics(name):
    case = load_case(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        arrs = derive_arrs(case.build())
    assert arrs
    box = inside_box(case)
    order = max(1, *(arr.order for arr in arrs))   # exact derivatives up to what the ARRs read
    run = simulate_reference(case, parameters=box, t_end=case.t_end * SHORT, order=order)
    errors = relative_errors(case, library_run(case, case.t_end * SHORT, parameters=box), run)
    assert set(errors) == set(case.outputs)
    assert max(errors.values()) < 1e-5, errors
    identity = {arr.name: identity_error(arr, run) for arr in arrs}
    for arr in arrs:
        # a running integral on the grid is a trapezoid sum: its error is the sampling's, not the solver's
        assert identity[arr.name] < (1e-3 if arr.integrals else 1e-6), identity


@pytest.mark.slow
@pytest.mark.parametrize("name", MODELS)
def test_step_record_is_complete_and_moves(name):
    case = load_case(name)
    run = simulate_reference(case, inputs="step", order=0)
    for sensor, noise in case.noise.items():
        column = run.columns[sensor]
        assert np.all(np.isfinite(column)), sensor
        assert np.ptp(column) > 20 * noise, sensor   # the noise is a small share of the signal's range
