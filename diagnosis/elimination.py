"""ARRs from minimal overdetermined sets: eliminate the unknowns along a matching, keep the BG-LFT split.

:func:`junction_arrs <diagnosis.junctions.junction_arrs>` writes one ARR per sensor junction along
causal paths, and misses the redundancy that needs an unknown taken from elsewhere (the current of a
motor from its mechanical balance, say).  :func:`structural_arrs` adds ARRs from the minimal
overdetermined sets of :mod:`diagnosis.structural`, one for each fault the ARRs in hand cannot detect
and each pair of faults they cannot tell apart while the structure can (a greedy selection: the sets
are sought near the fault, and the one of lowest derivative order, then smallest, is kept).

In each set one junction balance is kept as the residual; every other equation is solved for the
unknown a matching gives it, in the order of the matching's dependency graph (an algebraic loop
solved as one block).  The matching prefers derivative causality: a state is taken from its element's
law when it can be, so the ARR needs derivatives of measured signals rather than integrals that drift
with their noise.  The same elimination on the model with theta (1 + delta_theta) gives Psi_2, split
per parameter as for the junction ARRs.

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
>>> arr.derivatives, arr.form
({'U': 0, 'omega': 2}, 'elimination')
>>> arr.origin[:3]
('U source', '1_e common', '1_e common')
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence
from functools import cached_property

import networkx as nx
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph.calculus import real_parts, time_derivative
from bondgraph.equations import labelled_equations
from bondgraph.errors import LawError
from bondgraph.laws import signed_power_inverse, solve_for
from bondgraph.structure import T, require_model

from .junctions import junction_arrs
from .arr import (ARR, ARRWarning, candidate_parameters, check_integral_form, measured_signals,
                       parameter_intervals, split_relation, uncertain_structure, written_without_integrals)
from ._operator_elimination import operator_order, operator_residual
from ._set_shapes import SetShape, Shapes, rewritten
from .deltas import delta_parameter
from .simulation_residuals import SimulationARR
from .structural import StructuralLimitError, StructuralModel, sensor_fault, structural_model

__all__ = [
    "BUDGET_FAULTS", "MAX_ELIMINATIONS", "MAX_OPERATIONS", "MAX_ORDER", "MAX_SEARCHES",
    "MAX_SEARCH_EQUATIONS", "REACHES", "EXPLAINED", "arr_from_set", "distinct_operations", "faults_of_arr",
    "structural_arrs", "unreached",
]

#: The default bound on the derivatives an ARR added for isolation may need: as high as the ARRs the model
#: needs anyway (its junction ARRs and those added for detection), no higher.  A second derivative of a
#: sampled signal is only as good as the sampling resolves the signal's fastest transient; an ARR that
#: asks more of the data than detection does would trade false alarms for isolation.
MAX_ORDER = "auto"

#: The work one derivation spends on added ARRs, counted (not timed, so that the outcome does not depend
#: on the machine), for a model of :data:`BUDGET_FAULTS` fault candidates and in proportion to the fault
#: candidates of a larger one: equations of the sets it eliminates (a sympy elimination costs about a
#: second per fifty equations of a long chain, and more as the derivatives it needs grow with the set; a
#: set of the same shape as one eliminated before costs nothing, :mod:`diagnosis._set_shapes`) and gaps
#: searched for minimal sets (each a structural search near the fault).  Past either, the ARRs found so
#: far are returned and an ARRWarning says where the search stopped.
MAX_ELIMINATIONS = 500
MAX_SEARCHES = 60
#: The equations the searches for minimal sets of one derivation may visit together (each overdetermined
#: subset explored counts its size: a matching over it).  A 5-tank cascade measured at every tank (179
#: minimal sets for 15 faults) stops short at 12000 (192 of 208 pairs) and reaches every pair with this (8 s
#: of CPU); the searches of a 200-stage chain stop on MAX_SEARCHES first, either way.
MAX_SEARCH_EQUATIONS = 48000
#: The model size the budgets above are for.
BUDGET_FAULTS = 60

#: An eliminated relation larger than this is not kept: nested inverses of non-linear laws grow without
#: bound.  Counted as distinct operations (a subexpression repeated counts once: the evaluation computes it
#: once, sympy's common subexpressions), so a chain of orifice inversions, whose tree repeats each inner
#: level many times, is kept while its evaluation stays small.
MAX_OPERATIONS = 500


class _StructureOnly:
    """A bond-graph-like object over a given structure (the model with theta -> theta (1 + delta_theta))."""

    def __init__(self, name: str, structure) -> None:
        self.name, self._structure = name, structure

    def structure(self):
        return self._structure


def structural_arrs(bg, *, existing: Sequence[ARR] | None = None, sensor_faults: bool = True,
                    max_order: int | str | None = MAX_ORDER, integrals: str = "avoid",
                    isolation: bool = True, spent: dict | None = None, simulated: bool = False) -> list[ARR]:
    """ARRs from minimal overdetermined sets that add detectability or isolability to ``existing``.

    Parameters
    ----------
    bg : BondGraph
    existing : sequence of ARR, optional
        The ARRs already in use (``junction_arrs(bg)`` when omitted).
    sensor_faults : bool
        Count a fault per sensor in the signatures the selection improves.
    max_order : int, "auto" or None
        The highest derivative of a measured signal an added ARR may need; None for no bound.  With
        ``"auto"`` (default), an ARR that detects a fault no other ARR detects may need any order (the
        lowest available is taken), and one added for isolation no more than the highest order of the
        ARRs in hand.
    integrals : {"avoid", "keep"}
        As in :func:`~diagnosis.junctions.junction_arrs`, for the integrals an elimination leaves.
    isolation : bool
        Add ARRs for isolation as well as for detection (default).  :func:`unreached` says what is left
        either way.
    spent : dict, optional
        Filled with the work the search spent (:meth:`_Shared.cost`): ``searches``, ``search_equations``,
        ``eliminated_sets``, ``eliminated_equations``, ``reused_sets``.
    simulated : bool
        Realise a set with no closed form (a loop only its own ODE closes, a law without explicit inverse, a
        relation over :data:`MAX_OPERATIONS`) as a simulation residual
        (:class:`~diagnosis.simulation_residuals.SimulationARR`, ``ARR_MSO_<k>`` with form ``"simulation"``).
        Off by default: such a residual needs its initial state, and the consumers that compile a closed form
        (streaming, code generation, prognosis) do not take it.

    Returns
    -------
    list of ARR
        The added ARRs ``ARR_MSO_1``, ``ARR_MSO_2``..., each with ``origin`` naming the equations
        (node and role) it comes from.

    Notes
    -----
    Each fault the ARRs do not detect, then each ordered pair ``(a, b)`` they cannot tell apart
    (every ARR that sees ``a`` sees ``b``) while the structure can, is a gap.  For a gap, the minimal
    overdetermined sets that hold ``a`` and avoid ``b`` are sought near ``a``
    (:meth:`~diagnosis.structural.StructuralModel.msos_through`); the one whose elimination needs the
    lowest derivatives, then the smallest, is kept if its ARR closes the gap.  Sets that cannot be
    eliminated (a law without explicit inverse, a loop only an ODE of the set closes) are named in one
    :class:`ARRWarning`; gaps that only sets above ``max_order`` close are named in another.
    """
    require_model(bg, "structural_arrs")
    check_integral_form(integrals)
    if max_order is not None and max_order != "auto" and not (isinstance(max_order, int) and max_order >= 0):
        raise ValueError(f"option max_order: {max_order!r} is not a non-negative integer, 'auto' or None")
    existing = junction_arrs(bg, integrals=integrals) if existing is None else list(existing)
    structure = bg.structure()
    faults = set(candidate_parameters(structure))
    faults |= {sensor_fault(s) for s in measured_signals(structure)} if sensor_faults else set()
    if not isolation and faults <= set().union(*(_seen(arr, faults) for arr in existing)):
        return []   # every fault detected and no isolation asked: the structure has nothing to add
    model = structural_model(bg, sensor_faults=sensor_faults)
    shared = _Shared(bg, model, integrals == "avoid", simulated)   # lazy: built for the first gap
    supports = [faults_of_arr(model, arr) for arr in existing]
    added, unrealizable, stopped = [], set(), None
    for fault, other in _gaps(model, supports, isolation=isolation):
        if _told_apart(supports, fault, other):
            continue
        bound = max_order
        if max_order == "auto":
            bound = None if other is None else max((a.order for a in existing + added), default=0)
        try:
            arr = _closing_arr(shared, fault, other, bound, unrealizable, f"ARR_MSO_{len(added) + 1}")
        except _OutOfBudget as exc:
            stopped = str(exc)
            break
        if arr is not None:
            supports.append(faults_of_arr(model, arr))
            added.append(arr)
    _warn_left(bg.name, model, supports, unrealizable, stopped)
    if spent is not None:
        spent.update(shared.cost())
    return added


def _warn_left(name: str, model: StructuralModel, supports: list, unrealizable: set, stopped: str | None) -> None:
    """One ARRWarning naming the faults the structure detects and no ARR sees (counted at the end: an ARR
    added for one gap may close another), why, and where the search stopped if it did."""
    seen = set().union(*supports)
    missed = [fault for fault in model.faults if fault not in seen and fault in model.detectable()]
    if not missed and stopped is None:
        return   # isolation left is for the report (unreached) to say
    parts = [f"{name}: "]
    if missed:
        parts.append(f"{len(missed)} fault(s) the structure can detect have no closed-form ARR: {', '.join(missed)}")
        if unrealizable:
            shown = sorted(unrealizable)
            more = f" and {len(shown) - 5} more" if len(shown) > 5 else ""
            parts.append(f"; {len(shown)} set(s) give none: {'; '.join(shown[:5])}{more}")
    if stopped is not None:
        parts.append(f"{'; ' if missed else ''}the search for further ARRs stopped: {stopped} "
                     "(diagnosis.elimination.unreached lists what is left)")
    warnings.warn("".join(parts), ARRWarning, stacklevel=3)


#: At most this many unreached faults and pairs are explained by :func:`unreached` (a search each).
EXPLAINED = 200


def unreached(bg, arrs: Sequence[ARR], *, sensor_faults: bool = True, explain: bool = False) -> dict:
    """What the structure of ``bg`` allows and ``arrs`` do not reach, and why.

    Parameters
    ----------
    bg : BondGraph
    arrs : sequence of ARR
    sensor_faults : bool
        Count a fault per sensor (as the derivation does by default).
    explain : bool
        Also say why each is left (the first :data:`EXPLAINED`): the lowest derivative order of the minimal
        sets near the fault that would reach it, or that every such set is closed only by an ODE of its
        own, or that no minimal set was found near the fault.

    Returns
    -------
    dict
        ``"detect"``: the faults the structure can detect and no ARR sees; ``"isolate"``: the ordered
        pairs ``(a, b)`` the structure can tell apart and the ARRs cannot (every ARR that sees ``a``
        sees ``b``); with ``explain``, ``"reasons"``: fault or pair -> one line.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> from diagnosis import derive_arrs
    >>> left = unreached(dc_motor(), derive_arrs(dc_motor()), explain=True)
    >>> left["detect"], ("k_m", "sensor i") in left["isolate"]
    ([], True)
    >>> left["reasons"][("k_m", "sensor i")]
    'the minimal sets that would tell them apart need derivatives of order 2 (the ARRs go to order 1)'
    >>> unreached(dc_motor(), derive_arrs(dc_motor(), max_order=2))["isolate"]
    []
    """
    require_model(bg, "unreached")
    model = structural_model(bg, sensor_faults=sensor_faults)
    supports = [faults_of_arr(model, arr) for arr in arrs]
    gaps = list(_gaps(model, supports))
    left = {"detect": [a for a, b in gaps if b is None], "isolate": [(a, b) for a, b in gaps if b is not None]}
    if explain:   # bounded by EXPLAINED, not by the derivation's budgets
        shared = _Shared(bg, model, True)
        shared.limits = dict.fromkeys(shared.limits, math.inf)
        shared.search["equations"] = math.inf
        order = max((arr.order for arr in arrs), default=0)
        left["reasons"] = {gap if gap[1] is not None else gap[0]: _reason(shared, *gap, order)
                           for gap in gaps[:EXPLAINED]}
    return left


def _reason(shared: _Shared, fault: str, other: str | None, order: int) -> str:
    """Why no ARR reaches a gap, from the minimal sets near ``fault`` that avoid ``other`` (no elimination)."""
    removed = shared.model.faults[other] if other is not None else frozenset()
    ignored: set = set()
    candidates = [rows for rows in shared.near(fault, ignored) if not rows & removed]
    for reach in REACHES:
        if candidates:
            break
        candidates = shared.searched(fault, removed, reach, ignored)
    what = "see it" if other is None else "tell them apart"
    if not candidates:
        return f"no minimal set that would {what} was found near {fault} ({ignored.pop() if ignored else 'reach'})"
    estimates = [e for e in (shared.estimated_order(rows) for rows in candidates) if e is not None]
    if not estimates:
        return f"every minimal set near {fault} that would {what} is closed only by an ODE of its own"
    if min(estimates) > order:
        return (f"the minimal sets that would {what} need derivatives of order {min(estimates)} "
                f"(the ARRs go to order {order})")
    return (f"the minimal sets that would {what} (order {min(estimates)}) have no closed form: a law without explicit "
            f"inverse or a relation over MAX_OPERATIONS, or the search stopped on its budget")


def arr_from_set(bg, rows, *, model: StructuralModel | None = None, name: str = "ARR_MSO",
                 simulated: bool = False) -> ARR:
    """The ARR of one minimal overdetermined set of equations of ``bg`` (indices into ``model.equations``): its
    closed form, or with ``simulated`` its simulation residual (:mod:`diagnosis.simulation_residuals`)."""
    model = structural_model(bg) if model is None else model
    shared = _Shared(bg, model, True, simulated)
    return shared.simulated(frozenset(rows), name) if simulated else shared.arr(frozenset(rows), name)


def faults_of_arr(model: StructuralModel, arr: ARR) -> set:
    """The faults of ``model`` an ARR sees: its parameters and the sensors of the signals it reads."""
    return _seen(arr, model.faults)


def _seen(arr: ARR, faults) -> set:
    """The ``faults`` (names) an ARR sees: its parameters and the sensors of the signals it reads."""
    sensors = {sensor_fault(s) for s in arr.signals}
    return {p for p in arr.parameters if p in faults} | {s for s in sensors if s in faults}


def _gaps(model: StructuralModel, supports: list, *, isolation: bool = True):
    """Faults the ARRs miss and the structure detects, then ordered pairs they cannot tell apart and it can.

    A generator: the pairs are listed after the detection gaps are closed, from the supports then.
    """
    seen = set().union(*supports)
    yield from ((fault, None) for fault in model.faults if fault not in seen and fault in model.detectable())
    if not isolation:
        return
    for fault in model.faults:
        with_fault = [s for s in supports if fault in s]
        if not with_fault:
            continue
        for other in sorted(set.intersection(*with_fault) - {fault}, key=list(model.faults).index):
            if model.isolable(fault, other):
                yield fault, other


def _told_apart(supports: list, fault: str, other: str | None) -> bool:
    return any(fault in s and (other is None or other not in s) for s in supports)


#: How far past the first overdetermined neighbourhood of a fault the searches for a closing set look, in
#: turn: the nearest sets first; farther ones when every near one is closed only by an ODE (a tank between
#: two unmeasured ones is told through the chain of orifices to a measured flow).
REACHES = (1, 2)


def _closing_arr(shared: _Shared, fault: str, other: str | None, max_order: int | None, unrealizable: set,
                 name: str) -> ARR | None:
    """The ARR of the lowest order, then the smallest set, that sees ``fault`` and not ``other``.

    The sets near ``fault`` are sought once for all its gaps (those avoiding ``other`` serve this one); only
    when none of them closes the gap is a search made that avoids ``other`` from the start, then a wider one.
    """
    model = shared.model
    removed = model.faults[other] if other is not None else frozenset()
    around = shared.near(fault, unrealizable)
    near = [rows for rows in around if not rows & removed]
    arr, higher = _first_closing(shared, near, fault, other, max_order, unrealizable)
    if arr is not None or higher:   # a set above max_order closes it: searches avoiding ``other`` find no lower
        return None if arr is None else dataclasses.replace(arr, name=name)
    orders = [o for o in map(shared.estimated_order, around) if o is not None]
    if max_order is not None and orders and min(orders) > max_order:
        return None   # every set near the fault is above the bound: one avoiding ``other`` is not sought
    shared.spend("searches", "gap searches")
    tried: set = set(near)
    for reach in REACHES:
        candidates = shared.searched(fault, removed, reach, unrealizable)
        fresh = [rows for rows in candidates if rows not in tried]
        tried.update(fresh)
        arr, higher = _first_closing(shared, fresh, fault, other, max_order, unrealizable)
        if arr is not None:
            return dataclasses.replace(arr, name=name)
        if higher:
            return None   # a set closes the gap, above max_order: a wider search would only find longer ones
    return None


def _first_closing(shared: _Shared, candidates: list, fault: str, other: str | None, max_order: int | None,
                   unrealizable: set) -> tuple[ARR | None, bool]:
    """(the ARR of the lowest order, then the smallest set, that closes the gap; whether a set was passed
    over for its order).  A set no elimination can close (its loops through states stay loops in either
    causality and it is not linear) is named in ``unrealizable`` without being tried, or, with
    ``simulated=True``, tried as a simulation residual after the closed forms, as is a set passed over for
    its order."""
    model = shared.model
    estimates = {rows: shared.estimated_order(rows) for rows in candidates}
    odes = sorted((rows for rows in candidates if estimates[rows] is None), key=len)
    if not shared.simulate:
        for rows in odes:
            unrealizable.add(f"{_short(model, rows)}: a loop through a state in either causality and a non-linear "
                             "law: only an ODE of the set closes it")
        odes = []
    higher = []
    for rows in sorted((r for r in candidates if estimates[r] is not None), key=lambda r: (estimates[r], len(r))):
        if max_order is not None and estimates[rows] > max_order:
            # the sets are sorted by their estimate: every other one needs more (or a simulation)
            higher = sorted((r for r in candidates if estimates[r] is not None and estimates[r] > max_order), key=len)
            break
        arr = shared.cached(rows, unrealizable)
        if _closes(shared, arr, fault, other, max_order):
            return arr, False
    # with simulated=True: a set only its own ODE closes, or one whose closed form needs more derivatives than
    # max_order, as a simulation residual (its states integrated: no high derivative of the record)
    for rows in (odes + higher) if shared.simulate else ():
        arr = shared.simulation(rows, unrealizable)
        if _closes(shared, arr, fault, other, max_order):
            return arr, False
    return None, bool(higher)


def _closes(shared: _Shared, arr: ARR | None, fault: str, other: str | None, max_order: int | None) -> bool:
    """Whether ``arr`` exists within ``max_order``, sees ``fault`` and not ``other``."""
    if arr is None or (max_order is not None and arr.order > max_order):
        return False
    support = faults_of_arr(shared.model, arr)
    return fault in support and (other is None or other not in support)


class _Shared:
    """What the eliminations of every set of one model share, computed once, on first use."""

    def __init__(self, bg, model: StructuralModel, avoid_integrals: bool, simulate: bool = False) -> None:
        self.bg, self.model, self.avoid_integrals, self.simulate = bg, model, avoid_integrals, simulate
        self.weights: dict = {}
        self.results: dict = {}
        self.simulations: dict = {}  # set -> its simulation residual (simulated=True), or None
        self.templates: dict = {}   # (kind, set shape) -> (the set eliminated, its ARR or None)
        self.reused: dict = {}      # set -> whether its ARR is another set's, renamed
        self._near: dict = {}       # fault -> the minimal sets near it
        self.estimates: dict = {}
        self.spent = {"searches": 0, "eliminations": 0}
        scale = max(1.0, len(model.faults) / BUDGET_FAULTS)
        self.limits = {"searches": round(MAX_SEARCHES * scale), "eliminations": round(MAX_ELIMINATIONS * scale),
                       "search_equations": round(MAX_SEARCH_EQUATIONS * scale)}
        self.search = {"equations": self.limits["search_equations"]}

    def near(self, fault: str, unrealizable: set) -> list:
        """The minimal sets near ``fault`` (:meth:`~diagnosis.structural.StructuralModel.msos_through`), once."""
        if fault not in self._near:
            self.spend("searches", "gap searches")
            self._near[fault] = self.searched(fault, frozenset(), REACHES[0], unrealizable)
        return self._near[fault]

    def searched(self, fault: str, removed: frozenset, reach: int, unrealizable: set) -> list:
        """The minimal sets near ``fault`` avoiding ``removed``; none (the set named) when there are too many."""
        try:
            return self.model.msos_through(self.model.faults[fault], removed, budget=self.search, reach=reach)
        except StructuralLimitError as exc:   # too many sets near this fault: the gap stays open, named at the end
            if self.search["equations"] < 0:
                raise _OutOfBudget(f"the searches visited {self.limits['search_equations']} equations "
                                   "(diagnosis.elimination.MAX_SEARCH_EQUATIONS, per BUDGET_FAULTS faults)") from None
            unrealizable.add(f"near {fault}: {exc}")
            return []

    def cost(self) -> dict:
        """The work spent: gap searches, equations the searches visited, sets eliminated and their equations,
        sets that took the ARR of a set of the same shape."""
        fresh = [rows for rows in self.results if not self.reused.get(rows)]
        return {"searches": self.spent["searches"],
                "search_equations": self.limits["search_equations"] - self.search["equations"],
                "eliminated_sets": len(fresh), "eliminated_equations": self.spent["eliminations"],
                "reused_sets": sum(self.reused.values())}

    def spend(self, what: str, label: str, amount: int = 1) -> None:
        """Count ``amount`` units of work; raise :class:`_OutOfBudget` rather than go over the limit."""
        limit = self.limits[what]
        if self.spent[what] + amount > limit:
            raise _OutOfBudget(f"{label} would go over {limit} (diagnosis.elimination.MAX_{what.upper()}, "
                               "per BUDGET_FAULTS faults)")
        self.spent[what] += amount

    @cached_property
    def structure(self):
        return self.bg.structure()

    @cached_property
    def signals(self) -> set:
        """The known signals: inputs (sources and the modulation of MTF/MGY two-ports) and measured ones."""
        return set(self.structure.inputs) | set(self.structure.outputs)

    @cached_property
    def unknowns(self) -> set:
        return set().union(*self.model.unknowns)

    @cached_property
    def _real(self) -> dict:
        """Plain -> real signals, states and parameters: then d|x|/dt is sign(x) dx/dt, not sympy's re/im form."""
        equations = self._plain_nominal + self._plain_true
        real = {f: sp.Function(f.func.__name__, real=True)(*f.args)
                for equation in equations for f in equation.atoms(AppliedUndef)}
        real.update({s: sp.Symbol(s.name, real=True) for equation in equations for s in equation.free_symbols
                     if s != T})
        return real

    @cached_property
    def _plain_nominal(self) -> list:
        return [m.equation for m in self.model.equations]

    @cached_property
    def _plain_true(self) -> list:
        uncertain = _StructureOnly(self.bg.name, uncertain_structure(self.structure))
        return [m.equation for m in labelled_equations(uncertain)]

    @cached_property
    def nominal(self) -> list:
        return [rewritten(e, self._real) for e in self._plain_nominal]

    @cached_property
    def true(self) -> list:
        return [rewritten(e, self._real) for e in self._plain_true]

    @cached_property
    def plain(self) -> dict:
        return {v: k for k, v in self._real.items()}

    def cached(self, rows: frozenset, unrealizable: set) -> ARR | None:
        """The ARR of ``rows``, made once; None (and the set described in ``unrealizable``) if it has none.

        A set of the same shape as one eliminated before (:mod:`diagnosis._set_shapes`: the same equations
        up to renaming, another stage of a chain) takes that one's ARR renamed, at no cost to the budget.
        """
        return self._made(rows, unrealizable, "closed form")

    def simulation(self, rows: frozenset, unrealizable: set) -> ARR | None:
        """The simulation residual of ``rows`` (:meth:`simulated`), made once, or renamed as :meth:`cached`
        does; None (and the set described in ``unrealizable``) if it has none."""
        return self._made(rows, unrealizable, "simulation")

    def _made(self, rows: frozenset, unrealizable: set, kind: str) -> ARR | None:
        store, make = (self.results, self.arr) if kind == "closed form" else (self.simulations, self.simulated)
        if rows in store:
            return store[rows]
        shape = self.shapes.shape(rows)
        key = None if shape is None else (kind, shape.key)
        if key in self.templates:
            first, arr = self.templates[key]
            if arr is None:
                unrealizable.add(f"{_short(self.model, rows)}: the equations of {_short(self.model, first.rows)} "
                                 f"renamed, which give no {kind}")
            store[rows] = None if arr is None else self._renamed(arr, first, shape)
            self.reused[rows] = True
            return store[rows]
        self.spend("eliminations", "the equations eliminated", len(rows))
        try:
            store[rows] = make(rows, "ARR_MSO")
        except (NotImplementedError, ValueError) as exc:
            store[rows] = None
            unrealizable.add(str(exc))
        if key is not None:
            self.templates[key] = (shape, store[rows])
        return store[rows]

    @cached_property
    def shapes(self) -> Shapes:
        return Shapes(self._plain_true, [m.role for m in self.model.equations], self._kind)

    def _kind(self, atom) -> str:
        """What a symbol of the equations stands for (the colour :mod:`diagnosis._set_shapes` starts from)."""
        if isinstance(atom, AppliedUndef):
            return "signal" if atom.func.__name__ in self.signals else "state"
        if delta_parameter(atom) is not None:
            return "delta"
        return "parameter" if atom.name in self.structure.parameters else "bond"

    def _renamed(self, arr: ARR, first: SetShape, second: SetShape) -> ARR:
        """``arr``, the ARR of the set ``first``, with its symbols renamed to those of ``second`` (same shape)."""
        mapping = dict(zip(first.atoms, second.atoms))
        names = {a.name: b.name for a, b in mapping.items() if isinstance(a, sp.Symbol)}
        rows = dict(zip(first.rows, second.rows))
        residual = min((i for i in first.rows if self.model.equations[i].node == arr.junction),
                       key=lambda i: self.model.equations[i].role != "balance")
        nominal = arr.nominal.xreplace(mapping)
        terms = {names[p]: term.xreplace(mapping) for p, term in arr.terms.items()}
        symbols = {x.name for x in nominal.free_symbols}
        uncertain = set(terms)
        intervals = parameter_intervals(self.structure)
        if arr.simulation:   # the simulated states and their rates are renamed with the rest
            functions = {a.func.__name__: b.func.__name__ for a, b in mapping.items() if isinstance(a, AppliedUndef)}
            rates, rates_true = (tuple(f.xreplace(mapping) for f in fs) for fs in (arr.rates, arr.rates_true))
            symbols |= {x.name for f in rates for x in f.free_symbols}
            uncertain |= {delta_parameter(x) for f in rates_true for x in f.free_symbols} - {None}
            arr = dataclasses.replace(arr, states=tuple(functions[x] for x in arr.states), rates=rates,
                                      rates_true=rates_true)
        return dataclasses.replace(
            arr, junction=self.model.equations[rows[residual]].node, nominal=nominal,
            uncertain=arr.uncertain.xreplace(mapping), terms=terms,
            parameters=frozenset(names[p] for p in arr.parameters),
            values={p: v for p, v in self.structure.parameters.items() if p in symbols or p in uncertain},
            uncertainties={p: intervals[p] for p in uncertain}, origin=tuple(self.model.describe(second.rows)))

    def arr(self, rows: frozenset, name: str) -> ARR:
        model = self.model
        try:
            found = _residual(self, rows)
        except ValueError:
            if not self.simulate:
                raise
            return self.simulated(rows, name)
        if found is None:
            linear = self._by_operators(rows, name)
            if linear is not None:
                return linear
            if self.simulate:
                return self.simulated(rows, name)
            raise ValueError(f"{_short(model, rows)}: every balance leaves a loop through a state (only an ODE "
                             "closes it) or an unknown no law gives explicitly")
        residual, assigned, r_n = found
        size = distinct_operations(r_n)
        if size > MAX_OPERATIONS:
            if self.simulate:
                return self.simulated(rows, name)
            raise ValueError(f"{_short(model, rows)}: the residual takes {size} operations "
                             f"(more than {MAX_OPERATIONS})")
        r_true = _eliminate(model, self.true, assigned, residual)
        r_n, r_true, form = written_without_integrals(r_n, r_true, "elimination", avoid=self.avoid_integrals)
        # back to the model's plain signals; any re/im a sympy solve left of a real quantity is the quantity
        r_n, r_true = real_parts(r_n.xreplace(self.plain)), real_parts(r_true.xreplace(self.plain))
        return split_relation(name, model.equations[residual].node, None, r_n, r_true, (), self.structure,
                              candidate_parameters(self.structure), parameter_intervals(self.structure),
                              origin=tuple(model.describe(rows)), form=form)

    def simulated(self, rows: frozenset, name: str) -> SimulationARR:
        """The simulation residual of ``rows`` (:mod:`diagnosis.simulation_residuals`): the states in loops of
        the matching (else every state of the set) integrated from their storage equations, the rest solved
        explicitly for the unknowns, one equation left over as the residual.  Of the choices that work: the
        fewest states no state feeds back on (:func:`_drifting`), then the lowest derivative order, the fewest
        states, the fewest operations.

        Raises a ValueError saying why when no equation of the set can be left over that way.
        """
        model = self.model
        every = {i: f"state {model.equations[i].node}" for i in rows if model.equations[i].role == "storage"}
        found, why = [], None
        # the states in loops (fewest to integrate), then every state of the set
        for nodes in dict.fromkeys([frozenset(self._looped(rows)), frozenset(model.equations[i].node for i in every)]):
            storage = {i: x for i, x in every.items() if model.equations[i].node in nodes}
            if not storage:
                continue
            known = frozenset(storage.values())
            kept = rows - set(storage)
            for residual in dict.fromkeys(_balances(model, kept) + sorted(kept)):
                try:
                    assigned = _matching(self, kept - {residual}, known=known)
                    nominal = self._simulated_parts(assigned, residual, storage, self.nominal, known)
                    true = self._simulated_parts(assigned, residual, storage, self.true, known)
                except (ValueError, NotImplementedError, _DifferentialLoop) as exc:
                    if not isinstance(exc, _DifferentialLoop) and "left over" not in str(exc):
                        why = why or str(exc).removeprefix(_short(model, kept - {residual}) + ": ")
                    continue
                order = max((d.derivative_count for e in nominal for d in e.atoms(sp.Derivative)), default=0)
                drifting = _drifting(nominal[1:], [self._plain_symbols[x] for x in known])
                found.append(((drifting, order, len(storage), sum(map(distinct_operations, nominal)), residual),
                              storage, nominal, true))
        if not found:
            raise ValueError(f"{_short(model, rows)}: no simulation either: "
                             f"{why or 'no equation can be left over with the others solved, its states integrated'}")
        (*_, residual), storage, (r_n, *rates), (r_true, *rates_true) = min(found, key=lambda f: f[0])
        arr = split_relation(name, model.equations[residual].node, None, r_n, r_true, (), self.structure,
                             candidate_parameters(self.structure), parameter_intervals(self.structure),
                             origin=tuple(model.describe(rows)), form="simulation")
        every = {s.name for e in (r_n, *rates) for s in e.free_symbols}
        deltas = {delta_parameter(s) for e in (r_true, *rates_true) for s in e.free_symbols} - {None}
        intervals = parameter_intervals(self.structure)
        fields = {f.name: getattr(arr, f.name) for f in dataclasses.fields(ARR) if f.init}
        fields.update(parameters=frozenset(p for p in self.structure.parameters if p in every),
                      values={p: v for p, v in self.structure.parameters.items() if p in every or p in deltas},
                      uncertainties={p: intervals[p] for p in deltas})
        states = tuple(self._plain_symbols[x].func.__name__ for x in storage.values())
        return SimulationARR(**fields, states=states, rates=tuple(rates), rates_true=tuple(rates_true))

    def _looped(self, rows: frozenset) -> set:
        """The storage elements of ``rows`` that the matching in derivative causality leaves in a loop."""
        looped: set = set()
        for residual in _balances(self.model, rows):
            try:
                found = _structural_order(self.model, _matching(self, rows - {residual}), residual)
            except ValueError:
                continue
            if not isinstance(found, int):
                looped |= found
        return looped

    def _simulated_parts(self, assigned: dict, residual: int, storage: dict, equations: list,
                         known: frozenset) -> list:
        """``[g, f_1, ..., f_n]``: the residual and the rate of each integrated state, in states and signals."""
        model = self.model
        solution = _solved(model, equations, assigned, known)
        residual_equation = _substituted(equations[residual], solution)
        parts = [residual_equation.lhs - residual_equation.rhs]
        rates = {}
        for i in storage:
            equation = _substituted(equations[i], solution)
            expression = equation.lhs - equation.rhs
            own = [d for d in expression.atoms(sp.Derivative)
                   if isinstance(d.expr, AppliedUndef) and f"state {d.expr.func.__name__[2:]}" in known]
            slope = sp.diff(expression, own[0]) if own else sp.S.Zero
            if slope == 0 or slope.has(own[0]):
                raise ValueError(f"{model.describe([i])[0]}: not a rate of its state")
            d = own[0]
            rates[d] = -expression.xreplace({d: 0}) / slope
            parts.append(rates[d])
        for _ in range(len(rates) + 1):   # a rate read through another state's law: its derivative, substituted
            parts = [p.xreplace(rates) for p in parts]
        parts = [real_parts(p.xreplace(self.plain)) for p in parts]
        states = {self._plain_symbols[x].func.__name__ for x in known}
        unknowns = self.unknowns - known
        for part in parts:
            if part.atoms(sp.Integral) or any(isinstance(d.expr, AppliedUndef) and d.expr.func.__name__ in states
                                              for d in part.atoms(sp.Derivative)):
                raise ValueError(f"{_short(model, assigned)}: a state's rate depends on its own derivative")
            if not _in_known_signals(part, self.signals | states, unknowns):
                raise ValueError(f"{_short(model, assigned)}: an unknown is left with the states integrated")
        if parts[0] == 0:
            raise ValueError(f"{_short(model, assigned)}: the residual vanishes")
        return parts

    def _by_operators(self, rows: frozenset, name: str) -> ARR | None:
        """The ARR of a set linear in its unknowns with constant coefficients, by operator elimination
        (:mod:`diagnosis._operator_elimination`); None when the set is not of that kind."""
        model = self.model
        r_true = operator_residual(*self._operator_problem(rows))
        if r_true is None:
            return None
        r_n = r_true.xreplace({d: 0 for d in r_true.free_symbols if delta_parameter(d) is not None})
        if r_n == 0 or not _in_known_signals(r_n, self.signals, self.unknowns):
            return None
        residual = _balances(model, rows)[0]
        return split_relation(name, model.equations[residual].node, None, r_n, r_true, (), self.structure,
                              candidate_parameters(self.structure), parameter_intervals(self.structure),
                              origin=tuple(model.describe(rows)), form="elimination")

    @cached_property
    def _plain_symbols(self) -> dict:
        """Structural unknown name -> its sympy object in the plain (model) equations."""
        found = {}
        for equation in self._plain_true:
            found.update(_symbols_of(equation))
        return found

    def weight(self, row: int, unknown: str) -> int:
        """1 if equation ``row`` can be solved explicitly for ``unknown``, 10 if only as a last resort."""
        key = (row, unknown)
        if key not in self.weights:
            m = self.model.equations[row]
            expression = m.equation.lhs - m.equation.rhs
            symbol = _symbols_of(m.equation)[unknown]
            # an unknown entering non-linearly (a valve law solved for its pressure) only as a last resort;
            # a storage equation gives its state by integration, whatever the form of its rate
            slope = sp.diff(expression, symbol)
            self.weights[key] = 1 if m.role == "storage" or (slope != 0 and not slope.has(symbol)) else 10
        return self.weights[key]

    def estimated_order(self, rows: frozenset) -> int | None:
        """The derivative order the elimination of ``rows`` would need (:meth:`_estimated_order`), once per shape."""
        if rows not in self.estimates:
            shape = self.shapes.shape(rows)
            key = rows if shape is None else shape.key
            if key not in self.estimates:
                self.estimates[key] = self._estimated_order(rows)
            self.estimates[rows] = self.estimates[key]
        return self.estimates[rows]

    def _estimated_order(self, rows: frozenset) -> int | None:
        """The derivative order the elimination of ``rows`` would need, from its matching alone (no algebra).

        When every balance leaves a loop through a state, the order of the operator elimination of a linear
        set (:func:`~diagnosis._operator_elimination.operator_order`, numeric, cheap); None if it has none.
        """
        orders = []
        for residual in _balances(self.model, rows):
            integral: frozenset = frozenset()
            for _ in range(_ATTEMPTS):   # as the elimination does: a looped state retried in integral causality
                found = _structural_order(self.model, _matching(self, rows - {residual}, integral), residual)
                if isinstance(found, int):
                    orders.append(found)
                    break
                if found <= integral:
                    break
                integral |= found
        if orders:
            return min(orders)
        return operator_order(*self._operator_problem(rows))   # a linear set the operators close, if any

    def _operator_problem(self, rows: frozenset) -> tuple[list, list]:
        """The equations (with theta (1 + delta_theta)) and unknowns of ``rows`` for the operator elimination."""
        order = sorted(rows)
        unknowns = sorted(set().union(*(self.model.unknowns[i] for i in order)))
        return [self._plain_true[i] for i in order], [self._plain_symbols[x] for x in unknowns]


