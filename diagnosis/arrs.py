"""Interval-valued analytical redundancy relations (I-ARRs) from a bond graph.

Jha et al. (2016), section 2.1 (after Samantaray, Djeziri and Ould Bouamama's BG-LFT):

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
   deviations ``delta_<param>``, true value ``value * (1 + delta)``.

Psi_2 is the difference between the balance written with the uncertain laws
and the nominal one, so ``r_n + Psi_2 = 0`` holds exactly for the true system
for any delta in the box.  Element by element it is the BG-LFT uncertain
effort or flow: ``-delta * z`` where the parameter multiplies the law (eq. 7),
the exact difference otherwise (``-delta/(1 + delta) * z`` for ``e = q/C``).

Example
-------
>>> from bondgraph.library import rlc_circuit
>>> arrs = derive_arrs(rlc_circuit())
>>> [(arr.junction, str(arr.nominal)) for arr in arrs]
[('J1', '-L*Derivative(i(t), t) - R*i(t) + V(t) - v_C(t)'), ('J0', '-C*Derivative(v_C(t), t) + i(t)')]
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Hashable
from dataclasses import dataclass, field

import networkx as nx
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph import BondGraph
from bondgraph import elements as el
from bondgraph.causality import diagnosis_causality
from bondgraph.equations import causal_equations, constitutive_law, substitute
from bondgraph.errors import PHMWarning
from bondgraph.structure import Structure, T, signal_function

from .deltas import delta, delta_parameter, latex
from .detection import Evaluation, evaluate
from .residuals import CompiledARR, compile_arr


class ARRWarning(PHMWarning):
    """A candidate ARR that could not be expressed in known variables."""


@dataclass
class ARR:
    """An interval-valued analytical redundancy relation ``r_n + Psi_2 = 0``.

    Attributes
    ----------
    name : str
        ``ARR_<junction>`` (or ``ARR_<detector>`` for a measurement ARR).
    junction : hashable
        The junction whose balance gives the relation.
    nominal : sympy.Expr
        ``r_n`` (Psi_1): signals ``x(t)``, ``Derivative(x(t), t)``,
        ``Integral(..., (t, 0, t))`` and nominal parameter symbols.
    uncertain : sympy.Expr
        Psi_2, in the same signals and ``delta_<param>`` symbols.
    terms : dict
        Uncertain parameter -> its contribution to Psi_2 (the BG-LFT
        uncertain effort or flow ``w`` as seen at the junction).
    parameters : frozenset of str
        Model parameters ``r_n`` is sensitive to (element parameters and law constants).
    values : dict
        Nominal value of every parameter in the relation.
    uncertainties : dict
        Parameter -> ``(delta_lo, delta_hi)`` for the deltas in Psi_2.
    implicit : bool
        True when an element law could not be inverted and the relation keeps
        that law in implicit form; ``blocked_by`` names the elements.
    origin : tuple of str
        For an ARR from a set of the model's equations (:mod:`diagnosis.elimination`), the node and
        role of each equation it comes from; empty for a junction's ARR.

    Examples
    --------
    Obtained from :func:`derive_arrs`; the capacitor junction of the RLC circuit:

    >>> from bondgraph.library import rlc_circuit
    >>> arr = derive_arrs(rlc_circuit())[1]
    >>> print(arr)
    ARR_J0: r_n = -C*Derivative(v_C(t), t) + i(t)
      Psi_2 = -C*delta_C*Derivative(v_C(t), t)
    >>> arr.name, arr.junction, arr.detector, arr.signals
    ('ARR_J0', 'J0', None, ['i', 'v_C'])
    >>> sorted(arr.parameters), arr.values, arr.uncertainties
    (['C'], {'C': 0.001}, {'C': (-0.1, 0.1)})
    >>> arr.terms["C"] == arr.uncertain, arr.implicit
    (True, False)
    """

    name: str
    junction: Hashable
    nominal: sp.Expr
    uncertain: sp.Expr
    terms: dict
    parameters: frozenset
    values: dict
    uncertainties: dict
    candidates: tuple = ()
    detector: Hashable | None = None
    implicit: bool = False
    blocked_by: tuple = ()
    origin: tuple = ()
    _compiled: CompiledARR | None = field(default=None, init=False, repr=False, compare=False)

    @property
    def signals(self) -> list[str]:
        """Names of the measured and input signals the relation uses."""
        return sorted({f.func.__name__ for f in self.nominal.atoms(sp.core.function.AppliedUndef)})

    def __str__(self) -> str:
        return f"{self.name}: r_n = {self.nominal}\n  Psi_2 = {self.uncertain}"

    def latex(self) -> str:
        """LaTeX of ``r_n`` and Psi_2, each delta with its parameter as subscript (:func:`diagnosis.deltas.latex`)."""
        return f"r_{{n}} = {latex(self.nominal)}, \\quad \\Psi_2 = {latex(self.uncertain)}"

    def _repr_latex_(self) -> str:
        return f"$\\displaystyle {self.latex()}$"

    @property
    def compiled(self) -> CompiledARR:
        """The relation compiled for numpy (:func:`~diagnosis.residuals.compile_arr`), built on first use.

        Evaluating an ARR over many records compiles it once: the lambdified functions and
        threshold evaluators are cached on this object.

        >>> from bondgraph.library import rlc_circuit
        >>> arr = derive_arrs(rlc_circuit())[1]
        >>> arr.compiled.points, arr.compiled is arr.compiled
        ([i, v_C, d1_v_C], True)
        """
        if self._compiled is None:
            self._compiled = compile_arr(self)
        return self._compiled

    def evaluate(self, record, **options) -> Evaluation:
        """Residual, thresholds and alarms over a record; see :func:`diagnosis.detection.evaluate`."""
        return evaluate(self, record, **options)


def derive_arrs(bg: BondGraph) -> list[ARR]:
    """Derive the I-ARRs of a bond graph with detectors.

    Parameters
    ----------
    bg : BondGraph
        A model following the model contract of docs/design.md, with De/Df detectors.

    Returns
    -------
    list of ARR
        One per junction carrying a dualized detector, then one per detector
        that had to stay a measurement.  Candidates that cannot be expressed
        in known variables are left out with an :class:`ARRWarning`.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> arrs = derive_arrs(dc_motor())
    >>> [(arr.name, arr.signals) for arr in arrs]
    [('ARR_1_e', ['U', 'i', 'omega']), ('ARR_1_m', ['i', 'omega'])]
    >>> arrs[0].nominal   # electrical balance: U = R_a i + L_a di/dt + k_m omega
    -L_a*Derivative(i(t), t) - R_a*i(t) - k_m*omega(t) + U(t)
    >>> arrs[1].nominal   # mechanical balance: k_m i = J domega/dt + b omega
    -J*Derivative(omega(t), t) - b*omega(t) + k_m*i(t)
    """
    structure = bg.structure()
    causality = diagnosis_causality(bg)
    nominal = causal_equations(bg, causality, structure, keep_blocked=True)
    true = causal_equations(bg, causality, uncertain_structure(structure), keep_blocked=True)
    candidates = candidate_parameters(structure)
    nominal_integrals, true_integrals = _integrals(nominal), _integrals(true)
    uncertainties = parameter_intervals(structure)

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
        arrs.append(split_relation(name, junction, detector, r_n, r_true, blocked_by, structure, candidates,
                                   uncertainties))
    return arrs


def uncertain_structure(structure: Structure) -> Structure:
    """The same model with every uncertain parameter theta replaced by theta (1 + delta_theta).

    >>> from bondgraph.library import rlc_circuit
    >>> uncertain_structure(rlc_circuit().structure()).elements["R"].law
    -R*f*(delta_R + 1) + e
    """
    uncertain = parameter_intervals(structure)
    mapping = {sp.Symbol(p): sp.Symbol(p) * (1 + delta(p)) for p in uncertain}
    elements = {}
    for name, element in structure.elements.items():
        if element.kind in el.LAW_VARIABLES and (element.law is not None or element.param in uncertain):
            element = dataclasses.replace(element, law=constitutive_law(element).xreplace(mapping))
        elif element.modulus is not None:
            element = dataclasses.replace(element, modulus=element.modulus.xreplace(mapping))
        elements[name] = element
    return dataclasses.replace(structure, elements=elements)


def candidate_parameters(structure: Structure) -> tuple:
    """Every element parameter, in element order: the rows of a signature matrix.

    >>> from bondgraph.library import rlc_circuit
    >>> candidate_parameters(rlc_circuit().structure())
    ('R', 'L', 'C')
    """
    return tuple(dict.fromkeys(e.param for e in structure.elements.values() if e.param is not None))


def parameter_intervals(structure: Structure) -> dict:
    """Parameter -> multiplicative interval, element parameters and law constants alike."""
    return {p: u for e in structure.elements.values() for p, u in e.uncertainties.items()}


class _Unknown(Exception):
    pass


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


def split_relation(name, junction, detector, r_n, r_true, blocked_by, structure, candidates, parameters) -> ARR:
    """The ARR of a relation: ``r_n`` nominal, ``r_true`` the same with theta (1 + delta_theta) for each parameter.

    Psi_2 is ``r_true - r_n`` split into one term per delta (BG-LFT), plus the products of deltas if
    an addend holds two.  ``parameters``: parameter -> multiplicative interval of the structure.
    """
    deltas = sorted((s for s in r_true.free_symbols if delta_parameter(s) is not None), key=str)
    # r_true - r_n vanishes with every delta, so each delta's term comes from the addends of r_true
    # that hold it: tidying those alone keeps the cost of an ARR independent of the size of the model
    holding = {d: [] for d in deltas}
    shared = False
    for addend in sp.Add.make_args(r_true):
        held = addend.free_symbols.intersection(deltas)
        shared |= len(held) > 1
        for d in held:
            holding[d].append(addend)
    terms = {}
    for d in deltas:
        part = sp.Add(*holding[d]).xreplace({o: 0 for o in deltas if o is not d})
        terms[delta_parameter(d)] = _tidy(part - part.xreplace({d: 0}))
    uncertain = sp.Add(*terms.values())
    # products of deltas (an uncertain element driven through another one) are what the terms miss
    cross = _tidy(r_true - r_n - uncertain) if shared else sp.S.Zero
    if cross != 0:  # an uncertain element driven through another one: keep the product terms too
        uncertain = uncertain + cross
    names = {s.name for s in r_n.free_symbols}
    values = {p: v for p, v in structure.parameters.items() if p in names or p in terms}
    return ARR(
        name=name,
        junction=junction,
        nominal=r_n,
        uncertain=uncertain,
        terms=terms,
        parameters=frozenset(p for p in structure.parameters if p in names),
        values=values,
        uncertainties={p: parameters[p] for p in terms},
        candidates=candidates,
        detector=detector,
        implicit=bool(blocked_by),
        blocked_by=blocked_by,
    )


def _tidy(expression: sp.Expr) -> sp.Expr:
    """Cancel a difference of balances over a common denominator.

    Derivatives and integrals are frozen as atoms so they are neither split
    nor merged, and no ``simplify`` rewrites ``sign(x)*sqrt(Abs(x))`` into a
    Piecewise that interval arithmetic could not evaluate.
    """
    frozen = {a: sp.Dummy() for a in expression.atoms(sp.Derivative, sp.Integral)}
    numerator, denominator = expression.xreplace(frozen).as_numer_denom()
    tidy = sp.factor_terms(sp.expand(numerator) / denominator)
    return tidy.xreplace({d: a for a, d in frozen.items()})
