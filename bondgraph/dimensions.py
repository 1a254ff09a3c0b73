"""The dimensional check of a bond graph: the units of every bond, parameter and signal.

``unit`` on an element is the unit of its own quantity: the parameter of C, I, R, TF, GY (and MTF, MGY),
the value or signal of a source, the signal of a detector; ``units`` maps its other names: the law
constants of ``params`` and the signal of a modulated two-port (units are written as in
:mod:`bondgraph.units`).  :func:`check_units` solves for the effort and flow of every bond (a junction's
bonds share them; ``e = R f``, ``f = p/I``, ``e = q/C``, the two-ports' ``e1 = m e2, f2 = m f1`` and
``e1 = m f2, e2 = m f1``; a law's terms all of one unit) and raises a
:class:`~bondgraph.errors.ModelError` naming the element whose unit does not fit.  A model that declares
no unit is not checked; one that declares some gets the others found where the bonds tell them.

:meth:`bondgraph.model.BondGraph.structure` runs the check, so a model is checked whenever it is used
(causality, equations, ARRs, simulation); :attr:`bondgraph.model.BondGraph.units` gives the result.

Examples
--------
>>> from bondgraph import BondGraph
>>> bg = BondGraph(name="heater")
>>> _ = bg.add("P", "Sf", unit="W"), bg.add("0_h", "0"), bg.add("C_h", "C", value=500.0, unit="J/K")
>>> _ = bg.add("R_h", "R", value=2.0, unit="K/W"), bg.add("T_h", "De", unit="K")
>>> for tail, head in [("P", "0_h"), ("0_h", "C_h"), ("0_h", "R_h"), ("0_h", "T_h")]:
...     _ = bg.bond(tail, head)
>>> bg.units.text("T_h")
'K'
>>> bg.graph.nodes["R_h"]["unit"] = "W/K"
>>> bg.validate()  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
bondgraph.errors.ModelError: R 'R_h': unit 'W/K' does not fit its bonds: the effort of ... is K (from De 'T_h'); ...
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping
from dataclasses import dataclass, field

import sympy as sp

from . import elements as el
from .errors import ModelError
from .structure import PORT_SYMBOLS, Bond, Element, signal_function
from .units import DIMENSIONLESS, SECOND, Unit, UnitError, dimension_of

__all__ = ["ModelUnits", "check_units"]


@dataclass(frozen=True)
class ModelUnits:
    """The units of a model: declared, or found from the bonds where a parameter or signal declares none.

    ``parameters`` and ``signals`` map names to their :class:`Unit` (absent when neither declared nor
    found); ``efforts`` and ``flows`` map each bond's key ``(tail, head)`` to its unit.  ``declared`` tells
    whether the model declared any unit (if not, everything is empty and nothing was checked).

    >>> from bondgraph.library import dc_motor
    >>> units = dc_motor().units
    >>> units.text("b"), units.text("omega"), units.text("k_m")
    ('N*m*s/rad', 'rad/s', 'N*m/A')
    """

    parameters: dict = field(default_factory=dict)
    signals: dict = field(default_factory=dict)
    efforts: dict = field(default_factory=dict)
    flows: dict = field(default_factory=dict)
    declared: bool = False

    def symbols(self) -> dict[sp.Basic, Unit]:
        """The units by sympy name, for :func:`~bondgraph.units.dimension_of`: each parameter's symbol and each
        signal's function ``name(t)``."""
        found: dict[sp.Basic, Unit] = {sp.Symbol(p): u for p, u in self.parameters.items()}
        found.update({signal_function(s): u for s, u in self.signals.items()})
        return found

    def text(self, name: str, default: str = "") -> str:
        """The unit of a parameter or signal as text, ``default`` when unknown."""
        unit = self.parameters.get(name, self.signals.get(name))
        return default if unit is None else str(unit)


