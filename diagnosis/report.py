"""ARR reports: the model, its drawing, its ARRs and fault signatures as Markdown, HTML or LaTeX.

The report holds, in order,

0. its provenance: the toolkit's version, when it was made (UTC; ``SOURCE_DATE_EPOCH`` when set) and
   the model's SHA-256 (:mod:`bondgraph.provenance`);
1. the element table: kind, parameter, nominal value, multiplicative uncertainty ``(delta_lo, delta_hi)``
   and the interval ``[value (1 + delta_lo), value (1 + delta_hi)]``, law or modulus, signal;
2. the bond graph drawn twice with power half-arrows and causal strokes: preferred integral causality
   (simulation) and preferred derivative causality with the sensors dualized (diagnosis), storage in
   derivative causality highlighted, and what the assignment found (notes such as dependent storage;
   errors such as conflicts);
3. every ARR: where it comes from, the signals, derivatives and integrals it needs, its nominal part
   ``r_n`` and uncertain part ``Psi_2``;
4. the fault signature matrix with detectability ``Mb`` and isolability ``Ib``.

The three formats carry the same content.  Parameters and signals are typeset as in the equations
(``omega_m`` is omega with subscript m; a name with more underscores has nested subscripts), derivatives
as ``d x / d t``; element ids and ARR names, which a user types, are set as code.  A long equation is
broken between its terms into lines of :data:`LINE_WIDTH` characters at most (a single term longer than
that scrolls in HTML and is scaled to the line in LaTeX).

HTML is one self-contained file: the drawings are inline SVG and the equations MathML, so it opens
offline in any browser with nothing fetched.  LaTeX is a standalone document (TikZ drawings, the
``amsmath`` and ``graphicx`` packages).  Markdown carries the drawings as data-URI SVG images and the
equations as ``$`` LaTeX.

Every text from the model (its free-text name, names, laws, messages) is escaped for the format it
lands in: HTML (:func:`html.escape`), Markdown (HTML escaped; backslash, backtick, brackets, dollar
and bar backslashed), LaTeX (:func:`bondgraph.drawing.latex_escape`), and the equations by
:func:`~diagnosis.deltas.mathml` and :func:`~diagnosis.deltas.latex`, which escape any name that is
not an identifier.

Example
-------
>>> from bondgraph.library import rlc_circuit
>>> text = arr_report(rlc_circuit(), format="md")
>>> "ARR_J1" in text and "| Mb | Ib |" in text and "Model SHA-256" in text
True
"""

from __future__ import annotations

import base64
import html
import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import sympy as sp

from bondgraph import BondGraph
from bondgraph import drawing
from bondgraph.calculus import T
from bondgraph.causality import diagnosis_causality
from bondgraph.errors import ModelError
from bondgraph.names import is_name
from bondgraph.provenance import Provenance, provenance
from bondgraph.structure import Element, require_model

from .derivation import ARR, ARRWarning, derive_arrs
from .deltas import latex, mathml, summands
from .elimination import EXPLAINED, unreached
from .signatures import SignatureMatrix, signature_matrix

__all__ = ["arr_report", "ELEMENT_COLUMNS", "FORMATS", "LINE_WIDTH", "DRAWING_SCALE"]

FORMATS = ("md", "html", "tex")

#: A line of a displayed equation holds terms up to this width (characters of the printed formula, roughly):
#: about the content column of the HTML page and the text width of the LaTeX page.
LINE_WIDTH = 90

#: The drawings' display size, times their drawing units: the labels' 12 units become 18 px, the size of the
#: text around them.  HTML shrinks a drawing to the content column when it is wider.
DRAWING_SCALE = 1.5


# ------------------------------------------------------------------------------------------- content
#
# Every format renders the same content.  A cell of a table or a line of prose is a tuple of parts: a str is
# text, a :class:`_Code` an identifier shown as code, a sympy expression inline math.


@dataclass(frozen=True)
class _Code:
    """An identifier the user types (an element id, an ARR name), shown as code."""

    text: str


@dataclass(frozen=True)
class _Remark:
    """A remark on a drawing: ``level`` is ``"note"`` (information), ``"warning"`` or ``"error"``."""

    level: str
    text: str


