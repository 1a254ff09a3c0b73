"""BondGraphTools' nested (modular) models, BondGraphTools 0.4.6 itself: a model of sub-models built and saved
by BondGraphTools reads with read_bgt to state equations equal to its own constitutive relations (its states
mapped through its sub-models to our paths, ``q_a.sub.C1``); and BondGraphTools loads the nested file
write_bgt makes of a composed model, to our equations."""

from __future__ import annotations

import pytest
import sympy as sp

from bondgraph import BondGraph, compose
from bondgraph.bgt_format import read_bgt, write_bgt
from tests.interop.test_bondgraphtools import bondgraphtools, our_rates, their_rates

pytestmark = [pytest.mark.interop, pytest.mark.slow]   # BondGraphTools imports matplotlib: seconds


def rc_cell(tools, name: str, r: float, c: float, port: str):
    """A series R, C on a 1-junction, its source-sensor exposed as the port ``port``."""
    cell = tools.new(name=name)
    ss, junction = tools.new("SS", name="SS1"), tools.new("1", name="J")
    resistor, capacitor = tools.new("R", name="R1", value=r), tools.new("C", name="C1", value=c)
    tools.add(cell, ss, junction, resistor, capacitor)
    tools.connect(ss, junction.non_inverting)
    tools.connect(junction.inverting, resistor)
    tools.connect(junction.inverting, capacitor)
    tools.expose(ss, port)
    return cell


def modular(tools):
    """A source, through R1 and a gyrator, drives the sub-model a: an inductor on a 0-junction and two RC
    cells (a.sub, a.sub2), one bonded by its model, one by its port's name."""
    inner = tools.new(name="a")
    port, junction, inductor = tools.new("SS", name="P"), tools.new("0", name="z"), tools.new("I", name="L1", value=5.0)
    first, second = rc_cell(tools, "sub", 2.0, 3.0, "A"), rc_cell(tools, "sub2", 0.5, 4.0, "B")
    tools.add(inner, port, junction, inductor, first, second)
    tools.connect(port, junction)
    tools.connect(junction, inductor)
    tools.connect(junction, first)
    tools.connect(junction, (second, "B"))
    tools.expose(port, "P")
    top = tools.new(name="modular")
    source, loop, resistor = tools.new("Se", name="U"), tools.new("1", name="K"), tools.new("R", name="R1", value=7.0)
    gyrator = tools.new("GY", name="G", value=1.5)
    tools.add(top, inner, source, loop, resistor, gyrator)
    tools.connect(source, loop.non_inverting)
    tools.connect(loop.inverting, resistor)
    tools.connect(loop.inverting, (gyrator, 1))
    tools.connect((gyrator, 0), inner)
    return top


def assert_same(ours: dict, theirs: dict) -> None:
    """Equal linear rates: the same terms, coefficients to 1e-12 (BondGraphTools rounds some to a float's digits,
    e.g. 0.0712871287128713 for 36/505)."""
    for state in ours:
        ours_poly, theirs_poly = (sp.Poly(side[state], *sorted(side[state].free_symbols, key=str))
                                  for side in (ours, theirs))
        assert ours_poly.monoms() == theirs_poly.monoms(), state
        for a, b in zip(ours_poly.coeffs(), theirs_poly.coeffs()):
            assert abs(float(a) - float(b)) <= 1e-12 * abs(float(a)), (state, a, b)


def test_our_equations_of_their_saved_modular_model_are_theirs(tmp_path):
    tools = bondgraphtools()
    model = modular(tools)
    path = tmp_path / "modular.bg"
    tools.save(model, str(path))
    text = path.read_text()
    assert "  /a/sub:" in text and "- a /a" in text and "- sub /a/sub" in text   # it saved it nested
    bg = read_bgt(path)
    assert {"a.sub.R1", "a.sub2.C1", "a.L1", "R1", "G"} <= set(bg.parameters)
    ours, theirs = our_rates(bg), their_rates(model)
    assert set(ours) == set(theirs) == {"p_a.L1", "q_a.sub.C1", "q_a.sub2.C1"}
    assert_same(ours, theirs)


def test_they_load_our_nested_composed_model_to_our_equations(tmp_path):
    tools = bondgraphtools()
    source = BondGraph(name="source")
    source.add("U", "Se"), source.add("out", "1"), source.add("R_s", "R", value=0.5), source.add("L", "I", value=2.0)
    source.bond("U", "out"), source.bond("out", "R_s"), source.bond("out", "L"), source.port("terminal", "out")
    load = BondGraph(name="load")
    load.add("in", "0"), load.add("C", "C", value=0.25), load.add("R", "R", value=4.0)
    load.bond("in", "C"), load.bond("in", "R"), load.port("terminal", "in")
    tail = BondGraph(name="tail")
    tail.add("in", "1"), tail.add("L", "I", value=0.2), tail.add("R", "R", value=3.0)
    tail.bond("in", "L"), tail.bond("in", "R"), tail.port("terminal", "in")
    stage = compose({"supply": source, "rc": load}, [("supply.terminal", "rc.terminal")],
                    ports={"out": "rc.terminal"}, name="stage")
    # the bond stage.rc.in -> tail.in leaves two models on one side: a port at each level
    composed = compose({"stage": stage, "tail": tail}, [("stage.out", "tail.terminal")], name="two stages")
    path = tmp_path / "ours.bg"
    path.write_text(write_bgt(composed))
    model = tools.load(str(path))
    assert {c.name for c in model.components} == {"stage", "tail"}
    ours, theirs = our_rates(composed), their_rates(model)
    assert set(ours) == set(theirs) == {"p_stage.supply.L", "q_stage.rc.C", "p_tail.L"}
    assert_same(ours, theirs)
