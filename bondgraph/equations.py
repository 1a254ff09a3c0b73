"""Bond graph equations with sympy: constitutive and junction equations, causal
solution, and state equations.

Variables
---------
Each power bond with label ``k`` carries an effort ``e_k`` and a flow ``f_k``
(sympy Symbols).  Energy variables of storage elements are functions of time,
``q_<C>(t)`` and ``p_<I>(t)``; signals are ``name(t)`` (docs/design.md, ARR
contract); parameters are Symbols named after ``param``.

Sign conventions: power flows along the bond direction.  A one-port's own flow
is the flow *into* it, ``s * f_k`` with ``s = +1`` if the bond points at the
element and ``-1`` otherwise.  A 0-junction balances ``sum(s_k f_k) = 0`` and a
1-junction ``sum(s_k e_k) = 0``, with ``s_k = +1`` for bonds into the junction.

Causal solution
---------------
Causality turns every element equation into an assignment of the variable it
outputs.  The assignments form a dependency graph; its strongly connected
components are algebraic loops, solved jointly with sympy where possible; the
rest is substituted in topological order.  Work grows with the number of
bonds, not with its cube.  Storage in derivative causality outputs ``d/dt`` of
an expression; the state equations are then linear in the state derivatives
and are solved for them.
"""

from __future__ import annotations

import copy
from collections.abc import Hashable
from dataclasses import dataclass, field

import networkx as nx
import sympy as sp

from . import elements as el
from .calculus import time_derivative
from .causality import INTEGRAL, Causality, assign_causality
from .errors import CausalityError, EquationError, LawError
from .laws import solve_for
from .memo import ContentCache, content_key
from .structure import PORT_SYMBOLS, T, BondGraphLike, Element, require_model, signal_function

__all__ = [
    "E_", "F_", "P_", "Q_", "REMEMBERED", "AlgebraicLoopError", "CausalEquations", "ModelEquation",
    "StateEquations", "causal_equations", "constitutive_law", "ddt", "effort", "energy_variable", "flow",
    "labelled_equations", "model_equations", "resolve", "solve_loop", "state_equations", "substitute",
]

E_, F_, Q_, P_ = (PORT_SYMBOLS[n] for n in "efqp")


class AlgebraicLoopError(EquationError):
    """An algebraic loop sympy cannot solve explicitly; ``variables`` are its bond variables."""

    def __init__(self, message: str, variables):
        super().__init__(message)
        self.variables = tuple(variables)


class ddt(sp.Function):
    """Marker for a time derivative to be taken once its argument is known."""


def effort(label: Hashable) -> sp.Symbol:
    """The effort symbol of bond ``label``: ``e_<label>``."""
    return sp.Symbol(f"e_{label}")


def flow(label: Hashable) -> sp.Symbol:
    """The flow symbol of bond ``label``: ``f_<label>``."""
    return sp.Symbol(f"f_{label}")


def energy_variable(element: Element) -> sp.Expr:
    """``q_<name>(t)`` for a C element, ``p_<name>(t)`` for an I element."""
    return sp.Function(f"{'q' if element.kind == 'C' else 'p'}_{element.name}")(T)


def constitutive_law(element: Element) -> sp.Expr:
    """The element's law as an expression equal to zero; linear by default.

    C: ``e - q/C``;  I: ``f - p/I``;  R: ``e - R*f``.
    """
    if element.law is not None:
        return element.law
    theta = sp.Symbol(element.param)
    return {"C": E_ - Q_ / theta, "I": F_ - P_ / theta, "R": E_ - theta * F_}[element.kind]


# ---------------------------------------------------------------------------
# acausal equations


@dataclass(frozen=True)
class ModelEquation:
    """One acausal equation of a bond graph with the node it comes from.

    Attributes
    ----------
    equation : sympy.Eq
    node : str
        The element or junction the equation belongs to.
    role : str
        ``"source"``, ``"law"`` (constitutive law of C, I, R), ``"storage"`` (``dx/dt`` equals
        the element's flow or effort), ``"transformer"`` (one of the two port relations of a TF
        or GY), ``"common"`` (a junction's common effort or flow), ``"balance"`` (a junction's
        sum) or ``"sensor"`` (a detector reads the junction's common variable).
    """

    equation: sp.Eq
    node: str
    role: str


