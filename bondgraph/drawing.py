"""Drawings of a bond graph: geometry, standalone SVG and plain TikZ.

Standard bond-graph notation (Karnopp, Margolis and Rosenberg):

* nodes are text labels, ``kind:name`` (``R:R_a``, ``I:J``, ``Se:U``); a
  junction is its ``0`` or ``1`` with the junction name as a subscript; a
  parameter (or signal) other than the node name is shown, ``TF:TF_1 (r1)``,
  or alone for a two-port named after its kind (``GY:k_m``); detectors
  dualized for diagnosis read ``SSe:name`` / ``SSf:name``;
* a power bond is a line with a half-arrow (one barb) at its head, the
  direction of positive power (edge tail -> head);
* a signal bond (to or from a De/Df detector) is a dashed line with a full
  arrow head;
* the causal stroke is a short bar across the bond at the end that *receives*
  the effort (:meth:`bondgraph.causality.Causality.stroke`); the bonds of
  storage elements in derivative causality are drawn in red.

The layout is deterministic and purely combinatorial: the longest chain of
junctions and two-ports (the power path) runs left to right from the first
source; the other elements sit on a grid around the node they are bonded to,
above and below first, and the columns are as wide as their labels.

Example
-------
>>> from bondgraph.library import rlc_circuit
>>> svg = to_svg(rlc_circuit())
>>> svg.startswith("<svg") and svg.count('class="bond"')
5
"""

from __future__ import annotations

import math
import re
from collections import deque
from collections.abc import Hashable
from dataclasses import dataclass
from xml.sax.saxutils import escape, quoteattr

import networkx as nx

from . import elements as el
from .causality import DERIVATIVE, INTEGRAL, Causality, assign_causality, diagnosis_causality
from .errors import ModelError
from .structure import BondGraphLike, Element, require_model

__all__ = ["Drawing", "DrawnBond", "layout", "to_svg", "to_tikz", "display_svg", "display_html", "latex_escape"]

# Geometry, in drawing units (SVG user units; 1 unit = 0.75 pt in TikZ).
FONT = 12.0  # label font size, monospace
SUB_FONT = 9.0  # subscript font size
CHAR = 0.6  # width of a monospace character, in ems
BOX_PAD = 4.0  # label box padding
BOX_HEIGHT = FONT + 2 * BOX_PAD
BOND_MARGIN = 3.0  # gap between a bond end and a label box
GAP_X = 28.0  # horizontal room between label boxes of neighbouring columns
ROW_STEP = 54.0  # distance between grid rows
MARGIN = 16.0
HALF_ARROW = (9.0, 5.0)  # length along the bond, barb offset
ARROW = (9.0, 4.0)  # full (signal) arrow: length, half width
STROKE = 7.0  # half length of a causal stroke
LEGEND_FONT = 11.0
LEGEND_LINE = 15.0

COLOR = "#1f1f1f"
DERIVATIVE_COLOR = "#d62728"
SIGNAL_COLOR = "#555555"


@dataclass(frozen=True)
class DrawnBond:
    """One bond of a :class:`Drawing`.

    Attributes
    ----------
    tail, head : hashable
        The bond's nodes; power flows from ``tail`` to ``head``.
    start, end : (float, float)
        The drawn line, from the border of the tail's label to the border of
        the head's label.
    signal : bool
        Drawn as a signal bond (full arrow): a bond to or from a detector that
        is not dualized.
    dualized : bool
        A detector bond turned into a source bond (SSe/SSf) for diagnosis;
        drawn as a power bond with its causal stroke.
    stroke : hashable or None
        The node receiving effort, at whose end the causal stroke sits; None
        when the bond has no causality (acausal drawing, conflict, signal).
    derivative : bool
        The bond of a storage element in derivative causality.
    label : hashable or None
        The bond label of the model (power bonds are numbered).
    """

    tail: Hashable
    head: Hashable
    start: tuple[float, float]
    end: tuple[float, float]
    signal: bool = False
    dualized: bool = False
    stroke: Hashable | None = None
    derivative: bool = False
    label: Hashable | None = None

    @property
    def stroke_point(self) -> tuple[float, float] | None:
        """The centre of the causal stroke, or None."""
        if self.stroke is None:
            return None
        return self.start if self.stroke == self.tail else self.end


