"""The analytical redundancy relation: a nominal part, an interval-uncertain part, and where it comes from.

An ARR ``r_n + Psi_2 = 0`` (Jha et al. (2016), eqs. 10-13, 18) holds for the true system for any
multiplicative deviation ``delta_theta`` of the parameters in their box.  :func:`split_relation` makes
one from a relation written twice, with the nominal parameters and with theta (1 + delta_theta)
(:func:`uncertain_structure`): Psi_2 is the difference, split into one BG-LFT term per parameter.
The two routes that write relations, causal paths (:mod:`diagnosis.junctions`) and the elimination of
overdetermined sets (:mod:`diagnosis.elimination`), both end here; :func:`diagnosis.derive_arrs`
combines them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Hashable
from dataclasses import dataclass, field

import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph import elements as el
from bondgraph.calculus import time_derivative
from bondgraph.equations import constitutive_law
from bondgraph.dimensions import ModelUnits
from bondgraph.errors import PHMWarning
from bondgraph.units import Unit, UnitError, dimension_of
from bondgraph.structure import Structure, T

from .deltas import delta, delta_parameter, latex
from .detection import Evaluation, evaluate
from .integral_forms import factor_out_of_integrals
from .records import Record
from .residuals import CompiledARR, compile_arr, read_record

__all__ = [
    "ARR", "INTEGRAL_FORMS", "TIDY_LIMIT", "ARRWarning", "candidate_parameters", "check_integral_form",
    "measured_signals", "parameter_intervals", "split_relation", "uncertain_structure",
    "written_without_integrals",
]


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
    sensors : tuple of str
        The model's measured signals: with ``candidates``, the fault candidates of a signature matrix
        (a sensor fault acts on the ARRs that read its signal).
    origin : tuple of str
        The equations the relation comes from, as ``"<node> <role>"``: the junction balance and the
        elements of its causal paths for a junction's ARR, every equation of the set for one from
        :mod:`diagnosis.elimination`.
    form : str
        How the relation is written: ``"balance"``, ``"differentiated balance"`` (written without the
        integral of a measured signal, which drifts with its noise), ``"balance with integral"`` (an
        integral kept, and why) or ``"elimination"``.

    Examples
    --------
    Obtained from :func:`derive_arrs`; the capacitor junction of the RLC circuit:

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
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
    sensors: tuple = ()
    origin: tuple = ()
    form: str = "balance"
    _compiled: CompiledARR | None = field(default=None, init=False, repr=False, compare=False)

    #: Whether the relation reads states it simulates (:class:`~diagnosis.simulation_residuals.SimulationARR`):
    #: such a relation has no closed form for a consumer that compiles ``nominal`` alone.
    simulation = False

    @property
    def signals(self) -> list[str]:
        """Names of the measured and input signals the relation uses."""
        return sorted({f.func.__name__ for f in self.nominal.atoms(sp.core.function.AppliedUndef)})

    @property
    def derivatives(self) -> dict:
        """Signal -> the highest time derivative of it the relation needs (0: the signal itself).

        >>> from diagnosis import derive_arrs
        >>> from bondgraph.library import rlc_circuit
        >>> derive_arrs(rlc_circuit())[0].derivatives
        {'V': 0, 'i': 1, 'v_C': 0}
        """
        orders = dict.fromkeys(self.signals, 0)
        for d in self.nominal.atoms(sp.Derivative):
            name = d.expr.func.__name__
            orders[name] = max(orders.get(name, 0), d.derivative_count)
        return orders

    @property
    def order(self) -> int:
        """The highest time derivative of a signal the relation needs."""
        return max(self.derivatives.values(), default=0)

    @property
    def integrals(self) -> list[str]:
        """The integrals from the start of the record the relation needs, as text (each drifts with its noise)."""
        return sorted(str(i.function) for i in self.nominal.atoms(sp.Integral))

    def unit(self, units: ModelUnits) -> Unit | None:
        """The unit of the residual ``r_n`` given the model's units (:attr:`bondgraph.model.BondGraph.units`), or
        None when a name in it has none.

        A junction's balance is in its bonds' effort (1-junction) or flow (0-junction) unit; a differentiated
        form is in that unit per second.

        >>> from bondgraph.library import dc_motor
        >>> from diagnosis import derive_arrs
        >>> [str(arr.unit(dc_motor().units)) for arr in derive_arrs(dc_motor())]
        ['V', 'N*m']
        """
        try:
            return dimension_of(self.nominal, units.symbols())
        except (KeyError, UnitError):
            return None

    def __str__(self) -> str:
        return f"{self.name}: r_n = {self.nominal}\n  Psi_2 = {self.uncertain}"

    def __dask_tokenize__(self) -> tuple:
        """What Dask hashes to name a task that takes this ARR: its fields, not the compiled cache.

        The compiled ARR points back to this one; followed, the cycle made ``dask.base.tokenize``
        (and so ``Client.submit(f, arr)``) recurse without end.
        """
        fields = (f.name for f in dataclasses.fields(self) if not f.name.startswith("_"))
        return (type(self).__name__, *(getattr(self, name) for name in fields))

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
        >>> from diagnosis import derive_arrs
        >>> arr = derive_arrs(rlc_circuit())[1]
        >>> arr.compiled.points, arr.compiled is arr.compiled
        ([i, v_C, d1_v_C], True)
        """
        if self._compiled is None:
            self._compiled = compile_arr(self)
        return self._compiled

    def prepared(self, record, *, extra: tuple = (), **estimator) -> tuple[Record, None]:
        """The record validated for this relation, and no band of its own (the band is Psi_2's range).

        A :class:`~diagnosis.simulation_residuals.SimulationARR` adds its simulated states to the record and
        returns its band; :func:`~diagnosis.detection.evaluate` asks every relation the same way.

        >>> from bondgraph.library import rlc_circuit
        >>> from diagnosis import derive_arrs
        >>> data, band = derive_arrs(rlc_circuit())[1].prepared({"t": [0.0, 0.1, 0.2], "i": [0, 1, 2],
        ...                                                      "v_C": [0, 0, 1]})
        >>> sorted(data.columns), band
        (['i', 'v_C'], None)
        """
        return read_record(self, record, extra=extra), None

    def evaluate(self, record, **options) -> Evaluation:
        """Residual, thresholds and alarms over a record; see :func:`diagnosis.detection.evaluate`."""
        return evaluate(self, record, **options)


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