def _drifting(rates: list, states: list) -> int:
    """How many of the simulated states no state feeds back on (the structural rank of the rates' Jacobian falls
    short by that much): such a state integrates the record's noise and drifts, and has no unique rest state."""
    graph = nx.Graph()
    graph.add_nodes_from(("rate", i) for i in range(len(rates)))
    graph.add_edges_from((("rate", i), ("state", j)) for i, rate in enumerate(rates)
                         for j, x in enumerate(states) if rate.has(x))
    matched = nx.bipartite.maximum_matching(graph, top_nodes=[("rate", i) for i in range(len(rates))])
    return len(rates) - len(matched) // 2


class _OutOfBudget(Exception):
    """The derivation spent its work budget: the gaps left are named, not searched."""


class _DifferentialLoop(Exception):
    """A block of the matching holds a state: only an ODE of the set, not an elimination, would give it."""

    def __init__(self, states: frozenset):
        super().__init__(f"states {sorted(states)} in a loop")
        self.states = states


def _short(model: StructuralModel, rows) -> str:
    """A set of equations named by its nodes, each once: ``{U, 1_e, R_a, ...}``."""
    return "{" + ", ".join(dict.fromkeys(model.equations[i].node for i in sorted(rows))) + "}"


def _balances(model: StructuralModel, rows: frozenset) -> list:
    return [i for i in sorted(rows) if model.equations[i].role == "balance"] or sorted(rows)