@dataclass(frozen=True)
class Drawing:
    """The geometry of a bond graph drawing, in drawing units (y points down).

    Attributes
    ----------
    positions : dict
        Node name -> ``(x, y)``, the centre of its label.
    labels : dict
        Node name -> label text (``"R:R_a"``, ``"1"``, ``"SSf:i"``).
    subscripts : dict
        Node name -> subscript drawn after the label: the junction name (less
        its ``0_``/``1_`` prefix); ``""`` for none.
    sizes : dict
        Node name -> ``(width, height)`` of its label box.
    bonds : tuple of DrawnBond
        In the model's bond order (power bonds, then signal bonds).
    width, height : float
        The extent of the nodes and bonds (the legend is not included).
    causality : str or None
        ``"integral"`` or ``"derivative"`` (the preferred causality), or None
        for an acausal drawing.
    title : str
        The model name.
    notes : tuple of str
        Legend lines: the causality and any bond left without causality.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> drawing = layout(dc_motor(), "integral")
    >>> drawing.labels["GY"], drawing.labels["1_e"], drawing.subscripts["1_e"]
    ('GY:k_m', '1', 'e')
    >>> sum(bond.stroke is not None for bond in drawing.bonds)
    7
    """

    positions: dict
    labels: dict
    subscripts: dict
    sizes: dict
    bonds: tuple
    width: float
    height: float
    causality: str | None = None
    title: str = ""
    notes: tuple = ()


# -- geometry ---------------------------------------------------------------------------


def layout(bg: BondGraphLike, causality: str | Causality | None = None) -> Drawing:
    """Compute the drawing of ``bg``: label positions, bond lines, causal strokes.

    Parameters
    ----------
    bg : BondGraph
    causality : None, "integral", "derivative" or Causality
        None draws the acausal bond graph (no strokes).  ``"integral"``
        assigns integral causality.  ``"derivative"`` assigns derivative
        causality with the detectors dualized as the diagnosis does (as many
        as causality allows, like :func:`diagnosis.derivation.derive_arrs`).
        A :class:`~bondgraph.causality.Causality` is drawn as given; bonds it
        could not assign (conflicts) get no stroke.

    Returns
    -------
    Drawing

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> drawing = layout(rlc_circuit(), "integral")
    >>> bond = next(b for b in drawing.bonds if (b.tail, b.head) == ("J0", "C"))
    >>> bond.stroke  # integral C imposes effort on its 0-junction
    'J0'
    >>> x_j0, x_c = drawing.positions["J0"][0], drawing.positions["C"][0]
    >>> x_j0 == x_c  # C hangs under (or over) its 0-junction
    True
    """
    require_model(bg, "layout")
    structure = bg.structure()
    if not structure.elements:
        raise ModelError(f"{bg.name!r}: an empty bond graph has nothing to draw; add elements first")
    causal = _resolve_causality(bg, causality)
    elements = structure.elements
    order = {name: i for i, name in enumerate(elements)}
    graph = nx.Graph()
    graph.add_nodes_from(elements)
    graph.add_edges_from(bond.key for bond in structure.bonds)

    labels, subscripts, sizes = {}, {}, {}
    for name, element in elements.items():
        labels[name], subscripts[name] = _label(name, element, causal)
        sizes[name] = _box(labels[name], subscripts[name])
    grid = _grid(graph, elements, order)
    positions, width, height = _place(grid, sizes)

    bonds = []
    for bond in structure.bonds:
        start, end = _clip(positions[bond.tail], positions[bond.head], sizes[bond.tail], sizes[bond.head])
        dualized = (causal is not None and bond.is_signal
                    and (bond.head in causal.dualized or bond.tail in causal.dualized))
        stroke = None
        if causal is not None and bond.key in causal.effort_from:
            stroke = causal.stroke(bond.key)
        derivative = causal is not None and any(causal.storage.get(n) == DERIVATIVE for n in bond.key)
        bonds.append(DrawnBond(bond.tail, bond.head, start, end, bond.is_signal and not dualized, dualized,
                               stroke, derivative, bond.label))
    preferred = causal.preferred if causal is not None else None
    return Drawing(positions, labels, subscripts, sizes, tuple(bonds), width, height, preferred,
                   str(bg.name), _notes(causal, bonds))


