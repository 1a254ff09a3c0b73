"""The report writers escape every user text, even text the model validation never sees.

Names can no longer carry markup (tests/bondgraph/test_model_input_rules.py), so these tests reach the writers
without it: through the model's display name, which is free text, and by calling the equation
printers on sympy expressions with hostile symbol and function names.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from html.parser import HTMLParser

import pytest
import sympy as sp

from bondgraph import BondGraph
from diagnosis import derive_arrs
from diagnosis.deltas import MATHML_ELEMENTS, delta, latex, mathml
from diagnosis.report import arr_report

HOSTILE = '<img src=x onerror=alert(1)><script>alert(2)</script>"\' & [x](javascript:alert(3)) $\\int$ `c`'
TEX_HOSTILE = "}\\input{/etc/passwd}\\write18{rm -rf /}{"
NAMES = [HOSTILE, TEX_HOSTILE, "a\x01b", "x&amp;y", "</mi><mtext>", "Ω"]
T = sp.Symbol("t")


def expression(name: str) -> sp.Expr:
    """A Psi_2-like expression whose symbol, function and delta all carry ``name``."""
    return sp.Symbol(name) * delta(name) * sp.Function(name)(T) + sp.Derivative(sp.Function(name)(T), T)


def xml_elements(text: str) -> list[ET.Element]:
    """Every element of a MathML fragment, parsed as XML (sympy's named entities, unknown to XML, dropped first)."""
    text = re.sub(r"&(?!(?:lt|gt|amp|quot|apos);)[A-Za-z]+;", "", text)
    return list(ET.fromstring(f'<math xmlns="http://www.w3.org/1998/Math/MathML">{text}</math>').iter())


@pytest.mark.parametrize("name", NAMES)
def test_mathml_keeps_hostile_names_as_text(name):
    text = mathml(expression(name))
    elements = xml_elements(text)
    tags = {e.tag.rsplit("}", 1)[-1] for e in elements}
    assert tags <= MATHML_ELEMENTS and not tags & {"script", "img", "mtext"}
    assert not [a for e in elements for a in e.attrib if a.lower().startswith("on")]
    printed = "".join("".join(e.itertext()) for e in elements if e.tag.endswith("}mi"))
    if name == HOSTILE:
        assert "<img src=x onerror=alert(1)>" in printed  # shown as text, not lost


def test_mathml_escapes_what_sympy_leaves_raw():
    x, y = sp.symbols("x y")
    assert mathml(x < y) == "<mrow><mi>x</mi><mo>&lt;</mo><mi>y</mi></mrow>"


@pytest.mark.parametrize("name", NAMES)
def test_latex_keeps_hostile_names_in_their_group(name):
    text = latex(expression(name))
    for command in ("\\input", "\\write", "\\include", "\\def", "\\catcode"):
        assert command not in text
    assert "<" not in text and ">" not in text and "\x01" not in text
    unescaped = re.sub(r"\\[{}]", "", text)  # the braces of the name are escaped, every other one is paired
    depth = 0
    for ch in unescaped:
        depth += {"{": 1, "}": -1}.get(ch, 0)
        assert depth >= 0, f"a brace closes a group it did not open: {text}"
    assert depth == 0


def test_latex_and_mathml_keep_plain_names_typeset():
    name = "omega_m"
    assert latex(sp.Function(name)(T)) == "\\omega_{m}{\\left(t \\right)}"
    assert latex(delta("L_a")) == "\\delta_{L_{a}}"
    assert mathml(delta("L_a")) == "<msub><mi>&#948;</mi><msub><mi>L</mi><mi>a</mi></msub></msub>"


class _Tags(HTMLParser):
    """Every start tag of an HTML document and its attributes."""

    def __init__(self):
        super().__init__()
        self.tags: list[tuple[str, list]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, attrs))


@pytest.fixture(scope="module")
def hostile_report():
    """A small valid model whose display name is hostile, and its ARRs (derived once)."""
    bg = BondGraph(name=HOSTILE + " " + TEX_HOSTILE)
    bg.add("V", "Se")
    bg.add("J", "1")
    bg.add("R", "R", value=2.0, uncertainty=(-0.1, 0.1))
    bg.add("i", "Df")
    for tail, head in [("V", "J"), ("J", "R"), ("J", "i")]:
        bg.bond(tail, head)
    return bg, derive_arrs(bg)


def test_the_html_report_escapes_the_model_name(hostile_report):
    bg, arrs = hostile_report
    text = arr_report(bg, "html", arrs=arrs)
    parser = _Tags()
    parser.feed(text)
    tags = [tag for tag, _ in parser.tags]
    assert "script" not in tags and "img" not in tags
    assert not [name for _, attrs in parser.tags for name, _ in attrs if name.lower().startswith("on")]
    assert "&lt;img src=x onerror=alert(1)&gt;" in text  # the name is shown as text
    for block in re.findall(r"<svg.*?</svg>", text, re.S):  # the drawings are well-formed XML
        ET.fromstring(block)


def test_the_markdown_report_escapes_the_model_name(hostile_report):
    bg, arrs = hostile_report
    text = arr_report(bg, "md", arrs=arrs)
    title = text.splitlines()[0]
    assert title.startswith("# ARR report: &lt;img src=x onerror=alert(1)&gt;&lt;script&gt;")
    assert "\\[x\\](javascript:alert(3))" in title and "\\$\\\\int\\$" in title and "\\`c\\`" in title
    assert text.count("<img") == 2 and all(
        line.startswith('<img alt="preferred') for line in text.splitlines() if "<img" in line)  # the drawings
    assert "<script" not in text


def test_the_latex_report_escapes_the_model_name(hostile_report):
    bg, arrs = hostile_report
    text = arr_report(bg, "tex", arrs=arrs)
    for command in ("\\input", "\\write18"):
        assert command not in text
    section = next(line for line in text.splitlines() if line.startswith("\\section*"))
    assert "\\}\\textbackslash{}input\\{/etc/passwd\\}" in section
    assert re.sub(r"\\[{}]", "", section).count("{") == re.sub(r"\\[{}]", "", section).count("}")


def test_a_model_name_in_place_of_a_model_is_a_type_error():
    with pytest.raises(TypeError, match=re.escape("derive_arrs: bg must be a BondGraph, got str 'dc-motor' "
                                                  "(use bondgraph.load_model('dc-motor').model)")):
        derive_arrs("dc-motor")
    with pytest.raises(TypeError, match="arr_report: bg must be a BondGraph, got int 3"):
        arr_report(3)
