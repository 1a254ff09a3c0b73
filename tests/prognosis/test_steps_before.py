"""The steps before the first alarm, weighed with an onset: against closed forms written here.

A change starts below the alarm thresholds.  Given the residuals of the steps before the first
(``before``) and the value theta had before the change (``nominal``), each particle also carries an
onset: nominal before it, the law traced back from theta_0 after it.  The filter must find the onset
of a broken line and of a jump, and tell a power law's exponent far better than from the alarm on.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from prognosis.degradation import JointDegradation, LinearDegradation, PerAssetDegradation, PowerDegradation
from prognosis.errors import PrognosisError
from prognosis.isolation import IsolatingMonitor
from prognosis.resample_move import ResampleMoveFilter

LEAD = 30  # steps measured before the first


def measured(theta: np.ndarray, noise: float, seed: int) -> np.ndarray:
    return theta + np.random.default_rng(seed).normal(0.0, noise, theta.size)


def filtered(model, y: np.ndarray, noise: float, theta_bounds, gamma_bounds, *, lead: int, nominal: float,
             seed: int, log_gamma=False, particles: int = 400) -> ResampleMoveFilter:
    """The filter over ``y``, its first ``lead`` values given as the steps before the first."""
    f = ResampleMoveFilter(model, lambda theta, points: theta, noise=noise, dt=1.0, n_particles=particles,
                           discrepancy=None, seed=seed)
    before = [(np.array([value]), ()) for value in y[:lead]]
    f.initialize(theta_bounds, gamma_bounds, assets=1, log_gamma=log_gamma, before=before,
                 nominal=nominal if lead else None)
    for value in y[lead:]:
        f.step(value)
    return f


def weighted_interval(values: np.ndarray, weights: np.ndarray, level: float = 0.9) -> tuple[float, float]:
    order = np.argsort(values)
    cdf = np.cumsum(weights[order])
    tail = (1.0 - level) / 2
    return float(values[order][np.searchsorted(cdf, tail)]), float(values[order][np.searchsorted(cdf, 1 - tail)])


def test_a_broken_line_gives_its_onset_and_its_rate():
    """Nominal 0 until 12 steps before the first, then 0.1 a step: the change starts no later than a step
    or two after 12 steps before the first (any onset before that traces the same path: the line stops
    at the nominal value), and the rate is known better than from the first step on."""
    steps = np.arange(-LEAD, 20)
    theta = np.maximum(0.1 * (steps + 12), 0.0)
    y = measured(theta, 0.05, seed=1)
    box = ((0.0, 3.0), (0.0, 1.0))
    f = filtered(LinearDegradation(), y, 0.05, *box, lead=LEAD, nominal=0.0, seed=2)
    alone = filtered(LinearDegradation(), y[LEAD:], 0.05, *box, lead=0, nominal=0.0, seed=2)
    w = f.weights[0]
    assert weighted_interval(f.z[0, :, -1], w)[0] > 10.0
    rate_lo, rate_hi = weighted_interval(f.gamma[0, :, 0], w)
    alone_lo, alone_hi = weighted_interval(alone.gamma[0, :, 0], alone.weights[0])
    assert rate_lo <= 0.1 <= rate_hi and rate_hi - rate_lo < 0.7 * (alone_hi - alone_lo)
    assert abs(float(np.sum(w * f.theta[0])) - theta[-1]) < 0.05


def test_a_jump_at_the_onset_is_a_change_that_starts_there():
    """A bias of 0.5 from 7 steps before the first: the onset lies in [7, 8) (steps -7 on are biased),
    and the steps before it, nominal, do not pull the bias down."""
    steps = np.arange(-LEAD, 15)
    y = measured(np.where(steps >= -7, 0.5, 0.0), 0.05, seed=3)
    f = filtered(LinearDegradation(), y, 0.05, (-2.0, 2.0), (0.0, 0.0), lead=LEAD, nominal=0.0, seed=4)
    w, onset = f.weights[0], f.z[0, :, -1]
    assert float(np.sum(w[(onset >= 7.0) & (onset < 8.0)])) > 0.9
    assert abs(float(np.sum(w * f.theta[0])) - 0.5) < 0.03


def test_the_start_of_a_power_law_tells_its_exponent():
    """theta = (t / 60)^2.5 from t = 0, seen from 5 s on and first alarmed at 45 s: with the steps
    before the alarm the exponent's 90 % interval holds 2.5 and is less than half as wide as from
    the alarm on."""
    t = np.arange(5.0, 58.0)
    theta = (t / 60.0) ** 2.5
    y = measured(theta, 0.01, seed=5)
    lead = int(np.searchsorted(t, 45.0))
    model, box = PowerDegradation(origin=0.0, span=1.0), ((0.0, 1.0), ((1e-3, 0.5), (0.5, 5.0)))
    widths = []
    for steps in (lead, 0):
        f = filtered(model, y if steps else y[lead:], 0.01, box[0], box[1], lead=steps, nominal=0.0, seed=6,
                     log_gamma=True)
        lo, hi = weighted_interval(f.gamma[0, :, 1], f.weights[0])
        widths.append(hi - lo)
        if steps:
            assert lo <= 2.5 <= hi
    assert widths[0] < 0.5 * widths[1]


def two_lines(lead: int, seed: int) -> ResampleMoveFilter:
    """Two parameters seen each by its own residual, nominal 0: the first drifts 0.05 a step from 20 steps
    before the first, the second jumps to 0.6 3 steps before it; ``lead`` of the steps before the first are
    given."""
    steps = np.arange(-LEAD, 25)
    theta = np.column_stack([np.maximum(0.05 * (steps + 20), 0.0), np.where(steps >= -3, 0.6, 0.0)])
    y = theta + np.random.default_rng(seed).normal(0.0, 0.05, theta.shape)
    bank = PerAssetDegradation((LinearDegradation(),), (0,))
    f = ResampleMoveFilter(JointDegradation((bank, bank)), lambda theta, points: theta, noise=[0.05, 0.05], dt=1.0,
                           n_particles=400, discrepancy=None, seed=seed + 1)
    f.initialize(((0.0, 0.0), (3.0, 3.0)), ((0.0, -0.5), (1.0, 1.0)), assets=1, components=2,
                 before=[(value[None, :], ()) for value in y[LEAD - lead:LEAD]], nominal=(0.0, 0.0) if lead else None)
    for value in y[LEAD:]:
        f.step(value[None, :])
    return f


def test_each_parameter_of_a_joint_hypothesis_has_its_own_onset():
    """The jump's onset lies in [3, 4) steps before the first; the drift's is no later than a step or two
    after 20 (any earlier onset traces the same path: the line stops at the nominal value).  One onset
    for both could not give that.  The drift's rate is known better than from the first step on."""
    f, alone = two_lines(LEAD, seed=7), two_lines(0, seed=7)
    w = f.weights[0]
    assert weighted_interval(f.z[0, :, -2], w)[0] > 15.0
    assert float(np.sum(w[(f.z[0, :, -1] >= 3.0) & (f.z[0, :, -1] < 4.0)])) > 0.9
    widths = []
    for g in (f, alone):
        lo, hi = weighted_interval(g.gamma[0, :, 0], g.weights[0])
        assert lo <= 0.05 <= hi
        widths.append(hi - lo)
    assert widths[0] < 0.7 * widths[1]
    assert np.allclose(np.sum(w[:, None] * f.theta[0], axis=0), [2.2, 0.6], atol=0.06)


