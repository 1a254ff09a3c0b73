"""Where to add sensors: the cheapest sets of detectors that reach a diagnosis goal.

A sensor on a bond graph is an effort detector on a 0-junction (its common effort) or a flow detector on a
1-junction (its common flow); the flow of one element on a 0-junction, or the effort across one on a
1-junction, is measured by a junction of the other kind inserted into the element's bond.
:func:`place_sensors` tries the detectors the model lacks, alone and together, judges each set by the
structure of the model with them (:func:`~diagnosis.structural_model`: which faults some overdetermined part
reaches, which pairs it tells apart), and returns the minimal sets (no sensor can be dropped) that reach the
goal, cheapest first, each checked by deriving the ARRs of the model with its sensors.

The goal is what every candidate together would give: ``"detect"``, every fault they would let some ARR
see; ``"isolate"``, moreover every ordered pair of faults they would tell apart.  With ``fallible=True``
(the default) a sensor can fail too: the faults of the added sensors must be detected, and the model's faults
told apart from them.

Example
-------
A DC motor with its speed sensor only: the armature current's junction gets a flow detector.

>>> from bondgraph import BondGraph
>>> from bondgraph.library import dc_motor
>>> graph = dc_motor().graph.copy()
>>> graph.remove_node("i")
>>> [p.sensors for p in place_sensors(BondGraph(graph), goal="isolate", check=False)]
[('Df 1_e',)]
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations

from bondgraph import BondGraph
from bondgraph.errors import SettingError

from .derivation import derive_arrs
from .signatures import signature_matrix
from .structural import sensor_fault, structural_model

__all__ = ["GOALS", "SensorPlacement", "element_detectors", "junction_detectors", "place_sensors", "with_sensors"]

#: The goals :func:`place_sensors` can reach.
GOALS = ("detect", "isolate")


@dataclass(frozen=True)
class SensorPlacement:
    """One set of sensors to add.

    Attributes
    ----------
    sensors : tuple of str
        The detectors, as ``"De 0_2"`` (the effort of 0-junction ``0_2``) or ``"Df 1_13"``.
    cost : float
    detects : frozenset
        The faults the structure then lets some ARR see.
    isolates : frozenset
        The ordered pairs ``(a, b)`` it then tells apart (``a`` acts where ``b`` does not).
    derived : dict or None
        The check by the ARRs themselves (``check=True``): ``detects`` and ``isolates`` as above, read
        from the signature matrix of :func:`~diagnosis.derive_arrs` of the model with the sensors.
    """

    sensors: tuple
    cost: float
    detects: frozenset
    isolates: frozenset
    derived: dict | None = None

    def model(self, bg) -> BondGraph:
        """``bg`` with these sensors added (a new model)."""
        return with_sensors(bg, self.sensors)


def place_sensors(bg, *, goal: str = "isolate", faults: Sequence[str] | None = None,
                  cost: Mapping[str, float] | None = None, fallible: bool = True, max_sensors: int = 3,
                  check: bool = True, max_order: int | str | None = None,
                  inside_elements: bool = False) -> list[SensorPlacement]:
    """The minimal sets of detectors, cheapest first, that reach ``goal``.

    Parameters
    ----------
    bg : BondGraph
    goal : {"detect", "isolate"}
        What every candidate together would give of detection, or of detection and isolation, of ``faults``.
    faults : sequence of str, optional
        The faults the goal is about (parameters, ``"sensor <signal>"``); default every parameter and, with
        ``fallible``, every sensor of the model.  The added sensors' own faults count too when ``fallible``.
    cost : mapping, optional
        Detector (``"De 0_2"``) -> its cost; default 1 each.
    fallible : bool
        Whether sensors can fail (each reading is a fault of its own).
    max_sensors : int
        The most detectors a set may add.
    check : bool
        Derive the ARRs of the model with each returned set and record what they achieve.
    max_order : int, "auto" or None
        The derivative bound of that derivation (:func:`~diagnosis.derive_arrs`); default None, no bound: the
        check asks whether every structural promise has an ARR, whatever its order.
    inside_elements : bool
        Also try detectors inside elements' bonds (:func:`element_detectors`): the flow through one valve of a
        tank, the torque of one friction.  Off by default: a junction detector is a sensor on a shared
        variable, the kind a plant already has taps for.

    Returns
    -------
    list of SensorPlacement
        Empty when the model already reaches the goal.

    Raises
    ------
    SettingError
        An unknown goal, fault or detector, ``max_sensors`` below 1, or no set of at most ``max_sensors``
        detectors that reaches the goal.
    """
    if goal not in GOALS:
        raise SettingError("goal", f"{{setting}} must be one of {', '.join(GOALS)}, got {goal!r}")
    if not (isinstance(max_sensors, int) and max_sensors >= 1):
        raise SettingError("max_sensors", f"{{setting}} must be a whole number >= 1, got {max_sensors!r}")
    candidates = junction_detectors(bg) + (element_detectors(bg) if inside_elements else [])
    prices = {c: 1.0 for c in candidates}
    for name, value in (cost or {}).items():
        if name not in prices:
            raise SettingError("cost", f"{{setting}}: {name!r} is not a detector the model lacks (candidates: "
                                       f"{', '.join(candidates) or 'none'})")
        prices[name] = float(value)
    base = structural_model(bg, sensor_faults=fallible)
    wanted = set(base.faults) if faults is None else set(faults)
    unknown = sorted(wanted - set(base.faults))
    if unknown:
        raise SettingError("faults", f"{{setting}}: the model has no fault {unknown[0]!r}")
    best = _reach(with_sensors(bg, candidates), wanted | _own_faults(candidates, fallible), goal)
    found = []
    for size in range(0, min(max_sensors, len(candidates)) + 1):
        for chosen in combinations(candidates, size):
            if any(set(f.sensors) <= set(chosen) for f in found):
                continue  # a superset of a set that reaches the goal is not minimal
            aims = wanted | _own_faults(chosen, fallible)
            detects, isolates = _reach(with_sensors(bg, chosen), aims, goal)
            # the model's faults told apart as far as every candidate would, and from the added sensors'
            # faults; an added sensor's own fault need only be detected
            target_detects = best[0] & aims
            target_isolates = {(a, b) for a, b in best[1] if a in wanted and b in aims}
            if target_detects <= detects and target_isolates <= isolates:
                found.append(SensorPlacement(chosen, sum(prices[c] for c in chosen), frozenset(detects),
                                             frozenset(isolates)))
    if any(not f.sensors for f in found):
        return []  # the model as it is reaches the goal
    if not found:
        raise SettingError("max_sensors", f"{{setting}}: no set of at most {max_sensors} of the {len(candidates)} "
                                          f"detectors the model lacks reaches the goal ({goal}); allow more")
    found.sort(key=lambda f: (f.cost, len(f.sensors), f.sensors))
    return [_checked(bg, f, fallible, max_order) for f in found] if check else found


def junction_detectors(bg) -> list[str]:
    """The detectors the model lacks: an effort detector per 0-junction, a flow detector per 1-junction."""
    graph = bg.graph
    kinds = {n: str(d.get("kind")) for n, d in graph.nodes(data=True)}
    lacking = []
    for junction, kind in kinds.items():
        wanted = {"0": "De", "1": "Df"}.get(kind)
        if wanted and not any(kinds[n] == wanted for n in (*graph.successors(junction), *graph.predecessors(junction))):
            lacking.append(f"{wanted} {junction}")
    return lacking


def element_detectors(bg) -> list[str]:
    """Detectors inside the bond of a one-port element (R, C, I) that no junction detector can be: the flow
    of an element on a 0-junction (``"Df az2"``), the effort across one on a 1-junction (``"De R_a"``).

    :func:`with_sensors` places one by inserting a junction of the other kind into the element's bond.
    """
    graph = bg.graph
    kinds = {n: str(d.get("kind")) for n, d in graph.nodes(data=True)}
    found = []
    for element, kind in kinds.items():
        if kind not in ("R", "C", "I"):
            continue
        (neighbour, *more) = [*graph.predecessors(element), *graph.successors(element)] or [None]
        wanted = {"0": "Df", "1": "De"}.get(kinds.get(neighbour))
        if wanted and not more:
            found.append(f"{wanted} {element}")
    return found


def with_sensors(bg, sensors: Sequence[str]) -> BondGraph:
    """A copy of ``bg`` with the detectors ``sensors``: on a junction (``"De 0_2"``) bonded to it, in an
    element's bond (``"Df az2"``) on a junction inserted into that bond (``1_az2``, power in the bond's
    direction)."""
    model = BondGraph(bg.graph.copy(), name=bg.name)
    for sensor in sensors:
        kind, node = sensor.split(" ", 1)
        name = _signal(sensor)
        if str(model.graph.nodes[node].get("kind")) not in ("0", "1"):
            node = _inserted_junction(model, node, "1" if kind == "Df" else "0")
        model.add(name, kind)
        model.bond(node, name)
    return model


def _inserted_junction(model: BondGraph, element: str, kind: str) -> str:
    """A ``kind`` junction put into the one bond of ``element``, keeping the bond's direction; its name."""
    graph = model.graph
    junction = f"{kind}_{element}"
    if junction in graph:
        raise SettingError("sensors", f"{{setting}}: a node {junction!r} exists already; cannot insert a junction "
                                      f"into the bond of {element!r}")
    tail, head = next(iter([*graph.in_edges(element), *graph.out_edges(element)]))
    attributes = dict(graph.edges[tail, head])
    graph.remove_edge(tail, head)
    model.add(junction, kind)
    model.bond(tail, junction, **attributes)   # the original bond keeps its label, on its tail's side
    model.bond(junction, head)
    return junction


