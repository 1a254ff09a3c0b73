"""Models composed of sub-models: parts with named ports, bonded together, every name kept as a path.

A sub-model is an ordinary :class:`~bondgraph.model.BondGraph` that names some of its junctions as
*ports*, where another model may be bonded (:meth:`BondGraph.port <bondgraph.model.BondGraph.port>`, or
``"graph": {"ports": {"shaft": "1_m"}}`` in a JSON file).  It is complete on its own, so it can be
simulated, diagnosed and tested alone: a port left unconnected is a junction with one bond fewer (a
free shaft, an open terminal pair).

:func:`compose` copies each part into one flat bond graph under the part's name, then bonds ports
together.  Whatever came from a part is named by its path (:data:`~bondgraph.names.PATH_SEPARATOR`):
the node ``1_m`` of the part ``motor`` becomes ``motor.1_m``, its parameter ``R_a`` becomes
``motor.R_a`` (in laws and moduli too), its signals ``motor.U`` and ``motor.i``, its bonds
``motor.1``, ``motor.2`` (the part's own numbering) and its states ``p_motor.L_a``.  The composed
model is flat: causality, equations, ARRs, reports and the command line see one bond graph, and name
each element by its path.  Parts may be composed models themselves (``drive.motor.R_a``).

A bond between two ports joins two junctions: two 1-junctions share their flow (a rigid coupling,
one speed), two 0-junctions their effort.  The bond's direction is the power's, from the first port
to the second.

Examples
--------
A source with its internal resistance and an RC load, each a model of its own, joined at their terminals:

>>> from bondgraph import BondGraph
>>> source = BondGraph(name="source")
>>> _ = source.add("U", "Se"), source.add("out", "1"), source.add("R_s", "R", value=1.0)
>>> _ = source.bond("U", "out"), source.bond("out", "R_s"), source.port("terminal", "out")
>>> load = BondGraph(name="load")
>>> _ = load.add("in", "0"), load.add("C", "C", value=1e-3), load.add("R", "R", value=50.0), load.add("v", "De")
>>> _ = load.bond("in", "C"), load.bond("in", "R"), load.bond("in", "v"), load.port("terminal", "in")
>>> circuit = compose({"supply": source, "rc": load}, [("supply.terminal", "rc.terminal")], name="RC")
>>> circuit.parameters, circuit.inputs, circuit.outputs
({'supply.R_s': 1.0, 'rc.C': 0.001, 'rc.R': 50.0}, ['supply.U'], ['rc.v'])
>>> print(circuit.state_equations())
dq_rc.C/dt = -q_rc.C/(rc.C*rc.R) + (-q_rc.C/rc.C + supply.U(t))/supply.R_s
rc.v = q_rc.C/rc.C
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping

import networkx as nx
import sympy as sp
from sympy.core.function import AppliedUndef

from .errors import ModelError
from .model import BondGraph, part_ports
from .names import PATH_SEPARATOR, check_name
from .structure import Element, require_model

__all__ = ["compose", "path", "renamed_settings"]


def path(part: str, name: Hashable) -> str:
    """The name ``name`` of the part ``part`` in the composed model: ``part.name``.

    >>> path("motor", "R_a"), path("motor", 3)
    ('motor.R_a', 'motor.3')
    """
    return f"{part}{PATH_SEPARATOR}{name}"


def compose(parts: Mapping[str, BondGraph], connections: Iterable = (), *, ports: Mapping[str, str] | None = None,
            name: str | None = None) -> BondGraph:
    """One flat bond graph of the ``parts``, their ports bonded as ``connections`` say (see the module).

    Parameters
    ----------
    parts : mapping
        Part name (an identifier without dots) -> its model.  The parts are copied, never changed.
    connections : iterable of pairs or triples
        ``("motor.shaft", "belt.drive")``: a bond from the port ``shaft`` of ``motor`` to the port
        ``drive`` of ``belt`` (power flows that way); a third item labels the bond.
    ports : mapping, optional
        The composed model's own ports: port name -> ``"part.port"``, so that it can be a part in turn.
    name : str, optional
        The composed model's name.

    Returns
    -------
    BondGraph
        Validated; its node ids, parameters, signals and bond labels are the parts' under their paths.

    Raises
    ------
    ModelError
        Naming the part, port or connection at fault; a part's own mistake is reported by the part's
        validation with the part's name in front.
    """
    if not isinstance(parts, Mapping) or not parts:
        raise ModelError("compose: give the parts as a non-empty mapping of part name -> BondGraph")
    graph = nx.DiGraph()
    found: dict[str, dict[str, Hashable]] = {}
    for part, model in parts.items():
        check_name(part, where="compose", what="part")
        if PATH_SEPARATOR in part:
            raise ModelError(f"compose: part name {part!r} has a {PATH_SEPARATOR!r}; a part's name is one word")
        require_model(model, "compose", f"part {part!r}")
        found[part] = _copy_part(graph, part, model)
    for index, connection in enumerate(connections):
        _connect(graph, found, connection, f"compose: connections[{index}]")
    if ports:
        graph.graph["ports"] = {port: _port_node(found, target, f"compose: ports[{port!r}]")
                                for port, target in ports.items()}
    composed = BondGraph(graph, name=name or " + ".join(parts))
    return composed


def renamed_settings(part: str, model: BondGraph, inputs: Mapping, x0: Mapping) -> tuple[dict, dict]:
    """A part's run settings under its path: its inputs by signal, its initial states by state or element.

    >>> from bondgraph.library import dc_motor
    >>> renamed_settings("motor", dc_motor(), {"U": 12.0}, {"p_J": 0.1, "L_a": 0.0})
    ({'motor.U': 12.0}, {'p_motor.J': 0.1, 'motor.L_a': 0.0})
    """
    elements = {str(name) for name in model.graph}
    renamed_x0 = {}
    for key, value in x0.items():
        text = str(key)
        prefix, _, element = text.partition("_")
        if text not in elements and prefix in ("q", "p") and element in elements:
            renamed_x0[f"{prefix}_{path(part, element)}"] = value
        else:
            renamed_x0[path(part, text)] = value
    return {path(part, signal): value for signal, value in inputs.items()}, renamed_x0


# ------------------------------------------------------------------------------------------- helpers

def _copy_part(graph: nx.DiGraph, part: str, model: BondGraph) -> dict[str, Hashable]:
    """Copy ``model``'s nodes and bonds into ``graph`` under ``part``; return its ports by name, as new node ids."""
    try:
        structure = model.structure()
        ports = part_ports(model)
    except ModelError as exc:
        raise type(exc)(f"part {part!r}: {exc}") from None
    names = _renaming(part, structure.elements.values())
    for node, data in model.graph.nodes(data=True):
        graph.add_node(path(part, node), **_renamed_node(data, structure.elements[node], names))
    for bond in structure.bonds:
        attributes = dict(model.graph.edges[bond.tail, bond.head])
        if bond.label is not None:
            attributes["label"] = path(part, bond.label)  # the part's own numbering, kept under its path
        graph.add_edge(path(part, bond.tail), path(part, bond.head), **attributes)
    return {port: path(part, node) for port, node in ports.items()}


