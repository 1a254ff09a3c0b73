"""Every stage of the toolkit on one zoo model, with the defaults: what ``test_chain`` and docs/zoo.md use.

:func:`run_chain` runs causality, equations, ARRs (default and complete), the identity of every ARR on
the model's reference physics, the signature matrix, the three reports, detection on a healthy record
with step inputs, and detection of a 30 % change of each parameter the detectability says the record can
show (reached over 2 % of the record: a fast wear; an abrupt jump of a parameter is an impulse for some
models, a transformer's modulus between two rigid inertias, say); it returns a :class:`ChainOutcome` of
plain figures.
"""

from __future__ import annotations

import importlib
import pkgutil
import warnings
from dataclasses import dataclass, field

import numpy as np

from bondgraph.errors import PHMError
from diagnosis import DetectionSettings, derive_arrs, detect, signature_matrix
from diagnosis.report import arr_report

from .identity import identity_error
from .reference import record, simulate_reference

CHANGE = 0.3  # the relative change of a parameter in the faulty records
CALIBRATE = FAULT_AT = 0.45  # share of the record: the end of the fault-free stretch, the fault's onset
RAMP = 0.02  # share of the record over which the parameter moves to its faulty value (a fast wear, not a jump)


def cases() -> list:
    """Every zoo model, in name order."""
    from . import models

    found = []
    for info in pkgutil.iter_modules(models.__path__):
        module = importlib.import_module(f"{models.__name__}.{info.name}")
        if hasattr(module, "CASE"):
            found.append(module.CASE)
    return sorted(found, key=lambda c: c.name)


@dataclass
class ChainOutcome:
    name: str
    domain: str
    elements: int
    sensors: list
    junction_arrs: list
    structural_arrs: list
    identity: dict                  # ARR name -> r_n + Psi_2 error on the reference (default and complete sets)
    signatures: object
    healthy_fired: list
    detectable: dict                # parameter -> smallest relative change any ARR detects on the step record
    faults: dict = field(default_factory=dict)   # parameter -> (fired ARRs, consistent candidates)
    errors: list = field(default_factory=list)   # PHMErrors met along the way (stage, message)


def inside_box(bg) -> dict:
    """Parameter values inside each uncertainty box (at 60 % of its upper side): the 'true' system."""
    return {p: bg.parameters[p] * (1.0 + 0.6 * hi if hi > 0 else 1.0 + 0.6 * lo)
            for p, (lo, hi) in bg.uncertainties.items()}


def run_chain(case, *, faults: bool = True) -> ChainOutcome:
    bg = case.build()
    bg.assign_causality("integral")
    bg.assign_causality("derivative")
    bg.state_equations()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        default = derive_arrs(bg)
        complete = derive_arrs(bg, max_order=None, isolation=True)
    order = max([a.order for a in default + complete] + [3])
    truth = simulate_reference(case, parameters=inside_box(bg), order=order)
    identity = {}
    for arr in {a.name + ("" if a in default else " (complete)"): a for a in default + complete}.items():
        identity[arr[0]] = identity_error(arr[1], truth)
    signatures = signature_matrix(default)
    for form in ("md", "html", "tex"):
        arr_report(bg, form, arrs=default)
    t_end = case.t_end
    healthy = record(simulate_reference(case, inputs="step"), noise=case.noise, seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = detect(bg, healthy, DetectionSettings(calibrate=CALIBRATE * t_end))
    detectable = {}
    for d in result.detectability.values():
        for p in d.rise:
            detectable[p] = min(detectable.get(p, np.inf), d.rise[p])
    outcome = ChainOutcome(case.name, case.domain, len(bg.elements), list(bg.outputs),
                           [a.name for a in default if a.form != "elimination" and "MSO" not in a.name],
                           [a.name for a in default if "MSO" in a.name], identity, signatures, result.fired,
                           detectable)
    if faults:
        for p, rise in detectable.items():
            if rise > CHANGE:
                continue
            faulty = record(simulate_reference(case, inputs="step", parameters={p: bg.parameters[p] * (1 + CHANGE)},
                                               fault_at=FAULT_AT * t_end, ramp=RAMP * t_end),
                            noise=case.noise, seed=2)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    seen = detect(bg, faulty, DetectionSettings(calibrate=CALIBRATE * t_end))
                except PHMError as exc:
                    outcome.errors.append((f"detect {p}", str(exc)))
                    continue
            outcome.faults[p] = (seen.fired, seen.candidates)
    return outcome
