"""Drawings of bond graphs: SVG structure, causal strokes, escaping, determinism, notebook display."""

import math
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import networkx as nx
import pytest

from bondgraph import BondGraph, ModelError, drawing
from bondgraph.drawing import layout, to_svg, to_tikz
from bondgraph.library import (dc_motor, friction_drive, mass_spring_chain, rlc_circuit, three_tank, torsion_bar,
                               torsion_bar_monitorable)

SVG = "{http://www.w3.org/2000/svg}"
ROOT = Path(__file__).resolve().parents[2]
MODELS = {
    "rlc_circuit": rlc_circuit,
    "dc_motor": dc_motor,
    "torsion_bar": torsion_bar,
    "torsion_bar_monitorable": torsion_bar_monitorable,
    "three_tank": three_tank,
    "friction_drive": friction_drive,
    "mass_spring_chain": lambda: mass_spring_chain(5),
}
HOSTILE = '<script>alert(1)</script>&"'
TEX_HOSTILE = "a_b$c\\d{e}"


def classes(element):
    return set((element.get("class") or "").split())


def shapes(root, name):
    """Every SVG element whose class list contains ``name``."""
    return [e for e in root.iter() if name in classes(e)]


def groups(root):
    """(tail, head) -> the bond's <g class="bond-group">."""
    return {(g.get("data-tail"), g.get("data-head")): g for g in shapes(root, "bond-group")}


def line_points(line):
    return (float(line.get("x1")), float(line.get("y1"))), (float(line.get("x2")), float(line.get("y2")))


def conflict_model():
    """Two effort sources on one 0-junction: a causal conflict."""
    bg = BondGraph(name="conflict")
    bg.add("E1", "Se")
    bg.add("E2", "Se")
    bg.add("J", "0")
    bg.add("C1", "C", value=1.0)
    for tail, head in [("E1", "J"), ("E2", "J"), ("J", "C1")]:
        bg.bond(tail, head)
    return bg


def hostile_model():
    """A valid model whose free-text name carries markup: the one user text the writers still receive."""
    bg = BondGraph(name=HOSTILE + " " + TEX_HOSTILE + " R~%#^& x\x01y")
    bg.add("V", "Se")
    bg.add("J", "1")
    bg.add("R", "R", value=1.0)
    bg.add("L", "I", value=1.0)
    for tail, head in [("V", "J"), ("J", "R"), ("J", "L")]:
        bg.bond(tail, head)
    return bg


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("preferred", ["integral", "derivative"])
def test_svg_has_one_shape_per_bond(name, preferred):
    bg = MODELS[name]()
    causality = layout(bg, preferred)
    root = ET.fromstring(to_svg(bg, preferred))
    assert root.tag == SVG + "svg"
    bonds = bg.bonds
    power = shapes(root, "bond")
    signal = shapes(root, "signal")
    assert len(power) + len(signal) == bg.graph.number_of_edges() == len(bonds)
    assert len(groups(root)) == len(bonds)
    assert len(shapes(root, "half-arrow")) == len(power)
    assert len(shapes(root, "arrow")) == len(signal)
    assigned = sum(b.stroke is not None for b in causality.bonds)
    assert len(shapes(root, "stroke")) == assigned
    if preferred == "integral":  # every power bond of the library models gets its causality
        assert assigned == sum(not b.is_signal for b in bonds)
        assert len(signal) == sum(b.is_signal for b in bonds)
    labels = {t.get("data-node") for t in shapes(root, "node")}
    assert labels == {str(n) for n in bg.graph}


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("preferred", [None, "derivative"])
def test_labels_do_not_overlap_and_bonds_are_visible(name, preferred):
    result = layout(MODELS[name](), preferred)
    boxes = {n: (x - w / 2, y - h / 2, x + w / 2, y + h / 2)
             for n, (x, y) in result.positions.items() for w, h in [result.sizes[n]]}
    names = list(boxes)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            ax0, ay0, ax1, ay1 = boxes[a]
            bx0, by0, bx1, by1 = boxes[b]
            assert ax1 <= bx0 or bx1 <= ax0 or ay1 <= by0 or by1 <= ay0, f"{a} overlaps {b}"
    for x0, y0, x1, y1 in boxes.values():
        assert 0 <= x0 and x1 <= result.width and 0 <= y0 and y1 <= result.height
    for bond in result.bonds:
        assert math.dist(bond.start, bond.end) >= 15  # the line outside the labels is long enough to read


