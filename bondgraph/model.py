"""The bond graph model: a networkx.DiGraph wrapped with a small DSL and validation.

A bond graph is a ``networkx.DiGraph`` (model contract in docs/design.md): node
attribute ``kind``; ``param``, ``value``, ``uncertainty``, ``law`` on
parametric elements; ``signal`` on sources and detectors; an edge ``u -> v`` is
a bond whose direction is the power half-arrow, and edges into De/Df are signal
bonds.  Extensions kept by this toolkit (docs/model.md lists them all, with the rules for names and
physical domains; :meth:`BondGraph.add` refuses any other attribute, a graph built with networkx keeps
and ignores foreign ones unless they look like a misspelling):

``modulus``
    TF/GY/MTF/MGY: the modulus as an expression in parameters (and, for MTF/MGY,
    the modulating signal), e.g. ``"1/k_belt"``.  Default: the parameter itself
    (TF, GY) or the modulating signal (MTF, MGY).
``params``
    A dict of auxiliary constants a law uses besides the element's own
    parameter, e.g. ``{"S_n": 5e-5, "g": 9.81}`` for a valve.
``domain``, ``domains``
    The physical domain of the element's parameter (or a source's value) and of
    its law constants: ``"positive"``, ``"negative"``, ``"nonzero"``, ``"real"``
    (:mod:`bondgraph.domains`).

The model sits on top of the analyses: its elements and bonds are read into the
types of :mod:`bondgraph.structure`, checked by :mod:`bondgraph.validation`, and its
methods call causality, equations and drawing, none of which imports this module.

Examples
--------
>>> bg = BondGraph()
>>> bg.add("V", "Se", signal="u")
'V'
>>> bg.add("J1", "1")
'J1'
>>> bg.add("R1", "R", value=2.0, uncertainty=(-0.1, 0.1))
'R1'
>>> bg.add("L1", "I", value=0.5)
'L1'
>>> for tail, head in [("V", "J1"), ("J1", "R1"), ("J1", "L1")]:
...     _ = bg.bond(tail, head)
>>> bg.parameters
{'R1': 2.0, 'L1': 0.5}
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Hashable, Mapping
from difflib import get_close_matches

import networkx as nx
import sympy as sp
from sympy.core.function import AppliedUndef

from . import drawing
from . import elements as el
from .causality import Causality, assign_causality
from .equations import StateEquations, model_equations, state_equations
from .domains import CONSTANT_DOMAIN, DOMAINS, check_in_domain, default_domain, describe, read_domain
from .errors import LawError, ModelError
from .laws import check_finite, parse_expression
from .names import check_name, check_node_id
from .structure import (BOND_ATTRIBUTES, NODE_ATTRIBUTES, PORT_SYMBOLS, RESERVED_NAMES, Bond, Element, Structure,
                        signal_function)
from .validation import check_model, parameter_domains
from .dimensions import ModelUnits, check_units
from .units import parse_unit

__all__ = ["MISSPELLING", "BondGraph", "part_ports"]


class BondGraph:
    """A bond graph model following the model contract of docs/design.md.

    Parameters
    ----------
    graph : networkx.DiGraph, optional
        A graph built with networkx directly.  It is validated at once and kept
        as given (``bg.graph is graph``).  Without it, build with :meth:`add`
        and :meth:`bond`.
    name : str, optional
        A name for reports.

    Examples
    --------
    A graph built with networkx is validated and wrapped as it is:

    >>> import networkx as nx
    >>> g = nx.DiGraph()
    >>> g.add_node("F", kind="Sf", signal="u")
    >>> g.add_node("J", kind="0")
    >>> g.add_node("C1", kind="C", value=1e-3)
    >>> g.add_node("R1", kind="R", value=100.0)
    >>> g.add_edges_from([("F", "J"), ("J", "C1"), ("J", "R1")])
    >>> bg = BondGraph(g, name="RC tank")
    >>> bg
    <BondGraph 'RC tank': 3 bonds; 1 0, 1 C, 1 R, 1 Sf>
    >>> bg.graph is g, bg.inputs, bg.parameters
    (True, ['u'], {'C1': 0.001, 'R1': 100.0})
    >>> print(bg.state_equations())
    dq_C1/dt = u(t) - q_C1/(C1*R1)

    Mistakes are reported at once, naming the node or bond:

    >>> bg.add("X", "Q")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    bondgraph.errors.ModelError: node 'X': unknown kind 'Q' (expected one of 0, 1, C, De, Df, ...)
    >>> bg.bond("J", "Y")
    Traceback (most recent call last):
    ...
    bondgraph.errors.ModelError: bond ('J' -> 'Y'): node 'Y' does not exist; add it first
    """

    def __init__(self, graph: nx.DiGraph | None = None, *, name: str | None = None):
        if graph is None:
            graph = nx.DiGraph()
        if not isinstance(graph, nx.DiGraph) or graph.is_multigraph():
            raise ModelError(f"a bond graph is a networkx.DiGraph, got {type(graph).__name__}")
        self._graph = graph
        self.name = name or graph.graph.get("name", "bond graph")
        if graph.number_of_nodes():
            self.validate()

    # -- building (DSL) -------------------------------------------------
    @property
    def graph(self) -> nx.DiGraph:
        """The underlying networkx graph (the same object, not a copy)."""
        return self._graph

    def add(self, name: Hashable, kind: str | int, **attributes) -> Hashable:
        """Add an element; node-local attributes are checked at once.

        ``bg.add("R1", "R", value=10.0, uncertainty=(-0.05, 0.05))``.  The attributes are those of
        the model contract (docs/model.md); any other keyword is refused, so that a misspelt one is
        not silently lost.

        >>> BondGraph().add("R", "R", value=10, uncertanty=(-0.05, 0.05))
        Traceback (most recent call last):
        ...
        bondgraph.errors.ModelError: R 'R': unknown attribute 'uncertanty' (did you mean 'uncertainty'?)
        """
        if name in self._graph:
            raise ModelError(f"node {name!r} already exists ({self._graph.nodes[name].get('kind')})")
        data = {"kind": kind, **attributes}
        _read_element(name, data, strict=True)  # raises with the node's name on bad input
        self._graph.add_node(name, **data)
        return name

    def bond(self, tail: Hashable, head: Hashable, *, label: Hashable | None = None, **attributes) -> tuple:
        """Add a bond with power flowing from ``tail`` to ``head``.

        A bond into a De/Df node is a signal bond (a sensor on a junction).  Its attributes are
        ``label`` (a name, :data:`~bondgraph.names.NODE_ID_PATTERN`) and ``description``.
        """
        for node in (tail, head):
            if node not in self._graph:
                raise ModelError(f"bond ({tail!r} -> {head!r}): node {node!r} does not exist; add it first")
        if self._graph.has_edge(tail, head):
            raise ModelError(f"bond ({tail!r} -> {head!r}) already exists")
        if label is not None:
            check_node_id(label, where=f"bond ({tail!r} -> {head!r})", what="label")
            attributes["label"] = label
        _check_attributes(f"bond ({tail!r} -> {head!r})", attributes, BOND_ATTRIBUTES, strict=True)
        self._graph.add_edge(tail, head, **attributes)
        return (tail, head)

    def port(self, name: str, node: Hashable) -> str:
        """Name the junction ``node`` a port ``name``, where a model composing this one may bond to it.

        A port is a 0- or 1-junction: a bond to it shares the junction's effort or flow
        (:func:`bondgraph.composition.compose`).  Ports are kept in ``graph.graph["ports"]``.

        >>> bg = BondGraph()
        >>> _ = bg.add("1_m", "1"), bg.add("J", "I", value=0.1), bg.bond("1_m", "J")
        >>> bg.port("shaft", "1_m"), bg.ports
        ('shaft', {'shaft': '1_m'})
        >>> bg.port("axle", "J")
        Traceback (most recent call last):
        ...
        bondgraph.errors.ModelError: port 'axle': node 'J' (I) is not a 0- or 1-junction
        """
        ports = dict(self._graph.graph.get("ports") or {})
        if name in ports:
            raise ModelError(f"port {name!r} already exists (at node {ports[name]!r})")
        ports[name] = node
        _check_ports(self._graph, {name: node})
        self._graph.graph["ports"] = ports
        return name

    @property
    def ports(self) -> dict[str, Hashable]:
        """The model's ports: port name -> junction node (:meth:`port`)."""
        return part_ports(self)

    # -- views ------------------------------------------------------------
    def validate(self) -> None:
        """Check the whole model; raise :class:`ModelError` naming the node or bond at fault."""
        self.structure()

    def structure(self) -> Structure:
        """Validate the model and return a snapshot of its elements, bonds and parameters.

        The graph may be edited between calls, so every call validates afresh.
        """
        elements = {name: _read_element(name, data) for name, data in self._graph.nodes(data=True)}
        if self._graph.graph.get("ports"):
            part_ports(self)
        bonds = _read_bonds(self._graph, elements)
        parameters = check_model(elements, bonds)
        at: dict[Hashable, list[Bond]] = {name: [] for name in elements}
        for bond in bonds:
            at[bond.tail].append(bond)
            at[bond.head].append(bond)
        return Structure(elements, bonds, parameters, at, parameter_domains(elements, parameters),
                         check_units(elements, bonds))

    @property
    def elements(self) -> dict[Hashable, Element]:
        """Validated elements by node name, in insertion order."""
        return self.structure().elements

    @property
    def bonds(self) -> list[Bond]:
        """Power bonds (with labels) followed by signal bonds, in edge order."""
        return self.structure().bonds

    @property
    def parameters(self) -> dict[str, float]:
        """Nominal value of every parameter (element parameters, then law constants)."""
        return self.structure().parameters

    @property
    def domains(self) -> dict[str, tuple[float, float]]:
        """The open interval ``(lo, hi)`` each parameter of :attr:`parameters` must stay in.

        From the elements' ``domain`` and ``domains`` (:mod:`bondgraph.domains`): ``(0, inf)`` for a
        positive parameter (the default of C, I and R), ``(-inf, inf)`` for a real one (two-port moduli
        and law constants by default); a nonzero parameter gives the half-line of its nominal value.

        >>> from bondgraph.library import dc_motor
        >>> dc_motor().domains   # the library declares its motor constant k_m positive too
        {'R_a': (0.0, inf), 'L_a': (0.0, inf), 'k_m': (0.0, inf), 'J': (0.0, inf), 'b': (0.0, inf)}
        """
        return self.structure().domains

    @property
    def units(self) -> ModelUnits:
        """The units of every parameter, signal and bond, declared or found (:mod:`bondgraph.dimensions`).

        >>> from bondgraph.library import rlc_circuit
        >>> rlc_circuit().units.text("L"), rlc_circuit().units.text("v_C")
        ('H', 'V')
        """
        return self.structure().units

    @property
    def uncertainties(self) -> dict[str, tuple[float, float]]:
        """Multiplicative interval ``(delta_lo, delta_hi)`` of each uncertain parameter."""
        return {p: u for e in self.elements.values() for p, u in e.uncertainties.items()}

    @property
    def inputs(self) -> list[str]:
        """Input signal names: sources and modulating signals of MTF/MGY."""
        return self.structure().inputs

    @property
    def outputs(self) -> list[str]:
        """Measured signal names (detectors)."""
        return self.structure().outputs

    # -- analysis -----------------------------------------------------------
    def assign_causality(self, preferred: str = "integral", *, dualize_detectors: bool | None = None) -> Causality:
        """Sequential causality assignment; see :func:`bondgraph.causality.assign_causality`."""
        return assign_causality(self, preferred=preferred, dualize_detectors=dualize_detectors)

    def equations(self) -> list[sp.Eq]:
        """Acausal constitutive and junction equations; see :func:`bondgraph.equations.model_equations`."""
        return model_equations(self)

    def state_equations(self, causality: Causality | None = None) -> StateEquations:
        """State equations in integral causality; see :func:`bondgraph.equations.state_equations`."""
        return state_equations(self, causality)

    def _repr_svg_(self) -> str:
        """Jupyter display: :func:`bondgraph.drawing.display_svg`."""
        return drawing.display_svg(self)

    def _repr_html_(self) -> str:
        """Jupyter display: :func:`bondgraph.drawing.display_html`."""
        return drawing.display_html(self)

    def __repr__(self) -> str:
        kinds: dict[str, int] = {}
        for _, data in self._graph.nodes(data=True):
            kind = str(data.get("kind"))
            kinds[kind] = kinds.get(kind, 0) + 1
        summary = ", ".join(f"{n} {k}" for k, n in sorted(kinds.items()))
        return f"<BondGraph {self.name!r}: {self._graph.number_of_edges()} bonds; {summary}>"