def labelled_equations(bg: BondGraphLike) -> list[ModelEquation]:
    """Every constitutive and junction equation of ``bg``, without causality, with its node and role.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> first = labelled_equations(rlc_circuit())[0]
    >>> first.equation, first.node, first.role
    (Eq(e_1, V(t)), 'V', 'source')
    """
    require_model(bg, "labelled_equations")
    structure = bg.structure()
    elements, at = structure.elements, structure.at
    equations: list[ModelEquation] = []

    def add(equation: sp.Eq, node: str, role: str) -> None:
        equations.append(ModelEquation(equation, node, role))

    for name, element in elements.items():
        power = [b for b in at[name] if not b.is_signal]
        kind = element.kind
        if kind in el.ONE_PORTS:
            b = power[0]
            s = b.sign_into(name)
            e, f = effort(b.label), s * flow(b.label)
            if kind in el.EFFORT_SOURCES:
                add(_equal(e, signal_function(element.signal)), name, "source")
            elif kind in el.FLOW_SOURCES:
                add(_equal(-f, signal_function(element.signal)), name, "source")
            else:
                x = energy_variable(element) if kind in el.STORAGE else None
                law = constitutive_law(element).xreplace({E_: e, F_: f, Q_: x, P_: x})
                add(_equal(law, 0), name, "law")
                if kind == "C":
                    add(_equal(sp.Derivative(x, T), f), name, "storage")
                elif kind == "I":
                    add(_equal(sp.Derivative(x, T), e), name, "storage")
        elif kind in el.TWO_PORTS:
            one, two = sorted(power, key=lambda b: b.head != name)  # entering bond first
            m = element.modulus
            e1, f1, e2, f2 = effort(one.label), flow(one.label), effort(two.label), flow(two.label)
            pair = [_equal(e1, m * e2), _equal(f2, m * f1)] if kind in el.TRANSFORMERS else \
                [_equal(e1, m * f2), _equal(e2, m * f1)]
            for equation in pair:
                add(equation, name, "transformer")
        elif kind in el.JUNCTIONS:
            common, summed = (effort, flow) if kind == "0" else (flow, effort)
            first = common(power[0].label)
            for b in power[1:]:
                add(_equal(common(b.label), first), name, "common")
            add(_equal(sp.Add(*(b.sign_into(name) * summed(b.label) for b in power)), 0), name, "balance")
            for b in at[name]:
                if b.is_signal:
                    add(_equal(signal_function(elements[b.head].signal), first), b.head, "sensor")
    return equations


def _equal(lhs, rhs) -> sp.Eq:
    """``Eq(lhs, rhs)`` as written: sympy's evaluation of an equality asks assumptions of both sides,
    which costs more than building the whole model and can only turn a model equation into True."""
    return sp.Eq(lhs, rhs, evaluate=False)


def model_equations(bg: BondGraphLike) -> list[sp.Eq]:
    """Every constitutive and junction equation of ``bg``, without causality.

    See :func:`labelled_equations` for the node and role of each.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> model_equations(rlc_circuit())[0]
    Eq(e_1, V(t))
    """
    require_model(bg, "model_equations")
    return [m.equation for m in labelled_equations(bg)]


# ---------------------------------------------------------------------------
# causal equations