@dataclass(frozen=True)
class _Equation:
    """``label = expression``, broken between terms into lines (each line a list of terms)."""

    label: sp.Symbol
    lines: list


@dataclass
class _Section:
    """One ARR: its name, the lines saying what it is built from, its two equations."""

    name: str
    details: list
    equations: list


@dataclass
class _Content:
    """What every format shows, computed once."""

    title: str
    provenance: Provenance
    element_header: list
    elements: list  # rows of cells
    drawings: list  # (caption, causality, remarks)
    arrs: list  # of _Section
    signature_header: list
    signatures: list  # rows of cells
    notes: list  # ARR derivation warnings, as text
    unreached: list  # lines: what the structure allows beyond these ARRs


def arr_report(bg: BondGraph, format: str = "md", *, arrs: list[ARR] | None = None) -> str:
    """The ARR report of a bond graph as a string in ``format`` (``"md"``, ``"html"`` or ``"tex"``).

    ``arrs`` defaults to :func:`~diagnosis.derivation.derive_arrs` of the model; candidates that cannot be
    expressed in known variables are listed as notes.  The report's provenance block gives the time it
    was made: the ``SOURCE_DATE_EPOCH`` environment variable when it is set (a reproducible build), else now.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> text = arr_report(dc_motor(), "html")
    >>> "<mfrac><mrow><mi mathvariant=\\"normal\\">d</mi><mi>i</mi></mrow>" in text   # di/dt
    True
    """
    require_model(bg, "arr_report")
    if format not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}, got {format!r}")
    notes = []
    if arrs is None:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ARRWarning)
            arrs = derive_arrs(bg)
        notes = [str(w.message) for w in caught if issubclass(w.category, ARRWarning)]
    arrs = list(arrs)
    signature_header, signature_rows = _signature_table(signature_matrix(arrs))
    units = bg.units
    content = _Content(bg.name, provenance(bg), [header for header, _ in ELEMENT_COLUMNS], _element_rows(bg),
                       _drawings(bg), [_section(arr, units) for arr in arrs], signature_header, signature_rows, notes,
                       _unreached_lines(bg, arrs))
    return {"md": _markdown, "html": _html, "tex": _latex}[format](bg, content)


def _name(name: str) -> tuple:
    """A parameter or signal name: typeset as math (``omega_m`` is omega sub m), as in the equations."""
    return (sp.Symbol(name),) if is_name(name) else (str(name),)


def _join(items: list, separator: str = ", ") -> list:
    """The parts of ``items`` (each a tuple of parts) with ``separator`` between them."""
    parts: list = []
    for i, item in enumerate(items):
        parts += ([separator] if i else []) + list(item)
    return parts


def _number(value: float | None) -> tuple:
    return () if value is None else (f"{value:.6g}",)


def _delta(name, e: Element) -> tuple:
    return () if e.uncertainty is None else (f"[{e.uncertainty[0]:+.3g}, {e.uncertainty[1]:+.3g}]",)


def _interval(name, e: Element) -> tuple:
    if e.uncertainty is None or e.value is None:
        return ()
    a, b = sorted((e.value * (1 + e.uncertainty[0]), e.value * (1 + e.uncertainty[1])))
    return (f"[{a:.6g}, {b:.6g}]",)


def _law(name, e: Element) -> tuple:
    """The law ``... = 0``, or a modulus other than the plain parameter (an expression, a signal), and constants."""
    parts: list = []
    if e.law is not None:
        parts.append(sp.Eq(e.law, 0, evaluate=False))
    elif e.modulus is not None and e.modulus != sp.Symbol(e.param or ""):
        parts.append(e.modulus)
    constants = [(sp.Eq(sp.Symbol(k), sp.Float(v, 6), evaluate=False),) for k, v in e.constants.items()]
    if constants:
        parts += ([" ("] if parts else []) + _join(constants) + ([")"] if parts else [])
    return tuple(parts)


