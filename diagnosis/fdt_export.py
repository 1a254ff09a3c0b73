"""A bond graph's equations as a Fault Diagnosis Toolbox model, for FDT's analyses on our models.

The Fault Diagnosis Toolbox (Frisk et al. (2017), ``pip install faultdiagnosistoolbox``, the optional extra
``fdt``) analyses sympy models: unknowns ``x``, faults ``f``, known signals ``z``, relations equal to zero,
and a differential constraint ``DiffConstraint(dx, x)`` per state.  :func:`to_fdt` writes the equations of
:func:`diagnosis.structural_model` that way:

* the bond variables and each state ``q_C`` are unknowns, the state's rate a further unknown ``dq_C``
  tied to it by a differential constraint (where :mod:`diagnosis.structural` counts a state and its rate as
  one unknown, FDT counts two and the constraint, which gives the same minimal sets);
* the model's inputs and measured signals are the known signals;
* each fault candidate (a parameter, and a sensor unless ``sensor_faults=False``) is an additive fault
  ``f_<name>`` on every equation it acts on: FDT's analyses read only where each fault appears.

Its minimal overdetermined sets, less the differential constraints, are ours (checked on the zoo in the
tests); its isolability, sensor placement, test selection and residual generators then run on our models.

Examples
--------
The definition needs no toolbox; :func:`to_fdt` hands it to FDT (``tests/interop/test_fdt.py`` compares the
minimal sets on the zoo):

>>> from bondgraph.library import dc_motor
>>> definition = fdt_definition(dc_motor())
>>> definition["z"], definition["f"][:3], definition["rates"]
(['U', 'i', 'omega'], ['f_R_a', 'f_L_a', 'f_k_m'], {'p_L_a': 'dp_L_a', 'p_J': 'dp_J'})
"""

from __future__ import annotations

import re

import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph.optional import import_optional
from bondgraph.structure import require_model

from .structural import structural_model

__all__ = ["fdt_definition", "to_fdt"]


def to_fdt(bg, *, sensor_faults: bool = True):
    """The FDT ``DiagnosisModel`` of a bond graph with detectors (see the module).

    Parameters
    ----------
    bg : BondGraph
    sensor_faults : bool
        A fault per sensor too (default), as :func:`diagnosis.structural_model` has.

    Returns
    -------
    faultdiagnosistoolbox.DiagnosisModel
        Named after the model.

    Raises
    ------
    ImportError
        Without the toolbox: one line naming the extra to install.
    """
    fdt = import_optional("faultdiagnosistoolbox", "to_fdt needs the Fault Diagnosis Toolbox: "
                                                   "pip install 'bondgraph-phm[fdt]'")
    definition = fdt_definition(bg, sensor_faults=sensor_faults)
    rates = definition.pop("rates")
    definition["rels"] += [fdt.DiffConstraint(rate, state) for state, rate in rates.items()]
    return fdt.DiagnosisModel(definition, name=bg.name or "")


def fdt_definition(bg, *, sensor_faults: bool = True) -> dict:
    """The model definition :func:`to_fdt` hands to FDT, without needing FDT: ``type``, ``x``, ``f``, ``z``,
    ``parameters``, ``rels`` (one per equation of :func:`diagnosis.structural_model`, in its order) and
    ``rates`` (state -> the name of its rate; the differential constraints FDT appends).

    >>> from bondgraph.library import rlc_circuit
    >>> definition = fdt_definition(rlc_circuit())
    >>> definition["z"], sorted(definition["rates"].items()), definition["f"][:3]
    (['V', 'i', 'v_C'], [('p_L', 'dp_L'), ('q_C', 'dq_C')], ['f_R', 'f_L', 'f_C'])
    >>> len(definition["rels"]) == len(structural_model(rlc_circuit()).equations)
    True
    """
    require_model(bg, "to_fdt")
    structure = bg.structure()
    model = structural_model(bg, sensor_faults=sensor_faults)
    signals = list(dict.fromkeys([*structure.inputs, *structure.outputs]))
    parameters = set(structure.parameters)
    faults = {name: sp.Symbol(_identifier(f"f_{name}")) for name in model.faults}
    states: dict = {}      # state function name -> its symbol
    rates: dict = {}       # state function name -> the symbol of its rate
    bonds: dict = {}
    rels = []
    for i, equation in enumerate(model.equations):
        expression = equation.equation.lhs - equation.equation.rhs
        swap = {}
        for d in sorted(expression.atoms(sp.Derivative), key=str):
            name = d.expr.func.__name__
            states.setdefault(name, sp.Symbol(name))
            swap[d] = rates.setdefault(name, sp.Symbol(f"d{name}"))
        expression = expression.xreplace(swap)
        for f in sorted(expression.atoms(AppliedUndef), key=str):
            name = f.func.__name__
            swap[f] = sp.Symbol(name) if name in signals else states.setdefault(name, sp.Symbol(name))
        expression = expression.xreplace(swap)
        for s in sorted(expression.free_symbols, key=str):
            if s.name not in parameters and s.name not in signals and s not in states.values() \
                    and s not in rates.values():
                bonds.setdefault(s.name, s)
        acting = [faults[name] for name, rows in model.faults.items() if i in rows]
        rels.append(expression + sp.Add(*acting))
    names = [*bonds, *states, *(r.name for r in rates.values())]
    clash = sorted(set(names) & (set(signals) | parameters | {f.name for f in faults.values()}))
    if clash:
        raise ValueError(f"to_fdt: the name {clash[0]!r} is both an unknown and a signal, parameter or fault")
    return {"type": "Symbolic", "x": names, "f": [f.name for f in faults.values()],
            "z": [s for s in signals if any(r.has(sp.Symbol(s)) for r in rels)],
            "parameters": sorted(p for p in parameters if any(r.has(sp.Symbol(p)) for r in rels)),
            "rels": rels, "rates": {name: rates[name].name for name in rates}}


def _identifier(text: str) -> str:
    """``text`` with every character that cannot be in a Python identifier replaced by ``_``."""
    return re.sub(r"\W", "_", text)