#: How often an elimination retries a set with the states of a loop taken in integral causality.
_ATTEMPTS = 4


def _residual(shared: _Shared, rows: frozenset, attempts: int = _ATTEMPTS):
    """(residual row, matching, nominal residual) for the first junction balance that leaves known signals only.

    A state that ends up in a loop of the matching is tried again in integral causality (from its storage
    equation), which breaks the loop when the state's rate is known from outside it.
    """
    model = shared.model
    _check_finite(model, shared.nominal, rows)
    for residual in _balances(model, rows):
        integral: frozenset = frozenset()
        for _ in range(attempts):
            assigned = _matching(shared, rows - {residual}, integral)
            try:
                r_n = _eliminate(model, shared.nominal, assigned, residual)
            except _DifferentialLoop as loop:
                if loop.states <= integral:
                    break
                integral |= loop.states
                continue
            except (NotImplementedError, ValueError):
                break
            if _in_known_signals(r_n, shared.signals, shared.unknowns):
                return residual, assigned, r_n
            break
    return None


def _matching(shared: _Shared, rows: frozenset, integral: frozenset = frozenset(),
              known: frozenset = frozenset()) -> dict:
    """Equation -> the unknown it is solved for.

    A state comes from its law (derivative causality) unless it is in ``integral``; an unknown that enters
    its equation non-linearly is matched to it only as a last resort; the ``known`` ones are not matched.
    """
    model = shared.model
    graph = nx.Graph()
    top = [("equation", i) for i in rows]
    graph.add_nodes_from(top)
    for i in rows:
        storage = model.equations[i].role == "storage"
        for x in model.unknowns[i] - known:
            weight = shared.weight(i, x)
            if x.startswith("state "):
                wanted_from_storage = x[len("state "):] in integral
                weight += 0 if storage == wanted_from_storage else 4 if wanted_from_storage else 1
            graph.add_edge(("equation", i), ("unknown", x), weight=weight)
    try:
        matching = nx.bipartite.minimum_weight_full_matching(graph, top_nodes=top)
    except ValueError:   # networkx: "cost matrix is infeasible"
        matching = {}
    if any(("equation", i) not in matching for i in rows):   # an equation with no unknown left to solve for
        raise ValueError(f"{_short(model, rows)}: no equation can be left over with every other one solved")
    return {i: matching[("equation", i)][1] for i in rows}