#: The element table: each column's header and its cell for an element ``(name, element)``.  A column is one
#: entry here, the same in every format: a unit column, once elements carry a unit, is
#: ``("unit", lambda name, e: (e.unit,) if e.unit else ())`` after ``"nominal"``.
ELEMENT_COLUMNS: tuple[tuple[str, Callable[[object, Element], tuple]], ...] = (
    ("element", lambda name, e: (_Code(str(name)),)),
    ("kind", lambda name, e: (e.kind,)),
    ("parameter", lambda name, e: _name(e.param) if e.param else ()),
    ("nominal", lambda name, e: _number(e.value)),
    ("unit", lambda name, e: _units(e)),
    ("delta", _delta),
    ("interval", _interval),
    ("law / modulus", _law),
    ("signal", lambda name, e: _name(e.signal) if e.signal else ()),
)

def _units(e: Element) -> tuple:
    """The element's unit, then its law constants' and modulating signal's (``M: kg``): as text, SI symbols."""
    own = (str(e.unit),) if e.unit is not None else ()
    others = "; ".join(f"{name}: {unit}" for name, unit in e.units.items())
    return own + ((("; " if own else "") + others,) if others else ())


#: The columns whose cells are numbers (right-aligned in HTML).
_NUMERIC = frozenset({"nominal", "delta", "interval"})


def _element_rows(bg: BondGraph) -> list[list[tuple]]:
    return [[cell(name, e) for _, cell in ELEMENT_COLUMNS] for name, e in bg.elements.items()]


def _drawings(bg: BondGraph) -> list:
    out = []
    for preferred, caption in (("integral", "preferred integral causality (simulation)"),
                               ("derivative", "preferred derivative causality, sensors dualized (diagnosis)")):
        causality = _causality(bg, preferred)
        if causality is None:
            remarks = [_Remark("error", "no causality assigned: the drawing is acausal")]
        else:
            remarks = [_Remark(_ISSUE_LEVEL.get(issue.kind, "error"), str(issue)) for issue in causality.issues]
        out.append((caption, causality, remarks))
    return out


#: How a causality issue is shown: dependent storage is information about the model, a loop asks for an
#: implicit equation, a conflict is a causality that could not be assigned (any other kind: an error).
_ISSUE_LEVEL = {"dependent storage": "note", "algebraic loop": "warning", "conflict": "error"}


def _causality(bg: BondGraph, preferred: str):
    """The assignment the toolkit uses: integral for simulation, derivative with dualized sensors for ARRs."""
    try:
        if preferred == "derivative":
            return diagnosis_causality(bg)
        return bg.assign_causality("integral")
    except ModelError:  # e.g. a law that cannot be inverted for the preferred causality: draw it acausal
        return None


def _section(arr: ARR, units=None) -> _Section:
    details = _arr_details(arr)
    unit = arr.unit(units) if units is not None and units.declared else None
    if unit is not None:
        details.insert(1, (f"Unit of the residual: {unit}",))
    if arr.simulation:   # the states are simulated: their rates instead of Psi_2, whose band the corners give
        details.append(("Simulated states (integrated from the record, at rest at its start unless given): ",
                        *_join([_name(x) for x in arr.states])))
        details.append(("Band: the range of the residual over the simulations at the corners of the parameters' "
                        "box",))
        rates = [_equation(sp.Derivative(sp.Function(x)(T), T), f) for x, f in zip(arr.states, arr.rates)]
        return _Section(arr.name, details, [_equation(sp.Symbol("r_n"), arr.nominal), *rates])
    return _Section(arr.name, details,
                    [_equation(sp.Symbol("r_n"), arr.nominal), _equation(sp.Symbol("Psi_2"), arr.uncertain)])


