"""The HTML ARR report as Chromium renders it: typeset equations, readable drawings, nothing off the page.

Three models: the DC motor (first derivatives, short equations), the three-tank system (long relations from
elimination, laws with absolute values) and the quarter car (second derivatives, integrals, dependent
storage).  Each report is written once, opened in headless Chromium, screenshotted to the test's
tmp_path, and its rendered DOM is checked.  The expectations come from the ARRs themselves (which
derivatives and integrals each needs), not from the printed text.
"""

from __future__ import annotations

import re
import warnings
from datetime import datetime, timezone

import pytest
import sympy as sp

from bondgraph import BondGraph
from bondgraph.library import dc_motor, three_tank
from bondgraph.provenance import model_sha256
from diagnosis import derive_arrs
from diagnosis.report import DRAWING_SCALE, arr_report
from tests.zoo.models import quarter_car

pytestmark = pytest.mark.slow

MODELS = {"dc_motor": dc_motor, "three_tank": three_tank, "quarter_car": quarter_car.build}
EPOCH = 1_700_000_000  # SOURCE_DATE_EPOCH of the reports: their date is this one, not the clock's
#: A drawing at least this wide (CSS px) in the 1400 px window, and its labels at least this high: the issue's
#: drawings were about 500 px wide with 12 px labels.
MIN_DRAWING_WIDTH = 900
MIN_LABEL_PX = 14


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    """Model name -> (model, its ARRs, the report's HTML file), written once for the module's tests."""
    folder = tmp_path_factory.mktemp("arr-reports")
    out = {}
    with pytest.MonkeyPatch.context() as patch, warnings.catch_warnings():
        patch.setenv("SOURCE_DATE_EPOCH", str(EPOCH))
        warnings.simplefilter("ignore")
        for name, build in MODELS.items():
            bg = build()
            arrs = derive_arrs(bg)
            path = folder / f"{name}.html"
            path.write_text(arr_report(bg, "html", arrs=arrs), encoding="utf-8")
            out[name] = (bg, arrs, path)
    return out


@pytest.mark.parametrize("name", MODELS)
def test_the_report_shows_no_raw_sympy_text(name, reports, open_page, tmp_path):
    bg, arrs, path = reports[name]
    page = open_page(path)
    shot = page.screenshot(tmp_path / f"{name}.png")
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    text = page.text()
    for raw in ("Integral(", "Derivative(", "\u2146", "sqrt(", "Abs("):
        assert raw not in text, f"{name}: raw sympy text {raw!r} on the page"
    maths = page.texts("math")
    assert maths, f"{name}: no MathML on the page"
    underscored = [m for m in maths if "_" in m]
    assert not underscored, f"{name}: a literal underscore in math: {underscored[:3]}"


# Every mfrac of the page: the tags and text of its numerator and denominator, and whether the numerator's d
# is upright (mathvariant="normal").
_FRACTIONS = """() => Array.from(document.querySelectorAll('mfrac'), f => {
  const [top, bottom] = f.children;
  const first = top.firstElementChild;
  const d = first && (first.tagName.toLowerCase() === 'msup' ? first.firstElementChild : first);
  return {top: top.textContent, bottom: bottom.textContent, parts: top.children.length,
          upright: !!d && d.getAttribute('mathvariant') === 'normal'};
})"""


@pytest.mark.parametrize("name", MODELS)
def test_derivatives_read_d_x_over_d_t(name, reports, open_page):
    """Each order of derivative the ARRs use is shown as d^k x / d t^k: d and the variable on top."""
    _, arrs, path = reports[name]
    orders = {d.derivative_count for arr in arrs for d in arr.nominal.atoms(sp.Derivative)}
    assert orders, f"{name}: the test needs a model whose ARRs use derivatives"
    fractions = open_page(path).evaluate(_FRACTIONS)
    for k in orders:
        power = "" if k == 1 else str(k)
        found = [f for f in fractions if f["top"].startswith("d" + power) and f["bottom"] == "dt" + power]
        assert found, f"{name}: no d{power}x/dt{power} among {fractions[:5]}"
        assert all(f["parts"] >= 2 and len(f["top"]) > len("d" + power) for f in found)  # d and the variable
        assert all(f["upright"] for f in found)