def _blocks(model: StructuralModel, assigned: dict, known: frozenset = frozenset()) -> list[list[int]]:
    """The equations of a matching in solving order, an algebraic loop as one block (``known``: unknowns
    given from outside the matching, the states a simulation integrates)."""
    owner = {x: i for i, x in assigned.items()}
    order = nx.DiGraph()
    order.add_nodes_from(assigned)
    order.add_edges_from((owner[x], i) for i in assigned for x in model.unknowns[i]
                         if x != assigned[i] and x not in known)
    blocks = nx.condensation(order)
    return [sorted(blocks.nodes[b]["members"]) for b in nx.topological_sort(blocks)]


def _structural_order(model: StructuralModel, assigned: dict, residual: int) -> int | frozenset:
    """The highest derivative of a known signal the residual would need, following the matching.

    A storage equation solved for its rate differentiates its state (one order up), solved for its
    state integrates the rate (one down); any other equation passes on the highest order of its inputs.
    When a block holds a state (a loop the elimination cannot close as it stands): the states of the
    loop, by element name, as :class:`_DifferentialLoop` names them.
    """
    order: dict = {}
    for members in _blocks(model, assigned):
        inputs = {x for i in members for x in model.unknowns[i]} - {assigned[i] for i in members}
        level = max((order[x] for x in inputs), default=0)
        if len(members) > 1:
            looped = frozenset(model.equations[i].node for i in members
                               if assigned[i].startswith("state ") or model.equations[i].role == "storage")
            if looped:
                return looped
            order.update((assigned[i], level) for i in members)
            continue
        (i,) = members
        if model.equations[i].role == "storage":
            level += -1 if assigned[i].startswith("state ") else 1
        order[assigned[i]] = level
    return max((order[x] for x in model.unknowns[residual]), default=0)


