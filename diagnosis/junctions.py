"""ARRs along causal paths: one per junction that carries a sensor (Jha et al. (2016), section 2.1).

After Samantaray, Djeziri and Ould Bouamama's BG-LFT:

1. preferred derivative causality, detectors dualized (De -> SSe, Df -> SSf);
2. one candidate ARR per junction carrying a dualized detector: its power
   balance ``sum(s e) = 0`` (1-junction) or ``sum(s f) = 0`` (0-junction)
   (eqs. 8-9); a detector that cannot be dualized (its junction's variable is
   already imposed) stays a measurement and gives ``y - computed y``;
3. unknown efforts and flows eliminated along causal paths back to inputs,
   measured signals and their derivatives; storage left in integral causality
   with a known input becomes an integral from the start of the record
   (Jha et al. (2016), eq. 45, the shaft spring; the energy variable is taken as zero at
   the start of the record);
4. the uncertain parameters split each ARR into a nominal part ``r_n``
   (Psi_1, nominal values) and an uncertain part Psi_2 in the multiplicative
   deviations ``delta_<param>``, true value ``value * (1 + delta)``
   (:func:`diagnosis.arr.split_relation`).

An integral of measured signals is a random walk of their noise, and it assumes the storage was
empty at the start of the record.  With ``integrals="avoid"`` (the default of
:func:`diagnosis.derive_arrs`) a balance that holds integrals only linearly is differentiated once
instead: the same relation, one derivative higher, without drift.

Example
-------
>>> from bondgraph.library import rlc_circuit
>>> arrs = junction_arrs(rlc_circuit())
>>> [(arr.junction, str(arr.nominal)) for arr in arrs]
[('J1', '-L*Derivative(i(t), t) - R*i(t) + V(t) - v_C(t)'), ('J0', '-C*Derivative(v_C(t), t) + i(t)')]
"""

from __future__ import annotations

import warnings

import networkx as nx
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph import elements as el
from bondgraph.causality import diagnosis_causality
from bondgraph.equations import causal_equations, substitute
from bondgraph.structure import Structure, T, require_model, signal_function

from .arr import (ARR, ARRWarning, candidate_parameters, check_integral_form, measured_signals,
                       parameter_intervals, split_relation, uncertain_structure, written_without_integrals)

__all__ = ["junction_arrs"]

def junction_arrs(bg, *, integrals: str = "avoid") -> list[ARR]:
    """The I-ARRs of a bond graph along causal paths, one per junction carrying a sensor.

    Parameters
    ----------
    bg : BondGraph
        A model following the model contract of docs/design.md, with De/Df detectors.
    integrals : {"avoid", "keep"}
        ``"avoid"``: a balance holding integrals of measured signals only linearly is differentiated
        (``form`` ``"differentiated balance"``); one where an integral enters non-linearly keeps it
        (``form`` ``"balance with integral"``).  ``"keep"`` writes every integral.

    Returns
    -------
    list of ARR
        One per junction carrying a dualized detector, then one per detector
        that had to stay a measurement.  Candidates that cannot be expressed
        in known variables are left out with an :class:`ARRWarning`.

    Examples
    --------
    >>> from bondgraph.library import dc_motor, torsion_bar_monitorable
    >>> arrs = junction_arrs(dc_motor())
    >>> [(arr.name, arr.signals) for arr in arrs]
    [('ARR_1_e', ['U', 'i', 'omega']), ('ARR_1_m', ['i', 'omega'])]
    >>> arrs[0].nominal   # electrical balance: U = R_a i + L_a di/dt + k_m omega
    -L_a*Derivative(i(t), t) - R_a*i(t) - k_m*omega(t) + U(t)
    >>> arrs[1].origin
    ('1_m balance', 'GY transformer', 'J law', 'b law', 'i sensor', 'omega sensor')
    >>> [(arr.form, arr.order) for arr in junction_arrs(torsion_bar_monitorable(), integrals="keep")]
    [('balance with integral', 1), ('balance with integral', 1)]
    >>> [(arr.form, arr.order) for arr in junction_arrs(torsion_bar_monitorable())]
    [('differentiated balance', 2), ('differentiated balance', 2)]
    """
    require_model(bg, "junction_arrs")
    check_integral_form(integrals)
    structure = bg.structure()
    causality = diagnosis_causality(bg)
    nominal = causal_equations(bg, causality, structure, keep_blocked=True)
    true = causal_equations(bg, causality, uncertain_structure(structure), keep_blocked=True)
    candidates = candidate_parameters(structure)
    nominal_integrals, true_integrals = _integrals(nominal), _integrals(true)
    uncertainties = parameter_intervals(structure)
    sensors, users = measured_signals(structure), _users(structure)

    arrs = []
    sources = [(junction, None, nominal.balances[junction], true.balances[junction]) for junction in nominal.balances]
    for detector, element in structure.elements.items():
        if element.kind in el.DETECTORS and detector not in causality.dualized:
            y = signal_function(element.signal)
            junction = next(b.tail for b in structure.at[detector])
            sources.append((junction, detector, y - nominal.outputs[element.signal], y - true.outputs[element.signal]))
    for junction, detector, balance, true_balance in sources:
        name = f"ARR_{junction if detector is None else detector}"
        try:
            r_n, blocked_by = _known(balance, nominal, nominal_integrals)
            r_true, _ = _known(true_balance, true, true_integrals)
        except _Unknown as exc:
            warnings.warn(f"{name}: cannot be expressed in known variables ({exc})", ARRWarning, stacklevel=2)
            continue
        if _not_finite(r_n) or _not_finite(r_true):
            culprits = [str(e) for e in structure.elements.values() if e.law is not None and _not_finite(e.law)]
            warnings.warn(f"{name}: left out, its relation is not finite ({r_n}); "
                          f"{', '.join(culprits) or 'a law'} divides by zero", ARRWarning, stacklevel=2)
            continue
        r_n, r_true, form = written_without_integrals(r_n, r_true, "balance", avoid=integrals == "avoid")
        origin = _origin(users, junction, detector, r_n)
        arrs.append(split_relation(name, junction, detector, r_n, r_true, blocked_by, structure, candidates,
                                   uncertainties, origin=origin, form=form, sensors=sensors))
    return arrs