class _Solver:
    """Efforts and flows of the bonds as unknown units tied by ratios: a union-find in which each unknown is
    its root's unit times an offset (``x = root * offset``).  The unknown ``ONE`` stands for the pure number:
    a component holding it has known units."""

    ONE = ("1",)

    def __init__(self):
        self.parent: dict = {self.ONE: self.ONE}
        self.offset: dict = {self.ONE: DIMENSIONLESS}   # x = parent(x) * offset(x)
        self.ties: dict = {}                            # x -> [(y, who)]: who tied x and y, to tell a conflict's origin

    def find(self, x) -> tuple[object, Unit]:
        """``x``'s root and ``x / root``."""
        if x not in self.parent:
            self.parent[x], self.offset[x] = x, DIMENSIONLESS
        path, root = [], x
        while self.parent[root] != root:
            path.append(root)
            root = self.parent[root]
        for node in reversed(path):  # from the root down: each node then points at the root with its whole offset
            parent = self.parent[node]
            if parent != root:
                self.offset[node] = self.offset[node] * self.offset[parent]
            self.parent[node] = root
        return root, (self.offset[x] if x != root else DIMENSIONLESS)

    def known(self, x) -> Unit | None:
        """The unit of ``x`` if its component holds ``ONE``."""
        root, unit = self.find(x)
        return unit if root == self.ONE else None

    def tie(self, x, y, ratio: Unit, who: str) -> bool:
        """Require ``x = y * ratio`` (``who`` requires it); False if that contradicts what is tied already."""
        rx, ox = self.find(x)
        ry, oy = self.find(y)
        if rx == ry:
            return ox.same_dimension(oy * ratio)
        self.ties.setdefault(x, []).append((y, who))
        self.ties.setdefault(y, []).append((x, who))
        if rx == self.ONE:  # keep ONE a root: ry = x / (oy ratio) = ox / (oy ratio)
            self.parent[ry], self.offset[ry] = rx, ox / (oy * ratio)
        else:               # rx = y ratio / ox = ry (oy ratio / ox)
            self.parent[rx], self.offset[rx] = ry, oy * ratio / ox
        return True

    def origin(self, x) -> list[str]:
        """The elements through which ``x`` got its unit, nearest last: the shortest chain of ties from ``x`` to
        ONE, its junctions left out (they only pass units on); empty if ``x`` has no unit."""
        came_from = {x: None}
        frontier = [x]
        while frontier and self.ONE not in came_from:
            following = []
            for node in frontier:
                for other, who in self.ties.get(node, ()):
                    if other not in came_from:
                        came_from[other] = (node, who)
                        following.append(other)
            frontier = following
        chain, node = [], self.ONE
        while came_from.get(node) is not None:
            node, who = came_from[node]
            if not who.startswith(("0 ", "1 ")) and who not in chain:
                chain.append(who)
        return chain


def check_units(elements: Mapping[Hashable, Element], bonds: Iterable[Bond]) -> ModelUnits:
    """Check a model's units and find those of every bond, parameter and signal.

    Reads each element's ``unit`` and ``units`` (see the module's notes).  Raises
    :class:`~bondgraph.errors.ModelError` naming the element whose unit does not fit.  With no unit
    declared, returns an empty :class:`ModelUnits`.
    """
    if not any(e.unit is not None or e.units for e in elements.values()):
        return ModelUnits()
    bonds = list(bonds)
    solver = _Solver()
    at: dict = {name: [] for name in elements}
    for bond in bonds:
        at[bond.tail].append(bond)
        at[bond.head].append(bond)
    for name, element in elements.items():  # a junction's bonds share their effort and their flow
        if element.kind in el.JUNCTIONS:
            for bond in at[name][1:]:
                for side in ("e", "f"):
                    solver.tie((side, at[name][0].key), (side, bond.key), DIMENSIONLESS, str(element))
    for name in sorted(elements, key=lambda n: _RANK.get(elements[n].kind, 9)):  # the surest units first
        element = elements[name]
        for x, y, ratio in _ties(element, at[name]):
            if not solver.tie(x, y, ratio, str(element)):
                raise ModelError(_conflict(element, x, y, solver))
    efforts = {b.key: solver.known(("e", b.key)) for b in bonds}
    flows = {b.key: solver.known(("f", b.key)) for b in bonds}
    for name, element in elements.items():
        _check_law(element, at[name], efforts, flows)
    parameters, signals = _named_units(elements, at, efforts, flows)
    return ModelUnits(parameters, signals, efforts, flows, declared=True)


#: The order in which elements tie units: sources and sensors (the units a user is surest of) first, then the
#: two-ports (so that a shaft's effort reads N*m from a motor constant, not kg*m^2*rad/s^2 from an inertia).
_RANK = {"Se": 0, "Sf": 0, "MSe": 0, "MSf": 0, "De": 1, "Df": 1, "TF": 2, "GY": 2, "MTF": 2, "MGY": 2, "R": 3, "C": 4,
         "I": 4}


def _ties(element: Element, bonds: list[Bond]) -> list[tuple]:
    """The element's requirements ``x = y * ratio`` between bond unknowns (``ONE`` for a known unit)."""
    one, own, kind = _Solver.ONE, element.unit, element.kind
    if kind in el.EFFORT_SOURCES | {"De"} and own is not None:
        return [(("e", bonds[0].key), one, own)]
    if kind in el.FLOW_SOURCES | {"Df"} and own is not None:
        return [(("f", bonds[0].key), one, own)]
    if kind in el.STORAGE | {"R"} and own is not None and element.law is None:
        bond = bonds[0].key
        if kind == "R":     # e = R f
            return [(("e", bond), ("f", bond), own)]
        if kind == "I":     # f = p / I with p = e s
            return [(("e", bond), ("f", bond), own / SECOND)]
        return [(("f", bond), ("e", bond), own / SECOND)]  # C: e = q / C with q = f s
    if kind in el.TWO_PORTS:
        modulus = _modulus_unit(element)
        if modulus is None:
            return []
        into, out = (bonds[0], bonds[1]) if bonds[0].head == element.name else (bonds[1], bonds[0])
        if kind in el.TRANSFORMERS:  # e1 = m e2, f2 = m f1
            return [(("e", into.key), ("e", out.key), modulus), (("f", out.key), ("f", into.key), modulus)]
        return [(("e", into.key), ("f", out.key), modulus), (("e", out.key), ("f", into.key), modulus)]  # GY
    return []