@dataclass
class CausalEquations:
    """Element equations oriented by a causal assignment.

    Attributes
    ----------
    assignments : dict
        Bond variable -> expression (in bond variables, energy variables,
        signals, parameters, and ``ddt(...)`` for derivative causality).
    states : dict
        Storage element in integral causality -> its energy variable ``q(t)``/``p(t)``.
    derivatives : dict
        Storage element in integral causality -> d(state)/dt in bond variables.
    outputs : dict
        Measured signal (detector not dualized) -> expression in bond variables.
    balances : dict
        Junction carrying a dualized detector -> its power balance (effort or
        flow sum), in bond variables: the candidate ARR of that junction.
    blocked : dict
        With ``keep_blocked``: placeholder symbol -> (element, law) for a law
        with no explicit solution in the form causality needs; the placeholder
        stands for the unknown port variable and ``law = 0`` still relates it.
    """

    causality: Causality
    assignments: dict = field(default_factory=dict)
    states: dict = field(default_factory=dict)
    derivatives: dict = field(default_factory=dict)
    outputs: dict = field(default_factory=dict)
    balances: dict = field(default_factory=dict)
    owners: dict = field(default_factory=dict)
    blocked: dict = field(default_factory=dict)
    keep_blocked: bool = False
    loops: list = field(default_factory=list)
    unsolved: list = field(default_factory=list)
    _resolved: dict | None = field(default=None, repr=False)

    @property
    def resolved(self) -> dict:
        """Bond variable -> expression in known quantities only (cached).

        With ``keep_blocked`` (diagnosis), an algebraic or differential loop
        that cannot be solved leaves its variables unresolved (listed in
        ``unsolved``) instead of raising.
        """
        if self._resolved is None:
            try:
                self._resolved, self.loops, self.unsolved = resolve(self.assignments, strict=not self.keep_blocked,
                                                                    pending=set(self.blocked))
            except AlgebraicLoopError as exc:
                names = ", ".join(dict.fromkeys(str(self.owners[v]) for v in exc.variables))
                raise AlgebraicLoopError(f"{exc} [elements in the loop: {names}]", exc.variables) from None
        return self._resolved

    def express(self, expression: sp.Expr) -> sp.Expr:
        """Rewrite ``expression`` (in bond variables) in known quantities."""
        return substitute(expression, self.resolved, set(self.assignments) | set(self.blocked))


def causal_equations(bg: BondGraphLike, causality: Causality, structure=None, *,
                     keep_blocked: bool = False) -> CausalEquations:
    """Orient every element equation of ``bg`` according to ``causality``.

    ``keep_blocked``: a law that cannot be solved for the variable causality
    asks of it yields a placeholder (see ``CausalEquations.blocked``) instead
    of an :class:`EquationError`.

    Raises
    ------
    CausalityError
        if the assignment has conflicts or unassigned bonds.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> bg = rlc_circuit()
    >>> oriented = causal_equations(bg, assign_causality(bg))
    >>> oriented.states, oriented.derivatives
    ({'L': p_L(t), 'C': q_C(t)}, {'L': e_3, 'C': f_5})
    >>> oriented.express(oriented.derivatives["L"])   # dp_L/dt in known quantities
    V(t) - R*p_L(t)/L - q_C(t)/C
    >>> oriented.outputs
    {'i': f_3, 'v_C': e_5}

    In derivative causality with dualized detectors each junction gives a balance (a candidate ARR):

    >>> diagnosis = causal_equations(bg, assign_causality(bg, "derivative"))
    >>> diagnosis.express(diagnosis.balances["J0"])
    -C*Derivative(v_C(t), t) + i(t)
    """
    if causality.conflicts or not causality.is_valid:
        problems = "; ".join(str(i) for i in causality.conflicts) or "some bonds have no causality"
        raise CausalityError(f"cannot orient the equations: {problems}")
    result = CausalEquations(causality, keep_blocked=keep_blocked)
    structure = structure or bg.structure()
    elements = structure.elements
    for name, element in elements.items():
        before = len(result.assignments)
        _orient(result, name, element, structure.at[name], elements, causality)
        for var in list(result.assignments)[before:]:
            result.owners[var] = element
    return result


