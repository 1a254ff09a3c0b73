"""How the ARR report typesets: derivatives, subscripts, integrals, long equations, remarks, provenance.

The printers (:func:`diagnosis.deltas.mathml`, :func:`diagnosis.deltas.latex`) are checked on small
expressions, parsed as XML where it is MathML; the report's three formats on the library's models.
The rendered page is checked in Chromium by tests/browser/test_arr_report_page.py.
"""

from __future__ import annotations

import re
import warnings
import xml.etree.ElementTree as ET

import pytest
import sympy as sp

from bondgraph.library import dc_motor, rlc_circuit, three_tank
from bondgraph.provenance import model_sha256
from diagnosis import derive_arrs
from diagnosis.deltas import delta, latex, mathml, summands
from diagnosis.report import ELEMENT_COLUMNS, arr_report

T = sp.Symbol("t")
X = sp.Function("x")(T)
MATHML = "{http://www.w3.org/1998/Math/MathML}"


def tree(text: str) -> ET.Element:
    """A MathML fragment as an element tree (namespace dropped from the tags)."""
    text = re.sub(r"&(?!(?:lt|gt|amp|quot|apos|#\d+|#x[0-9A-Fa-f]+);)[A-Za-z]+;", "", text)
    root = ET.fromstring(f'<math xmlns="http://www.w3.org/1998/Math/MathML">{text}</math>')
    for element in root.iter():
        element.tag = element.tag.replace(MATHML, "")
    return root


def shape(element: ET.Element) -> str:
    """``tag(child, child)`` with the text of leaves: the structure of a MathML tree, compactly."""
    children = list(element)
    if not children:
        return f"{element.tag}:{element.text or ''}"
    return f"{element.tag}(" + ", ".join(shape(c) for c in children) + ")"


@pytest.mark.parametrize("order", [1, 2, 3])
def test_mathml_derivative_is_d_x_over_d_t(order):
    fraction = tree(mathml(sp.Derivative(X, (T, order)))).find("mfrac")
    top, bottom = list(fraction)
    d = "mi:d" if order == 1 else f"msup(mi:d, mn:{order})"
    t = "mi:t" if order == 1 else f"msup(mi:t, mn:{order})"
    assert shape(top) == f"mrow({d}, mi:x)" and shape(bottom) == f"mrow(mi:d, {t})"
    assert all(e.get("mathvariant") == "normal" for e in fraction.iter("mi") if e.text == "d")  # upright d


def test_mathml_has_no_differential_sign_nor_raw_names():
    text = mathml(sp.Derivative(X, (T, 2)) + sp.Integral(X, (T, 0, T)) + sp.Symbol("h_tank_2"))
    assert "&dd;" not in text and "\u2146" not in text and "&#8518;" not in text
    assert "_" not in "".join(tree(text).itertext())


def test_a_derivative_of_an_expression_keeps_it_in_parentheses():
    y = sp.Function("y")(T)
    printed = shape(tree(mathml(sp.Derivative(X * y, T)))[0])
    assert printed.startswith("mrow(mfrac(mrow(mi:d), mrow(mi:d, mi:t)), mrow(mo:(")
    assert latex(sp.Derivative(X * y, T)) == (r"\frac{\mathrm{d}}{\mathrm{d} t} \left(x{\left(t \right)} "
                                              r"y{\left(t \right)}\right)")


def test_a_derivative_in_a_product_is_not_parenthesized():
    text = mathml(sp.Symbol("L") * sp.Derivative(X, T))
    assert "<mo>(</mo><mfrac>" not in text and "<mfrac>" in text


@pytest.mark.parametrize("order, expected", [(1, r"\frac{\mathrm{d} x}{\mathrm{d} t}"),
                                             (2, r"\frac{\mathrm{d}^{2} x}{\mathrm{d} t^{2}}")])
def test_latex_derivative_is_d_x_over_d_t(order, expected):
    assert latex(sp.Derivative(X, (T, order))) == expected