def _eliminate(model: StructuralModel, equations: list, assigned: dict, residual: int) -> sp.Expr:
    """The residual equation with every unknown of ``assigned`` replaced by its value in known signals."""
    equation = _substituted(equations[residual], _solved(model, equations, assigned))
    return equation.lhs - equation.rhs


def _solved(model: StructuralModel, equations: list, assigned: dict, known: frozenset = frozenset()) -> dict:
    """Every unknown of ``assigned`` (sympy object) -> its value in known signals (and ``known`` unknowns)."""
    symbols = _unknown_symbols(equations, assigned)
    solution: dict = {}
    for members in _blocks(model, assigned, known):
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
        if len(members) == 1:
            found = {targets[0]: _solve_one(equations_here[0], targets[0], model.describe(members)[0])}
        else:
            try:
                found = sp.solve([e.lhs - e.rhs for e in equations_here], targets, dict=True)
            except (TypeError, ZeroDivisionError) as exc:   # sympy gives up inside a piecewise or sign law
                raise ValueError(f"{model.describe(members)}: sympy cannot solve the loop ({exc})") from None
            if len(found) != 1:
                raise ValueError(f"{model.describe(members)}: no unique solution for {targets}")
            found = found[0]
        for target, value in found.items():  # stop before nested inverses grow without bound
            if distinct_operations(value) > MAX_OPERATIONS:
                raise ValueError(f"{_short(model, assigned)}: {target} takes more than {MAX_OPERATIONS} operations")
        solution.update(found)
    return solution