def _orient(result: CausalEquations, name, element: Element, bonds, elements, causality: Causality) -> None:
    assign = result.assignments
    kind = element.kind
    ef = causality.effort_from
    power = [b for b in bonds if not b.is_signal]
    if kind in el.ONE_PORTS:
        b = power[0]
        s = b.sign_into(name)
        e, f = effort(b.label), flow(b.label)
        if kind in el.EFFORT_SOURCES:
            assign[e] = signal_function(element.signal)
        elif kind in el.FLOW_SOURCES:
            assign[f] = -s * signal_function(element.signal)
        elif kind == "R":
            law = constitutive_law(element)
            if ef[b.key] == name:  # resistance causality: e = phi(f)
                assign[e] = _solve(result, law, E_, element, {F_: s * f})
            else:  # conductance causality: f = phi^-1(e)
                assign[f] = s * _solve(result, law, F_, element, {E_: e})
        else:
            _orient_storage(result, name, element, b, s, causality.storage[name])
    elif kind in el.TWO_PORTS:
        one, two = sorted(power, key=lambda b: b.head != name)
        m = element.modulus
        e1, f1, e2, f2 = effort(one.label), flow(one.label), effort(two.label), flow(two.label)
        if kind in el.TRANSFORMERS:
            if ef[one.key] != name:  # effort enters at port 1: e2 = e1/m, f1 = f2/m
                assign[e2], assign[f1] = e1 / m, f2 / m
            else:
                assign[e1], assign[f2] = m * e2, m * f1
        else:
            if ef[one.key] == name:  # GY imposes both efforts
                assign[e1], assign[e2] = m * f2, m * f1
            else:
                assign[f2], assign[f1] = e1 / m, e2 / m
    elif kind in el.JUNCTIONS:
        _orient_junction(result, name, kind, bonds, elements, causality)


def _orient_storage(result, name, element, bond, s, state):
    e, f = effort(bond.label), flow(bond.label)
    law = constitutive_law(element)
    x = energy_variable(element)
    if element.kind == "C":
        if state == INTEGRAL:  # e = phi(q), dq/dt = flow in
            result.assignments[e] = _solve(result, law, E_, element, {Q_: x})
            result.states[name], result.derivatives[name] = x, s * f
        else:  # f = d/dt phi^-1(e)
            result.assignments[f] = s * ddt(_solve(result, law, Q_, element, {E_: e}))
    else:
        if state == INTEGRAL:  # f = phi(p), dp/dt = e
            result.assignments[f] = s * _solve(result, law, F_, element, {P_: x})
            result.states[name], result.derivatives[name] = x, e
        else:  # e = d/dt phi^-1(f)
            result.assignments[e] = ddt(_solve(result, law, P_, element, {F_: s * f}))


def _orient_junction(result, name, kind, bonds, elements, causality):
    ef = causality.effort_from
    common, summed = (effort, flow) if kind == "0" else (flow, effort)

    def is_strong(b):
        return (ef[b.key] != name) if kind == "0" else (ef[b.key] == name)

    strong = next(b for b in bonds if is_strong(b))
    power = [b for b in bonds if not b.is_signal]
    if strong.is_signal:  # a dualized detector imposes the common variable
        value = signal_function(elements[strong.head].signal)
        for b in power:
            result.assignments[common(b.label)] = value
        result.balances[name] = sp.Add(*(b.sign_into(name) * summed(b.label) for b in power))
    else:
        value = common(strong.label)
        for b in power:
            if b is not strong:
                result.assignments[common(b.label)] = value
        others = sp.Add(*(b.sign_into(name) * summed(b.label) for b in power if b is not strong))
        result.assignments[summed(strong.label)] = -strong.sign_into(name) * others
    for b in bonds:
        if b.is_signal and b is not strong:
            result.outputs[elements[b.head].signal] = value


# Explicit forms of the default linear laws, so they need no symbolic solve.
_LINEAR_FORMS = {
    ("C", "e"): lambda th: Q_ / th, ("C", "q"): lambda th: th * E_,
    ("I", "f"): lambda th: P_ / th, ("I", "p"): lambda th: th * F_,
    ("R", "e"): lambda th: th * F_, ("R", "f"): lambda th: E_ / th,
}


def _solve(result: CausalEquations, law: sp.Expr, variable: sp.Symbol, element: Element, ports: dict) -> sp.Expr:
    """The law solved for ``variable``, with the other port variable(s) replaced by ``ports``."""
    if element.law is None:
        return _LINEAR_FORMS[(element.kind, variable.name)](sp.Symbol(element.param)).xreplace(ports)
    try:
        return solve_for(law, variable, where=str(element)).xreplace(ports)
    except LawError as exc:
        if not result.keep_blocked:
            raise EquationError(f"{exc} (the causality puts {element} in a form that needs {variable})") from None
    placeholder = sp.Symbol(f"_{variable}_{element.name}")
    result.blocked[placeholder] = (element, law.xreplace({variable: placeholder, **ports}))
    return placeholder