def part_ports(bg: BondGraph) -> dict[str, Hashable]:
    """The ports of ``bg`` (``graph.graph["ports"]``), checked: each names an existing 0- or 1-junction."""
    ports = bg.graph.graph.get("ports") or {}
    if not isinstance(ports, Mapping):
        raise ModelError(f"ports must map port names to junction nodes, got {ports!r}")
    _check_ports(bg.graph, ports)
    return dict(ports)


def _check_ports(graph: nx.DiGraph, ports: Mapping) -> None:
    for name, node in ports.items():
        check_name(name, where=f"port {name!r}", what="port")
        if node not in graph:
            raise ModelError(f"port {name!r}: node {node!r} does not exist")
        kind = el.normalize_kind(graph.nodes[node].get("kind"))
        if kind not in el.JUNCTIONS:
            raise ModelError(f"port {name!r}: node {node!r} ({kind}) is not a 0- or 1-junction")


def _read_element(name: Hashable, data: Mapping, *, strict: bool = False) -> Element:
    """Validate one node's attributes and return its :class:`Element`.

    ``strict`` (the DSL): every attribute must be one of :data:`NODE_ATTRIBUTES`.  Otherwise (a graph
    built with networkx) a foreign attribute is kept and ignored, unless it looks like a misspelt one.
    """
    check_node_id(name, where="", what="node id")
    kind = el.normalize_kind(data.get("kind"))
    if kind is None:
        raise ModelError(
            f"node {name!r}: unknown kind {data.get('kind')!r} (expected one of {', '.join(sorted(el.KINDS))})"
        )
    where = f"{kind} {name!r}"
    _check_attributes(where, data, NODE_ATTRIBUTES, strict=strict)
    param = value = uncertainty = law = modulus = signal = None
    constants = _read_constants(where, data.get("params"))
    constant_uncertainties = _read_constant_uncertainties(where, data.get("uncertainties"), constants)
    constant_domains = _read_constant_domains(where, data.get("domains"), constants)
    domain = _read_own_domain(where, kind, data.get("domain"))

    stiffness = data.get("stiffness")
    if stiffness is not None:
        _check_stiffness_alone(where, kind, data)
    if kind in el.PARAMETRIC:
        param = _read_name(where, "parameter", data.get("param"), name, "param")
        if param in RESERVED_NAMES:
            raise ModelError(f"{where}: parameter name {param!r} is reserved (e, f, q, p, t)")
        value = _read_value(where, data.get("value") if stiffness is None else stiffness)
        if data.get("uncertainty") is not None:
            uncertainty = _read_uncertainty(where, data["uncertainty"])
    elif data.get("uncertainty") is not None:
        raise ModelError(f"{where}: has an uncertainty but no parameter (only C, I, R, TF, GY, MTF, MGY do)")
    if kind in el.SOURCES | el.DETECTORS | el.MODULATED_TWO_PORTS:
        signal = _read_name(where, "signal", data.get("signal"), name, "signal")
        if signal == "t":  # signals are functions of the time symbol t
            raise ModelError(f"{where}: signal name 't' is reserved for time")
    if kind in el.SOURCES and data.get("value") is not None:
        value = _read_value(where, data["value"])  # optional constant input

    names = {**{c: sp.Symbol(c) for c in constants}, **({param: sp.Symbol(param)} if param else {})}
    if stiffness is not None:  # a linear spring e = k q: exactly the law form, so every stage treats it as one
        law = _read_law(where, kind, PORT_SYMBOLS["e"] - sp.Symbol(param) * PORT_SYMBOLS["q"], names, param)
    if data.get("law") is not None:
        if kind not in el.LAW_VARIABLES:
            raise ModelError(f"{where}: a law is only for C, I and R elements (use 'modulus' on a two-port)")
        law = _read_law(where, kind, data["law"], names, param)
    if kind in el.TWO_PORTS:
        modulus = _read_modulus(where, kind, data.get("modulus"), names, param, signal)
    if kind in el.PARAMETRIC and value is None:
        form = next((x for x in (law, modulus) if x is not None), sp.Symbol(param))
        if sp.Symbol(param) in form.free_symbols:  # a law or modulus may not need the parameter
            raise ModelError(f"{where}: missing nominal 'value' for parameter {param!r}")
    _check_domains(where, kind, data, domain, value, uncertainty, param, law)
    declared = data.get("domains") or {}
    for constant, number in constants.items():
        _check_box(where, f"constant {constant!r}", constant_domains[constant], number,
                   constant_uncertainties.get(constant),
                   hint="" if constant in declared else "set its domain in 'domains' if another sign is meant")
    unit, units = _read_units(where, kind, data, constants, signal)
    return Element(name, kind, param, value, uncertainty, law, modulus, signal, constants, constant_uncertainties,
                   domain, constant_domains, unit, units)


