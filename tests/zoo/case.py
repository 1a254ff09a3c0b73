"""The contract of a zoo model: a bond graph a user might write, and its physics written independently.

A :class:`ZooCase` holds a model built with the public DSL (``build``) and, beside it, the same
system's state equations written by hand from the physics (``states``, ``rhs``, ``outputs``), never
from the library's equations.  :mod:`tests.zoo.reference` integrates those equations with scipy and
differentiates the outputs exactly along the trajectory, so that every ARR the library derives is
checked against something the library did not produce.

Names: every input symbol in ``rhs``/``outputs`` is named after the model's source signal, every
parameter symbol after the model's parameter (a C element's ``value`` is its compliance unless a
``law`` says otherwise), every key of ``outputs`` after a sensor's signal.

Units: every element of ``build()`` but the junctions declares its coherent SI unit (``unit``, and
``units`` for law constants and a modulating signal, docs/model.md "Units"), so that the model passes the
dimensional check and every parameter, signal and bond has a unit (``tests/zoo/test_units.py``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import sympy as sp

t = sp.Symbol("t")

DOMAINS = ("electrical", "translational", "rotational", "hydraulic", "pneumatic", "thermal", "mixed")


@dataclass(frozen=True)
class ZooCase:
    """One zoo system.

    Attributes
    ----------
    name : str
        Identifier (``[a-z0-9_]+``), used in test ids and docs/zoo.md.
    domain : str
        One of :data:`DOMAINS`.
    source : str
        Where the physics comes from (textbook section or datasheet), one line.
    build : callable
        ``build() -> BondGraph``: nominal values and uncertainty boxes on the uncertain parameters.
    states : tuple of sympy.Symbol
        The physical state (charges, momenta, displacements, volumes, heats...).
    rhs : tuple of sympy.Expr
        ``d states / dt`` in the states, input symbols, parameter symbols and ``t``.
    outputs : dict
        Sensor signal -> its value in the states, inputs and parameters.
    smooth_inputs : dict
        Input signal -> a smooth expression in ``t`` (the identity check needs exact derivatives).
    step_inputs : dict
        Input signal -> ``((t_0, level_0), (t_1, level_1), ...)``, a piecewise-constant profile
        (``t_0 = 0``) with at least one step inside the record: the detection records.
        A closed loop: an input of either kind may be an expression in sensor signals (a controller
        law, e.g. ``k_p*(0.5 - h2)``, a level a set-point); the reference reads them from the states
        and a simulation passes it as ``u(t, y)``.
    t_end, dt : float
        Record horizon and sampling step in seconds; ``t_end / dt`` about 1000-5000 samples.
    noise : dict
        Sensor signal -> realistic noise standard deviation (about 0.1-1 % of its range).
    x0 : dict
        State -> initial value (default 0: integral-form ARRs take stored energy as zero at the start).
    faults : tuple of str
        Parameters whose 30 % change the physics makes visible on the step record (the detection test
        uses them; default: every uncertain parameter).
    """

    name: str
    domain: str
    source: str
    build: Callable
    states: tuple
    rhs: tuple
    outputs: Mapping
    smooth_inputs: Mapping
    step_inputs: Mapping
    t_end: float
    dt: float
    noise: Mapping
    x0: Mapping = field(default_factory=dict)
    faults: tuple = ()

    def __post_init__(self):
        if self.domain not in DOMAINS:
            raise ValueError(f"{self.name}: domain {self.domain!r} not in {DOMAINS}")
        if len(self.states) != len(self.rhs):
            raise ValueError(f"{self.name}: {len(self.states)} states but {len(self.rhs)} right-hand sides")

    def __str__(self) -> str:
        return self.name
