"""Every stage on zoo models with the defaults: the chain of tests/zoo/chain.py.

The whole zoo runs in ``benchmarks/zoo.py`` (docs/zoo.md); here, models that cover a closed loop and a
nonlinear law (the speed loop with quadratic drag, and more) in the slow tier; the fast tier runs the
speed loop through the command line (test_cli_chain.py).
"""

import pytest

from tests.zoo.chain import CHANGE, cases, run_chain

BY_NAME = {case.name: case for case in cases()}


def check_chain(name: str) -> None:
    outcome = run_chain(BY_NAME[name])
    assert all(error < 1e-3 for error in outcome.identity.values()), outcome.identity
    assert outcome.healthy_fired == [], f"{name}: a healthy record with step inputs alarms"
    detectable = [p for p, change in outcome.detectable.items() if change <= CHANGE]
    assert sorted(outcome.faults) == sorted(detectable)
    for parameter, (fired, candidates) in outcome.faults.items():
        assert fired, f"{name}: a {CHANGE:.0%} rise of {parameter} raised no alarm"
        assert parameter in candidates, f"{name}: {parameter} not among the faults consistent with {fired}"


def test_the_zoo_is_wide():
    domains = {case.domain for case in BY_NAME.values()}
    assert len(BY_NAME) >= 30
    assert {"electrical", "translational", "rotational", "hydraulic", "pneumatic", "thermal", "mixed"} <= domains


@pytest.mark.slow
@pytest.mark.parametrize("name", ["flywheel_speed_loop", "quarter_car", "two_tank_orifice"])
def test_the_chain(name):
    check_chain(name)