def _read_units(where: str, kind: str, data: Mapping, constants: Mapping, signal: str | None) -> tuple:
    """``unit`` (the parameter's, or the source's or detector's signal's) and ``units`` (law constants, and a
    modulated two-port's signal), parsed (:mod:`bondgraph.units`)."""
    unit = data.get("unit")
    if unit is not None:
        if kind in el.JUNCTIONS:
            raise ModelError(f"{where}: a junction has no unit (its bonds take theirs from the elements around it)")
        unit = parse_unit(unit, where=where)
    others = data.get("units")
    if others is None:  # the common case, kept cheap: structure() reads every element on every call
        return unit, {}
    if not isinstance(others, Mapping):
        raise ModelError(f"{where}: 'units' must map law constants (or a modulated two-port's signal) to units, "
                         f"got {others!r}")
    allowed = set(constants) | ({signal} if kind in el.MODULATED_TWO_PORTS else set())
    for key in others:
        if key not in allowed:
            what = f"one of {sorted(allowed)}" if allowed else "nothing here (give the element's own unit in 'unit')"
            raise ModelError(f"{where}: 'units' names {key!r}, which is not a law constant or a modulating signal of "
                             f"this element; it may name {what}")
    return unit, {key: parse_unit(text, where=f"{where} {key!r}") for key, text in others.items()}