def _modulus_unit(element: Element) -> Unit | None:
    """A two-port's modulus unit: its parameter's, or its modulus expression's; None if a name has none."""
    if element.modulus is None:
        return element.unit
    try:
        return dimension_of(element.modulus, _name_units(element))
    except KeyError:
        return None  # a name without a unit: this two-port ties nothing
    except UnitError as exc:
        raise ModelError(f"{element}: modulus {element.modulus}: {exc}") from None


def _name_units(element: Element) -> dict[sp.Basic, Unit]:
    """The element's symbols (parameter, constants) and signal function with a declared unit."""
    found: dict[sp.Basic, Unit] = {sp.Symbol(n): u for n, u in element.units.items()}
    if element.signal is not None and element.signal in element.units:
        found[sp.Function(element.signal)(sp.Symbol("t"))] = element.units[element.signal]
    if element.unit is not None and element.param is not None:
        found[sp.Symbol(element.param)] = element.unit
    return found


def _check_law(element: Element, bonds: list[Bond], efforts: Mapping, flows: Mapping) -> None:
    """A law's terms must all have one unit (when its bond's and every name's unit is known)."""
    if element.law is None:
        return
    effort, flow = efforts[bonds[0].key], flows[bonds[0].key]
    if effort is None or flow is None:
        return
    ports = {PORT_SYMBOLS["e"]: effort, PORT_SYMBOLS["f"]: flow, PORT_SYMBOLS["q"]: flow * SECOND,
             PORT_SYMBOLS["p"]: effort * SECOND}
    try:
        dimension_of(element.law, {**ports, **_name_units(element)})
    except KeyError:
        return
    except UnitError as exc:
        raise ModelError(f"{element}: law {element.law} = 0 does not hold in units: {exc} (its bond's effort is "
                         f"{effort}, its flow {flow})") from None


def _named_units(elements, at, efforts, flows) -> tuple[dict, dict]:
    """Each parameter's and signal's unit: declared, else found from its bond."""
    parameters: dict = {}
    signals: dict = {}
    for name, element in elements.items():
        for constant in element.constants:
            if constant in element.units:
                parameters.setdefault(constant, element.units[constant])
        if element.kind in el.SOURCES | el.DETECTORS:
            bond = at[name][0].key
            found = efforts[bond] if element.kind in el.EFFORT_SOURCES | {"De"} else flows[bond]
            unit = element.unit if element.unit is not None else found
            if unit is not None:
                signals.setdefault(element.signal, unit)
            continue
        if element.kind in el.MODULATED_TWO_PORTS and element.signal in element.units:
            signals.setdefault(element.signal, element.units[element.signal])
        if element.param is None or element.value is None:  # a modulus without its parameter has none
            continue
        unit = element.unit if element.unit is not None else _found(element, at[name], efforts, flows)
        if unit is not None:
            parameters.setdefault(element.param, unit)
    return parameters, signals


def _found(element: Element, bonds: list[Bond], efforts: Mapping, flows: Mapping) -> Unit | None:
    """The unit a linear one-port's parameter takes from its bond's effort and flow."""
    if element.kind not in el.STORAGE | {"R"} or element.law is not None:
        return None
    effort, flow = efforts[bonds[0].key], flows[bonds[0].key]
    if effort is None or flow is None:
        return None
    return {"R": effort / flow, "I": effort * SECOND / flow, "C": flow * SECOND / effort}[element.kind]


def _conflict(element: Element, x, y, solver: _Solver) -> str:
    """One line: the element, its unit, and what its bonds carry already (and which element said so)."""
    own = f"unit {str(element.unit)!r}" if element.unit is not None else "its unit"
    if element.kind in el.TWO_PORTS:
        own = f"modulus unit {_modulus_unit(element)}"
    sides = [u for u in (x, y) if u != _Solver.ONE]
    facts = "; ".join(_carried(u, solver) for u in sides)
    text = f"{element}: {own} does not fit its bonds: {facts}"
    if element.kind in el.STORAGE | {"R"} and len(sides) == 2:
        effort, flow = solver.known(("e", sides[0][1])), solver.known(("f", sides[0][1]))
        if effort is not None and flow is not None:
            made = {"R": effort / flow, "I": effort * SECOND / flow, "C": flow * SECOND / effort}[element.kind]
            text += f"; they make {made}"
    return text


def _carried(unknown, solver: _Solver) -> str:
    side, (tail, head) = unknown
    unit, chain = solver.known(unknown), solver.origin(unknown)
    what = f"the {'effort' if side == 'e' else 'flow'} of bond {tail!r} -> {head!r}"
    if unit is None:
        return f"{what} is tied to another unit by its neighbours"
    # the source of the unit, and the elements it passed through: any of them may be the one at fault
    through = f" through {', '.join(chain[1:])}" if len(chain) > 1 else ""
    return f"{what} is {unit}" + (f" (from {chain[0]}{through})" if chain else "")