def _resolve_causality(bg: BondGraphLike, causality) -> Causality | None:
    if causality is None or isinstance(causality, Causality):
        return causality
    if causality == INTEGRAL:
        return assign_causality(bg, INTEGRAL)
    if causality == DERIVATIVE:
        return diagnosis_causality(bg)
    raise ValueError(f"causality must be None, 'integral', 'derivative' or a Causality, got {causality!r}")


def _notes(causal: Causality | None, bonds: list[DrawnBond]) -> tuple[str, ...]:
    if causal is None:
        return ("acausal drawing: no causal strokes",)
    notes = [f"{causal.preferred} causality preferred; stroke at the end receiving effort; "
             f"red: storage in derivative causality"]
    if causal.dualized:
        notes.append("SSe/SSf: detectors dualized into signal sources")
    missing = sum(1 for b in bonds if b.stroke is None and not b.signal)
    if missing or causal.conflicts:
        notes.append(f"{len(causal.conflicts)} causal conflict(s); {missing} bond(s) left without causality")
    return tuple(notes)


def _label(name: Hashable, element: Element, causal: Causality | None) -> tuple[str, str]:
    """Main label and subscript of a node."""
    kind = element.kind
    text = str(name)
    if kind in el.JUNCTIONS:
        prefix = kind + "_"
        if text == kind:
            return kind, ""
        if text.startswith(prefix) and len(text) > len(prefix):
            return kind, text[len(prefix):]
        return kind, text
    if causal is not None and name in causal.dualized:
        kind = causal.dualized[name]
    extra = element.param if element.param is not None else element.signal
    if extra is None or extra == text:
        return f"{kind}:{text}", ""
    if text == element.kind:  # a two-port named after its kind: show its parameter
        return f"{kind}:{extra}", ""
    return f"{kind}:{text} ({extra})", ""


def _box(label: str, subscript: str) -> tuple[float, float]:
    width = CHAR * (FONT * len(label) + SUB_FONT * len(subscript)) + 2 * BOX_PAD
    return (round(width, 2), BOX_HEIGHT)


def _grid(graph: nx.Graph, elements: dict, order: dict) -> dict:
    """Integer grid cells of the nodes, component by component, stacked downwards."""
    cells: dict = {}
    top = 0
    components = sorted((sorted(c, key=order.__getitem__) for c in nx.connected_components(graph)),
                        key=lambda c: order[c[0]])
    for nodes in components:
        local = _component_grid(graph.subgraph(nodes), nodes, elements, order)
        low = min(y for _, y in local.values())
        high = max(y for _, y in local.values())
        for node, (x, y) in local.items():
            cells[node] = (x, y - low + top)
        top += high - low + 2
    return cells


def _component_grid(graph: nx.Graph, nodes: list, elements: dict, order: dict) -> dict:
    """The spine (power path) on row 0, every other node on a free cell near its neighbour."""
    key = order.__getitem__
    degree = dict(graph.degree())
    core = [n for n in nodes if degree[n] >= 2]
    spine = _longest_path(graph.subgraph(core) if core else graph, core or nodes, key)
    sources = [n for n in nodes if elements[n].kind in el.SOURCES]
    if sources and len(spine) > 1:
        distance = nx.single_source_shortest_path_length(graph, sources[0])
        if distance[spine[-1]] < distance[spine[0]]:
            spine.reverse()
    if core:  # a source bonded to an end of the power path starts (or ends) it
        for end, attach in ((spine[0], lambda n: spine.insert(0, n)), (spine[-1], spine.append)):
            leaf = next((n for n in sorted(graph[end], key=key)
                         if degree[n] == 1 and n in sources and n not in spine), None)
            if leaf is not None:
                attach(leaf)

    cells = {node: (2 * i, 0) for i, node in enumerate(spine)}
    taken = set(cells.values()) | {(2 * i + 1, 0) for i in range(len(spine) - 1)}
    outward = {node: (0, 0) for node in spine}
    queue = deque(spine)
    while queue:
        node = queue.popleft()
        children = [n for n in sorted(graph[node], key=key) if n not in cells]
        children.sort(key=lambda n: degree[n] < 2)  # branches first: they need room
        for child in children:
            step = 2 if degree[child] >= 2 else 1
            cell, crossed = _free_cell(cells[node], outward[node], step, taken)
            cells[child] = cell
            taken.add(cell)
            taken.update(crossed)
            dx, dy = cell[0] - cells[node][0], cell[1] - cells[node][1]
            outward[child] = ((dx > 0) - (dx < 0), (dy > 0) - (dy < 0))
            queue.append(child)
    return cells