def _check_stiffness_alone(where: str, kind: str, data: Mapping) -> None:
    """A ``stiffness`` declares a C element's parameter and law (``e = k q``): nothing else may."""
    if kind != "C":
        raise ModelError(f"{where}: 'stiffness' is only for C elements (a linear spring, e = k q)")
    if isinstance(data["stiffness"], bool) or not isinstance(data["stiffness"], numbers.Real):
        raise ModelError(f"{where}: stiffness {data['stiffness']!r} is not a number")
    for other, meaning in (("value", "a compliance, e = q/C"), ("law", "its own law")):
        if data.get(other) is not None:
            raise ModelError(f"{where}: give 'stiffness' (e = k q) or '{other}' ({meaning}), not both")


def _check_attributes(where: str, data: Mapping, known: frozenset, *, strict: bool) -> None:
    """Refuse an unknown attribute: any (``strict``), or one that looks like a misspelt known one."""
    for key in data:
        if key in known or key == "kind":
            continue
        close = get_close_matches(key, sorted(known), n=1) if isinstance(key, str) else []
        if strict:
            hint = f" (did you mean {close[0]!r}?)" if close else f" (known: {', '.join(sorted(known))})"
            raise ModelError(f"{where}: unknown attribute {key!r}{hint}")
        close = get_close_matches(key, sorted(known), n=1, cutoff=MISSPELLING) if isinstance(key, str) else []
        if close:  # foreign attributes (colour, pos) are kept and ignored; a misspelt field would be lost
            raise ModelError(f"{where}: unknown attribute {key!r} (did you mean {close[0]!r}?); "
                             "other attributes are kept and ignored, but this one looks like a misspelling")


