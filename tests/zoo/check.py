"""Check a zoo model by hand: the library's simulation against the reference, and every ARR's identity.

Run ``python -m tests.zoo.check quarter_car rc_ladder ...`` for a survey of each named model (all of
``tests/zoo/models`` without names): the relative error of ``bondgraph.simulate`` on every sensor, and
for the default ARRs and those of ``max_order=None, isolation=True`` the identity error
``r_n + Psi_2`` on a reference run at parameters inside the box, and whether ``arr.evaluate`` runs on
a noisy record.  Library failures are printed as ``FAIL <stage>: <exception>``, never raised.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
import warnings
from collections.abc import Mapping

import numpy as np
import sympy as sp

from .case import ZooCase, t
from .identity import identity_error
from .reference import ReferenceRun, record, simulate_reference


def load_case(name: str) -> ZooCase:
    """The ``CASE`` of ``tests/zoo/models/<name>.py``.

    >>> load_case("quarter_car").domain
    'translational'
    """
    return importlib.import_module(f"tests.zoo.models.{name}").CASE


def model_names() -> list[str]:
    """Every module of ``tests/zoo/models``, sorted.

    >>> "quarter_car" in model_names()
    True
    """
    from . import models
    return sorted(m.name for m in pkgutil.iter_modules(models.__path__))


def inside_box(case: ZooCase, fraction: float = 0.6) -> dict:
    """Every uncertain parameter moved ``fraction`` of the way to one edge of its box (alternating edges).

    >>> moved = inside_box(load_case("quarter_car"))
    >>> round(moved["c_s"] / 1500.0, 3)
    1.06
    """
    bg = case.build()
    out = {}
    for k, (name, (lo, hi)) in enumerate(sorted(bg.uncertainties.items())):
        edge = hi if (k % 2 == 0 and hi > 0) or lo == 0 else lo
        out[name] = bg.parameters[name] * (1.0 + fraction * edge)
    return out


def library_run(case: ZooCase, t_end: float | None = None, parameters: Mapping | None = None) -> dict:
    """``bondgraph.simulate`` of the model with the smooth inputs, on the reference grid: signal -> samples.

    LSODA at ``rtol=1e-10`` agrees with the reference to about 1e-8 on the zoo, at a twentieth of the
    cost of the library's Radau (whose Jacobian is numerical).
    """
    from bondgraph import simulate

    t_end = case.t_end if t_end is None else t_end
    grid = np.round(np.arange(0.0, t_end + case.dt / 2, case.dt) / case.dt) * case.dt
    grid = grid[grid <= t_end]
    inputs = {}
    for name, expression in case.smooth_inputs.items():
        fn = sp.lambdify(t, sp.sympify(expression), modules="numpy")
        inputs[name] = (lambda f: lambda s: float(f(s)))(fn)
    x0 = {str(s): v for s, v in case.x0.items()}
    result = simulate(case.build(), (0.0, t_end), inputs, t_eval=grid, rtol=1e-10, atol=1e-15, method="LSODA",
                      parameters=parameters, **({"x0": x0} if x0 else {}))
    return {"t": result.t, **result.signals}


def relative_errors(case: ZooCase, library: Mapping, reference: ReferenceRun) -> dict:
    """Sensor -> ``max |library - reference| / max |reference|`` over the samples both runs have."""
    errors = {}
    for sensor in case.outputs:
        ref = reference.columns[sensor]
        n = min(ref.size, library[sensor].size)
        # nanmax: the reference leaves NaN at a last grid point that rounds past t_end
        scale = max(float(np.nanmax(np.abs(ref))), 1e-300)
        errors[sensor] = float(np.nanmax(np.abs(library[sensor][:n] - ref[:n]))) / scale
    return errors


def simulation_errors(case: ZooCase, t_end: float | None = None) -> dict:
    """Sensor -> ``max |library - reference| / max |reference|`` on the smooth input, nominal parameters.

    >>> errors = simulation_errors(load_case("quarter_car"), t_end=0.5)
    >>> max(errors.values()) < 1e-5
    True
    """
    return relative_errors(case, library_run(case, t_end), simulate_reference(case, t_end=t_end, order=0))


def identity_errors(arrs: list, run: ReferenceRun) -> dict:
    """ARR name -> ``identity_error`` on ``run``, or the text of the exception the judge met."""
    out = {}
    for arr in arrs:
        try:
            out[arr.name] = identity_error(arr, run)
        except Exception as error:  # noqa: BLE001 - a survey reports every failure
            out[arr.name] = f"{type(error).__name__}: {error}"
    return out


def _derive(bg, **options) -> tuple:
    from diagnosis import derive_arrs

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            arrs = derive_arrs(bg, **options)
        except Exception as error:  # noqa: BLE001
            return [], [f"{type(error).__name__}: {error}"], [str(w.message) for w in caught]
    return arrs, [], [f"{w.category.__name__}: {w.message}" for w in caught]


def survey(case: ZooCase, out=sys.stdout) -> None:
    """Print every check of one model (see the module's docstring)."""
    print(f"== {case.name}", file=out)
    try:
        errors = simulation_errors(case)
        print("  simulate:", {k: f"{v:.1e}" for k, v in errors.items()}, file=out)
    except Exception as error:  # noqa: BLE001
        print(f"  FAIL simulate: {type(error).__name__}: {error}", file=out)
    step = simulate_reference(case, inputs="step", order=0)
    clean, noisy = record(step), record(step, noise=case.noise)
    for label, options in (("default", {}), ("full", {"max_order": None, "isolation": True})):
        arrs, failures, caught = _derive(case.build(), **options)
        order = max([3, *(arr.order for arr in arrs)])
        run = simulate_reference(case, parameters=inside_box(case), order=order)
        for failure in failures:
            print(f"  FAIL derive_arrs({label}): {failure}", file=out)
        for message in caught:
            print(f"  warn derive_arrs({label}): {message}", file=out)
        for arr in arrs:
            error = identity_errors([arr], run)[arr.name]
            text = f"{error:.1e}" if isinstance(error, float) else f"FAIL {error}"
            try:
                arr.evaluate(noisy, margin=0.0)
                alarms = int(np.sum(arr.evaluate(clean, margin=0.0).alarm))
                text += f"  evaluate ok ({alarms} alarms on the clean step record)"
            except Exception as error:  # noqa: BLE001
                text += f"  FAIL evaluate: {type(error).__name__}: {str(error)[:120]}"
            print(f"  {label} {arr.name} [{arr.form}, order {arr.order}, {len(arr.integrals)} int,"
                  f" {sorted(arr.parameters)}]: {text}", file=out)


def fault_visibility(case: ZooCase, change: float = 0.3, names: tuple | None = None) -> dict:
    """Parameter -> ``max |y_faulty - y_nominal| / noise`` over the sensors, on the step record.

    ``y_faulty`` has the parameter ``(1 + change)`` times its nominal value from the start; a fault is
    clearly visible when this is well above 1 (the noise's standard deviation).  ``names``: the
    parameters to try (default: every uncertain one).

    >>> visibility = fault_visibility(load_case("quarter_car"), names=("c_s",))
    >>> visibility["c_s"] > 3
    True
    """
    nominal = simulate_reference(case, inputs="step", order=0)
    bg = case.build()
    out = {}
    for name in names or tuple(bg.uncertainties):
        value = bg.parameters[name]
        faulty = simulate_reference(case, inputs="step", order=0, parameters={name: value * (1 + change)})
        out[name] = max(float(np.nanmax(np.abs(faulty.columns[s] - nominal.columns[s]))) / case.noise[s]
                        for s in case.outputs)
    return out


if __name__ == "__main__":
    for name in sys.argv[1:] or model_names():
        survey(load_case(name))