def _longest_path(graph: nx.Graph, nodes: list, key) -> list:
    """A longest shortest path (by two breadth-first searches), deterministic."""

    def farthest(start):
        parent, last, frontier = {start: None}, start, deque([start])
        while frontier:
            node = frontier.popleft()
            last = node
            for n in sorted(graph[node], key=key):
                if n not in parent:
                    parent[n] = node
                    frontier.append(n)
        return last, parent

    end, _ = farthest(nodes[0])
    other, parent = farthest(end)
    path = [other]
    while parent[path[-1]] is not None:
        path.append(parent[path[-1]])
    return path[::-1]


def _free_cell(origin: tuple, outward: tuple, step: int, taken: set) -> tuple[tuple, list]:
    """The preferred free cell around ``origin`` (and the lattice points the bond crosses)."""
    ox, oy = outward

    def preference(offset):
        dx, dy = offset
        if outward == (0, 0):  # on the power path: above, below, then diagonals; along it last
            return (dy == 0, abs(dx), dy > 0, dx)
        cosine = (dx * ox + dy * oy) / (math.hypot(dx, dy) * math.hypot(ox, oy))
        return (-round(cosine, 6), dy > 0, dx)

    for ring in range(1, 1000):
        offsets = [(dx, dy) for dx in range(-ring, ring + 1) for dy in range(-ring, ring + 1)
                   if max(abs(dx), abs(dy)) == ring]
        for dx, dy in sorted(offsets, key=preference):
            vx, vy = step * dx, step * dy
            cell = (origin[0] + vx, origin[1] + vy)
            g = math.gcd(vx, vy)
            crossed = [(origin[0] + k * vx // g, origin[1] + k * vy // g) for k in range(1, g)]
            if cell not in taken and not any(c in taken for c in crossed):
                return cell, crossed
    raise RuntimeError("no free cell")  # pragma: no cover - the grid is unbounded in practice


def _place(cells: dict, sizes: dict) -> tuple[dict, float, float]:
    """Grid cells -> drawing units: each column as wide as its widest label."""
    xs = [x for x, _ in cells.values()]
    ys = [y for _, y in cells.values()]
    columns = range(min(xs), max(xs) + 1)
    widths = {c: 0.0 for c in columns}
    for node, (x, _) in cells.items():
        widths[x] = max(widths[x], sizes[node][0])
    centre = {}
    position = MARGIN + widths[columns[0]] / 2
    for c in columns:
        if c != columns[0]:
            position += max(GAP_X, (widths[c - 1] + widths[c]) / 2 + GAP_X)
        centre[c] = position
    low = min(ys)
    positions = {node: (round(centre[x], 2), round(MARGIN + BOX_HEIGHT / 2 + (y - low) * ROW_STEP, 2))
                 for node, (x, y) in cells.items()}
    width = centre[columns[-1]] + widths[columns[-1]] / 2 + MARGIN
    height = MARGIN * 2 + BOX_HEIGHT + (max(ys) - low) * ROW_STEP
    return positions, round(width, 2), round(height, 2)


def _clip(a: tuple, b: tuple, size_a: tuple, size_b: tuple) -> tuple[tuple, tuple]:
    """The segment a -> b shortened to start and end outside both label boxes."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length = math.hypot(dx, dy)
    if length == 0:
        return a, b
    ux, uy = dx / length, dy / length

    def reach(size):
        half_w, half_h = size[0] / 2 + BOND_MARGIN, size[1] / 2 + BOND_MARGIN
        return min(half_w / abs(ux) if ux else math.inf, half_h / abs(uy) if uy else math.inf)

    ta, tb = reach(size_a), reach(size_b)
    if ta + tb > length - 8:  # overlapping boxes: keep a short visible segment in the middle
        ta = tb = max(0.0, (length - 8) / 2)
    start = (round(a[0] + ux * ta, 2), round(a[1] + uy * ta, 2))
    end = (round(b[0] - ux * tb, 2), round(b[1] - uy * tb, 2))
    return start, end


def _frame(bond: DrawnBond) -> tuple[float, float, float, float]:
    """Unit vector along the bond (tail -> head) and its normal (the half-arrow side)."""
    dx, dy = bond.end[0] - bond.start[0], bond.end[1] - bond.start[1]
    length = math.hypot(dx, dy) or 1.0
    ux, uy = dx / length, dy / length
    return ux, uy, uy, -ux  # normal: left of the direction, i.e. above a left-to-right bond


def _decorations(bond: DrawnBond) -> dict:
    """Half-arrow or arrow head and causal stroke, as point lists."""
    ux, uy, nx_, ny = _frame(bond)
    ex, ey = bond.end
    shapes = {}
    if bond.signal:
        length, half = ARROW
        bx, by = ex - ux * length, ey - uy * length
        shapes["arrow"] = [(ex, ey), (bx + nx_ * half, by + ny * half), (bx - nx_ * half, by - ny * half)]
    else:
        length, offset = HALF_ARROW
        shapes["half-arrow"] = [(ex, ey), (ex - ux * length + nx_ * offset, ey - uy * length + ny * offset)]
    point = bond.stroke_point
    if point is not None:
        px, py = point
        shapes["stroke"] = [(px + nx_ * STROKE, py + ny * STROKE), (px - nx_ * STROKE, py - ny * STROKE)]
    return {k: [(round(x, 2), round(y, 2)) for x, y in v] for k, v in shapes.items()}


# -- SVG ----------------------------------------------------------------------------------

_XML_ILLEGAL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def _xml_text(value: object) -> str:
    """Text content safe for XML: illegal characters replaced, ``& < >`` escaped."""
    return escape(_XML_ILLEGAL.sub("\ufffd", str(value)))


def _xml_attr(value: object) -> str:
    """A quoted XML attribute value (quotes included)."""
    return quoteattr(_XML_ILLEGAL.sub("\ufffd", str(value)), {"\n": "&#10;", "\r": "&#13;", "\t": "&#9;"})


def _num(value: float) -> str:
    text = f"{value:.2f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def to_svg(bg: BondGraphLike, causality: str | Causality | None = "integral", *, scale: float = 1.0) -> str:
    """A standalone SVG drawing of ``bg`` (no scripts, no external references).

    Parameters
    ----------
    bg : BondGraph
    causality : None, "integral", "derivative" or Causality
        As for :func:`layout`.
    scale : float
        Display size factor (``width``/``height`` attributes; the viewBox is
        in drawing units).

    Returns
    -------
    str
        An ``<svg xmlns="http://www.w3.org/2000/svg" ...>`` document.  Bond
        lines have ``class="bond"`` (power), ``"signal"`` (to a detector),
        with ``derivative`` or ``dualized`` added; their decorations are
        ``"half-arrow"``, ``"arrow"`` and ``"stroke"``; each bond's shapes sit
        in a ``<g class="bond-group" data-tail=... data-head=...>``; labels are
        ``<text class="node ...">`` with ``data-node``.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> svg = to_svg(dc_motor(), "derivative", scale=1.5)
    >>> svg.count('class="stroke derivative"'), "SSf:omega" in svg
    (2, True)
    """
    if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be a positive number, got {scale!r}")
    drawing = layout(bg, causality)
    legend = [f"{drawing.title}: bond graph"] + list(drawing.notes)
    width = max(drawing.width, 2 * MARGIN + max(len(line) for line in legend) * CHAR * LEGEND_FONT)
    height = drawing.height + len(legend) * LEGEND_LINE + MARGIN / 2
    width, height = round(width, 2), round(height, 2)
    caption = f"{drawing.title}: bond graph, " + (f"{drawing.causality} causality" if drawing.causality else "acausal")

    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{_num(width * scale)}" height="{_num(height * scale)}" '
        f'viewBox="0 0 {_num(width)} {_num(height)}" class="bondgraph" role="img" font-family="monospace">',
        f"<title>{_xml_text(caption)}</title>",
        f'<rect class="background" x="0" y="0" width="{_num(width)}" height="{_num(height)}" fill="#ffffff"/>',
        '<g class="bonds" fill="none" stroke-linecap="round" stroke-width="1.4">',
    ]
    for bond in drawing.bonds:
        color = DERIVATIVE_COLOR if bond.derivative else (SIGNAL_COLOR if bond.signal else COLOR)
        extra = " derivative" if bond.derivative else (" dualized" if bond.dualized else "")
        label = f" data-label={_xml_attr(bond.label)}" if bond.label is not None else ""
        out.append(f'<g class="bond-group" data-tail={_xml_attr(bond.tail)} data-head={_xml_attr(bond.head)}{label}>')
        (x1, y1), (x2, y2) = bond.start, bond.end
        line_class = "signal" if bond.signal else "bond"
        dash = ' stroke-dasharray="5 3"' if bond.signal else ""
        out.append(f'<line class="{line_class}{extra}" x1="{_num(x1)}" y1="{_num(y1)}" x2="{_num(x2)}" '
                   f'y2="{_num(y2)}" stroke="{color}"{dash}/>')
        shapes = _decorations(bond)
        if "arrow" in shapes:
            points = " ".join(f"{_num(x)},{_num(y)}" for x, y in shapes["arrow"])
            out.append(f'<polygon class="arrow" points="{points}" fill="{color}" stroke="none"/>')
        for name in ("half-arrow", "stroke"):
            if name in shapes:
                (a, b), (c, d) = shapes[name]
                width_attr = ' stroke-width="2"' if name == "stroke" else ""
                out.append(f'<line class="{name}{extra}" x1="{_num(a)}" y1="{_num(b)}" x2="{_num(c)}" '
                           f'y2="{_num(d)}" stroke="{color}"{width_attr}/>')
        out.append("</g>")
    out.append("</g>")
    out.append(f'<g class="nodes" text-anchor="middle" font-size="{_num(FONT)}" fill="#000000">')
    for node, (x, y) in drawing.positions.items():
        kind = "junction" if drawing.labels[node] in el.JUNCTIONS else "element"
        sub = drawing.subscripts[node]
        tspan = f'<tspan font-size="{_num(SUB_FONT)}" dy="4">{_xml_text(sub)}</tspan>' if sub else ""
        out.append(f'<text class="node {kind}" data-node={_xml_attr(node)} x="{_num(x)}" '
                   f'y="{_num(y + 0.35 * FONT)}">{_xml_text(drawing.labels[node])}{tspan}</text>')
    out.append("</g>")
    out.append(f'<g class="legend" font-size="{_num(LEGEND_FONT)}" fill="#444444">')
    for i, line in enumerate(legend):
        y = drawing.height + (i + 0.7) * LEGEND_LINE
        out.append(f'<text class="legend" x="{_num(MARGIN)}" y="{_num(y)}">{_xml_text(line)}</text>')
    out.append("</g>")
    out.append("</svg>")
    return "\n".join(out)


def display_svg(bg: BondGraphLike) -> str:
    """The SVG drawing Jupyter shows for a bond graph (``BondGraph._repr_svg_``).

    Integral causality when it can be assigned, else the acausal drawing: a display never fails
    on causality.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> svg = display_svg(rlc_circuit())
    >>> svg.startswith("<svg"), "integral causality" in svg
    (True, True)
    """
    return to_svg(bg, _display_causality(bg))


def display_html(bg: BondGraphLike) -> str:
    """The HTML snippet Jupyter shows for a bond graph (``BondGraph._repr_html_``): :func:`display_svg` inline.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> display_html(rlc_circuit()).startswith('<div class="bondgraph-drawing"')
    True
    """
    return f'<div class="bondgraph-drawing" style="max-width:100%;overflow-x:auto">{display_svg(bg)}</div>'


def _display_causality(bg: BondGraphLike) -> Causality | None:
    """Integral causality for display, or None (acausal) if it cannot be assigned."""
    try:
        return assign_causality(bg, INTEGRAL)
    except Exception:  # a drawing should never fail on causality: draw the acausal graph
        return None


# -- TikZ ---------------------------------------------------------------------------------

_LATEX = {
    "\\": r"\textbackslash{}", "{": r"\{", "}": r"\}", "$": r"\$", "&": r"\&", "#": r"\#",
    "^": r"\textasciicircum{}", "_": r"\_", "%": r"\%", "~": r"\textasciitilde{}",
    "<": r"\textless{}", ">": r"\textgreater{}", "|": r"\textbar{}",
}


def latex_escape(value: object) -> str:
    r"""Text safe inside a LaTeX group: special characters escaped, control characters dropped.

    >>> print(latex_escape("a_b$c"))
    a\_b\$c
    """
    text = re.sub(r"[\x00-\x1f\x7f]", " ", str(value))
    return "".join(_LATEX.get(ch, ch) for ch in text)


def to_tikz(bg: BondGraphLike, causality: str | Causality | None = "integral") -> str:
    r"""A ``tikzpicture`` of ``bg`` (plain TikZ: ``\usepackage{tikz}`` is enough).

    Coordinates are the drawing units of :func:`layout` (``x=0.75pt``,
    ``y=-0.75pt``, so 1 unit = 1 px); every bond is a ``\draw`` with explicit
    half-arrow (or filled arrow head) and causal stroke; storage bonds in
    derivative causality are red.

    Parameters
    ----------
    bg : BondGraph
    causality : None, "integral", "derivative" or Causality
        As for :func:`layout`.

    Returns
    -------
    str

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> tikz = to_tikz(rlc_circuit())
    >>> tikz.startswith(r"\begin{tikzpicture}"), r"{I:L}" in tikz, tikz.endswith(r"\end{tikzpicture}")
    (True, True, True)
    """
    drawing = layout(bg, causality)

    def point(p):
        return f"({_num(p[0])},{_num(p[1])})"

    caption = f"{drawing.title}: bond graph, " + (f"{drawing.causality} causality" if drawing.causality else "acausal")
    out = [r"\begin{tikzpicture}[x=0.75pt, y=-0.75pt, font=\ttfamily\small]", f"% {latex_escape(caption)}"]
    for bond in drawing.bonds:
        color = "red" if bond.derivative else ("gray" if bond.signal else "black")
        style = f"draw={color}, line width=0.6pt" + (", dashed" if bond.signal else "")
        what = "signal" if bond.signal else f"bond {latex_escape(bond.label)}"
        out.append(f"% {what}: {latex_escape(bond.tail)} -> {latex_escape(bond.head)}")
        out.append(rf"\draw[{style}] {point(bond.start)} -- {point(bond.end)};")
        shapes = _decorations(bond)
        if "arrow" in shapes:
            out.append(rf"\fill[{color}] " + " -- ".join(point(p) for p in shapes["arrow"]) + " -- cycle;")
        if "half-arrow" in shapes:
            out.append(rf"\draw[draw={color}, line width=0.6pt] " + " -- ".join(map(point, shapes["half-arrow"])) + ";")
        if "stroke" in shapes:
            out.append(rf"\draw[draw={color}, line width=0.9pt] " + " -- ".join(map(point, shapes["stroke"])) + ";")
    for node, (x, y) in drawing.positions.items():
        sub = drawing.subscripts[node]
        text = latex_escape(drawing.labels[node]) + (rf"\textsubscript{{{latex_escape(sub)}}}" if sub else "")
        out.append(rf"\node[inner sep=0pt] at {point((x, y))} {{{text}}};")
    for i, line in enumerate([f"{drawing.title}: bond graph", *drawing.notes]):
        y = drawing.height + (i + 0.5) * LEGEND_LINE
        out.append(rf"\node[anchor=west, inner sep=0pt, font=\ttfamily\scriptsize] at {point((MARGIN, y))} "
                   f"{{{latex_escape(line)}}};")
    out.append(r"\end{tikzpicture}")
    return "\n".join(out)