#: How close (difflib ratio) a foreign attribute of a networkx graph may come to a known one before it is
#: taken for a misspelling: ``uncertanty`` (0.95), ``lable`` (0.8) are; ``name``/``domain`` (0.6) is not.
MISSPELLING = 0.8


def _read_name(where: str, what: str, given, name: Hashable, key: str) -> str:
    """A parameter or signal name: ``given`` (the ``key`` attribute) or, by default, the node's id."""
    if given is not None:
        return check_name(given, where=where, what=what)
    return check_name(str(name), where=where, what=what,
                      hint=f"the node id names it by default, so give the node a '{key}' that is one")


def _read_own_domain(where: str, kind: str, domain) -> str:
    if domain is None:
        return default_domain(kind)
    if kind not in el.PARAMETRIC | el.SOURCES:
        raise ModelError(f"{where}: has a domain but no parameter or value (only C, I, R, two-ports and sources do)")
    return read_domain(domain, where=where)


def _check_domains(where, kind, data, domain, value, uncertainty, param, law) -> None:
    """The nominal value and its uncertainty box in the element's domain; a linear C, I, R never zero."""
    what = f"parameter {param!r}" if param is not None else "value"
    if kind in el.LAW_VARIABLES and law is None and value == 0:  # whatever the domain says
        raise ModelError(f"{where}: {what} = 0 is not allowed: its linear law divides by it "
                         f"({_DIVIDES[kind]}); domain {describe(domain)}")
    hint = "" if data.get("domain") is not None else "set its 'domain' if another sign is meant"
    _check_box(where, what, domain, value, uncertainty, hint=hint)