#: How a relation holding integrals of measured signals is written: "avoid" differentiates it once when
#: that removes every integral, "keep" writes the integrals (the form of Jha et al. (2016), eq. 45).
INTEGRAL_FORMS = ("avoid", "keep")


def check_integral_form(integrals: str) -> None:
    """Raise a ValueError naming the option unless ``integrals`` is one of :data:`INTEGRAL_FORMS`."""
    if integrals not in INTEGRAL_FORMS:
        raise ValueError(f"option integrals: {integrals!r} is not one of {', '.join(INTEGRAL_FORMS)}")


def written_without_integrals(r_n: sp.Expr, r_true: sp.Expr, form: str, *, avoid: bool = True) -> tuple:
    """``(r_n, r_true, form)``: the relation differentiated once when that removes every integral.

    An integral of measured signals from the start of the record is a random walk of their noise
    (and assumes the storage empty at the start); the derivative of a relation that holds integrals
    linearly holds their integrands instead.  ``form`` is the name of the relation as written; it
    becomes ``"differentiated <form>"``, or ``"<form> with integral"`` when an integral is kept (an
    integral inside a non-linear law, or ``avoid=False``).

    >>> import sympy as sp
    >>> t = sp.Symbol("t"); w, u = sp.Function("w"), sp.Function("u")
    >>> written_without_integrals(u(t) - 3*sp.Integral(w(t), (t, 0, t)), u(t), "balance")
    (-3*w(t) + Derivative(u(t), t), Derivative(u(t), t), 'differentiated balance')
    """
    if not r_n.has(sp.Integral):
        return r_n, r_true, form
    if avoid:
        rate = _rate(r_n)
        if not rate.has(sp.Integral):
            return rate, _rate(r_true), f"differentiated {form}"
    return r_n, r_true, f"{form} with integral"


def _rate(expression: sp.Expr) -> sp.Expr:
    """d/dt of a sum, term by term: ``c * Integral(g)`` with ``c`` constant gives ``c g`` without sympy's diff."""
    terms = []
    for term in sp.Add.make_args(expression):
        factor, signal = term.as_independent(T, as_Add=False)
        if isinstance(signal, sp.Integral) and signal.limits == ((T, 0, T),):
            terms.append(factor * signal.function)
        elif isinstance(signal, AppliedUndef) and signal.args == (T,):
            terms.append(factor * sp.Derivative(signal, T))
        elif (isinstance(signal, sp.Derivative) and isinstance(signal.expr, AppliedUndef)
              and set(signal.variables) == {T}):
            terms.append(factor * sp.Derivative(signal.expr, (T, signal.derivative_count + 1)))
        else:
            terms.append(time_derivative(term))
    return sp.Add(*terms)


def measured_signals(structure: Structure) -> tuple:
    """The signals of the model's detectors, in element order: the sensor-fault candidates.

    >>> from bondgraph.library import dc_motor
    >>> measured_signals(dc_motor().structure())
    ('i', 'omega')
    """
    return tuple(dict.fromkeys(e.signal for e in structure.elements.values() if e.kind in el.DETECTORS))


def split_relation(name, junction, detector, r_n, r_true, blocked_by, structure, candidates, parameters,
                   **details) -> ARR:
    """The ARR of a relation: ``r_n`` nominal, ``r_true`` the same with theta (1 + delta_theta) for each parameter.

    Psi_2 is ``r_true - r_n`` split into one term per delta (BG-LFT), plus the products of deltas if
    an addend holds two.  ``parameters``: parameter -> multiplicative interval of the structure;
    ``details``: further fields of the :class:`ARR` (``origin``, ``form``, ``sensors`` when the caller
    has them already).
    """
    deltas = sorted((s for s in r_true.free_symbols if delta_parameter(s) is not None), key=str)
    # an integral is computed once from the record: uncertain parameters and their deltas stand outside it
    uncertain_symbols = [*deltas, *(sp.Symbol(delta_parameter(d)) for d in deltas)]
    r_n = factor_out_of_integrals(r_n, uncertain_symbols)
    r_true = factor_out_of_integrals(r_true, uncertain_symbols)
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
        **{"sensors": measured_signals(structure), **details},
    )


#: The largest uncertain term (sympy operations) put over a common denominator and cancelled.
TIDY_LIMIT = 300


def _tidy(expression: sp.Expr) -> sp.Expr:
    """Cancel a difference of balances over a common denominator.

    Derivatives and integrals are frozen as atoms so they are neither split
    nor merged, and no ``simplify`` rewrites ``sign(x)*sqrt(Abs(x))`` into a
    Piecewise that interval arithmetic could not evaluate.
    """
    if sp.count_ops(expression) > TIDY_LIMIT:
        # nested inverses of non-linear laws: expanding costs minutes; the difference stays exact as it is
        return expression
    frozen = {a: sp.Dummy() for a in expression.atoms(sp.Derivative, sp.Integral)}
    numerator, denominator = expression.xreplace(frozen).as_numer_denom()
    tidy = sp.factor_terms(sp.expand(numerator) / denominator)
    return tidy.xreplace({d: a for a, d in frozen.items()})
