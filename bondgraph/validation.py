"""Structural checks of a bond graph: bonds per element, detectors, names.

Node-local checks (kind, value, uncertainty, law) happen when an element is
read (:meth:`bondgraph.model.BondGraph.add` and ``structure``); this module checks
how elements are connected and that names are used consistently across the model.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping

import sympy as sp

from . import elements as el
from .domains import bounds, describe, intersect
from .errors import ModelError
from .structure import Bond, Element

__all__ = ["check_model", "parameter_domains"]


def check_model(elements: Mapping[Hashable, Element], bonds: list[Bond]) -> dict[str, float]:
    """Check connectivity and names; return the nominal value of every parameter.

    Raises
    ------
    ModelError
        naming the node, bond, parameter or signal at fault.
    """
    _check_bonds(elements, bonds)
    _check_node_names(elements)
    parameters = _check_parameters(elements)
    _check_signals(elements, parameters)
    return parameters


def _check_bonds(elements, bonds) -> None:
    power_in = {n: [] for n in elements}
    power_out = {n: [] for n in elements}
    sensors = {n: [] for n in elements}
    for bond in bonds:
        tail, head = elements[bond.tail], elements[bond.head]
        if bond.is_signal:
            if tail.kind in el.DETECTORS:
                raise ModelError(f"{bond}: a detector ({tail}) only receives a signal bond from a junction")
            if tail.kind not in el.JUNCTIONS:
                raise ModelError(f"{bond}: detector {head} is on {tail}, which is not a junction")
            wanted = el.DETECTOR_JUNCTION[head.kind]
            if tail.kind != wanted:
                raise ModelError(
                    f"{bond}: {head} must sit on a {wanted}-junction "
                    f"({'common effort' if wanted == '0' else 'common flow'}); {tail} is a {tail.kind}-junction"
                )
            sensors[bond.head].append(bond)
            continue
        if tail.kind in el.SOURCES and head.kind in el.SOURCES:
            raise ModelError(f"{bond}: a bond between two sources ({tail} and {head})")
        power_out[bond.tail].append(bond)
        power_in[bond.head].append(bond)

    for name, element in elements.items():
        n_in, n_out = len(power_in[name]), len(power_out[name])
        where = str(element)
        if element.kind in el.ONE_PORTS and n_in + n_out != 1:
            raise ModelError(f"{where}: a one-port element needs exactly 1 bond, it has {n_in + n_out}")
        if element.kind in el.TWO_PORTS and (n_in, n_out) != (1, 1):
            raise ModelError(
                f"{where}: a two-port needs exactly one entering bond (port 1) and one leaving bond (port 2); "
                f"it has {n_in} entering and {n_out} leaving"
            )
        if element.kind in el.JUNCTIONS and n_in + n_out < 2:
            raise ModelError(f"{where}: a junction needs at least 2 power bonds, it has {n_in + n_out}")
        if element.kind in el.DETECTORS and len(sensors[name]) != 1:
            raise ModelError(f"{where}: a detector needs exactly 1 signal bond from a junction, "
                             f"it has {len(sensors[name])}")


def _check_node_names(elements) -> None:
    # Symbols are named after nodes (q_<node>, p_<node>): two nodes must not print alike.
    seen: dict[str, Hashable] = {}
    for name in elements:
        key = str(name)
        if key in seen and seen[key] != name:
            raise ModelError(f"nodes {seen[key]!r} and {name!r} have the same printed name {key!r}")
        seen[key] = name


def _check_parameters(elements) -> dict[str, float]:
    values: dict[str, float | None] = {}
    owners: dict[str, str] = {}

    def declare(name: str, value: float | None, owner: str) -> None:
        if name in values and value is not None and values[name] is not None and values[name] != value:
            raise ModelError(
                f"parameter {name!r} has conflicting values: {values[name]!r} ({owners[name]}) "
                f"and {value!r} ({owner})"
            )
        if name not in values or values[name] is None:
            values[name], owners[name] = value, owner

    intervals: dict[str, tuple] = {}
    for element in elements.values():
        if element.param is not None:
            declare(element.param, element.value, str(element))
        for name, interval in element.uncertainties.items():
            if name in intervals and intervals[name][0] != interval:
                first, owner = intervals[name]
                raise ModelError(
                    f"parameter {name!r} has conflicting uncertainty intervals: {first} ({owner}) "
                    f"and {interval} ({element})"
                )
            intervals.setdefault(name, (interval, str(element)))
    for element in elements.values():
        for name, value in element.constants.items():
            declare(name, value, f"{element} constant")
    for element in elements.values():
        used = set()
        for expression in (element.law, element.modulus):
            if expression is not None:
                used |= {s.name for s in expression.free_symbols}
        for name in sorted(used - {"e", "f", "q", "p", "t"}):
            if values.get(name) is None:
                raise ModelError(f"{element}: parameter {name!r} used in its law or modulus has no value")
    return {name: value for name, value in values.items() if value is not None}


def parameter_domains(elements: Mapping[Hashable, Element], parameters: Mapping[str, float]
                      ) -> dict[str, tuple[float, float]]:
    """The open interval ``(lo, hi)`` of each parameter: the intersection of the domains its elements give it.

    A parameter shared by several elements (a constant used by several laws) lies in all their
    domains; :func:`bondgraph.domains.bounds` turns the domain into an interval.

    Raises
    ------
    ModelError
        naming the parameter and two elements whose domains share no value.
    """
    domains: dict[str, tuple[str, str]] = {}  # parameter -> (domain, who said so)
    for element in elements.values():
        declared = [(element.param, element.domain, str(element))] if element.param is not None else []
        declared += [(c, d, f"{element} constant") for c, d in element.constant_domains.items()]
        for name, domain, owner in declared:
            if name not in domains:
                domains[name] = (domain, owner)
                continue
            common = intersect(domains[name][0], domain)
            if common is None:
                raise ModelError(f"parameter {name!r} has conflicting domains: {describe(domains[name][0])} "
                                 f"({domains[name][1]}) and {describe(domain)} ({owner})")
            domains[name] = (common, f"{domains[name][1]} and {owner}")
    return {name: bounds(domains[name][0], value) for name, value in parameters.items()}


def _check_signals(elements, parameters) -> None:
    inputs: dict[str, Hashable] = {}
    constant: dict[str, tuple[float, Hashable]] = {}
    measured: dict[str, Hashable] = {}
    for name, element in elements.items():
        if element.kind in el.DETECTORS:
            if element.signal in measured:
                raise ModelError(
                    f"{element}: signal {element.signal!r} is already measured by detector {measured[element.signal]!r}"
                )
            measured[element.signal] = name
        elif element.signal is not None:
            inputs.setdefault(element.signal, name)
            if element.kind in el.SOURCES and element.value is not None:
                previous = constant.get(element.signal)
                if previous is not None and previous[0] != element.value:
                    raise ModelError(
                        f"{element}: input {element.signal!r} has value {element.value!r}, "
                        f"but source {previous[1]!r} gives it {previous[0]!r}"
                    )
                constant[element.signal] = (element.value, name)
    for signal, node in measured.items():
        if signal in inputs:
            raise ModelError(
                f"signal {signal!r} is both an input (at {inputs[signal]!r}) and a measurement (detector {node!r})"
            )
    for signal, node in {**inputs, **measured}.items():
        if signal in parameters:
            raise ModelError(f"name {signal!r} is both a signal (at {node!r}) and a parameter")
    for element in elements.values():
        if element.modulus is not None and element.kind in el.MODULATED_TWO_PORTS:
            names = {type(f).__name__ for f in element.modulus.atoms(sp.core.function.AppliedUndef)}
            if names - set(inputs):
                raise ModelError(f"{element}: modulus uses unknown signal(s) {sorted(names - set(inputs))}")