def test_a_parameter_held_at_its_nominal_value_has_no_onset():
    """A joint row's missing part (theta held at nominal) has nothing to date: its onset is fixed."""
    bank = PerAssetDegradation((LinearDegradation(),), (0,))
    f = ResampleMoveFilter(JointDegradation((bank, bank)), lambda theta, points: theta, noise=[0.1, 0.1], dt=1.0,
                           n_particles=10)
    f.initialize(((0.0, 1.0), (1.0, 1.0)), ((0.0, 0.0), (1.0, 0.0)), components=2,
                 before=[(np.zeros((1, 2)), ())] * 4, nominal=(0.0, 1.0))
    assert f.prior.free[0, -2:].tolist() == [True, False]


def test_the_steps_before_need_the_nominal_value():
    f = ResampleMoveFilter(LinearDegradation(), lambda theta, points: theta, noise=0.1, dt=1.0, n_particles=10)
    with pytest.raises(PrognosisError, match="nominal value"):
        f.initialize((0.0, 1.0), (0.0, 1.0), before=[(np.zeros(1), ())])


def test_the_steps_before_stop_at_an_alarm_and_at_the_healthy_stretch():
    t = np.arange(0.0, 10.0, 0.5)
    quiet, alarmed = np.zeros(t.size, bool), np.zeros(t.size, bool)
    alarmed[8] = True
    evaluations = [SimpleNamespace(t=t, alarm=quiet), SimpleNamespace(t=t, alarm=alarmed)]
    monitor = SimpleNamespace(healthy_until=2.0)
    # back from sample 16 by 2 samples: 14, 12, 10, then 8 is in alarm
    assert IsolatingMonitor.steps_before(monitor, evaluations, 16, 2) == [10, 12, 14]
    # back from sample 7: 5 (t = 2.5); 3 lies in the healthy stretch
    assert IsolatingMonitor.steps_before(monitor, evaluations[:1], 7, 2) == [5]