# ---------------------------------------------------------------------------
# resolution


def substitute(expression: sp.Expr, resolved: dict, unknowns: set = frozenset()) -> sp.Expr:
    """Replace resolved bond variables and carry out pending ``ddt`` derivatives.

    A ``ddt`` whose argument still holds one of ``unknowns`` stays pending:
    differentiating an unresolved symbol would wrongly give zero.
    """
    mapping = {s: resolved[s] for s in expression.free_symbols if s in resolved}
    if mapping:
        expression = expression.xreplace(mapping)
    if expression.has(ddt):
        expression = expression.replace(
            lambda e: isinstance(e, ddt) and not (e.free_symbols & unknowns),
            lambda e: time_derivative(e.args[0]),
        )
    return expression


def resolve(assignments: dict, *, strict: bool = True, pending: set = frozenset()) -> tuple[dict, list, list]:
    """Express every assigned variable in known quantities.

    Returns the resolved mapping, the algebraic loops solved and the loops
    left unsolved (``strict=False`` only), each a tuple of its variables.
    An unsolved loop's variables resolve to themselves, so whatever depends
    on them visibly keeps an unknown.  ``pending``: further unknowns that no
    assignment gives (the placeholders of blocked laws); a ``ddt`` of them
    stays pending too, rather than differentiate them as constants.

    Raises
    ------
    AlgebraicLoopError
        with ``strict``, for a loop that has no unique explicit solution.
    """
    graph = nx.DiGraph()
    graph.add_nodes_from(assignments)
    for var, expression in assignments.items():
        graph.add_edges_from((dep, var) for dep in expression.free_symbols & assignments.keys())
    unknowns = set(assignments) | set(pending)
    condensed = nx.condensation(graph)
    resolved: dict = {}
    loops: list = []
    unsolved: list = []
    for component in nx.topological_sort(condensed):
        members = sorted(condensed.nodes[component]["members"], key=sp.default_sort_key)
        if len(members) == 1 and not graph.has_edge(members[0], members[0]):
            resolved[members[0]] = substitute(assignments[members[0]], resolved, unknowns)
            continue
        equations = [var - substitute(assignments[var], resolved, unknowns) for var in members]
        try:
            resolved.update(solve_loop(equations, members))
            loops.append(tuple(members))
        except AlgebraicLoopError:
            if strict:
                raise
            resolved.update({var: var for var in members})
            unsolved.append(tuple(members))
    return resolved, loops, unsolved