def _arr_details(arr: ARR) -> list[tuple]:
    """What an ARR is built from and what it asks of the data, as lines of parts."""
    if arr.detector is not None:
        place = ("sensor ", _Code(str(arr.detector)))
    else:
        place = ("junction ", _Code(str(arr.junction)))
    highest: dict = {}  # signal -> its highest derivative in the relation
    for d in arr.nominal.atoms(sp.Derivative):
        name = str(d.expr.func) if isinstance(d.expr, sp.core.function.AppliedUndef) else str(d.expr)
        if name not in highest or d.derivative_count > highest[name].derivative_count:
            highest[name] = d
    derivatives = [(highest[name],) for name in sorted(highest)]
    integrals = [(i,) for i in sorted(arr.nominal.atoms(sp.Integral), key=sp.default_sort_key)]
    lines = [("Residual at ", *place, f", written as: {arr.form}" + ("; implicit (non-invertible law)"
                                                                     if arr.implicit else "")),
             ("Signals: ", *(_join([_name(s) for s in arr.signals]) or ["none"])),
             ("Derivatives: ", *(_join(derivatives) or ["none"])),
             ("Integrals: ", *(_join(integrals) or ["none"]))]
    if arr.origin:
        equations = [(_Code(node), f" {role}") for node, _, role in (o.partition(" ") for o in arr.origin)]
        lines.append(("From the equations: ", *_join(equations)))
    return lines


def _equation(label: sp.Symbol, expression: sp.Expr) -> _Equation:
    """``label = expression`` broken between terms into lines of about :data:`LINE_WIDTH` characters."""
    lines: list = [[]]
    width = 0
    for term in summands(expression):
        size = _printed_width(term)
        if lines[-1] and width + size > LINE_WIDTH:
            lines.append([])
            width = 0
        lines[-1].append(term)
        width += size + 3  # and the sign between terms
    return _Equation(label, lines)


def _printed_width(expression: sp.Expr) -> int:
    """A rough width of a printed formula, in characters: its LaTeX less the markup.

    A fraction counts its numerator and denominator side by side, so long fractions break early rather
    than late; the estimate only chooses where lines break.
    """
    text = re.sub(r"\\(?:left|right)\b", "", latex(expression))
    text = re.sub(r"\\[A-Za-z]+", "x", text)  # a command is one glyph: \omega, \delta
    return len(re.sub(r"[{}\s^_]|\\,", "", text))


def _fault(fault: str) -> tuple:
    """A fault candidate: a parameter, or ``sensor <signal>``."""
    kind, _, signal = str(fault).partition(" ")
    if kind == "sensor" and signal:
        return ("sensor ", *_name(signal))
    return _name(str(fault))


def _signature_table(s: SignatureMatrix) -> tuple[list, list]:
    header = [("fault",), *[(_Code(str(c)),) for c in s.columns], ("Mb",), ("Ib",)]
    detectable, isolable = s.detectable.tolist(), s.isolable.tolist()  # once: each is a pass over the matrix
    rows = [[_fault(r), *[(str(v),) for v in values], (str(detectable[i]),), (str(isolable[i]),)]
            for i, (r, values) in enumerate(zip(s.rows, s.matrix.tolist()))]
    return header, rows


def _unreached_lines(bg: BondGraph, arrs: list) -> list[tuple]:
    """What the structure allows beyond ``arrs``, grouped by the reason :func:`unreached` gives."""
    if not arrs:
        return []
    left = unreached(bg, arrs, explain=True)
    reasons = left["reasons"]
    lines = [("Detectable by the structure, seen by no ARR: ", *_fault(fault),
              f" ({reasons.get(fault, 'not examined')})") for fault in left["detect"]]
    groups: dict = {}
    for a, b in left["isolate"]:
        groups.setdefault(reasons.get((a, b), f"not examined (more than {EXPLAINED} gaps)"), []).append((a, b))
    for reason, pairs in groups.items():
        lines.append((f"Isolable by the structure, not by these ARRs ({len(pairs)} ordered pairs; {reason}): ",
                      *_join([(*_fault(a), " from ", *_fault(b)) for a, b in pairs])))
    return lines


_PROVENANCE_HEADS = ("Generated by", "Generated on", "Model SHA-256")


def _provenance_values(p: Provenance) -> tuple[str, str, str]:
    return f"{p.tool} {p.version} (sympy {p.sympy})", p.generated, p.model_sha256


# ------------------------------------------------------------------------------------------- markdown