#: Where the linear law of a C, I or R divides by its parameter (R: in conductance causality).
_DIVIDES = {"C": "e = q/C", "I": "f = p/I", "R": "f = e/R"}


def _check_box(where: str, what: str, domain: str, value, box, *, hint: str = "") -> None:
    check_in_domain(domain, value, box, where=where, what=what, hint=hint)
    if box is not None and box[0] <= -1.0:
        raise ModelError(f"{where}: uncertainty {box} lets {what} reach zero or change sign (need lo > -1: "
                         "a law solved for its other variable divides by value * (1 + delta))")


def _read_value(where: str, value) -> float | None:
    if value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ModelError(f"{where}: nominal value {value!r} is not a number") from None
    if not math.isfinite(number):
        raise ModelError(f"{where}: nominal value {value!r} is not finite")
    return number


def _read_uncertainty(where: str, interval) -> tuple[float, float]:
    try:
        lo, hi = (float(x) for x in interval)
    except (TypeError, ValueError):
        raise ModelError(f"{where}: uncertainty {interval!r} is not a pair (delta_lo, delta_hi)") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ModelError(f"{where}: uncertainty {interval!r} is not finite")
    if lo > hi:
        raise ModelError(f"{where}: uncertainty {interval!r} has lo > hi")
    if not lo <= 0.0 <= hi:
        raise ModelError(
            f"{where}: multiplicative uncertainty {interval!r} must contain 0 "
            "(true value = value * (1 + delta), delta in [lo, hi])"
        )
    return (lo, hi)


def _read_constants(where: str, params) -> dict[str, float]:
    if params is None:
        return {}
    if not isinstance(params, Mapping):
        raise ModelError(f"{where}: 'params' must be a mapping of constant names to values, got {params!r}")
    constants = {}
    for key, value in params.items():
        check_name(key, where=where, what="constant")
        if key in RESERVED_NAMES:
            raise ModelError(f"{where}: constant name {key!r} is reserved (e, f, q, p, t)")
        constants[key] = _read_value(f"{where} constant {key!r}", value)
        if constants[key] is None:
            raise ModelError(f"{where}: constant {key!r} has no value")
    return constants


def _read_constant_uncertainties(where: str, intervals, constants: Mapping) -> dict[str, tuple[float, float]]:
    """``uncertainties={"mu": (-0.1, 0.1)}``: multiplicative intervals of law constants."""
    if intervals is None:
        return {}
    if not isinstance(intervals, Mapping):
        raise ModelError(f"{where}: 'uncertainties' must map law constants to (delta_lo, delta_hi), got {intervals!r}")
    _check_constant_keys(where, "uncertainties", intervals, constants, "the element parameter's interval goes in "
                         "'uncertainty'")
    return {k: _read_uncertainty(f"{where} constant {k!r}", v) for k, v in intervals.items()}


def _read_constant_domains(where: str, domains, constants: Mapping) -> dict[str, str]:
    """``domains={"M": "positive"}``: the domains of law constants (default :data:`CONSTANT_DOMAIN`)."""
    if domains is None:  # the common case, kept cheap: structure() reads every element on every call
        return dict.fromkeys(constants, CONSTANT_DOMAIN)
    if not isinstance(domains, Mapping):
        raise ModelError(f"{where}: 'domains' must map law constants to a domain ({', '.join(DOMAINS)}), "
                         f"got {domains!r}")
    _check_constant_keys(where, "domains", domains, constants, "the element parameter's domain goes in 'domain'")
    given = {k: read_domain(v, where=f"{where} constant {k!r}") for k, v in domains.items()}
    return {c: given.get(c, CONSTANT_DOMAIN) for c in constants}


