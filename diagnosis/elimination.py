"""ARRs from minimal overdetermined sets: eliminate the unknowns along a matching, keep the BG-LFT split.

:func:`derive_arrs <diagnosis.arrs.derive_arrs>` writes one ARR per sensor junction along causal
paths, and misses the redundancy that needs an unknown taken from elsewhere (the current of a motor
from its mechanical balance, say).  :func:`structural_arrs` adds ARRs from the minimal overdetermined
sets of :mod:`diagnosis.structural`, chosen greedily until the set reaches the detectability and
isolability the structure allows.  In each set one junction balance is kept as the residual; every
other equation is solved for the unknown a matching gives it, in the order of the matching's
dependency graph (an algebraic loop solved as one block).  The matching prefers derivative causality:
a state is taken from its element's law when it can be, so the ARR needs derivatives of measured
signals rather than integrals that drift with their noise.  The same elimination on the model with
theta (1 + delta_theta) gives Psi_2, split per parameter as in ``derive_arrs``.

Examples
--------
A DC motor with its speed sensor only: no junction ARR exists, the structure gives one through the
gyrator, with the current taken from the mechanical balance:

>>> import sympy as sp
>>> from bondgraph import BondGraph
>>> from bondgraph.library import dc_motor
>>> graph = dc_motor().graph.copy()
>>> graph.remove_node("i")
>>> (arr,) = structural_arrs(BondGraph(graph), existing=[])
>>> sorted(arr.parameters)   # U = R_a i + L_a di/dt + k_m omega, i = (J domega/dt + b omega) / k_m
['J', 'L_a', 'R_a', 'b', 'k_m']
>>> sorted(str(d) for d in arr.nominal.atoms(sp.Derivative))
['Derivative(omega(t), (t, 2))', 'Derivative(omega(t), t)']
>>> arr.origin[:3]
('U source', '1_e common', '1_e common')
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence

import networkx as nx
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph.equations import labelled_equations
from bondgraph.structure import T

from .arrs import (ARR, ARRWarning, candidate_parameters, derive_arrs, parameter_intervals, split_relation,
                   uncertain_structure)
from .structural import StructuralModel, structural_model


class _StructureOnly:
    """A bond-graph-like object over a given structure (the model with theta -> theta (1 + delta_theta))."""

    def __init__(self, name: str, structure) -> None:
        self.name, self._structure = name, structure

    def structure(self):
        return self._structure


def structural_arrs(bg, *, existing: Sequence[ARR] | None = None, sensor_faults: bool = True) -> list[ARR]:
    """ARRs from minimal overdetermined sets that add detectability or isolability to ``existing``.

    Parameters
    ----------
    bg : BondGraph
    existing : sequence of ARR, optional
        The ARRs already in use (``derive_arrs(bg)`` when omitted).
    sensor_faults : bool
        Count a fault per sensor in the signatures the selection improves.

    Returns
    -------
    list of ARR
        The added ARRs, each with ``origin`` naming the equations (node and role) it comes from.

    Notes
    -----
    The sets are tried smallest first; one is kept when the faults it sees detect a fault no kept
    ARR sees, or tell apart a pair of faults no kept ARR tells apart.
    """
    existing = derive_arrs(bg) if existing is None else existing
    model = structural_model(bg, sensor_faults=sensor_faults)
    shared = _Shared.of(bg, model)
    supports = [_faults_of_arr(model, arr) for arr in existing]
    added, skipped = [], []
    for index, rows in enumerate(model.mso_sets()):
        support = {fault for fault, fault_rows in model.faults.items() if fault_rows & rows}
        if not _improves(supports, support, model.faults):
            continue
        name = f"ARR_MSO_{index + 1}"
        try:
            arr = shared.arr(rows, name)
        except (NotImplementedError, ValueError):  # see the warning below
            skipped.append(name)
            continue
        supports.append(support)
        added.append(arr)
    if skipped:
        warnings.warn(f"{len(skipped)} overdetermined set(s) could not be eliminated to known signals (a law "
                      f"without explicit inverse, or a loop only an ODE of the set closes): {', '.join(skipped)}",
                      ARRWarning, stacklevel=2)
    return added


def arr_from_set(bg, rows, *, model: StructuralModel | None = None, name: str = "ARR_MSO") -> ARR:
    """The ARR of one overdetermined set of equations of ``bg`` (indices into ``model.equations``)."""
    return _Shared.of(bg, structural_model(bg) if model is None else model).arr(frozenset(rows), name)


@dataclasses.dataclass(frozen=True)
class _Shared:
    """What the eliminations of every set of one model share, computed once."""

    model: StructuralModel
    structure: object
    nominal: list
    true: list
    signals: set
    unknowns: set

    @classmethod
    def of(cls, bg, model: StructuralModel) -> _Shared:
        structure = bg.structure()
        uncertain = _StructureOnly(bg.name, uncertain_structure(structure))
        signals = {f.func.__name__ for m in model.equations if m.role in ("source", "sensor")
                   for f in m.equation.atoms(AppliedUndef)}
        return cls(model, structure, [m.equation for m in model.equations],
                   [m.equation for m in labelled_equations(uncertain)], signals, set().union(*model.unknowns))

    def arr(self, rows: frozenset, name: str) -> ARR:
        model = self.model
        found = _residual(model, self.nominal, rows, self.signals, self.unknowns)
        if found is None:
            raise ValueError(f"no junction balance of the set leaves a residual in known signals "
                             f"({', '.join(model.describe(rows))})")
        residual, assigned, r_n = found
        r_true = _eliminate(model, self.true, assigned, residual)
        arr = split_relation(name, model.equations[residual].node, None, r_n, r_true, (), self.structure,
                             candidate_parameters(self.structure), parameter_intervals(self.structure))
        return dataclasses.replace(arr, origin=tuple(model.describe(rows)))


class _DifferentialLoop(Exception):
    """A block of the matching holds a state: only an ODE of the set, not an elimination, would give it."""

    def __init__(self, states: frozenset):
        super().__init__(f"states {sorted(states)} in a loop")
        self.states = states


def _residual(model: StructuralModel, equations: list, rows: frozenset, signals: set, unknowns: set,
              attempts: int = 4):
    """(residual row, matching, nominal residual) for the first junction balance that leaves known signals only.

    A state that ends up in a loop of the matching is tried again in integral causality (from its storage
    equation), which breaks the loop when the state's rate is known from outside it.
    """
    balances = [i for i in sorted(rows) if model.equations[i].role == "balance"] or sorted(rows)
    for residual in balances:
        integral: frozenset = frozenset()
        for _ in range(attempts):
            assigned = _matching(model, rows - {residual}, integral)
            try:
                r_n = _eliminate(model, equations, assigned, residual)
            except _DifferentialLoop as loop:
                if loop.states <= integral:
                    break
                integral |= loop.states
                continue
            except (NotImplementedError, ValueError):
                break
            if _in_known_signals(r_n, signals, unknowns):
                return residual, assigned, r_n
            break
    return None


def _matching(model: StructuralModel, rows: frozenset, integral: frozenset = frozenset()) -> dict:
    """Equation -> the unknown it is solved for.

    A state comes from its law (derivative causality) unless it is in ``integral``; an unknown that enters
    its equation non-linearly is matched to it only as a last resort.
    """
    graph = nx.Graph()
    top = [("equation", i) for i in rows]
    graph.add_nodes_from(top)
    symbols = _unknown_symbols([m.equation for m in model.equations], dict.fromkeys(rows))
    for i in rows:
        equation = model.equations[i].equation
        expression = equation.lhs - equation.rhs
        storage = model.equations[i].role == "storage"
        for x in model.unknowns[i]:
            # an unknown entering non-linearly (a valve law solved for its pressure) only as a last resort;
            # a storage equation gives its state by integration, whatever the form of its rate
            slope = sp.diff(expression, symbols[x])
            weight = 1 if storage or (slope != 0 and not slope.has(symbols[x])) else 10
            if x.startswith("state "):
                wanted_from_storage = x[len("state "):] in integral
                weight += 0 if storage == wanted_from_storage else 4 if wanted_from_storage else 1
            graph.add_edge(("equation", i), ("unknown", x), weight=weight)
    matching = nx.bipartite.minimum_weight_full_matching(graph, top_nodes=top)
    return {i: matching[("equation", i)][1] for i in rows}


def _eliminate(model: StructuralModel, equations: list, assigned: dict, residual: int) -> sp.Expr:
    """The residual equation with every unknown of ``assigned`` replaced by its value in known signals."""
    owner = {x: i for i, x in assigned.items()}
    order = nx.DiGraph()
    order.add_nodes_from(assigned)
    order.add_edges_from((owner[x], i) for i in assigned for x in model.unknowns[i] if x != assigned[i])
    blocks = nx.condensation(order)
    symbols = _unknown_symbols(equations, assigned)
    solution: dict = {}
    for block in nx.topological_sort(blocks):
        members = sorted(blocks.nodes[block]["members"])
        targets = [symbols[assigned[i]] for i in members]
        states = frozenset(model.equations[i].node for i in members
                           if model.equations[i].role in ("storage", "law")
                           and isinstance(symbols[assigned[i]], AppliedUndef))
        looped = {model.equations[i].node for i in members if model.equations[i].role == "storage"}
        if len(members) > 1 and (states or looped):
            raise _DifferentialLoop(states | looped)
        equations_here = [_substituted(equations[i], solution) for i in members]
        if len(members) == 1 and model.equations[members[0]].role == "storage" and isinstance(targets[0], AppliedUndef):
            # integral causality: the state is the integral of its rate from the start of the record
            equation = equations_here[0]
            rate = equation.rhs if isinstance(equation.lhs, sp.Derivative) else equation.lhs
            solution[targets[0]] = sp.Integral(rate, (T, 0, T))
            continue
        found = sp.solve([e.lhs - e.rhs for e in equations_here], targets, dict=True)
        if len(found) != 1:
            raise ValueError(f"{[model.describe([i])[0] for i in members]}: no unique solution for {targets}")
        solution.update(found[0])
    equation = _substituted(equations[residual], solution)
    return equation.lhs - equation.rhs


def _in_known_signals(expression: sp.Expr, signals: set, unknowns: set) -> bool:
    """Whether ``expression`` holds none of the ``unknowns`` (bond variables) and no function of time but signals."""
    functions = {f.func.__name__ for f in expression.atoms(AppliedUndef)}
    return functions <= signals and not {str(v) for v in expression.free_symbols} & unknowns


def _unknown_symbols(equations: list, assigned: dict) -> dict:
    """Structural unknown name -> its sympy object (bond variable symbol or state function)."""
    found = {}
    for i in assigned:
        found.update({str(s): s for s in equations[i].free_symbols})
        found.update({f"state {f.func.__name__[2:]}": f for f in equations[i].atoms(AppliedUndef)})
    return found


def _substituted(equation: sp.Eq, solution: dict) -> sp.Eq:
    """``equation`` with solved unknowns replaced, a state's derivative by the derivative of its value."""
    derivatives = {d: sp.diff(solution[d.expr], T, d.derivative_count)
                   for d in equation.atoms(sp.Derivative) if d.expr in solution}
    return equation.xreplace(derivatives).xreplace(solution)


def _faults_of_arr(model: StructuralModel, arr: ARR) -> set:
    """The faults an ARR sees: its parameters and the sensors of the signals it reads."""
    sensors = {m.equation.lhs.func.__name__: f"sensor {m.node}" for m in model.equations if m.role == "sensor"}
    seen = {p for p in arr.parameters if p in model.faults}
    return seen | {sensors[s] for s in arr.signals if s in sensors and sensors[s] in model.faults}


def _improves(supports: list, support: set, faults: dict) -> bool:
    """Whether a residual seeing ``support`` detects or isolates something the ``supports`` do not."""
    seen = set().union(*supports) if supports else set()
    if support - seen:
        return True
    for a in support:
        for b in faults:
            if b not in support and not any(a in s and b not in s for s in supports):
                return True
    return False