def _markdown(bg: BondGraph, c: _Content) -> str:
    lines = [f"# ARR report: {_md(c.title)}", ""]
    tool, date, digest = _provenance_values(c.provenance)
    lines += [f"- {_PROVENANCE_HEADS[0]}: {_md(tool)}", f"- {_PROVENANCE_HEADS[1]}: {_md(date)}",
              f"- {_PROVENANCE_HEADS[2]}: `{digest}` ({_md(c.provenance.hashed)})", ""]
    lines += ["## Elements", "", _md_table(c.element_header, c.elements), "", "## Bond graph", ""]
    for caption, causality, remarks in c.drawings:
        svg = drawing.to_svg(bg, causality, scale=DRAWING_SCALE)
        data = base64.b64encode(svg.encode("utf-8")).decode("ascii")
        lines += [f"**{caption}**", "", f'<img alt="{html.escape(caption)}" src="data:image/svg+xml;base64,{data}"/>',
                  ""]
        lines += [f"> **{r.level.capitalize()}:** {_md(r.text)}\n>" for r in remarks]
        lines += [""] if remarks else []
    lines += ["## Analytical redundancy relations", ""]
    if not c.arrs:
        lines += ["The model gives no ARR (it needs De/Df sensors on its junctions).", ""]
    for arr in c.arrs:
        lines += [f"### {_md(arr.name)}", ""] + [f"- {_md_inline(line)}" for line in arr.details] + [""]
        lines += [f"$${_tex_equation(eq, 'aligned', fit=False)}$$\n" for eq in arr.equations]
    lines += ["## Fault signatures", "", _md_table(c.signature_header, c.signatures), ""]
    if c.unreached:
        lines += ["## Beyond these ARRs", ""] + [f"- {_md_inline(n)}" for n in c.unreached] + [""]
    if c.notes:
        lines += ["## Notes", ""] + [f"- {_md(n)}" for n in c.notes] + [""]
    return "\n".join(lines)


#: Markdown syntax a text from the model may not use: links and images (``[x](javascript:...)``), code
#: spans and math (``$``); each is backslash-escaped (HTML is escaped by :func:`html.escape`).
_MD_SPECIAL = {ch: "\\" + ch for ch in "\\`[]$|"}


def _md(text: str) -> str:
    """Text shown as itself in Markdown: HTML escaped, link, code, math and table syntax backslashed."""
    escaped = "".join(_MD_SPECIAL.get(ch, ch) for ch in html.escape(str(text), quote=False))
    return re.sub(r"[\x00-\x1f\x7f]", " ", escaped)  # a newline would end the line (or the table row)


def _md_math(expression: sp.Expr) -> str:
    """Inline math; ``|`` spelt ``\\vert`` so that an absolute value cannot end a table cell."""
    return "$" + latex(expression).replace("\\|", "\\Vert ").replace("|", "\\vert ") + "$"


def _md_inline(parts: tuple) -> str:
    out = []
    for part in parts:
        if isinstance(part, _Code):
            # ids and ARR names are letters, digits and _; anything else is shown as escaped text
            out.append(f"`{part.text}`" if re.fullmatch(r"\w+", part.text, re.ASCII) else _md(part.text))
        elif isinstance(part, sp.Basic):
            out.append(_md_math(part))
        else:
            out.append(_md(part))
    return "".join(out)


