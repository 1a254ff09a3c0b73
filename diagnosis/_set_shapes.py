"""Sets of equations equal up to renaming: one elimination serves every stage of a repeated structure.

A chain of stages, a ladder or a cascade gives the same minimal set at every stage with other names (``m3``
for ``m2``, ``v4`` for ``v3``).  The elimination of a set is a sympy computation that only the form of its
equations decides, so the ARR of one set, renamed, is the ARR of every set of the same shape.

The shape of a set is found by colour refinement (Weisfeiler and Leman (1968)) on the graph of its equations and
the symbols they hold: an equation starts with its role and its law written with every symbol replaced by
its kind (parameter, uncertainty, bond variable, state, signal), a symbol with its kind; each round a node
takes the colours of its neighbours.  When every node ends with a colour of its own, sorting by colour
orders the equations and symbols canonically, and the equations written with the symbols renamed in
that order are the set's shape.  Two sets of equal shape are the same equations up to the renaming
that maps one canonical order onto the other; a set whose colours stay tied (a symmetric set) has no
shape and is eliminated on its own.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph.structure import T

__all__ = ["SetShape", "Shapes", "rewritten"]

#: A symbol's mark in an equation's template.
_MARK = re.compile(r"__(\d+)__")


@dataclass(frozen=True)
class SetShape:
    """The shape of a set: ``key`` (equal for sets equal up to renaming), its equations and symbols in
    canonical order."""

    key: tuple
    rows: tuple
    atoms: tuple


class Shapes:
    """Shapes of sets of one model's equations; colours are shared, so equal shapes get equal keys.

    Parameters
    ----------
    equations : list of sympy.Eq
        The model's equations (with theta (1 + delta_theta): the uncertain form decides the ARR too).
    roles : list of str
        The role of each equation.
    kind : callable
        ``kind(atom) -> str``: ``"parameter"``, ``"delta"``, ``"bond"``, ``"state"`` or ``"signal"``.
    """

    def __init__(self, equations: list, roles: list, kind) -> None:
        self.equations, self.roles, self.kind = equations, roles, kind
        self._colours: dict = {}
        self._atoms: dict = {}
        self._labels: dict = {}
        self._templates: dict = {}

    def shape(self, rows) -> SetShape | None:
        """The shape of ``rows``; None when colour refinement leaves two nodes alike."""
        rows = sorted(rows)
        atoms = {i: self.atoms_of(i) for i in rows}
        colour = {("row", i): self._colour(("label", self.label(i))) for i in rows}
        colour.update({("atom", a): self._colour(("kind", self.kind(a))) for i in rows for a in atoms[i]})
        holders: dict = {}
        for i in rows:
            for a in atoms[i]:
                holders.setdefault(a, []).append(i)
        distinct = len(set(colour.values()))
        while distinct < len(colour):
            refined = {("row", i): self._refined(colour, ("row", i), [("atom", a) for a in atoms[i]]) for i in rows}
            refined.update({("atom", a): self._refined(colour, ("atom", a), [("row", i) for i in held])
                            for a, held in holders.items()})
            colour = refined
            now = len(set(colour.values()))
            if now == distinct:
                return None
            distinct = now
        ordered_rows = tuple(sorted(rows, key=lambda i: colour[("row", i)]))
        ordered_atoms = tuple(sorted(holders, key=lambda a: colour[("atom", a)]))
        index = {a: k for k, a in enumerate(ordered_atoms)}
        key = tuple(self._written(i, index) for i in ordered_rows)
        return SetShape(key, ordered_rows, ordered_atoms)

    def _written(self, row: int, index: dict) -> str:
        """The equation with its symbols named by their canonical ``index`` (its exact sympy form)."""
        template, atoms = self._template(row)
        return _MARK.sub(lambda m: f"x{index[atoms[int(m.group(1))]]}", template)

    def _template(self, row: int) -> tuple[str, list]:
        """The equation's exact form (``srepr``) with its k-th symbol written ``__k__``, made once per equation."""
        if row not in self._templates:
            atoms = sorted(self.atoms_of(row), key=sp.srepr)
            marked = {a: _placeholder(f"__{k}__", a) for k, a in enumerate(atoms)}
            self._templates[row] = (f"{self.roles[row]}: {sp.srepr(rewritten(self.equations[row], marked))}", atoms)
        return self._templates[row]

    def atoms_of(self, row: int) -> frozenset:
        """The symbols of an equation: parameters, deltas, bond variables, and states and signals (as ``x(t)``)."""
        if row not in self._atoms:
            equation = self.equations[row]
            self._atoms[row] = frozenset((equation.free_symbols - {T}) | equation.atoms(AppliedUndef))
        return self._atoms[row]

    def label(self, row: int) -> str:
        """An equation's role and law with every symbol replaced by its kind."""
        if row not in self._labels:
            kinds = {a: _placeholder(self.kind(a), a) for a in self.atoms_of(row)}
            self._labels[row] = f"{self.roles[row]}: {sp.srepr(rewritten(self.equations[row], kinds))}"
        return self._labels[row]

    def _refined(self, colour: dict, node: tuple, neighbours: list) -> int:
        """A node's next colour: its colour and the multiset of its neighbours' colours."""
        return self._colour((colour[node], tuple(sorted(colour[n] for n in neighbours))))

    def _colour(self, signature: tuple) -> int:
        return self._colours.setdefault(signature, len(self._colours))


def _placeholder(name: str, atom) -> sp.Basic:
    """A symbol or a function of ``t`` named ``name``, as ``atom`` is one or the other."""
    return sp.Function(name)(T) if isinstance(atom, AppliedUndef) else sp.Symbol(name)


def rewritten(equation: sp.Eq, mapping: dict) -> sp.Eq:
    """``equation`` with ``mapping`` applied to each side, left unevaluated.

    ``Eq.xreplace`` evaluates the new equality, and a law sympy can decide (``e/0 - f``, a ``zoo`` times a
    variable) becomes ``False``, which is no equation to solve.
    """
    return sp.Eq(equation.lhs.xreplace(mapping), equation.rhs.xreplace(mapping), evaluate=False)
