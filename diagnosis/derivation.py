"""Interval-valued analytical redundancy relations (I-ARRs) of a bond graph: every one its structure allows.

Two routes write relations, and :func:`derive_arrs` combines them:

1. causal paths (:mod:`diagnosis.junctions`, Jha et al. (2016), section 2.1): one ARR per junction
   carrying a sensor, its power balance with the unknowns eliminated back to known signals;
2. minimal overdetermined sets of the model's equations (:mod:`diagnosis.structural`,
   :mod:`diagnosis.elimination`): the ARRs the first route misses, added until the set detects every
   fault the structure lets detect and tells apart every pair it lets tell apart, within a derivative
   order.

Each ARR keeps the BG-LFT split ``r_n + Psi_2 = 0`` (:mod:`diagnosis.arr`), names the equations it
comes from (``origin``) and how it is written (``form``), and says which derivatives and integrals
it needs.  Faults are the element parameters and, by default, one per sensor (a bias or drift on its
read-out).

Example
-------
>>> from bondgraph.library import rlc_circuit
>>> arrs = derive_arrs(rlc_circuit())
>>> [(arr.junction, str(arr.nominal)) for arr in arrs]
[('J1', '-L*Derivative(i(t), t) - R*i(t) + V(t) - v_C(t)'), ('J0', '-C*Derivative(v_C(t), t) + i(t)')]
"""

from __future__ import annotations

import copy
import warnings

from bondgraph import BondGraph
from bondgraph.memo import ContentCache, content_key
from bondgraph.structure import require_model

from . import arr as arr_module, elimination, structural
from .elimination import MAX_ORDER, structural_arrs
from .junctions import junction_arrs
from .arr import ARR, ARRWarning
from .residuals import ARRError

__all__ = ["ARR", "ARRError", "ARRWarning", "derive_arrs", "evaluable"]


def derive_arrs(bg: BondGraph, *, complete: bool = True, sensor_faults: bool = True,
                max_order: int | str | None = MAX_ORDER, integrals: str = "avoid",
                isolation: bool = True, simulated: bool = False) -> list[ARR]:
    """Derive the I-ARRs of a bond graph with detectors.

    Parameters
    ----------
    bg : BondGraph
        A model following the model contract of docs/design.md, with De/Df detectors.
    complete : bool
        Add the ARRs of minimal overdetermined sets that the junction ARRs miss (default); False keeps
        the junction ARRs only.
    sensor_faults : bool
        Count a fault per sensor when completing the set (default); False assumes healthy sensors.
    max_order : int, "auto" or None
        The highest derivative of a measured signal an added ARR may need (None: no bound).  ``"auto"``
        (default): any order to detect a fault nothing else detects, and for isolation no higher than
        the ARRs the model needs anyway.
    integrals : {"avoid", "keep"}
        ``"avoid"`` writes a relation that would integrate measured signals in its differentiated form
        when that removes the integrals; ``"keep"`` keeps the integrals (the form of Jha et al.
        (2016), eq. 45).
    isolation : bool
        Complete isolation as well as detection (default), within the work budgets of
        :mod:`diagnosis.elimination` (which grow with the model's fault candidates); False: detection only.
    simulated : bool
        Fill the gaps no closed form fills with simulation residuals (:mod:`diagnosis.simulation_residuals`):
        the set's states integrated from the record, the band enclosing them over the parameters' box.  Off
        by default (they need an initial state; streaming, code generation and prognosis refuse them).

    Returns
    -------
    list of ARR
        The junction ARRs (:func:`~diagnosis.junctions.junction_arrs`), then the added ones
        (:func:`~diagnosis.elimination.structural_arrs`).  Candidates that cannot be expressed in known
        variables, and gaps left, are named in an :class:`ARRWarning`.

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

    Telling k_m from a fault of either sensor takes ARRs of second order, beyond the first-order
    junction ARRs, so only an explicit ``max_order`` adds them:

    >>> extra = derive_arrs(dc_motor(), max_order=2)[2:]
    >>> [(arr.name, arr.form, arr.derivatives) for arr in extra]
    [('ARR_MSO_1', 'elimination', {'U': 0, 'omega': 2}), ('ARR_MSO_2', 'elimination', {'U': 1, 'i': 2})]

    The derivation is symbolic and can take seconds; the ARRs of the last :data:`REMEMBERED` models
    (by content: elements, laws, values, bonds, name, and the options) are remembered.  Asking again
    returns fresh copies that share the compiled numerics, and repeats the warnings; a model edited
    since is a different model:

    >>> again = derive_arrs(dc_motor())
    >>> again == arrs, again[0] is arrs[0], again[0].compiled is arrs[0].compiled
    (True, False, True)
    """
    require_model(bg, "derive_arrs")
    key = _key(bg, complete, sensor_faults, max_order, integrals, isolation, simulated)
    arrs = _REMEMBERED.get(key, lambda: _derive(bg, complete, sensor_faults, max_order, integrals, isolation,
                                                simulated))
    return [_copy(arr) for arr in arrs]