def solve_loop(equations: list, unknowns: list) -> dict:
    """Solve the equations of an algebraic loop (each ``= 0``) for ``unknowns``.

    Variables that enter an equation linearly, with a coefficient free of the
    loop's unknowns, are eliminated one by one.  What is left must be
    polynomial and have a single solution, which sympy then finds; a loop
    through ``sign``, ``Abs``, ``sqrt``... is reported rather than handed to
    ``sympy.solve``, which may not terminate on it.

    Examples
    --------
    >>> x, y, a = sp.symbols("x y a")
    >>> solve_loop([x - a*y - 1, y - x/2], [x, y])
    {x: -2/(a - 2), y: -1/(a - 2)}
    """
    looped = set(unknowns)
    if any(d.free_symbols & looped for eq in equations for d in eq.atoms(ddt)):
        # a loop variable under a derivative: a differential loop; eliminating a long one first costs
        # minutes (an RLC ladder) to find the same
        raise AlgebraicLoopError(
            f"differential loop in {', '.join(map(str, unknowns))}: a variable depends on its own time derivative",
            unknowns,
        )
    pending, free, solution = list(equations), list(unknowns), {}
    progress = True
    while pending and progress:
        progress = False
        for equation in pending:
            variable = next((v for v in free if _enters_linearly(equation, v, free)), None)
            if variable is None:
                continue
            value = -equation.subs(variable, 0) / sp.diff(equation, variable)
            pending.remove(equation)
            free.remove(variable)
            pending = [eq.xreplace({variable: value}) for eq in pending]
            solution = {v: x.xreplace({variable: value}) for v, x in solution.items()}
            solution[variable] = value
            progress = True
            break
    if pending:
        polynomial = all(eq.is_polynomial(*free) for eq in pending)
        roots = sp.solve(pending, free, dict=True) if polynomial else []
        if len(roots) != 1 or set(roots[0]) != set(free):
            reason = (f"{len(roots)} solution(s)" if polynomial else "it is not polynomial in them")
            raise AlgebraicLoopError(
                f"algebraic loop in {', '.join(map(str, unknowns))}: no unique explicit solution for "
                f"{', '.join(map(str, free))} ({reason}); remaining: "
                + "; ".join(f"{eq} = 0" for eq in pending),
                unknowns,
            )
        solution = {v: x.xreplace(roots[0]) for v, x in solution.items()}
        solution.update(roots[0])
    if any(x.has(ddt) for x in solution.values()):  # a derivative of a loop variable: a differential loop
        raise AlgebraicLoopError(
            f"differential loop in {', '.join(map(str, unknowns))}: a variable depends on its own time derivative",
            unknowns,
        )
    return {v: sp.simplify(x) for v, x in solution.items()}


def _enters_linearly(equation: sp.Expr, variable: sp.Symbol, unknowns: list) -> bool:
    coefficient = sp.diff(equation, variable)
    return coefficient != 0 and not any(coefficient.has(u) for u in unknowns)


# ---------------------------------------------------------------------------
# state equations