def _renaming(part: str, elements: Iterable[Element]) -> dict[str, str]:
    """Every parameter, law constant and signal name of a part -> its path."""
    names: dict[str, str] = {}
    for element in elements:
        for name in [element.param, element.signal, *element.constants]:
            if name is not None:
                names[name] = path(part, name)
    return names


def _renamed_node(data: Mapping, element: Element, names: Mapping[str, str]) -> dict:
    """A node's attributes with its names replaced by their paths (laws and moduli rewritten in sympy)."""
    renamed = dict(data)
    if element.param is not None:
        renamed["param"] = names[element.param]
    if element.signal is not None:
        renamed["signal"] = names[element.signal]
    if data.get("law") is not None:
        renamed["law"] = _renamed_expression(element.law, names)
    if data.get("modulus") is not None:
        renamed["modulus"] = _renamed_expression(element.modulus, names)
    for field in ("params", "uncertainties", "domains", "units"):
        if isinstance(data.get(field), Mapping):
            renamed[field] = {names.get(key, key): value for key, value in data[field].items()}
    return renamed


def _renamed_expression(expression: sp.Expr, names: Mapping[str, str]) -> sp.Expr:
    """``expression`` with its parameter and constant symbols, and its signals ``u(t)``, renamed."""
    symbols = {s: sp.Symbol(names[s.name]) for s in expression.free_symbols if s.name in names}
    expression = expression.xreplace(symbols)
    signals = {f: sp.Function(names[f.func.__name__])(*f.args) for f in expression.atoms(AppliedUndef)
               if f.func.__name__ in names}
    return expression.xreplace(signals)


def _connect(graph: nx.DiGraph, found: Mapping, connection, where: str) -> None:
    """Bond two ports: ``(tail, head)`` or ``(tail, head, label)``."""
    if isinstance(connection, (str, bytes)) or not isinstance(connection, Iterable):
        raise ModelError(f"{where}: expected a pair of ports 'part.port' (and an optional label), "
                         f"got {connection!r}")
    items = list(connection)
    if len(items) not in (2, 3):
        raise ModelError(f"{where}: expected a pair of ports 'part.port' (and an optional label), got {items!r}")
    tail, head = (_port_node(found, item, where) for item in items[:2])
    if graph.has_edge(tail, head) or graph.has_edge(head, tail):
        raise ModelError(f"{where}: {items[0]} and {items[1]} are already bonded")
    graph.add_edge(tail, head, **({"label": items[2]} if len(items) == 3 else {}))


def _port_node(found: Mapping[str, Mapping[str, Hashable]], target, where: str) -> Hashable:
    """The node id of the port ``"part.port"``."""
    if not isinstance(target, str) or PATH_SEPARATOR not in target:
        raise ModelError(f"{where}: {target!r} is not a port 'part.port'")
    part, _, port = target.partition(PATH_SEPARATOR)
    if part not in found:
        raise ModelError(f"{where}: {target!r}: no part {part!r} (parts: {', '.join(found)})")
    if port not in found[part]:
        known = ", ".join(found[part]) or "none"
        raise ModelError(f"{where}: {target!r}: part {part!r} has no port {port!r} (its ports: {known})")
    return found[part][port]