@pytest.mark.parametrize("build", [rlc_circuit, dc_motor])
def test_stroke_sits_at_the_end_receiving_effort(build):
    bg = build()
    causality = bg.assign_causality("integral")
    positions = layout(bg, "integral").positions
    root = ET.fromstring(to_svg(bg, "integral"))
    checked = 0
    for (tail, head), group in groups(root).items():
        strokes = shapes(group, "stroke")
        if (tail, head) not in causality.effort_from:
            assert not strokes
            continue
        receiver = causality.stroke((tail, head))
        other = head if receiver == tail else tail
        (a, b), = [line_points(s) for s in strokes]
        centre = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
        assert math.dist(centre, positions[receiver]) < math.dist(centre, positions[other])
        # the stroke is a bar across the bond
        (s, e), = [line_points(line) for line in shapes(group, "bond")]
        along = (e[0] - s[0], e[1] - s[1])
        across = (b[0] - a[0], b[1] - a[1])
        assert abs(along[0] * across[0] + along[1] * across[1]) < 1e-6 * math.hypot(*along) * math.hypot(*across) + 0.1
        checked += 1
    assert checked == len(causality.effort_from) == sum(not b.is_signal for b in bg.bonds)


@pytest.mark.parametrize("build", [rlc_circuit, dc_motor])
def test_half_arrow_is_at_the_head(build):
    bg = build()
    positions = layout(bg).positions
    root = ET.fromstring(to_svg(bg, None))
    assert not shapes(root, "stroke")  # acausal drawing
    for (tail, head), group in groups(root).items():
        tips = shapes(group, "half-arrow") or []
        if tips:
            (tip, barb), = [line_points(t) for t in tips]
            assert math.dist(tip, positions[head]) < math.dist(tip, positions[tail])
            assert math.dist(barb, positions[head]) < math.dist(barb, positions[tail])
        else:  # a signal bond: a full arrow at the detector
            points = [tuple(map(float, p.split(","))) for p in shapes(group, "arrow")[0].get("points").split()]
            assert all(math.dist(p, positions[head]) < math.dist(p, positions[tail]) for p in points)


def test_derivative_causality_highlights_storage_and_dualizes_detectors():
    bg = dc_motor()
    root = ET.fromstring(to_svg(bg, "derivative"))
    texts = {t.get("data-node"): "".join(t.itertext()) for t in shapes(root, "node")}
    assert texts["i"] == "SSf:i" and texts["omega"] == "SSf:omega"
    by_bond = groups(root)
    for key, group in by_bond.items():
        storage = key in {("1_e", "L_a"), ("1_m", "J")}
        line = (shapes(group, "bond") + shapes(group, "signal"))[0]
        assert ("derivative" in classes(line)) == storage
        assert (line.get("stroke") == drawing.DERIVATIVE_COLOR) == storage
        stroke = shapes(group, "stroke")
        assert len(stroke) == 1  # dualized detector bonds get a stroke too
        assert ("derivative" in classes(stroke[0])) == storage
    assert "dualized" in classes(shapes(by_bond[("1_e", "i")], "bond")[0])
    assert "derivative causality" in root.find(SVG + "title").text

    integral = ET.fromstring(to_svg(bg, "integral"))
    assert not shapes(integral, "derivative")
    texts = {t.get("data-node"): "".join(t.itertext()) for t in shapes(integral, "node")}
    assert texts["i"] == "Df:i" and texts["GY"] == "GY:k_m" and texts["1_e"] == "1e"


def test_labels_follow_the_notation():
    result = layout(friction_drive(), "integral")
    assert result.labels["TF_1"] == "TF:TF_1 (r1)"
    assert result.labels["T_m"] == "MSe:T_m"
    assert (result.labels["0_c"], result.subscripts["0_c"]) == ("0", "c")
    rlc = layout(rlc_circuit(), "derivative")
    assert (rlc.labels["J1"], rlc.subscripts["J1"]) == ("1", "J1")
    assert rlc.labels["v_C"] == "SSe:v_C" and rlc.labels["C"] == "C:C"
    assert all(b.derivative == (b.head in ("L", "C")) for b in rlc.bonds)


@pytest.mark.parametrize("node", [HOSTILE, TEX_HOSTILE, "R~%#^&", "x\x01y", "<img src=x onerror=alert(1)>"])
def test_hostile_node_ids_are_refused(node):
    with pytest.raises(ModelError, match="is not a name"):
        BondGraph().add(node, "R", value=1.0)
    G = nx.DiGraph()
    G.add_node("V", kind="Se")
    G.add_node(node, kind="R", value=1.0)
    G.add_edge("V", node)
    with pytest.raises(ModelError, match=re.escape(repr(node))):
        BondGraph(G)


def test_hostile_names_are_escaped():
    bg = hostile_model()
    svg = to_svg(bg, "integral")
    assert "<script" not in svg and HOSTILE not in svg
    root = ET.fromstring(svg)
    assert not [e for e in root.iter() if e.tag.rsplit("}", 1)[-1].lower() == "script"]
    assert HOSTILE in root.find(SVG + "title").text  # the text survives the round trip
    legend = ["".join(t.itertext()) for t in shapes(root, "legend") if t.tag == SVG + "text"]
    assert legend[0].startswith(HOSTILE + " " + TEX_HOSTILE) and "x\ufffdy" in legend[0]

    tikz = to_tikz(bg, "integral")
    assert r"a\_b\$c\textbackslash{}d\{e\}" in tikz
    assert r"\textless{}script\textgreater{}alert(1)\textless{}/script\textgreater{}\&" in tikz
    assert r"R\textasciitilde{}\%\#\textasciicircum{}\&" in tikz
    for raw in (TEX_HOSTILE, HOSTILE, "R~%#^&", "\x01"):
        assert raw not in tikz
    body = tikz.split("\n")
    assert all(line.startswith(("\\", "%")) for line in body)  # no name breaks out of its line