def distinct_operations(expression: sp.Expr) -> int:
    """The operations of ``expression`` with each repeated subexpression counted once.

    >>> x, y = sp.symbols("x y")
    >>> inner = sp.sqrt(x + y)
    >>> distinct_operations(inner * (inner + 1) / (inner + 2)), sp.count_ops(inner * (inner + 1) / (inner + 2))
    (7, 13)
    """
    nodes, stack = set(), [expression]
    while stack:   # a signal and its derivatives are read from the record: no operation, nothing below
        node = stack.pop()
        if node.is_Atom or isinstance(node, (AppliedUndef, sp.Derivative)) or node in nodes:
            continue
        nodes.add(node)
        stack.extend(node.args)
    return sum(max(len(node.args) - 1, 1) for node in nodes)


def _solve_one(equation: sp.Eq, target, where: str) -> sp.Expr:
    """One equation solved for one unknown: linearly, as a signed power (an orifice), or by sympy."""
    expression = equation.lhs - equation.rhs
    inverse = signed_power_inverse(expression, target)
    if inverse is not None:
        return inverse
    try:
        return solve_for(expression, target, where=where)
    except LawError as exc:
        raise ValueError(str(exc)) from None


def _in_known_signals(expression: sp.Expr, signals: set, unknowns: set) -> bool:
    """Whether ``expression`` holds none of the ``unknowns`` (bond variables) and no function of time but signals."""
    functions = {f.func.__name__ for f in expression.atoms(AppliedUndef)}
    return functions <= signals and not {str(v) for v in expression.free_symbols} & unknowns


