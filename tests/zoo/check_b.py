"""Check zoo models stage by stage: the library's simulation against the reference, ARR identities, evaluation.

``python -m tests.zoo.check_b quarter_car two_tank_cascade`` prints, per model, the relative error of
every sensor between :func:`bondgraph.simulate` and the hand-written reference, the identity error
``r_n + Psi_2`` of every ARR (default derivation and ``max_order=None, isolation=True``) at parameters
inside the box, and what ``evaluate`` does on a noisy record.  Every failure is printed, never raised.
"""

from __future__ import annotations

import importlib
import sys
import warnings

import numpy as np
import sympy as sp

from bondgraph import simulate
from diagnosis import derive_arrs

from .case import ZooCase, t
from .identity import identity_error
from .reference import ORDER, record, simulate_reference


def load(name: str) -> ZooCase:
    """The ``CASE`` of ``tests/zoo/models/<name>.py``."""
    return importlib.import_module(f"tests.zoo.models.{name}").CASE


def _profile(levels: tuple, sensors: set):
    """A piecewise-constant input (levels may be controller laws in sensor signals) as ``u(t)`` or ``u(t, y)``."""
    times = np.array([s for s, _ in levels], float)
    laws = [sp.sympify(v) for _, v in levels]
    names = sorted({str(s) for law in laws for s in law.free_symbols} & sensors)
    fns = [sp.lambdify([sp.Symbol(n) for n in names], law, modules="numpy") for law in laws]

    def level(s):
        return np.searchsorted(times, s, side="right") - 1

    if not names:
        return lambda s: float(fns[level(s)]())
    return lambda s, y: float(fns[level(s)](*(y[n] for n in names)))


def library_inputs(case: ZooCase, inputs: str = "smooth") -> dict:
    """The case's inputs as the callables ``bondgraph.simulate`` takes (``u(t)``, or ``u(t, y)`` in a loop)."""
    sensors = set(case.outputs)
    out = {}
    if inputs == "step":
        return {k: _profile(v, sensors) for k, v in case.step_inputs.items()}
    for name, expression in case.smooth_inputs.items():
        expression = sp.sympify(expression)
        names = sorted({str(s) for s in expression.free_symbols} & sensors)
        fn = sp.lambdify([t, *map(sp.Symbol, names)], expression, modules="numpy")
        if names:
            out[name] = lambda s, y, fn=fn, names=names: float(fn(s, *(y[n] for n in names)))
        else:
            out[name] = lambda s, fn=fn: float(fn(s))
    return out


def simulation_errors(case: ZooCase, *, inputs: str = "smooth", t_end: float | None = None) -> dict:
    """Sensor -> ``max |library - reference| / max |reference|`` on the case's grid."""
    run = simulate_reference(case, inputs=inputs, t_end=t_end, order=0)
    grid = run.columns["t"]
    x0 = {str(k): v for k, v in case.x0.items()}   # zoo models with an x0 name their states as the library does
    result = simulate(case.build(), (0.0, float(grid[-1])), library_inputs(case, inputs), t_eval=grid,
                      rtol=1e-10, atol=1e-13, x0=x0 or None, max_step=case.dt * 10)
    return {name: float(np.max(np.abs(np.asarray(result[name]) - run.columns[name]))
                        / max(np.max(np.abs(run.columns[name])), 1e-300))
            for name in case.outputs}


def inside_box(case: ZooCase, share: float = 0.5) -> dict:
    """Every uncertain parameter moved ``share`` of the way to the upper end of its box (the lower if flat)."""
    out = {}
    for name, element in case.build().elements.items():
        del name
        for parameter, (lo, hi) in _boxes(element).items():
            value = case.build().parameters[parameter]
            out[parameter] = value * (1 + share * (hi if hi > 0 else lo))
    return out


def _boxes(element) -> dict:
    boxes = {}
    if getattr(element, "uncertainty", None) and getattr(element, "param", None):
        boxes[element.param] = tuple(element.uncertainty)
    for parameter, box in (getattr(element, "uncertainties", None) or {}).items():
        boxes[parameter] = tuple(box)
    return boxes


def arr_identities(case: ZooCase, run=None, **options) -> list[tuple[str, object]]:
    """``[(ARR name, identity error or the exception's one-line text), ...]`` for ``derive_arrs(**options)``."""
    run = run or simulate_reference(case, parameters=inside_box(case))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            arrs = derive_arrs(case.build(), **options)
        except Exception as error:  # noqa: BLE001 - the report lists every failure
            return [("derive_arrs", f"{type(error).__name__}: {error}")]
    out = [(f"warning {type(w.message).__name__}", str(w.message).splitlines()[0][:200]) for w in caught]
    order = max([ORDER, *(k for arr in arrs for k in arr.derivatives.values())])
    if order > ORDER:   # an ARR of higher order than the run holds: a run with those derivatives
        run = simulate_reference(case, parameters=run.parameters, order=order)
    for arr in arrs:
        try:
            out.append((arr.name, identity_error(arr, run)))
        except Exception as error:  # noqa: BLE001
            out.append((arr.name, f"{type(error).__name__}: {str(error).splitlines()[0][:200]}"))
    return out


def main(names: list[str]) -> None:
    for name in names:
        case = load(name)
        print(f"== {name}")
        for inputs in ("smooth", "step"):
            try:
                errors = simulation_errors(case, inputs=inputs)
                print(f"  simulate {inputs}: " + ", ".join(f"{k} {v:.1e}" for k, v in errors.items()))
            except Exception as error:  # noqa: BLE001
                print(f"  simulate {inputs}: {type(error).__name__}: {error}")
        run = simulate_reference(case, parameters=inside_box(case))
        for options in ({}, {"max_order": None, "isolation": True}):
            print(f"  derive_arrs{options or ''}")
            for arr, value in arr_identities(case, run, **options):
                print(f"    {arr}: {value:.1e}" if isinstance(value, float) else f"    {arr}: {value}")
        clean = record(simulate_reference(case, inputs="step"))
        try:
            arrs = derive_arrs(case.build())
        except Exception:  # noqa: BLE001 - already reported
            arrs = []
        for arr in arrs:
            try:
                evaluation = arr.evaluate(clean)
                alarms = int(np.sum(np.asarray(evaluation.alarm)))
                print(f"  evaluate {arr.name} {arr.derivatives} integrals {arr.nominal.has(sp.Integral)}: "
                      f"{alarms} alarm samples on the healthy noise-free step record")
            except Exception as error:  # noqa: BLE001
                print(f"  evaluate {arr.name}: {type(error).__name__}: {str(error).splitlines()[0][:200]}")


if __name__ == "__main__":
    main(sys.argv[1:])