def _md_table(header: list, rows: list) -> str:
    out = ["| " + " | ".join(_md_inline(_parts(h)) for h in header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(_md_inline(cell) for cell in row) + " |" for row in rows]
    return "\n".join(out)


def _parts(cell) -> tuple:
    """A header is a plain string or a tuple of parts."""
    return cell if isinstance(cell, tuple) else (cell,)


# ------------------------------------------------------------------------------------------- html

_CSS = """body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;max-width:70em;margin:2em auto;padding:0 1em;
color:#222;line-height:1.45}h2{margin-top:1.8em;border-bottom:1px solid #ddd;padding-bottom:.2em}
.table{overflow-x:auto;margin:1em 0}table{border-collapse:collapse}
td,th{border:1px solid #bbb;padding:.25em .6em;text-align:left;vertical-align:top}th{background:#f0f0f0}
td.number{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
code{font-family:ui-monospace,SFMono-Regular,Menlo,Consolas,monospace;font-size:.92em}
math{font-size:1.1em;font-family:"STIX Two Math","Cambria Math","DejaVu Math TeX Gyre",math}
figure{margin:1em 0}figcaption{font-weight:600;margin-bottom:.5em}
figure svg{display:block;max-width:100%;height:auto}
.equation{overflow-x:auto;overflow-y:hidden;margin:.5em 0;padding:.2em 0}
.equation mtd{text-align:left;padding:.15em 0;math-style:normal}.equation mtd:first-child{text-align:right}
.arr{margin:1.5em 0}.arr p{margin:.3em 0}
.remark{margin:.5em 0;padding:.4em .8em;border-left:4px solid}
.note{background:#eef3f8;border-color:#7a96b8}.warning{background:#fff6e0;border-color:#c99400}
.error{background:#fdecea;border-color:#c62828;color:#8b1a1a}
.provenance{font-size:.9em;color:#444;background:#fafafa;border:1px solid #ddd;padding:.6em 1em}
.provenance dl{display:grid;grid-template-columns:max-content 1fr;gap:.2em 1em;margin:0}
.provenance dt{font-weight:600}.provenance dd{margin:0;overflow-wrap:anywhere}
.provenance small{display:block;color:#666}
@media print{.equation,.table{overflow:visible}}"""


def _html(bg: BondGraph, c: _Content) -> str:
    e = html.escape
    parts = ["<!DOCTYPE html>", "<html lang=\"en\"><head><meta charset=\"utf-8\">",
             "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">",
             f"<title>ARR report: {e(c.title)}</title><style>{_CSS}</style></head><body>",
             f"<h1>ARR report: {e(c.title)}</h1>", _html_provenance(c.provenance),
             "<h2 id=\"elements\">Elements</h2>", _html_table(c.element_header, c.elements, _NUMERIC),
             "<h2 id=\"bond-graph\">Bond graph</h2>"]
    for caption, causality, remarks in c.drawings:
        parts.append(f"<figure><figcaption>{e(caption)}</figcaption>"
                     f"{drawing.to_svg(bg, causality, scale=DRAWING_SCALE)}</figure>")
        parts += [f"<p class=\"remark {r.level}\"><strong>{r.level.capitalize()}:</strong> {e(r.text)}</p>"
                  for r in remarks]
    parts.append("<h2 id=\"arrs\">Analytical redundancy relations</h2>")
    if not c.arrs:
        parts.append("<p>The model gives no ARR (it needs De/Df sensors on its junctions).</p>")
    for arr in c.arrs:
        parts.append(f"<section class=\"arr\" id=\"{e(arr.name)}\"><h3>{e(arr.name)}</h3>")
        parts += [f"<p>{_html_inline(line)}</p>" for line in arr.details]
        parts += [_html_equation(eq) for eq in arr.equations] + ["</section>"]
    parts += ["<h2 id=\"signatures\">Fault signatures</h2>", _html_table(c.signature_header, c.signatures)]
    if c.unreached:
        parts += ["<h2>Beyond these ARRs</h2><ul>"] + [f"<li>{_html_inline(n)}</li>" for n in c.unreached] + ["</ul>"]
    if c.notes:
        parts += ["<h2>Notes</h2>"] + [f"<p class=\"remark note\">{e(n)}</p>" for n in c.notes]
    parts.append("</body></html>")
    return "\n".join(parts)


def _html_provenance(p: Provenance) -> str:
    e = html.escape
    tool, date, digest = _provenance_values(p)
    return (f"<section class=\"provenance\" aria-label=\"provenance\"><dl><dt>{_PROVENANCE_HEADS[0]}</dt>"
            f"<dd>{e(tool)}</dd><dt>{_PROVENANCE_HEADS[1]}</dt><dd><time>{e(date)}</time></dd>"
            f"<dt>{_PROVENANCE_HEADS[2]}</dt><dd><code class=\"sha256\">{e(digest)}</code>"
            f"<small>{e(p.hashed)}</small></dd></dl></section>")


def _html_math(expression: sp.Expr) -> str:
    return f"<math>{mathml(expression)}</math>"


def _html_inline(parts: tuple) -> str:
    out = []
    for part in parts:
        if isinstance(part, _Code):
            out.append(f"<code>{html.escape(part.text)}</code>")
        elif isinstance(part, sp.Basic):
            out.append(_html_math(part))
        else:
            out.append(html.escape(part))
    return "".join(out)


def _mathml_terms(terms: list, first: bool) -> str:
    """The MathML of consecutive terms of a sum; a line after the first starts with its sign."""
    out = []
    for i, term in enumerate(terms):
        if not i and first:
            out.append(mathml(term))
            continue
        sign, term = ("&#8722;", -term) if term.could_extract_minus_sign() else ("+", term)
        out.append(f"<mo>{sign}</mo>{mathml(term)}")
    return "".join(out)


def _html_equation(eq: _Equation) -> str:
    """A displayed equation in a box that scrolls sideways should a single term be wider than the page."""
    label = mathml(eq.label)
    if len(eq.lines) == 1:
        body = f"<mrow>{label}<mo>=</mo>{_mathml_terms(eq.lines[0], True)}</mrow>"
    else:
        rows = [f"<mtr><mtd>{label}</mtd><mtd><mo>=</mo>{_mathml_terms(eq.lines[0], True)}</mtd></mtr>"]
        rows += [f"<mtr><mtd></mtd><mtd><mspace width=\"1em\"></mspace>{_mathml_terms(line, False)}</mtd></mtr>"
                 for line in eq.lines[1:]]
        body = f"<mtable>{''.join(rows)}</mtable>"
    return (f"<div class=\"equation\"><math display=\"block\" xmlns=\"http://www.w3.org/1998/Math/MathML\">{body}"
            "</math></div>")


def _html_table(header: list, rows: list, numeric: frozenset = frozenset()) -> str:
    opening = ["<td class=\"number\">" if isinstance(h, str) and h in numeric else "<td>" for h in header]
    head = "".join(f"<th scope=\"col\">{_html_inline(_parts(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"{td}{_html_inline(cell)}</td>" for cell, td in zip(row, opening)) + "</tr>"
                   for row in rows)
    return f"<div class=\"table\"><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>"


# ------------------------------------------------------------------------------------------- latex

#: ``\fitted{width}`` sets the saved box at its size, or scaled down to ``width`` when it is wider, so that
#: neither a drawing nor a long term runs off the page.
_TEX_PREAMBLE = r"""\documentclass{article}
\usepackage[margin=2cm]{geometry}
\usepackage{amsmath}
\usepackage{array}
\usepackage{graphicx}
\usepackage{tikz}
\usepackage{longtable}
\newsavebox{\fitbox}
\newcommand{\fitted}[1]{\ifdim\wd\fitbox>#1\resizebox{#1}{!}{\usebox{\fitbox}}\else\usebox{\fitbox}\fi}
\newcommand{\fitmath}[1]{\sbox{\fitbox}{$\displaystyle #1$}\fitted{0.85\linewidth}}
\setlength{\emergencystretch}{3em}"""


def _latex(bg: BondGraph, c: _Content) -> str:
    t = drawing.latex_escape
    tool, date, digest = _provenance_values(c.provenance)
    parts = [_TEX_PREAMBLE, r"\begin{document}", rf"\section*{{ARR report: {t(c.title)}}}",
             r"\begin{small}\begin{tabular}{@{}l>{\raggedright\arraybackslash}p{0.75\linewidth}@{}}",
             rf"{_PROVENANCE_HEADS[0]} & {t(tool)} \\", rf"{_PROVENANCE_HEADS[1]} & {t(date)} \\",
             rf"{_PROVENANCE_HEADS[2]} & \texttt{{{t(digest)}}} \\ & {t(c.provenance.hashed)} \\",
             r"\end{tabular}\end{small}",
             r"\subsection*{Elements}", _tex_table(c.element_header, c.elements, law_column=True),
             r"\subsection*{Bond graph}"]
    for caption, causality, remarks in c.drawings:
        parts += [rf"\paragraph{{{t(caption)}}}", "", r"\begin{center}\begin{lrbox}{\fitbox}",
                  drawing.to_tikz(bg, causality), r"\end{lrbox}\fitted{\linewidth}\end{center}"]
        parts += [(rf"\noindent\textbf{{Error:}} {t(r.text)}\par" if r.level == "error"
                   else rf"\noindent\textit{{{r.level.capitalize()}:}} {t(r.text)}\par") for r in remarks]
    parts.append(r"\subsection*{Analytical redundancy relations}")
    if not c.arrs:
        parts.append("The model gives no ARR (it needs De/Df sensors on its junctions).")
    for arr in c.arrs:
        parts += [rf"\subsubsection*{{{t(arr.name)}}}", r"\begin{itemize}"]
        parts += [rf"\item {_tex_inline(line)}" for line in arr.details] + [r"\end{itemize}"]
        parts += [r"\begin{align*}", " \\\\\n".join(_tex_equation(eq, None, fit=True) for eq in arr.equations),
                  r"\end{align*}"]
    parts += [r"\subsection*{Fault signatures}", _tex_table(c.signature_header, c.signatures, turned=True)]
    if c.unreached:
        parts += [r"\subsection*{Beyond these ARRs}", r"\begin{itemize}"]
        parts += [rf"\item {_tex_inline(n)}" for n in c.unreached] + [r"\end{itemize}"]
    if c.notes:
        parts += [r"\subsection*{Notes}", r"\begin{itemize}"] + [rf"\item {t(n)}" for n in c.notes] + [r"\end{itemize}"]
    parts.append(r"\end{document}")
    return "\n".join(parts) + "\n"


def _latex_terms(terms: list, first: bool) -> str:
    """The LaTeX of consecutive terms of a sum; a line after the first starts with its sign."""
    out = []
    for i, term in enumerate(terms):
        if not i and first:
            out.append(latex(term))
            continue
        sign, term = ("-", -term) if term.could_extract_minus_sign() else ("+", term)
        out.append(("" if i else "{} ") + f"{sign} {latex(term)}")  # {}: a binary sign at the start of a line
    return " ".join(out)


def _tex_equation(eq: _Equation, environment: str | None, *, fit: bool) -> str:
    """``label &= line \\\\ &\\quad line ...``: rows of an ``align*`` (or inside ``environment``).

    With ``fit`` each line is set by ``\\fitmath``, scaled down to the page should a single term be wider.
    """
    def line(terms, first):
        text = _latex_terms(terms, first)
        return rf"\fitmath{{{text}}}" if fit else text

    rows = [f"{latex(eq.label)} &= {line(eq.lines[0], True)}"]
    rows += [rf"&\quad {line(terms, False)}" for terms in eq.lines[1:]]
    body = " \\\\\n".join(rows)
    if environment is None:
        return body
    if len(rows) == 1:
        return body.replace(" &= ", " = ", 1)
    return rf"\begin{{{environment}}}{body}\end{{{environment}}}"


def _tex_inline(parts: tuple) -> str:
    out = []
    for part in parts:
        if isinstance(part, _Code):
            out.append(rf"\texttt{{{drawing.latex_escape(part.text)}}}")
        elif isinstance(part, sp.Basic):
            out.append(f"${latex(part)}$")
        else:
            out.append(drawing.latex_escape(part))
    return "".join(out)


def _tex_table(header: list, rows: list, *, law_column: bool = False, turned: bool = False) -> str:
    """A small ``longtable``; the law column, when there is one, wraps at a quarter of the line (inline math
    breaks after its operators); ``turned`` sets the headers after the first upright (a signature matrix
    with many ARRs)."""
    spec = "".join(r">{\raggedright\arraybackslash}p{0.25\linewidth}" if law_column and h == "law / modulus"
                   else "l" for h in header)
    cells = [_tex_inline(_parts(h)) for h in header]
    if turned:
        cells = cells[:1] + [rf"\rotatebox{{90}}{{{cell}}}" for cell in cells[1:]]
    lines = [r"\begingroup\small\setlength{\tabcolsep}{3pt}", rf"\begin{{longtable}}{{{spec}}}",
             " & ".join(cells) + r" \\ \hline", r"\endhead"]
    lines += [" & ".join(_tex_inline(cell) for cell in row) + r" \\" for row in rows]
    lines.append(r"\end{longtable}\endgroup")
    return "\n".join(lines)
