"""BondGraphTools itself (the test extra pins 0.4.6): models built and saved by BondGraphTools read by
read_bgt give state equations equal to BondGraphTools' own constitutive relations, states matched by
name; and BondGraphTools loads what write_bgt writes, to the equations of our model."""

from __future__ import annotations

import pytest
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph import BondGraph
from bondgraph.bgt_format import read_bgt, write_bgt
from bondgraph.library import dc_motor, rlc_circuit

pytestmark = [pytest.mark.interop, pytest.mark.slow]   # BondGraphTools imports matplotlib: seconds


def bondgraphtools():
    from bondgraph.optional import import_optional

    return import_optional("BondGraphTools", "pip install BondGraphTools (the test extra pins it)")


def readme_rlc(tools):
    """BondGraphTools' README example: R, L, C on a 0-junction, here driven by a flow source."""
    model = tools.new(name="RLC")
    parts = [tools.new("R", name="R1", value=1.0), tools.new("I", name="L1", value=2.0),
             tools.new("C", name="C1", value=3.0), tools.new("0", name="law"), tools.new("Sf", name="Sf")]
    tools.add(model, *parts)
    resistor, inductor, capacitor, law, source = parts
    for part in (resistor, capacitor, inductor):
        tools.connect(law, part)
    tools.connect(source, law)
    return model


def driven_oscillator(tools):
    """A mass (I) on a spring (C) and damper (R), driven by a force (Se), all on one 1-junction."""
    model = tools.new(name="oscillator")
    force, junction = tools.new("Se", name="F"), tools.new("1", name="v")
    mass, spring = tools.new("I", name="m", value=2.5), tools.new("C", name="k", value=0.2)
    damper = tools.new("R", name="b", value=0.7)
    tools.add(model, force, junction, mass, spring, damper)
    tools.connect(force, junction.non_inverting)
    for part in (mass, spring, damper):
        tools.connect(junction.inverting, part)
    return model


def motor(tools, turned: bool):
    """A DC motor with a gearbox: voltage, winding (R, L), gyrator, TF, load inertia and friction."""
    model = tools.new(name="motor")
    u, j1 = tools.new("Se", name="U"), tools.new("1", name="J1")
    ra, la = tools.new("R", name="Ra", value=1.2), tools.new("I", name="La", value=0.3)
    gy, tf = tools.new("GY", name="G", value=0.8), tools.new("TF", name="T", value=4.0)
    j2, jl, b = tools.new("1", name="J2"), tools.new("I", name="Jl", value=0.05), tools.new("R", name="b", value=0.1)
    tools.add(model, u, j1, ra, la, gy, tf, j2, jl, b)
    near, far = (1, 0) if turned else (0, 1)
    tools.connect(u, j1.non_inverting)
    tools.connect(j1.inverting, ra)
    tools.connect(j1.inverting, la)
    tools.connect(j1.inverting, (gy, near))
    tools.connect((gy, far), (tf, near))
    tools.connect((tf, far), j2.non_inverting)
    tools.connect(j2.inverting, jl)
    tools.connect(j2.inverting, b)
    return model


def plain(expression) -> sp.Expr:
    return sp.sympify(expression).replace(lambda e: isinstance(e, AppliedUndef), lambda e: sp.Symbol(e.func.__name__))


def leaf(model, variable: str, table: str) -> tuple[str, str]:
    """A state (``table="state_vars"``) or control variable of ``model`` followed down its sub-models:
    (our path of the component, its own variable)."""
    component, own = getattr(model, table)[variable]
    if hasattr(component, "components"):   # a sub-model: its own variable, one level down
        path, own = leaf(component, own, table)
        return f"{component.name}.{path}", own
    return component.name, own


def their_rates(model) -> dict:
    """BondGraphTools' constitutive relations solved for each state's rate, in our names: {q_C1: rhs}, and
    {q_a.sub.C1: rhs} in a sub-model."""
    names = {}
    for x in model.state_vars:
        path, own = leaf(model, x, "state_vars")
        names[sp.Symbol(x)] = sp.Symbol(f"{own[0]}_{path}")
        names[sp.Symbol(f"d{x}")] = sp.Symbol(f"d{own[0]}_{path}")
    for u in model.control_vars:
        names[sp.Symbol(u)] = sp.Symbol(leaf(model, u, "control_vars")[0])
    relations = [sp.sympify(r).xreplace(names) for r in model.constitutive_relations]
    rates = [names[sp.Symbol(f"d{x}")] for x in model.state_vars]
    solution = sp.solve(relations, rates, dict=True)
    assert len(solution) == 1
    return {str(rate)[1:]: solution[0][rate] for rate in rates}


def our_rates(bg) -> dict:
    eqs = bg.state_equations()
    values = {sp.Symbol(k): sp.nsimplify(v) for k, v in bg.parameters.items()}
    return {str(plain(x)): plain(rhs).subs(values) for x, rhs in zip(eqs.states, eqs.rhs)}


@pytest.mark.parametrize("build", [readme_rlc, driven_oscillator, lambda t: motor(t, False), lambda t: motor(t, True)],
                         ids=["readme_rlc", "driven_oscillator", "motor", "motor_turned_round"])
def test_our_equations_of_their_saved_model_are_theirs(build, tmp_path):
    tools = bondgraphtools()
    model = build(tools)
    path = tmp_path / "model.bg"
    tools.save(model, str(path))
    ours, theirs = our_rates(read_bgt(path)), their_rates(model)
    assert set(ours) == set(theirs) and len(ours) >= 2
    for state in ours:
        assert sp.simplify(ours[state] - theirs[state]) == 0, state


def without_sensors(bg: BondGraph) -> BondGraph:
    """``bg`` less its detectors: BondGraphTools 0.4.6 cannot reduce a model with a source-sensor at its top
    (its reduce_model fails with a ShapeError), which is what write_bgt makes of a sensor."""
    graph = bg.graph.copy()
    graph.remove_nodes_from([n for n, d in bg.graph.nodes(data=True) if d["kind"] in ("De", "Df")])
    return BondGraph(graph)


@pytest.mark.parametrize("original", [rlc_circuit, dc_motor])
def test_they_load_what_we_write_to_our_equations(original, tmp_path):
    tools = bondgraphtools()
    bg = without_sensors(original())
    path = tmp_path / "ours.bg"
    path.write_text(write_bgt(bg))
    ours, theirs = our_rates(bg), their_rates(tools.load(str(path)))
    assert set(ours) == set(theirs) and len(ours) == 2
    for state in ours:   # they round each coefficient to a float's digits (nsimplify of 1.23/0.00134)
        ours_poly, theirs_poly = (sp.Poly(side[state], *sorted(side[state].free_symbols, key=str))
                                  for side in (ours, theirs))
        assert ours_poly.monoms() == theirs_poly.monoms(), state
        for a, b in zip(ours_poly.coeffs(), theirs_poly.coeffs()):
            assert abs(float(a) - float(b)) <= 1e-12 * abs(float(a)), (state, a, b)


def test_they_load_our_sensors_as_source_sensors(tmp_path):
    tools = bondgraphtools()
    path = tmp_path / "motor.bg"
    path.write_text(write_bgt(dc_motor()))
    model = tools.load(str(path))
    sensors = {c.name: c.template for c in model.components if c.name in ("i", "omega")}
    assert sensors == {"i": "base/SS", "omega": "base/SS"}
