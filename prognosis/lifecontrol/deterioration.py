"""Energy-driven deterioration appended to a model's state equations (Rodriguez Obando et al. (2021), section 2.2).

The deterioration ``D`` of a dissipative element is the energy it has
dissipated, ``D(t) = int_0^t P(tau) dtau`` (eq. 8), where ``P`` is the power the
element absorbs, taken from the bond graph's own effort and flow variables
(``StateEquations.power``).  The element's coefficient ``alpha`` decays with
``D`` (eq. 10, ``alpha = alpha(0) - m D``), and the rate ``m`` is an unknown
parameter modelled as constant up to process noise (eq. 11).  Differentiating
(eqs. 9, 12, 14)::

    d alpha / dt = -m P(x, u, alpha),    dm/dt = 0,    dD/dt = P(x, u, alpha),

which, appended to the model's own state equations (eq. 13), is the augmented
system of eqs. (16)-(19) on ``[x, alpha, m, D]``.  For the friction drive
``P = alpha (r1 omega1 - r2 omega2)^2 = alpha p(omega)`` (eqs. 6-7).

The result has the fields of :class:`bondgraph.equations.StateEquations` that
:func:`prognosis.statespace.discretize` reads (``states``, ``rhs``, ``inputs``,
``outputs``, ``parameters``), so an EKF on the augmented state is one call away.

Example
-------
>>> from bondgraph.library import friction_drive
>>> eqs = friction_drive().state_equations().coenergy_states({"J1": "omega1", "J2": "omega2"})
>>> model = energy_deterioration(eqs, "alpha", rate_value=1e-6)
>>> model.states
[omega1, omega2, alpha, m, D]
>>> model.rhs[4]
alpha*(omega1*r1 - omega2*r2)**2
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass, field

import sympy as sp

from ..errors import PrognosisError

__all__ = ["DeteriorationEquations", "energy_deterioration"]


@dataclass(frozen=True)
class DeteriorationEquations:
    """State equations augmented with an energy-driven deterioration.

    Attributes
    ----------
    states : list of sympy.Symbol
        The model's states, then ``coefficient``, ``rate``, ``energy``.
    rhs : list of sympy.Expr
    inputs : list of str
    outputs : dict
    parameters : dict
        Constant parameters (the coefficient is a state now).
    element : hashable
        The dissipative element.
    power : sympy.Expr
        Power absorbed by ``element``, ``P(x, u, alpha)``.
    coefficient, rate, energy : str
        Names of the decaying coefficient, its rate ``m`` and the dissipated energy ``D``.
    nominal : dict
        Nominal values of ``coefficient`` and ``rate`` (initial estimates).

    Examples
    --------
    Returned by :func:`energy_deterioration`; a resistor whose resistance
    decays with the energy it dissipates:

    >>> from bondgraph.library import rlc_circuit
    >>> model = energy_deterioration(rlc_circuit().state_equations(), "R", rate_value=0.01)
    >>> print(model)
    dp_L/dt = V(t) - R*p_L/L - q_C/C
    dq_C/dt = p_L/L
    dR/dt = -R*m*p_L**2/L**2
    dm/dt = 0
    dD/dt = R*p_L**2/L**2
    i = p_L/L
    v_C = q_C/C
    >>> model.element, model.power, (model.coefficient, model.rate, model.energy)
    ('R', R*p_L**2/L**2, ('R', 'm', 'D'))
    >>> model.nominal, model.parameters, model.inputs
    ({'R': 10.0, 'm': 0.01}, {'L': 0.1, 'C': 0.001}, ['V'])
    """

    states: list
    rhs: list
    inputs: list
    outputs: dict
    parameters: dict
    element: Hashable
    power: sp.Expr
    coefficient: str
    rate: str
    energy: str
    nominal: dict = field(default_factory=dict)

    def __str__(self) -> str:
        lines = [f"d{x}/dt = {r}" for x, r in zip(self.states, self.rhs)]
        return "\n".join(lines + [f"{name} = {expr}" for name, expr in self.outputs.items()])


def energy_deterioration(equations, element: Hashable, *, coefficient: str | None = None, rate: str = "m",
                         energy: str = "D", rate_value: float = 0.0) -> DeteriorationEquations:
    """Append ``alpha`` (the element's parameter), ``m`` and ``D`` to ``equations`` as states.

    Parameters
    ----------
    equations : bondgraph.equations.StateEquations
        The model's state equations (any storage variables, e.g. after ``coenergy_states``).
    element : hashable
        The dissipative one-port whose absorbed power drives the deterioration.
    coefficient : str, optional
        The parameter that decays, ``alpha = alpha(0) - m D`` (default: the one
        the element's power depends on, when that is a single parameter).
    rate, energy : str
        Names of the new states ``m`` and ``D``.
    rate_value : float
        Nominal ``m``, recorded in ``nominal``.

    Returns
    -------
    DeteriorationEquations
        ``d alpha/dt = -m P``, ``dm/dt = 0``, ``dD/dt = P`` appended (Rodriguez Obando et al. (2021), eqs. 17-19).

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> model = energy_deterioration(rlc_circuit().state_equations(), "R", rate="k", energy="E")
    >>> model.states, model.rhs[2:]
    ([p_L, q_C, R, k, E], [-R*k*p_L**2/L**2, 0, R*p_L**2/L**2])
    >>> model.nominal   # rate_value defaults to 0
    {'R': 10.0, 'k': 0.0}

    The coefficient and the rate are states now, so a discrete model for an
    estimator needs no augmentation:

    >>> from prognosis.statespace import discretize
    >>> discretize(model, dt=1e-3).states
    ('p_L', 'q_C', 'R', 'k', 'E')
    """
    power = equations.power(element)
    parameters = {str(k): v for k, v in equations.parameters.items()}
    if coefficient is None:
        candidates = sorted(str(s) for s in power.free_symbols if str(s) in parameters)
        own = [c for c in candidates if c == str(element)]
        if not own and len(candidates) != 1:
            raise PrognosisError(f"element {element!r}: its power depends on parameters {candidates}; "
                                 "say which one decays with coefficient=")
        coefficient = own[0] if own else candidates[0]
    if coefficient not in parameters:
        raise PrognosisError(f"coefficient {coefficient!r} is not a parameter of the model; "
                             f"it has {sorted(parameters)}")
    taken = {str(s) for s in equations.states} | set(parameters) - {coefficient}
    for name in (rate, energy):
        if name in taken or name == coefficient:
            raise PrognosisError(f"state name {name!r} is already used by the model")
    if rate == energy:
        raise PrognosisError(f"rate and energy need different names, both are {rate!r}")
    if not power.has(sp.Symbol(coefficient)):
        raise PrognosisError(f"the power of {element!r} ({power}) does not depend on {coefficient!r}")
    alpha, m, d = sp.Symbol(coefficient), sp.Symbol(rate), sp.Symbol(energy)
    return DeteriorationEquations(
        states=[*equations.states, alpha, m, d],
        rhs=[*equations.rhs, -m * power, sp.S.Zero, power],
        inputs=list(equations.inputs),
        outputs=dict(equations.outputs),
        parameters={k: v for k, v in parameters.items() if k != coefficient},
        element=element,
        power=power,
        coefficient=coefficient,
        rate=rate,
        energy=energy,
        nominal={coefficient: parameters[coefficient], rate: float(rate_value)},
    )
