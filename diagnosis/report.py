"""ARR reports: the model, its drawing, its ARRs and fault signatures as Markdown, HTML or LaTeX.

The report holds, in order,

1. the element table: kind, parameter, nominal value, multiplicative uncertainty ``(delta_lo, delta_hi)``
   and the interval ``[value (1 + delta_lo), value (1 + delta_hi)]``, law or modulus, signal;
2. the bond graph drawn twice with power half-arrows and causal strokes: preferred integral causality
   (simulation) and preferred derivative causality with the sensors dualized (diagnosis), storage in
   derivative causality highlighted, and what the assignment found (conflicts, loops);
3. every ARR: its nominal part ``r_n`` and uncertain part ``Psi_2`` (and the signals it uses);
4. the fault signature matrix with detectability ``Mb`` and isolability ``Ib``.

HTML is one self-contained file: the drawings are inline SVG and the equations MathML from sympy, so it
opens offline in any browser with nothing fetched.  LaTeX is a standalone document (TikZ drawings).
Markdown carries the drawings as data-URI SVG images and the equations as ``$$`` LaTeX.

Every text from the model (its free-text name, names, laws, messages) is escaped for the format it
lands in: HTML (:func:`html.escape`), Markdown (HTML escaped; backslash, backtick, brackets, dollar
and bar backslashed), LaTeX (:func:`bondgraph.drawing.latex_escape`), and the equations by
:func:`~diagnosis.deltas.mathml` and :func:`~diagnosis.deltas.latex`, which escape any name that is
not an identifier.

Example
-------
>>> from bondgraph.library import rlc_circuit
>>> text = arr_report(rlc_circuit(), format="md")
>>> "ARR_J1" in text and "| Mb | Ib |" in text
True
"""

from __future__ import annotations

import base64
import html
import re
import warnings
from dataclasses import dataclass

import sympy as sp

from bondgraph import BondGraph
from bondgraph import drawing
from bondgraph.causality import diagnosis_causality
from bondgraph.errors import ModelError
from bondgraph.structure import require_model

from .derivation import ARR, ARRWarning, derive_arrs
from .deltas import latex, mathml
from .elimination import unreached
from .signatures import SignatureMatrix, signature_matrix

__all__ = ["arr_report", "FORMATS"]

FORMATS = ("md", "html", "tex")


@dataclass
class _Content:
    """What every format shows, computed once."""

    title: str
    elements: list  # rows of the element table (strings)
    drawings: list  # (caption, causality, issues)
    arrs: list
    signatures: SignatureMatrix
    notes: list
    unreached: list  # what the structure allows beyond these ARRs, as sentences