def _check_constant_keys(where: str, field: str, mapping: Mapping, constants: Mapping, hint: str) -> None:
    unknown = sorted(map(str, set(mapping) - set(constants)))
    if unknown:
        raise ModelError(f"{where}: '{field}' names {unknown}, which are not law constants in 'params' "
                         f"({sorted(constants)}); {hint}")


def _read_law(where: str, kind: str, law, names: dict, param: str) -> sp.Expr:
    ports = el.LAW_VARIABLES[kind]
    allowed = {**names, **{v: PORT_SYMBOLS[v] for v in ports}}
    if isinstance(law, str):
        expression = parse_expression(law, allowed, where=f"{where} law")
    elif isinstance(law, sp.Basic):
        expression = law
        if isinstance(law, sp.Equality):
            expression = law.lhs - law.rhs
        unknown = {s.name for s in expression.free_symbols} - set(allowed)
        if unknown:
            raise LawError(f"{where} law: unknown symbol(s) {sorted(unknown)} (allowed: {sorted(allowed)})")
        if expression.atoms(AppliedUndef):
            raise LawError(f"{where} law: undefined function(s) {sorted(map(str, expression.atoms(AppliedUndef)))}")
    else:
        raise LawError(f"{where} law: expected a sympy expression or a string, got {type(law).__name__}")
    check_finite(expression, where=f"{where} law")
    symbols = {s.name for s in expression.free_symbols}
    missing = [v for v in ports if v not in symbols]
    if missing:
        raise LawError(
            f"{where} law {expression} = 0 does not mention the port variable(s) {missing} "
            f"(a {kind} law relates {' and '.join(ports)})"
        )
    return expression


def _read_modulus(where, kind, modulus, names, param, signal) -> sp.Expr:
    if kind in el.MODULATED_TWO_PORTS:
        names = {**names, signal: signal_function(signal)}
    if modulus is None:
        return signal_function(signal) if kind in el.MODULATED_TWO_PORTS else sp.Symbol(param)
    if isinstance(modulus, (int, float)) and not isinstance(modulus, bool):
        raise ModelError(f"{where}: give a numeric modulus as 'value', not 'modulus'")
    if isinstance(modulus, str):  # a modulating signal is written by name; it stands for name(t)
        return parse_expression(modulus, names, where=f"{where} modulus")
    if isinstance(modulus, sp.Basic):
        allowed = {str(v) for v in names.values()}
        unknown = {str(s) for s in modulus.free_symbols | modulus.atoms(AppliedUndef)} - allowed - {"t"}
        if unknown:
            raise LawError(f"{where} modulus: unknown symbol(s) {sorted(unknown)}")
        check_finite(modulus, where=f"{where} modulus")
        return modulus
    raise LawError(f"{where} modulus: expected a sympy expression or a string, got {type(modulus).__name__}")


def _read_bonds(graph: nx.DiGraph, elements: Mapping[Hashable, Element]) -> list[Bond]:
    power, signal, used = [], [], set()
    for tail, head, data in graph.edges(data=True):
        where = f"bond ({tail!r} -> {head!r})"
        _check_attributes(where, data, BOND_ATTRIBUTES, strict=False)
        is_signal = elements[head].kind in el.DETECTORS or elements[tail].kind in el.DETECTORS
        label = data.get("label")
        if label is not None:
            check_node_id(label, where=where, what="label")
        if is_signal:
            signal.append(Bond(tail, head, label, True))
            continue
        if label is not None:
            if str(label) in used:  # labels name the symbols e_<label>, f_<label>
                raise ModelError(f"{where}: label {label!r} is used by another bond")
            used.add(str(label))
        power.append([tail, head, label])
    number = 1
    for entry in power:  # number unlabeled bonds, skipping labels the user chose
        if entry[2] is None:
            while str(number) in used:
                number += 1
            entry[2] = number
            used.add(str(number))
    return [Bond(t, h, label) for t, h, label in power] + signal