def _not_finite(expression: sp.Expr) -> bool:
    """Whether ``expression`` holds an infinity or NaN (a law that divides by zero)."""
    return expression.has(sp.zoo, sp.oo, -sp.oo, sp.nan)


def _users(structure: Structure) -> dict:
    """Parameter or signal name -> the ``"<node> <role>"`` of each element that holds it, indexed once."""
    users: dict = {}
    for name, element in structure.elements.items():
        if element.kind in el.DETECTORS:
            users.setdefault(("signal", element.signal), []).append(f"{name} sensor")
        elif element.kind in el.SOURCES:
            users.setdefault(("signal", element.signal), []).append(f"{name} source")
        elif element.param is not None:
            role = "transformer" if element.kind in el.TWO_PORTS else "law"
            users.setdefault(("parameter", element.param), []).append(f"{name} {role}")
    return users


def _origin(users: dict, junction, detector, r_n: sp.Expr) -> tuple:
    """The equations a junction's ARR uses: its balance (or read-out), the elements whose parameters
    it holds, the sources and sensors whose signals it reads."""
    keys = [("parameter", s.name) for s in r_n.free_symbols]
    keys += [("signal", f.func.__name__) for f in r_n.atoms(AppliedUndef)]
    first = f"{detector} sensor" if detector is not None else f"{junction} balance"
    used = {entry for key in keys for entry in users.get(key, ())} - {first}
    return (first, *sorted(used, key=_by_role))


def _by_role(entry: str) -> tuple:
    node, role = entry.rsplit(" ", 1)
    return ({"source": 0, "transformer": 1, "law": 2, "sensor": 3}.get(role, 4), node)


class _Unknown(Exception):
    """A balance needs a variable no causal path gives in known signals."""


def _known(expression: sp.Expr, equations, integrals: dict) -> tuple[sp.Expr, tuple]:
    """Rewrite a balance in known variables: signals, their derivatives and ``integrals`` (of ``equations``)."""
    expression = equations.express(expression)
    expression = expression.xreplace(integrals)
    blocked_by = ()
    for placeholder, (element, law) in equations.blocked.items():
        if not expression.has(placeholder):
            continue
        law = equations.express(law).xreplace(integrals)
        coefficient = sp.diff(expression, placeholder)
        if coefficient == 0 or coefficient.has(placeholder):
            raise _Unknown(f"{element} law cannot be inverted and does not enter the balance linearly")
        # the balance gives the blocked variable; its law, written with it, is the (implicit) relation
        value = -expression.subs(placeholder, 0) / coefficient
        expression = law.xreplace({placeholder: value})
        blocked_by += (element.name,)
    leftover = expression.free_symbols & (set(equations.assignments) | set(equations.blocked))
    states = {f for f in expression.atoms(sp.core.function.AppliedUndef) if f in set(equations.states.values())}
    if leftover or states:
        named = [f"{v} (from {equations.owners[v]})" if v in equations.owners else str(v)
                 for v in sorted(leftover | states, key=str)]
        raise _Unknown(f"needs unmeasured {', '.join(named)}")
    return expression, blocked_by


def _integrals(equations) -> dict:
    """Energy variables of storage left in integral causality, as integrals of known flows/efforts.

    A state is known once every state its rate needs is known: the rates' dependencies form a graph,
    built once, and the integrals are made in a topological order of it (linear in the number of
    states).  A state on a cycle of that graph, or fed by one, has no integral of known quantities.
    """
    rates = {x: substitute(equations.derivatives[name], equations.resolved) for name, x in equations.states.items()}
    needs = nx.DiGraph()
    needs.add_nodes_from(rates)
    needs.add_edges_from((other, x) for x, rate in rates.items() for other in rate.atoms(AppliedUndef) & rates.keys())
    cyclic = {x for component in nx.strongly_connected_components(needs)
              for x in component if len(component) > 1 or needs.has_edge(x, x)}
    unknown = cyclic.union(*(nx.descendants(needs, x) for x in cyclic))
    known: dict = {}
    for x in nx.topological_sort(needs.subgraph(set(rates) - unknown)):
        known[x] = sp.Integral(rates[x].xreplace(known), (T, 0, T))
    return known


