"""Sets only an ODE seemed to close, realised by eliminating with d/dt as an operator, judged on the physics.

The zoo models below have minimal sets whose matching leaves a loop through a state (a spring and a
damper in parallel whose deflection is not measured, a thermal capacitance between two unmeasured
resistances).  Their ARRs are checked against each model's hand-written reference physics with exact
derivatives, never against the library's own simulation.
"""

from __future__ import annotations

import warnings

import pytest
import sympy as sp

from bondgraph.structure import T
from diagnosis import ARRWarning, derive_arrs
from diagnosis._operator_elimination import operator_order, operator_residual
from diagnosis.elimination import unreached
from tests.zoo.check import inside_box, load_case
from tests.zoo.identity import identity_error
from tests.zoo.reference import simulate_reference

#: Zoo models with unmeasured Kelvin-Voigt pairs, thermal or pneumatic loops (unreached pairs before).
LOOPED = ["quarter_car", "two_mass_drive", "torque_sensor_shaft", "power_module_thermal", "pneumatic_line"]


@pytest.mark.slow
@pytest.mark.parametrize("name", LOOPED)
def test_every_isolable_pair_is_reached_and_every_arr_holds_on_the_physics(name):
    case = load_case(name)
    bg = case.build()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        arrs = derive_arrs(bg, max_order=None)
    assert unreached(bg, arrs) == {"detect": [], "isolate": []}
    order = max(arr.order for arr in arrs)
    assert order >= 2
    run = simulate_reference(case, parameters=inside_box(case), t_end=case.t_end * 0.2, order=order)
    for arr in arrs:   # a running integral on the grid is a trapezoid sum: its error is the sampling's
        assert identity_error(arr, run) < (1e-3 if arr.integrals else 1e-6), arr.name


def _spring_damper():
    """``q/C + c f = F``, ``dq/dt = f``, ``f = v``: the deflection only an ODE gives."""
    q, F, v = sp.Function("q")(T), sp.Function("F")(T), sp.Function("v")(T)
    C, c, f = sp.symbols("C c f")
    return [sp.Eq(q / C + c * f, F), sp.Eq(sp.Derivative(q, T), f), sp.Eq(f, v)], [q, f], (F, v, C, c)


def test_the_relation_left_holds_on_a_solution_of_the_equations():
    equations, unknowns, (F, v, C, c) = _spring_damper()
    residual = operator_residual(equations, unknowns)
    # any deflection history: F and v follow from it by the equations
    q = sp.sin(3 * T) + T ** 2
    on_solution = residual.subs({F: q / C + c * sp.diff(q, T), v: sp.diff(q, T)}).doit()
    assert sp.simplify(on_solution) == 0
    assert residual.has(sp.Derivative(F, T)) and operator_order(equations, unknowns) == 1


def test_a_law_not_linear_in_its_unknowns_is_left_to_the_other_routes():
    equations, unknowns, (F, v, C, c) = _spring_damper()
    equations[0] = sp.Eq(sp.sqrt(unknowns[0]) / C + c * unknowns[1], F)   # a non-linear spring
    assert operator_residual(equations, unknowns) is None
    assert operator_order(equations, unknowns) is None
