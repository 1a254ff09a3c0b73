"""Reference runs of zoo models, from their hand-written physics (scipy), with exact output derivatives.

The state equations ``dx/dt = f(x, u, p, t)`` of a :class:`~tests.zoo.case.ZooCase` are integrated by
:func:`scipy.integrate.solve_ivp` (Radau, tight tolerances) in each stretch where the inputs are smooth;
the ``n``-th time derivative of an output ``y = h(x, u, p, t)`` is the ``n``-th Lie derivative
``L^n h`` along ``f`` (``L g = dg/dx f + dg/dt``, with the inputs and parameters written as functions of
``t``), evaluated on the trajectory: exact up to the solver's tolerance, with no finite differences.
Between the steps of a piecewise-constant input its derivatives are exactly zero.

Nothing here uses the library's equations or its simulator.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from .case import ZooCase, t

ORDER = 3  # highest exact derivative provided (ARRs of the zoo need at most this)


@dataclass
class ReferenceRun:
    """Samples of a reference run.

    ``columns``: ``t`` and every input and sensor signal; ``derivatives``: signal -> ``[d1, d2, ...]``
    exact time derivatives (``d1`` first) at the same samples; ``parameters``: the values used.
    """

    columns: dict
    derivatives: dict
    parameters: dict

    def exact(self) -> dict:
        """The derivatives in the form ``evaluate(exact_derivatives=...)`` takes: ``"x"``, ``"x:2"``, ..."""
        out = {}
        for name, ds in self.derivatives.items():
            for order, values in enumerate(ds, start=1):
                out[name if order == 1 else f"{name}:{order}"] = values
        return out


def nominal_parameters(case: ZooCase) -> dict:
    return dict(case.build().parameters)


def _segments(case: ZooCase, inputs: str, t_end: float, cuts: tuple = ()) -> list[tuple[float, float, dict]]:
    """``[(start, end, {input symbol: expression in t}), ...]`` stretches with smooth inputs (and cut at ``cuts``)."""
    inner = tuple(c for c in cuts if 0.0 < c < t_end)
    if inputs == "smooth":
        times = sorted({0.0, t_end, *inner})
        smooth = {sp.Symbol(k): sp.sympify(v) for k, v in case.smooth_inputs.items()}
        return [(a, b, smooth) for a, b in zip(times[:-1], times[1:])]
    if inputs != "step":
        raise ValueError(f"inputs must be 'smooth' or 'step', not {inputs!r}")
    times = sorted({0.0, t_end, *inner, *(float(s) for profile in case.step_inputs.values() for s, _ in profile
                                          if 0.0 < s < t_end)})
    segments = []
    for start, end in zip(times[:-1], times[1:]):
        levels = {}
        for name, profile in case.step_inputs.items():
            level = [v for s, v in profile if s <= start][-1]
            levels[sp.Symbol(name)] = sp.sympify(level)
        segments.append((start, end, levels))
    return segments


def simulate_reference(case: ZooCase, *, parameters: Mapping | None = None, inputs: str = "smooth",
                       t_end: float | None = None, dt: float | None = None, order: int = ORDER,
                       fault_at: float | None = None, ramp: float = 0.0) -> ReferenceRun:
    """Integrate the case's physics and sample its inputs, outputs and their exact derivatives.

    ``parameters``: parameter -> a number or a sympy expression in ``t`` (a drifting parameter);
    the others keep their nominal values; with ``fault_at``, they take these values from that time on
    (an abrupt fault), nominal before, or move to them linearly over ``ramp`` seconds from that time
    (a fast wear: no discontinuity of the state's derivatives).  ``inputs``: ``"smooth"`` or ``"step"``.
    """
    t_end = case.t_end if t_end is None else t_end
    dt = case.dt if dt is None else dt
    grid = np.round(np.arange(0.0, t_end + dt / 2, dt) / dt) * dt
    values = nominal_parameters(case)
    unknown = set(parameters or {}) - set(values)
    if unknown:
        raise ValueError(f"{case.name}: unknown parameter(s) {sorted(unknown)}")
    healthy = {sp.Symbol(k): sp.sympify(v) for k, v in values.items()}
    values.update(parameters or {})
    psubs = {sp.Symbol(k): sp.sympify(v) for k, v in values.items()}
    states = list(case.states)
    x = np.array([float(case.x0.get(s, 0.0)) for s in states])
    columns = {"t": grid}
    names = list(case.outputs) + [k for k in (case.smooth_inputs if inputs == "smooth" else case.step_inputs)]
    samples = {n: np.full(grid.size, np.nan) for n in names}
    derivs = {n: [np.full(grid.size, np.nan) for _ in range(order)] for n in names}
    # a closed loop: an input written in sensor signals (a controller) reads them from the states
    cuts = () if fault_at is None else (fault_at, fault_at + ramp) if ramp > 0 else (fault_at,)
    for start, end, u in _segments(case, inputs, t_end, cuts):
        params = healthy if fault_at is not None and start < fault_at else psubs
        if fault_at is not None and ramp > 0 and fault_at <= start < fault_at + ramp:
            share = (t - fault_at) / ramp  # healthy at fault_at, faulty at fault_at + ramp
            params = {k: healthy[k] + share * (psubs[k] - healthy[k]) for k in psubs}
        sensors = {sp.Symbol(k): sp.sympify(v).xreplace(params) for k, v in case.outputs.items()}
        u = {k: v.xreplace(sensors) for k, v in u.items()}
        subs = {**params, **u}
        f = [sp.sympify(e).xreplace(subs) for e in case.rhs]
        rhs = sp.lambdify([t, states], f, modules="numpy")
        jac = sp.lambdify([t, states], sp.Matrix(f).jacobian(states), modules="numpy")
        solution = solve_ivp(lambda s, y: np.asarray(rhs(s, y), float).ravel(), (start, end), x, method="Radau",
                             jac=lambda s, y: np.asarray(jac(s, y), float), rtol=1e-11, atol=1e-13,
                             dense_output=True)
        if not solution.success:
            raise RuntimeError(f"{case.name}: reference solver failed: {solution.message}")
        last = end == t_end
        mask = (grid >= start) & ((grid <= end) if last else (grid < end))
        tk = grid[mask]
        xk = solution.sol(tk) if tk.size else np.zeros((len(states), 0))
        for name in names:
            g = sp.sympify(case.outputs[name]).xreplace(subs) if name in case.outputs else u[sp.Symbol(name)]
            for k in range(order + 1):
                fn = sp.lambdify([t, states], g, modules="numpy")
                value = np.broadcast_to(np.asarray(fn(tk, xk), float), tk.shape)
                if k == 0:
                    samples[name][mask] = value
                else:
                    derivs[name][k - 1][mask] = value
                g = sum(sp.diff(g, s) * fs for s, fs in zip(states, f)) + sp.diff(g, t)
        x = solution.sol(end)
    columns.update(samples)
    return ReferenceRun(columns, derivs, values)


def record(run: ReferenceRun, *, noise: Mapping | None = None, seed: int = 0) -> dict:
    """The run's columns with Gaussian noise of ``noise[signal]`` std on the named sensor columns."""
    rng = np.random.default_rng(seed)
    out = {k: np.array(v, float) for k, v in run.columns.items()}
    for name, std in (noise or {}).items():
        out[name] = out[name] + rng.normal(0.0, std, out[name].size)
    return out
