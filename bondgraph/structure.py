"""The validated parts of a bond graph: elements, bonds, the structure snapshot, and their symbols.

This is the bottom layer of ``bondgraph``: the analyses (causality, equations, drawing, validation)
read a model only through these types and :class:`BondGraphLike`, so none of them imports
:mod:`bondgraph.model`, whose :class:`~bondgraph.model.BondGraph` calls them.

Examples
--------
>>> from bondgraph.library import rlc_circuit
>>> structure = rlc_circuit().structure()
>>> structure.inputs, structure.outputs, [str(b) for b in structure.at["R"]]
(['V'], ['i', 'v_C'], ["bond 2 ('J1' -> 'R')"])
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping
from dataclasses import dataclass, field
from pathlib import PurePath
from typing import Protocol

import sympy as sp

from . import elements as el
from .units import Unit

__all__ = [
    "BOND_ATTRIBUTES", "NODE_ATTRIBUTES", "PORT_SYMBOLS", "RESERVED_NAMES", "T", "Bond", "BondGraphLike",
    "Element", "Structure", "require_model", "signal_function",
]

#: The time symbol of the contract: signals are ``name(t)``, energy variables ``q_<C>(t)``, ``p_<I>(t)``.
T = sp.Symbol("t")
#: The port variables a law may relate: effort, flow, charge (integral of flow), momentum (of effort).
PORT_SYMBOLS = {name: sp.Symbol(name) for name in ("e", "f", "q", "p")}
#: Names no parameter, constant or signal may take: they would clash with the port variables or time.
RESERVED_NAMES = frozenset(PORT_SYMBOLS) | {"t"}
#: The node attributes of the model contract (docs/model.md), what ``BondGraph.add`` and a JSON node accept.
NODE_ATTRIBUTES = frozenset({"kind", "param", "value", "stiffness", "uncertainty", "law", "modulus", "signal",
                             "params", "uncertainties", "domain", "domains", "unit", "units", "label", "description"})
#: The bond attributes of the model contract, what ``BondGraph.bond`` and a JSON link accept.
BOND_ATTRIBUTES = frozenset({"label", "description"})


def signal_function(name: str) -> sp.Expr:
    """The contract's form of a measured or input signal: ``name(t)``.

    >>> signal_function("omega_m")
    omega_m(t)
    """
    return sp.Function(name)(T)


@dataclass(frozen=True)
class Element:
    """A validated node of the bond graph.

    ``law`` is in the port symbols ``e, f, q, p`` and parameter symbols;
    ``modulus`` (two-ports) is in parameter symbols and signal functions.
    Elements are read from the graph by :attr:`BondGraph.elements`.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit, torsion_bar_monitorable
    >>> r = rlc_circuit().elements["R"]
    >>> str(r), r.kind, r.param, r.value, r.uncertainty
    ("R 'R'", 'R', 'R', 10.0, (-0.05, 0.05))
    >>> r.law is None, r.uncertainties, r.domain   # default linear law e = R f, R > 0
    (True, {'R': (-0.05, 0.05)}, 'positive')
    >>> spring = torsion_bar_monitorable().elements["k_s"]
    >>> spring.law, spring.value
    (e - k_s*q, 1.786)
    """

    name: Hashable
    kind: str
    param: str | None = None
    value: float | None = None
    uncertainty: tuple[float, float] | None = None
    law: sp.Expr | None = None
    modulus: sp.Expr | None = None
    signal: str | None = None
    constants: Mapping[str, float] = field(default_factory=dict)
    constant_uncertainties: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    domain: str = "real"
    constant_domains: Mapping[str, str] = field(default_factory=dict)
    unit: Unit | None = None                                   # of the parameter, or of a source's or detector's signal
    units: Mapping[str, Unit] = field(default_factory=dict)   # of the law constants, a modulated two-port's signal

    @property
    def uncertainties(self) -> dict[str, tuple[float, float]]:
        """Multiplicative interval of the element's parameter and of its uncertain law constants."""
        own = {self.param: self.uncertainty} if self.uncertainty is not None else {}
        return {**own, **self.constant_uncertainties}

    def __str__(self) -> str:
        return f"{self.kind} {self.name!r}"


