"""Structural analysis of a bond graph's equations: redundancy, minimal overdetermined sets, fault signatures.

Which analytical redundancy exists does not depend on the values of the parameters, only on which
unknowns each equation holds.  The equations are those of
:func:`bondgraph.equations.labelled_equations` (sources, element laws, storage, two-ports, junctions,
sensors); the unknowns are the bond variables and the energy variables of storage elements, a state
and its time derivative counting as one unknown (mixed causality: an ARR may integrate or
differentiate); the known variables are the input and measured signals.

A set of equations is *structurally overdetermined* when it holds more equations than unknowns in
every part.  The Dulmage-Mendelsohn decomposition of the bipartite graph of equations and unknowns
gives the overdetermined part ``M+`` of any set (the equations reachable from an unmatched equation
by alternating paths of a maximum matching), and its redundancy ``|M+| - |unknowns of M+|``.
Every ARR a model allows comes from an overdetermined set; the *minimal* ones (MSO sets, redundancy
one; Krysander et al. (2008)) are the smallest ARRs, and together they reach every
detectability and isolability the structure allows:

* a fault is detectable when one of its equations lies in ``M+`` of the whole model;
* fault ``a`` is isolable from fault ``b`` when one of ``a``'s equations lies in ``M+`` of the
  model without ``b``'s equations.

Faults are the element parameters (each acts on the equations that hold it) and, by default, one
fault per sensor (a bias or drift acting on its read-out equation).

Examples
--------
A DC motor with its speed sensor only has one redundant relation, and it sees every parameter:

>>> from bondgraph import BondGraph
>>> from bondgraph.library import dc_motor
>>> graph = dc_motor().graph.copy()
>>> graph.remove_node("i")   # no current sensor
>>> model = structural_model(BondGraph(graph))
>>> model.redundancy()
1
>>> sorted(model.detectable())
['J', 'L_a', 'R_a', 'b', 'k_m', 'sensor omega']
>>> [len(m) for m in model.mso_sets()]
[17]
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property

import networkx as nx
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph.equations import ModelEquation, effort, energy_variable, flow, labelled_equations
from bondgraph.errors import PHMError
from bondgraph.structure import Structure, require_model

__all__ = ["MSO_SEARCH_LIMIT", "StructuralLimitError", "StructuralModel", "sensor_fault", "structural_model"]

#: The most overdetermined subsets :meth:`StructuralModel.mso_sets` explores before it gives up.
MSO_SEARCH_LIMIT = 20000


class StructuralLimitError(PHMError, ValueError):
    """The search for minimal overdetermined sets went over its limit (the model is too large for the full set)."""


@dataclass(frozen=True)
class StructuralModel:
    """The structure of a model's equations: which unknowns each holds, which faults act on it.

    Attributes
    ----------
    equations : tuple of ModelEquation
        The equations, with the node and role each comes from.
    unknowns : tuple of frozenset
        The unknowns of each equation (bond variables ``e_k``, ``f_k`` and energy variables).
    faults : dict
        Fault name -> the indices of the equations it acts on: an element parameter by its name,
        a sensor as ``"sensor <signal>"`` (:func:`sensor_fault`).
    """

    equations: tuple[ModelEquation, ...]
    unknowns: tuple[frozenset, ...]
    faults: dict

    @property
    def all(self) -> frozenset:
        """The indices of every equation."""
        return frozenset(range(len(self.equations)))

    def overdetermined(self, equations: Iterable[int] | None = None) -> frozenset:
        """``M+``: the structurally overdetermined part of ``equations`` (all of them by default)."""
        equations = self.all if equations is None else frozenset(equations)
        owner: dict = {}   # unknown -> the equation matched to it
        spare = [i for i in sorted(equations) if not self._matched(i, owner)]
        # alternating paths from the unmatched equations: any edge to an unknown, the matched edge back
        reached, frontier = set(spare), list(spare)
        while frontier:
            row = frontier.pop()
            for unknown in self.unknowns[row]:
                partner = owner.get(unknown)
                if partner is not None and partner not in reached:
                    reached.add(partner)
                    frontier.append(partner)
        return frozenset(reached)

    def _matched(self, root: int, owner: dict) -> bool:
        """Match equation ``root`` to an unknown of its own, by an augmenting path if need be (Kuhn (1955),
        iterative); ``owner`` (unknown -> equation) is updated.  False if no path frees an unknown for it.

        M+ does not depend on which maximum matching is found, so the order unknowns are tried in is free.
        """
        free = next((x for x in self.unknowns[root] if x not in owner), None)
        if free is not None:
            owner[free] = root
            return True
        visited: set = set()
        stack, path = [(root, iter(self.unknowns[root]))], []
        while stack:
            row, untried = stack[-1]
            for x in untried:
                if x in visited:
                    continue
                visited.add(x)
                path.append((row, x))
                if x not in owner:   # each equation on the path takes the unknown it was left by
                    owner.update({u: r for r, u in path})
                    return True
                stack.append((owner[x], iter(self.unknowns[owner[x]])))
                break
            else:
                stack.pop()
                if path:
                    path.pop()
        return False

    def redundancy(self, equations: Iterable[int] | None = None) -> int:
        """Equations minus unknowns of the overdetermined part of ``equations``: how many ARRs are independent."""
        return self._excess(self.overdetermined(equations))

    def _excess(self, part: frozenset) -> int:
        """Equations minus unknowns of a set that is already its own overdetermined part."""
        return len(part) - len(frozenset().union(*(self.unknowns[i] for i in part)))

    def mso_sets(self, equations: Iterable[int] | None = None, *, keep: frozenset | None = None,
                 limit: int = MSO_SEARCH_LIMIT, budget: dict | None = None) -> list[frozenset]:
        """Every minimal structurally overdetermined subset of ``equations`` (all by default), smallest first.

        Each overdetermined set of redundancy above one is reduced by removing one equation at a
        time and taking the overdetermined part of the rest; sets already seen are not explored
        again.  With ``keep``, only sets holding one of those equations are explored.  Raises
        :class:`StructuralLimitError` after ``limit`` sets, or when ``budget["equations"]`` (shared by
        several searches, decremented by the size of each set explored: its cost) runs out.
        """
        found, seen = set(), set()
        stack = [self.overdetermined(equations)]
        while stack:
            current = stack.pop()
            if current in seen or not current or (keep is not None and not current & keep):
                continue
            seen.add(current)
            if budget is not None:
                budget["equations"] -= len(current)
                if budget["equations"] < 0:
                    raise StructuralLimitError("structural analysis: the shared budget of overdetermined subsets "
                                               "is spent")
            if len(seen) > limit:
                raise StructuralLimitError(f"structural analysis: more than {limit} overdetermined subsets; "
                                           "the full set of minimal ones is out of reach for this model")
            if self._excess(current) == 1:  # current is an M+ already: no second matching
                found.add(current)
                continue
            stack.extend(self.overdetermined(current - {i}) for i in current)
        return sorted(found, key=lambda m: (len(m), sorted(m)))

    def detectable(self) -> set:
        """The faults whose equations reach the overdetermined part of the whole model."""
        part = self._whole
        return {fault for fault, rows in self.faults.items() if rows & part}

    def isolable(self, fault: str, other: str) -> bool:
        """Whether ``fault`` can be told from ``other``: it acts on ``M+`` of the model without ``other``."""
        return self.reaches(self.faults[fault], self.faults[other])

    def isolability(self) -> dict:
        """Fault -> the faults it can be told from (every pair of :meth:`isolable`)."""
        return {a: {b for b in self.faults if b != a and self.isolable(a, b)} for a in self.faults}

    def reaches(self, rows: frozenset, removed: frozenset = frozenset()) -> bool:
        """Whether one of ``rows`` lies in ``M+`` of the model without the equations ``removed``.

        Local: the maximum matching of the whole model is repaired where ``removed`` freed an unknown
        (an augmenting path to a spare equation), then an alternating path is sought backwards from
        ``rows`` to an unmatched equation.  On a long chain both stay near ``rows``, where a fresh
        Dulmage-Mendelsohn decomposition would visit the whole model.
        """
        row_of, unknown_of = dict(self._matching[0]), dict(self._matching[1])
        for r in removed:
            x = unknown_of.pop(r, None)
            if x is not None:
                del row_of[x]
                self._augment(x, row_of, unknown_of, removed)
        seen, stack = set(), [r for r in rows if r not in removed]
        while stack:
            r = stack.pop()
            if r in seen:
                continue
            seen.add(r)
            x = unknown_of.get(r)
            if x is None:
                return True
            stack.extend(e for e in self._holders[x] if e not in removed and e not in seen)
        return False

    def _augment(self, free: str, row_of: dict, unknown_of: dict, removed: frozenset) -> None:
        """Match the unknown ``free`` by an augmenting path to an unmatched equation, if there is one."""
        found_by = {}   # equation -> the unknown whose equations were being scanned when it was reached
        queue, queued = [free], {free}
        for x in queue:
            for r in self._holders[x]:
                if r in removed or r in found_by:
                    continue
                found_by[r] = x
                y = unknown_of.get(r)
                if y is None:  # r is spare: shift the matching along the path back to ``free``
                    while x is not None:
                        previous = row_of.get(x)
                        row_of[x], unknown_of[r] = r, x
                        r, x = previous, (found_by[previous] if previous is not None else None)
                    return
                if y not in queued:
                    queued.add(y)
                    queue.append(y)

    @cached_property
    def _holders(self) -> dict:
        """Unknown -> the equations that hold it."""
        holders: dict = {}
        for i, unknowns in enumerate(self.unknowns):
            for x in unknowns:
                holders.setdefault(x, []).append(i)
        return holders

    @cached_property
    def _matching(self) -> tuple[dict, dict]:
        """A maximum matching of the whole model: (unknown -> equation, equation -> unknown)."""
        graph = self._bipartite(self.all)
        matching = nx.bipartite.hopcroft_karp_matching(graph, top_nodes=[("equation", i) for i in self.all])
        pairs = [(x, i) for (kind, x), (_, i) in matching.items() if kind == "unknown"]
        return {x: i for x, i in pairs}, {i: x for x, i in pairs}

    @cached_property
    def _whole(self) -> frozenset:
        return self.overdetermined()

    def _bipartite(self, equations: frozenset) -> nx.Graph:
        graph = nx.Graph()
        graph.add_nodes_from(("equation", i) for i in equations)
        graph.add_edges_from((("equation", i), ("unknown", x)) for i in equations for x in self.unknowns[i])
        return graph

    def msos_through(self, rows: frozenset, removed: frozenset = frozenset(), limit: int = 200,
                     budget: dict | None = None, reach: int = 1) -> list[frozenset]:
        """Minimal overdetermined sets that hold one of ``rows`` and none of ``removed``, found near ``rows``.

        The search looks in the equations within a growing distance of ``rows`` until one of them is
        overdetermined there, then ``reach`` steps further, and reduces that neighbourhood to minimal sets
        keeping one of ``rows`` (at most ``limit`` subsets explored, and ``budget`` as in :meth:`mso_sets`).
        Smallest sets first.
        """
        rows = frozenset(rows) - removed
        ball, found, past = set(rows), False, 0
        while True:
            found = found or bool(self.overdetermined(ball) & rows)
            wider = {e for r in ball for x in self.unknowns[r] for e in self._holders[x]} - removed
            if wider <= ball:
                break
            ball |= wider
            past += found
            if past >= reach:   # ``reach`` steps past the first neighbourhood where a row is overdetermined
                break
        part = self.overdetermined(ball)
        return self.mso_sets(part, keep=rows, limit=limit, budget=budget) if part & rows else []

    def describe(self, rows: Iterable[int]) -> list[str]:
        """``"node role"`` of each equation in ``rows``: which junctions and elements a set uses."""
        return [f"{self.equations[i].node} {self.equations[i].role}" for i in sorted(rows)]


def structural_model(bg, *, sensor_faults: bool = True) -> StructuralModel:
    """The structural model of a bond graph: its equations, their unknowns and the faults acting on them.

    Parameters
    ----------
    bg : BondGraph
        A model with De/Df detectors.
    sensor_faults : bool
        Give each sensor a fault of its own (on by default); ``False`` assumes healthy sensors.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> model = structural_model(dc_motor())
    >>> len(model.equations), model.redundancy()
    (18, 2)
    >>> model.describe(model.faults["sensor i"])
    ['i sensor']
    """
    require_model(bg, "structural_model")
    structure: Structure = bg.structure()
    equations = labelled_equations(bg)
    bonds = {b for bonds in structure.at.values() for b in bonds}
    variables = {v for b in bonds for v in (effort(b.label), flow(b.label))}
    states = {energy_variable(e): e.name for e in structure.elements.values() if e.kind in ("C", "I")}
    unknowns = tuple(_unknowns(m.equation, variables, states) for m in equations)
    holding: dict = {}  # symbol -> the equations that hold it, indexed once
    for i, m in enumerate(equations):
        for symbol in m.equation.free_symbols:
            holding.setdefault(symbol, set()).add(i)
    faults = {}
    for element in structure.elements.values():
        if element.param is not None:
            rows = frozenset(holding.get(sp.Symbol(element.param), ()))
            faults[element.param] = faults.get(element.param, frozenset()) | rows
    if sensor_faults:
        for i, m in enumerate(equations):
            if m.role == "sensor":
                faults[sensor_fault(m.equation.lhs.func.__name__)] = frozenset({i})
    return StructuralModel(tuple(equations), unknowns, faults)


def sensor_fault(signal: str) -> str:
    """The name of the fault of the sensor that reads ``signal``: a row of a signature matrix.

    >>> sensor_fault("omega_m")
    'sensor omega_m'
    """
    return f"sensor {signal}"


def _unknowns(equation: sp.Eq, variables: set, states: dict) -> frozenset:
    """Bond variables and states (a state's derivative counts as the state) of one equation."""
    found = {str(s) for s in equation.free_symbols & variables}
    found |= {f"state {states[f]}" for f in equation.atoms(AppliedUndef) if f in states}
    return frozenset(found)