@pytest.mark.parametrize("name, mathml_shape, tex", [
    ("r_n", "msub(mi:r, mi:n)", "r_{n}"),
    ("Psi_2", "msub(mi:\u03a8, mn:2)", r"\Psi_{2}"),
    ("h_tank_2", "msub(mi:h, msub(mi:tank, mn:2))", "h_{tank_{2}}"),
    ("omega_m_ref", "msub(mi:\u03c9, msub(mi:m, mi:ref))", r"\omega_{m_{ref}}"),
])
def test_underscores_are_nested_subscripts(name, mathml_shape, tex):
    assert shape(tree(mathml(sp.Symbol(name)))[0]) == mathml_shape
    assert latex(sp.Symbol(name)) == tex


@pytest.mark.parametrize("name", ["_x", "x_", "x__y"])
def test_names_with_empty_parts_are_shown_as_written(name):
    assert "".join(tree(mathml(sp.Symbol(name))).itertext()) == name
    assert latex(sp.Symbol(name)) == r"\text{" + name.replace("_", r"\_") + "}"


def test_integrals_are_typeset():
    integral = sp.Integral(-sp.Derivative(X, T), (T, 0, T))
    root = tree(mathml(integral))[0]
    sign = root.find("msubsup")
    assert shape(sign) == "msubsup(mo:\u222b, mn:0, mi:t)"
    assert shape(root[1]).startswith("mrow(mo:(, mrow(mo:\u2212, mfrac(")  # a negative integrand in parentheses
    assert [shape(e) for e in root[-3:]] == ["mspace:", "mi:d", "mi:t"]
    assert latex(integral) == (r"\int\limits_{0}^{t} \left(- \frac{\mathrm{d} x}{\mathrm{d} t}\right)\, "
                               r"\mathrm{d}t")


def test_summands_follow_the_printed_order():
    """Printed one by one with their signs, the terms give the printed sum: a broken line keeps the order."""
    expression = sp.Symbol("b") * X - sp.Symbol("a") * sp.Derivative(X, T) + delta("R") * sp.Symbol("R") - 3
    terms = summands(expression)
    assert len(terms) == 4 and sp.Add(*terms) == expression
    joined = [latex(terms[0])] + [f"- {latex(-t)}" if t.could_extract_minus_sign() else f"+ {latex(t)}"
                                  for t in terms[1:]]
    assert " ".join(joined) == latex(expression)


@pytest.fixture(scope="module")
def motor():
    """The DC motor's reports in the three formats, at a fixed date."""
    bg = dc_motor()
    arrs = derive_arrs(bg)
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("SOURCE_DATE_EPOCH", "86400")
        return bg, arrs, {fmt: arr_report(bg, fmt, arrs=arrs) for fmt in ("md", "html", "tex")}


def test_every_format_labels_the_equations_with_subscripts(motor):
    _, arrs, text = motor
    html = text["html"]
    assert html.count("<msub><mi>r</mi><mi>n</mi></msub><mo>=</mo>") == len(arrs)
    assert html.count("<msub><mi>&#936;</mi><mn>2</mn></msub><mo>=</mo>") == len(arrs)
    for fmt in ("md", "tex"):
        assert text[fmt].count("r_{n} ") == len(arrs) and text[fmt].count(r"\Psi_{2} ") == len(arrs)
    assert "<mi>r_n</mi>" not in html and "\u03a8_2" not in html


def test_every_format_writes_derivatives_as_fractions(motor):
    _, arrs, text = motor
    signals = {d.expr.func.__name__ for arr in arrs for d in arr.nominal.atoms(sp.Derivative)}
    for name in signals:  # in the equations and on the "Derivatives:" line
        symbol = sp.Symbol(name)
        assert text["html"].count(f'<mfrac><mrow><mi mathvariant="normal">d</mi>{mathml(symbol)}</mrow>') >= 2
        for fmt in ("md", "tex"):
            assert text[fmt].count(rf"\frac{{\mathrm{{d}} {latex(symbol)}}}{{\mathrm{{d}} t}}") >= 2
    for raw in ("Derivative(", "&dd;", "\u2146", r"\frac{d}{d t}"):
        assert all(raw not in t for t in text.values())