#: How many models' ARRs :func:`derive_arrs` remembers (the least recently asked for is forgotten first).
REMEMBERED = 64
_REMEMBERED = ContentCache(REMEMBERED)


def _derive(bg, complete: bool, sensor_faults: bool, max_order, integrals: str, isolation,
            simulated: bool = False) -> list[ARR]:
    if not complete:
        return evaluable(junction_arrs(bg, integrals=integrals))
    with warnings.catch_warnings():
        # a junction whose balance needs an unmeasured variable is what the completion makes up for;
        # what it cannot make up for is named in its own warning
        warnings.simplefilter("ignore", ARRWarning)
        arrs = evaluable(junction_arrs(bg, integrals=integrals), warn=False)
    return arrs + evaluable(structural_arrs(bg, existing=arrs, sensor_faults=sensor_faults, max_order=max_order,
                                            integrals=integrals, isolation=isolation, simulated=simulated))


def _key(bg, *options):
    """The model's content, the options and the search budgets: everything the derivation depends on."""
    budgets = (elimination.MAX_ELIMINATIONS, elimination.MAX_SEARCHES, elimination.MAX_SEARCH_EQUATIONS,
               elimination.MAX_OPERATIONS, elimination.BUDGET_FAULTS, elimination.REACHES,
               structural.MSO_SEARCH_LIMIT, arr_module.TIDY_LIMIT)
    return content_key(("derive_arrs", type(bg).__name__, getattr(bg, "name", None), bg.structure(), options,
                        budgets))


def _copy(arr: ARR) -> ARR:
    """A copy the caller may change without changing what is remembered; the compiled numerics are shared."""
    twin = copy.copy(arr)
    twin.terms, twin.values, twin.uncertainties = dict(arr.terms), dict(arr.values), dict(arr.uncertainties)
    return twin


def evaluable(arrs: list[ARR], *, warn: bool = True) -> list[ARR]:
    """The ARRs a record can evaluate; each one left out is named, with the reason, in an :class:`ARRWarning`.

    An ARR is offered only if it compiles to numerics (:func:`~diagnosis.residuals.compile_arr`): a
    relation that holds, say, an uncertainty inside an integral or a function numpy cannot compute would
    fail on the user's first record, so it is not offered, and the warning (a note of the ARR report)
    says why.

    >>> from bondgraph.library import rlc_circuit
    >>> [arr.name for arr in evaluable(derive_arrs(rlc_circuit()))]
    ['ARR_J1', 'ARR_J0']
    """
    kept = []
    for arr in arrs:
        try:
            arr.compiled
        except ARRError as exc:
            if warn:
                warnings.warn(f"{arr.name} is not offered: {str(exc).removeprefix(arr.name + ': ')}", ARRWarning,
                              stacklevel=3)
            continue
        kept.append(arr)
    return kept