def _unknown_symbols(equations: list, assigned: dict) -> dict:
    """Structural unknown name -> its sympy object, over the equations of ``assigned``."""
    found = {}
    for i in assigned:
        found.update(_symbols_of(equations[i]))
    return found


def _symbols_of(equation: sp.Eq) -> dict:
    """Structural unknown name -> its sympy object (bond variable symbol or state function) in ``equation``."""
    found = {str(s): s for s in equation.free_symbols}
    found.update({f"state {f.func.__name__[2:]}": f for f in equation.atoms(AppliedUndef)})
    return found


def _substituted(equation: sp.Eq, solution: dict) -> sp.Eq:
    """``equation`` with solved unknowns replaced, a state's derivative by the derivative of its value."""
    derivatives = {d: _time_derivative(solution[d.expr], d.derivative_count)
                   for d in equation.atoms(sp.Derivative) if d.expr in solution}
    return rewritten(rewritten(equation, derivatives), solution)


def _check_finite(model: StructuralModel, equations: list, rows) -> None:
    """Raise a ValueError naming the first equation of ``rows`` that holds an infinity or NaN."""
    for i in sorted(rows):
        if equations[i].has(sp.zoo, sp.oo, -sp.oo, sp.nan):
            m = model.equations[i]
            raise ValueError(f"{m.node} {m.role}: {m.equation} is not finite (a division by zero in the law?)")


def _time_derivative(expression: sp.Expr, count: int) -> sp.Expr:
    """The ``count``-th time derivative, every quantity real (no ``re``/``im``), Dirac pulses dropped."""
    return time_derivative(expression, count)