def test_every_format_carries_the_same_provenance(motor):
    bg, _, text = motor
    digest = model_sha256(bg)
    for fmt, t in text.items():
        assert digest in t and "1970-01-02 00:00:00 UTC" in t and "bondgraph-phm" in t, fmt
    assert f'<code class="sha256">{digest}</code>' in text["html"]


def test_every_format_has_the_element_columns(motor):
    _, _, text = motor
    headers = [h for h, _ in ELEMENT_COLUMNS]
    assert "| " + " | ".join(headers) + " |" in text["md"]
    assert "".join(f'<th scope="col">{h}</th>' for h in headers) in text["html"]
    assert " & ".join(headers) + r" \\ \hline" in text["tex"]


def test_integrals_are_typeset_in_every_format():
    bg = rlc_circuit()
    arrs = derive_arrs(bg, integrals="keep")  # the capacitor's ARR keeps the integral of i
    assert any(arr.nominal.atoms(sp.Integral) for arr in arrs)
    for fmt in ("md", "html", "tex"):
        text = arr_report(bg, fmt, arrs=arrs)
        assert "Integral(" not in text, fmt
        line = next(line for line in text.splitlines() if "Integrals: " in line and "none" not in line)
        assert ("<msubsup><mo>&#8747;</mo><mn>0</mn><mi>t</mi></msubsup>" if fmt == "html"
                else r"\int\limits_{0}^{t}") in line, fmt


@pytest.mark.slow  # derives the three-tank system's long relations: about 6 s
def test_a_long_equation_is_broken_between_terms_alike_in_every_format():
    bg = three_tank()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arrs = derive_arrs(bg)
    longest = max(arrs, key=lambda arr: len(summands(arr.uncertain)))
    text = {fmt: arr_report(bg, fmt, arrs=[longest]) for fmt in ("md", "html", "tex")}
    rows = text["html"].split('<div class="equation">')[1].count("<mtr>")  # r_n's lines
    assert rows > 1, "the test needs an r_n longer than a line"
    r_n = text["tex"].split(r"\Psi_{2}", 1)[0].rsplit(r"\begin{align*}", 1)[1]
    assert r_n.count(r"\fitmath{") == rows  # each line set by \fitmath, scaled to the page if still too wide
    md = text["md"].split("$$")[1]
    assert md.startswith(r"\begin{aligned}r_{n} &=") and md.count(r"\\") == rows - 1


def test_html_equations_sit_in_a_scrolling_box():
    text = arr_report(rlc_circuit(), "html")
    assert text.count('<div class="equation"><math display="block"') == 4
    assert re.search(r"\.equation\{overflow-x:auto", text)
    assert re.search(r"figure svg\{display:block;max-width:100%;height:auto\}", text)


def test_markdown_tables_hold_no_bare_bar():
    """three_tank's laws hold |e|: in a table cell a bare | would end the cell."""
    text = arr_report(three_tank(), "md", arrs=[])
    table = text.split("## Elements", 1)[1].split("##", 1)[0]
    rows = [line for line in table.splitlines() if line.startswith("| ")]
    header_bars = rows[0].count("|")
    assert r"\vert" in text
    assert all(len(re.findall(r"(?<!\\)\|", row)) == header_bars for row in rows)


def test_dependent_storage_is_a_note_and_a_conflict_an_error():
    from tests.zoo.models import quarter_car

    html = arr_report(quarter_car.build(), "html", arrs=[])
    notes = re.findall(r'<p class="remark (\w+)"><strong>\w+:</strong> ([^<]*)</p>', html)
    assert notes and all(level == "note" for level, text in notes if text.startswith("dependent storage"))
    assert '<p class="remark error">' not in html
    md = arr_report(quarter_car.build(), "md", arrs=[])
    assert "> **Note:** dependent storage" in md
    assert ".error{" in html and re.search(r"\.note\{background:#eef3f8", html)