@dataclass
class StateEquations:
    """Explicit state equations ``dx/dt = rhs(x, u, theta)`` and outputs.

    Attributes
    ----------
    states : list of sympy.Symbol
        Energy variables ``q_<C>``, ``p_<I>`` of storage in integral causality.
    elements : list
        The storage element of each state.
    rhs : list of sympy.Expr
        Time derivative of each state, in states, input signals ``u(t)`` and
        parameter symbols.
    inputs : list of str
        Input signal names.
    outputs : dict
        Measured signal -> expression.
    efforts, flows : dict
        Bond label -> expression of its effort and flow.
    parameters : dict
        Parameter name -> nominal value.
    causality : Causality
    algebraic_loops : list
        Tuples of bond variables of the algebraic loops solved symbolically.

    Examples
    --------
    Obtained from :meth:`BondGraph.state_equations <bondgraph.model.BondGraph.state_equations>`
    or :func:`state_equations`:

    >>> from bondgraph.library import rlc_circuit
    >>> eqs = rlc_circuit().state_equations()
    >>> print(eqs)
    dp_L/dt = V(t) - R*p_L/L - q_C/C
    dq_C/dt = p_L/L
    i = p_L/L
    v_C = q_C/C
    >>> eqs.states, eqs.elements, eqs.inputs, eqs.parameters
    ([p_L, q_C], ['L', 'C'], ['V'], {'R': 10.0, 'L': 0.1, 'C': 0.001})
    >>> eqs.efforts[2], eqs.flows[2]   # bond 2 is J1 -> R
    (R*p_L/L, p_L/L)
    >>> eqs.dependent_storage, eqs.algebraic_loops
    ([], [])
    """

    states: list
    elements: list
    rhs: list
    inputs: list
    outputs: dict
    efforts: dict
    flows: dict
    parameters: dict
    causality: Causality
    algebraic_loops: list
    ports: dict = field(default_factory=dict)
    #: Numeric functions compiled from these equations (by :func:`~bondgraph.simulation.simulate`), shared by copies.
    compiled: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def dependent_storage(self) -> list:
        """Storage elements in derivative causality, forced by others, so without a state (from ``causality``)."""
        return self.causality.dependent_storage

    def power(self, element: Hashable) -> sp.Expr:
        """Power flowing into one-port ``element``, ``sum_k s_k e_k f_k``, in states and inputs.

        For an R element this is the power it dissipates (Rodriguez Obando et al. (2021), eq. 6: ``P_c = F_c v``).

        >>> from bondgraph.library import rlc_circuit
        >>> rlc_circuit().state_equations().power("R")
        R*p_L**2/L**2
        """
        if element not in self.ports:
            raise KeyError(f"{element!r} is not a one-port element of the model; one-ports are {list(self.ports)}")
        return sum((s * self.efforts[k] * self.flows[k] for k, s in self.ports[element]), sp.S.Zero)

    def coenergy_states(self, names: dict | None = None) -> "StateEquations":
        """The same equations with each storage state replaced by its co-energy variable.

        An I element's state ``p`` becomes its flow ``f = p/I`` (a velocity), a C
        element's ``q`` its effort ``e = q/C``; with ``x = g^{-1}(y)``,
        ``dy/dt = g'(x) dx/dt``.  ``names`` maps storage element -> new state name
        (default ``f_<I>`` / ``e_<C>``).  The law must be invertible for the state.

        >>> from bondgraph.library import rlc_circuit
        >>> eqs = rlc_circuit().state_equations().coenergy_states({"L": "i"})
        >>> eqs.states, eqs.rhs[0]
        ([i, e_C], (-R*i - e_C + V(t))/L)
        """
        names = dict(names or {})
        unknown = sorted(map(str, set(names) - set(self.elements)))
        if unknown:
            raise KeyError(f"{unknown} are not storage elements with a state; they are {self.elements}")
        new_states, forward, backward = [], {}, {}
        for x, element in zip(self.states, self.elements):
            (label, sign), = self.ports[element]
            kind = "I" if str(x).startswith("p_") else "C"  # energy_variable names them p_<I>, q_<C>
            co = sign * self.flows[label] if kind == "I" else self.efforts[label]
            y = sp.Symbol(names.get(element, f"{'f' if kind == 'I' else 'e'}_{element}"))
            solutions = sp.solve(sp.Eq(co, y), x, dict=True)
            if len(solutions) != 1 or x not in solutions[0]:
                raise EquationError(f"storage {element!r}: cannot invert its law {co} for the state {x}")
            new_states.append(y)
            forward[x] = co
            backward[x] = solutions[0][x]
        rhs = [sp.simplify((sp.diff(forward[x], x) * r).xreplace(backward))
               for x, r in zip(self.states, self.rhs)]

        def swap(expression):
            return sp.simplify(expression.xreplace(backward))

        return StateEquations(
            states=new_states, elements=list(self.elements), rhs=rhs, inputs=list(self.inputs),
            outputs={k: swap(v) for k, v in self.outputs.items()},
            efforts={k: swap(v) for k, v in self.efforts.items()}, flows={k: swap(v) for k, v in self.flows.items()},
            parameters=dict(self.parameters), causality=self.causality, algebraic_loops=list(self.algebraic_loops),
            ports=dict(self.ports),
        )

    def __str__(self) -> str:
        lines = [f"d{x}/dt = {rhs}" for x, rhs in zip(self.states, self.rhs)]
        lines += [f"{name} = {expr}" for name, expr in self.outputs.items()]
        return "\n".join(lines)


def state_equations(bg: BondGraphLike, causality: Causality | None = None) -> StateEquations:
    """Derive the state equations of ``bg`` in (preferred) integral causality.

    Storage forced into derivative causality (dependent storage) is handled by
    solving the equations, which are then linear in the state derivatives.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> eqs = rlc_circuit().state_equations()
    >>> eqs.states, eqs.rhs[0]
    ([p_L, q_C], V(t) - R*p_L/L - q_C/C)

    The equations of the last :data:`REMEMBERED` models (by content) are remembered: asking again, say
    for each run of a parameter sweep, returns a copy at no cost.
    """
    require_model(bg, "state_equations")
    if causality is None:
        remembered = _REMEMBERED.get(content_key(("state_equations", bg.structure())),
                                     lambda: _state_equations(bg, assign_causality(bg, INTEGRAL,
                                                                                   dualize_detectors=False)))
        return _copy(remembered)
    return _state_equations(bg, causality)