@pytest.mark.parametrize("name", MODELS)
def test_names_are_subscripts_and_integrals_are_typeset(name, reports, open_page):
    _, arrs, path = reports[name]
    page = open_page(path)
    labels = page.evaluate("Array.from(document.querySelectorAll('.equation'), e => "
                           "(e.querySelector('msub') || {textContent: ''}).textContent)")
    assert labels == ["rn", "\u03a82"] * len(arrs)  # r_n and Psi_2 of each ARR, as subscripts
    assert page.count("td math msub") > 0  # the parameters in the element table
    with_integrals = sum(1 for arr in arrs if arr.nominal.atoms(sp.Integral))
    typeset = page.evaluate("Array.from(document.querySelectorAll('.arr p')).filter(p => p.textContent"
                            ".startsWith('Integrals:')).map(p => p.querySelectorAll('math msubsup').length)")
    assert len(typeset) == len(arrs)
    assert sum(n > 0 for n in typeset) == with_integrals
    if name == "quarter_car":
        assert with_integrals > 0  # the model is here for its integrals


@pytest.mark.parametrize("name", MODELS)
def test_drawings_are_readable(name, reports, open_page):
    page = open_page(reports[name][2])
    drawings = page.evaluate("Array.from(document.querySelectorAll('figure svg'), s => ({width: "
                             "s.getBoundingClientRect().width, units: s.viewBox.baseVal.width, font: "
                             "parseFloat(s.querySelector('g.nodes').getAttribute('font-size'))}))")
    assert len(drawings) == 2
    column = page.rects("body")[0]["width"]
    for d in drawings:
        assert d["width"] >= min(MIN_DRAWING_WIDTH, column - 40), d
        assert d["font"] * d["width"] / d["units"] >= MIN_LABEL_PX, d  # the labels' size on screen
        assert d["width"] <= DRAWING_SCALE * d["units"] + 0.5  # never blown up beyond the set scale


@pytest.mark.parametrize("name", MODELS)
def test_nothing_runs_off_the_page(name, reports, open_page):
    page = open_page(reports[name][2])
    width = page.page_width()
    assert width["scroll"] <= width["viewport"], f"{name}: the page scrolls sideways: {width}"
    assert page.overflowing() == []
    boxes = page.evaluate("Array.from(document.querySelectorAll('.equation'), e => ({scrolls: e.scrollWidth > "
                          "e.clientWidth, overflow: getComputedStyle(e).overflowX, right: "
                          "e.getBoundingClientRect().right}))")
    assert all(b["overflow"] == "auto" and b["right"] <= width["viewport"] for b in boxes)
    if name == "three_tank":  # its elimination ARRs hold single terms wider than the page: they scroll in their box
        assert any(b["scrolls"] for b in boxes)


def _reddish(colour: str) -> bool:
    """A CSS ``rgb(...)`` colour in which red dominates."""
    r, g, b = (int(v) for v in re.findall(r"\d+", colour)[:3])
    return r > 120 and r > 2 * g and r > 2 * b


def test_notes_are_notes_and_errors_are_red(reports, open_page, tmp_path):
    page = open_page(reports["quarter_car"][2])
    assert page.count(".remark.note") > 0  # dependent storage
    assert page.count(".remark.error") == 0
    assert not any(_reddish(c) for c in page.style(".remark.note", "color"))
    assert not any(_reddish(c) for c in page.style(".remark.note", "background-color"))
    clash = BondGraph(name="two sources on one junction")  # a causal conflict: an error, in red
    for name, kind in [("E1", "Se"), ("E2", "Se"), ("J", "0"), ("R", "R")]:
        clash.add(name, kind, **({"value": 1.0} if kind == "R" else {}))
    for tail, head in [("E1", "J"), ("E2", "J"), ("J", "R")]:
        clash.bond(tail, head)
    path = tmp_path / "clash.html"
    path.write_text(arr_report(clash, "html", arrs=[]), encoding="utf-8")  # no ARR: its equations conflict
    page = open_page(path)
    assert page.count(".remark.error") > 0
    assert all(_reddish(c) for c in page.style(".remark.error", "color"))
    assert all("conflict" in t or "no causality" in t for t in page.texts(".remark.error"))


@pytest.mark.parametrize("name", MODELS)
def test_the_provenance_block(name, reports, open_page):
    bg, _, path = reports[name]
    page = open_page(path)
    digest = page.texts(".provenance code.sha256")
    assert len(digest) == 1 and re.fullmatch(r"[0-9a-f]{64}", digest[0])
    assert digest[0] == model_sha256(bg)
    expected = datetime.fromtimestamp(EPOCH, timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    assert page.texts(".provenance time") == [expected]
    assert "bondgraph-phm" in page.texts(".provenance dd")[0]