@dataclass(frozen=True)
class Bond:
    """A bond ``tail -> head`` (power direction); signal bonds end at a detector.

    Power bonds carry a ``label`` (numbered in edge order unless given), which
    names their effort and flow symbols ``e_<label>``, ``f_<label>``; signal
    bonds have none.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> bonds = rlc_circuit().bonds
    >>> first = bonds[0]
    >>> str(first), first.key, first.label
    ("bond 1 ('V' -> 'J1')", ('V', 'J1'), 1)
    >>> first.other("V"), first.sign_into("J1"), first.sign_into("V")
    ('J1', 1, -1)
    >>> first.other("R")
    Traceback (most recent call last):
    ...
    ValueError: 'R' is not an end of bond 1 ('V' -> 'J1')
    >>> sensor = bonds[-1]   # signal bonds come after the power bonds
    >>> str(sensor), sensor.is_signal
    ("signal bond ('J0' -> 'v_C')", True)
    """

    tail: Hashable
    head: Hashable
    label: Hashable | None
    is_signal: bool = False

    @property
    def key(self) -> tuple[Hashable, Hashable]:
        """The edge ``(tail, head)`` that identifies the bond, e.g. in ``Causality.effort_from``."""
        return (self.tail, self.head)

    def other(self, node: Hashable) -> Hashable:
        """The node at the other end of the bond from ``node``, one of its two ends (else ValueError)."""
        if node == self.tail:
            return self.head
        if node == self.head:
            return self.tail
        raise ValueError(f"{node!r} is not an end of {self}")

    def sign_into(self, node: Hashable) -> int:
        """+1 if power flows into ``node`` along this bond, -1 if out of it (``node`` one of its ends)."""
        if node == self.head:
            return 1
        if node == self.tail:
            return -1
        raise ValueError(f"{node!r} is not an end of {self}")

    def __str__(self) -> str:
        name = f"bond {self.label} " if self.label is not None else "signal bond "
        return f"{name}({self.tail!r} -> {self.head!r})"


@dataclass(frozen=True)
class Structure:
    """A validated snapshot of a bond graph, taken once per analysis.

    ``at[node]`` lists the bonds (power and signal) touching ``node``; ``domains`` holds the open
    interval ``(lo, hi)`` each parameter of ``parameters`` must stay in (:mod:`bondgraph.domains`);
    ``units`` the units of the parameters, signals and bonds (:mod:`bondgraph.dimensions`).
    """

    elements: dict
    bonds: list
    parameters: dict
    at: dict
    domains: dict = field(default_factory=dict)
    units: object = None  # the bondgraph.dimensions.ModelUnits of the model (that module reads this one)

    @property
    def inputs(self) -> list[str]:
        """Input signal names, without repeats, in element order: of the sources and the modulating ones of MTF/MGY."""
        names = [e.signal for e in self.elements.values() if e.kind in el.SOURCES | el.MODULATED_TWO_PORTS]
        return list(dict.fromkeys(names))

    @property
    def outputs(self) -> list[str]:
        """Measured signal names, one per detector (De, Df), in element order."""
        return [e.signal for e in self.elements.values() if e.kind in el.DETECTORS]


class BondGraphLike(Protocol):
    """What the analyses read from a model: its ``name`` and a validated :class:`Structure`.

    :class:`~bondgraph.model.BondGraph` is one.  Causality, equations and drawings take any such
    object, so they need not import the model class (which calls them from its methods).

    >>> from bondgraph.library import dc_motor
    >>> def bond_count(bg: BondGraphLike) -> int:
    ...     return len(bg.structure().bonds)
    >>> bond_count(dc_motor())
    9
    """

    name: str

    def structure(self) -> Structure:
        """Validate the model and return a snapshot of its elements, bonds and parameters."""
        ...


def require_model(bg: object, function: str, argument: str = "bg") -> None:
    """Raise :class:`TypeError` unless ``bg`` is a model (has a ``structure()``), naming ``function`` and ``argument``.

    The analyses take a :class:`BondGraphLike`; a model name or a path given in its place would
    otherwise fail deep inside with an ``AttributeError``.

    >>> require_model("dc-motor", "derive_arrs")
    Traceback (most recent call last):
    ...
    TypeError: derive_arrs: bg must be a BondGraph, got str 'dc-motor' (use bondgraph.load_model('dc-motor').model)
    """
    if callable(getattr(bg, "structure", None)):
        return
    shown = repr(bg) if len(repr(bg)) <= 60 else repr(bg)[:50] + "..."
    got = shown if shown.startswith(type(bg).__name__) else f"{type(bg).__name__} {shown}"
    hint = ""
    if isinstance(bg, (str, PurePath)):  # a model name or a file: say how to load it
        hint = f" (use bondgraph.load_model({shown if isinstance(bg, str) else repr(str(bg))}).model)"
    raise TypeError(f"{function}: {argument} must be a BondGraph, got {got}{hint}")