def _signal(sensor: str) -> str:
    kind, node = sensor.split(" ", 1)
    return f"{'e' if kind == 'De' else 'f'}_{node}"


def _own_faults(sensors, fallible: bool) -> set:
    return {sensor_fault(_signal(s)) for s in sensors} if fallible else set()


def _reach(model: BondGraph, faults: set, goal: str) -> tuple[set, set]:
    """The faults of ``faults`` the structure of ``model`` detects, and (goal ``isolate``) the ordered pairs
    of them it tells apart."""
    structure = structural_model(model, sensor_faults=any(f.startswith("sensor ") for f in faults))
    detects = {f for f in structure.detectable() if f in faults}
    if goal == "detect":
        return detects, set()
    isolates = {(a, b) for a in detects for b in faults if a != b and b in structure.faults
                and structure.isolable(a, b)}
    return detects, isolates


def _checked(bg, placement: SensorPlacement, fallible: bool, max_order) -> SensorPlacement:
    """``placement`` with what the ARRs of the model with its sensors achieve."""
    arrs = derive_arrs(with_sensors(bg, placement.sensors), max_order=max_order, sensor_faults=fallible)
    signatures = signature_matrix(arrs, sensor_faults=fallible)
    seen = {row: {c for c, v in zip(signatures.columns, signatures.matrix[i]) if v}
            for i, row in enumerate(signatures.rows)}
    detects = {f for f, arrs in seen.items() if arrs}
    isolates = {(a, b) for a in detects for b in seen if a != b and seen[a] - seen[b]}
    return SensorPlacement(placement.sensors, placement.cost, placement.detects, placement.isolates,
                           {"detects": frozenset(detects), "isolates": frozenset(isolates)})