#: How many models' state equations :func:`state_equations` remembers.
REMEMBERED = 64
_REMEMBERED = ContentCache(REMEMBERED)


def _copy(equations: StateEquations) -> StateEquations:
    """A copy whose lists and dicts the caller may change; the causality and compiled functions are shared."""
    twin = copy.copy(equations)
    for name in ("states", "elements", "rhs", "inputs", "algebraic_loops"):
        setattr(twin, name, list(getattr(equations, name)))
    for name in ("outputs", "efforts", "flows", "parameters", "ports"):
        setattr(twin, name, dict(getattr(equations, name)))
    return twin


def _state_equations(bg: BondGraphLike, causality: Causality) -> StateEquations:
    if causality.dualized:
        raise CausalityError("state equations need detectors as measurements, not dualized sources")
    structure = bg.structure()
    oriented = causal_equations(bg, causality, structure)
    resolved = oriented.resolved
    names = list(oriented.states)
    functions = [oriented.states[n] for n in names]
    symbols = [sp.Symbol(str(x.func)) for x in functions]
    to_symbol = dict(zip(functions, symbols))
    rhs = [substitute(oriented.derivatives[n], resolved) for n in names]
    rhs = _solve_for_derivatives(rhs, functions, [structure.elements[n] for n in names])

    rates = {sp.Derivative(x, T): r for x, r in zip(functions, rhs)}

    def finish(expression):
        """Dependent storage leaves d(state)/dt in efforts and flows: use the state equations."""
        if expression.has(sp.Derivative):
            expression = expression.xreplace(rates)
        return expression.xreplace(to_symbol)

    labels = [b.label for b in structure.bonds if not b.is_signal]
    efforts = {k: finish(resolved.get(effort(k), effort(k))) for k in labels}
    flows = {k: finish(resolved.get(flow(k), flow(k))) for k in labels}
    outputs = {s: finish(oriented.express(expr)) for s, expr in oriented.outputs.items()}
    return StateEquations(
        states=symbols,
        elements=names,
        rhs=[finish(r) for r in rhs],
        inputs=structure.inputs,
        outputs=outputs,
        efforts=efforts,
        flows=flows,
        parameters=structure.parameters,
        causality=causality,
        algebraic_loops=oriented.loops,
        ports=_one_ports(structure),
    )


def _one_ports(structure) -> dict:
    """One-port element -> [(bond label, +1 if the bond points at it else -1)]."""
    return {name: [(b.label, b.sign_into(name)) for b in structure.at[name] if not b.is_signal]
            for name, element in structure.elements.items() if element.kind in el.ONE_PORTS}


def _solve_for_derivatives(rhs: list, states: list, elements: list) -> list:
    """Eliminate ``d x_j/dt`` terms (from dependent storage) from the right-hand sides."""
    pending = [i for i, r in enumerate(rhs) if r.has(sp.Derivative)]
    if not pending:
        return rhs
    derivatives = {sp.Derivative(x, T): sp.Symbol(f"_d_{x.func}") for x in states}
    unknown_derivatives = set()
    for i in pending:
        unknown_derivatives |= rhs[i].atoms(sp.Derivative)
    stray = unknown_derivatives - set(derivatives)
    if stray:
        raise EquationError(
            f"state equations need time derivatives of {sorted(map(str, stray))}: "
            "a storage element in derivative causality is driven by an input"
        )
    involved = {derivatives[d] for d in unknown_derivatives}
    rows = sorted(set(pending) | {i for i, x in enumerate(states) if derivatives[sp.Derivative(x, T)] in involved})
    unknowns = [derivatives[sp.Derivative(states[i], T)] for i in rows]
    equations = [unknowns[k] - rhs[i].xreplace(derivatives) for k, i in enumerate(rows)]
    solution = sp.solve(equations, unknowns, dict=True)
    if len(solution) != 1:
        raise EquationError(
            "dependent storage: cannot solve for the derivatives of "
            + ", ".join(str(elements[i]) for i in rows)
        )
    rhs = list(rhs)
    for k, i in enumerate(rows):
        rhs[i] = sp.simplify(solution[0][unknowns[k]])
    return rhs
