"""A zoo system's hand-written physics with wearing parameters, integrated by scipy (not the library's simulate).

A :class:`~tests.zoo.case.ZooCase` carries its state equations written from the physics (``states``,
``rhs``, ``outputs``); :mod:`tests.zoo.reference` integrates them for constant (or symbolic) parameters
and differentiates the outputs exactly, which a wear record does not need.  Here the same equations are
integrated with each parameter a number or a function ``theta(t)`` of time (a wear law of
:mod:`tests.wear.laws`), evaluated at every call of the right-hand side, so that the record holds the
law exactly; the inputs are expressions in ``t`` (and, for a closed loop, in sensor signals).

>>> from tests.zoo.check import load_case
>>> import sympy as sp
>>> case = load_case("heat_exchanger")
>>> run = simulate(case, {}, inputs={"T_hi": sp.Integer(40), "T_ci": sp.Integer(0)}, t_end=1.0, dt=0.5,
...                noise={}, seed=0)
>>> sorted(run), run["t"].tolist()
(['T_c', 'T_ci', 'T_h', 'T_hi', 'q_c', 'q_w', 't'], [0.0, 0.5, 1.0])
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from tests.zoo.case import ZooCase, t

RTOL, ATOL = 1e-9, 1e-13   # model error about 1e-8 of the signals, far below any sensor noise


def nominal(case: ZooCase) -> dict:
    """Parameter -> nominal value, from the case's model."""
    return dict(case.build().parameters)


def simulate(case: ZooCase, parameters: Mapping[str, float | Callable], *, inputs: Mapping[str, sp.Expr],
             t_end: float, dt: float, noise: Mapping[str, float], seed: int, breaks: tuple = ()) -> dict:
    """Columns ``t``, every input and every sensor signal; ``parameters``: name -> value or ``theta(t)``.

    Parameters
    ----------
    case : ZooCase
        The system: its states, right-hand sides and outputs in sympy.
    parameters : mapping
        Parameter -> a number or a function of time; the others keep their nominal values.
    inputs : mapping
        Input signal -> sympy expression in ``t`` and, for a closed loop, in sensor signals.
    t_end, dt : float
        The record's horizon and sample time (s).
    noise : mapping
        Sensor or input signal -> standard deviation of the Gaussian noise added to its column.
    seed : int
        The noise's seed.
    breaks : tuple of float
        Times where a law may jump or bend (its onset, say): the integration restarts there, so that the
        solver never steps across a discontinuity of the right-hand side.

    Returns
    -------
    dict
        Column name -> samples on the grid ``0, dt, ..., t_end``.
    """
    values = nominal(case)
    unknown = set(parameters) - set(values)
    if unknown:
        raise ValueError(f"{case.name}: unknown parameter(s) {sorted(unknown)}")
    values.update(parameters)
    names = sorted(values)
    symbols = [sp.Symbol(n) for n in names]
    states = list(case.states)
    # a closed loop: the inputs read the sensors, which are functions of the states
    sensors = {sp.Symbol(k): sp.sympify(v) for k, v in case.outputs.items()}
    u = {sp.Symbol(k): sp.sympify(v).xreplace(sensors) for k, v in inputs.items()}
    rhs = sp.lambdify([t, states, symbols], [sp.sympify(e).xreplace(u) for e in case.rhs], modules="numpy")
    signals = {**{k: sp.sympify(v).xreplace(u) for k, v in case.outputs.items()}, **{str(k): v for k, v in u.items()}}
    read = sp.lambdify([t, states, symbols], list(signals.values()), modules="numpy")

    def at(time):
        return [float(v(time)) if callable(v) else float(v) for v in (values[n] for n in names)]

    grid = np.round(np.arange(0.0, t_end + dt / 2, dt) / dt) * dt
    x = np.array([float(case.x0.get(s, 0.0)) for s in states])
    trajectory = np.empty((len(states), grid.size))
    cuts = sorted({0.0, float(grid[-1]), *(b for b in breaks if 0.0 < b < grid[-1])})
    for start, end in zip(cuts[:-1], cuts[1:]):
        # explicit and of high order: the systems chosen are not stiff (their fastest time constant spans
        # several samples), so long steps keep the law's evaluations, the cost here, few
        mask = (grid >= start) & ((grid <= end) if end == cuts[-1] else (grid < end))
        solution = solve_ivp(lambda s, y: np.asarray(rhs(s, y, at(s)), float).ravel(), (start, end), x,
                             method="DOP853", t_eval=grid[mask], rtol=RTOL, atol=ATOL, dense_output=True)
        if not solution.success:
            raise RuntimeError(f"{case.name}: solver failed: {solution.message}")
        trajectory[:, mask] = solution.y
        x = solution.sol(end)
    columns = {"t": grid}
    # the laws take arrays: every sample's parameters at once
    every = [np.broadcast_to(np.asarray(v(grid) if callable(v) else v, float), grid.shape)
             for v in (values[n] for n in names)]
    for name, value in zip(signals, read(grid, trajectory, every)):
        columns[name] = np.broadcast_to(np.asarray(value, float), grid.shape).copy()
    rng = np.random.default_rng(seed)
    for name, std in noise.items():
        columns[name] = columns[name] + rng.normal(0.0, std, grid.size)
    return columns
