"""Sequential causality assignment procedure (SCAP).

Causality decides, for each bond, which end imposes the effort (the other end
imposes the flow; the causal stroke sits at the end that *receives* effort).

Procedure (Karnopp, Margolis and Rosenberg; Samantaray and Ould Bouamama for
the dualized detectors used in diagnosis):

1. sources (Se, Sf, MSe, MSf), and detectors dualized to signal sources
   (De -> SSe, Df -> SSf) when requested, each followed by propagation;
2. storage elements (C, I) in the preferred causality, integral or derivative,
   each followed by propagation; an element already fixed by propagation
   the other way is *dependent storage*;
3. R elements still free, then any bond still free: every such choice is
   arbitrary and signals an algebraic loop (zero-order causal path).

Propagation enforces the junction rules (a 0-junction receives its effort on
exactly one bond, a 1-junction its flow on exactly one bond), the TF rule
(effort passes through) and the GY rule (effort in on both ports or out on
both).  Conflicts are reported, never raised: the assignment is inspectable
even for an invalid model.

Example
-------
>>> from bondgraph.library import rlc_circuit
>>> causality = rlc_circuit().assign_causality("integral")
>>> causality.storage
{'L': 'integral', 'C': 'integral'}
>>> causality.is_valid
True
"""

from __future__ import annotations

from collections import deque
from collections.abc import Hashable
from dataclasses import dataclass, field

from . import elements as el
from .laws import solve_for
from .errors import LawError
from .structure import PORT_SYMBOLS, Bond, BondGraphLike, require_model

__all__ = ["DERIVATIVE", "INTEGRAL", "CausalIssue", "Causality", "assign_causality", "diagnosis_causality"]

INTEGRAL, DERIVATIVE = "integral", "derivative"


@dataclass(frozen=True)
class CausalIssue:
    """Something the assignment found: ``kind`` is ``"conflict"``,
    ``"dependent storage"`` or ``"algebraic loop"``."""

    kind: str
    elements: tuple
    bonds: tuple
    message: str

    def __str__(self) -> str:
        return f"{self.kind}: {self.message}"


@dataclass
class Causality:
    """The result of SCAP.

    Attributes
    ----------
    preferred : str
        ``"integral"`` or ``"derivative"``.
    effort_from : dict
        Bond key ``(tail, head)`` -> the node that imposes effort on that bond.
        Dualized detector bonds are included.  A bond missing here could not
        be assigned (see ``issues``).
    storage : dict
        Storage element -> ``"integral"`` or ``"derivative"``.
    dualized : dict
        Detector -> ``"SSe"`` or ``"SSf"`` when detectors were dualized.
    issues : list of CausalIssue

    Examples
    --------
    Derivative causality with the detectors dualized, as for diagnosis:

    >>> from bondgraph.library import dc_motor
    >>> causality = dc_motor().assign_causality("derivative")
    >>> causality.storage, causality.dualized
    ({'L_a': 'derivative', 'J': 'derivative'}, {'i': 'SSf', 'omega': 'SSf'})
    >>> causality.effort_from[("1_e", "L_a")], causality.stroke(("1_e", "L_a"))
    ('L_a', '1_e')
    >>> causality.is_valid, causality.issues
    (True, [])
    >>> print(causality.summary())
    causality (derivative preferred): 0 integral, 2 derivative storage
    """

    preferred: str
    effort_from: dict = field(default_factory=dict)
    storage: dict = field(default_factory=dict)
    dualized: dict = field(default_factory=dict)
    issues: list = field(default_factory=list)
    bonds: list = field(default_factory=list, repr=False)

    def stroke(self, bond: tuple) -> Hashable:
        """The end of ``bond`` that receives effort (where the causal stroke is drawn)."""
        tail, head = bond
        return head if self.effort_from[bond] == tail else tail

    def _of(self, kind: str) -> list[CausalIssue]:
        return [issue for issue in self.issues if issue.kind == kind]

    @property
    def conflicts(self) -> list[CausalIssue]:
        """The ``"conflict"`` issues: bonds where the source, storage, junction or two-port rules clash."""
        return self._of("conflict")

    @property
    def dependent_storage(self) -> list[Hashable]:
        """Storage elements (C, I) not in the preferred causality (the ``"dependent storage"`` issues)."""
        return [issue.elements[0] for issue in self._of("dependent storage")]

    @property
    def algebraic_loops(self) -> list[CausalIssue]:
        """The ``"algebraic loop"`` issues: R elements or bonds whose causality was an arbitrary choice."""
        return self._of("algebraic loop")

    @property
    def is_valid(self) -> bool:
        """No conflicts and every bond assigned."""
        return not self.conflicts and all(b.key in self.effort_from for b in self.bonds)

    def summary(self) -> str:
        """A short text report."""
        lines = [f"causality ({self.preferred} preferred): "
                 f"{sum(v == INTEGRAL for v in self.storage.values())} integral, "
                 f"{sum(v == DERIVATIVE for v in self.storage.values())} derivative storage"]
        lines += [f"  {issue}" for issue in self.issues]
        return "\n".join(lines)


