"""The flexible power law: a power of the time since onset, whose exponent is estimated with the rate.

Judged against the closed form ``theta(t) = origin + span (a (t - onset))^q`` written here, never
against the library's own stepping; and in a bank beside one-gamma laws, whose rows must behave as if
the extra gamma were not there.
"""

import math

import numpy as np
import pytest

from bondgraph.errors import SettingError
from prognosis.degradation import LinearDegradation, PerAssetDegradation, PowerDegradation, degradation_model
from prognosis.errors import PrognosisError
from prognosis.resample_move import ResampleMoveFilter

ORIGIN, SPAN = 0.003, 0.447     # the torsion bar's b_Md from nominal to failure
RATE, EXPONENT = 1 / 90.0, 2.5  # failure 90 s after onset, as the 2.5th power of time


def closed_form(t: np.ndarray, rate: float = RATE, exponent: float = EXPONENT, onset: float = 0.0) -> np.ndarray:
    return ORIGIN + SPAN * np.power(rate * np.clip(t - onset, 0.0, None), exponent)


@pytest.mark.parametrize("exponent", [0.5, 1.0, 2.5, 5.0])
def test_stepping_follows_the_closed_form_at_any_step(exponent):
    model = PowerDegradation(ORIGIN, SPAN)
    gamma = np.array([[RATE, exponent]])
    for dt in (0.1, 7.0):
        theta, t = closed_form(np.array([3.0]), exponent=exponent), 3.0
        for _ in range(10):
            theta, t = model.step(theta, gamma, dt), t + dt
            assert theta[0] == pytest.approx(closed_form(np.array([t]), exponent=exponent)[0], rel=1e-9)


def test_exponent_one_is_the_linear_law_and_a_falling_parameter_falls():
    linear = LinearDegradation().step(np.array([0.5]), np.array([[SPAN * RATE]]), dt=2.0)
    power = PowerDegradation(ORIGIN, SPAN).step(np.array([0.5]), np.array([[RATE, 1.0]]), dt=2.0)
    assert power == pytest.approx(linear, rel=1e-12)
    falling = PowerDegradation(2.0, -1.5)  # from 2 down to 0.5
    assert falling.step(np.array([1.9]), np.array([[0.1, 2.0]]), dt=1.0)[0] < 1.9
    # on the nominal side of the origin it starts from the onset, never backwards
    assert falling.step(np.array([2.1]), np.array([[0.1, 2.0]]), dt=1.0)[0] == pytest.approx(2.0 - 1.5 * 0.01)


def test_horizon_path_equals_stepping_with_and_without_process_noise():
    model = PowerDegradation(ORIGIN, SPAN)
    rng = np.random.default_rng(0)
    theta = closed_form(rng.uniform(5, 40, 6))
    gamma = np.broadcast_to(np.column_stack([rng.uniform(0.005, 0.02, 6), rng.uniform(0.5, 4, 6)])[:, None, :],
                            (6, 50, 2))
    for noise in (np.zeros((6, 50)), 1e-4 * rng.standard_normal((6, 50))):
        current, stepped = theta, []
        for step in range(50):
            current = model.step(current, gamma[:, step, :], 0.5) + noise[:, step]
            stepped.append(current)
        assert np.allclose(model.path(theta, gamma, noise, 0.5), np.column_stack(stepped), rtol=1e-10, atol=1e-14)


def test_a_bank_of_laws_with_one_and_two_gammas_moves_each_row_by_its_own():
    bank = PerAssetDegradation((LinearDegradation(), PowerDegradation(ORIGIN, SPAN)), laws=(0, 1))
    assert bank.n_gamma == 2
    theta = np.array([[0.1, 0.2], [0.1, 0.2]])
    gamma = np.array([[[0.01, 7.0], [0.02, 7.0]], [[RATE, 2.0], [RATE, 1.0]]])
    moved = bank.step(theta, gamma, dt=1.0)
    assert moved[0] == pytest.approx([0.11, 0.22])  # the linear row ignores its second gamma
    assert moved[1] == pytest.approx(PowerDegradation(ORIGIN, SPAN).step(theta[1], gamma[1], 1.0))


def test_the_power_law_needs_its_ends():
    with pytest.raises(PrognosisError, match="nominal= and failure="):
        degradation_model("power")
    with pytest.raises(PrognosisError, match="nonzero span"):
        PowerDegradation(1.0, 0.0)


@pytest.mark.slow
def test_resample_move_finds_the_exponent_and_leaves_a_fixed_gamma_alone():
    """Rows of one bank: a power law on a 2.5-power wear, a linear law on the same record with its
    unused gamma fixed by the prior; the power row finds q, the linear row stays distinct and unmoved
    along the fixed coordinate."""
    dt, noise = 1.0, 2e-3
    t = 40.0 + dt * np.arange(50)
    rng = np.random.default_rng(7)
    y = closed_form(t) + rng.normal(0.0, noise, t.size)
    bank = PerAssetDegradation((PowerDegradation(ORIGIN, SPAN), LinearDegradation()), laws=(0, 1))
    f = ResampleMoveFilter(bank, lambda theta, points: theta, noise=noise, dt=dt, n_particles=400, seed=3)
    f.initialize(([0.0, 0.0], [0.2, 0.2]), gamma_bounds=([[1e-3, 0.5], [1e-4, 1.0]], [[1e-1, 5.0], [1e-1, 1.0]]),
                 assets=2, log_gamma=True)
    collapsed = [f.step(np.array([v, v])).collapsed for v in y]
    assert not np.any(collapsed)
    w = f.weights
    exponent = f.gamma[0, :, 1]
    order = np.argsort(exponent)
    cdf = np.cumsum(w[0][order])
    lo, hi = exponent[order][np.searchsorted(cdf, 0.01)], exponent[order][np.searchsorted(cdf, 0.99)]
    assert lo <= EXPONENT <= hi and hi - lo < 0.6   # a 98 % interval: it misses once in fifty
    assert np.all(f.gamma[1, :, 1] == 1.0)
    assert np.unique(f.gamma[1, :, 0]).size > 0.3 * f.n
    # a linear law cannot follow an accelerating wear: the evidence says so, decisively
    assert f.log_evidence[0] - f.log_evidence[1] > math.log(100.0)


def test_the_fleet_refuses_a_law_with_more_than_a_rate():
    from bondgraph.library import rlc_circuit
    from diagnosis import derive_arrs
    from prognosis.fleet import FleetMonitor

    arrs = derive_arrs(rlc_circuit())
    with pytest.raises(SettingError, match="'power' has more gammas"):
        FleetMonitor(arrs, {"R": 20.0}, noise_std={a.name: 1e-3 for a in arrs}, laws=("linear", "power"))
