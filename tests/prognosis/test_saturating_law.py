"""The saturating law: a power law of the time since onset that levels off toward ``1 / c`` of the way.

Judged against the closed form ``theta(t) = origin + span (1 - exp(-c (a (t - onset))^q)) / c`` written
here (and, for c -> 0, against the power law's), never against the library's own stepping.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from bondgraph.errors import SettingError
from prognosis.degradation import (LinearDegradation, PerAssetDegradation, PowerDegradation, SaturatingDegradation,
                                   degradation_model)
from prognosis.errors import PrognosisError
from prognosis.resample_move import ResampleMoveFilter

ORIGIN, SPAN = 0.003, 0.447     # the torsion bar's b_Md from nominal to failure
RATE, EXPONENT, LEVEL = 1 / 90.0, 2.5, 0.8


def closed_form(t, rate=RATE, exponent=EXPONENT, level=LEVEL, onset=0.0):
    w = np.power(rate * np.clip(np.asarray(t, float) - onset, 0.0, None), exponent)
    return ORIGIN + SPAN * (1.0 - np.exp(-level * w)) / level


@pytest.mark.parametrize("exponent, level", [(0.5, 0.05), (1.0, 0.5), (2.5, 0.8), (5.0, 0.99)])
def test_stepping_follows_the_closed_form_at_any_step(exponent, level):
    model = SaturatingDegradation(ORIGIN, SPAN)
    gamma = np.array([[RATE, exponent, level]])
    for dt in (0.1, 7.0):
        theta, t = closed_form(3.0, exponent=exponent, level=level), 3.0
        for _ in range(10):
            theta, t = model.step(np.atleast_1d(theta), gamma, dt), t + dt
            assert theta[0] == pytest.approx(closed_form(t, exponent=exponent, level=level), rel=1e-9)
        # the trajectory in closed form says the same, at once
        start = closed_form(3.0, exponent=exponent, level=level)
        path = model.trajectory(np.array([start]), gamma, 0, 11, dt)[0]
        assert path == pytest.approx(closed_form(3.0 + dt * np.arange(11), exponent=exponent, level=level), rel=1e-9)


def test_crossing_is_the_root_of_the_closed_form():
    model = SaturatingDegradation(ORIGIN, SPAN)
    fail = ORIGIN + SPAN
    for exponent, level, now in [(1.0, 0.5, 10.0), (2.5, 0.8, 40.0), (4.0, 0.95, 80.0)]:
        root = brentq(lambda t: closed_form(t, exponent=exponent, level=level) - fail, now, 1e5)
        theta = np.array([closed_form(now, exponent=exponent, level=level)])
        crossing = model.crossing(theta, np.array([[RATE, exponent, level]]), fail)[0]
        assert crossing == pytest.approx(root - now, rel=1e-9)
    # a level at or below the failure value (c >= 1) never gets there
    assert model.crossing(np.array([0.1]), np.array([[RATE, 2.0, 1.2]]), fail)[0] == math.inf


def test_a_small_level_is_the_power_law_and_the_law_slows_where_the_power_law_does_not():
    theta, power = np.array([0.1]), PowerDegradation(ORIGIN, SPAN)
    gamma = np.array([[RATE, EXPONENT]])
    nearly = SaturatingDegradation(ORIGIN, SPAN).step(theta, np.array([[RATE, EXPONENT, 1e-9]]), 5.0)
    assert nearly == pytest.approx(power.step(theta, gamma, 5.0), rel=1e-7)
    # late in life the saturating law's increments shrink, the power law's (q > 1) grow
    t = np.array([60.0, 70.0, 80.0, 90.0])
    assert np.all(np.diff(np.diff(closed_form(t, exponent=1.0, level=0.9))) < 0)
    law = SaturatingDegradation(ORIGIN, SPAN)
    path = law.trajectory(np.array([closed_form(60.0, exponent=1.0, level=0.9)]), np.array([[RATE, 1.0, 0.9]]),
                          0, 4, 10.0)[0]
    assert np.all(np.diff(np.diff(path)) < 0)


def test_a_theta_beyond_its_level_stays_and_a_falling_parameter_falls():
    model = SaturatingDegradation(ORIGIN, SPAN)
    beyond = ORIGIN + SPAN * 1.5           # beyond the level 1 / 0.8 = 1.25 of the way
    assert model.step(np.array([beyond]), np.array([[RATE, 2.0, 0.8]]), 1.0)[0] == beyond
    falling = SaturatingDegradation(2.0, -1.5)  # from 2 down to 0.5
    assert falling.step(np.array([1.9]), np.array([[0.1, 2.0, 0.5]]), dt=1.0)[0] < 1.9


def test_path_equals_stepping_with_process_noise_and_the_law_needs_its_ends():
    model = SaturatingDegradation(ORIGIN, SPAN)
    rng = np.random.default_rng(1)
    theta = closed_form(rng.uniform(5, 40, 4))
    gamma = np.broadcast_to(np.array([RATE, 2.0, 0.5]), (4, 20, 3))
    noise = 1e-4 * rng.standard_normal((4, 20))
    current, stepped = theta, []
    for step in range(20):
        current = model.step(current, gamma[:, step, :], 0.5) + noise[:, step]
        stepped.append(current)
    assert np.allclose(model.path(theta, gamma, noise, 0.5), np.column_stack(stepped), rtol=1e-12)
    with pytest.raises(PrognosisError, match="saturating law runs from the nominal to the failure value"):
        degradation_model("saturating")
    with pytest.raises(PrognosisError, match="nonzero span"):
        SaturatingDegradation(1.0, 0.0)
    assert degradation_model("saturating", nominal=1.0, failure=3.0) == SaturatingDegradation(1.0, 2.0)


@pytest.mark.slow
def test_resample_move_tells_a_saturating_wear_from_a_power_law():
    """A wear that levels off (q = 2.5, c = 0.8), seen to 80 % of its life: the saturating row finds a
    level inside a 98 % interval and beats the power law on evidence; a bank with a linear row (one
    gamma) leaves that row's fixed gammas alone."""
    dt, noise = 1.0, 2e-3
    t = 10.0 + dt * np.arange(70)
    rng = np.random.default_rng(11)
    y = closed_form(t) + rng.normal(0.0, noise, t.size)
    bank = PerAssetDegradation((SaturatingDegradation(ORIGIN, SPAN), PowerDegradation(ORIGIN, SPAN),
                                LinearDegradation()), laws=(0, 1, 2))
    f = ResampleMoveFilter(bank, lambda theta, points: theta, noise=noise, dt=dt, n_particles=400, seed=5)
    f.initialize(([0.0] * 3, [0.02] * 3),
                 gamma_bounds=([[1e-3, 0.5, 0.05], [1e-3, 0.5, 1.0], [1e-4, 1.0, 1.0]],
                               [[1e-1, 5.0, 0.99], [1e-1, 5.0, 1.0], [1e-1, 1.0, 1.0]]),
                 assets=3, log_gamma=True)
    assert not np.any([f.step(np.array([v, v, v])).collapsed for v in y])
    level, w = f.gamma[0, :, 2], f.weights[0]
    order = np.argsort(level)
    cdf = np.cumsum(w[order])
    lo, hi = level[order][np.searchsorted(cdf, 0.01)], level[order][np.searchsorted(cdf, 0.99)]
    assert lo <= LEVEL <= hi
    assert f.log_evidence[0] - f.log_evidence[1] > math.log(100.0)
    assert np.all(f.gamma[2, :, 1:] == 1.0) and np.all(f.gamma[1, :, 2] == 1.0)


def test_the_fleet_refuses_the_saturating_law():
    from bondgraph.library import rlc_circuit
    from diagnosis import derive_arrs
    from prognosis.fleet import FleetMonitor

    arrs = derive_arrs(rlc_circuit())
    with pytest.raises(SettingError, match="'saturating' has more gammas"):
        FleetMonitor(arrs, {"R": 20.0}, noise_std={a.name: 1e-3 for a in arrs}, laws=("linear", "saturating"))