class _Conflict(Exception):
    def __init__(self, node: Hashable, message: str):
        super().__init__(message)
        self.node = node


def assign_causality(bg: BondGraphLike, preferred: str = INTEGRAL, *, dualize_detectors=None) -> Causality:
    """Assign causality to every bond of ``bg`` by SCAP.

    Parameters
    ----------
    bg : BondGraph
    preferred : {"integral", "derivative"}
        Preferred storage causality: integral for simulation, derivative for
        diagnosis (no unknown initial conditions).
    dualize_detectors : bool or iterable of detector names, optional
        Turn De into SSe and Df into SSf (they impose their measured effort or
        flow on their junction): all detectors (True), none (False) or the
        named ones.  Default: all for derivative preference, none otherwise.

    Returns
    -------
    Causality

    Examples
    --------
    Two inertias on one 1-junction share their velocity: the second one is
    dependent storage, forced into derivative causality by the first.

    >>> from bondgraph import BondGraph
    >>> bg = BondGraph(name="two inertias")
    >>> bg.add("F", "Se"), bg.add("J", "1")
    ('F', 'J')
    >>> bg.add("I1", "I", value=1.0), bg.add("I2", "I", value=2.0), bg.add("R1", "R", value=0.5)
    ('I1', 'I2', 'R1')
    >>> for tail, head in [("F", "J"), ("J", "I1"), ("J", "I2"), ("J", "R1")]:
    ...     _ = bg.bond(tail, head)
    >>> causality = assign_causality(bg)
    >>> causality.storage, causality.dependent_storage, causality.is_valid
    ({'I1': 'integral', 'I2': 'derivative'}, ['I2'], True)
    >>> print(causality.issues[0])
    dependent storage: I 'I2' is in derivative causality, forced by I 'I1'

    Preferred derivative causality dualizes every detector by default:

    >>> from bondgraph.library import rlc_circuit
    >>> assign_causality(rlc_circuit(), "derivative").dualized
    {'i': 'SSf', 'v_C': 'SSe'}
    >>> assign_causality(rlc_circuit(), "derivative", dualize_detectors=["i"]).dualized
    {'i': 'SSf'}
    """
    require_model(bg, "assign_causality")
    if preferred not in (INTEGRAL, DERIVATIVE):
        raise ValueError(f"preferred causality must be 'integral' or 'derivative', got {preferred!r}")
    if dualize_detectors is None:
        dualize_detectors = preferred == DERIVATIVE
    return _Scap(bg, preferred, dualize_detectors).run()


def diagnosis_causality(bg: BondGraphLike) -> Causality:
    """Derivative causality with as many detectors dualized as causality allows (the ARRs' assignment).

    Dualize every detector (De -> SSe, Df -> SSf); while dualized detectors clash, measure the last
    clashing one instead (it then gives a measurement ARR ``y - computed y``).

    >>> from bondgraph.library import dc_motor
    >>> diagnosis_causality(dc_motor()).dualized
    {'i': 'SSf', 'omega': 'SSf'}
    """
    dualized = {n for n, e in bg.structure().elements.items() if e.kind in el.DETECTORS}
    while True:
        causality = assign_causality(bg, DERIVATIVE, dualize_detectors=dualized)
        clashing = {n for issue in causality.conflicts for n in issue.elements if n in dualized}
        if not clashing:
            return causality
        dualized -= {sorted(clashing, key=str)[-1]}  # keep the first sensor, measure the other