def arr_report(bg: BondGraph, format: str = "md", *, arrs: list[ARR] | None = None) -> str:
    """The ARR report of a bond graph as a string in ``format`` (``"md"``, ``"html"`` or ``"tex"``).

    ``arrs`` defaults to :func:`~diagnosis.derivation.derive_arrs` of the model; candidates that cannot be
    expressed in known variables are listed as notes.
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
    content = _Content(bg.name, _element_rows(bg), _drawings(bg), list(arrs), signature_matrix(arrs), notes,
                       _unreached_lines(bg, arrs))
    return {"md": _markdown, "html": _html, "tex": _latex}[format](bg, content)


# ------------------------------------------------------------------------------------------- content

ELEMENT_HEADER = ("element", "kind", "parameter", "nominal", "delta", "interval", "law / modulus", "signal")


def _element_rows(bg: BondGraph) -> list[tuple[str, ...]]:
    rows = []
    for name, e in bg.elements.items():
        nominal = "" if e.value is None else f"{e.value:.6g}"
        delta = interval = ""
        if e.uncertainty is not None:
            lo, hi = e.uncertainty
            delta = f"[{lo:+.3g}, {hi:+.3g}]"
            if e.value is not None:
                a, b = sorted((e.value * (1 + lo), e.value * (1 + hi)))
                interval = f"[{a:.6g}, {b:.6g}]"
        form = ""
        if e.law is not None:
            form = f"{e.law} = 0"
        elif e.modulus is not None and e.modulus != sp.Symbol(e.param or ""):
            form = str(e.modulus)  # a modulus other than the plain parameter (an expression, a signal)
        constants = ", ".join(f"{k} = {v:.6g}" for k, v in e.constants.items())
        if constants:
            form = f"{form} ({constants})" if form else constants
        rows.append((str(name), e.kind, e.param or "", nominal, delta, interval, form, e.signal or ""))
    return rows


def _drawings(bg: BondGraph) -> list:
    out = []
    for preferred, caption in (("integral", "preferred integral causality (simulation)"),
                               ("derivative", "preferred derivative causality, sensors dualized (diagnosis)")):
        causality = _causality(bg, preferred)
        issues = [str(issue) for issue in causality.issues] if causality is not None else ["no causality assigned"]
        out.append((caption, causality, issues))
    return out


def _causality(bg: BondGraph, preferred: str):
    """The assignment the toolkit uses: integral for simulation, derivative with dualized sensors for ARRs."""
    try:
        if preferred == "derivative":
            return diagnosis_causality(bg)
        return bg.assign_causality("integral")
    except ModelError:  # e.g. a law that cannot be inverted for the preferred causality: draw it acausal
        return None


def _arr_details(arr: ARR) -> list[str]:
    """What an ARR is built from and what it asks of the data, as plain sentences."""
    place = f"sensor {arr.detector}" if arr.detector is not None else f"junction {arr.junction}"
    derivatives = ", ".join(f"{s} (order {k})" for s, k in arr.derivatives.items() if k) or "none"
    lines = [f"Residual at {place}, written as: {arr.form}"
             + ("; implicit (non-invertible law)" if arr.implicit else ""),
             f"Signals: {', '.join(arr.signals)}; derivatives: {derivatives}; integrals: "
             + (", ".join(f"of {i}" for i in arr.integrals) or "none")]
    if arr.origin:
        lines.append(f"From the equations: {', '.join(arr.origin)}")
    return lines


def _unreached_lines(bg: BondGraph, arrs: list) -> list[str]:
    if not arrs:
        return []
    left = unreached(bg, arrs)
    lines = [f"Detectable by the structure, seen by no ARR: {fault}" for fault in left["detect"]]
    pairs = [f"{a} from {b}" for a, b in left["isolate"]]
    if pairs:
        lines.append(f"Isolable by the structure, not by these ARRs ({len(pairs)} ordered pairs; higher derivatives, "
                     f"max_order, or an ODE would be needed): {', '.join(pairs)}")
    return lines


def _signature_rows(s: SignatureMatrix) -> tuple[list[str], list[list[str]]]:
    header = ["fault", *map(str, s.columns), "Mb", "Ib"]
    rows = [[str(r), *map(str, s.matrix[i].tolist()), str(s.detectable[i]), str(s.isolable[i])]
            for i, r in enumerate(s.rows)]
    return header, rows


# ------------------------------------------------------------------------------------------- markdown

def _markdown(bg: BondGraph, c: _Content) -> str:
    lines = [f"# ARR report: {_md(c.title)}", "", "## Elements", "", _md_table(ELEMENT_HEADER, c.elements), "",
             "## Bond graph", ""]
    for caption, causality, issues in c.drawings:
        svg = drawing.to_svg(bg, causality)
        data = base64.b64encode(svg.encode("utf-8")).decode("ascii")
        lines += [f"**{caption}**", "", f'<img alt="{html.escape(caption)}" src="data:image/svg+xml;base64,{data}"/>',
                  ""]
        lines += [f"- {_md(i)}" for i in issues] + ([""] if issues else [])
    lines += ["## Analytical redundancy relations", ""]
    if not c.arrs:
        lines += ["The model gives no ARR (it needs De/Df sensors on its junctions).", ""]
    for arr in c.arrs:
        lines += [f"### {_md(arr.name)}", ""] + [f"- {_md(line)}" for line in _arr_details(arr)] + [
                  "", "$$r_n = " + latex(arr.nominal) + "$$", "", "$$\\Psi_2 = " + latex(arr.uncertain) + "$$", ""]
    lines += ["## Fault signatures", ""]
    header, rows = _signature_rows(c.signatures)
    lines += [_md_table(header, rows), ""]
    if c.unreached:
        lines += ["## Beyond these ARRs", ""] + [f"- {_md(n)}" for n in c.unreached] + [""]
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


def _md_table(header, rows) -> str:
    out = ["| " + " | ".join(_md(h) for h in header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(_md(v) for v in row) + " |" for row in rows]
    return "\n".join(out)


# ------------------------------------------------------------------------------------------- html

_CSS = """body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:70em;margin:2em auto;padding:0 1em;
color:#222}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:.25em .6em;text-align:left}
th{background:#f0f0f0}figure{margin:1em 0}figcaption{font-weight:600;margin-bottom:.5em}
math{font-size:1.1em}.arr{margin:1.5em 0}.note{color:#a33}"""


def _html(bg: BondGraph, c: _Content) -> str:
    e = html.escape
    parts = ["<!DOCTYPE html>", "<html lang=\"en\"><head><meta charset=\"utf-8\">",
             f"<title>ARR report: {e(c.title)}</title><style>{_CSS}</style></head><body>",
             f"<h1>ARR report: {e(c.title)}</h1>", "<h2>Elements</h2>", _html_table(ELEMENT_HEADER, c.elements),
             "<h2>Bond graph</h2>"]
    for caption, causality, issues in c.drawings:
        parts.append(f"<figure><figcaption>{e(caption)}</figcaption>{drawing.to_svg(bg, causality)}</figure>")
        parts += [f"<p class=\"note\">{e(i)}</p>" for i in issues]
    parts.append("<h2>Analytical redundancy relations</h2>")
    if not c.arrs:
        parts.append("<p>The model gives no ARR (it needs De/Df sensors on its junctions).</p>")
    for arr in c.arrs:
        parts += [f"<div class=\"arr\"><h3>{e(arr.name)}</h3>"] + [f"<p>{e(line)}</p>" for line in _arr_details(arr)]
        parts += [_math("r_n", arr.nominal), _math("\u03a8_2", arr.uncertain), "</div>"]
    header, rows = _signature_rows(c.signatures)
    parts += ["<h2>Fault signatures</h2>", _html_table(header, rows)]
    if c.unreached:
        parts += ["<h2>Beyond these ARRs</h2><ul>"] + [f"<li>{e(n)}</li>" for n in c.unreached] + ["</ul>"]
    if c.notes:
        parts += ["<h2>Notes</h2><ul>"] + [f"<li>{e(n)}</li>" for n in c.notes] + ["</ul>"]
    parts.append("</body></html>")
    return "\n".join(parts)


def _math(label: str, expression: sp.Expr) -> str:
    body = mathml(expression)
    return (f"<p><math display=\"block\" xmlns=\"http://www.w3.org/1998/Math/MathML\"><mrow><mi>{html.escape(label)}"
            f"</mi><mo>=</mo>{body}</mrow></math></p>")


def _html_table(header, rows) -> str:
    e = html.escape
    head = "".join(f"<th>{e(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{e(str(v))}</td>" for v in row) + "</tr>" for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


# ------------------------------------------------------------------------------------------- latex

def _latex(bg: BondGraph, c: _Content) -> str:
    t = drawing.latex_escape
    parts = [r"\documentclass{article}", r"\usepackage[margin=2cm]{geometry}", r"\usepackage{amsmath}",
             r"\usepackage{tikz}", r"\usepackage{longtable}", r"\begin{document}",
             rf"\section*{{ARR report: {t(c.title)}}}", r"\subsection*{Elements}",
             _tex_table(ELEMENT_HEADER, c.elements),
             r"\subsection*{Bond graph}"]
    for caption, causality, issues in c.drawings:
        parts += [rf"\paragraph{{{t(caption)}}}", "", r"\begin{center}", drawing.to_tikz(bg, causality),
                  r"\end{center}"]
        parts += [t(i) + r"\\" for i in issues]
    parts.append(r"\subsection*{Analytical redundancy relations}")
    for arr in c.arrs:
        details = " ".join(t(line) + "." for line in _arr_details(arr))
        parts += [rf"\paragraph{{{t(arr.name)}}} {details}",
                  r"\begin{align*}", "r_n &= " + latex(arr.nominal) + r" \\",
                  r"\Psi_2 &= " + latex(arr.uncertain), r"\end{align*}"]
    header, rows = _signature_rows(c.signatures)
    parts += [r"\subsection*{Fault signatures}", _tex_table(header, rows)]
    if c.unreached:
        parts += [r"\subsection*{Beyond these ARRs}", r"\begin{itemize}"] + [rf"\item {t(n)}" for n in c.unreached]
        parts.append(r"\end{itemize}")
    if c.notes:
        parts += [r"\subsection*{Notes}", r"\begin{itemize}"] + [rf"\item {t(n)}" for n in c.notes] + [r"\end{itemize}"]
    parts.append(r"\end{document}")
    return "\n".join(parts) + "\n"


def _tex_table(header, rows) -> str:
    spec = "l" * len(header)
    lines = [rf"\begin{{longtable}}{{{spec}}}", " & ".join(drawing.latex_escape(h) for h in header) + r" \\ \hline"]
    lines += [" & ".join(drawing.latex_escape(v) for v in row) + r" \\" for row in rows]
    lines.append(r"\end{longtable}")
    return "\n".join(lines)