def test_escape_helpers():
    assert drawing.latex_escape("}\\input{/etc/passwd}") == r"\}\textbackslash{}input\{/etc/passwd\}"
    assert drawing.latex_escape("a\nb\x00c") == "a b c"


def test_output_is_deterministic():
    for build in (torsion_bar, three_tank):
        assert to_svg(build(), "derivative") == to_svg(build(), "derivative")
        assert to_tikz(build()) == to_tikz(build())
        assert layout(build(), "integral") == layout(build(), "integral")


@pytest.mark.slow
def test_output_does_not_depend_on_the_hash_seed():
    code = "from bondgraph.drawing import to_svg; from bondgraph.library import torsion_bar; " \
           "import sys; sys.stdout.write(to_svg(torsion_bar(), 'derivative'))"
    seed = "2" if os.environ.get("PYTHONHASHSEED") == "1" else "1"
    env = {**os.environ, "PYTHONHASHSEED": seed}
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    assert run.stdout == to_svg(torsion_bar(), "derivative")


def test_notebook_display():
    bg = dc_motor()
    svg, html = bg._repr_svg_(), bg._repr_html_()
    assert svg.startswith("<svg") and svg == to_svg(bg, "integral")
    assert "<svg" in html and html.startswith("<div") and svg in html
    ET.fromstring(svg)


def test_model_with_a_causal_conflict_is_drawn():
    bg = conflict_model()
    causality = bg.assign_causality("integral")
    assert causality.conflicts
    for svg in (bg._repr_svg_(), to_svg(bg, "integral"), to_svg(bg, "derivative")):
        root = ET.fromstring(svg)
        assert len(shapes(root, "bond")) == 3
    assert "<svg" in bg._repr_html_()
    assert "conflict" in " ".join(layout(bg, "integral").notes)
    partial = layout(bg, "integral")
    assert [b.stroke is not None for b in partial.bonds] == [k in causality.effort_from for k in
                                                              [(b.tail, b.head) for b in partial.bonds]]


def test_notebook_display_falls_back_to_acausal(monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("causality failed")

    monkeypatch.setattr(drawing, "assign_causality", broken)
    bg = rlc_circuit()
    root = ET.fromstring(bg._repr_svg_())
    assert not shapes(root, "stroke") and len(shapes(root, "bond")) == 5
    assert "acausal" in root.find(SVG + "title").text
    assert "<svg" in bg._repr_html_()


def test_bonds_without_assignment_get_no_stroke():
    bg = rlc_circuit()
    causality = bg.assign_causality("integral")
    del causality.effort_from[("J1", "R")]
    root = ET.fromstring(to_svg(bg, causality))
    assert not shapes(groups(root)[("J1", "R")], "stroke")
    assert len(shapes(root, "stroke")) == 4
    assert "1 bond(s) left without causality" in "".join(root.itertext())


def test_tikz_draws_every_bond():
    for build in (rlc_circuit, dc_motor):
        bg = build()
        tikz = to_tikz(bg, "derivative")
        assert tikz.startswith(r"\begin{tikzpicture}") and tikz.endswith(r"\end{tikzpicture}")
        lines = tikz.splitlines()
        assert sum(line.startswith(r"\draw") for line in lines) >= len(bg.bonds)
        assert sum(line.startswith(r"\node") for line in lines) >= bg.graph.number_of_nodes()
        assert "draw=red" in tikz and "SSf:i" in tikz
        assert tikz.count("{") == tikz.count("}")
    acausal = to_tikz(rlc_circuit(), None)
    assert "line width=0.9pt" not in acausal  # no strokes


def test_arguments_are_checked():
    with pytest.raises(ValueError, match="causality"):
        layout(rlc_circuit(), "sideways")
    with pytest.raises(ValueError, match="scale"):
        to_svg(rlc_circuit(), scale=0)
    big = ET.fromstring(to_svg(rlc_circuit(), scale=2))
    small = ET.fromstring(to_svg(rlc_circuit()))
    assert float(big.get("width")) == pytest.approx(2 * float(small.get("width")))
    assert big.get("viewBox") == small.get("viewBox")


def test_disconnected_model_is_stacked():
    bg = BondGraph(name="two parts")
    for suffix in ("a", "b"):
        bg.add(f"S{suffix}", "Se")
        bg.add(f"R{suffix}", "R", value=1.0)
        bg.bond(f"S{suffix}", f"R{suffix}")
    result = layout(bg, "integral")
    assert result.positions["Sa"][1] == result.positions["Ra"][1] < result.positions["Sb"][1]
    assert len(shapes(ET.fromstring(to_svg(bg)), "stroke")) == 2