class _Scap:
    def __init__(self, bg: BondGraphLike, preferred: str, dualize):
        structure = bg.structure()
        self.elements = structure.elements
        detectors = [n for n, e in self.elements.items() if e.kind in el.DETECTORS]
        if isinstance(dualize, bool):
            self.dualized = set(detectors) if dualize else set()
        else:
            self.dualized = set(dualize)
            unknown = self.dualized - set(detectors)
            if unknown:
                raise ValueError(f"cannot dualize {sorted(map(str, unknown))}: not detectors of the model")

        def kept(bond):
            return not bond.is_signal or bond.head in self.dualized

        self.bonds = [b for b in structure.bonds if kept(b)]
        self.at = {n: [b for b in bonds if kept(b)] for n, bonds in structure.at.items()}
        self.result = Causality(preferred, bonds=self.bonds)
        self.effort_from = self.result.effort_from
        self.origin: dict[tuple, Hashable] = {}  # which element's choice fixed a bond

    # -- driver -----------------------------------------------------------
    def run(self) -> Causality:
        kinds = {name: e.kind for name, e in self.elements.items()}
        for name, kind in kinds.items():
            if kind in el.SOURCES:
                self._fix_source(name)
        for name, kind in kinds.items():
            if name in self.dualized:
                self.result.dualized[name] = "SSe" if kind == "De" else "SSf"
                self._fix_source(name)
        for name, kind in kinds.items():
            if kind in el.STORAGE:
                self._fix_storage(name)
        for name, kind in kinds.items():
            if kind == "R" and self.at[name][0].key not in self.effort_from:
                self._fix_free(self.at[name][0], self._preferred_r(name), name)
        for bond in self.bonds:
            if bond.key not in self.effort_from:
                self._fix_free(bond, bond.tail, None)
        return self.result

    def _fix_source(self, name: Hashable) -> None:
        """A source (or dualized detector) imposes its effort or its flow on its bond."""
        element, bond = self.elements[name], self.at[name][0]
        effort_from = name if element.kind in el.EFFORT_SOURCES or element.kind == "De" else bond.other(name)
        role = self.result.dualized.get(name)
        label = f"{role} {name!r} (dualized {element.kind})" if role else str(element)
        current = self.effort_from.get(bond.key)
        if current is not None:
            if current != effort_from:
                origin = self.origin[bond.key]
                self._issue("conflict", (name, origin), (bond.key,),
                            f"{label} cannot impose its {'effort' if effort_from == name else 'flow'} on {bond}: "
                            f"already imposed through propagation from {self.elements[origin]}")
            return
        try:
            self._propagate(bond, effort_from, name)
        except _Conflict as conflict:
            self._issue("conflict", (name, conflict.node), (bond.key,), f"{label}: {conflict}")

    def _fix_storage(self, name: Hashable) -> None:
        bond = self.at[name][0]
        kind = self.elements[name].kind
        preferred = self.result.preferred
        # integral C imposes effort (e = q/C); integral I receives effort (f = p/I)
        integral_from = name if kind == "C" else bond.other(name)
        current = self.effort_from.get(bond.key)
        if current is None:
            wanted = integral_from if preferred == INTEGRAL else bond.other(integral_from)
            try:
                self._propagate(bond, wanted, name)
                current = wanted
            except _Conflict:
                try:
                    self._propagate(bond, bond.other(wanted), name)
                    current = bond.other(wanted)
                except _Conflict as conflict:
                    self._issue("conflict", (name, conflict.node), (bond.key,),
                                f"{self.elements[name]}: no causality is consistent: {conflict}")
                    return
        state = INTEGRAL if current == integral_from else DERIVATIVE
        self.result.storage[name] = state
        if state != preferred:
            origin = self.origin.get(bond.key, name)
            self._issue("dependent storage", (name,), (bond.key,),
                        f"{self.elements[name]} is in {state} causality, forced by "
                        f"{self.elements[origin] if origin != name else 'a causal loop'}")

    def _preferred_r(self, name: Hashable) -> Hashable:
        """Resistance causality (R imposes effort) unless only the conductance form is explicit."""
        element, bond = self.elements[name], self.at[name][0]
        if element.law is not None:
            try:
                solve_for(element.law, PORT_SYMBOLS["e"], where=str(element))
            except LawError:
                return bond.other(name)
        return name

    def _fix_free(self, bond: Bond, effort_from: Hashable, element: Hashable | None) -> None:
        for choice in (effort_from, bond.other(effort_from)):
            try:
                self._propagate(bond, choice, element if element is not None else choice)
                break
            except _Conflict:
                continue
        else:
            self._issue("conflict", (bond.tail, bond.head), (bond.key,), f"{bond}: no causality is consistent")
            return
        what = f"{self.elements[element]}" if element is not None else f"{bond}"
        self._issue("algebraic loop", (element,) if element is not None else (bond.tail, bond.head), (bond.key,),
                    f"arbitrary causality chosen at {what}: an algebraic loop (zero-order causal path) through it")

    def _issue(self, kind, elements, bonds, message) -> None:
        self.result.issues.append(CausalIssue(kind, tuple(elements), tuple(bonds), message))

    # -- propagation --------------------------------------------------------
    def _propagate(self, bond: Bond, effort_from: Hashable, origin: Hashable) -> None:
        """Assign one bond and everything it implies; undo all of it on conflict."""
        trail: list[tuple] = []
        queue = deque([(bond, effort_from)])
        try:
            while queue:
                current, source = queue.popleft()
                assigned = self.effort_from.get(current.key)
                if assigned is not None:
                    if assigned != source:
                        raise _Conflict(current.tail, f"{current} would need effort from both ends")
                    continue
                self.effort_from[current.key] = source
                self.origin[current.key] = origin
                trail.append(current.key)
                for node in (current.tail, current.head):
                    queue.extend(self._implied(node))
        except _Conflict:
            for key in trail:
                del self.effort_from[key]
                del self.origin[key]
            raise

    def _implied(self, node: Hashable) -> list[tuple[Bond, Hashable]]:
        kind = self.elements[node].kind
        bonds = self.at[node]
        if kind in el.JUNCTIONS:
            return self._junction_rule(node, kind, bonds)
        if kind in el.TWO_PORTS:
            return self._two_port_rule(node, kind, bonds)
        return []

    def _junction_rule(self, node, kind, bonds):
        # 0-junction: exactly one bond brings effort in (effort_from != node).
        # 1-junction: exactly one bond brings flow in, i.e. the junction imposes effort on it.
        def is_strong(bond):
            return (self.effort_from[bond.key] != node) if kind == "0" else (self.effort_from[bond.key] == node)

        assigned = [b for b in bonds if b.key in self.effort_from]
        free = [b for b in bonds if b.key not in self.effort_from]
        strong = [b for b in assigned if is_strong(b)]
        if len(strong) > 1:
            names = ", ".join(str(b) for b in strong)
            what = "effort" if kind == "0" else "flow"
            raise _Conflict(node, f"{self.elements[node]} receives its {what} from more than one bond ({names})")
        if strong:  # every other bond is weak
            return [(b, node if kind == "0" else b.other(node)) for b in free]
        if len(free) == 1:  # the last free bond must be the strong one
            b = free[0]
            return [(b, b.other(node) if kind == "0" else node)]
        if not free:
            what = "effort" if kind == "0" else "flow"
            raise _Conflict(node, f"no bond sets the {what} of {self.elements[node]}")
        return []

    def _two_port_rule(self, node, kind, bonds):
        first, second = bonds
        assigned = [b for b in bonds if b.key in self.effort_from]
        if len(assigned) != 1:
            if len(assigned) == 2:
                out = [self.effort_from[b.key] == node for b in bonds]
                ok = out[0] != out[1] if kind in el.TRANSFORMERS else out[0] == out[1]
                if not ok:
                    rule = ("passes effort through" if kind in el.TRANSFORMERS
                            else "takes effort on both ports or neither")
                    raise _Conflict(node, f"{self.elements[node]} {rule}")
            return []
        known = assigned[0]
        other = second if known is first else first
        imposes = self.effort_from[known.key] == node
        # TF: effort in on one port, out on the other; GY: same role on both ports
        out_on_other = (not imposes) if kind in el.TRANSFORMERS else imposes
        return [(other, node if out_on_other else other.other(node))]
